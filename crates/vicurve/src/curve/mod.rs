//! Plane curves as uniform B-spline curves.
//!
//! Every curve the method handles (the initial circle or segment, each
//! reference curve between stages, the measured result) is a
//! [`SplineCurve`]: control points `P_i` on a uniform [`Basis`] whose
//! parameter `u` runs over `[0, L]` (open) or `[0, L)` (periodic) and is
//! close to the arc length (chord-length parametrisation of dense samples).
//!
//! # Orientation
//! Unit tangent `t = C'(u) / |C'(u)|`, unit normal `n = (-t_y, t_x)`. Closed
//! curves are oriented counterclockwise *as seen on screen* (y down), so that
//! `n` points outward; open curves keep the direction they were given, `n`
//! on the screen-right of the direction of travel. The signed curvature
//! `kappa` satisfies `dt/ds = kappa n`: a convex closed curve has
//! `kappa < 0`, and the point `C + r n` lies on a parallel curve whose
//! length element is `(1 - kappa r)` times the curve's.

mod corners;
pub mod init;
mod project;

pub(crate) use corners::crossing;
pub use corners::Clearance;
pub use init::InitialCurve;

use crate::error::{Error, Result};
use crate::solver::chunked::chunked_sum;
use crate::solver::{BandCholesky, SymBandMatrix};
use crate::spline::{Basis, MAX_DEGREE};
use serde::{Deserialize, Serialize};

/// Position, unit tangent and normal, curvature and speed at a parameter.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Frame {
    /// The point `C(u)`, pixels.
    pub point: [f64; 2],
    /// Unit tangent.
    pub tangent: [f64; 2],
    /// Unit normal `(-t_y, t_x)`.
    pub normal: [f64; 2],
    /// Signed curvature `kappa`, 1/pixels (see the module docs).
    pub curvature: f64,
    /// `|C'(u)|`, close to 1 for the chord-length parametrisation.
    pub speed: f64,
}

/// A B-spline curve in the image plane; see the [module documentation](self).
#[derive(Clone, Debug, PartialEq)]
pub struct SplineCurve {
    basis: Basis,
    ctrl: Vec<[f64; 2]>,
    /// Per element, the power-basis coefficients of x and y in the local
    /// coordinate `t` in `[0, 1]`: evaluation is one Horner pass, which
    /// makes the projection of ~1e5 band pixels cheap.
    poly: Vec<[[f64; MAX_DEGREE + 1]; 2]>,
    /// Parameters of the corners (knots of multiplicity >= degree), sorted.
    corners: Vec<f64>,
}

/// The serialisable description of a [`SplineCurve`] for result files.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub struct SplineCurveData {
    /// Degree.
    pub degree: usize,
    /// Whether the curve is closed (periodic).
    pub closed: bool,
    /// Knot vector (pixels of parameter). For closed curves the unwrapped
    /// periodic vector: the first `degree` control points are repeated at the
    /// end of `control_points`, so that the data describe an ordinary
    /// (clamped-free, uniform) B-spline curve on `[knots[p], knots[n]]`.
    pub knots: Vec<f64>,
    /// Control points `[x, y]`, pixels.
    pub control_points: Vec<[f64; 2]>,
}

impl SplineCurve {
    /// A curve from its basis and control points (`basis.n_functions()` of
    /// them). Errors on a count mismatch or non-finite coordinates.
    pub fn new(basis: Basis, ctrl: Vec<[f64; 2]>) -> Result<Self> {
        if ctrl.len() != basis.n_functions() {
            return Err(Error::invalid(
                "control points",
                format!(
                    "{} control points for {} basis functions",
                    ctrl.len(),
                    basis.n_functions()
                ),
            ));
        }
        if ctrl.iter().any(|p| !(p[0].is_finite() && p[1].is_finite())) {
            return Err(Error::NonFinite {
                what: "curve control points".into(),
            });
        }
        let p = basis.degree();
        let poly = (0..basis.n_elements())
            .map(|e| {
                let (first, pieces) = basis.element_polynomials(e);
                let mut c = [[0.0; MAX_DEGREE + 1]; 2];
                for (k, piece) in pieces.iter().enumerate().take(p + 1) {
                    let q = ctrl[basis.index(first, k)];
                    for m in 0..=p {
                        c[0][m] += q[0] * piece[m];
                        c[1][m] += q[1] * piece[m];
                    }
                }
                c
            })
            .collect();
        let corners = basis
            .breaks()
            .iter()
            .filter(|b| b.multiplicity >= p)
            .map(|b| b.at)
            .collect();
        Ok(SplineCurve {
            basis,
            ctrl,
            poly,
            corners,
        })
    }

