//! `vicurve bench conformance`: the conformance sweep. Every shape, start,
//! blur, noise level, depth and polarity of the sweep ([`cases`]) is
//! rendered, started as a user would ([`run`]), measured in-process and
//! scored against the exact truth and the acceptance criteria ([`score`]);
//! `conformance.csv` and `conformance.md` ([`report`]) say which cases
//! fail and why.

pub(super) mod cases;
mod report;
pub(super) mod run;
mod score;

use crate::failure::Failure;
pub use cases::Set;
use cases::{filtered, Case};
use indicatif::{ProgressBar, ProgressStyle};
use rayon::prelude::*;
use score::Row;
use std::path::PathBuf;
use vicurve::Image;

/// Arguments of `vicurve bench conformance`.
#[derive(clap::Args)]
pub struct ConformanceArgs {
    /// Output directory (created if needed): conformance.csv and
    /// conformance.md are replaced.
    #[arg(long)]
    out: PathBuf,
    /// `ci`: every shape and start on a rotation of the conditions (a
    /// minute or two); `full`: the whole sweep (minutes).
    #[arg(long, value_enum, default_value = "ci")]
    set: Set,
    /// Run only the cases whose id contains this text.
    #[arg(long, value_name = "SUBSTR")]
    filter: Option<String>,
    /// Also write each measured case's samples with their signed error to
    /// the truth (`OUT/samples/ID.csv`, the id's `/` as `_`), to see where
    /// a case fails, and what measures it again with `vicurve measure`:
    /// its image (`ID.png`), its start's points (`ID.start.csv`, for
    /// `--init polyline:`) and its truth (`ID.truth.json`, for `vicurve
    /// eval`).
    #[arg(long)]
    samples: bool,
}

/// Run the sweep and write its outputs.
pub fn conformance(args: &ConformanceArgs) -> Result<(), Failure> {
    let out = &args.out;
    std::fs::create_dir_all(out)
        .map_err(|e| format!("cannot create the output directory {}: {e}", out.display()))?;
    let cases = filtered(cases::cases(args.set), args.filter.as_deref());
    if cases.is_empty() {
        return Err(Failure::Error("no case matches --filter".into()));
    }
    let samples = args.samples.then(|| out.join("samples"));
    if let Some(dir) = &samples {
        std::fs::create_dir_all(dir)
            .map_err(|e| format!("cannot create {}: {e}", dir.display()))?;
    }
    let rows = run_all(&cases, samples.as_deref())?;
    write(&out.join("conformance.csv"), &report::csv(&rows))?;
    write(
        &out.join("conformance.md"),
        &report::report(&rows, &command_line(args)),
    )?;
    let passed = rows.iter().filter(|r| r.pass).count();
    println!(
        "{passed} of {} cases pass; wrote {} (conformance.csv, conformance.md)",
        rows.len(),
        out.display()
    );
    Ok(())
}

fn write(path: &std::path::Path, text: &str) -> Result<(), String> {
    std::fs::write(path, text).map_err(|e| format!("cannot write {}: {e}", path.display()))
}

/// The command that reproduces the outputs.
fn command_line(args: &ConformanceArgs) -> String {
    let set = match args.set {
        Set::Ci => "ci",
        Set::Full => "full",
    };
    let mut c = format!(
        "vicurve bench conformance --out {} --set {set}",
        args.out.display()
    );
    if let Some(f) = &args.filter {
        c.push_str(&format!(" --filter {f}"));
    }
    c
}

/// Every case, in order: the images are measured in parallel (rayon's
/// threads), each rendered once for all the cases on it, which run one
/// after the other.
fn run_all(cases: &[Case], samples: Option<&std::path::Path>) -> Result<Vec<Row>, Failure> {
    let bar = ProgressBar::new(cases.len() as u64);
    bar.set_style(
        ProgressStyle::with_template("{bar:40} {pos}/{len} {msg} (ETA {eta})")
            .map_err(|e| e.to_string())?,
    );
    let groups = by_image(cases);
    let rows: Vec<Vec<Row>> = groups
        .par_iter()
        .map(|group| {
            bar.set_message(group[0].image.id.clone());
            let rows = run_image(group, samples);
            bar.inc(group.len() as u64);
            rows
        })
        .collect();
    bar.finish_and_clear();
    Ok(rows.into_iter().flatten().collect())
}

/// Consecutive cases on the same image.
fn by_image(cases: &[Case]) -> Vec<&[Case]> {
    let mut groups = Vec::new();
    let mut start = 0;
    for i in 1..=cases.len() {
        if i == cases.len() || cases[i].image.id != cases[start].image.id {
            groups.push(&cases[start..i]);
            start = i;
        }
    }
    groups
}

/// Render the image of `group` and run each of its cases on it (writing
/// each case's samples into `samples` when given).
fn run_image(group: &[Case], samples: Option<&std::path::Path>) -> Vec<Row> {
    let image: Result<Image, String> =
        vicurve::render::render(&group[0].image.spec).map_err(|e| e.to_string());
    group
        .iter()
        .map(|case| {
            let ran = match &image {
                Ok(img) => run::run_case(case, img),
                Err(e) => run::Ran::Failed {
                    message: format!("rendering: {e}"),
                    seconds: 0.0,
                },
            };
            let row = score::score(case, &ran);
            if let Some(dir) = samples {
                let stem = case.id.replace('/', "_");
                if let run::Ran::Measured { m, .. } = &ran {
                    let path = dir.join(format!("{stem}.csv"));
                    if let Err(e) = std::fs::write(&path, score::samples_csv(case, m)) {
                        eprintln!("cannot write {}: {e}", path.display());
                    }
                }
                if let Ok(img) = &image {
                    if let Err(e) = reproduction(case, img, dir, &stem) {
                        eprintln!("{e}");
                    }
                }
            }
            row
        })
        .collect()
}

/// What a user needs to measure `case` again with the CLI and score it:
/// its image (`STEM.png`, at the case's depth), its truth
/// (`STEM.truth.json`, for `vicurve eval`) and its start
/// (`STEM.start.csv`, the start's points for `--init polyline:` with
/// `--closed` when it is closed; an automatic start has none).
fn reproduction(
    case: &Case,
    image: &Image,
    dir: &std::path::Path,
    stem: &str,
) -> Result<(), String> {
    let png = dir.join(format!("{stem}.png"));
    vicurve::io::save_image(&png, image, case.image.bits)
        .map_err(|e| format!("cannot write {}: {e}", png.display()))?;
    let truth = dir.join(format!("{stem}.truth.json"));
    vicurve::render::Truth::from_spec(&case.image.spec)
        .save(&truth)
        .map_err(|e| format!("cannot write {}: {e}", truth.display()))?;
    if case.start == cases::Start::Auto {
        return Ok(());
    }
    let init = run::initial_curve(case, image)?;
    let points = init.dense_points(1.0).map_err(|e| e.to_string())?;
    let mut text = String::from("x,y\n");
    for p in &points {
        text.push_str(&format!("{},{}\n", p[0], p[1]));
    }
    let path = dir.join(format!("{stem}.start.csv"));
    write(&path, &text)
}
