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

use super::job::{AxisChoice, CurveSpec, Job, OverlayKind};
use super::resume::{rebuild, tracking_state};
use super::summary::Row;
use crate::output::measurement::overlay_layers;
use crate::output::overlay;
use crate::output::{write_atomic, write_points_csv, ResultFile};
use rayon::prelude::*;
use serde::Serialize;
use std::fmt::Write as _;
use std::path::{Path, PathBuf};
use std::sync::{Mutex, OnceLock};
use vicurve::curve::{InitialCurve, SplineCurve};
use vicurve::derived::{width_profile, WidthAxis};
use vicurve::fit::{
    measure_from, measure_tracked_cached, FitConfig, Measurement, Outcome, TrackCache,
    TrackSnapshot, TrackState,
};
use vicurve::interp::{Interpolation, Sampler};
use vicurve::Image;

/// Spacing of the points that stand for the previous curve in a tracked
/// frame's `initial_curve` record, px (the fit itself starts from the
/// previous B-spline: as it is for the tracking schedule, which refits it
/// itself, smoothed for the job's stages, see [`tracked_start`]).
const RECORD_SPACING: f64 = 2.0;

/// Control-point spacing of a tracked frame's start, px (at most; at least
/// 16 control intervals along the curve).
const START_SPACING: f64 = 10.0;

/// The last good curve of one curve of the job, the frame it is from, and
/// what the tracking schedule takes from it.
#[derive(Clone)]
pub struct Previous {
    pub curve: SplineCurve,
    pub stem: String,
    pub state: Option<TrackState>,
    /// The band its frame left for the next one, written down (see
    /// [`vicurve::fit::TrackCache`]).
    pub band: Option<TrackSnapshot>,
}

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
    pub dir: PathBuf,
    pub stem: String,
    several: bool,
}

impl FrameFiles {
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