    /// Least-squares B-spline curve of `degree` through dense samples of a
    /// curve, with control points about `spacing` pixels apart.
    ///
    /// The samples are parametrised by cumulative chord length (for closed
    /// curves the closing chord counts too and the last sample must not repeat
    /// the first). They must be dense compared with `spacing` (at least two
    /// per element); consecutive duplicates are dropped. A tiny first-difference
    /// penalty keeps the system definite where the samples are sparse, without
    /// measurable bias (its weight is 1e-10 of the data's). Closed curves are
    /// re-oriented counterclockwise on screen.
    pub fn fit(points: &[[f64; 2]], closed: bool, degree: usize, spacing: f64) -> Result<Self> {
        SplineCurve::fit_with_corners(points, closed, degree, spacing, &[])
    }

    /// [`SplineCurve::fit`] with a corner at each of the points whose
    /// indices are in `corners`: a knot of multiplicity `degree` (the curve
    /// is `C^0` there and its tangent may break) at that point's chord-length
    /// parameter. Without corners this is [`SplineCurve::fit`]. A corner
    /// at the first point of an open curve or at its last is ignored (the
    /// ends are breaks already); out-of-range indices are errors. A closed
    /// curve with corners starts at its first corner (after the
    /// re-orientation).
    pub fn fit_with_corners(
        points: &[[f64; 2]],
        closed: bool,
        degree: usize,
        spacing: f64,
        corners: &[usize],
    ) -> Result<Self> {
        if let Some(&i) = corners.iter().find(|&&i| i >= points.len()) {
            return Err(Error::invalid(
                "corner",
                format!("point {i} of {}", points.len()),
            ));
        }
        // Every input point's index among the kept points.
        let mut kept_index = Vec::with_capacity(points.len());
        if points
            .iter()
            .any(|p| !(p[0].is_finite() && p[1].is_finite()))
        {
            return Err(Error::NonFinite {
                what: "curve points".into(),
            });
        }
        if !(spacing.is_finite() && spacing > 0.0) {
            return Err(Error::invalid(
                "control point spacing",
                format!("{spacing}"),
            ));
        }
        let mut pts: Vec<[f64; 2]> = Vec::with_capacity(points.len());
        for &p in points {
            if pts.last().is_none_or(|q| dist(*q, p) > 1e-9) {
                pts.push(p);
            }
            kept_index.push(pts.len() - 1);
        }
        if closed && pts.len() > 1 && dist(pts[0], pts[pts.len() - 1]) <= 1e-9 {
            pts.pop();
            let n = pts.len();
            kept_index.iter_mut().for_each(|k| *k %= n);
        }
        let min_points = if closed { 3 } else { 2 };
        if pts.len() < min_points {
            return Err(Error::InvalidCurve {
                reason: format!(
                    "{} distinct points (a {} curve needs at least {min_points})",
                    pts.len(),
                    if closed { "closed" } else { "open" }
                ),
            });
        }
        let mut corner_at: Vec<usize> = corners.iter().map(|&i| kept_index[i]).collect();
        if closed && shoelace(&pts) > 0.0 {
            pts.reverse();
            // Point k is now n - 1 - k; the curve starts at the old last one.
            let n = pts.len();
            corner_at.iter_mut().for_each(|k| *k = n - 1 - *k);
        }
        if closed {
            start_at_first_corner(&mut pts, &mut corner_at);
        }
        let mut params = Vec::with_capacity(pts.len());
        let mut acc = 0.0;
        params.push(0.0);
        for w in pts.windows(2) {
            acc += dist(w[0], w[1]);
            params.push(acc);
        }
        let length = if closed {
            acc + dist(pts[pts.len() - 1], pts[0])
        } else {
            acc
        };
        if length.is_nan() || length <= 1e-6 {
            return Err(Error::InvalidCurve {
                reason: "the curve has zero length".into(),
            });
        }
        let min_el = if closed { degree + 1 } else { 1 };
        let n_el = ((length / spacing).round() as usize).max(min_el);
        let breaks: Vec<crate::spline::Break> = corner_at
            .iter()
            .map(|&k| params[k])
            .filter(|&at| closed || (at > 0.0 && at < length))
            .map(|at| crate::spline::Break {
                at,
                multiplicity: degree,
            })
            .collect::<Vec<_>>();
        let mut breaks = breaks;
        breaks.sort_by(|a, b| a.at.total_cmp(&b.at));
        breaks.dedup_by(|a, b| a.at == b.at);
        let basis = Basis::with_breaks(degree, n_el, length, closed, &breaks)?;
        let n = basis.n_functions();
        // The normal equations, summed over fixed chunks of points in
        // parallel (`solver::chunked`: the same bits on every run).
        let zero = SymBandMatrix::zeros(n, degree, closed)?;
        let (mut m, mut rhs_x, mut rhs_y) = chunked_sum(
            pts.len(),
            |range| {
                let mut m = zero.clone();
                let mut rhs_x = vec![0.0; n];
                let mut rhs_y = vec![0.0; n];
                let mut v = [0.0; MAX_DEGREE + 1];
                for (p, &u) in pts[range.clone()].iter().zip(&params[range]) {
                    let first = basis.eval(u, &mut v);
                    for (a, va) in v[..=degree].iter().enumerate() {
                        let ia = basis.index(first, a);
                        rhs_x[ia] += va * p[0];
                        rhs_y[ia] += va * p[1];
                    }
                    m.add_outer(first, 1.0, &v[..=degree]);
                }
                (m, rhs_x, rhs_y)
            },
            |t, part| {
                t.0.add_matrix(&part.0);
                t.1.iter_mut().zip(&part.1).for_each(|(a, b)| *a += b);
                t.2.iter_mut().zip(&part.2).for_each(|(a, b)| *a += b);
            },
        )
        .ok_or_else(|| Error::InvalidCurve {
            reason: "no points".into(),
        })?;
        let scale = (0..n).map(|i| m.get(i, i)).fold(0.0, f64::max);
        let lambda = 1e-10 * scale.max(1e-300);
        let pairs = if closed { n } else { n - 1 };
        for i in 0..pairs {
            let j = (i + 1) % n;
            if i == j {
                continue;
            }
            m.add(i, i, lambda);
            m.add(j, j, lambda);
            m.add(i, j, -lambda);
        }
        let chol = BandCholesky::factor(&m)?;
        chol.solve_in_place(&mut rhs_x);
        chol.solve_in_place(&mut rhs_y);
        let ctrl = rhs_x.into_iter().zip(rhs_y).map(|(x, y)| [x, y]).collect();
        SplineCurve::new(basis, ctrl)
    }

