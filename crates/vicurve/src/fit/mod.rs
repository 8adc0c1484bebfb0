//! The measurement: multi-scale Gauss–Newton correlation of the virtual
//! image with the physical one (method, sections 5 and 6).
//!
//! [`measure`] runs the stages of the schedule in turn. In each stage the
//! curve is `x(s) = x0(s) + U(s) n(s)` with `U` a B-spline of the stage's
//! elements on the reference `x0`; the reference is replaced by the current
//! curve (new band, new matrix, `U = 0`) when a stage ends and whenever
//! `max |U|` exceeds a fraction of `R` within a stage, so that a start far
//! from the edge (a circle crossing a star) converges.
//!
//! ```no_run
//! use vicurve::{fit::{measure, FitConfig}, curve::InitialCurve, io::load_image};
//! let image = load_image("part.png".as_ref())?;
//! let init = InitialCurve::Circle { cx: 320.0, cy: 240.0, r: 100.0 };
//! let m = measure(&image, &init, &FitConfig::default())?;
//! println!("{}: length {:.4} px", m.outcome, m.length());
//! # Ok::<(), vicurve::Error>(())
//! ```

pub mod breaks;
mod config;
mod correlation;
pub mod grow;
pub mod levels;
mod track;

pub use crate::measurement::{
    Divergence, IterationRecord, LevelSample, Measurement, Outcome, RunKind, Sample, StageReport,
};
pub use config::{default_stages, parse_stages, Coords, Elements, FitConfig, Polarity, Stage};
pub use levels::LevelModel;
pub use track::{
    measure_tracked, measure_tracked_cached, measure_tracked_from, TrackCache, TrackSnapshot,
    TrackState,
};

use crate::band::Band;
use crate::curve::{InitialCurve, SplineCurve};
use crate::error::{Error, Result};
use crate::image::Image;
use crate::interp::Sampler;
use crate::psf;
use crate::spline::{Basis, MAX_DEGREE};
use crate::virtual_image::{Kind, Profile};
use correlation::{Correlation, StepFailure};
use rayon::prelude::*;
use std::f64::consts::TAU;
use std::time::Instant;

/// Spacing of the samples used to rebuild a reference curve, pixels (the
/// smallest; see `reference_sample_step`).
const REFERENCE_SAMPLE_STEP: f64 = 0.5;
/// Samples per control-point interval of a rebuilt reference, at least
/// (`reference_sample_step`).
const REFERENCE_SAMPLES_PER_INTERVAL: f64 = 16.0;
/// Largest spacing of those samples, pixels.
const MAX_REFERENCE_SAMPLE_STEP: f64 = 2.0;
/// Control-point spacing of output curves, and the smallest of reference
/// curves, pixels.
const CURVE_SPACING: f64 = 2.0;
/// Largest control-point spacing of a new reference, pixels (see
/// `reference_spacing`).
const MAX_REFERENCE_SPACING: f64 = 40.0;
/// Half-width of the first band on which the edge's blur is estimated,
/// pixels (a wider one is tried when the edge fills it).
const EDGE_SPREAD_BAND: f64 = 8.0;
/// The band half-width that matches an edge of spread `s` is about
/// `MATCHED_BAND * s` (the transition of an error-function edge spans
/// roughly +-2.5 s; R = 2 px for a sharp, focused edge).
const MATCHED_BAND: f64 = 2.5;
/// A band narrower than the matched one by more than this factor does not
/// see the whole edge.
const BAND_MISMATCH: f64 = 1.5;
/// The blur correction needs an edge that an error function fits this well
/// (fraction of the variance explained); clutter or texture turn it off.
const MIN_EDGE_FIT_QUALITY: f64 = 0.8;
/// Re-references allowed within one stage before it is declared stuck.
const MAX_REREFERENCES: usize = 100;
/// The last stage of the default schedule re-references until its
/// displacement is under this, pixels (see `settle` in [`measure_from`]).
///
/// A settling re-reference moves the result by a small fraction of the
/// displacement it re-references on: 3 to 7 % in a measurement of 8
/// tracked frames each of an exact-coverage disc (r = 120 px) and a
/// five-lobed star (r = 130 (1 + 0.15 cos 5θ)) moving 0.4 px per frame,
/// blur 1 px, noise 0 and 1 %. There, stopping after the first settle
/// (displacements up to 0.02 px) instead of settling to 2e-3 px moved no
/// sample by more than 9.4e-4 px, and changed the bias against the exact
/// shape by 2e-5 px at most and the largest error by under 8e-4 px; the
/// 2e-3 px tolerance also sat at the noise floor of the 1 % noise star,
/// whose settles then ran to `MAX_SETTLES` without contracting.
const SETTLE_TOLERANCE: f64 = 0.02;
/// A settle whose displacement is not under this fraction of the previous
/// run's (with the same profile) does not contract: noise, not shape,
/// drives it, and the stage stops. Only for displacements under
/// `SETTLE_NOISE_CHECK` times `SETTLE_TOLERANCE`: larger ones are a shape
/// the elements cannot follow (a corner without a break), which settles
/// to `MAX_SETTLES` as before.
const SETTLE_CONTRACTION: f64 = 0.5;
/// See [`SETTLE_CONTRACTION`].
const SETTLE_NOISE_CHECK: f64 = 5.0;
/// Settling re-references of the last stage, at most.
const MAX_SETTLES: usize = 4;
/// A run of the last stage that a settle is sure to follow (its first,
/// see `settle` in [`measure_from`]) stops after a step under this (pixels)
/// instead of [`FitConfig::tolerance`]: it only places the settle's
/// reference, and the settle's result moves by a few percent of the
/// reference's error, the error [`SETTLE_TOLERANCE`] accepts of the
/// settles themselves. The step is applied, and Gauss–Newton converges
/// fast here: the error left is about the next step's (1e-4 px after a
/// 3e-3 px step on the `track_speed` example's star). With the
/// once-per-stage checks, tracked frames of that example take 4.1
/// iterations instead of 5.2.
const PRE_SETTLE_TOLERANCE: f64 = SETTLE_TOLERANCE;
/// A run on one reference that has not converged after this many
/// iterations goes on with the reference's profile derivative in its
/// gradient (`Correlation::use_reference_gradient`): the displaced one's
/// may keep a model that does not fit the image from contracting. Runs
/// that converge take 2 to 6.
const DISPLACED_GRADIENT_ITERATIONS: usize = 12;
/// Contraction ratio of successive steps under which a run's error left
/// is estimated (`error_left`).
const FAST_CONTRACTION: f64 = 0.25;
/// Largest spacing of the points of `x0 + U n` the output curve is fitted
/// to (control points `CURVE_SPACING` apart: four points per interval),
/// pixels; see `Final::samples` for the spacing taken.
const FINE_STEP: f64 = 0.5;
/// How much the displacement may stretch the reference (`1 + U kappa`)
/// before the output samples, every `k`-th point of `x0 + U n`, come
/// closer than the requested spacing (`Final::samples`).
const STRETCH_ALLOWANCE: f64 = 0.03;
/// Spacing of [`Measurement::levels`] along the curve, pixels.
const LEVEL_SAMPLE_SPACING: f64 = 8.0;
/// Band pixels used to fit the blur of the pixel-edge profile at most.
const BLUR_FIT_PIXELS: usize = 8192;
/// Runs of the pixel-edge stage with an updated blur, at most.
const MAX_BLUR_UPDATES: usize = 3;
/// A fitted blur that differs from the one in use by more than this (pixels)
/// is worth another run.
const BLUR_TOLERANCE: f64 = 0.01;
/// The pixel-edge stage's band covers the pixel's largest extent along a
/// normal (`sqrt(2) / 2` px), this many blur deviations and
/// `PIXEL_EDGE_PLATEAU` px of the flat levels on each side, and is at least
/// `PIXEL_EDGE_MIN_BAND` px wide. Narrow on purpose: the flat levels fix
/// `a` and `c`, and on a noiseless 8-bit image a flat level rounded by up to
/// half a gray level no longer lies on the line through the transition's
/// levels; the wider its share of the band, the more the curve follows
/// (1.0 px of plateau and 3 blurs: -3.5e-3 px on a blur-1 disc at gray
/// levels 0.1 and 0.85; 0.5 px and 2 blurs: within +-7e-4 px).
const PIXEL_EDGE_REACH: f64 = 2.0;
/// See [`PIXEL_EDGE_REACH`], pixels.
const PIXEL_EDGE_PLATEAU: f64 = 0.5;
/// See [`PIXEL_EDGE_REACH`], pixels.
const PIXEL_EDGE_MIN_BAND: f64 = 1.5;
/// Iteration records reserved per stage at most (see
/// [`StageReport::history`]): the loop pushes without allocating up to here.
const HISTORY_RESERVE: usize = 1024;

