//! [`run_job`]: every frame of a job, the next frame to measure decoded
//! while this one is measured; what `vicurve run`, `vicurve track` and the
//! Python package's `vicurve.run` do.

use super::frame::{FrameOutput, OverlayWriter};
use super::job::Job;
use super::runner::SequenceRun;
use super::summary::RunStatus;
use crate::error::Result;
use crate::image::Image;
use std::time::Duration;

/// What a front end is told as a job runs (a progress bar, a log); every
/// method does nothing unless overridden.
pub trait RunObserver {
    /// The run starts with `to_do` frames to measure (the others look done).
    fn started(&mut self, to_do: usize) {
        let _ = to_do;
    }
    /// A frame that looked done has unusable files and is measured again.
    fn one_more(&mut self) {}
    /// Frame `index` (from 0, of `total`) named `stem` was measured, in
    /// `elapsed` (decoding included).
    fn measured(
        &mut self,
        (index, total): (usize, usize),
        stem: &str,
        out: &FrameOutput,
        elapsed: Duration,
    ) {
        let _ = (index, total, stem, out, elapsed);
    }
}

/// The counts and the end of a finished run.
#[derive(Clone, Debug, PartialEq, Eq)]
pub struct RunReport {
    /// Frames skipped as done by an earlier run.
    pub skipped: usize,
    /// Frames measured by this run.
    pub measured: usize,
    /// How the run ended.
    pub status: RunStatus,
    /// The summary's rows (CSV lines, no header) of every frame, in order.
    pub lines: Vec<Vec<String>>,
}

/// Run every frame of `job` (`force`: measure the frames done before
/// again), telling `observer`; overlays drawn by `overlay`. The next frame
/// to measure is decoded while this one is measured (a frame's fit leaves
/// a core idle part of the time), so that at most two frames are in memory.
///
/// Errors: [`crate::Error::Job`] when the run cannot start or its summary
/// cannot be written; the frames' own failures are in the summary and the
/// report's status.
pub fn run_job(
    job: Job,
    force: bool,
    observer: &mut dyn RunObserver,
    overlay: Option<&OverlayWriter>,
) -> Result<RunReport> {
    let mut run = SequenceRun::start(job, force)?;
    let frames = run.job().images.clone();
    let total = frames.len();
    let done: Vec<bool> = frames.iter().map(|f| run.is_done(&f.stem)).collect();
    observer.started(done.iter().filter(|d| !**d).count());
    let mut prefetched: Option<(usize, std::result::Result<Image, String>)> = None;
    for (i, frame) in frames.iter().enumerate() {
        let input = frame.input();
        if done[i] {
            if run.resume(&frame.stem, &input)?.is_some() {
                continue;
            }
            observer.one_more();
        }
        let started = std::time::Instant::now();
        let decoded = match prefetched.take() {
            Some((k, d)) if k == i => d,
            _ => frame.decode(),
        };
        let next = (i + 1..total).find(|&k| !done[k]);
        let (out, next_decoded) = rayon::join(
            || run.measure((&frame.stem, &input), decoded, overlay),
            || next.map(|k| (k, frames[k].decode())),
        );
        prefetched = next_decoded;
        observer.measured((i, total), &frame.stem, &out?, started.elapsed());
    }
    let status = run.finish()?;
    let (skipped, measured) = run.counts();
    Ok(RunReport {
        skipped,
        measured,
        status,
        lines: run.lines().to_vec(),
    })
}
