//! Breaks: corners of the measured curve at chosen positions
//! ([`FitConfig::breaks`](super::FitConfig::breaks), the CLI's `--break`).
//!
//! The method's curve is `x(s) = x0(s) + U(s) n(s)` with `U` and `x0`
//! smooth B-splines, so it cannot follow a corner (a polygon's vertex, the
//! shoulder of a necking specimen): near one the error grows to a fraction
//! of the element length. A break puts repeated knots at a point of the
//! curve (the paper, section 8.2):
//!
//! * **The reference curve** gets a knot of multiplicity `p` there
//!   ([`SplineCurve::fit_with_corners`]): it is `C^0` and may have a corner.
//! * **The displacement** gets a knot of multiplicity `p + 1`: `U` is
//!   discontinuous, the two sides are measured independently. A `C^0` `U`
//!   would force both sides to move by the same amount at the corner, which
//!   ties the corner to its bisector: a reference corner off the true one
//!   could then only move along it.
//! * **The corner of the new reference** (each re-referencing, each stage,
//!   the output) is where the two displaced sides meet: the intersection of
//!   their tangent lines at the break (for a corner of a straight-sided
//!   polygon, exactly the offset corner). The side that overshoots it is
//!   trimmed, the one that falls short is extended by a straight segment.
//!   When the tangents are nearly parallel (or the intersection is far
//!   from both displaced ends) the midpoint of the two ends is taken.
//!   The break then sits at that point's parameter of the new reference:
//!   it follows the curve through the stages.
//! * **The band** leaves out the pixels whose closest point is the vertex
//!   (the wedge beyond a convex corner), as it leaves out those past the
//!   ends of an open curve, and assigns the others to the side they are
//!   nearest to (see `curve/corners.rs`).
//!
//! # Positions
//! Break positions are arc lengths in pixels along the initial curve: from
//! its start for an open curve (the segment's first point, the polyline's
//! first vertex); for a closed one from its start point, in the direction
//! the curve is given (a circle starts at `(cx + r, cy)` and runs
//! counterclockwise on screen; a closed polyline from its first vertex
//! along its vertices). A polyline's corners are kept exactly when a break
//! falls on them. A reference handed to [`super::measure_from`] that has
//! corners already (a previous measurement, when tracking) keeps them and
//! the positions are not used again; a smooth one gets the breaks at these
//! arc lengths along it.
//!
//! Breaks need the exact closest-point coordinates (`coords = exact`).

use super::reference::{displaced_point, REFERENCE_SAMPLE_STEP};
use crate::curve::{crossing, InitialCurve, SplineCurve};
use crate::error::{Error, Result};
use crate::spline::{Basis, Break, MAX_DEGREE};
use rayon::prelude::*;

/// Degree of the reference curves built here (as in `reference::next_reference`).
const REFERENCE_DEGREE: usize = 3;
/// Control-point spacing of the initial reference with breaks, pixels.
const INITIAL_SPACING: f64 = 2.0;

/// The initial reference for `init` with corners at the arc lengths
/// `breaks` (see the [module docs](self)); [`InitialCurve::to_curve`] when
/// there are none.
pub(crate) fn initial_curve(init: &InitialCurve, breaks: &[f64]) -> Result<SplineCurve> {
    if breaks.is_empty() {
        return init.to_curve();
    }
    let pts = init.dense_points(0.25)?;
    with_corners_at(&pts, init.is_closed(), breaks, INITIAL_SPACING)
}

/// The reference of [`super::measure_from`]: unchanged without breaks or
/// when it has corners already, else refitted with corners at the arc
/// lengths `breaks` along it.
pub(crate) fn prepare(reference: SplineCurve, breaks: &[f64]) -> Result<SplineCurve> {
    if breaks.is_empty() || !reference.corners().is_empty() {
        return Ok(reference);
    }
    let l = reference.param_length();
    let count = (l / 0.25).ceil() as usize;
    let closed = reference.is_closed();
    let params = reference.sample_params(if closed { count } else { count + 1 });
    let pts: Vec<[f64; 2]> = params.iter().map(|&u| reference.point(u)).collect();
    with_corners_at(&pts, closed, breaks, INITIAL_SPACING)
}