/// Measure the curve in `image` starting from `init`.
///
/// Errors are reserved for inputs that cannot be measured at all: an
/// invalid configuration, an initial curve or first band outside the image,
/// a band with too few pixels. A fit that starts but fails later is
/// reported as [`Outcome::Diverged`] with the last good curve.
pub fn measure(image: &Image, init: &InitialCurve, config: &FitConfig) -> Result<Measurement> {
    config.validate()?;
    let sampler = Sampler::new(image, config.interpolation);
    let start = breaks::initial_curve(init, &config.breaks)?;
    measure_from(&sampler, start, config)
}

/// [`measure`] with a prepared image sampler and reference curve (for
/// sequences and benchmarks: the sampler's prefilter is done once).
pub fn measure_from(
    sampler: &Sampler,
    reference: SplineCurve,
    config: &FitConfig,
) -> Result<Measurement> {
    run_schedule(sampler, reference, config, None)
}

/// [`measure_from`]; with `tracked`, the schedule is the tracking one
/// instead (the pixel-edge stage alone, see [`track`]), on the band the
/// cache keeps when it serves, and the cache updated after it.
///
/// Runs on a thread of rayon's pool (the caller's own when it is one).
/// A fit has tens of parallel loops, each a fraction of a millisecond:
/// called from outside the pool, each would hand its work over to the pool
/// and put the caller to sleep until it is done, and the pool's threads
/// fall asleep between loops while the caller runs the serial parts. On
/// the `track_speed` example's frames, tracked from the main thread: 8.4
/// to 9.2 ms per frame this way against 9.0 to 9.8 ms (a scratch harness,
/// six runs each, in turns), and 77 to 86 frames/s against 68 to 82 in
/// the example itself (eight runs each, in turns, in a busy hour).
fn run_schedule(
    sampler: &Sampler,
    reference: SplineCurve,
    config: &FitConfig,
    tracked: Option<(TrackState, &mut TrackCache)>,
) -> Result<Measurement> {
    rayon::scope(|_| run_schedule_here(sampler, reference, config, tracked))
}

