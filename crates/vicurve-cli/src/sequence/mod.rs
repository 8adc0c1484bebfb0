//! Running a job over a sequence of frames: `vicurve run` and `vicurve
//! track`.
//!
//! Frames are measured in order, each curve started from its last good
//! result (see [`frame`]), with a progress bar (frames per second
//! and the time left) on a terminal and one log line per frame otherwise.
//! After every frame the summary is rewritten atomically; a run that is
//! killed loses at most the frame in progress, and running the same job
//! again skips the frames done (see [`resume`]) and goes on from the
//! last good curves, with the same results as an uninterrupted run.
//! `--force` measures every frame again.
//!
//! The outcome: every frame measured, `Ok`; some frames failed (an
//! unreadable image, a fit that diverged or could not start), exit 3 with
//! one line saying how many and the first reason (the others are measured
//! and written, the summary says which failed and why); nothing measured at
//! all, or the job cannot run, exit 1.
//!
//! - [`job`]: job files, and the job `track`'s flags describe;
//! - [`frame`]: one frame (decode, measure its curves, derive the widths,
//!   write its files);
//! - `resume`: the job's fingerprint and the frames read back;
//! - `summary`: `summary.csv`, and the exit status read from it;
//! - `progress`: the progress bar; `plots`: the width plots.

pub mod frame;
pub mod frames;
pub mod job;
pub mod merge;
mod plots;
mod progress;
mod resume;
mod summary;

use crate::failure::Failure;
use crate::output::write_atomic;
use frame::{measure_frame, FrameFiles, Tracking};
use frames::Frame;
use job::{Job, MANIFEST_STEM, SUMMARY_STEM};
use resume::{read_fingerprint, read_recorded, remove_stale_temporaries, Manifest};
use std::collections::HashMap;
use std::time::{Duration, Instant};
use summary::{read_summary, status, write_summary};
use vicurve::curve::SplineCurve;
use vicurve::fit::{TrackSnapshot, TrackState};

/// A summary larger than this (bytes) is rewritten at most every
/// [`SUMMARY_PERIOD`] rather than after every frame.
const SUMMARY_SMALL: usize = 1 << 20;
const SUMMARY_PERIOD: Duration = Duration::from_secs(1);