/// A curve fitted to the polyline `pts` with corners at the arc lengths
/// `breaks` along it (each inserted as a vertex, or an existing vertex
/// within 1e-6 px).
fn with_corners_at(
    pts: &[[f64; 2]],
    closed: bool,
    breaks: &[f64],
    spacing: f64,
) -> Result<SplineCurve> {
    let dist = |a: [f64; 2], b: [f64; 2]| (a[0] - b[0]).hypot(a[1] - b[1]);
    let mut s = vec![0.0];
    for w in pts.windows(2) {
        s.push(s[s.len() - 1] + dist(w[0], w[1]));
    }
    let length = s[s.len() - 1]
        + if closed {
            dist(pts[pts.len() - 1], pts[0])
        } else {
            0.0
        };
    let mut sorted = breaks.to_vec();
    sorted.sort_by(f64::total_cmp);
    for &b in &sorted {
        let inside = if closed {
            (0.0..length).contains(&b)
        } else {
            b > 0.0 && b < length
        };
        if !inside {
            return Err(Error::invalid(
                "break",
                format!(
                    "{b} px is not inside the initial curve (length {length:.3} px{})",
                    if closed {
                        ", from 0"
                    } else {
                        ", ends excluded"
                    }
                ),
            ));
        }
    }
    let mut out: Vec<[f64; 2]> = Vec::with_capacity(pts.len() + sorted.len());
    let mut corners = Vec::with_capacity(sorted.len());
    let mut next = sorted.iter().peekable();
    let n = pts.len();
    let segs = if closed { n } else { n - 1 };
    for i in 0..segs {
        let (a, b) = (pts[i], pts[(i + 1) % n]);
        let (sa, sb) = (s[i], if i + 1 < n { s[i + 1] } else { length });
        out.push(a);
        while let Some(&&at) = next.peek() {
            if at > sb + 1e-6 {
                break;
            }
            next.next();
            if (at - sa).abs() <= 1e-6 {
                corners.push(out.len() - 1);
            } else if (at - sb).abs() <= 1e-6 && i + 1 < n {
                // The next vertex: marked when it is pushed.
                corners.push(out.len());
            } else {
                let t = (at - sa) / (sb - sa);
                out.push([a[0] + t * (b[0] - a[0]), a[1] + t * (b[1] - a[1])]);
                corners.push(out.len() - 1);
            }
        }
    }
    if !closed {
        out.push(pts[n - 1]);
    }
    corners.dedup();
    SplineCurve::fit_with_corners(&out, closed, REFERENCE_DEGREE, spacing, &corners)
}

/// The displacement basis of degree `p` with about `n_el` elements on
/// `reference`'s parameter: discontinuous at its corners (multiplicity
/// `p + 1`, see the module docs), uniform when it has none.
pub(crate) fn displacement_basis(reference: &SplineCurve, p: usize, n_el: usize) -> Result<Basis> {
    let breaks: Vec<Break> = reference
        .corners()
        .iter()
        .map(|&at| Break {
            at,
            multiplicity: p + 1,
        })
        .collect();
    Basis::with_breaks(
        p,
        n_el,
        reference.param_length(),
        reference.is_closed(),
        &breaks,
    )
}

/// `x0(u) + U(u) n(u)` and its derivative in `u`, from the left of `u`
/// (`left`) or the right: at a corner both `x0`'s normal and `U` jump.
fn displaced_side(
    reference: &SplineCurve,
    basis: &Basis,
    lambda: &[f64],
    u: f64,
    left: bool,
) -> ([f64; 2], [f64; 2]) {
    let [p, d1, d2] = if left {
        reference.derivatives_left(u)
    } else {
        reference.derivatives(u)
    };
    let (e, t) = if left {
        basis.locate_left(u)
    } else {
        basis.locate(u)
    };
    let v = basis.eval_derivs_at(e, t);
    let (mut disp, mut slope) = (0.0, 0.0);
    for k in 0..=basis.degree().min(MAX_DEGREE) {
        let c = lambda[basis.index(v.first, k)];
        disp += c * v.value[k];
        slope += c * v.d1[k];
    }
    let speed = d1[0].hypot(d1[1]).max(1e-300);
    let tan = [d1[0] / speed, d1[1] / speed];
    let n = [-tan[1], tan[0]];
    let kappa = (d1[0] * d2[1] - d1[1] * d2[0]) / (speed * speed * speed);
    // d/du (x0 + U n) = speed (1 - kappa U) t + U' n.
    let along = speed * (1.0 - kappa * disp);
    (
        [p[0] + disp * n[0], p[1] + disp * n[1]],
        [along * tan[0] + slope * n[0], along * tan[1] + slope * n[1]],
    )
}