/// [`run_schedule`] on the calling thread.
fn run_schedule_here(
    sampler: &Sampler,
    reference: SplineCurve,
    config: &FitConfig,
    tracked: Option<(TrackState, &mut TrackCache)>,
) -> Result<Measurement> {
    let (tracked, mut cache) = match tracked {
        Some((t, c)) => (Some(t), Some(c)),
        None => (None, None),
    };
    config.validate()?;
    if sampler.kind() != config.interpolation {
        return Err(Error::invalid(
            "interpolation",
            "the sampler was prepared for another interpolation than the configuration's",
        ));
    }
    // The level model may be downgraded to the global pair on the way (see
    // `Correlation::levels_significant`).
    let mut config = config.clone();
    let closed = reference.is_closed();
    let (width, height) = (sampler.width(), sampler.height());
    let (mut stages, auto) = match (&config.stages, tracked) {
        (_, Some(t)) => (vec![t.stage()], true),
        (Some(s), None) => (s.clone(), false),
        (None, None) => (default_stages(), true),
    };
    let p = config.degree;
    let min_el = if closed { p + 1 } else { 1 };

    let mut current = breaks::prepare(reference, &config.breaks)?;
    // Tracking: the band the previous frame left, when it serves this one
    // (see `TrackCache`), and the margin of a new band.
    let mut reuse = match (tracked, cache.as_deref_mut()) {
        (Some(t), Some(c)) => c.take_for(&t, config.levels, sampler, config.coords),
        _ => None,
    };
    let track_margin = cache
        .as_deref()
        .map_or(track::TRACK_MARGIN, TrackCache::margin);
    // A tracked frame's run does not settle (see `track::TRACK_MARGIN`):
    // its reference, the previous frame's curve, is refitted with control
    // points one element apart first, as a settle's would be. The
    // displacement cannot remove detail finer than its elements, which
    // would otherwise stay in the result and pile up from frame to frame.
    // A kept band's reference was.
    match (tracked, &reuse) {
        (Some(_), Some(kept)) => current = kept.reference.clone(),
        (Some(t), None) => {
            let stage = t.stage();
            let n = stage.element_count(current.param_length(), min_el);
            let basis = breaks::displacement_basis(&current, p, n)?;
            let spacing = basis.element_length().max(CURVE_SPACING);
            let clip = Clip {
                half_width: stage.half_width + track_margin,
                width: sampler.width(),
                height: sampler.height(),
            };
            let zero = vec![0.0; basis.n_functions()];
            current = displaced(&current, &basis, &zero, spacing, clip)?;
        }
        (None, _) => {}
    }
    // Tracking: where the previous frame's curve is on the current band
    // (its displacement), and how far the curve moved on the frame's
    // earlier bands (pixels, the sum of their largest displacements: a
    // bound; none when the frame measured on one band).
    let mut run_start: Option<Vec<f64>> = None;
    let mut moved_before: Option<f64> = None;
    let mut reports = Vec::new();
    let mut skipped = Vec::new();
    let mut last: Option<Final> = None;
    let mut outcome = Outcome::Converged;

    let mut next_stage = 0;
    let mut edge_spread = None;
    // Whether a stage matched to the edge's blur was appended (once), and
    // the profile of that stage when it is a silhouette's pixel edge.
    // (A tracked schedule's one stage is that pixel-edge stage.)
    let mut matched_added = tracked.is_some();
    let mut pixel_edge: Option<Profile> = tracked.map(|t| t.profile());
    'stages: while next_stage < stages.len() {
        let k = next_stage;
        next_stage += 1;
        let stage = &stages[k].clone();
        let is_last = k + 1 == stages.len();
        let appended = matched_added && is_last;
        let r = stage.half_width;
        if auto && !is_last {
            let length = current.arc_length();
            let size = if closed { length / TAU } else { length };
            if r > 0.5 * size {
                skipped.push(format!(
                    "R = {r} px: too wide for a curve of length {length:.1} px"
                ));
                continue;
            }
        }
        let started = Instant::now();
        let mut iterations = 0;
        let mut rereferences = 0;
        let mut step = None;
        let mut blur_updates = 0;
        // Tracking: once a refit of the blur confirms the one in use, the
        // stage's settling runs do not refit it again.
        let mut blur_confirmed = false;
        // Once the last stage has chosen its elements, re-runs keep them.
        let mut fixed_elements: Option<usize> = None;
        // An open curve's new references keep their band inside the image.
        let clip = Clip {
            half_width: r,
            width,
            height,
        };
        let mut settles = 0;
        // A silhouette's stage that a pixel-edge stage follows leaves the
        // settling to it.
        let followed = config.kind == Kind::Silhouette && config.blur_correction && !matched_added;
        // Decided once per stage, on its first converged run (the runs
        // after it re-reference the same image a fraction of a pixel
        // away): whether varying levels are significant, whether the band
        // holds clutter (`None`: not yet probed), and the image noise.
        let mut levels_tested = false;
        let mut cluttered: Option<bool> = None;
        let mut stage_noise: Option<f64> = None;
        // The light's tilt, measured on the stage's first reference.
        let mut tilt: Option<correlation::MeasuredTilt> = None;
        // The largest displacement of the run before this one, pixels.
        let mut previous_move = f64::INFINITY;
        let mut history = Vec::with_capacity(config.max_iterations.min(HISTORY_RESERVE));
        loop {
            // The pushed pixel-edge profile is only ever the appended stage's.
            let pushed = if appended { pixel_edge } else { None };
            let profile = pushed.unwrap_or(Profile::Paper { kind: config.kind });
            let length = current.param_length();
            let n_elements = fixed_elements.unwrap_or_else(|| stage.element_count(length, min_el));
            // A kept band serves the frame's first run.
            let reused = match (iterations, rereferences) {
                (0, 0) => reuse.take(),
                _ => None,
            };
            let basis = match &reused {
                Some(kept) => kept.corr.basis.clone(),
                None => breaks::displacement_basis(&current, p, n_elements)?,
            };
            let first_band = last.is_none() && iterations == 0;
            // Coarse stages (all but the last) only bring the curve near the
            // edge: half the pixels do that, a quarter in bands of 16 px or
            // more (at least 8 pixels across per unit of length).
            let thin = match (is_last, r >= 16.0) {
                (true, _) => 1,
                (false, false) => 2,
                (false, true) => 4,
            };
            // A tracked frame's band has a margin, so that its one run
            // counts the pixels around the edge whatever the reference (see
            // `track::TRACK_MARGIN`); where that band does not fit in the
            // image, the plain one settles as the full schedule does.
            let margin = match (tracked, pushed) {
                (Some(_), Some(_)) => track_margin,
                _ => 0.0,
            };
            let (mut corr, band_pixels, kept_lambda) = if let Some(kept) = reused {
                let track::Kept {
                    mut corr,
                    lambda,
                    velocity,
                    ..
                } = *kept;
                corr.reload(sampler)?;
                let pixels = corr.band.len();
                (corr, pixels, Some((lambda, velocity)))
            } else {
                let plain = || {
                    Band::build_with(
                        &current,
                        &basis,
                        r,
                        profile,
                        width,
                        height,
                        thin,
                        config.coords,
                    )
                };
                let built = if margin > 0.0 {
                    let coords = config.coords;
                    Band::build_windowed(
                        &current, &basis, r, margin, profile, width, height, coords,
                    )
                    .or_else(|_| plain())
                } else {
                    plain()
                };
                let band = match built {
                    Ok(b) => b,
                    Err(e @ (Error::BandOutsideImage { .. } | Error::CurveOutsideImage { .. })) => {
                        if appended && iterations == 0 {
                            // The matched band does not fit: keep the result.
                            skipped.push(format!("R = {r} px (matched to the edge's blur): {e}"));
                            continue 'stages;
                        }
                        if first_band && auto && !is_last {
                            skipped.push(format!("R = {r} px: {e}"));
                            continue 'stages;
                        }
                        if first_band {
                            return Err(e);
                        }
                        if appended {
                            // An optional refinement: the previous result stands.
                            skipped.push(format!("R = {r} px (matched to the blur): {e}"));
                            break 'stages;
                        }
                        let (x, y) = match e {
                            Error::BandOutsideImage { x, y, .. }
                            | Error::CurveOutsideImage { x, y, .. } => (x, y),
                            _ => (f64::NAN, f64::NAN),
                        };
                        outcome = Outcome::Diverged {
                            divergence: Divergence::LeftImage { x, y },
                        };
                        reports.push(report(
                            stage,
                            profile,
                            &basis,
                            0,
                            iterations,
                            rereferences,
                            step,
                            started,
                            outcome,
                            std::mem::take(&mut history),
                        ));
                        break 'stages;
                    }
                    Err(e) => return Err(e),
                };
                let band_pixels = band.len();
                let prepared = Correlation::prepare(
                    band,
                    basis.clone(),
                    sampler,
                    config.levels,
                    tilt.as_ref(),
                );
                let corr = match prepared {
                    Ok(c) => c,
                    Err(e) if first_band => return Err(e),
                    Err(e) if appended => {
                        skipped.push(format!("R = {r} px (matched to the blur): {e}"));
                        break 'stages;
                    }
                    Err(_) => {
                        outcome = Outcome::Diverged {
                            divergence: Divergence::Degenerate,
                        };
                        reports.push(report(
                            stage,
                            profile,
                            &basis,
                            band_pixels,
                            iterations,
                            rereferences,
                            step,
                            started,
                            outcome,
                            std::mem::take(&mut history),
                        ));
                        break 'stages;
                    }
                };
                (corr, band_pixels, None)
            };
            if corr.noise_var.is_none() {
                corr.noise_var = stage_noise;
            }
            // A cluttered band's fits (its reweighted ones, and the stage's
            // later runs) keep the reference's profile derivative in their
            // gradient (`Correlation::use_reference_gradient`): with the
            // displaced one, on the test's disc crossed by two dark lines
            // (tests/robust.rs), the largest error went from 2.8e-2 to
            // 4.2e-2 px and the scatter away from the lines from 7.5e-3 to
            // 9.5e-3 px (the weights follow the residuals, and the clutter's
            // residuals are far beyond the noise; not understood further).
            if cluttered == Some(true) {
                corr.use_reference_gradient();
            }
            tilt = corr.measured_tilt().cloned();
            let mut lambda = vec![0.0; corr.n_unknowns()];
            if let Some((kept, velocity)) = kept_lambda {
                // The previous frame's curve, moved on as it moved last
                // (see `TrackCache`). The blur stands as the band's first
                // frame fitted it: a sequence's blur changes slowly, and
                // the next band (a few frames on) fits it again.
                blur_confirmed = true;
                lambda.clone_from(&kept);
                for (l, v) in lambda.iter_mut().zip(velocity.iter().flatten()) {
                    *l += v;
                }
                // The profile on the curvature of that curve, as a band
                // built on it would have (see `band`).
                corr.band.bend_to(&corr.basis, &lambda);
                run_start = Some(kept);
            } else if tracked.is_some() {
                run_start = Some(lambda.clone());
            }
            let budget = config.max_iterations.saturating_sub(iterations);
            // A band with a margin needs no settle (see `track::TRACK_MARGIN`).
            let windowed = corr.band.margin() > 0.0;
            // A run that a settle is sure to follow only places its reference.
            let pre_settle = auto && is_last && !followed && settles == 0 && !windowed;
            let tolerance = if pre_settle {
                config.tolerance.max(PRE_SETTLE_TOLERANCE)
            } else {
                config.tolerance
            };
            // A windowed band serves displacements within its margin.
            let reref_limit = if rereferences >= MAX_REREFERENCES {
                f64::INFINITY
            } else if windowed {
                corr.band.margin()
            } else {
                config.rereference_fraction * r
            };
            let before = history.len();
            let (end, used) = iterate_to_end(
                &mut corr,
                &mut lambda,
                sampler,
                &config,
                r,
                (budget, tolerance),
                reref_limit,
                &mut step,
                (&mut history, RunKind::Reference),
            );
            iterations += used;
            // Tracking: a step beyond the band's half-width means that the
            // band does not see the edge (the start is too far from it, or
            // the iteration went astray); the frame is for the full
            // schedule, whose wide bands do, rather than for a chase that
            // ends wherever the steps happen to land.
            let lost = tracked.is_some() && history[before..].iter().any(|h| h.max_step > r);
            let end = if lost {
                Run::Failed(Divergence::NoContrast)
            } else {
                end
            };
            let stage_end = match end {
                Run::Rereference => None,
                Run::Converged => Some(Outcome::Converged),
                Run::IterationLimit => Some(Outcome::IterationLimit),
                Run::Failed(divergence) => Some(Outcome::Diverged { divergence }),
            };
            match stage_end {
                None => {
                    let spacing = reference_spacing(&corr.basis);
                    current = displaced(&current, &corr.basis, &lambda, spacing, clip)?;
                    rereferences += 1;
                    let moved = largest_change(&lambda, run_start.as_deref());
                    moved_before = Some(moved_before.unwrap_or(0.0) + moved);
                }
                Some(Outcome::Diverged { divergence }) if appended => {
                    skipped.push(format!("R = {r} px (matched to the blur): {divergence}"));
                    break 'stages;
                }
                Some(o @ Outcome::Diverged { .. }) => {
                    outcome = o;
                    reports.push(report(
                        stage,
                        profile,
                        &corr.basis,
                        band_pixels,
                        iterations,
                        rereferences,
                        step,
                        started,
                        o,
                        std::mem::take(&mut history),
                    ));
                    break 'stages;
                }
                Some(o) => {
                    outcome = o;
                    // Varying levels that explain no more than noise would
                    // are dropped (they cost precision): this stage runs
                    // once more with the global pair, and so do the next.
                    let test_levels = o == Outcome::Converged && !levels_tested;
                    levels_tested |= test_levels;
                    if test_levels
                        && corr.varying_levels()
                        && !corr.levels_significant(&lambda, sampler)
                    {
                        config.levels = LevelModel::Global;
                        let band = corr.band.clone();
                        if let Ok(mut global) =
                            Correlation::prepare(band, basis.clone(), sampler, config.levels, None)
                        {
                            let mut global_lambda = lambda.clone();
                            let mut global_step = None;
                            let (end, used) = iterate_to_end(
                                &mut global,
                                &mut global_lambda,
                                sampler,
                                &config,
                                r,
                                (config.max_iterations, tolerance),
                                f64::INFINITY,
                                &mut global_step,
                                (&mut history, RunKind::GlobalLevels),
                            );
                            iterations += used;
                            if let (Run::Converged, Some(_)) = (end, global_step) {
                                (corr, lambda, step) = (global, global_lambda, global_step);
                            }
                        }
                    }
                    let auto_elements = matches!(stage.elements, Elements::Auto { .. });
                    if let (Elements::Auto { shortest, .. }, Some(s), None) =
                        (stage.elements, step, fixed_elements)
                    {
                        let refined = refine(
                            &current,
                            corr,
                            lambda,
                            s,
                            shortest,
                            sampler,
                            &config,
                            (r, profile),
                            &mut history,
                        )?;
                        (corr, lambda, step) = (refined.0, refined.1, Some(refined.2));
                        iterations += refined.3;
                    }
                    if auto_elements {
                        fixed_elements = Some(corr.basis.n_elements());
                    }
                    if o == Outcome::Converged && cluttered != Some(false) {
                        let (used, found) = robust_refit(
                            &mut corr,
                            &mut lambda,
                            &mut step,
                            sampler,
                            &config,
                            r,
                            &mut history,
                        );
                        iterations += used;
                        cluttered = Some(found);
                    }
                    // The noise of a clean band serves the stage's next runs
                    // (a cluttered one's estimate is made without the
                    // rejected pixels, on each run's own weights).
                    if cluttered == Some(false) && stage_noise.is_none() {
                        stage_noise = corr.noise_var;
                    }
                    // The pixel edge's blur is fitted on the converged
                    // curve; a change means one more run with it.
                    let mut again = false;
                    if let (Some(Profile::PixelEdge { blur }), Outcome::Converged) = (pushed, o) {
                        if blur_updates < MAX_BLUR_UPDATES && !blur_confirmed {
                            let fitted = match tracked {
                                Some(_) => track::refit_blur(&corr, &lambda, blur),
                                None => fit_blur(&corr, &lambda, blur),
                            };
                            if (fitted - blur).abs() > BLUR_TOLERANCE {
                                pixel_edge = Some(Profile::PixelEdge { blur: fitted });
                                blur_updates += 1;
                                again = true;
                            } else {
                                blur_confirmed = tracked.is_some();
                            }
                        }
                    }
                    // Settle (default schedule, last stage): re-reference on
                    // the measured curve, refitted with control points one
                    // element apart, until the displacement vanishes. The
                    // result is then a fixed point of the stage (to about
                    // 1e-3 px, see `SETTLE_TOLERANCE`), whatever
                    // the path that led there: two different starts give the
                    // same curve, and detail finer than the elements that the
                    // start (a traced boundary, a hand-drawn polyline) put in
                    // the reference, which the displacement cannot remove,
                    // is gone. A pushed profile is also exact only at U = 0.
                    // At least once: a wiggle finer than the elements leaves
                    // U near 0. A silhouette's R = 2 px stage leaves this to
                    // the pixel-edge stage that follows it. "Vanishes":
                    // under `SETTLE_TOLERANCE`, or no longer contracting.
                    let moved = lambda.iter().fold(0.0, |m: f64, l| m.max(l.abs()));
                    let contracting = moved < SETTLE_CONTRACTION * previous_move
                        || moved >= SETTLE_NOISE_CHECK * SETTLE_TOLERANCE;
                    let settle = auto
                        && is_last
                        && !followed
                        && !windowed
                        && o == Outcome::Converged
                        && settles < MAX_SETTLES
                        && (settles == 0 || (moved > SETTLE_TOLERANCE && contracting));
                    // A run with a new blur starts a new comparison: its
                    // displacement came from the profile's change.
                    previous_move = if again { f64::INFINITY } else { moved };
                    if again || settle {
                        let spacing = corr.basis.element_length().max(CURVE_SPACING);
                        current = displaced(&current, &corr.basis, &lambda, spacing, clip)?;
                        let moved = largest_change(&lambda, run_start.as_deref());
                        moved_before = Some(moved_before.unwrap_or(0.0) + moved);
                        settles += 1;
                        rereferences += 1;
                        continue;
                    }
                    if let (None, Some(_)) = (corr.noise_var, step) {
                        corr.estimate_noise(&lambda, sampler);
                    }
                    // The next stage's reference, or the curve the edge's
                    // spread is measured on after the last stage; the
                    // tracking schedule's one stage needs neither.
                    let next = if tracked.is_some() && is_last {
                        None
                    } else {
                        let spacing = reference_spacing(&corr.basis);
                        Some(displaced(&current, &corr.basis, &lambda, spacing, clip)?)
                    };
                    reports.push(report(
                        stage,
                        profile,
                        &corr.basis,
                        band_pixels,
                        iterations,
                        rereferences,
                        step,
                        started,
                        o,
                        std::mem::take(&mut history),
                    ));
                    last = Some(Final {
                        half_width: r,
                        profile,
                        reference: match next {
                            Some(next) => std::mem::replace(&mut current, next),
                            None => current.clone(),
                        },
                        corr,
                        lambda,
                    });
                    break;
                }
            }
        }
        // After the last stage: estimate the edge's blur on the measured
        // curve. With the default schedule, measure once more with a profile
        // matched to it: for a silhouette the pixel edge through that blur
        // (exact, see `Profile::PixelEdge`); for a line much wider than the
        // last band, a band matched to it (the paper's optimum, R_g = R_f),
        // where the blur correction is exact.
        if is_last && config.blur_correction && tracked.is_none() {
            edge_spread = estimate_spread(sampler, &current, config.kind);
            let chosen = last.as_ref().map(|f| f.corr.basis.element_length());
            if let (Some(e), Some(chosen), true, false) = (edge_spread, chosen, auto, matched_added)
            {
                let good = e.fit_quality >= MIN_EDGE_FIT_QUALITY;
                let matched = (matched_band(&e) * 2.0).round() / 2.0;
                if good && config.kind == Kind::Silhouette {
                    // Starting from the elements the last stage chose, and
                    // refining further when that stage could (its sine
                    // profile may have stopped on aliasing, which the pixel
                    // edge does not have).
                    let elements = match stage.elements {
                        Elements::Auto { shortest, .. } => Elements::Auto {
                            longest: chosen,
                            shortest,
                        },
                        _ => Elements::Length(chosen),
                    };
                    let blur = (e.sigma * e.sigma - 1.0 / 12.0).max(0.0).sqrt();
                    matched_added = true;
                    pixel_edge = Some(Profile::PixelEdge { blur });
                    stages.push(Stage {
                        half_width: pixel_edge_band(blur),
                        elements,
                    });
                } else if good && matched > BAND_MISMATCH * r {
                    matched_added = true;
                    stages.push(Stage {
                        half_width: matched,
                        elements: Elements::Length(chosen),
                    });
                }
            }
            // A silhouette's last stage left its settling to a pixel-edge
            // stage that is not coming (no edge spread: an edge within
            // `EDGE_SPREAD_BAND` px of the image border; or an edge that is
            // not a blurred step: texture, clutter). Run it once more, this
            // time settling (its profile stays the sine, as `pixel_edge` is
            // unset), so that detail finer than the elements, such as a
            // traced start's staircase, does not stay in the result (about
            // +-0.2 px before on a disc 3 px from the border, seen once;
            // tests/realistic.rs asserts the result now).
            if let (Some(chosen), true, false, Kind::Silhouette) =
                (chosen, auto, matched_added, config.kind)
            {
                matched_added = true;
                stages.push(Stage {
                    half_width: r,
                    elements: Elements::Length(chosen),
                });
            }
        }
    }
    let fin = match last {
        Some(f) => f,
        None => {
            // Not even one stage completed: report the start as the result.
            return Ok(Measurement {
                edge_spread: None,
                blur_corrected: false,
                outcome,
                curve_fit_error: 0.0,
                samples: plain_samples(&current, config.sample_spacing),
                curve: current,
                stages: reports,
                skipped,
                levels: Vec::new(),
            });
        }
    };
    // The blur's curvature shift: removed when the edge (or line) looks
    // like a blurred step (or bar) and the last band is not much narrower than it
    // (a narrow band sees only the middle of a wide edge, and stays between
    // the half-level and the boundary).
    // A pixel-edge profile models the shift already.
    let pixel_edge_result = matches!(fin.profile, Profile::PixelEdge { .. });
    let blur = edge_spread
        .filter(|_| !pixel_edge_result)
        .filter(|e| e.fit_quality >= MIN_EDGE_FIT_QUALITY)
        .filter(|e| matched_band(e) <= BAND_MISMATCH * fin.half_width)
        .map(|e| e.sigma);
    let (curve, curve_fit_error, samples, levels) =
        fin.samples(config.sample_spacing, p.max(3), blur)?;
    if let Some(cache) = cache {
        // The frame's last band, kept for the next frame (see
        // `TrackCache`), with how far the curve moved; not after a robust
        // reweighting (the weights would carry over).
        let motion = run_start
            .as_deref()
            .map(|start| moved_before.unwrap_or(0.0) + largest_change(&fin.lambda, Some(start)));
        // How the curve moved on its one band, if it did on one.
        let velocity = match (&run_start, moved_before) {
            (Some(start), None) => Some(fin.lambda.iter().zip(start).map(|(l, s)| l - s).collect()),
            _ => None,
        };
        let keep = outcome == Outcome::Converged
            && motion.is_some()
            && fin.corr.band.margin() > 0.0
            && !fin.corr.reweighted();
        let kept = keep.then(|| {
            Box::new(track::Kept {
                reference: fin.reference,
                corr: fin.corr,
                lambda: fin.lambda,
                velocity,
                levels: config.levels,
                size: (width, height),
            })
        });
        cache.update(kept, motion);
    }
    Ok(Measurement {
        outcome,
        curve,
        curve_fit_error,
        samples,
        stages: reports,
        skipped,
        edge_spread,
        blur_corrected: blur.is_some() || pixel_edge_result,
        levels,
    })
}

