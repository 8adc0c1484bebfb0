//! Best-fit ellipse: geometric least squares (orthogonal distances, each
//! point's foot on the ellipse found by Eberly's robust root finding),
//! started from the direct algebraic fit of Fitzgibbon, Pilu and Fisher in
//! the numerically stable form of Halíř and Flusser.

use super::circle::{normalisation, rms};
use super::lsq::{self, Model};
use crate::error::{Error, Result};
use rayon::prelude::*;
use serde::{Deserialize, Serialize};
use std::f64::consts::{FRAC_PI_2, PI};

/// Relative difference of the semi-axes under which an ellipse is taken
/// for a circle (its angle undetermined).
const CIRCLE_TOLERANCE: f64 = 1e-9;

/// An ellipse fitted to points, with the standard deviations of its
/// parameters. Lengths in pixels, angles in radians.
///
/// The angle follows [`crate::truth::Shape::Ellipse`]: the direction of the
/// `a` axis, `(cos angle, -sin angle)` in `(x, y)`, i.e. measured from `+x`
/// counterclockwise *on screen* (towards `-y`), in `(-pi/2, pi/2]`.
#[derive(Clone, Copy, Debug, PartialEq, Serialize, Deserialize)]
pub struct EllipseFit {
    /// Centre, x (column), px.
    pub cx: f64,
    /// Centre, y (row), px.
    pub cy: f64,
    /// Major semi-axis, px (`a >= b > 0`).
    pub a: f64,
    /// Minor semi-axis, px.
    pub b: f64,
    /// Direction of the major axis, rad (see the type's documentation);
    /// 0 for a circle (`a` and `b` equal within 1e-9 relative).
    pub angle: f64,
    /// Standard deviation of `cx`, px (NaN when it cannot be estimated: no
    /// more points, or independent points, than unknowns).
    pub sigma_cx: f64,
    /// Standard deviation of `cy`, px.
    pub sigma_cy: f64,
    /// Standard deviation of `a`, px.
    pub sigma_a: f64,
    /// Standard deviation of `b`, px.
    pub sigma_b: f64,
    /// Standard deviation of `angle`, rad; NaN for a circle (the angle is
    /// then undetermined), and large (meaningless) when `a - b` is not
    /// larger than the deviations of `a` and `b`.
    pub sigma_angle: f64,
    /// RMS of the points' orthogonal distances to the ellipse, px
    /// (unweighted).
    pub rms: f64,
}

/// The ellipse that minimises the (weighted) sum of squared orthogonal
/// distances from `points` (pixels) to it.
///
/// `sigma` and the deviations are as in [`super::fit_circle`]; the points
/// are taken as independent (see [`fit_ellipse_with`] for correlated ones).
///
/// Errors: [`Error::NonFinite`] for a NaN or infinite coordinate;
/// [`Error::InvalidCurve`] for fewer than 5 points, collinear points, or
/// points that determine no ellipse; [`Error::InvalidParameter`] when
/// `sigma` and `points` differ in length.
pub fn fit_ellipse(points: &[[f64; 2]], sigma: Option<&[f64]>) -> Result<EllipseFit> {
    fit_ellipse_with(points, sigma, None)
}

/// [`fit_ellipse`] for points that carry only `independent` independent
/// pieces of information; see [`super::fit_circle_with`].
pub fn fit_ellipse_with(
    points: &[[f64; 2]],
    sigma: Option<&[f64]>,
    independent: Option<f64>,
) -> Result<EllipseFit> {
    lsq::check_points(points, 5, "ellipse")?;
    let w = lsq::weights(points.len(), sigma)?;
    let (m, scale, planar) = normalisation(points);
    if !planar {
        return Err(Error::InvalidCurve {
            reason: "the points are collinear (or coincident): no ellipse fits them".into(),
        });
    }
    let start = direct_fit(points, m, scale).unwrap_or_else(|| moments(points, m));
    let sol = lsq::minimise(
        &EllipseModel { points },
        start.to_vec(),
        points.len(),
        w.as_deref(),
        "ellipse",
    )?;
    let p = &sol.params;
    if p.iter().any(|v| !v.is_finite()) {
        return Err(Error::InvalidCurve {
            reason: "the ellipse fit diverged".into(),
        });
    }
    // A circle (to rounding) has no axis direction: its angle is reported
    // as 0 and left out of the covariance.
    let circle = (p[2] - p[3]).abs() <= CIRCLE_TOLERANCE * p[2].max(p[3]);
    let dev = lsq::deviations(&sol, independent, &[4], circle);
    let (mut a, mut b, mut angle) = (p[2], p[3], if circle { 0.0 } else { p[4] });
    let (mut sa, mut sb) = (dev[2], dev[3]);
    if b > a {
        std::mem::swap(&mut a, &mut b);
        std::mem::swap(&mut sa, &mut sb);
        angle += FRAC_PI_2;
    }
    Ok(EllipseFit {
        cx: p[0],
        cy: p[1],
        a,
        b,
        angle: normalise_angle(angle),
        sigma_cx: dev[0],
        sigma_cy: dev[1],
        sigma_a: sa,
        sigma_b: sb,
        sigma_angle: dev[4],
        rms: rms(&sol.residuals),
    })
}