/// Where the displaced sides meet at the corner `c` (see the module docs),
/// and their unit tangents (left, right).
fn meeting_point(
    reference: &SplineCurve,
    basis: &Basis,
    lambda: &[f64],
    c: f64,
) -> ([f64; 2], [f64; 2], [f64; 2]) {
    let (pl, dl) = displaced_side(reference, basis, lambda, c, true);
    let (pr, dr) = displaced_side(reference, basis, lambda, c, false);
    let unit = |d: [f64; 2]| {
        let n = d[0].hypot(d[1]).max(1e-300);
        [d[0] / n, d[1] / n]
    };
    let (tl, tr) = (unit(dl), unit(dr));
    let mid = [0.5 * (pl[0] + pr[0]), 0.5 * (pl[1] + pr[1])];
    let bound = 3.0 * (pr[0] - pl[0]).hypot(pr[1] - pl[1]) + 1.0;
    match crossing(pl, tl, pr, tr, 1e-3) {
        Some((a, b)) if a.abs() <= bound && b.abs() <= bound => {
            ([pl[0] + a * tl[0], pl[1] + a * tl[1]], tl, tr)
        }
        _ => (mid, tl, tr),
    }
}

/// Points of `x0 + U n` about `step` pixels apart in `reference`'s
/// parameter, with the parameter of each, and the indices of the corner
/// points among them (see the module docs). Without corners: the points at
/// `reference.sample_params` (`ceil(L / step)` intervals), no corner.
pub(crate) fn displaced_samples(
    reference: &SplineCurve,
    basis: &Basis,
    lambda: &[f64],
    step: f64,
) -> (Vec<f64>, Vec<[f64; 2]>, Vec<usize>) {
    let l = reference.param_length();
    let closed = reference.is_closed();
    let corners = reference.corners();
    let at = |u: f64| displaced_point(reference, basis, lambda, u);
    if corners.is_empty() {
        let count = (l / step).ceil() as usize;
        let params = reference.sample_params(if closed { count } else { count + 1 });
        let pts = params.par_iter().map(|&u| at(u)).collect();
        return (params, pts, Vec::new());
    }
    let starts_at_corner = closed && corners[0] == 0.0;
    let (mut pieces, after) = corner_pieces(reference, step, &at);
    let meet = trim_at_corners(reference, basis, lambda, &mut pieces, &after);
    let seq = in_order(&pieces, &meet, starts_at_corner);
    fill_gaps(&seq, closed, step)
}

/// Points `(parameter, point)` of a piece of the displaced curve.
type Piece = Vec<(f64, [f64; 2])>;
/// Where two pieces meet at a corner: its parameter and point.
type Meeting = Option<(f64, [f64; 2])>;

/// The displaced curve's points (`at`) about `step` apart on the pieces
/// between `reference`'s corners, the corners themselves left out; and the
/// corner after each piece (`None`: the end of an open curve, or of a
/// closed one that does not start at a corner).
fn corner_pieces(
    reference: &SplineCurve,
    step: f64,
    at: &(impl Fn(f64) -> [f64; 2] + Sync),
) -> (Vec<Piece>, Vec<Option<f64>>) {
    let l = reference.param_length();
    let closed = reference.is_closed();
    let corners = reference.corners();
    let starts_at_corner = closed && corners[0] == 0.0;
    let mut bounds = vec![0.0];
    bounds.extend(corners.iter().copied().filter(|&c| c > 0.0));
    bounds.push(l);
    let is_corner = |u: f64| corners.contains(&u) || (closed && u == l && starts_at_corner);
    let mut pieces: Vec<Piece> = Vec::new();
    let mut after: Vec<Option<f64>> = Vec::new();
    for (i, w) in bounds.windows(2).enumerate() {
        let (a, b) = (w[0], w[1]);
        let count = ((b - a) / step).ceil().max(1.0) as usize;
        let last = i + 2 == bounds.len();
        let piece = (0..=count)
            .map(|k| {
                if k == count {
                    b
                } else {
                    a + (b - a) * k as f64 / count as f64
                }
            })
            .filter(|&u| !(is_corner(u) || (closed && last && u == b)))
            .map(|u| (u, at(u)))
            .collect();
        pieces.push(piece);
        after.push(if last {
            starts_at_corner.then_some(0.0)
        } else {
            Some(b)
        });
    }
    (pieces, after)
}

