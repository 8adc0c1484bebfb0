//! `vicurve`: measure curves and edges in images to a fraction of a pixel.
//!
//! Errors are printed as one line, `vicurve: error: ...`, and the exit code
//! says what happened: 0 success (a fit that hit its iteration limit prints
//! a warning), 1 an error in the input or the files, 2 a usage error, 3 a
//! fit that diverged (its outputs are still written) or, for a sequence
//! (`track`, `run`), frames that failed (the others are measured and
//! written; `summary.csv` says which failed and why).

mod bench_paper;
mod cmd_bench;
mod cmd_demo;
mod cmd_eval;
mod cmd_export;
mod cmd_measure;
mod cmd_mesh;
mod cmd_run;
mod cmd_synth;
mod cmd_track;
mod diagnostics;
mod diagnostics_png;
mod frame;
mod job;
mod model_output;
mod output;
mod overlay;
mod plot;
mod plot_width;
mod resume;
mod sequence;
mod summary;
mod synth_sequence;

use clap::{Parser, Subcommand};
use std::process::ExitCode;

/// Sub-pixel measurement of contours (thin lines) and silhouettes (edges) in
/// images by Virtual Image Correlation with B-splines.
#[derive(Parser)]
#[command(name = "vicurve", version)]
struct Cli {
    #[command(subcommand)]
    command: Command,
}

#[derive(Subcommand)]
enum Command {
    /// Measure a curve in an image from a starting curve.
    Measure(cmd_measure::Args),
    /// Render a test image with exactly known geometry (and its truth file).
    Synth(cmd_synth::Args),
    /// Compare measured points with a truth file: bias, scatter, max error.
    Eval(cmd_eval::Args),
    /// Synthesise a star, measure it from a circle, print the accuracy and
    /// write the overlay.
    Demo(cmd_demo::Args),
    /// Benchmark studies: `bench paper` re-runs the paper's section 7.
    Bench(cmd_bench::Args),
    /// Track a curve through a sequence of images, each frame started from
    /// the previous frame's result.
    Track(cmd_track::Args),
    /// Run a job file (TOML): images, named curves, widths, outputs.
    Run(cmd_run::Args),
    /// Export a measured curve from its result file: DXF SPLINE (CAD),
    /// SVG of exact cubic Béziers.
    Export(cmd_export::Args),
    /// The NURBS surface patch between two measured edges: JSON, VTK (.vtu).
    Mesh(cmd_mesh::Args),
}

/// How a command failed.
pub enum Failure {
    /// Bad input or files: exit 1.
    Error(String),
    /// The fit diverged (outputs written): exit 3.
    Diverged(String),
}

impl From<vicurve::Error> for Failure {
    fn from(e: vicurve::Error) -> Self {
        Failure::Error(e.to_string())
    }
}

impl From<String> for Failure {
    fn from(e: String) -> Self {
        Failure::Error(e)
    }
}

fn main() -> ExitCode {
    let cli = Cli::parse();
    let result = match cli.command {
        Command::Measure(a) => cmd_measure::run(a),
        Command::Synth(a) => cmd_synth::run(a),
        Command::Eval(a) => cmd_eval::run(a),
        Command::Demo(a) => cmd_demo::run(a),
        Command::Bench(a) => cmd_bench::run(a),
        Command::Track(a) => cmd_track::run(a),
        Command::Run(a) => cmd_run::run(a),
        Command::Export(a) => cmd_export::run(a),
        Command::Mesh(a) => cmd_mesh::run(a),
    };
    match result {
        Ok(()) => ExitCode::SUCCESS,
        Err(Failure::Error(msg)) => {
            eprintln!("vicurve: error: {}", one_line(&msg));
            ExitCode::from(1)
        }
        Err(Failure::Diverged(msg)) => {
            eprintln!("vicurve: error: {}", one_line(&msg));
            ExitCode::from(3)
        }
    }
}

/// Messages are printed on one line whatever their source.
fn one_line(msg: &str) -> String {
    msg.split_whitespace().collect::<Vec<_>>().join(" ")
}
