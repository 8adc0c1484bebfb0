//! `vicurve bench objects`: the time of `measure --all` on issue 20's case,
//! 100 circles of radius 15 px in a 1-megapixel image (blur 1 px, noise 1 %
//! of the contrast, 8 bits; [`vicurve::render::scene::circle_grid`]).
//!
//! The image is rendered by exact coverage and saved as PNG with its truth;
//! then it is measured by whole `vicurve measure IMAGE --all --out --table`
//! processes (after one untimed run; wall clock, median, minimum and
//! maximum) and in this process ([`inproc`]): the search, the interpolant,
//! `measure_all` on the machine's cores and on one thread, each stage's
//! time and iterations summed over the objects, and a separate call of the
//! blur estimate on every measured curve. The measured objects are matched
//! to the truth so that the timing is of a correct measurement. [`report`]
//! writes `objects-speed.md` and `objects-speed.csv`.

mod inproc;
mod report;

use super::speed::process;
use crate::failure::Failure;
use std::path::{Path, PathBuf};
use vicurve::render::scene::{circle_grid, render_scene, Scene};
use vicurve::Image;

/// Arguments of `vicurve bench objects`.
#[derive(clap::Args)]
pub struct ObjectsArgs {
    /// Timed runs (whole processes, and as many in-process measurements).
    #[arg(long, default_value_t = 5)]
    repeats: usize,
    /// Output directory (created if needed): objects-speed.md and
    /// objects-speed.csv are replaced.
    #[arg(long, default_value = "docs/objects")]
    out: PathBuf,
    /// Working directory for the image, its truth and the runs' outputs;
    /// default: vicurve-objects in the system's temporary directory.
    #[arg(long, value_name = "DIR")]
    work: Option<PathBuf>,
    /// A small image of 16 circles (a smoke test of the command).
    #[arg(long, hide = true)]
    quick: bool,
}

/// The benchmark's case: the scene, its image, where it is saved.
pub struct Case {
    /// The scene (its own truth).
    pub scene: Scene,
    /// The rendered image.
    pub image: Image,
    /// The PNG measured.
    pub path: PathBuf,
}

/// Run the benchmark and write its outputs.
pub fn objects(args: &ObjectsArgs) -> Result<(), Failure> {
    if args.repeats == 0 {
        return Err(Failure::Error("--repeats must be at least 1".into()));
    }
    let work = args
        .work
        .clone()
        .unwrap_or_else(|| std::env::temp_dir().join("vicurve-objects"));
    for d in [&args.out, &work] {
        std::fs::create_dir_all(d)
            .map_err(|e| format!("cannot create the directory {}: {e}", d.display()))?;
    }
    let machine = super::speed::report::Machine::now();
    let case = make_case(&work, args.quick)?;
    eprintln!("objects: {} processes ...", args.repeats);
    let runs = time_processes(&case, &work, args.repeats)?;
    eprintln!("objects: {} in-process runs ...", args.repeats);
    let inproc = inproc::run(&case, args.repeats)?;
    let command = format!(
        "vicurve bench objects --repeats {} --out {}{}",
        args.repeats,
        args.out.display(),
        if args.quick { " --quick" } else { "" }
    );
    let results = report::Results {
        case: &case,
        runs: &runs,
        inproc: &inproc,
        machine: &machine,
        command: &command,
    };
    print!("{}", report::table(&results));
    write(
        &args.out.join("objects-speed.md"),
        &report::markdown(&results),
    )?;
    write(&args.out.join("objects-speed.csv"), &report::csv(&results))?;
    println!(
        "wrote {} (objects-speed.md, objects-speed.csv); image and runs in {}",
        args.out.display(),
        work.display()
    );
    Ok(())
}

/// Render the case (10x10 circles of radius 15 in 1000x1000; `quick`: 4x4
/// in 400x400) and save its image and truth in `work`.
fn make_case(work: &Path, quick: bool) -> Result<Case, Failure> {
    let (size, n) = if quick { (400, 4) } else { (1000, 10) };
    let scene = circle_grid(size, size, n, n, 30.0, false, 20)?;
    let image = render_scene(&scene)?;
    let path = work.join("circles.png");
    vicurve::io::save_image(&path, &image, 8)?;
    crate::output::write_json(&work.join("circles.truth.json"), &scene)?;
    Ok(Case { scene, image, path })
}

/// `vicurve measure IMAGE --all --out --table`, once untimed then
/// `repeats` times; every run must exit 0 (all objects measured).
fn time_processes(
    case: &Case,
    work: &Path,
    repeats: usize,
) -> Result<Vec<process::ProcessRun>, Failure> {
    let exe = std::env::current_exe().map_err(|e| format!("cannot find this program: {e}"))?;
    let args: Vec<String> = vec![
        "measure".into(),
        case.path.display().to_string(),
        "--all".into(),
        "--out".into(),
        work.join("all.json").display().to_string(),
        "--table".into(),
        work.join("objects.csv").display().to_string(),
    ];
    process::run(&exe, &args)?;
    let mut runs = Vec::with_capacity(repeats);
    for _ in 0..repeats {
        let r = process::run(&exe, &args)?;
        if r.code != Some(0) {
            return Err(Failure::Error(format!(
                "vicurve {} exited with {:?} (some object failed?)",
                args.join(" "),
                r.code
            )));
        }
        runs.push(r);
    }
    Ok(runs)
}

fn write(path: &Path, text: &str) -> Result<(), Failure> {
    std::fs::write(path, text)
        .map_err(|e| Failure::Error(format!("cannot write {}: {e}", path.display())))
}