/// The meeting point of the two sides of each corner (`after`, see
/// [`corner_pieces`]), with what overshoots it on either side trimmed off
/// the pieces.
fn trim_at_corners(
    reference: &SplineCurve,
    basis: &Basis,
    lambda: &[f64],
    pieces: &mut [Piece],
    after: &[Option<f64>],
) -> Vec<Meeting> {
    let np = pieces.len();
    let mut meet = vec![None; np];
    for i in 0..np {
        let Some(c) = after[i] else { continue };
        let (q, tl, tr) = meeting_point(reference, basis, lambda, c);
        let ahead = |p: [f64; 2], t: [f64; 2]| (p[0] - q[0]) * t[0] + (p[1] - q[1]) * t[1];
        while pieces[i].last().is_some_and(|x| ahead(x.1, tl) >= 0.0) {
            pieces[i].pop();
        }
        let j = (i + 1) % np;
        let head = pieces[j]
            .iter()
            .take_while(|x| ahead(x.1, tr) <= 0.0)
            .count();
        pieces[j].drain(..head);
        meet[i] = Some((c, q));
    }
    meet
}

/// The pieces and corners in order: `(parameter, point, is a corner)`.
fn in_order(
    pieces: &[Piece],
    meet: &[Meeting],
    starts_at_corner: bool,
) -> Vec<(f64, [f64; 2], bool)> {
    let np = pieces.len();
    let mut seq: Vec<(f64, [f64; 2], bool)> = Vec::new();
    if starts_at_corner {
        if let Some((c, q)) = meet[np - 1] {
            seq.push((c, q, true));
        }
    }
    for i in 0..np {
        seq.extend(pieces[i].iter().map(|&(u, p)| (u, p, false)));
        if i + 1 < np || !starts_at_corner {
            if let Some((c, q)) = meet[i] {
                seq.push((c, q, true));
            }
        }
    }
    seq
}

/// The parameters and points of `seq` (see [`in_order`]), with the indices
/// of its corners: a side that falls short of its corner is extended by a
/// straight segment, sampled about `step` apart like the rest (the fill
/// takes the corner's parameter, for `sigma` and the levels there).
fn fill_gaps(
    seq: &[(f64, [f64; 2], bool)],
    closed: bool,
    step: f64,
) -> (Vec<f64>, Vec<[f64; 2]>, Vec<usize>) {
    let mut params = Vec::with_capacity(seq.len());
    let mut pts = Vec::with_capacity(seq.len());
    let mut corner_idx = Vec::new();
    let n = seq.len();
    let pairs = if closed { n } else { n.saturating_sub(1) };
    for i in 0..n {
        let (u, p, corner) = seq[i];
        if corner {
            corner_idx.push(pts.len());
        }
        params.push(u);
        pts.push(p);
        if i >= pairs {
            continue;
        }
        let (_, q, next_corner) = seq[(i + 1) % n];
        if !(corner || next_corner) {
            continue;
        }
        // At most `step` apart, as the pieces' points are (the output
        // keeps every n-th point by the largest chord).
        let gap = (q[0] - p[0]).hypot(q[1] - p[1]);
        let fill = (gap / step).ceil() as usize;
        let c = if corner { u } else { seq[(i + 1) % n].0 };
        for k in 1..fill {
            let t = k as f64 / fill as f64;
            pts.push([p[0] + t * (q[0] - p[0]), p[1] + t * (q[1] - p[1])]);
            params.push(c);
        }
    }
    (params, pts, corner_idx)
}

/// The new reference `x0 + U n` with its corners (see the module docs): a
/// cubic B-spline with control points `spacing` pixels apart. Unlike a
/// smooth open curve, one with corners is not trimmed at the image border:
/// the trimmed stretch would need its corners mapped again.
pub(crate) fn displaced(
    reference: &SplineCurve,
    basis: &Basis,
    lambda: &[f64],
    spacing: f64,
) -> Result<SplineCurve> {
    let (_, pts, corners) = displaced_samples(reference, basis, lambda, REFERENCE_SAMPLE_STEP);
    SplineCurve::fit_with_corners(
        &pts,
        reference.is_closed(),
        REFERENCE_DEGREE,
        spacing,
        &corners,
    )
}