    /// The basis (degree, elements, parameter length).
    pub fn basis(&self) -> &Basis {
        &self.basis
    }

    /// Control points, pixels.
    pub fn control_points(&self) -> &[[f64; 2]] {
        &self.ctrl
    }

    /// Whether the curve is closed.
    pub fn is_closed(&self) -> bool {
        self.basis.is_closed()
    }

    /// Length of the parameter range, pixels (close to the arc length).
    pub fn param_length(&self) -> f64 {
        self.basis.length()
    }

    /// The point `C(u)`.
    #[inline]
    pub fn point(&self, u: f64) -> [f64; 2] {
        self.derivatives(u)[0]
    }

    /// `C(u)`, `C'(u)` and `C''(u)` (Horner on the element's polynomial).
    #[inline]
    pub fn derivatives(&self, u: f64) -> [[f64; 2]; 3] {
        let (e, t) = self.basis.locate(u);
        self.derivatives_at(e, t)
    }

    /// [`SplineCurve::derivatives`] on element `e` at local coordinate `t`.
    #[inline]
    pub(crate) fn derivatives_at(&self, e: usize, t: f64) -> [[f64; 2]; 3] {
        let p = self.basis.degree();
        let inv_h = 1.0 / self.basis.element_bounds(e).1;
        let mut out = [[0.0; 2]; 3];
        for (axis, c) in self.poly[e].iter().enumerate() {
            let (mut v, mut d1, mut d2) = (c[p], 0.0, 0.0);
            for m in (0..p).rev() {
                d2 = d2 * t + 2.0 * d1;
                d1 = d1 * t + v;
                v = v * t + c[m];
            }
            out[0][axis] = v;
            out[1][axis] = d1 * inv_h;
            out[2][axis] = d2 * inv_h * inv_h;
        }
        out
    }