/// `angle` modulo `pi`, in `(-pi/2, pi/2]`.
fn normalise_angle(angle: f64) -> f64 {
    let mut t = angle.rem_euclid(PI);
    if t > FRAC_PI_2 {
        t -= PI;
    }
    t
}

/// Unit vectors of the `a` and `b` axes for `angle` (see [`EllipseFit`]).
fn axes(angle: f64) -> ([f64; 2], [f64; 2]) {
    let (s, c) = angle.sin_cos();
    ([c, -s], [s, c])
}

/// Halíř–Flusser direct least-squares ellipse on centred, scaled
/// coordinates; `None` when no eigenvector satisfies the ellipse constraint
/// (the points are far from any ellipse).
fn direct_fit(points: &[[f64; 2]], m: [f64; 2], scale: f64) -> Option<[f64; 5]> {
    let mut s1 = [[0.0; 3]; 3];
    let mut s2 = [[0.0; 3]; 3];
    let mut s3 = [[0.0; 3]; 3];
    for p in points {
        let x = (p[0] - m[0]) / scale;
        let y = (p[1] - m[1]) / scale;
        let d1 = [x * x, x * y, y * y];
        let d2 = [x, y, 1.0];
        for i in 0..3 {
            for j in 0..3 {
                s1[i][j] += d1[i] * d1[j];
                s2[i][j] += d1[i] * d2[j];
                s3[i][j] += d2[i] * d2[j];
            }
        }
    }
    // T = -S3^-1 S2^T, M = S1 + S2 T, then C1^-1 M.
    let s3i = inverse3(&s3)?;
    let mut t = [[0.0; 3]; 3];
    for i in 0..3 {
        for j in 0..3 {
            t[i][j] = -(0..3).map(|k| s3i[i][k] * s2[j][k]).sum::<f64>();
        }
    }
    let mut mm = s1;
    for i in 0..3 {
        for j in 0..3 {
            mm[i][j] += (0..3).map(|k| s2[i][k] * t[k][j]).sum::<f64>();
        }
    }
    let n = [
        [mm[2][0] / 2.0, mm[2][1] / 2.0, mm[2][2] / 2.0],
        [-mm[1][0], -mm[1][1], -mm[1][2]],
        [mm[0][0] / 2.0, mm[0][1] / 2.0, mm[0][2] / 2.0],
    ];
    let mut best: Option<([f64; 3], f64)> = None;
    for lambda in eigenvalues3(&n) {
        let Some(v) = null_vector(&n, lambda) else {
            continue;
        };
        let cond = 4.0 * v[0] * v[2] - v[1] * v[1];
        let norm2 = v.iter().map(|x| x * x).sum::<f64>();
        let c = cond / norm2;
        if c > 0.0 && best.is_none_or(|(_, b)| c > b) {
            best = Some((v, c));
        }
    }
    let (a1, _) = best?;
    let a2: Vec<f64> = (0..3)
        .map(|i| (0..3).map(|k| t[i][k] * a1[k]).sum())
        .collect();
    let [cx, cy, a, b, angle] = conic_to_parameters([a1[0], a1[1], a1[2], a2[0], a2[1], a2[2]])?;
    Some([
        m[0] + scale * cx,
        m[1] + scale * cy,
        scale * a,
        scale * b,
        angle,
    ])
}

