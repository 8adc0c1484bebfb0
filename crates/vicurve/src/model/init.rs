//! Initial shapes from the samples of a measured curve.
//!
//! - circle and ellipse (closed curves): the ellipse with the same area,
//!   centroid and second moments as the region the samples enclose
//!   (Green's theorem on the closed polygon of samples). For an ellipse the
//!   central second moments are `S = R diag(a^2, b^2) R^T / 4`, so this is
//!   exact up to the polygon's chords (relative 1e-6 for samples 1 px apart
//!   on a radius of 100 px), needs no eigenvalue solver beyond 2 x 2, and
//!   does not depend on how the samples are spaced; the circle's radius is
//!   `sqrt(area / pi)`.
//! - line (open curves): total least squares (the principal axis of the
//!   samples), directed like the curve, over the span of the samples.
//! - polygon of `N` vertices (closed curves): the measured curve rounds the
//!   corners, so vertices are found from the straight parts: `N` corner
//!   candidates by iterative splitting (start from the two samples farthest
//!   apart, then split the stretch whose sample lies farthest from its
//!   chord), then a few rounds of fitting a line (total least squares) to
//!   the middle 70 % of each side and intersecting consecutive lines. Two
//!   consecutive sides that are nearly collinear mean the curve has fewer
//!   than `N` corners: an error rather than a degenerate fit.

use super::line::Line;
use super::polygon;
use super::{ModelShape, ShapeModel};
use crate::error::{Error, Result};
use std::f64::consts::PI;

/// Two consecutive sides turning by less than this (radians, 3 degrees)
/// are one side.
const MIN_TURN: f64 = 0.052;
/// Rounds of line fits and intersections.
const POLYGON_ROUNDS: usize = 4;
/// Fraction of each side's samples left out at each end for its line fit.
const SIDE_TRIM: f64 = 0.15;
/// Samples left out at each end of a side at least.
const MIN_TRIM: usize = 2;
/// Samples a side's line fit needs at least.
const MIN_SIDE_SAMPLES: usize = 3;

fn mismatch(model: ShapeModel, reason: impl Into<String>) -> Error {
    Error::ModelMismatch {
        model: model.to_string(),
        reason: reason.into(),
    }
}

/// The initial shape of `model` for a measured curve through `points`
/// (pixels, in the curve's direction; closed curves counterclockwise on
/// screen, the last point not repeating the first).
///
/// Errors: [`Error::ModelMismatch`] when the model does not suit the curve
/// (a line for a closed curve, a closed shape for an open one, a polygon
/// with more sides than the curve has corners);
/// [`Error::NonFinite`] for NaN or infinite points.
pub fn initial_shape(points: &[[f64; 2]], closed: bool, model: ShapeModel) -> Result<ModelShape> {
    if points
        .iter()
        .any(|p| !(p[0].is_finite() && p[1].is_finite()))
    {
        return Err(Error::NonFinite {
            what: "measured points".into(),
        });
    }
    if points.len() < 8 {
        return Err(mismatch(
            model,
            format!("the measured curve has {} samples", points.len()),
        ));
    }
    match (model, closed) {
        (ShapeModel::BsplineCurve, _) => Err(mismatch(
            model,
            "a free B-spline curve has no parametric shape (see model::bspline_curve)",
        )),
        (ShapeModel::Line, false) => Ok(line(points).shape()),
        (ShapeModel::Line, true) => Err(mismatch(
            model,
            "the measured curve is closed; a line fits an open curve (start from a segment)",
        )),
        (_, false) => Err(mismatch(
            model,
            "the measured curve is open; this model needs a closed curve",
        )),
        (ShapeModel::Circle, true) => {
            let m = Moments::of(points);
            Ok(ModelShape::Circle {
                cx: m.centre[0],
                cy: m.centre[1],
                r: (m.area / PI).sqrt(),
            })
        }
        (ShapeModel::Ellipse, true) => {
            let m = Moments::of(points);
            let [sxx, sxy, syy] = m.central;
            let mean = 0.5 * (sxx + syy);
            let dev = (0.25 * (sxx - syy).powi(2) + sxy * sxy).sqrt();
            let (l1, l2) = (mean + dev, (mean - dev).max(0.0));
            // Eigenvector of l1 (screen coordinates); the angle is
            // counterclockwise on screen, hence the minus sign on y.
            let (ex, ey) = if sxy.abs() > 1e-12 * mean {
                (l1 - syy, sxy)
            } else if sxx >= syy {
                (1.0, 0.0)
            } else {
                (0.0, 1.0)
            };
            Ok(ModelShape::Ellipse {
                cx: m.centre[0],
                cy: m.centre[1],
                a: 2.0 * l1.sqrt(),
                b: 2.0 * l2.sqrt(),
                angle: (-ey).atan2(ex),
            })
        }
        (ShapeModel::Polygon { sides }, true) => Ok(ModelShape::Polygon {
            vertices: polygon_vertices(points, sides, model)?,
        }),
    }
}

