//! Running a job over a sequence of frames: `vicurve run` and `vicurve
//! track`, by the library's runner ([`vicurve::sequence::run`]: the frames,
//! their files, the summary and the resume), with a progress bar (frames
//! per second and the time left) on a terminal and one log line per frame
//! otherwise, the overlays and the width plots.
//!
//! The outcome: every frame measured, `Ok`; some frames failed (an
//! unreadable image, a fit that diverged or could not start), exit 3 with
//! one line saying how many and the first reason (the others are measured
//! and written, the summary says which failed and why); nothing measured at
//! all, or the job cannot run, exit 1.
//!
//! - `merge`: the parts of a sharded run joined;
//! - `overlay`: the overlays of a frame's curves;
//! - `progress`: the progress bar; `plots`: the width plots.

pub mod merge;
mod overlay;
mod plots;
mod progress;

use crate::failure::Failure;
use indicatif::ProgressBar;
use std::time::Duration;
use vicurve::sequence::run::frame::FrameOutput;
use vicurve::sequence::run::job::Job;
use vicurve::sequence::run::{run_job, RunObserver, RunStatus};

pub use vicurve::sequence::run::{frames, job};

/// Run `job`; `force` measures every frame again.
pub fn run(job: &Job, force: bool) -> Result<(), Failure> {
    let mut log = Log {
        bar: progress::bar(0)?,
    };
    let report = run_job(job.clone(), force, &mut log, Some(&overlay::draw))?;
    log.bar.finish_and_clear();
    if report.skipped > 0 {
        eprintln!(
            "vicurve: {} frame(s) already done, skipped (--force measures them again); {} measured",
            report.skipped, report.measured
        );
    }
    if job.outputs.plots && job.shard.is_none() {
        let stems: Vec<String> = job.images.iter().map(|f| f.stem.clone()).collect();
        if let Err(e) = plots::write_plots(job, &stems, &report.lines) {
            eprintln!("vicurve: warning: {e}");
        }
    }
    exit_status(report.status)
}

/// The command's exit for a run's status (see the module docs).
pub fn exit_status(status: RunStatus) -> Result<(), Failure> {
    match status {
        RunStatus::Complete => Ok(()),
        RunStatus::SomeFailed(m) => Err(Failure::Diverged(m)),
        RunStatus::NoneMeasured(m) => Err(Failure::Error(m)),
    }
}

/// The progress bar, or one line per frame when stderr is not a terminal.
struct Log {
    bar: ProgressBar,
}

impl Log {
    fn line(&self, line: &str) {
        if self.bar.is_hidden() {
            eprintln!("{line}");
        } else {
            self.bar.println(line);
        }
    }
}

impl RunObserver for Log {
    fn started(&mut self, to_do: usize) {
        self.bar.set_length(to_do as u64);
    }

    fn one_more(&mut self) {
        self.bar.inc_length(1);
    }

    fn measured(
        &mut self,
        (index, total): (usize, usize),
        stem: &str,
        out: &FrameOutput,
        elapsed: Duration,
    ) {
        for p in &out.problems {
            self.line(&format!("vicurve: warning: {p}"));
        }
        self.bar.inc(1);
        if self.bar.is_hidden() {
            eprintln!(
                "vicurve: frame {}/{total} {stem}: {} in {:.0} ms",
                index + 1,
                if out.problems.is_empty() {
                    "measured"
                } else {
                    "measured with problems"
                },
                elapsed.as_secs_f64() * 1e3
            );
        }
    }
}
