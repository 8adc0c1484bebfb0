//! Job files: a sequence of images, the curves to measure on each, the
//! widths to derive between them and the outputs, in TOML; `vicurve run
//! job.toml`.
//!
//! ```toml
//! images = "frames/*.png"      # a glob, or a list ["a.png", "b.png"];
//!                              # relative to the job file's folder
//! out_dir = "results"          # per-frame files, summary.csv, plots
//! track = true                 # start each frame from the previous result
//!
//! [[curve]]
//! name = "top"                 # names the files when there are several curves
//! init = "segment:10,50,390,50"  # as `measure --init` (polyline: files are
//!                              # relative to the job file's folder)
//! kind = "silhouette"          # or "contour"
//! # closed, polarity, stages, track_stages, degree, interp, tolerance,
//! # max_iter, no_blur_correction: as the flags of `vicurve measure`/`track`
//!
//! [[curve]]
//! name = "bottom"
//! init = "segment:10,150,390,150"
//!
//! [[width]]
//! name = "section"             # default "width"
//! between = ["top", "bottom"]
//! axis = "x"                   # "x", "y", "estimate" or [x0, y0, dx, dy]
//! step = 1.0                   # px between the profile's positions
//!
//! [outputs]
//! points = true                # per-frame points CSV (default true)
//! overlay = "png"              # "png", "svg" or "none" (default)
//! plots = true                 # width plots (default true)
//! ```
//!
//! Unknown keys are errors (a misspelt option is not silently ignored).
//!
//! Frames started from the previous frame's result use the first frame's
//! stages unless a curve says otherwise (`track_stages`). When those are
//! the default schedule (no `stages`, no `track_stages`), a silhouette's
//! tracked frames run the *tracking schedule*
//! ([`crate::fit::measure_tracked_from`]): the pixel-edge stage alone,
//! from the previous frame's blur and elements, on the image without
//! interpolation; a frame it cannot measure (the previous one did not end
//! with a pixel-edge stage, or the stage fails) gets the whole default
//! schedule. `track_stages = "default"` forces the whole default schedule
//! on every frame (the coarse bands, 20, 10 and 5 px, then re-estimate the
//! blur and elements from scratch); `track_stages = "R:N,..."` gives
//! explicit stages, which end without the pixel-edge stage and are less
//! accurate (docs/benchmarks.md, "Sequences").

use super::frames::{frames, Frame};
use super::one_line;
use super::options::CurveOptions;
use crate::curve::InitialCurve;
use crate::error::{Error, Result};
use crate::fit::FitConfig;
use serde::Deserialize;
use std::path::{Path, PathBuf};

/// `DIR/summary.csv`.
pub const SUMMARY_STEM: &str = "summary";
/// `DIR/job.json`: the job's manifest and fingerprint.
pub const MANIFEST_STEM: &str = "job";

/// The job file as written (TOML).
#[derive(Deserialize, Debug)]
#[serde(deny_unknown_fields)]
struct JobFile {
    images: Images,
    out_dir: PathBuf,
    #[serde(default = "yes")]
    track: bool,
    #[serde(default)]
    curve: Vec<CurveFile>,
    #[serde(default)]
    width: Vec<WidthFile>,
    #[serde(default)]
    outputs: OutputsFile,
}

fn yes() -> bool {
    true
}

#[derive(Deserialize, Debug)]
#[serde(untagged)]
enum Images {
    Glob(String),
    List(Vec<String>),
}

/// One curve as written in a job file: `name`, `init`, `track_stages`,
/// and the keys of [`CurveOptions`] (the flags of `measure` and `track`).
#[derive(Deserialize, Debug)]
#[serde(deny_unknown_fields)]
struct CurveFile {
    name: Option<String>,
    init: String,
    kind: Option<String>,
    #[serde(default)]
    closed: bool,
    polarity: Option<String>,
    stages: Option<String>,
    track_stages: Option<String>,
    degree: Option<usize>,
    interp: Option<String>,
    tolerance: Option<f64>,
    max_iter: Option<usize>,
    #[serde(default)]
    no_blur_correction: bool,
}

impl CurveFile {
    /// The curve's options: the flags' defaults for the keys left out.
    fn args(&self) -> CurveOptions {
        let d = CurveOptions::default();
        CurveOptions {
            closed: self.closed,
            kind: self.kind.clone().unwrap_or(d.kind),
            polarity: self.polarity.clone().unwrap_or(d.polarity),
            stages: self.stages.clone(),
            degree: self.degree.unwrap_or(d.degree),
            interp: self.interp.clone(),
            tolerance: self.tolerance.unwrap_or(d.tolerance),
            max_iter: self.max_iter.unwrap_or(d.max_iter),
            no_blur_correction: self.no_blur_correction,
        }
    }
}