/// Area, centroid and central second moments of a closed polygon.
struct Moments {
    area: f64,
    centre: [f64; 2],
    /// `[Sxx, Sxy, Syy]`, px^2, per unit area.
    central: [f64; 3],
}

impl Moments {
    fn of(points: &[[f64; 2]]) -> Moments {
        // About the mean point, for rounding.
        let n = points.len();
        let o = points
            .iter()
            .fold([0.0, 0.0], |s, p| [s[0] + p[0], s[1] + p[1]]);
        let o = [o[0] / n as f64, o[1] / n as f64];
        let (mut a2, mut mx, mut my, mut mxx, mut mxy, mut myy) = (0.0, 0.0, 0.0, 0.0, 0.0, 0.0);
        for i in 0..n {
            let (x0, y0) = (points[i][0] - o[0], points[i][1] - o[1]);
            let q = points[(i + 1) % n];
            let (x1, y1) = (q[0] - o[0], q[1] - o[1]);
            let c = x0 * y1 - x1 * y0;
            a2 += c;
            mx += (x0 + x1) * c;
            my += (y0 + y1) * c;
            mxx += (x0 * x0 + x0 * x1 + x1 * x1) * c;
            myy += (y0 * y0 + y0 * y1 + y1 * y1) * c;
            mxy += (x0 * y1 + 2.0 * x0 * y0 + 2.0 * x1 * y1 + x1 * y0) * c;
        }
        // Signed area (a2 / 2) divides out: the formulas hold in either
        // orientation.
        let area = 0.5 * a2;
        let (cx, cy) = (mx / (3.0 * a2), my / (3.0 * a2));
        let sxx = mxx / (12.0 * area) - cx * cx;
        let syy = myy / (12.0 * area) - cy * cy;
        let sxy = mxy / (24.0 * area) - cx * cy;
        Moments {
            area: area.abs(),
            centre: [cx + o[0], cy + o[1]],
            central: [sxx, sxy, syy],
        }
    }
}

/// Centroid and unit principal direction of points (total least squares).
pub(crate) fn principal(points: &[[f64; 2]]) -> ([f64; 2], [f64; 2]) {
    let n = points.len() as f64;
    let c = points
        .iter()
        .fold([0.0, 0.0], |s, p| [s[0] + p[0], s[1] + p[1]]);
    let c = [c[0] / n, c[1] / n];
    let (mut sxx, mut sxy, mut syy) = (0.0, 0.0, 0.0);
    for p in points {
        let (x, y) = (p[0] - c[0], p[1] - c[1]);
        sxx += x * x;
        sxy += x * y;
        syy += y * y;
    }
    // Angle of the major axis of the scatter matrix.
    let theta = 0.5 * (2.0 * sxy).atan2(sxx - syy);
    (c, [theta.cos(), theta.sin()])
}

/// The total-least-squares line through open-curve samples, directed
/// like them, over their span.
fn line(points: &[[f64; 2]]) -> Line {
    let (c, mut t) = principal(points);
    let (first, last) = (points[0], points[points.len() - 1]);
    if t[0] * (last[0] - first[0]) + t[1] * (last[1] - first[1]) < 0.0 {
        t = [-t[0], -t[1]];
    }
    let proj = |p: &[f64; 2]| t[0] * (p[0] - c[0]) + t[1] * (p[1] - c[1]);
    let (lo, hi) = points
        .iter()
        .map(proj)
        .fold((f64::INFINITY, f64::NEG_INFINITY), |(l, h), u| {
            (l.min(u), h.max(u))
        });
    Line {
        q0: c,
        // t = (cos alpha, -sin alpha).
        alpha: (-t[1]).atan2(t[0]),
        offset: 0.0,
        t_start: lo,
        t_end: hi,
    }
}

/// Distance from `p` to the line through `a` and `b`.
fn chord_distance(p: [f64; 2], a: [f64; 2], b: [f64; 2]) -> f64 {
    let (ex, ey) = (b[0] - a[0], b[1] - a[1]);
    let len = ex.hypot(ey);
    if len == 0.0 {
        return (p[0] - a[0]).hypot(p[1] - a[1]);
    }
    ((p[0] - a[0]) * ey - (p[1] - a[1]) * ex).abs() / len
}