/// The largest change of the coefficients from `start` (from 0 without
/// one), pixels: a bound on that of the displacement (the B-splines are a
/// partition of unity).
fn largest_change(lambda: &[f64], start: Option<&[f64]>) -> f64 {
    match start {
        Some(start) => lambda
            .iter()
            .zip(start)
            .fold(0.0, |m: f64, (l, s)| m.max((l - s).abs())),
        None => lambda.iter().fold(0.0, |m: f64, l| m.max(l.abs())),
    }
}

/// How a run of Gauss–Newton iterations on one reference ended.
enum Run {
    Converged,
    IterationLimit,
    /// `max |U|` passed the re-referencing limit.
    Rereference,
    Failed(Divergence),
}

/// Iterate on one reference until convergence (a step under `tolerance`,
/// pixels, or a step that leaves less than that: `error_left`), the
/// iteration `budget`, a displacement past `reref_limit` (pixels) or a
/// failure. Returns how it ended and the iterations used; `step` keeps the
/// last successful step.
#[allow(clippy::too_many_arguments)]
fn iterate_to_end(
    corr: &mut Correlation,
    lambda: &mut [f64],
    sampler: &Sampler,
    config: &FitConfig,
    r: f64,
    (budget, tolerance): (usize, f64),
    reref_limit: f64,
    step: &mut Option<correlation::Step>,
    (history, run): (&mut Vec<IterationRecord>, RunKind),
) -> (Run, usize) {
    let mut relax = Relaxation::new(lambda.len());
    let cap = config.max_step_fraction * r;
    let mut used = 0;
    // The two raw steps before this one (pixels), and the contraction the
    // system showed on earlier runs, for `error_left`.
    let mut previous_steps = [f64::INFINITY; 2];
    let mut known = corr.contraction();
    loop {
        if used >= budget {
            return (Run::IterationLimit, used);
        }
        if used == DISPLACED_GRADIENT_ITERATIONS && corr.displaced_gradient() {
            corr.use_reference_gradient();
            relax = Relaxation::new(lambda.len());
            known = None;
        }
        let s = match corr.iterate(lambda, sampler, config.polarity) {
            Ok(s) => s,
            Err(failure) => {
                let divergence = match failure {
                    StepFailure::LeftImage([x, y]) => Divergence::LeftImage { x, y },
                    StepFailure::NoContrast => Divergence::NoContrast,
                    StepFailure::NonFinite => Divergence::NonFinite,
                };
                return (Run::Failed(divergence), used);
            }
        };
        history.push(IterationRecord {
            iteration: history.len(),
            max_step: s.max_step,
            residual_rms: s.residual_rms,
            run,
            new_reference: run == RunKind::Reference && used == 0,
        });
        used += 1;
        *step = Some(s);
        let omega = relax.factor(&corr.delta);
        let scale = omega
            * if omega * s.max_step > cap {
                cap / (omega * s.max_step)
            } else {
                1.0
            };
        relax.applied(scale);
        for (l, d) in lambda.iter_mut().zip(&corr.delta) {
            *l += scale * d;
        }
        if previous_steps[1].is_finite() {
            corr.observe_contraction(s.max_step / previous_steps[1]);
        }
        let left = error_left(s.max_step, previous_steps, known);
        if s.max_step < tolerance || left < tolerance {
            return (Run::Converged, used);
        }
        previous_steps = [previous_steps[1], s.max_step];
        if lambda.iter().any(|l| l.abs() > reref_limit) {
            return (Run::Rereference, used);
        }
    }
}

