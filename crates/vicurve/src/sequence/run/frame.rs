//! One frame of a sequence: decode it, measure its curves (in parallel,
//! each from the previous frame's result or from its start), derive the
//! widths, and write the frame's files.
//!
//! Files of frame `STEM` in the output folder (each written to a temporary
//! name and renamed):
//! - `STEM.json` and `STEM.csv` (one curve), or `STEM.NAME.json` and
//!   `STEM.NAME.csv` per curve (several): the result file of `measure
//!   --out` with a `sequence` record added (the job's fingerprint, the frame,
//!   where the fit started), and the samples as `measure --points` writes
//!   them;
//! - `STEM.WIDTH.csv` per width: `position,width,sigma` (position along
//!   the axis, width and its standard deviation, px);
//! - `STEM.overlay.png` or `.svg` on request.

use super::job::{AxisChoice, Job, OverlayKind};
use super::resume::{rebuild, tracking_state};
use super::summary::Row;
use crate::curve::SplineCurve;
use crate::derived::{width_profile, WidthAxis};
use crate::fit::{Measurement, Outcome, TrackCache, TrackSnapshot, TrackState};
use crate::interp::Interpolation;
use crate::io::write::temporary_name;
use crate::io::{write_atomic, write_points_csv};
use crate::report::ResultFile;
use crate::sequence::{measure_curve, CurveStep, FrameSamplers};
use crate::Image;
use rayon::prelude::*;
use serde::Serialize;
use std::fmt::Write as _;
use std::path::{Path, PathBuf};
use std::sync::Mutex;

pub use crate::sequence::Previous;

/// The state a sequence carries from frame to frame.
pub struct Tracking {
    /// Per curve of the job.
    pub last_good: Vec<Option<Previous>>,
    /// Per curve of the job: the band the last good frame left
    /// ([`TrackCache`]), as that frame's measurement left it in memory or
    /// as read back from its result file (the same numbers, so that a
    /// resumed run goes on exactly as an uninterrupted one).
    pub caches: Vec<Mutex<TrackCache>>,
    /// Per width of the job: the axis, fixed for the whole sequence (an
    /// estimated axis is estimated once, on the first frame where both
    /// curves are good, so that positions compare between frames).
    pub axes: Vec<Option<WidthAxis>>,
}

impl Tracking {
    /// Nothing carried yet: the axes given by the job fixed.
    pub fn new(job: &Job) -> Tracking {
        Tracking {
            last_good: vec![None; job.curves.len()],
            caches: job.curves.iter().map(|_| Mutex::default()).collect(),
            axes: job
                .widths
                .iter()
                .map(|w| match w.axis {
                    AxisChoice::X => Some(WidthAxis::x()),
                    AxisChoice::Y => Some(WidthAxis::y()),
                    AxisChoice::Explicit { origin, direction } => {
                        WidthAxis::new(origin, direction).ok()
                    }
                    AxisChoice::Estimate => None,
                })
                .collect(),
        }
    }

    /// Take the good curves of a frame (as written: see [`super::resume`])
    /// with their tracking states and bands, and fix the estimated axes
    /// that are not yet. `measured`: the frame was just measured, and the
    /// caches hold what its good curves left (else it was read back, and
    /// they are made from `bands`). A curve that is not good goes on from
    /// its last good frame, band included.
    pub fn update(
        &mut self,
        job: &Job,
        stem: &str,
        good: &[Option<SplineCurve>],
        states: &[Option<TrackState>],
        bands: &[Option<TrackSnapshot>],
        measured: bool,
    ) {
        let curves = self.last_good.iter_mut().zip(&self.caches);
        for (((slot, cache), g), (state, band)) in curves.zip(good).zip(states.iter().zip(bands)) {
            let mut cache = cache.lock().unwrap_or_else(|e| e.into_inner());
            match g {
                Some(c) => {
                    *slot = Some(Previous {
                        curve: c.clone(),
                        stem: stem.to_string(),
                        state: *state,
                        band: band.clone(),
                    });
                    if !measured {
                        *cache = band
                            .clone()
                            .map(TrackCache::from_snapshot)
                            .unwrap_or_default();
                    }
                }
                None => {
                    let last = slot.as_ref().and_then(|p| p.band.clone());
                    *cache = last.map(TrackCache::from_snapshot).unwrap_or_default();
                }
            }
        }
        for (w, axis) in job.widths.iter().zip(self.axes.iter_mut()) {
            if axis.is_none() {
                if let (Some(a), Some(b)) = (&good[w.between[0]], &good[w.between[1]]) {
                    *axis = WidthAxis::estimate_curves(a, b).ok();
                }
            }
        }
    }
}

