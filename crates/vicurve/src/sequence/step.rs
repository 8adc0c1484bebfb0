//! One curve measured on one frame of a sequence, from the previous
//! frame's result or from its start (see [`super`]).

use super::{Previous, SequenceCurve};
use crate::curve::{InitialCurve, SplineCurve};
use crate::fit::{
    measure_from, measure_tracked_cached, FitConfig, Measurement, Outcome, TrackCache,
    TrackSnapshot,
};
use crate::interp::{Interpolation, Sampler};

/// Spacing of the points that stand for the previous curve in a tracked
/// frame's `init` record, px (the fit itself starts from the previous
/// B-spline: as it is for the tracking schedule, which refits it itself,
/// smoothed for the curve's stages, see [`tracked_start`]).
const RECORD_SPACING: f64 = 2.0;

/// Control-point spacing of a tracked frame's start, px (at most; at least
/// 16 control intervals along the curve).
const START_SPACING: f64 = 10.0;

/// One curve measured on a frame.
#[derive(Clone, Debug)]
pub struct CurveStep {
    /// The measurement, or why there is none (one line).
    pub measured: Result<Measurement, String>,
    /// The start as recorded (the previous curve as points about 2 px
    /// apart for a tracked frame).
    pub init: InitialCurve,
    /// The configuration used.
    pub config: FitConfig,
    /// `init`, or the name of the frame whose curve the fit started from.
    pub started_from: String,
    /// A retry, when there was one (else empty).
    pub note: String,
    /// What the curve's cache holds after the fit, written down.
    pub band: Option<TrackSnapshot>,
}

/// Measure one curve on a frame: from `prev` with the tracked
/// configuration (the tracking schedule first when `spec` asks for it and
/// `prev` left a state; the tracked configuration's own schedule when that
/// cannot measure), or from its start with the first configuration when
/// there is no `prev`; a tracked fit that fails is tried again from the
/// same curve with the first configuration when the two differ. The
/// tracking schedule measures on the band `cache` keeps when it serves, and
/// leaves this frame's there; any other fit empties the cache.
///
/// `sampler` gives the frame prepared for an interpolation (`None` when it
/// cannot), so that only the interpolations a fit asks for are prepared.
pub fn measure_curve<'s>(
    spec: SequenceCurve<'_>,
    prev: Option<&Previous>,
    cache: &mut TrackCache,
    sampler: &dyn Fn(Interpolation) -> Option<&'s Sampler>,
) -> CurveStep {
    let mut result = measure_curve_with(spec, prev, cache, sampler);
    result.band = cache.snapshot();
    result
}

/// [`measure_curve`] but for the band it records.
fn measure_curve_with<'s>(
    spec: SequenceCurve<'_>,
    prev: Option<&Previous>,
    cache: &mut TrackCache,
    sampler: &dyn Fn(Interpolation) -> Option<&'s Sampler>,
) -> CurveStep {
    let run = |reference: SplineCurve, config: &FitConfig| -> Result<Measurement, String> {
        let s = sampler(config.interpolation)
            .ok_or_else(|| "no image prepared for this interpolation".to_string())?;
        measure_from(s, reference, config).map_err(|e| e.to_string())
    };
    let Some(p) = prev else {
        cache.clear();
        let measured = spec
            .init
            .to_curve()
            .map_err(|e| e.to_string())
            .and_then(|c| run(c, spec.first));
        return CurveStep {
            measured,
            init: spec.init.clone(),
            config: spec.first.clone(),
            started_from: "init".into(),
            note: String::new(),
            band: None,
        };
    };
    let init = InitialCurve::Polyline {
        points: record_points(&p.curve),
        closed: p.curve.is_closed(),
    };
    // The tracking schedule takes the previous curve as it is (it refits
    // it with control points one element apart itself); the stages of the
    // curve, the smoothed start.
    let plain = sampler(Interpolation::Bilinear);
    let short = match (spec.tracking_schedule, &p.state, plain) {
        (true, Some(state), Some(s)) => {
            // Empties the cache when it cannot measure.
            measure_tracked_cached(s, p.curve.clone(), state, spec.tracked, cache)
                .ok()
                .flatten()
        }
        _ => {
            cache.clear();
            None
        }
    };
    let tracked_result = |measured| CurveStep {
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
    let first = run(start.clone(), spec.tracked);
    let failed = match &first {
        Err(e) => Some(e.clone()),
        Ok(m) => match m.outcome {
            Outcome::Diverged { divergence } => Some(divergence.to_string()),
            _ => None,
        },
    };
    match failed {
        Some(why) if spec.tracked != spec.first => CurveStep {
            measured: run(start, spec.first),
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

/// The start of a tracked frame measured with the curve's stages (the
/// tracking schedule refits its start itself): the previous curve refitted
/// with control points [`START_SPACING`] apart. The measured curve has
/// control points 2 px apart and carries the previous frame's noise at
/// that scale; a fit whose displacement has longer elements (as a schedule
/// without coarse stages has) cannot remove it, so it would pass on to the
/// next frame and grow from frame to frame.
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
