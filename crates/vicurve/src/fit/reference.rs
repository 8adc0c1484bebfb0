//! New references: the curve `x0 + U n` a run converged to becomes the
//! reference of the next run (method, section 6), refitted as a B-spline
//! with control points as far apart as the elements that measured it.

use super::breaks;
use super::refine::displacement;
use crate::band::{check_inside, inside_stretch};
use crate::curve::SplineCurve;
use crate::error::{Error, Result};
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

/// Where an open curve's runs keep their band: inside an image of this
/// size, out to this distance from the reference, this far from the
/// border.
#[derive(Clone, Copy, Debug)]
pub(super) struct Clip {
    /// The band's reach (half-width and margin), pixels.
    pub half_width: f64,
    /// Distance the band keeps from the border, pixels (at least
    /// [`TRIM_MARGIN`]).
    pub margin: f64,
    /// Image width, pixels.
    pub width: usize,
    /// Image height, pixels.
    pub height: usize,
}

/// Distance a trimmed reference's band keeps from the image border at
/// least, pixels: the refitted stretch may differ from the curve it was cut
/// from by a small fraction of a pixel. (A band that samples the image at
/// its pixels displaced by `U` keeps that much more, see
/// `Schedule::trim_reference`.)
pub(super) const TRIM_MARGIN: f64 = 0.5;
/// A trimmed reference keeps at least this fraction of the curve's length;
/// a shorter stretch means the curve runs along the border, not across it,
/// and its band leaves the image.
const MIN_STRETCH: f64 = 0.5;
/// Spacing of the points that carry the trimmed ends and that a trimmed
/// stretch is refitted to, pixels.
const TRIM_SAMPLE_STEP: f64 = 0.25;

/// The parts of an open curve beyond the stretch whose band fits in the
/// image (see [`trim_to_band`]): they are carried along with the
/// reference, each moved by the displacement of its end continued
/// linearly, so that a narrower band later measures as far towards the
/// border as it fits. Empty when the curve was not trimmed.
#[derive(Clone, Debug, Default, PartialEq)]
pub(super) struct Ends {
    /// The points before the stretch, from the curve's start to the
    /// stretch's first point (excluded), about [`TRIM_SAMPLE_STEP`] apart.
    pub before: Vec<[f64; 2]>,
    /// The points after the stretch, from its last point (excluded) to the
    /// curve's end.
    pub after: Vec<[f64; 2]>,
    /// The reach of the band that trimmed them, pixels.
    pub reach: f64,
}

impl Ends {
    /// Whether nothing was trimmed.
    pub fn is_empty(&self) -> bool {
        self.before.is_empty() && self.after.is_empty()
    }

    /// Length of the part before the stretch (`start`) or after it, to
    /// the stretch's end point `joint`, pixels (0 when not trimmed there).
    pub fn length(&self, start: bool, joint: [f64; 2]) -> f64 {
        let mut part: Vec<[f64; 2]> = if start {
            self.before.iter().rev().copied().collect()
        } else {
            self.after.clone()
        };
        if part.is_empty() {
            return 0.0;
        }
        part.insert(0, joint);
        chord_lengths(&part).last().copied().unwrap_or(0.0)
    }
}

/// An open curve `full` trimmed to the longest stretch whose band (`clip`)
/// stays inside the image ([`crate::band::inside_stretch`], `clip.margin`
/// from its border), refitted with the same control-point spacing, and the
/// parts cut off (see [`Ends`]). A closed curve, or one whose band fits
/// whole, is returned as it is with no ends.
///
/// Errors: [`Error::CurveOutsideImage`] / [`Error::BandOutsideImage`] when
/// no stretch of at least [`MIN_STRETCH`] of the curve fits (the curve
/// lies outside the image, or runs along its border).
pub(super) fn trim_to_band(full: &SplineCurve, clip: Clip) -> Result<(SplineCurve, Ends)> {
    let l = full.param_length();
    if full.is_closed() {
        return Ok((full.clone(), Ends::default()));
    }
    let (w, h) = (clip.width, clip.height);
    let (u0, u1) = inside_stretch(full, clip.half_width, clip.margin.max(TRIM_MARGIN), w, h)?;
    if u0 <= 0.0 && u1 >= l {
        return Ok((full.clone(), Ends::default()));
    }
    if u1 - u0 < MIN_STRETCH * l {
        // The band leaves the image: where it first does, or next to the
        // stretch when it stays just inside.
        check_inside(full, clip.half_width, w, h)?;
        let p = full.point(if u0 > 0.0 { u0 } else { u1 });
        return Err(Error::BandOutsideImage {
            half_width: clip.half_width,
            x: p[0],
            y: p[1],
        });
    }
    let spacing = l / full.basis().n_elements() as f64;
    let (pts, corners) = stretch_points(full, u0, u1);
    let stretch = SplineCurve::fit_with_corners(&pts, false, 3, spacing, &corners)?;
    // `count` points from `a` towards `b`, `a` included, `b` not.
    let part = |a: f64, b: f64| -> Vec<[f64; 2]> {
        let count = ((b - a).abs() / TRIM_SAMPLE_STEP).ceil() as usize;
        (0..count)
            .map(|k| full.point(a + (b - a) * k as f64 / count as f64))
            .collect()
    };
    let mut after = part(l, u1);
    after.reverse();
    let ends = Ends {
        before: part(0.0, u0),
        after,
        reach: clip.half_width,
    };
    Ok((stretch, ends))
}