#[derive(Deserialize, Debug)]
#[serde(deny_unknown_fields)]
struct WidthFile {
    name: Option<String>,
    between: [String; 2],
    axis: Option<AxisFile>,
    step: Option<f64>,
}

#[derive(Deserialize, Debug)]
#[serde(untagged)]
enum AxisFile {
    Named(String),
    Explicit([f64; 4]),
}

#[derive(Deserialize, Debug)]
#[serde(deny_unknown_fields)]
struct OutputsFile {
    #[serde(default = "yes")]
    points: bool,
    overlay: Option<String>,
    #[serde(default = "yes")]
    plots: bool,
}

impl Default for OutputsFile {
    fn default() -> Self {
        OutputsFile {
            points: true,
            overlay: None,
            plots: true,
        }
    }
}

/// A job ready to run: what `run` reads from a file and `track` builds
/// from its flags.
#[derive(Debug, Clone)]
pub struct Job {
    /// The frames, in order (the pages of a stack one by one).
    pub images: Vec<Frame>,
    /// The output folder: per-frame files, the summary, the manifest.
    pub out_dir: PathBuf,
    /// Start each frame from the previous frame's result (else every frame
    /// from the curves' `init`).
    pub track: bool,
    /// The curves measured on every frame (at least one).
    pub curves: Vec<CurveSpec>,
    /// The widths derived between two of them.
    pub widths: Vec<WidthSpec>,
    /// The optional outputs.
    pub outputs: JobOutputs,
    /// The part of a larger job these frames are (`run --shard K/N`).
    pub shard: Option<Shard>,
}

/// Part `index` (from 1) of `count` of a job whose frames start at
/// `first` of the whole job's (`run --shard K/N`).
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub struct Shard {
    /// K, from 1.
    pub index: usize,
    /// N.
    pub count: usize,
    /// The whole job's index of the part's first frame.
    pub first: usize,
}

impl Shard {
    /// `summary.shard-K-of-N.csv`, the part's summary (`merge` joins them).
    pub fn summary_name(&self) -> String {
        format!("{SUMMARY_STEM}.shard-{}-of-{}.csv", self.index, self.count)
    }
}

/// `K/N` with `1 <= K <= N`.
pub fn parse_shard(text: &str) -> Result<(usize, usize)> {
    let bad = || {
        Error::job(format!(
            "--shard '{text}': expected K/N with 1 <= K <= N, such as 3/10"
        ))
    };
    let (k, n) = text.split_once('/').ok_or_else(bad)?;
    let (k, n): (usize, usize) = (
        k.trim().parse().map_err(|_| bad())?,
        n.trim().parse().map_err(|_| bad())?,
    );
    if k == 0 || k > n {
        return Err(bad());
    }
    Ok((k, n))
}

/// Keep part `k` of `n` of the job's frames: the frames split evenly in
/// order (part `k` has frames `(k-1) T / N` to `k T / N`). A tracked job
/// is one sequence, each frame started from the one before: it cannot be
/// split without changing its results, so it is one part (split a
/// campaign of sequences by giving each its own job file).
pub fn shard(job: &mut Job, k: usize, n: usize) -> Result<()> {
    if job.track && n > 1 {
        return Err(Error::job(
            "--shard: a tracked job is one sequence (each frame starts from the one before) and cannot be split; give each sequence its own job file, or set track = false for independent frames",
        ));
    }
    let total = job.images.len();
    let (first, end) = ((k - 1) * total / n, k * total / n);
    job.images = job.images[first..end].to_vec();
    job.shard = Some(Shard {
        index: k,
        count: n,
        first,
    });
    Ok(())
}

/// One curve to measure on every frame.
#[derive(Debug, Clone, serde::Serialize)]
pub struct CurveSpec {
    /// Names its files when a job has several curves.
    pub name: String,
    /// The start of the first frame (and of frames after a failure with no
    /// good curve before them).
    pub init: InitialCurve,
    /// Configuration of frames started from `init`.
    pub first: FitConfig,
    /// Configuration of frames started from the previous frame's result.
    pub tracked: FitConfig,
    /// Whether those frames run the tracking schedule first (see the
    /// [module docs](self)), `tracked` being the fallback.
    pub tracking_schedule: bool,
}

impl CurveSpec {
    /// The curve as the library's sequence step takes it.
    pub fn as_sequence(&self) -> crate::sequence::SequenceCurve<'_> {
        crate::sequence::SequenceCurve {
            init: &self.init,
            first: &self.first,
            tracked: &self.tracked,
            tracking_schedule: self.tracking_schedule,
        }
    }
}

