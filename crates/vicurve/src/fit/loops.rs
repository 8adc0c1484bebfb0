//! Loops: a curve that crosses itself or folds back is not a measurement.
//!
//! A measured edge is a simple curve: it never crosses itself, and a
//! closed one turns once round (turning number ±1). A fit whose band lost
//! the edge can still end on a curve (by the iteration limit, or by
//! converging on noise) that loops: parts of it wander inside an object,
//! curl and cross the rest. That result must be reported as a divergence,
//! never as a success, so the fit checks every new reference (the curve
//! `x0 + U n` refitted, [`curve_loops`]) and the output samples
//! ([`looped`]): a closed curve must turn once round (a curve that loops
//! inside an object, folding back on itself, turns more), and no two
//! segments may cross ([`crossing`], a grid of cells so that 50,000
//! samples cost milliseconds, not `n^2` tests).
//!
//! The new reference is checked, not `x0 + U n` itself: where `U` exceeds
//! the reference's radius of curvature (a start's sharp corner, moved
//! inwards) `x0 + U n` has a small swallowtail that the refit smooths
//! away, an ordinary step of a fit. The output samples are `x0 + U n`
//! at convergence, where any such loop is an error.

use super::Divergence;
use crate::curve::SplineCurve;
use std::f64::consts::TAU;

/// Spacing of the points a curve is checked on, pixels: finer than any
/// loop that a displacement on elements of at least a few pixels can make
/// and that matters, coarse enough to be cheap.
const CHECK_STEP: f64 = 1.0;
/// Most points a curve is checked on (a longer curve is checked more
/// coarsely).
const MAX_CHECK_POINTS: usize = 200_000;
/// A closed curve whose turning number differs from ±1 by more than this
/// has looped (the turning number of a polyline is a whole number up to
/// rounding).
const TURNING_SLACK: f64 = 0.25;

/// Whether `curve` loops (then where): [`looped`] on points about
/// `CHECK_STEP` apart.
pub(super) fn curve_loops(curve: &SplineCurve) -> Option<Divergence> {
    let params = curve.sample_params(check_count(curve.param_length()));
    let points: Vec<[f64; 2]> = params.iter().map(|&u| curve.point(u)).collect();
    looped(&points, curve.is_closed())
}

/// Whether the polyline `points` (closed: the last joins the first) loops:
/// a closed one whose turning number is not ±1 ([`Divergence::FoldedBack`]
/// at its sharpest turn), or two segments that cross
/// ([`Divergence::SelfIntersecting`] where they do).
pub(crate) fn looped(points: &[[f64; 2]], closed: bool) -> Option<Divergence> {
    if closed {
        if let Some((turns, at)) = turning(points) {
            if (turns.abs() - 1.0).abs() > TURNING_SLACK {
                return Some(Divergence::FoldedBack { x: at[0], y: at[1] });
            }
        }
    }
    crossing(points, closed).map(|[x, y]| Divergence::SelfIntersecting { x, y })
}

/// Number of check points on a curve of parameter length `length`.
fn check_count(length: f64) -> usize {
    ((length / CHECK_STEP).ceil() as usize).clamp(16, MAX_CHECK_POINTS)
}

/// The turning number of a closed polyline (total signed turn of its
/// chords over a full turn) and the point of its sharpest turn; `None`
/// under three distinct points.
fn turning(points: &[[f64; 2]]) -> Option<(f64, [f64; 2])> {
    let n = points.len();
    if n < 3 {
        return None;
    }
    let (mut total, mut sharpest, mut at) = (0.0, 0.0, points[0]);
    let mut counted = 0;
    for i in 0..n {
        let a = points[(i + n - 1) % n];
        let b = points[i];
        let c = points[(i + 1) % n];
        let (u, v) = ([b[0] - a[0], b[1] - a[1]], [c[0] - b[0], c[1] - b[1]]);
        let cross = u[0] * v[1] - u[1] * v[0];
        let dot = u[0] * v[0] + u[1] * v[1];
        if cross == 0.0 && dot == 0.0 {
            continue;
        }
        let angle = cross.atan2(dot);
        counted += 1;
        total += angle;
        if angle.abs() > sharpest {
            (sharpest, at) = (angle.abs(), b);
        }
    }
    (counted >= 3).then_some((total / TAU, at))
}