/// Run `job`; `force` measures every frame again.
pub fn run(job: &Job, force: bool) -> Result<(), Failure> {
    let dir = &job.out_dir;
    std::fs::create_dir_all(dir)
        .map_err(|e| format!("cannot create the output folder {}: {e}", dir.display()))?;
    remove_stale_temporaries(dir);
    let manifest = Manifest {
        vicurve_version: env!("CARGO_PKG_VERSION"),
        track: job.track,
        curves: &job.curves,
        widths: &job.widths,
    };
    let fingerprint = manifest.fingerprint();
    let manifest_path = dir.join(format!("{MANIFEST_STEM}.json"));
    if !force {
        if let Some(old) = read_fingerprint(&manifest_path) {
            if old != fingerprint {
                return Err(Failure::Error(format!(
                    "{} holds the results of another job (different curves or settings); use --force to measure every frame again there, or another output folder",
                    dir.display()
                )));
            }
        }
    }
    let mut manifest_text = serde_json::to_value(&manifest).unwrap_or_default();
    manifest_text["fingerprint"] = serde_json::Value::String(fingerprint.clone());
    write_atomic(
        &manifest_path,
        (serde_json::to_string_pretty(&manifest_text).unwrap_or_default() + "\n").as_bytes(),
    )?;

    let summary_path = dir.join(match &job.shard {
        None => format!("{SUMMARY_STEM}.csv"),
        Some(s) => s.summary_name(),
    });
    let offset = job.shard.map_or(0, |s| s.first);
    let mut old_rows = if force {
        HashMap::new()
    } else {
        read_summary(&summary_path)
    };
    let rows_per_frame = job.curves.len() + job.widths.len();
    let stems: Vec<String> = job.images.iter().map(|f| f.stem.clone()).collect();
    // Done: rows in the summary and every curve's JSON present (checked
    // further when read back).
    let done: Vec<bool> = stems
        .iter()
        .map(|stem| {
            let files = FrameFiles::new(job, stem);
            old_rows
                .get(stem)
                .is_some_and(|r| r.len() == rows_per_frame)
                && job.curves.iter().all(|c| files.json(&c.name).is_file())
        })
        .collect();
    let to_do = done.iter().filter(|d| !**d).count();

    let bar = progress::bar(to_do as u64)?;
    let log = |line: &str| {
        if bar.is_hidden() {
            eprintln!("{line}");
        } else {
            bar.println(line);
        }
    };
    let mut tracking = Tracking::new(job);
    let mut lines: Vec<Vec<String>> = vec![Vec::new(); stems.len()];
    let mut skipped = 0;
    let mut measured = 0;
    let mut last_write = Instant::now();
    let total = stems.len();
    // The next frame, decoded ahead (its index and what decoding gave).
    let mut prefetched: Option<(usize, Result<vicurve::Image, String>)> = None;
    for (i, (frame, stem)) in job.images.iter().zip(&stems).enumerate() {
        let files = FrameFiles::new(job, stem);
        if done[i] {
            if let Some((good, states, bands)) = read_done(job, &fingerprint, frame, &files) {
                tracking.update(job, stem, &good, &states, &bands, false);
                lines[i] = old_rows.remove(stem).unwrap_or_default();
                skipped += 1;
                continue;
            }
            // Unreadable or from another job after all: measure it.
            bar.inc_length(1);
        }
        let started = Instant::now();
        let decoded = match prefetched.take() {
            Some((k, d)) if k == i => d,
            _ => frame.decode(),
        };
        // The next frame to measure is decoded while this one is measured
        // (a frame's fit leaves a core idle part of the time).
        let next = (i + 1..total).find(|&k| !done[k]);
        let (out, next_decoded) = rayon::join(
            || {
                measure_frame(
                    job,
                    &fingerprint,
                    offset + i,
                    (frame, decoded),
                    &files,
                    &tracking,
                )
            },
            || next.map(|k| (k, job.images[k].decode())),
        );
        prefetched = next_decoded;
        tracking.update(job, stem, &out.good, &out.states, &out.bands, true);
        lines[i] = out.rows.iter().map(|r| r.to_line()).collect();
        measured += 1;
        for p in &out.problems {
            log(&format!("vicurve: warning: {p}"));
        }
        bar.inc(1);
        if bar.is_hidden() {
            eprintln!(
                "vicurve: frame {}/{total} {stem}: {} in {:.0} ms",
                i + 1,
                if out.problems.is_empty() {
                    "measured"
                } else {
                    "measured with problems"
                },
                started.elapsed().as_secs_f64() * 1e3
            );
        }
        let size: usize = lines.iter().flatten().map(|l| l.len() + 1).sum();
        if size < SUMMARY_SMALL || last_write.elapsed() >= SUMMARY_PERIOD {
            write_summary(&summary_path, &lines)?;
            last_write = Instant::now();
        }
    }
    write_summary(&summary_path, &lines)?;
    bar.finish_and_clear();
    if skipped > 0 {
        eprintln!(
            "vicurve: {skipped} frame(s) already done, skipped (--force measures them again); {measured} measured"
        );
    }
    if job.outputs.plots && job.shard.is_none() {
        if let Err(e) = plots::write_plots(job, &stems, &lines) {
            eprintln!("vicurve: warning: {e}");
        }
    }
    status(&lines, total, &summary_path)
}

/// A done frame's good curves, their tracking states and the bands they
/// left, per curve of the job.
type DoneCurves = (
    Vec<Option<SplineCurve>>,
    Vec<Option<TrackState>>,
    Vec<Option<TrackSnapshot>>,
);

/// A done frame's curves as written, `None` if any JSON is unusable.
fn read_done(
    job: &Job,
    fingerprint: &str,
    frame: &Frame,
    files: &FrameFiles,
) -> Option<DoneCurves> {
    let input = frame.input();
    let recorded: Vec<_> = job
        .curves
        .iter()
        .map(|c| read_recorded(&files.json(&c.name), fingerprint, &input))
        .collect::<Option<_>>()?;
    let mut done: DoneCurves = (Vec::new(), Vec::new(), Vec::new());
    for r in recorded {
        let (curve, state, band) = if r.good {
            (Some(r.curve), r.state, r.band)
        } else {
            (None, None, None)
        };
        done.0.push(curve);
        done.1.push(state);
        done.2.push(band);
    }
    Some(done)
}