    /// The [`Frame`] at `u`.
    #[inline]
    pub fn frame(&self, u: f64) -> Frame {
        let [p, d1, d2] = self.derivatives(u);
        frame_from(p, d1, d2)
    }

    /// The largest `|kappa|` (1/pixels) over the curve, sampled at most
    /// `step` apart along the parameter, both ends included (a closed
    /// curve's meet). A peak between samples is missed by up to its
    /// variation over `step`.
    pub fn largest_curvature(&self, step: f64) -> f64 {
        let l = self.param_length();
        let n = (l / step).ceil().max(1.0) as usize;
        (0..=n)
            .map(|i| self.frame(i as f64 * l / n as f64).curvature.abs())
            .fold(0.0, f64::max)
    }

    /// Arc length, pixels (5-point Gauss–Legendre on each element: exact to
    /// rounding for the smooth curves handled here).
    pub fn arc_length(&self) -> f64 {
        self.arc_length_between(0.0, self.param_length())
    }

    /// Arc length between two parameters `u0 <= u1`.
    pub fn arc_length_between(&self, u0: f64, u1: f64) -> f64 {
        let h = self.basis.element_length();
        let mut total = 0.0;
        let mut a = u0;
        while a < u1 {
            // Integrate element by element: the integrand is smooth inside one.
            let next = if self.basis.breaks().is_empty() {
                ((a / h).floor() + 1.0) * h
            } else {
                let (e, _) = self.basis.locate(a);
                let (start, len) = self.basis.element_bounds(e);
                // Parameters past L on a closed curve: the element's copy.
                // (`a - a.rem_euclid(L)` is `floor(a / L) L`, of either sign.)
                start + len + (a - a.rem_euclid(self.param_length()))
            };
            let b = if next > a {
                next.min(u1)
            } else {
                (a + h).min(u1)
            };
            total += gauss_legendre(a, b, |u| {
                let d = self.derivatives(u)[1];
                d[0].hypot(d[1])
            });
            a = b;
        }
        total
    }

    /// Enclosed area of a closed curve, pixels squared (positive), by
    /// Green's theorem with Gauss–Legendre quadrature; `None` for open curves.
    pub fn area(&self) -> Option<f64> {
        if !self.is_closed() {
            return None;
        }
        let mut total = 0.0;
        for e in 0..self.basis.n_elements() {
            let (a, h) = self.basis.element_bounds(e);
            total += gauss_legendre(a, a + h, |u| {
                let [p, d, _] = self.derivatives(u);
                0.5 * (p[0] * d[1] - p[1] * d[0])
            });
        }
        Some(total.abs())
    }

    /// Points at `count` parameters equally spaced over the curve (both ends
    /// included for open curves; `[0, L)` for closed ones).
    pub fn sample_params(&self, count: usize) -> Vec<f64> {
        let l = self.param_length();
        let count = count.max(2);
        if self.is_closed() {
            (0..count).map(|i| l * i as f64 / count as f64).collect()
        } else {
            (0..count)
                .map(|i| l * i as f64 / (count - 1) as f64)
                .collect()
        }
    }

    /// Axis-aligned bounding box of the control polygon (which contains the
    /// curve): `[xmin, ymin, xmax, ymax]`.
    pub fn bounding_box(&self) -> [f64; 4] {
        self.ctrl.iter().fold(
            [
                f64::INFINITY,
                f64::INFINITY,
                f64::NEG_INFINITY,
                f64::NEG_INFINITY,
            ],
            |b, p| {
                [
                    b[0].min(p[0]),
                    b[1].min(p[1]),
                    b[2].max(p[0]),
                    b[3].max(p[1]),
                ]
            },
        )
    }