/// The error (pixels) that remains once a step of `step` is applied, the
/// two steps before it being `previous` (older first, infinite when the run
/// has not made them) and `known` the slowest contraction the system
/// showed on earlier runs (`Correlation::contraction`):
/// Gauss–Newton with a constant matrix contracts linearly, and with `q` the
/// larger ratio of the last three steps the steps still to come add up to
/// about `step q / (1 - q)`; taken twice for safety, and only once three
/// steps show a good contraction (`q` under `FAST_CONTRACTION`), infinite
/// otherwise. A run whose next step would be far under the tolerance then
/// stops one iteration earlier: on a tracked frame, steps of 0.37, 9.5e-3
/// and 4.3e-4 px (then 5.4e-5) stop after the third, with about 4e-5 px
/// left (1e-4 px tolerance).
///
/// The contraction is a property of the system, not of the run: on a band
/// that earlier runs have shown to contract fast (a kept band's next
/// frames, see `TrackCache`), two steps of the run do, `q` then being at
/// least what those runs showed. On the `track_speed` example's star such
/// frames take steps of about 5e-2, 5e-4 and 1e-5 px, ratios of 0.01 to
/// 0.03 on every frame of a band: they stop after the second.
fn error_left(step: f64, previous: [f64; 2], known: Option<f64>) -> f64 {
    let q = match (previous[0].is_finite(), known) {
        (true, _) => (step / previous[1]).max(previous[1] / previous[0]),
        (false, Some(k)) if previous[1].is_finite() => (step / previous[1]).max(k),
        _ => return f64::INFINITY,
    };
    if q < FAST_CONTRACTION {
        2.0 * step * q / (1.0 - q)
    } else {
        f64::INFINITY
    }
}

/// Automatic element length of the last stage: halve the elements on the
/// same reference while the finer curve differs from the coarser one by more
/// than the noise explains.
///
/// With nested spline spaces the mean squared difference between the two
/// normal positions is about `rep^2 + (sigma_f^2 - sigma_c^2)`, where `rep`
/// is the coarse curve's shape (representation) error and `sigma` the noise
/// scatter of each fit. Refining lowers the total error `rep^2 + sigma^2`
/// when `rep^2 > sigma_f^2 - sigma_c^2` (the fine error being ~rep/16 for
/// cubics), i.e. when the difference exceeds twice the noise increase. The
/// noise variance comes from [`Correlation::estimate_noise`], which excludes
/// the systematic mismatch between the profiles. A shape error also shrinks
/// fast with the element length (16 times per halving for cubics, 4 for
/// linear elements); differences driven by noise or by the aliasing of a
/// sharp edge on the pixel grid do not, so refinement also stops when the
/// change is not at least halved (RMS) from one halving to the next.
#[allow(clippy::too_many_arguments)]
fn refine(
    reference: &SplineCurve,
    mut corr: Correlation,
    mut lambda: Vec<f64>,
    mut step: correlation::Step,
    shortest: f64,
    sampler: &Sampler,
    config: &FitConfig,
    (r, profile): (f64, Profile),
    history: &mut Vec<IterationRecord>,
) -> Result<(Correlation, Vec<f64>, correlation::Step, usize)> {
    let closed = reference.is_closed();
    let min_el = if closed { config.degree + 1 } else { 1 };
    let length = reference.param_length();
    let params = reference.sample_params((length.ceil() as usize).max(8));
    let mut iterations = 0;
    let mut previous_diff2 = f64::INFINITY;
    corr.estimate_noise(&lambda, sampler);
    loop {
        let h = corr.basis.element_length() / 2.0;
        if h < shortest {
            break;
        }
        let n_el = ((length / h).round() as usize).max(min_el);
        let basis = breaks::displacement_basis(reference, config.degree, n_el)?;
        let Ok(band) = Band::build_with(
            reference,
            &basis,
            r,
            profile,
            sampler.width(),
            sampler.height(),
            1,
            config.coords,
        ) else {
            break;
        };
        let Ok(mut fine) = Correlation::prepare(band, basis, sampler, config.levels, None) else {
            break;
        };
        let mut fine_lambda = vec![0.0; fine.n_unknowns()];
        let mut fine_step = None;
        let (end, used) = iterate_to_end(
            &mut fine,
            &mut fine_lambda,
            sampler,
            config,
            r,
            (config.max_iterations, config.tolerance),
            f64::INFINITY,
            &mut fine_step,
            (&mut *history, RunKind::Refine),
        );
        iterations += used;
        let (Run::Converged, Some(fs)) = (end, fine_step) else {
            break;
        };
        fine.estimate_noise(&fine_lambda, sampler);
        let (mut diff2, mut noise2) = (0.0, 0.0);
        for &u in &params {
            let d =
                displacement(&fine.basis, &fine_lambda, u) - displacement(&corr.basis, &lambda, u);
            diff2 += d * d;
            let sf = fine.position_sigma(u);
            let sc = corr.position_sigma(u);
            noise2 += sf * sf - sc * sc;
        }
        // Significant, and still converging like a shape error (a change
        // that does not shrink is noise or aliasing being chased).
        if diff2 <= 2.0 * noise2.max(0.0) || diff2 >= 0.25 * previous_diff2 {
            break;
        }
        previous_diff2 = diff2;
        (corr, lambda, step) = (fine, fine_lambda, fs);
    }
    Ok((corr, lambda, step, iterations))
}