/// Centre, semi-axes and angle of the ellipse
/// `A x^2 + B x y + C y^2 + D x + E y + F = 0`; `None` if it is not a real
/// ellipse.
fn conic_to_parameters(c: [f64; 6]) -> Option<[f64; 5]> {
    let [a, b, cc, d, e, f] = c;
    let det = 4.0 * a * cc - b * b;
    if det.is_nan() || det == 0.0 {
        return None;
    }
    let x0 = (b * e - 2.0 * cc * d) / det;
    let y0 = (b * d - 2.0 * a * e) / det;
    let f0 = f + 0.5 * (d * x0 + e * y0);
    // Eigen-decomposition of [[a, b/2], [b/2, cc]].
    let half = 0.5 * ((a - cc).powi(2) + b * b).sqrt();
    let mean = 0.5 * (a + cc);
    let (l1, l2) = (mean - half, mean + half);
    let (ax1, ax2) = (-f0 / l1, -f0 / l2);
    if !(ax1 > 0.0 && ax2 > 0.0 && ax1.is_finite() && ax2.is_finite()) {
        return None;
    }
    // Eigenvector of l1 (the smaller |lambda| when both are positive, i.e.
    // the longer axis when f0 < 0; normalised afterwards anyway).
    let v = if b.abs() > 1e-300 || (a - l1).abs() > 1e-300 {
        let cand1 = [b / 2.0, l1 - a];
        let cand2 = [l1 - cc, b / 2.0];
        if cand1[0].hypot(cand1[1]) >= cand2[0].hypot(cand2[1]) {
            cand1
        } else {
            cand2
        }
    } else {
        [1.0, 0.0]
    };
    let v = if v[0].hypot(v[1]) > 0.0 {
        v
    } else {
        [1.0, 0.0]
    };
    let angle = (-v[1]).atan2(v[0]);
    Some([x0, y0, ax1.sqrt(), ax2.sqrt(), angle])
}

/// Start from second moments: centroid, principal axes, semi-axes
/// `sqrt(2 lambda)` (exact for points evenly spread in the eccentric
/// anomaly).
fn moments(points: &[[f64; 2]], m: [f64; 2]) -> [f64; 5] {
    let n = points.len() as f64;
    let (mut sxx, mut sxy, mut syy) = (0.0, 0.0, 0.0);
    for p in points {
        let (x, y) = (p[0] - m[0], p[1] - m[1]);
        sxx += x * x / n;
        sxy += x * y / n;
        syy += y * y / n;
    }
    let half = 0.5 * ((sxx - syy).powi(2) + 4.0 * sxy * sxy).sqrt();
    let mean = 0.5 * (sxx + syy);
    let (big, small) = (mean + half, (mean - half).max(1e-6 * (mean + half)));
    let theta = 0.5 * (2.0 * sxy).atan2(sxx - syy); // direction of `big`, in (x, y)
    let angle = -theta;
    [m[0], m[1], (2.0 * big).sqrt(), (2.0 * small).sqrt(), angle]
}

/// Inverse of a 3x3 matrix; `None` if singular.
fn inverse3(m: &[[f64; 3]; 3]) -> Option<[[f64; 3]; 3]> {
    let c = |i: usize, j: usize| {
        let (i1, i2) = ((i + 1) % 3, (i + 2) % 3);
        let (j1, j2) = ((j + 1) % 3, (j + 2) % 3);
        m[i1][j1] * m[i2][j2] - m[i1][j2] * m[i2][j1]
    };
    let det = m[0][0] * c(0, 0) + m[0][1] * c(0, 1) + m[0][2] * c(0, 2);
    let scale = m.iter().flatten().map(|v| v.abs()).fold(0.0, f64::max);
    if det.is_nan() || det.abs() <= 1e-14 * scale.powi(3) {
        return None;
    }
    let mut out = [[0.0; 3]; 3];
    for (i, row) in out.iter_mut().enumerate() {
        for (j, v) in row.iter_mut().enumerate() {
            *v = c(j, i) / det;
        }
    }
    Some(out)
}

/// Real eigenvalues of a 3x3 matrix (roots of its characteristic cubic,
/// polished by Newton steps).
fn eigenvalues3(m: &[[f64; 3]; 3]) -> Vec<f64> {
    let tr = m[0][0] + m[1][1] + m[2][2];
    let minors = m[0][0] * m[1][1] - m[0][1] * m[1][0] + m[0][0] * m[2][2] - m[0][2] * m[2][0]
        + m[1][1] * m[2][2]
        - m[1][2] * m[2][1];
    let det = m[0][0] * (m[1][1] * m[2][2] - m[1][2] * m[2][1])
        - m[0][1] * (m[1][0] * m[2][2] - m[1][2] * m[2][0])
        + m[0][2] * (m[1][0] * m[2][1] - m[1][1] * m[2][0]);
    // lambda^3 + a lambda^2 + b lambda + c
    let (a, b, c) = (-tr, minors, -det);
    let q = (a * a - 3.0 * b) / 9.0;
    let r = (2.0 * a * a * a - 9.0 * a * b + 27.0 * c) / 54.0;
    let mut roots = Vec::with_capacity(3);
    if r * r < q * q * q {
        let theta = (r / (q * q * q).sqrt()).clamp(-1.0, 1.0).acos();
        let sq = -2.0 * q.sqrt();
        for k in 0..3 {
            roots.push(sq * ((theta + 2.0 * PI * k as f64) / 3.0).cos() - a / 3.0);
        }
    } else {
        let big = -r.signum() * (r.abs() + (r * r - q * q * q).sqrt()).cbrt();
        let small = if big != 0.0 { q / big } else { 0.0 };
        roots.push(big + small - a / 3.0);
    }
    for x in &mut roots {
        for _ in 0..3 {
            let f = ((*x + a) * *x + b) * *x + c;
            let df = (3.0 * *x + 2.0 * a) * *x + b;
            if df != 0.0 && (f / df).is_finite() {
                *x -= f / df;
            }
        }
    }
    roots
}