/// An open start must lie in the image: within half a pixel of the pixel
/// centres' hull `[0, width - 1] x [0, height - 1]` (on the outermost
/// pixels), tested every half pixel along it. Its band may leave the image
/// (it is trimmed, [`trim_to_band`]); its points may not.
///
/// Errors: [`Error::CurveOutsideImage`] at the first point outside.
pub(super) fn check_open_start(curve: &SplineCurve, (width, height): (usize, usize)) -> Result<()> {
    if curve.is_closed() {
        return Ok(());
    }
    let (lo, x_hi, y_hi) = (-0.5, width as f64 - 0.5, height as f64 - 0.5);
    let count = ((curve.param_length() / 0.5).ceil() as usize).max(8);
    for u in curve.sample_params(count + 1) {
        let p = curve.point(u);
        if !(p[0] >= lo && p[1] >= lo && p[0] <= x_hi && p[1] <= y_hi) {
            return Err(Error::CurveOutsideImage {
                x: p[0],
                y: p[1],
                width,
                height,
            });
        }
    }
    Ok(())
}

/// Points of `curve` from `u0` to `u1` about [`TRIM_SAMPLE_STEP`] apart,
/// its corners among them (and their indices).
fn stretch_points(curve: &SplineCurve, u0: f64, u1: f64) -> (Vec<[f64; 2]>, Vec<usize>) {
    let mut bounds = vec![u0];
    bounds.extend(
        curve
            .corners()
            .iter()
            .copied()
            .filter(|&c| c > u0 && c < u1),
    );
    bounds.push(u1);
    let mut pts = Vec::new();
    let mut corners = Vec::new();
    for w in bounds.windows(2) {
        if !pts.is_empty() {
            corners.push(pts.len());
        }
        let count = ((w[1] - w[0]) / TRIM_SAMPLE_STEP).ceil().max(1.0) as usize;
        pts.extend((0..count).map(|k| curve.point(w[0] + (w[1] - w[0]) * k as f64 / count as f64)));
    }
    pts.push(curve.point(u1));
    (pts, corners)
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
/// An open reference trimmed from a longer curve (`ends`, see
/// [`trim_to_band`]) gets its trimmed parts back, each moved by the
/// displacement of its end continued linearly ([`carry`]), and cut where
/// they leave the image (`size`, pixels): the new reference is the whole
/// curve again, for the next run to trim to its own band. A narrower band
/// then measures further towards the border than a wide one, and the
/// measured curve ends where the last stage's band leaves the image, not
/// where the first one's did.
pub(super) fn next_reference(
    reference: &SplineCurve,
    basis: &Basis,
    lambda: &[f64],
    spacing: f64,
    ends: &Ends,
    size: (usize, usize),
) -> Result<SplineCurve> {
    if ends.is_empty() {
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
        return SplineCurve::fit(&pts, closed, 3, spacing);
    }
    let step = reference_sample_step(spacing).min(REFERENCE_SAMPLE_STEP);
    let (_, pts, corners) = breaks::displaced_samples(reference, basis, lambda, step);
    let l = reference.param_length();
    let at_end = |u: f64| {
        let d = basis.eval_derivs(u);
        let (mut value, mut slope) = (0.0, 0.0);
        for k in 0..=basis.degree() {
            let c = lambda[basis.index(d.first, k)];
            value += c * d.value[k];
            slope += c * d.d1[k];
        }
        (value, slope)
    };
    let inside = |q: [f64; 2]| {
        q[0] >= 0.0 && q[1] >= 0.0 && q[0] <= size.0 as f64 - 1.0 && q[1] <= size.1 as f64 - 1.0
    };
    let before: Vec<[f64; 2]> = {
        let rev: Vec<[f64; 2]> = ends.before.iter().rev().copied().collect();
        let (u, du) = at_end(0.0);
        let mut moved = carry(reference.point(0.0), &rev, u, -du, -1.0, &inside);
        moved.reverse();
        moved
    };
    let (u, du) = at_end(l);
    let after = carry(reference.point(l), &ends.after, u, du, 1.0, &inside);
    let mut all = before.clone();
    all.extend_from_slice(&pts);
    all.extend_from_slice(&after);
    let corners: Vec<usize> = corners.iter().map(|&c| c + before.len()).collect();
    SplineCurve::fit_with_corners(&all, false, 3, spacing, &corners)
}

/// A trimmed part `part` of an open curve, ordered from its joint with the
/// reference (the point `joint`, excluded) outwards, moved by the
/// reference's displacement there continued linearly: `u + slope d` at
/// the distance `d` along the part (pixels; `slope` per pixel outwards),
/// along the part's own normal (`direction`: +1 when the part runs along
/// the curve's direction of travel, -1 against it). Cut at its first point
/// outside the image (`inside`).
fn carry(
    joint: [f64; 2],
    part: &[[f64; 2]],
    u: f64,
    slope: f64,
    direction: f64,
    inside: &impl Fn([f64; 2]) -> bool,
) -> Vec<[f64; 2]> {
    let mut line = Vec::with_capacity(part.len() + 1);
    line.push(joint);
    line.extend_from_slice(part);
    let d = chord_lengths(&line);
    let mut out = Vec::with_capacity(part.len());
    for k in 1..line.len() {
        let (a, b) = (line[k - 1], line[(k + 1).min(line.len() - 1)]);
        let (tx, ty) = (b[0] - a[0], b[1] - a[1]);
        let norm = tx.hypot(ty);
        if norm <= 0.0 {
            break;
        }
        // The curve's normal (-t_y, t_x) for its direction of travel.
        let n = [-direction * ty / norm, direction * tx / norm];
        let shift = u + slope * d[k];
        let q = [line[k][0] + shift * n[0], line[k][1] + shift * n[1]];
        if !inside(q) {
            break;
        }
        out.push(q);
    }
    out
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
