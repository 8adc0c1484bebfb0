//! `vicurve`: measure curves and edges in images to a fraction of a pixel.
//!
//! Errors are printed as one line, `vicurve: error: ...`, and the exit code
//! says what happened: 0 success (a fit that hit its iteration limit prints
//! a warning), 1 an error in the input or the files, 2 a usage error, 3 a
//! fit that diverged (its outputs are still written) or, for a sequence
//! (`track`, `run`), frames that failed (the others are measured and
//! written; `summary.csv` says which failed and why). Output piped into
//! a reader that stops early (`| head`) ends the program quietly, as it
//! does the shell's own tools, not with a panic.
//!
//! The crate in layers; a module imports only from the layers below it:
//!
//! 1. `main`: the command enum, dispatch and exit codes;
//! 2. [`commands`]: one file per subcommand, each thin;
//! 3. [`sequence`] (frames of `track` and `run`: jobs, frames, resuming,
//!    the summary, progress, width plots) and [`measure_start`]
//!    (`measure`'s start: found automatically, or grown);
//! 4. [`output`]: what a measurement writes and prints (result files,
//!    overlays, shape models, diagnostics, CAD exports);
//! 5. [`plot`]: figures and colour maps;
//! 6. [`args`]: every option, declared once, and its values parsed by the
//!    library's `FromStr` into the library's configuration;
//! 7. [`failure`]: how a command fails.

mod args;
mod commands;
mod failure;
mod measure_start;
mod output;
mod plot;
mod sequence;

use clap::{Parser, Subcommand};
use commands::{bench, demo, eval, export, grid, measure, merge, mesh, run, synth, track};
use failure::{one_line, Failure};
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
    Measure(Box<measure::Args>),
    /// Render a test image with exactly known geometry (and its truth file).
    Synth(synth::Args),
    /// Compare measured points with a truth file: bias, scatter, max error.
    Eval(eval::Args),
    /// Synthesise a star, measure it from a circle, print the accuracy and
    /// write the overlay.
    Demo(demo::Args),
    /// Benchmark studies: `bench paper` re-runs the paper's section 7.
    Bench(bench::Args),
    /// Track a curve through a sequence of images, each frame started from
    /// the previous frame's result.
    Track(track::Args),
    /// Run a job file (TOML): images, named curves, widths, outputs.
    Run(run::Args),
    /// Join the parts of a job run with `run --shard K/N` into one summary.
    Merge(merge::Args),
    /// Export a measured curve from its result file: DXF SPLINE (CAD),
    /// SVG of exact cubic Béziers.
    Export(export::Args),
    /// The NURBS surface patch between two measured edges: JSON, VTK (.vtu).
    Mesh(mesh::Args),
    /// Circle-grid strain analysis: every printed circle measured as an
    /// ellipse, its true strains with their uncertainties.
    Grid(grid::Args),
}

/// Let a closed output pipe end the program, as it does the shell's tools:
/// Rust ignores `SIGPIPE`, so `println!` to a reader that has gone panics.
/// Results are written to files as they are made, so those already made
/// stay.
#[cfg(unix)]
fn restore_sigpipe() {
    // SAFETY: first thing in `main`, before any thread exists; `SIG_DFL`
    // is a valid disposition for `SIGPIPE`.
    unsafe {
        libc::signal(libc::SIGPIPE, libc::SIG_DFL);
    }
}

#[cfg(not(unix))]
fn restore_sigpipe() {}

/// Let glibc's allocator keep the memory a fit frees for its next
/// allocations: blocks under 16 MiB from the heap (not mapped afresh from
/// the kernel and unmapped when freed), and up to 32 MiB of free memory
/// kept at the heap's top. A fit builds a band of a few megabytes at every
/// stage and re-reference and frees the previous one; with glibc's
/// defaults each new band's pages are faulted in and zeroed by the kernel
/// again. Larger blocks (a megapixel image's buffers) are still mapped,
/// which bounds what is kept (docs/benchmarks.md, "Speed of one
/// measurement").
#[cfg(all(target_os = "linux", target_env = "gnu"))]
fn keep_freed_memory() {
    // SAFETY: first thing in `main` after the signal disposition, before
    // any allocation of ours or any thread; `mallopt` only sets the
    // allocator's thresholds (its return value, 0 on an unknown option,
    // leaves the defaults in place).
    unsafe {
        libc::mallopt(libc::M_MMAP_THRESHOLD, 16 << 20);
        libc::mallopt(libc::M_TRIM_THRESHOLD, 32 << 20);
    }
}

#[cfg(not(all(target_os = "linux", target_env = "gnu")))]
fn keep_freed_memory() {}

fn main() -> ExitCode {
    restore_sigpipe();
    keep_freed_memory();
    let cli = Cli::parse();
    let result = match cli.command {
        Command::Measure(a) => measure::run(*a),
        Command::Synth(a) => synth::run(a),
        Command::Eval(a) => eval::run(a),
        Command::Demo(a) => demo::run(a),
        Command::Bench(a) => bench::run(a),
        Command::Track(a) => track::run(a),
        Command::Run(a) => run::run(a),
        Command::Merge(a) => merge::run(a),
        Command::Export(a) => export::run(a),
        Command::Mesh(a) => mesh::run(a),
        Command::Grid(a) => grid::run(a),
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