/// `N` vertices from the samples of a closed curve (module docs).
fn polygon_vertices(points: &[[f64; 2]], sides: usize, model: ShapeModel) -> Result<Vec<[f64; 2]>> {
    let m = points.len();
    let min_samples = sides * (2 * MIN_TRIM + MIN_SIDE_SAMPLES);
    if m < min_samples {
        return Err(mismatch(
            model,
            format!("the measured curve ({m} samples) is too short for {sides} sides"),
        ));
    }
    let at = |k: usize| points[k % m];
    // Corner candidates by iterative splitting.
    let (c, _) = principal(points);
    let far = |from: [f64; 2]| {
        (0..m)
            .max_by(|&i, &j| {
                let di = (points[i][0] - from[0]).hypot(points[i][1] - from[1]);
                let dj = (points[j][0] - from[0]).hypot(points[j][1] - from[1]);
                di.total_cmp(&dj)
            })
            .unwrap_or(0)
    };
    let i0 = far(c);
    let i1 = far(points[i0]);
    let mut idx = vec![i0.min(i1), i0.max(i1)];
    if idx[0] == idx[1] {
        return Err(mismatch(model, "the measured curve has no extent"));
    }
    while idx.len() < sides {
        let mut best = (f64::NEG_INFINITY, 0, 0);
        for k in 0..idx.len() {
            let (a, mut b) = (idx[k], idx[(k + 1) % idx.len()]);
            if b <= a {
                b += m;
            }
            for j in a + 1..b {
                let dist = chord_distance(at(j), at(a), at(b));
                if dist > best.0 {
                    best = (dist, k, j % m);
                }
            }
        }
        if best.0 < 0.0 {
            return Err(mismatch(model, format!("cannot place {sides} vertices")));
        }
        idx.push(best.2);
        idx.sort_unstable();
        idx.dedup();
    }
    // Lines through the middle of each side, intersected.
    let mut vertices = Vec::new();
    for _ in 0..POLYGON_ROUNDS {
        let mut lines = Vec::with_capacity(sides);
        for k in 0..sides {
            let (a, mut b) = (idx[k], idx[(k + 1) % sides]);
            if b <= a {
                b += m;
            }
            let count = b - a - 1;
            let trim = ((SIDE_TRIM * count as f64).ceil() as usize).max(MIN_TRIM);
            if count < 2 * trim + MIN_SIDE_SAMPLES {
                return Err(mismatch(
                    model,
                    format!(
                        "side {k} is too short ({count} samples): the curve has fewer than {sides} corners"
                    ),
                ));
            }
            let part: Vec<[f64; 2]> = (a + 1 + trim..b - trim).map(at).collect();
            lines.push(principal(&part));
        }
        vertices.clear();
        for k in 0..sides {
            let (p, u) = lines[(k + sides - 1) % sides];
            let (q, w) = lines[k];
            let det = u[0] * w[1] - u[1] * w[0];
            if det.abs() < MIN_TURN.sin() {
                return Err(mismatch(
                    model,
                    format!(
                        "sides {} and {k} are nearly collinear: the curve has fewer than {sides} corners",
                        (k + sides - 1) % sides
                    ),
                ));
            }
            // p + s u = q + r w.
            let s = ((q[0] - p[0]) * w[1] - (q[1] - p[1]) * w[0]) / det;
            vertices.push([p[0] + s * u[0], p[1] + s * u[1]]);
        }
        // Re-anchor each corner to its nearest sample.
        let mut next: Vec<usize> = vertices
            .iter()
            .map(|v| {
                (0..m)
                    .min_by(|&i, &j| {
                        let di = (points[i][0] - v[0]).hypot(points[i][1] - v[1]);
                        let dj = (points[j][0] - v[0]).hypot(points[j][1] - v[1]);
                        di.total_cmp(&dj)
                    })
                    .unwrap_or(0)
            })
            .collect();
        // Keep the vertices in the curve's order (starting anywhere).
        let first = (0..sides).min_by_key(|&k| next[k]).unwrap_or(0);
        next.rotate_left(first);
        vertices.rotate_left(first);
        if next.windows(2).any(|w| w[1] <= w[0]) {
            return Err(mismatch(
                model,
                format!("the {sides} corners found are not in the curve's order"),
            ));
        }
        idx = next;
    }
    polygon::check(&vertices).map_err(|reason| mismatch(model, reason))?;
    Ok(vertices)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn moments_of_an_ellipse() {
        let (cx, cy, a, b, angle) = (50.2f64, 41.7f64, 30.0f64, 12.0f64, 0.4f64);
        let (sa, ca) = angle.sin_cos();
        let pts: Vec<[f64; 2]> = (0..2000)
            .map(|k| {
                let s = std::f64::consts::TAU * k as f64 / 2000.0;
                let (lx, ly) = (a * s.cos(), b * s.sin());
                [cx + lx * ca - ly * sa, cy - (lx * sa + ly * ca)]
            })
            .collect();
        let ModelShape::Ellipse {
            cx: x,
            cy: y,
            a: ea,
            b: eb,
            angle: an,
        } = initial_shape(&pts, true, ShapeModel::Ellipse).unwrap()
        else {
            panic!()
        };
        assert!((x - cx).abs() < 1e-9 && (y - cy).abs() < 1e-9, "{x} {y}");
        assert!((ea - a).abs() < 1e-3 && (eb - b).abs() < 1e-3, "{ea} {eb}");
        assert!((an - angle).abs() < 1e-6, "{an}");
    }
}