/// File names of a frame's results.
pub struct FrameFiles {
    /// The job's output folder.
    pub dir: PathBuf,
    /// The frame's name.
    pub stem: String,
    several: bool,
}

impl FrameFiles {
    /// The files of frame `stem` of `job`.
    pub fn new(job: &Job, stem: &str) -> FrameFiles {
        FrameFiles {
            dir: job.out_dir.clone(),
            stem: stem.to_string(),
            several: job.curves.len() > 1,
        }
    }

    fn named(&self, name: &str, ext: &str) -> PathBuf {
        self.dir.join(format!("{}.{name}.{ext}", self.stem))
    }

    /// The result JSON of a curve.
    pub fn json(&self, curve: &str) -> PathBuf {
        if self.several {
            self.named(curve, "json")
        } else {
            self.dir.join(format!("{}.json", self.stem))
        }
    }

    /// The points CSV of a curve.
    pub fn points(&self, curve: &str) -> PathBuf {
        if self.several {
            self.named(curve, "csv")
        } else {
            self.dir.join(format!("{}.csv", self.stem))
        }
    }

    /// The profile CSV of a width.
    pub fn width(&self, name: &str) -> PathBuf {
        self.named(name, "csv")
    }

    /// The overlay of the frame.
    pub fn overlay(&self, kind: OverlayKind) -> PathBuf {
        self.named(
            "overlay",
            match kind {
                OverlayKind::Png => "png",
                OverlayKind::Svg => "svg",
            },
        )
    }
}

/// What the result file records of the sequence, next to the measurement.
#[derive(Serialize)]
struct SequenceInfo<'a> {
    /// Fingerprint of the job (see [`super::resume::Manifest`]).
    job: &'a str,
    /// Index of the frame in the sequence (from 0).
    frame: usize,
    /// The curve's name in the job.
    curve: &'a str,
    /// `init`, or the stem of the frame whose measured B-spline (its
    /// `curve` record) this fit started from.
    started_from: &'a str,
    /// A retry, when there was one.
    #[serde(skip_serializing_if = "str::is_empty")]
    note: &'a str,
    /// The band the fit leaves for the next frame (see
    /// [`crate::fit::TrackCache`]), so that a resumed run reuses it as an
    /// uninterrupted one does.
    #[serde(skip_serializing_if = "Option::is_none")]
    track_band: Option<&'a TrackSnapshot>,
}

/// The result file of `measure --out` and the sequence record.
#[derive(Serialize)]
struct FrameRecord<'a> {
    #[serde(flatten)]
    result: ResultFile<'a>,
    sequence: SequenceInfo<'a>,
}

/// Draws a frame's overlay (the command line's drawing; the library has
/// none): the format, the file to write, the frame and its curves' fits
/// (in the job's order). The error, one line, is logged as a problem of
/// the frame.
pub type OverlayWriter =
    dyn Fn(OverlayKind, &Path, &Image, &[CurveStep]) -> Result<(), String> + Sync;