    /// The serialisable description (degree, knots, control points).
    pub fn to_data(&self) -> SplineCurveData {
        let p = self.basis.degree();
        let mut control_points = self.ctrl.clone();
        let knots = if self.is_closed() {
            control_points.extend_from_slice(&self.ctrl[..p]);
            self.basis.knots()
        } else {
            self.basis.knots()
        };
        SplineCurveData {
            degree: p,
            closed: self.is_closed(),
            knots,
            control_points,
        }
    }
}

/// The [`Frame`] from a point and its first two derivatives.
#[inline]
pub(crate) fn frame_from(p: [f64; 2], d1: [f64; 2], d2: [f64; 2]) -> Frame {
    // sqrt rather than hypot: no overflow risk at pixel scales, and much
    // faster in the band's projection loop.
    let speed = (d1[0] * d1[0] + d1[1] * d1[1]).sqrt();
    let inv = if speed > 0.0 { 1.0 / speed } else { 0.0 };
    let t = [d1[0] * inv, d1[1] * inv];
    let curvature = (d1[0] * d2[1] - d1[1] * d2[0]) * inv * inv * inv;
    Frame {
        point: p,
        tangent: t,
        normal: [-t[1], t[0]],
        curvature,
        speed,
    }
}

#[inline]
pub(crate) fn dist(a: [f64; 2], b: [f64; 2]) -> f64 {
    // Not `hypot`: its guard against overflow costs several times more,
    // and pixel coordinates are nowhere near the range where it matters.
    let (dx, dy) = (a[0] - b[0], a[1] - b[1]);
    (dx * dx + dy * dy).sqrt()
}

/// Twice the signed area of a closed polygon in the (x, y) frame; negative
/// for a polygon that runs counterclockwise on screen (y down).
pub(crate) fn shoelace(pts: &[[f64; 2]]) -> f64 {
    let n = pts.len();
    (0..n)
        .map(|i| {
            let a = pts[i];
            let b = pts[(i + 1) % n];
            a[0] * b[1] - a[1] * b[0]
        })
        .sum()
}

/// Whether `q` lies inside the closed polygon `pts` (crossing number).
pub(crate) fn polygon_contains(pts: &[[f64; 2]], q: [f64; 2]) -> bool {
    let n = pts.len();
    let mut inside = false;
    for i in 0..n {
        let (a, b) = (pts[i], pts[(i + 1) % n]);
        if (a[1] > q[1]) != (b[1] > q[1]) {
            let x = a[0] + (q[1] - a[1]) / (b[1] - a[1]) * (b[0] - a[0]);
            if q[0] < x {
                inside = !inside;
            }
        }
    }
    inside
}

/// 5-point Gauss–Legendre quadrature of `f` on `[a, b]`.
fn gauss_legendre(a: f64, b: f64, f: impl Fn(f64) -> f64) -> f64 {
    const X: [f64; 5] = [
        0.0,
        0.538_469_310_105_683_1,
        -0.538_469_310_105_683_1,
        0.906_179_845_938_664,
        -0.906_179_845_938_664,
    ];
    const W: [f64; 5] = [
        0.568_888_888_888_888_9,
        0.478_628_670_499_366_5,
        0.478_628_670_499_366_5,
        0.236_926_885_056_189_1,
        0.236_926_885_056_189_1,
    ];
    let c = 0.5 * (a + b);
    let r = 0.5 * (b - a);
    X.iter().zip(W).map(|(x, w)| w * f(c + r * x)).sum::<f64>() * r
}

/// A closed polyline `pts` with corners at the point indices `corners`
/// turned to start at the corner of smallest index (unchanged without
/// corners). A displacement basis on the curve has an element boundary at
/// the parameter origin as well as at each corner, so an origin just short
/// of a corner would leave an element of a fraction of a pixel there,
/// inside the corner's clearance: no band pixel on it, a singular system.
fn start_at_first_corner(pts: &mut [[f64; 2]], corners: &mut [usize]) {
    let Some(&first) = corners.iter().min() else {
        return;
    };
    let n = pts.len();
    pts.rotate_left(first);
    for c in corners.iter_mut() {
        *c = (*c + n - first) % n;
    }
}
