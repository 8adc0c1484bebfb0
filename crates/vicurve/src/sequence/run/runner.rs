//! [`SequenceRun`]: a job's frames one at a time, in order, with its files
//! and its resume (see [`super`]). The frames come from the caller, so
//! that a front end reads them as it likes (a job's files with the next
//! one decoded ahead, or a Python iterator).

use super::frame::{measure_frame, FrameFiles, FrameOutput, OverlayWriter, Tracking};
use super::job::{Job, MANIFEST_STEM, SUMMARY_STEM};
use super::resume::{read_fingerprint, read_recorded, remove_stale_temporaries, Manifest};
use super::summary::{read_summary, status, write_summary, RunStatus};
use crate::curve::SplineCurve;
use crate::error::{Error, Result};
use crate::fit::{TrackSnapshot, TrackState};
use crate::image::Image;
use crate::io::write_atomic;
use std::collections::{HashMap, HashSet};
use std::path::{Path, PathBuf};
use std::time::{Duration, Instant};

/// A summary larger than this (bytes) is rewritten at most every
/// [`SUMMARY_PERIOD`] rather than after every frame.
const SUMMARY_SMALL: usize = 1 << 20;
const SUMMARY_PERIOD: Duration = Duration::from_secs(1);

/// A job being run: its output folder claimed, the rows of the frames done
/// so far, what tracking carries to the next frame.
pub struct SequenceRun {
    job: Job,
    fingerprint: String,
    summary_path: PathBuf,
    old_rows: HashMap<String, Vec<String>>,
    tracking: Tracking,
    lines: Vec<Vec<String>>,
    stems: HashSet<String>,
    last_write: Instant,
    skipped: usize,
    measured: usize,
}

/// A done frame's good curves, their tracking states and the bands they
/// left, per curve of the job.
type DoneCurves = (
    Vec<Option<SplineCurve>>,
    Vec<Option<TrackState>>,
    Vec<Option<TrackSnapshot>>,
);

impl SequenceRun {
    /// Claim `job.out_dir` for the job: create it, remove a killed run's
    /// temporary files, check that what it holds is this job's (unless
    /// `force`: every frame is measured again) and write the manifest.
    ///
    /// Errors: [`Error::Job`] when the folder cannot be created or written,
    /// or holds another job's results.
    pub fn start(job: Job, force: bool) -> Result<SequenceRun> {
        let dir = &job.out_dir;
        std::fs::create_dir_all(dir).map_err(|e| {
            Error::job(format!(
                "cannot create the output folder {}: {e}",
                dir.display()
            ))
        })?;
        remove_stale_temporaries(dir);
        let manifest = Manifest {
            vicurve_version: env!("CARGO_PKG_VERSION"),
            track: job.track,
            curves: &job.curves,
            widths: &job.widths,
        };
        let fingerprint = manifest.fingerprint();
        let manifest_path = dir.join(format!("{MANIFEST_STEM}.json"));
        if !force && read_fingerprint(&manifest_path).is_some_and(|old| old != fingerprint) {
            return Err(Error::job(format!(
                "{} holds the results of another job (different curves or settings); use --force to measure every frame again there, or another output folder",
                dir.display()
            )));
        }
        let mut text = serde_json::to_value(&manifest).unwrap_or_default();
        text["fingerprint"] = serde_json::Value::String(fingerprint.clone());
        let text = serde_json::to_string_pretty(&text).unwrap_or_default() + "\n";
        write_atomic(&manifest_path, text.as_bytes()).map_err(Error::job)?;
        let summary_path = dir.join(match &job.shard {
            None => format!("{SUMMARY_STEM}.csv"),
            Some(s) => s.summary_name(),
        });
        let old_rows = if force {
            HashMap::new()
        } else {
            read_summary(&summary_path)
        };
        Ok(SequenceRun {
            tracking: Tracking::new(&job),
            job,
            fingerprint,
            summary_path,
            old_rows,
            lines: Vec::new(),
            stems: HashSet::new(),
            last_write: Instant::now(),
            skipped: 0,
            measured: 0,
        })
    }

    /// The job.
    pub fn job(&self) -> &Job {
        &self.job
    }

    /// The summary file this run writes.
    pub fn summary_path(&self) -> &Path {
        &self.summary_path
    }

    /// Frames skipped as done, and frames measured, so far.
    pub fn counts(&self) -> (usize, usize) {
        (self.skipped, self.measured)
    }