/// What a frame produced.
pub struct FrameOutput {
    /// Each curve's fit, its start and configuration (per curve of the
    /// job; empty when the frame could not be decoded).
    pub steps: Vec<CurveStep>,
    /// Its summary rows (curves, then widths).
    pub rows: Vec<Row>,
    /// The good curves as written (per curve of the job).
    pub good: Vec<Option<SplineCurve>>,
    /// What the next frame's tracking schedule takes from them.
    pub states: Vec<Option<TrackState>>,
    /// The bands they leave for the next frame, written down.
    pub bands: Vec<Option<TrackSnapshot>>,
    /// One line per problem, for the log.
    pub problems: Vec<String>,
}

/// Measure frame `index` (recorded as `input`, decoded into `decoded`;
/// results named `files.stem`), its overlay drawn by `overlay` when the
/// job asks for one.
pub fn measure_frame(
    job: &Job,
    fingerprint: &str,
    (index, input): (usize, &str),
    decoded: Result<Image, String>,
    files: &FrameFiles,
    tracking: &Tracking,
    overlay: Option<&OverlayWriter>,
) -> FrameOutput {
    let stem = files.stem.as_str();
    let image = match decoded {
        Ok(i) => i,
        Err(e) => return unreadable(job, stem, &e),
    };
    let path_text = input;
    let samplers = FrameSamplers::new(&image);
    let sampler = |k: Interpolation| samplers.get(k);
    // Curves are independent: measure them in parallel (each fit also
    // uses the thread pool for its bands and matrices).
    let results: Vec<CurveStep> = job
        .curves
        .par_iter()
        .zip(tracking.last_good.par_iter())
        .zip(tracking.caches.par_iter())
        .map(|((spec, prev), cache)| {
            let prev = if job.track { prev.as_ref() } else { None };
            let mut cache = cache.lock().unwrap_or_else(|e| e.into_inner());
            measure_curve(spec.as_sequence(), prev, &mut cache, &sampler)
        })
        .collect();

    let mut rows = Vec::new();
    let mut good: Vec<Option<SplineCurve>> = vec![None; job.curves.len()];
    let mut states: Vec<Option<TrackState>> = vec![None; job.curves.len()];
    let bands: Vec<Option<TrackSnapshot>> = results.iter().map(|r| r.band.clone()).collect();
    let mut measured: Vec<Option<&Measurement>> = vec![None; job.curves.len()];
    let mut problems = Vec::new();
    for (i, (spec, r)) in job.curves.iter().zip(&results).enumerate() {
        let row = Row::new(stem, &spec.name);
        let m = match &r.measured {
            Ok(m) => m,
            Err(e) => {
                problems.push(format!("{stem}: {}: {e}", spec.name));
                rows.push(row.failed("failed", e));
                continue;
            }
        };
        let record = FrameRecord {
            result: ResultFile::new(
                path_text,
                (image.width(), image.height()),
                &r.init,
                &r.config,
                m,
            ),
            sequence: SequenceInfo {
                job: fingerprint,
                frame: index,
                curve: &spec.name,
                started_from: &r.started_from,
                note: &r.note,
                track_band: r.band.as_ref(),
            },
        };
        let written = write_curve_files(job, files, &spec.name, &record, m);
        // The summary's derived measures are the result file's.
        let derived = &record.result.derived;
        let closed = match &derived.closed_error {
            Some(e) => Err(e.as_str()),
            None => Ok(derived.closed.as_ref()),
        };
        let mut row = row.curve(m, &r.started_from, &r.note, closed);
        if let Err(e) = written {
            problems.push(format!("{stem}: {}: {e}", spec.name));
            rows.push(row.failed("failed", &e));
            continue;
        }
        match m.outcome {
            Outcome::Diverged { divergence } => {
                problems.push(format!(
                    "{stem}: {}: the fit diverged: {divergence}",
                    spec.name
                ));
            }
            o => {
                if o == Outcome::IterationLimit {
                    problems.push(format!(
                        "{stem}: {}: the iteration limit was reached before convergence (the curve is kept)",
                        spec.name
                    ));
                }
                // Go on from the curve as written (see `resume`).
                match rebuild(&m.curve_data()) {
                    Ok(c) => {
                        states[i] = tracking_state(m, &c);
                        good[i] = Some(c);
                        measured[i] = Some(m);
                    }
                    Err(e) => {
                        problems.push(format!("{stem}: {}: {e}", spec.name));
                        row = row.failed("failed", &e);
                    }
                }
            }
        }
        rows.push(row);
    }

    for (w, axis) in job.widths.iter().zip(&tracking.axes) {
        let row = Row::new(stem, &w.name);
        let (a, b) = (measured[w.between[0]], measured[w.between[1]]);
        let (Some(a), Some(b)) = (a, b) else {
            rows.push(row.failed("failed", "one of its curves was not measured"));
            continue;
        };
        // An estimated axis not fixed yet is this frame's.
        let axis = match axis {
            Some(x) => Ok(*x),
            None => match (&good[w.between[0]], &good[w.between[1]]) {
                (Some(ca), Some(cb)) => {
                    WidthAxis::estimate_curves(ca, cb).map_err(|e| e.to_string())
                }
                _ => Err("no axis".to_string()),
            },
        };
        let profile =
            axis.and_then(|axis| width_profile(a, b, &axis, w.step).map_err(|e| e.to_string()));
        match profile {
            Ok(p) => {
                let mut text = String::from("position,width,sigma\n");
                for s in &p.samples {
                    let _ = writeln!(text, "{:.6},{:.6},{:.3e}", s.position, s.width, s.sigma);
                }
                match write_atomic(&files.width(&w.name), text.as_bytes()) {
                    Ok(()) => {
                        let row = row.width(p.min.as_ref(), p.samples.len());
                        if p.min.is_none() {
                            problems.push(format!("{stem}: {}: no section in common", w.name));
                        }
                        rows.push(row);
                    }
                    Err(e) => {
                        problems.push(format!("{stem}: {}: {e}", w.name));
                        rows.push(row.failed("failed", &e));
                    }
                }
            }
            Err(e) => {
                problems.push(format!("{stem}: {}: {e}", w.name));
                rows.push(row.failed("failed", &e));
            }
        }
    }

    if let Some(kind) = job.outputs.overlay {
        let drawn = match overlay {
            Some(draw) => draw(kind, &files.overlay(kind), &image, &results),
            None => Err("not drawn (overlays are drawn by the command-line tool)".into()),
        };
        if let Err(e) = drawn {
            problems.push(format!("{stem}: overlay: {e}"));
        }
    }
    FrameOutput {
        steps: results,
        rows,
        good,
        states,
        bands,
        problems,
    }
}