/// A unit vector spanning the null space of `m - lambda I` (the largest
/// cross product of two of its rows); `None` if all vanish.
fn null_vector(m: &[[f64; 3]; 3], lambda: f64) -> Option<[f64; 3]> {
    let mut rows = *m;
    for (i, row) in rows.iter_mut().enumerate() {
        row[i] -= lambda;
    }
    let cross = |u: [f64; 3], v: [f64; 3]| {
        [
            u[1] * v[2] - u[2] * v[1],
            u[2] * v[0] - u[0] * v[2],
            u[0] * v[1] - u[1] * v[0],
        ]
    };
    let cands = [
        cross(rows[0], rows[1]),
        cross(rows[0], rows[2]),
        cross(rows[1], rows[2]),
    ];
    let (v, n) = cands
        .iter()
        .map(|v| (*v, v.iter().map(|x| x * x).sum::<f64>().sqrt()))
        .fold(
            ([0.0; 3], 0.0),
            |best, c| if c.1 > best.1 { c } else { best },
        );
    (n > 0.0 && n.is_finite()).then(|| [v[0] / n, v[1] / n, v[2] / n])
}

/// The point of the ellipse `(x/e0)^2 + (y/e1)^2 = 1` (`e0 >= e1 > 0`)
/// closest to `(y0, y1)` in the first quadrant (Eberly, "Distance from a
/// point to an ellipse"): the root of a monotone function, found by
/// safeguarded Newton steps within a bracket.
fn foot_first_quadrant(e0: f64, e1: f64, y0: f64, y1: f64) -> [f64; 2] {
    if y1 > 0.0 {
        if y0 > 0.0 {
            let (z0, z1) = (y0 / e0, y1 / e1);
            let g = z0 * z0 + z1 * z1 - 1.0;
            if g == 0.0 {
                return [y0, y1];
            }
            let r0 = (e0 / e1) * (e0 / e1);
            let s = root(r0, z0, z1, g);
            [r0 * y0 / (s + r0), y1 / (s + 1.0)]
        } else {
            [0.0, e1]
        }
    } else {
        let (num, den) = (e0 * y0, e0 * e0 - e1 * e1);
        if num < den {
            let x = num / den;
            [e0 * x, e1 * (1.0 - x * x).max(0.0).sqrt()]
        } else {
            [e0, 0.0]
        }
    }
}

/// Root of `G(s) = (r0 z0 / (s + r0))^2 + (z1 / (s + 1))^2 - 1`, decreasing
/// and convex for `s > -1`, bracketed by Eberly's bounds.
fn root(r0: f64, z0: f64, z1: f64, g: f64) -> f64 {
    let n0 = r0 * z0;
    let (mut lo, mut hi) = (z1 - 1.0, if g < 0.0 { 0.0 } else { n0.hypot(z1) - 1.0 });
    let eval = |s: f64| {
        let (q0, q1) = (n0 / (s + r0), z1 / (s + 1.0));
        (
            q0 * q0 + q1 * q1 - 1.0,
            -2.0 * (q0 * q0 / (s + r0) + q1 * q1 / (s + 1.0)),
        )
    };
    // Newton's step from s = 0 (where G = g): for the points of a fit,
    // close to the ellipse, within rounding of the root after two or three
    // more steps (the bracket's middle took dozens of halvings).
    let first = g / (2.0 * (z0 * z0 / r0 + z1 * z1));
    let mut s = if first > lo && first < hi {
        first
    } else {
        0.5 * (lo + hi)
    };
    for _ in 0..200 {
        let (f, df) = eval(s);
        if f == 0.0 {
            return s;
        }
        if f > 0.0 {
            lo = s;
        } else {
            hi = s;
        }
        let newton = s - f / df;
        let next = if newton > lo && newton < hi && newton.is_finite() {
            newton
        } else {
            0.5 * (lo + hi)
        };
        if (next - s).abs() <= 4.0 * f64::EPSILON * (1.0 + s.abs()) || next == lo || next == hi {
            return next;
        }
        s = next;
    }
    s
}