    /// Whether the frame `stem` looks done: its rows in the summary and
    /// every curve's JSON present (checked further by [`Self::resume`]).
    pub fn is_done(&self, stem: &str) -> bool {
        let files = FrameFiles::new(&self.job, stem);
        let rows = self.job.curves.len() + self.job.widths.len();
        self.old_rows.get(stem).is_some_and(|r| r.len() == rows)
            && self
                .job
                .curves
                .iter()
                .all(|c| files.json(&c.name).is_file())
    }

    /// The next frame (`stem`, recorded as `input`) when it is done: its
    /// curves read back and tracking set to go on from them, its summary
    /// rows (CSV lines) returned. `None` when it must be measured (not
    /// done, or its files are unreadable or another job's).
    ///
    /// Errors: [`Error::Job`] for a frame name used twice in the run.
    pub fn resume(&mut self, stem: &str, input: &str) -> Result<Option<Vec<String>>> {
        if !self.is_done(stem) {
            return Ok(None);
        }
        let Some((good, states, bands)) = self.read_done(stem, input) else {
            return Ok(None);
        };
        self.claim(stem, input)?;
        self.tracking
            .update(&self.job, stem, &good, &states, &bands, false);
        let rows = self.old_rows.remove(stem).unwrap_or_default();
        self.lines.push(rows.clone());
        self.skipped += 1;
        Ok(Some(rows))
    }

    /// Measure the next frame (`stem`, recorded as `input`, decoded into
    /// `decoded` or why it could not be), write its files and the summary,
    /// and set tracking to go on from it; `overlay` draws the overlay a
    /// job asks for.
    ///
    /// Errors: [`Error::Job`] for a frame name used twice in the run, or a
    /// summary that cannot be written (the frame's own problems are in its
    /// output, not errors).
    pub fn measure(
        &mut self,
        (stem, input): (&str, &str),
        decoded: std::result::Result<Image, String>,
        overlay: Option<&OverlayWriter>,
    ) -> Result<FrameOutput> {
        self.claim(stem, input)?;
        let index = self.job.shard.map_or(0, |s| s.first) + self.lines.len();
        let files = FrameFiles::new(&self.job, stem);
        let fp = &self.fingerprint;
        let out = measure_frame(
            &self.job,
            fp,
            (index, input),
            decoded,
            &files,
            &self.tracking,
            overlay,
        );
        self.tracking
            .update(&self.job, stem, &out.good, &out.states, &out.bands, true);
        self.lines
            .push(out.rows.iter().map(|r| r.to_line()).collect());
        self.measured += 1;
        let size: usize = self.lines.iter().flatten().map(|l| l.len() + 1).sum();
        if size < SUMMARY_SMALL || self.last_write.elapsed() >= SUMMARY_PERIOD {
            write_summary(&self.summary_path, &self.lines)?;
            self.last_write = Instant::now();
        }
        Ok(out)
    }

    /// Write the summary of every frame run, and say how the run ended.
    ///
    /// Errors: [`Error::Job`] when the summary cannot be written.
    pub fn finish(&self) -> Result<RunStatus> {
        write_summary(&self.summary_path, &self.lines)?;
        Ok(status(&self.lines, self.lines.len(), &self.summary_path))
    }

    /// The summary rows (CSV lines) of every frame run so far, in order.
    pub fn lines(&self) -> &[Vec<String>] {
        &self.lines
    }

    /// Record `stem` as run; a second frame of the same name is refused
    /// (their files would overwrite each other).
    fn claim(&mut self, stem: &str, input: &str) -> Result<()> {
        if !self.stems.insert(stem.to_string()) {
            return Err(Error::job(format!(
                "two frames are named '{stem}' (results are named after the file stem): {input}"
            )));
        }
        Ok(())
    }

    /// A done frame's curves as written, `None` if any JSON is unusable.
    fn read_done(&self, stem: &str, input: &str) -> Option<DoneCurves> {
        let files = FrameFiles::new(&self.job, stem);
        let recorded: Vec<_> = self
            .job
            .curves
            .iter()
            .map(|c| read_recorded(&files.json(&c.name), &self.fingerprint, input))
            .collect::<Option<_>>()?;
        let mut done: DoneCurves = (Vec::new(), Vec::new(), Vec::new());
        for r in recorded {
            let good = r.good;
            done.0.push(good.then_some(r.curve));
            done.1.push(r.state.filter(|_| good));
            done.2.push(r.band.filter(|_| good));
        }
        Some(done)
    }
}