/// How the axis of a width profile is chosen.
#[derive(Debug, Clone, Copy, PartialEq, serde::Serialize)]
#[serde(rename_all = "snake_case")]
pub enum AxisChoice {
    /// The image's x axis (positions are x).
    X,
    /// The image's y axis.
    Y,
    /// Estimated on each frame from the two curves.
    Estimate,
    /// Origin and direction, px.
    Explicit {
        /// A point of the axis, px.
        origin: [f64; 2],
        /// Its direction (any length but zero).
        direction: [f64; 2],
    },
}

/// A width between two named curves.
#[derive(Debug, Clone, serde::Serialize)]
pub struct WidthSpec {
    /// Names its files and summary rows.
    pub name: String,
    /// Indices into `Job::curves`.
    pub between: [usize; 2],
    /// The axis the profile's positions run along.
    pub axis: AxisChoice,
    /// Spacing of the profile's positions, px.
    pub step: f64,
}

/// Overlay format.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum OverlayKind {
    /// A PNG image.
    Png,
    /// An SVG drawing over the image.
    Svg,
}

#[derive(Debug, Clone)]
/// The optional outputs of a job.
pub struct JobOutputs {
    /// A points CSV per frame and curve.
    pub points: bool,
    /// An overlay per frame.
    pub overlay: Option<OverlayKind>,
    /// The width plots (drawn by the command-line tool).
    pub plots: bool,
}

/// Read and check a job file.
pub fn load(path: &Path) -> Result<Job> {
    let text = std::fs::read_to_string(path)
        .map_err(|e| {
            if e.kind() == std::io::ErrorKind::NotFound {
                format!("job file not found: {}", path.display())
            } else {
                format!("cannot read the job file {}: {e}", path.display())
            }
        })
        .map_err(Error::job)?;
    let file: JobFile = toml::from_str(&text)
        .map_err(|e| format!("job file {}: {}", path.display(), one_line(&e.to_string())))
        .map_err(Error::job)?;
    let base = path.parent().unwrap_or(Path::new("")).to_path_buf();
    let images = match &file.images {
        Images::Glob(pattern) => expand_glob(&resolve(&base, pattern))?,
        Images::List(list) => list.iter().map(|p| base.join(p)).collect(),
    };
    let images = frames(images)?;
    let curves = file
        .curve
        .iter()
        .enumerate()
        .map(|(i, c)| {
            let name = c.name.clone().unwrap_or_else(|| format!("curve{}", i + 1));
            let init = match c.init.strip_prefix("polyline:") {
                Some(file) => format!("polyline:{}", resolve(&base, file)),
                None => c.init.clone(),
            };
            curve_spec(name, &init, &c.args(), c.track_stages.as_deref())
        })
        .collect::<Result<Vec<_>>>()?;
    let widths = file
        .width
        .iter()
        .map(|w| width_spec(w, &curves))
        .collect::<Result<Vec<_>>>()?;
    let overlay = match file.outputs.overlay.as_deref() {
        None | Some("none") => None,
        Some(o) => Some(parse_overlay(o)?),
    };
    let job = Job {
        images,
        out_dir: base.join(&file.out_dir),
        track: file.track,
        curves,
        widths,
        outputs: JobOutputs {
            points: file.outputs.points,
            overlay,
            plots: file.outputs.plots,
        },
        shard: None,
    };
    check(&job)?;
    Ok(job)
}

/// `png` or `svg`.
pub fn parse_overlay(text: &str) -> Result<OverlayKind> {
    match text {
        "png" => Ok(OverlayKind::Png),
        "svg" => Ok(OverlayKind::Svg),
        _ => Err(Error::job(format!(
            "unknown overlay '{text}' (expected png, svg or none)"
        ))),
    }
}

/// `dir/pattern` unless the pattern is absolute.
fn resolve(base: &Path, pattern: &str) -> String {
    if Path::new(pattern).is_absolute() || base.as_os_str().is_empty() {
        pattern.to_string()
    } else {
        base.join(pattern).display().to_string()
    }
}

/// The files matching a glob pattern, sorted by name (`*`, `?`, `[...]`;
/// see the `glob` crate). No match is an error: a misspelt pattern should
/// not look like an empty sequence.
pub fn expand_glob(pattern: &str) -> Result<Vec<PathBuf>> {
    let paths = glob::glob(pattern)
        .map_err(|e| Error::job(format!("bad image pattern '{pattern}': {e}")))?
        .filter_map(|entry| entry.ok())
        .filter(|p| p.is_file())
        .collect::<Vec<_>>();
    if paths.is_empty() {
        return Err(Error::job(format!(
            "no image matches '{pattern}' (quote the pattern so that the shell does not expand it)"
        )));
    }
    let mut paths = paths;
    paths.sort();
    Ok(paths)
}

