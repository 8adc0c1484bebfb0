//! `vicurve track`: one curve through a sequence of images, each frame
//! started from the previous frame's result (see [`crate::sequence`]).

use crate::args::CurveArgs;
use crate::failure::Failure;
use crate::sequence::job::{self, Job, JobOutputs};
use std::path::PathBuf;

/// Track a curve through a sequence of images.
#[derive(clap::Args)]
pub struct Args {
    /// The frames: a glob pattern (quote it: `'frames/*.tif'`), sorted by
    /// name, or several files in order. A multi-page TIFF stands for its
    /// pages, a video (`.mp4`, `.mkv`, `.avi`, ...: decoded by FFmpeg's
    /// `ffmpeg` and `ffprobe`, which must be on PATH) for its frames, frame
    /// `STEM_0000` the first.
    #[arg(required = true)]
    pub images: Vec<String>,
    /// Starting curve of the first frame, as for `measure`:
    /// `circle:CX,CY,R`, `segment:X0,Y0,X1,Y1` or `polyline:FILE.csv`.
    #[arg(long)]
    pub init: String,
    #[command(flatten)]
    pub curve: CurveArgs,
    /// Stages of the frames started from the previous result: `default`
    /// (the whole default schedule on every frame) or `R:N,...`. Default:
    /// those of the first frame; when that is the default schedule, a
    /// silhouette's frames run the tracking schedule (the pixel-edge stage
    /// alone, from the previous frame's blur and elements; the default
    /// schedule when it cannot measure a frame). `2:auto` is faster than
    /// the default schedule but less accurate: see docs/benchmarks.md.
    #[arg(long)]
    pub track_stages: Option<String>,
    /// Start every frame from `--init` instead of the previous result.
    #[arg(long)]
    pub no_tracking: bool,
    /// Output folder: per-frame JSON and points CSV named after the frame's
    /// file stem, `summary.csv`, `job.json`.
    #[arg(long)]
    pub out_dir: PathBuf,
    /// Also write an overlay per frame: `png` or `svg`.
    #[arg(long)]
    pub overlay: Option<String>,
    /// Do not write the per-frame points CSV.
    #[arg(long)]
    pub no_points: bool,
    /// Measure every frame again, even those already done in the output
    /// folder (by default a re-run skips them).
    #[arg(long)]
    pub force: bool,
}

pub fn run(args: Args) -> Result<(), Failure> {
    let job = build(&args)?;
    crate::sequence::run(&job, args.force)
}

/// The job `track`'s flags describe.
fn build(args: &Args) -> Result<Job, Failure> {
    let images = if args.images.len() == 1 && has_wildcard(&args.images[0]) {
        job::expand_glob(&args.images[0])?
    } else {
        let list: Vec<PathBuf> = args.images.iter().map(PathBuf::from).collect();
        if let Some(p) = list.iter().find(|p| has_wildcard(&p.display().to_string())) {
            return Err(Failure::Error(format!(
                "'{}': give one quoted pattern, or a list of files",
                p.display()
            )));
        }
        list
    };
    let track_stages = args.track_stages.as_deref();
    let spec = job::curve_spec(
        "curve".into(),
        &args.init,
        &args.curve.options(),
        track_stages,
    )?;
    let overlay = match args.overlay.as_deref() {
        None | Some("none") => None,
        Some(o) => Some(job::parse_overlay(o)?),
    };
    let job = Job {
        images: crate::sequence::frames::frames(images)?,
        out_dir: args.out_dir.clone(),
        track: !args.no_tracking,
        curves: vec![spec],
        widths: Vec::new(),
        outputs: JobOutputs {
            points: !args.no_points,
            overlay,
            plots: false,
        },
        shard: None,
    };
    job::check(&job)?;
    Ok(job)
}

fn has_wildcard(s: &str) -> bool {
    s.contains(['*', '?', '['])
}
