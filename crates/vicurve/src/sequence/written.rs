//! A frame's curve as its result file records it, and what the next
//! frame's tracking schedule takes from it: computed the same way whether
//! the frame was just measured or read back, so that a resumed run goes on
//! exactly as an uninterrupted one.

use crate::curve::{SplineCurve, SplineCurveData};
use crate::fit::{Measurement, TrackState};
use crate::spline::Basis;

/// The B-spline described by `data` (as [`SplineCurve::to_data`] writes
/// it: a closed curve's first `degree` control points repeated at the end).
///
/// Errors (one line): too few knots, knots that do not span a positive
/// length or are not uniform, control points that do not fit the basis.
pub fn rebuild(data: &SplineCurveData) -> Result<SplineCurve, String> {
    let p = data.degree;
    let bad = |why: &str| format!("the recorded curve is not usable: {why}");
    if data.knots.len() < 2 * p + 2 {
        return Err(bad("too few knots"));
    }
    let n_el = data.knots.len() - 2 * p - 1;
    // Knots are (i - p) h with h = L / n, so knot p + n is L to within an
    // ulp or two: the length whose basis gives the recorded knots exactly
    // is among its neighbours (the same L when the file was written from a
    // basis; else the nearest, within 1e-12 relative).
    let guess = data.knots[p + n_el];
    if !(guess.is_finite() && guess > 0.0) {
        return Err(bad("the knots do not span a positive length"));
    }
    let mut best: Option<(f64, Basis)> = None;
    for k in -4i64..=4 {
        let length = f64::from_bits((guess.to_bits() as i64 + k) as u64);
        let basis = Basis::new(p, n_el, length, data.closed).map_err(|e| bad(&e.to_string()))?;
        let err = basis
            .knots()
            .iter()
            .zip(&data.knots)
            .map(|(a, b)| (a - b).abs())
            .fold(0.0, f64::max);
        if best.as_ref().is_none_or(|b| err < b.0) {
            best = Some((err, basis));
        }
    }
    let (err, basis) = best.ok_or_else(|| bad("no basis"))?;
    if err > 1e-12 * guess {
        return Err(bad("non-uniform knots"));
    }
    let mut ctrl = data.control_points.clone();
    if data.closed {
        ctrl.truncate(ctrl.len().saturating_sub(p));
    }
    SplineCurve::new(basis, ctrl).map_err(|e| bad(&e.to_string()))
}

/// What the frame after `m` takes from it for the tracking schedule, `m`'s
/// curve being `written` as read back ([`rebuild`]); a result file read
/// back gives the same from its last band stage (not a whole-object one)
/// and gray levels.
pub fn tracking_state(m: &Measurement, written: &SplineCurve) -> Option<TrackState> {
    let last = crate::measurement::last_band_stage(&m.stages)?;
    TrackState::from_last_stage(
        last.profile,
        last.elements,
        last.outcome,
        written.param_length(),
        !m.levels.is_empty(),
    )
}