/// The curve `name` started from `init` (as `--init`, its file already
/// resolved), with its two configurations: frames started from `init`
/// get `args`' stages, frames started from the previous result
/// `track_stages` (`default`: the default schedule; none: the first
/// frame's, or the tracking schedule when that is the default).
pub fn curve_spec(
    name: String,
    init: &str,
    args: &CurveOptions,
    track_stages: Option<&str>,
) -> Result<CurveSpec> {
    let context = |e: Error| Error::job(format!("curve '{name}': {e}"));
    let init = args.init(init).map_err(context)?;
    let first = args.config().map_err(context)?;
    first.validate().map_err(context)?;
    let (tracked, tracking_schedule) =
        crate::sequence::tracked_config(&first, track_stages).map_err(context)?;
    Ok(CurveSpec {
        name,
        init,
        first,
        tracked,
        tracking_schedule,
    })
}

fn width_spec(w: &WidthFile, curves: &[CurveSpec]) -> Result<WidthSpec> {
    let name = w.name.clone().unwrap_or_else(|| "width".into());
    let find = |n: &str| {
        curves.iter().position(|c| c.name == n).ok_or_else(|| {
            Error::job(format!(
                "width '{name}': no curve named '{n}' (the curves are: {})",
                curves
                    .iter()
                    .map(|c| c.name.as_str())
                    .collect::<Vec<_>>()
                    .join(", ")
            ))
        })
    };
    let between = [find(&w.between[0])?, find(&w.between[1])?];
    if between[0] == between[1] {
        return Err(Error::job(format!(
            "width '{name}': the two curves must differ"
        )));
    }
    for &i in &between {
        if curves[i].init.is_closed() {
            return Err(Error::job(format!(
                "width '{name}': curve '{}' is closed; a width is measured between two open curves",
                curves[i].name
            )));
        }
    }
    let axis = match &w.axis {
        None => AxisChoice::Estimate,
        Some(AxisFile::Named(a)) => match a.as_str() {
            "x" => AxisChoice::X,
            "y" => AxisChoice::Y,
            "estimate" => AxisChoice::Estimate,
            _ => {
                return Err(Error::job(format!(
                    "width '{name}': unknown axis '{a}' (expected \"x\", \"y\", \"estimate\" or [x0, y0, dx, dy])"
                )));
            }
        },
        Some(AxisFile::Explicit(v)) => {
            if !v.iter().all(|x| x.is_finite()) || v[2].hypot(v[3]) == 0.0 {
                return Err(Error::job(format!(
                    "width '{name}': the axis [x0, y0, dx, dy] needs finite numbers and a non-zero direction"
                )));
            }
            AxisChoice::Explicit {
                origin: [v[0], v[1]],
                direction: [v[2], v[3]],
            }
        }
    };
    let step = w.step.unwrap_or(1.0);
    if !(step.is_finite() && step > 0.0) {
        return Err(Error::job(format!(
            "width '{name}': step {step} px (must be > 0)"
        )));
    }
    Ok(WidthSpec {
        name,
        between,
        axis,
        step,
    })
}

/// Names are unique, usable in file names, and frames have distinct stems
/// that do not collide with the job's own files.
pub fn check(job: &Job) -> Result<()> {
    if job.curves.is_empty() {
        return Err(Error::job(
            "the job measures no curve: add a [[curve]] table with at least `init`",
        ));
    }
    if job.images.is_empty() {
        return Err(Error::job("the job lists no image"));
    }
    let mut names: Vec<&str> = Vec::new();
    for n in job
        .curves
        .iter()
        .map(|c| c.name.as_str())
        .chain(job.widths.iter().map(|w| w.name.as_str()))
    {
        let ok = !n.is_empty()
            && n.chars()
                .all(|c| c.is_ascii_alphanumeric() || c == '-' || c == '_');
        if !ok {
            return Err(Error::job(format!(
                "name '{n}': use letters, digits, '-' and '_' only (it names files)"
            )));
        }
        if names.contains(&n) {
            return Err(Error::job(format!(
                "name '{n}' is used twice (curves and widths need distinct names)"
            )));
        }
        names.push(n);
    }
    let mut seen = std::collections::HashSet::new();
    for f in &job.images {
        let stem = &f.stem;
        if stem == SUMMARY_STEM || stem == MANIFEST_STEM {
            return Err(Error::job(format!(
                "frame {}: the name '{stem}' is reserved for the job's own files; rename the image",
                f.input()
            )));
        }
        if !seen.insert(stem.as_str()) {
            return Err(Error::job(format!(
                "two frames are named '{stem}' (results are named after the file stem): {}",
                f.input()
            )));
        }
    }
    Ok(())
}