/// A frame that cannot be read: every curve and width fails with `reason`.
fn unreadable(job: &Job, stem: &str, reason: &str) -> FrameOutput {
    let rows = job
        .curves
        .iter()
        .map(|c| c.name.as_str())
        .chain(job.widths.iter().map(|w| w.name.as_str()))
        .map(|n| Row::new(stem, n).failed("failed", reason))
        .collect();
    FrameOutput {
        steps: Vec::new(),
        rows,
        good: vec![None; job.curves.len()],
        states: vec![None; job.curves.len()],
        bands: vec![None; job.curves.len()],
        problems: vec![format!("{stem}: {reason}")],
    }
}

/// The JSON and points CSV of one curve.
fn write_curve_files(
    job: &Job,
    files: &FrameFiles,
    name: &str,
    record: &FrameRecord,
    m: &Measurement,
) -> Result<(), String> {
    let text = serde_json::to_string_pretty(record)
        .map_err(|e| format!("cannot encode the result: {e}"))?
        + "\n";
    if job.outputs.points {
        // The points first: the JSON is what marks the curve done.
        let target = files.points(name);
        let tmp = temporary_name(&target);
        write_points_csv(&tmp, m)?;
        std::fs::rename(&tmp, &target)
            .map_err(|e| format!("cannot write {}: {e}", target.display()))?;
    }
    write_atomic(&files.json(name), text.as_bytes())
}