/// Where two segments of the polyline `points` cross (closed: with the
/// segment from the last point to the first), if any two do; segments that
/// share an end point are not compared.
///
/// The segments are put in square cells of the plane (side the longest
/// segment or the plane's area per segment, whichever is larger, so that a
/// segment touches at most a few cells and a cell holds a few segments);
/// only segments in a common cell are compared: `O(n)` for a curve, where
/// comparing every pair would be `O(n^2)`.
pub(crate) fn crossing(points: &[[f64; 2]], closed: bool) -> Option<[f64; 2]> {
    let n = points.len();
    let segments = if closed { n } else { n.saturating_sub(1) };
    if segments < 3 {
        return None;
    }
    let seg = |i: usize| (points[i], points[(i + 1) % n]);
    let (mut lo, mut hi, mut longest) = ([f64::INFINITY; 2], [f64::NEG_INFINITY; 2], 0.0f64);
    for p in points {
        if !(p[0].is_finite() && p[1].is_finite()) {
            return None;
        }
        for a in 0..2 {
            lo[a] = lo[a].min(p[a]);
            hi[a] = hi[a].max(p[a]);
        }
    }
    for i in 0..segments {
        let (a, b) = seg(i);
        longest = longest.max((b[0] - a[0]).hypot(b[1] - a[1]));
    }
    let area = (hi[0] - lo[0]).max(1e-9) * (hi[1] - lo[1]).max(1e-9);
    let cell = longest.max((area / segments as f64).sqrt()).max(1e-9);
    let columns = ((hi[0] - lo[0]) / cell).floor() as u64 + 1;
    let index = |v: f64, a: usize| ((v - lo[a]) / cell).floor() as u64;
    // (cell, segment) for every cell a segment's bounding box touches.
    let mut entries: Vec<(u64, u32)> = Vec::with_capacity(2 * segments);
    for i in 0..segments {
        let (a, b) = seg(i);
        let (x0, x1) = (index(a[0].min(b[0]), 0), index(a[0].max(b[0]), 0));
        let (y0, y1) = (index(a[1].min(b[1]), 1), index(a[1].max(b[1]), 1));
        for y in y0..=y1 {
            for x in x0..=x1 {
                entries.push((y * columns + x, i as u32));
            }
        }
    }
    entries.sort_unstable();
    let neighbours = |i: usize, j: usize| {
        let d = i.abs_diff(j);
        d <= 1 || (closed && d == segments - 1)
    };
    for run in entries.chunk_by(|a, b| a.0 == b.0) {
        for (k, &(_, i)) in run.iter().enumerate() {
            for &(_, j) in &run[k + 1..] {
                let (i, j) = (i as usize, j as usize);
                if neighbours(i, j) {
                    continue;
                }
                let (a, b) = seg(i);
                let (c, d) = seg(j);
                if let Some(p) = intersection(a, b, c, d) {
                    return Some(p);
                }
            }
        }
    }
    None
}

/// The point where segments `ab` and `cd` cross (strictly: touching or
/// collinear segments do not count).
fn intersection(a: [f64; 2], b: [f64; 2], c: [f64; 2], d: [f64; 2]) -> Option<[f64; 2]> {
    let cross = |o: [f64; 2], p: [f64; 2], q: [f64; 2]| {
        (p[0] - o[0]) * (q[1] - o[1]) - (p[1] - o[1]) * (q[0] - o[0])
    };
    let (d1, d2) = (cross(c, d, a), cross(c, d, b));
    let (d3, d4) = (cross(a, b, c), cross(a, b, d));
    if d1 * d2 < 0.0 && d3 * d4 < 0.0 {
        let t = d1 / (d1 - d2);
        Some([a[0] + t * (b[0] - a[0]), a[1] + t * (b[1] - a[1])])
    } else {
        None
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn circle(n: usize, r: f64, turns: f64) -> Vec<[f64; 2]> {
        (0..n)
            .map(|i| {
                let t = TAU * turns * i as f64 / n as f64;
                [100.0 + r * t.cos(), 100.0 + r * t.sin()]
            })
            .collect()
    }

    #[test]
    fn a_circle_is_simple_and_a_figure_eight_is_not() {
        assert_eq!(looped(&circle(5000, 50.0, 1.0), true), None);
        let eight: Vec<[f64; 2]> = (0..4000)
            .map(|i| {
                let t = TAU * i as f64 / 4000.0;
                [100.0 + 50.0 * t.sin(), 100.0 + 30.0 * (2.0 * t).sin()]
            })
            .collect();
        let hit = crossing(&eight, true).expect("the figure eight crosses");
        assert!((hit[0] - 100.0).abs() < 0.1 && (hit[1] - 100.0).abs() < 0.1);
        // Its turning number is 0.
        assert!(matches!(
            looped(&eight, true),
            Some(Divergence::FoldedBack { .. })
        ));
    }

    #[test]
    fn a_curl_is_found_and_an_open_arc_is_not() {
        // A circle run twice round: turning number 2.
        assert!(matches!(
            looped(&circle(3000, 40.0, 2.0), true),
            Some(Divergence::FoldedBack { .. })
        ));
        // An open spiral-free arc of three quarters of a circle.
        assert_eq!(looped(&circle(3000, 40.0, 0.75), false), None);
        // An open curl (a loop of a trochoid).
        let curl: Vec<[f64; 2]> = (0..3000)
            .map(|i| {
                let t = -3.0 + 6.0 * i as f64 / 2999.0;
                [10.0 * t - 15.0 * t.sin(), -15.0 * t.cos()]
            })
            .collect();
        assert!(matches!(
            looped(&curl, false),
            Some(Divergence::SelfIntersecting { .. })
        ));
    }
}