    fn overlay(&self, kind: OverlayKind) -> PathBuf {
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
    /// [`vicurve::fit::TrackCache`]), so that a resumed run reuses it as an
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

/// One curve measured on a frame.
struct CurveResult {
    /// The measurement, or why there is none.
    measured: Result<Measurement, String>,
    /// The start as recorded, and the configuration used.
    init: InitialCurve,
    config: FitConfig,
    started_from: String,
    note: String,
    /// What the curve's cache holds after the fit, written down.
    band: Option<TrackSnapshot>,
}

/// What a frame produced.
pub struct FrameOutput {
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

/// Decode frame `path` (the error as the one line the summary records).
pub fn decode_frame(path: &Path) -> Result<Image, String> {
    vicurve::io::load_image(path).map_err(|e| e.to_string())
}

/// Measure frame `index` (`path`, decoded by [`decode_frame`] into
/// `decoded`; results named `files.stem`).
pub fn measure_frame(
    job: &Job,
    fingerprint: &str,
    index: usize,
    (path, decoded): (&Path, Result<Image, String>),
    files: &FrameFiles,
    tracking: &Tracking,
) -> FrameOutput {
    let stem = files.stem.as_str();
    let image = match decoded {
        Ok(i) => i,
        Err(e) => return unreadable(job, stem, &e),
    };
    let path_text = path.display().to_string();
    // One prepared image per interpolation, prepared when a fit first asks
    // for it: the tracking schedule needs no interpolation (bilinear, which
    // shares the image's pixels), and the cubic prefilter of a whole frame
    // would cost more than its fit.
    let samplers: Vec<(Interpolation, OnceLock<Sampler>)> = Interpolation::ALL
        .iter()
        .map(|&k| (k, OnceLock::new()))
        .collect();
    let sampler = |k: Interpolation| {
        samplers
            .iter()
            .find(|(kind, _)| *kind == k)
            .map(|(_, s)| s.get_or_init(|| Sampler::new(&image, k)))
    };
    // Curves are independent: measure them in parallel (each fit also
    // uses the thread pool for its bands and matrices).
    let results: Vec<CurveResult> = job
        .curves
        .par_iter()
        .zip(tracking.last_good.par_iter())
        .zip(tracking.caches.par_iter())
        .map(|((spec, prev), cache)| {
            let prev = if job.track { prev.as_ref() } else { None };
            let mut cache = cache.lock().unwrap_or_else(|e| e.into_inner());
            measure_curve(spec, prev, &mut cache, &sampler)
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
                &path_text,
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
        if let Err(e) = write_overlay(kind, files, &image, &results) {
            problems.push(format!("{stem}: overlay: {e}"));
        }
    }
    FrameOutput {
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
        rows,
        good: vec![None; job.curves.len()],
        states: vec![None; job.curves.len()],
        bands: vec![None; job.curves.len()],
        problems: vec![format!("{stem}: {reason}")],
    }
}

/// Measure one curve: from the previous frame's result with the tracked
/// configuration (the tracking schedule first when the spec asks for it
/// and the previous frame left a state; the tracked configuration's own
/// schedule when that cannot measure), or from its start with the first; a
/// tracked fit that fails is tried again from the same curve with the first
/// frame's configuration when the two differ. The tracking schedule
/// measures on the band `cache` keeps when it serves, and leaves this
/// frame's there (the result records it, written down); any other fit
/// empties the cache.
fn measure_curve<'s>(
    spec: &CurveSpec,
    prev: Option<&Previous>,
    cache: &mut TrackCache,
    sampler: &dyn Fn(Interpolation) -> Option<&'s Sampler>,
) -> CurveResult {
    let mut result = measure_curve_with(spec, prev, cache, sampler);
    result.band = cache.snapshot();
    result
}

/// [`measure_curve`] but for the band it records.
fn measure_curve_with<'s>(
    spec: &CurveSpec,
    prev: Option<&Previous>,
    cache: &mut TrackCache,
    sampler: &dyn Fn(Interpolation) -> Option<&'s Sampler>,
) -> CurveResult {
    let run = |reference: SplineCurve, config: &FitConfig| -> Result<Measurement, String> {
        let s = sampler(config.interpolation)
            .ok_or_else(|| "no image prepared for this interpolation".to_string())?;
        measure_from(s, reference, config).map_err(|e| e.to_string())
    };
    match prev {
        None => {
            cache.clear();
            let measured = spec
                .init
                .to_curve()
                .map_err(|e| e.to_string())
                .and_then(|c| run(c, &spec.first));
            CurveResult {
                measured,
                init: spec.init.clone(),
                config: spec.first.clone(),
                started_from: "init".into(),
                note: String::new(),
                band: None,
            }
        }
        Some(p) => {
            let init = InitialCurve::Polyline {
                points: record_points(&p.curve),
                closed: p.curve.is_closed(),
            };
            // The tracking schedule takes the previous curve as it is (it
            // refits it with control points one element apart itself); the
            // stages of the job, the smoothed start.
            let plain = sampler(Interpolation::Bilinear);
            let short = match (spec.tracking_schedule, &p.state, plain) {
                (true, Some(state), Some(s)) => {
                    // Empties the cache when it cannot measure.
                    measure_tracked_cached(s, p.curve.clone(), state, &spec.tracked, cache)
                        .ok()
                        .flatten()
                }
                _ => {
                    cache.clear();
                    None
                }
            };
            let tracked_result = |measured| CurveResult {
                measured,
                init: init.clone(),
                config: spec.tracked.clone(),
                started_from: p.stem.clone(),
                note: String::new(),
                band: None,
            };
            if let Some(m) = short {
                return tracked_result(Ok(m));
            }
            let start = match tracked_start(&p.curve) {
                Ok(c) => c,
                Err(e) => return tracked_result(Err(e)),
            };
            let first = run(start.clone(), &spec.tracked);
            let failed = match &first {
                Err(e) => Some(e.clone()),
                Ok(m) => match m.outcome {
                    Outcome::Diverged { divergence } => Some(divergence.to_string()),
                    _ => None,
                },
            };
            match failed {
                Some(why) if spec.tracked != spec.first => CurveResult {
                    measured: run(start, &spec.first),
                    init,
                    config: spec.first.clone(),
                    started_from: p.stem.clone(),
                    note: format!(
                        "the tracked fit failed ({why}); measured again with the first frame's stages"
                    ),
                    band: None,
                },
                _ => tracked_result(first),
            }
        }
    }
}

/// The start of a tracked frame measured with the job's stages (the
/// tracking schedule refits its start itself): the previous curve refitted
/// with control points [`START_SPACING`] apart. The measured curve has
/// control points 2 px apart and carries the previous frame's noise at
/// that scale; a fit whose displacement has longer elements (as a schedule
/// without coarse stages has) cannot remove it, so it would pass on to the
/// next frame and grow from frame to frame (`examples/track_speed.rs`
/// tracks a star with the `2:auto` stage alone).
fn tracked_start(curve: &SplineCurve) -> Result<SplineCurve, String> {
    let length = curve.param_length();
    let spacing = (length / 16.0).clamp(2.0, START_SPACING);
    let n = ((length / 0.5).ceil() as usize).max(8);
    let pts: Vec<[f64; 2]> = curve
        .sample_params(n)
        .into_iter()
        .map(|u| curve.point(u))
        .collect();
    SplineCurve::fit(&pts, curve.is_closed(), 3, spacing).map_err(|e| e.to_string())
}

/// Points of `curve` about [`RECORD_SPACING`] apart.
fn record_points(curve: &SplineCurve) -> Vec<[f64; 2]> {
    let n = (curve.param_length() / RECORD_SPACING).ceil().max(4.0) as usize;
    curve
        .sample_params(n)
        .into_iter()
        .map(|u| curve.point(u))
        .collect()
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
        let tmp = target.with_file_name(format!(
            ".{}.tmp-{}",
            target.file_name().unwrap_or_default().to_string_lossy(),
            std::process::id()
        ));
        write_points_csv(&tmp, m)?;
        std::fs::rename(&tmp, &target)
            .map_err(|e| format!("cannot write {}: {e}", target.display()))?;
    }
    write_atomic(&files.json(name), text.as_bytes())
}

/// Every curve of the frame over the image.
fn write_overlay(
    kind: OverlayKind,
    files: &FrameFiles,
    image: &Image,
    results: &[CurveResult],
) -> Result<(), String> {
    let mut layers = Vec::new();
    for r in results {
        if let Ok(m) = &r.measured {
            let l = overlay_layers(&r.init, &r.config, m).map_err(|e| e.message())?;
            layers.extend(l);
        }
    }
    let path = files.overlay(kind);
    match kind {
        OverlayKind::Png => overlay::write_png(&path, image, &layers, 1),
        OverlayKind::Svg => overlay::write_svg(&path, image, &layers),
    }
}
