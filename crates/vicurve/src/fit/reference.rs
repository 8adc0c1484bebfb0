//! New references: the curve `x0 + U n` a run converged to becomes the
//! reference of the next run (method, section 6), refitted as a B-spline
//! with control points as far apart as the elements that measured it.

use super::breaks;
use super::refine::displacement;
use crate::curve::SplineCurve;
use crate::error::Result;
use crate::spline::Basis;
use rayon::prelude::*;

/// Spacing of the samples used to rebuild a reference curve, pixels (the
/// smallest; see [`reference_sample_step`]).
pub(super) const REFERENCE_SAMPLE_STEP: f64 = 0.5;
/// Samples per control-point interval of a rebuilt reference, at least
/// ([`reference_sample_step`]).
const REFERENCE_SAMPLES_PER_INTERVAL: f64 = 16.0;
/// Largest spacing of those samples, pixels.
const MAX_REFERENCE_SAMPLE_STEP: f64 = 2.0;
/// Control-point spacing of output curves, and the smallest of reference
/// curves, pixels.
pub(super) const CURVE_SPACING: f64 = 2.0;
/// Largest control-point spacing of a new reference, pixels (see
/// [`reference_spacing`]).
const MAX_REFERENCE_SPACING: f64 = 40.0;

/// Where an open curve's new reference must stay: its band, of this
/// half-width, inside an image of this size.
#[derive(Clone, Copy, Debug)]
pub(super) struct Clip {
    /// Band half-width, pixels.
    pub half_width: f64,
    /// Image width, pixels.
    pub width: usize,
    /// Image height, pixels.
    pub height: usize,
}

/// `x0(u) + U(u) n(u)`.
pub(super) fn displaced_point(
    reference: &SplineCurve,
    basis: &Basis,
    lambda: &[f64],
    u: f64,
) -> [f64; 2] {
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
pub(super) fn reference_spacing(basis: &Basis) -> f64 {
    basis
        .element_length()
        .clamp(CURVE_SPACING, MAX_REFERENCE_SPACING)
}

/// Spacing of the points of `x0 + U n` a new reference with control points
/// `spacing` pixels apart is fitted to, pixels: half a pixel, or
/// `REFERENCE_SAMPLES_PER_INTERVAL` per interval of a coarser reference
/// (whose fit would average over many more points than it needs), up to
/// `MAX_REFERENCE_SAMPLE_STEP`.
fn reference_sample_step(spacing: f64) -> f64 {
    (spacing / REFERENCE_SAMPLES_PER_INTERVAL)
        .clamp(REFERENCE_SAMPLE_STEP, MAX_REFERENCE_SAMPLE_STEP)
}

/// The new reference curve `x0 + U n`, a cubic B-spline with control points
/// `spacing` pixels apart fitted to it (a curve with corners keeps them:
/// [`breaks::displaced`]).
///
/// An open curve whose ends reach the image border (an edge that crosses
/// the image) is trimmed to the longest stretch whose band (`clip`) stays
/// inside the image: near a border the displacement tilts the end's normal
/// and would push the end, or its band, out of the image, which is not a
/// divergence. A stretch under half the curve is not taken (the curve has
/// left the image; the band check reports it).
pub(super) fn next_reference(
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
    match inside_stretch(&curve, &pts, clip) {
        Some((a, b)) => SplineCurve::fit(&pts[a..b], closed, 3, spacing),
        None => Ok(curve),
    }
}

/// The longest stretch `a..b` of the points `pts` of the open `curve`
/// whose band (`clip`) stays inside the image, when some do not and the
/// stretch is at least half of them; `None` to keep the whole curve.
fn inside_stretch(curve: &SplineCurve, pts: &[[f64; 2]], clip: Clip) -> Option<(usize, usize)> {
    // A pixel of margin: the fitted spline may overshoot its points.
    let (w, h) = (clip.width as f64 - 2.0, clip.height as f64 - 2.0);
    let inside = |q: [f64; 2]| q[0] >= 1.0 && q[1] >= 1.0 && q[0] <= w && q[1] <= h;
    let s = chord_lengths(pts);
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
        return None;
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
        return None;
    }
    Some(best)
}

/// Cumulative chord lengths of a polyline (the parameters
/// [`SplineCurve::fit`] gives its points).
pub(super) fn chord_lengths(pts: &[[f64; 2]]) -> Vec<f64> {
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