/// The foot of `(u, v)` (local coordinates along the `a` and `b` axes) on
/// the ellipse of semi-axes `a`, `b`, any quadrant and either axis longer.
fn foot(a: f64, b: f64, u: f64, v: f64) -> [f64; 2] {
    let q = if a >= b {
        foot_first_quadrant(a, b, u.abs(), v.abs())
    } else {
        let f = foot_first_quadrant(b, a, v.abs(), u.abs());
        [f[1], f[0]]
    };
    [q[0].copysign(u), q[1].copysign(v)]
}

/// Signed orthogonal distances (positive outside) and their derivatives
/// with respect to `(cx, cy, a, b, angle)`: with the foot `E(t)` fixed, the
/// derivative of `(p - E) . n` is `-n . dE/dparameter` (the foot's own
/// motion is along the tangent).
struct EllipseModel<'a> {
    points: &'a [[f64; 2]],
}

impl Model for EllipseModel<'_> {
    fn eval(&self, p: &[f64], r: &mut [f64], jac: &mut [f64]) -> bool {
        let (cx, cy, a, b, angle) = (p[0], p[1], p[2], p[3], p[4]);
        if !(a > 0.0 && b > 0.0 && angle.is_finite()) {
            return false;
        }
        let (ua, ub) = axes(angle);
        // In parallel: every point's foot (an iterative root) is its own.
        self.points
            .par_iter()
            .zip(r.par_iter_mut())
            .zip(jac.par_chunks_mut(5))
            .with_min_len(256)
            .for_each(|((q, ri), row)| {
                let d = [q[0] - cx, q[1] - cy];
                let u = d[0] * ua[0] + d[1] * ua[1];
                let v = d[0] * ub[0] + d[1] * ub[1];
                let f = foot(a, b, u, v);
                let (cos_t, sin_t) = (f[0] / a, f[1] / b);
                let nl = [b * cos_t, a * sin_t];
                // sqrt, not hypot: pixel scales cannot overflow, and hypot
                // took a tenth of the fit.
                let len = (nl[0] * nl[0] + nl[1] * nl[1]).sqrt();
                let (n0, n1) = (nl[0] / len, nl[1] / len);
                *ri = (u - f[0]) * n0 + (v - f[1]) * n1;
                row[0] = -(n0 * ua[0] + n1 * ub[0]);
                row[1] = -(n0 * ua[1] + n1 * ub[1]);
                row[2] = -n0 * cos_t;
                row[3] = -n1 * sin_t;
                row[4] = -(n0 * b * sin_t - n1 * a * cos_t);
            });
        true
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn foot_is_on_the_ellipse_and_normal() {
        for &(a, b) in &[(5.0, 3.0), (3.0, 5.0), (2.0, 2.0)] {
            // Far, inside, on the axes, and a thousandth of a unit off the
            // ellipse (a fit's points: the root's first guess is then close).
            let near = |t: f64, d: f64| (a * t.cos() * (1.0 + d), b * t.sin() * (1.0 + d));
            for &(u, v) in &[
                (7.0, 1.0),
                (0.3, -0.2),
                (-1.0, 4.0),
                (0.0, 0.5),
                (6.0, 0.0),
                near(0.7, 1e-3),
                near(-2.2, -1e-3),
                near(1.5, 2e-4),
            ] {
                let f = foot(a, b, u, v);
                let on = (f[0] / a).powi(2) + (f[1] / b).powi(2);
                assert!((on - 1.0).abs() < 1e-12, "{a} {b} {u} {v}: {on}");
                // (p - f) is along the normal (f/a^2, f/b^2).
                let n = [f[0] / (a * a), f[1] / (b * b)];
                let cross = (u - f[0]) * n[1] - (v - f[1]) * n[0];
                assert!(cross.abs() < 1e-12, "{a} {b} {u} {v}: {cross}");
            }
        }
    }

    #[test]
    fn conic_round_trip() {
        // (x-3)^2/25 + (y+1)^2/4 = 1, axis along x: angle 0.
        let c = [4.0, 0.0, 25.0, -24.0, 50.0, 36.0 + 25.0 - 100.0];
        let p = conic_to_parameters(c).unwrap();
        assert!((p[0] - 3.0).abs() < 1e-12 && (p[1] + 1.0).abs() < 1e-12);
        assert!((p[2] - 5.0).abs() < 1e-12 && (p[3] - 2.0).abs() < 1e-12);
        assert!(normalise_angle(p[4]).abs() < 1e-12);
    }
}