/// Residuals beyond this many robust deviations mark a band as cluttered
/// (below, the fit is left as it is: a clean image is not reweighted).
const OUTLIER: f64 = 5.0;
/// Tukey's biweight constant, in robust deviations (95 % efficiency on
/// Gaussian noise).
const TUKEY: f64 = 4.685;
/// The robust scale is at least this fraction of the contrast `|c|`.
const MIN_ROBUST_SCALE: f64 = 0.02;
/// Band pixels whose residuals decide whether to reweight, at most.
const ROBUST_PROBE_PIXELS: usize = 8192;
/// Reweighting rounds at most.
const ROBUST_ROUNDS: usize = 3;

/// The robust scale of `residuals` (gray levels; `c` the contrast) when
/// some of them are clutter, `None` when the band is clean (then nothing is
/// reweighted). The scale is 1.4826 times the median absolute residual, at
/// least `MIN_ROBUST_SCALE |c|`: on a noiseless image most residuals are
/// (nearly) zero, and the floor keeps quantisation and small profile
/// mismatch from passing for clutter. Clutter: a residual beyond `OUTLIER`
/// scales.
pub(crate) fn clutter_scale(residuals: &[f64], c: f64) -> Option<f64> {
    let mut abs: Vec<f64> = residuals.iter().map(|v| v.abs()).collect();
    if abs.is_empty() {
        return None;
    }
    let mid = abs.len() / 2;
    let mad = 1.4826 * *abs.select_nth_unstable_by(mid, f64::total_cmp).1;
    let scale = mad.max(MIN_ROBUST_SCALE * c.abs());
    if scale.is_nan() || scale <= 0.0 || residuals.iter().all(|v| v.abs() < OUTLIER * scale) {
        return None;
    }
    Some(scale)
}

/// Tukey's biweight of residual `v` for the robust `scale` (see
/// [`clutter_scale`]): 1 at 0, falling to 0 at `TUKEY` scales and beyond.
pub(crate) fn tukey_weight(v: f64, scale: f64) -> f64 {
    let t = v / (TUKEY * scale);
    if t.abs() < 1.0 {
        (1.0 - t * t).powi(2)
    } else {
        0.0
    }
}

/// Robust weights: when some residuals of the converged fit are far beyond
/// the others (a wire, a scratch or a speck crossing the band; the scale is
/// 1.4826 times the median absolute residual, and at least
/// `MIN_ROBUST_SCALE` of the contrast), weight each pixel by Tukey's
/// biweight of its residual and fit again on the same reference, a few
/// rounds (iteratively reweighted least squares). Rejected pixels no longer
/// drag the curve; their share is reported per sample
/// ([`Sample::weight`]). The matrix is re-assembled each round. Returns the
/// iterations used and whether the band holds clutter; on any failure the
/// fit before it stands.
fn robust_refit(
    corr: &mut Correlation,
    lambda: &mut Vec<f64>,
    step: &mut Option<correlation::Step>,
    sampler: &Sampler,
    config: &FitConfig,
    r: f64,
    history: &mut Vec<IterationRecord>,
) -> (usize, bool) {
    let base: Vec<f64> = corr
        .band
        .full_weights()
        .iter()
        .zip(&corr.robust)
        .map(|(w, k)| if *k > 0.0 { w / k } else { *w })
        .collect();
    let mut used = 0;
    let mut found = false;
    for _ in 0..ROBUST_ROUNDS {
        let Some(s) = *step else { break };
        // A pixel displaced out of the image counts as fitting exactly.
        let residual = |i: usize| corr.residual(i, lambda, sampler).unwrap_or(0.0);
        // Detection on a regular subsample (a crossing wire still leaves
        // several of its pixels in it); all residuals only when needed.
        let stride = corr.band.len().div_ceil(ROBUST_PROBE_PIXELS).max(1);
        let probe: Vec<f64> = (0..corr.band.len().div_ceil(stride))
            .into_par_iter()
            .map(|k| residual(k * stride))
            .collect();
        let Some(scale) = clutter_scale(&probe, s.c) else {
            break;
        };
        found = true;
        let res: Vec<f64> = (0..corr.band.len()).into_par_iter().map(residual).collect();
        let robust: Vec<f64> = res.iter().map(|v| tukey_weight(*v, scale)).collect();
        let mut band = corr.band.clone();
        let weights = base.iter().zip(&robust).map(|(b, k)| b * k).collect();
        band.set_full_weights(weights, &corr.basis, lambda);
        let Ok(mut next) =
            Correlation::prepare(band, corr.basis.clone(), sampler, config.levels, None)
        else {
            break;
        };
        next.robust = robust;
        // As the stage's later runs (see `cluttered` in `run_schedule`).
        next.use_reference_gradient();
        let mut next_lambda = lambda.clone();
        let mut next_step = None;
        let (end, it) = iterate_to_end(
            &mut next,
            &mut next_lambda,
            sampler,
            config,
            r,
            (config.max_iterations, config.tolerance),
            f64::INFINITY,
            &mut next_step,
            (&mut *history, RunKind::Robust),
        );
        used += it;
        let (Run::Converged, Some(_)) = (end, next_step) else {
            break;
        };
        let moved = next_lambda
            .iter()
            .zip(lambda.iter())
            .fold(0.0f64, |m, (a, b)| m.max((a - b).abs()));
        (*corr, *lambda, *step) = (next, next_lambda, next_step);
        if moved < config.tolerance {
            break;
        }
    }
    (used, found)
}

/// `U(u)` of a displacement basis and coefficients.
fn displacement(basis: &Basis, lambda: &[f64], u: f64) -> f64 {
    let mut v = [0.0; MAX_DEGREE + 1];
    let first = basis.eval(u, &mut v);
    (0..=basis.degree())
        .map(|k| lambda[basis.index(first, k)] * v[k])
        .sum()
}

/// The spread of the edge (silhouettes) or line (contours) around
/// `curve` ([`psf::edge_spread`], [`psf::line_spread`]). An edge's search is
/// bounded by a third of the band, so a result near that bound is estimated
/// again on a band four times the spread.
fn estimate_spread(sampler: &Sampler, curve: &SplineCurve, kind: Kind) -> Option<psf::EdgeSpread> {
    if kind == Kind::Contour {
        return psf::line_spread(sampler, curve, EDGE_SPREAD_BAND);
    }
    let first = psf::edge_spread(sampler, curve, EDGE_SPREAD_BAND)?;
    if first.sigma < 0.9 * EDGE_SPREAD_BAND / 3.0 {
        return Some(first);
    }
    psf::edge_spread(sampler, curve, 4.0 * first.sigma).or(Some(first))
}

/// The band half-width that sees the whole edge or line: `2.5 s` for an
/// edge, plus half the width for a line.
fn matched_band(e: &psf::EdgeSpread) -> f64 {
    MATCHED_BAND * e.sigma + 0.5 * e.line_width.unwrap_or(0.0)
}

