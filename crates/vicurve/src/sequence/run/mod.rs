//! Running a job over a sequence of frames, with its files: what `vicurve
//! run`, `vicurve track` and the Python package's `vicurve.run` and
//! `vicurve.track(..., out_dir=...)` do, so that they write the same files
//! and resume each other's runs.
//!
//! Frames are measured in order, each curve started from its last good
//! result (see [`frame`]). After every frame the summary is rewritten
//! atomically; a run that is killed loses at most the frame in progress,
//! and running the same job again skips the frames done (see [`resume`])
//! and goes on from the last good curves, with the same results as an
//! uninterrupted run. `force` measures every frame again.
//!
//! - [`job`]: job files, and the jobs front ends build from their options
//!   ([`options`]: one curve's options as text);
//! - [`frames`]: a job's frames (image files, pages of a stack);
//! - [`frame`]: one frame (measure its curves, derive the widths, write
//!   its files);
//! - [`resume`]: the job's fingerprint and the frames read back;
//! - [`summary`]: `summary.csv`, and how a run ended;
//! - [`SequenceRun`]: frames one at a time, given by the caller;
//!   [`run_job`]: every frame of a job's list.

mod all;
pub mod frame;
pub mod frames;
pub mod job;
pub mod options;
pub mod resume;
mod runner;
pub mod summary;

pub use all::{run_job, RunObserver, RunReport};
pub use options::CurveOptions;
pub use runner::SequenceRun;
pub use summary::RunStatus;

/// A message on one line whatever its source (a TOML parser's error spans
/// several).
pub fn one_line(msg: &str) -> String {
    msg.split_whitespace().collect::<Vec<_>>().join(" ")
}