/// The optical blur (pixels) of the pixel-edge profile that best fits the
/// band of `corr` at `lambda` (least squares, gray levels refitted; golden
/// section within 30 % + 0.15 px of `current`, on at most `BLUR_FIT_PIXELS`
/// band pixels; when the optimum is at the bracket's end, the caller's next
/// run brackets again around it). The position hardly depends on the blur
/// along a straight edge (the profile is symmetric), but a mismatched width
/// makes the fit depend on the edge's sub-pixel phase: a focused edge fitted
/// with a 0.12 px blur scatters 8e-4 px instead of 1.2e-4 px.
fn fit_blur(corr: &Correlation, lambda: &[f64], current: f64) -> f64 {
    let stride = corr.band.len().div_ceil(BLUR_FIT_PIXELS);
    let ssr = |blur: f64| {
        corr.pushed_ssr(lambda, Profile::PixelEdge { blur }, stride)
            .unwrap_or(f64::INFINITY)
    };
    let lo = (0.7 * current - 0.15).max(0.0);
    let hi = 1.3 * current + 0.15;
    // 12 steps: the bracket shrinks to 3e-3 of its width.
    let best = psf::golden(lo, hi, 12, ssr);
    // The bracket's ends are never evaluated: a focused edge's optimum is 0.
    if lo == 0.0 && ssr(0.0) <= ssr(best) {
        0.0
    } else {
        best
    }
}

/// Half-width of the band of the pixel-edge stage for an optical blur of
/// `blur` pixels (see the constants), rounded up to a quarter pixel.
fn pixel_edge_band(blur: f64) -> f64 {
    let r = std::f64::consts::FRAC_1_SQRT_2 + PIXEL_EDGE_REACH * blur + PIXEL_EDGE_PLATEAU;
    (r.max(PIXEL_EDGE_MIN_BAND) * 4.0).ceil() / 4.0
}

/// Scalar secant relaxation of the Gauss–Newton steps.
///
/// The step replaces the gradient of the physical image by the virtual
/// one's, and models how the refitted gray levels follow a shift of the
/// curve as if the physical edge had the virtual profile. When it has not (a
/// sharp or blurred edge under a sine profile), the iteration is a linear
/// contraction `d_(k+1) = (1 - w_k lambda) d_k` along its dominant mode, with
/// `lambda` up to ~2 (oscillation) or under 1 (slow creep). The ratio of two
/// successive steps measures `lambda`; the next factor is `w = 1 / lambda`
/// (clamped to `[0.2, 3]`), which removes that mode in one more step. With a
/// matched profile `lambda = 1` and `w` stays 1.
struct Relaxation {
    previous: Vec<f64>,
    have_previous: bool,
    omega: f64,
    last_applied: f64,
}

impl Relaxation {
    fn new(n: usize) -> Self {
        Relaxation {
            previous: vec![0.0; n],
            have_previous: false,
            omega: 1.0,
            last_applied: 1.0,
        }
    }

    /// The factor for the raw step `delta` (before the step-length cap).
    fn factor(&mut self, delta: &[f64]) -> f64 {
        if self.have_previous {
            let (mut dot, mut norm) = (0.0, 0.0);
            for (d, p) in delta.iter().zip(&self.previous) {
                dot += d * p;
                norm += p * p;
            }
            if norm > 0.0 {
                let rho = dot / norm;
                let lambda = (1.0 - rho) / self.last_applied;
                if lambda.is_finite() && lambda > 1.0 / 3.0 {
                    self.omega = (1.0 / lambda).clamp(0.2, 3.0);
                }
            }
        }
        self.previous.copy_from_slice(delta);
        self.have_previous = true;
        self.omega
    }

    /// Record the factor actually applied (after the cap).
    fn applied(&mut self, factor: f64) {
        self.last_applied = factor;
    }
}

/// The last completed stage, kept to produce the output samples and their
/// uncertainty.
struct Final {
    /// Band half-width of the stage, pixels.
    half_width: f64,
    /// The stage's virtual profile.
    profile: Profile,
    reference: SplineCurve,
    corr: Correlation,
    lambda: Vec<f64>,
}

impl Final {
    /// Dense samples of `x0 + U n` (moved by the blur's curvature shift
    /// when `blur` is given, see [`crate::psf`]), the B-spline fitted to
    /// them and its largest deviation from them, and the output samples with
    /// `sigma`, and the gray levels along the curve when they vary.
    fn samples(
        &self,
        spacing: f64,
        degree: usize,
        blur: Option<f64>,
    ) -> Result<(SplineCurve, f64, Vec<Sample>, Vec<LevelSample>)> {
        // The output samples are every `per`-th of the points of `x0 + U
        // n`, so that they are at most `spacing` apart: the points are
        // taken a little closer than `spacing / per` on the reference, for
        // the displacement's stretch (else, a chord a hair over half a
        // pixel would make every point an output sample at 0.5 px).
        let per = (spacing / FINE_STEP).ceil().max(1.0);
        let fine_step = spacing / per / (1.0 + STRETCH_ALLOWANCE);
        let l = self.reference.param_length();
        let closed = self.reference.is_closed();
        let (params, mut pts, corners) =
            breaks::displaced_samples(&self.reference, &self.corr.basis, &self.lambda, fine_step);
        let mut curve =
            SplineCurve::fit_with_corners(&pts, closed, degree, CURVE_SPACING, &corners)?;
        let mut s = chord_lengths(&pts);
        if let Some(sigma) = blur {
            for (q, &si) in pts.iter_mut().zip(&s) {
                let f = curve.frame(si);
                let shift = crate::psf::curvature_shift(sigma, f.curvature);
                q[0] += shift * f.normal[0];
                q[1] += shift * f.normal[1];
            }
            curve = SplineCurve::fit_with_corners(&pts, closed, degree, CURVE_SPACING, &corners)?;
            s = chord_lengths(&pts);
        }
        // Robust weights binned by the reference parameter, 1 px bins (none
        // when no pixel was reweighted: the weight is 1 everywhere).
        let reweighted = self.corr.reweighted();
        let nbins = if reweighted { l.ceil() as usize + 1 } else { 0 };
        let mut bins = vec![(0.0, 0.0); nbins];
        if reweighted {
            for (i, &u) in self.corr.band.s.iter().enumerate() {
                let b = &mut bins[(u.max(0.0) as usize).min(nbins - 1)];
                b.0 += self.corr.robust[i];
                b.1 += 1.0;
            }
        }
        let weight_at = |u: f64| {
            if !reweighted {
                return 1.0;
            }
            let k = (u.max(0.0) as usize).min(nbins - 1);
            let (mut sum, mut n) = (0.0, 0.0);
            for b in &bins[k.saturating_sub(1)..=(k + 1).min(nbins - 1)] {
                sum += b.0;
                n += b.1;
            }
            if n > 0.0 {
                sum / n
            } else {
                1.0
            }
        };
        let max_chord = s.windows(2).map(|w| w[1] - w[0]).fold(0.0, f64::max);
        let every = ((spacing / max_chord.max(1e-9)).floor() as usize).max(1);
        let mut levels = Vec::new();
        if self.corr.varying_levels() {
            let mut next_level = 0.0;
            for (i, &u) in params.iter().enumerate() {
                let last = !closed && i + 1 == pts.len();
                if s[i] >= next_level || last {
                    if let Some((a, c)) = self.corr.levels_at(u) {
                        levels.push(LevelSample { s: s[i], a, c });
                    }
                    next_level = s[i] + LEVEL_SAMPLE_SPACING;
                }
            }
        }
        // In parallel (each point's values are its own; a maximum does not
        // depend on the order).
        let fit_error = pts
            .par_iter()
            .zip(&s)
            .map(|(q, &si)| crate::curve::dist(curve.point(si), *q))
            .reduce(|| 0.0, f64::max);
        let kept: Vec<usize> = (0..pts.len())
            .filter(|&i| i % every == 0 || (!closed && i + 1 == pts.len()))
            .collect();
        let out: Vec<Sample> = kept
            .par_iter()
            .map(|&i| {
                let q = pts[i];
                let f = curve.frame(s[i]);
                Sample {
                    s: s[i],
                    x: q[0],
                    y: q[1],
                    nx: f.normal[0],
                    ny: f.normal[1],
                    sigma: self.corr.position_sigma(params[i]),
                    weight: weight_at(params[i]),
                }
            })
            .collect();
        Ok((curve, fit_error, out, levels))
    }
}

/// Cumulative chord lengths of a polyline (the parameters
/// [`SplineCurve::fit`] gives its points).
fn chord_lengths(pts: &[[f64; 2]]) -> Vec<f64> {
    let mut acc = 0.0;
    let mut out = Vec::with_capacity(pts.len());
    for (i, q) in pts.iter().enumerate() {
        if i > 0 {
            acc += crate::curve::dist(pts[i - 1], *q);
        }
        out.push(acc);
    }
    out
}

/// `x0(u) + U(u) n(u)`.
fn displaced_point(reference: &SplineCurve, basis: &Basis, lambda: &[f64], u: f64) -> [f64; 2] {
    let f = reference.frame(u);
    let disp = displacement(basis, lambda, u);
    [
        f.point[0] + disp * f.normal[0],
        f.point[1] + disp * f.normal[1],
    ]
}

/// Control-point spacing of a new reference after a stage with `basis`:
/// its element length, capped at `MAX_REFERENCE_SPACING` (and at least
/// `CURVE_SPACING`). The measured curve holds no detail finer than the
/// elements; what the previous reference held below that scale (the pixel
/// staircase of a traced start, a hand-drawn polyline's corners) the
/// displacement cannot remove, so the refit drops it. The cap keeps the
/// shape a coarse first stage caught on a short open curve.
fn reference_spacing(basis: &Basis) -> f64 {
    basis
        .element_length()
        .clamp(CURVE_SPACING, MAX_REFERENCE_SPACING)
}

/// Spacing of the points of `x0 + U n` a new reference with control points
/// `spacing` pixels apart is fitted to, pixels: half a pixel, or
/// `REFERENCE_SAMPLES_PER_INTERVAL` per interval of a coarser reference
/// (whose fit averages over many more points than it needs: a tracked
/// frame's start, refitted with control points an element (40 px) apart,
/// took 5 times longer from points 0.5 px apart), up to
/// `MAX_REFERENCE_SAMPLE_STEP`.
fn reference_sample_step(spacing: f64) -> f64 {
    (spacing / REFERENCE_SAMPLES_PER_INTERVAL)
        .clamp(REFERENCE_SAMPLE_STEP, MAX_REFERENCE_SAMPLE_STEP)
}

/// Where an open curve's new reference must stay: its band, of this
/// half-width, inside an image of this size.
#[derive(Clone, Copy, Debug)]
struct Clip {
    half_width: f64,
    width: usize,
    height: usize,
}

/// The new reference curve `x0 + U n`, a cubic B-spline with control points
/// `spacing` pixels apart fitted to it.
///
/// An open curve whose ends reach the image border (an edge that crosses
/// the image) is trimmed to the longest stretch whose band (`clip`) stays
/// inside the image: near a border the displacement tilts the end's normal
/// and would push the end, or its band, out of the image, which is not a
/// divergence. A stretch under half the curve is not taken (the curve has
/// left the image; the band check reports it).
fn displaced(
    reference: &SplineCurve,
    basis: &Basis,
    lambda: &[f64],
    spacing: f64,
    clip: Clip,
) -> Result<SplineCurve> {
    if !reference.corners().is_empty() {
        return breaks::displaced(reference, basis, lambda, spacing);
    }
    let l = reference.param_length();
    let count = (l / reference_sample_step(spacing)).ceil() as usize;
    let closed = reference.is_closed();
    let params = reference.sample_params(if closed { count } else { count + 1 });
    let pts: Vec<[f64; 2]> = params
        .par_iter()
        .map(|&u| displaced_point(reference, basis, lambda, u))
        .collect();
    let curve = SplineCurve::fit(&pts, closed, 3, spacing)?;
    if closed {
        return Ok(curve);
    }
    // A pixel of margin: the fitted spline may overshoot its points.
    let (w, h) = (clip.width as f64 - 2.0, clip.height as f64 - 2.0);
    let inside = |q: [f64; 2]| q[0] >= 1.0 && q[1] >= 1.0 && q[0] <= w && q[1] <= h;
    let s = chord_lengths(&pts);
    let rr = clip.half_width;
    let ok: Vec<bool> = s
        .iter()
        .map(|&u| {
            let f = curve.frame(u.min(curve.param_length()));
            let (q, n) = (f.point, f.normal);
            inside(q)
                && inside([q[0] + rr * n[0], q[1] + rr * n[1]])
                && inside([q[0] - rr * n[0], q[1] - rr * n[1]])
        })
        .collect();
    if ok.iter().all(|k| *k) {
        return Ok(curve);
    }
    let (mut best, mut start) = ((0, 0), None);
    for (i, &k) in ok.iter().chain(std::iter::once(&false)).enumerate() {
        match (k, start) {
            (true, None) => start = Some(i),
            (false, Some(a)) => {
                if i - a > best.1 - best.0 {
                    best = (a, i);
                }
                start = None;
            }
            _ => {}
        }
    }
    if 2 * (best.1 - best.0) < pts.len() {
        return Ok(curve);
    }
    SplineCurve::fit(&pts[best.0..best.1], closed, 3, spacing)
}

/// Samples of a curve without a fit behind them (sigma unknown: NaN).
fn plain_samples(curve: &SplineCurve, spacing: f64) -> Vec<Sample> {
    let l = curve.param_length();
    let count = (l / spacing).ceil() as usize;
    let params = curve.sample_params(if curve.is_closed() { count } else { count + 1 });
    params
        .iter()
        .map(|&u| {
            let f = curve.frame(u);
            Sample {
                s: u,
                x: f.point[0],
                y: f.point[1],
                nx: f.normal[0],
                ny: f.normal[1],
                sigma: f64::NAN,
                weight: f64::NAN,
            }
        })
        .collect()
}

#[allow(clippy::too_many_arguments)]
fn report(
    stage: &Stage,
    profile: Profile,
    basis: &Basis,
    band_pixels: usize,
    iterations: usize,
    rereferences: usize,
    step: Option<correlation::Step>,
    started: Instant,
    outcome: Outcome,
    history: Vec<IterationRecord>,
) -> StageReport {
    StageReport {
        half_width: stage.half_width,
        profile,
        elements: basis.n_elements(),
        iterations,
        rereferences,
        band_pixels,
        residual_rms: step.map_or(f64::NAN, |s| s.residual_rms),
        a: step.map_or(f64::NAN, |s| s.a),
        c: step.map_or(f64::NAN, |s| s.c),
        seconds: started.elapsed().as_secs_f64(),
        outcome,
        history,
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    const INF: f64 = f64::INFINITY;

    /// The steps of a linear contraction by `q` from a first step `first`.
    fn steps(first: f64, q: f64, n: usize) -> Vec<f64> {
        (0..n).map(|k| first * q.powi(k as i32)).collect()
    }

    #[test]
    fn two_steps_need_a_known_contraction() {
        let s = steps(5e-2, 0.01, 2);
        // Nothing known: two steps say nothing yet.
        assert_eq!(error_left(s[1], [INF, s[0]], None), INF);
        // A known fast contraction: twice `step q / (1 - q)`, with `q` the
        // slower of the known one and the run's own ratio.
        let left = error_left(s[1], [INF, s[0]], Some(0.03));
        assert!((left - 2.0 * s[1] * 0.03 / 0.97).abs() < 1e-18, "{left}");
        let left = error_left(s[1], [INF, s[0]], Some(0.001));
        assert!((left - 2.0 * s[1] * 0.01 / 0.99).abs() < 1e-18, "{left}");
        // A known slow one, or a run slower than `FAST_CONTRACTION`: none.
        assert_eq!(error_left(s[1], [INF, s[0]], Some(0.3)), INF);
        assert_eq!(error_left(0.3 * s[0], [INF, s[0]], Some(0.01)), INF);
        // A first step: nothing to compare it with.
        assert_eq!(error_left(s[0], [INF, INF], Some(0.01)), INF);
    }

    #[test]
    fn three_steps_go_by_the_run_alone() {
        let s = steps(0.37, 0.03, 3);
        let own = error_left(s[2], [s[0], s[1]], None);
        assert!((own - 2.0 * s[2] * 0.03 / 0.97).abs() < 1e-15, "{own}");
        for known in [Some(0.001), Some(0.2), Some(0.9)] {
            assert_eq!(error_left(s[2], [s[0], s[1]], known), own);
        }
    }

    /// Whenever the contraction is as fast as the estimate assumes (every
    /// ratio at most the larger of the known one and the run's), the error
    /// left (the sum of the steps still to come) is under the estimate.
    #[test]
    fn the_estimate_bounds_a_linear_contraction() {
        for q in [0.001, 0.01, 0.05, 0.1, 0.2, 0.24] {
            for known in [q, 1.5 * q, 0.24] {
                let s = steps(0.1, q, 40);
                let left: f64 = s[2..].iter().sum();
                let estimate = error_left(s[1], [INF, s[0]], Some(known));
                assert!(
                    left <= estimate,
                    "q {q}, known {known}: {left} > {estimate}"
                );
                let left: f64 = s[3..].iter().sum();
                assert!(left <= error_left(s[2], [s[0], s[1]], None), "q {q}");
            }
        }
    }
}
