//! Plane B-spline curves on general knot vectors: the exchange form of a
//! measured curve.
//!
//! A measured [`SplineCurve`](crate::curve::SplineCurve) lives on a
//! uniform basis whose knots extend `p` elements beyond the curve's ends
//! (open curves) or wrap around (closed ones). [`SplineCurveData`] writes
//! both as an ordinary B-spline curve on the domain `[U_p, U_n] = [0, L]`
//! (closed curves with their first `p` control points repeated at the
//! end); [`BSplineCurve::from_data`] reads that form as it is, so its
//! points at any `u` are the measured curve's.
//!
//! Other programs mostly want other forms, obtained here exactly by knot
//! insertion: [`BSplineCurve::clamped`] (end knots of multiplicity `p + 1`,
//! the curve starts and ends at control points: DXF, IGES, OpenCASCADE),
//! [`BSplineCurve::bezier_segments`] (one Bézier piece per knot span: SVG,
//! PostScript, PDF), and [`BSplineCurve::elevated`] (a higher degree).

use super::basis::{
    basis_funs, check_knots, find_span, greville, interior_knots, multiplicity, MAX_DEGREE,
};
use super::refine::{insert_knot, insert_to_multiplicity};
use crate::curve::SplineCurveData;
use crate::error::{Error, Result};

/// A non-rational B-spline curve in the plane; see the [module
/// documentation](self).
#[derive(Clone, Debug, PartialEq)]
pub struct BSplineCurve {
    degree: usize,
    knots: Vec<f64>,
    points: Vec<[f64; 2]>,
}

impl BSplineCurve {
    /// A curve of `degree` (1 to [`MAX_DEGREE`]) on `knots` with control
    /// points `points` (pixels).
    ///
    /// Errors: [`Error::NonFinite`] for a NaN or infinite coordinate or
    /// knot; [`Error::InvalidCurve`] / [`Error::InvalidParameter`] for an
    /// inconsistent knot vector (see [`check_knots`]).
    pub fn new(degree: usize, knots: Vec<f64>, points: Vec<[f64; 2]>) -> Result<Self> {
        if points
            .iter()
            .any(|p| !(p[0].is_finite() && p[1].is_finite()))
        {
            return Err(Error::NonFinite {
                what: "curve control points".into(),
            });
        }
        check_knots(degree, &knots, points.len())?;
        Ok(BSplineCurve {
            degree,
            knots,
            points,
        })
    }

    /// The curve a result file records (see the module documentation):
    /// same parameter, same points.
    pub fn from_data(data: &SplineCurveData) -> Result<Self> {
        if data.control_points.is_empty() {
            return Err(Error::InvalidCurve {
                reason: "the curve has no control points".into(),
            });
        }
        let curve =
            BSplineCurve::new(data.degree, data.knots.clone(), data.control_points.clone())?;
        if data.closed {
            // The unwrapped periodic form repeats the first p points.
            let (n, p) = (data.control_points.len(), data.degree);
            let wraps = n >= 2 * p
                && (0..p).all(|i| data.control_points[i] == data.control_points[n - p + i]);
            if !wraps {
                return Err(Error::InvalidCurve {
                    reason: format!(
                        "a closed curve must repeat its first {p} control points at the end"
                    ),
                });
            }
        }
        Ok(curve)
    }

    /// Degree `p`.
    pub fn degree(&self) -> usize {
        self.degree
    }

    /// The knot vector (`n + p + 1` values).
    pub fn knots(&self) -> &[f64] {
        &self.knots
    }

    /// The `n` control points, pixels.
    pub fn control_points(&self) -> &[[f64; 2]] {
        &self.points
    }

    /// The parameter domain `[U_p, U_n]`.
    pub fn domain(&self) -> (f64, f64) {
        (self.knots[self.degree], self.knots[self.points.len()])
    }

    /// The point `C(u)`; `u` is clamped to the domain.
    pub fn point(&self, u: f64) -> [f64; 2] {
        let (p, n) = (self.degree, self.points.len());
        let k = find_span(p, &self.knots, n, u);
        let (a, b) = self.domain();
        let v = basis_funs(k, u.clamp(a, b), p, &self.knots);
        let mut out = [0.0; 2];
        for (j, w) in v.iter().enumerate() {
            let q = self.points[k - p + j];
            out[0] += w * q[0];
            out[1] += w * q[1];
        }
        out
    }

    /// Whether both ends have knots of multiplicity `p + 1` (and nothing
    /// outside the domain): the curve starts at the first control point
    /// and ends at the last.
    pub fn is_clamped(&self) -> bool {
        let (a, b) = self.domain();
        let p = self.degree;
        self.knots[..=p].iter().all(|&k| k == a)
            && self.knots[self.knots.len() - p - 1..]
                .iter()
                .all(|&k| k == b)
    }

    /// Insert `u` (inside the domain) `times` times; the geometry is
    /// unchanged. Errors as [`insert_knot`].
    pub fn insert_knot(&mut self, u: f64, times: usize) -> Result<()> {
        for _ in 0..times {
            insert_knot(self.degree, &mut self.knots, &mut self.points, u)?;
        }
        Ok(())
    }

    /// The same curve with clamped ends (see [`Self::is_clamped`]): the
    /// ends of the domain are inserted until they have multiplicity `p`,
    /// then the knots and control points that only act outside the domain
    /// are dropped. Exact up to rounding; the domain is kept.
    pub fn clamped(&self) -> Result<Self> {
        let (a, b) = self.domain();
        let p = self.degree;
        let mut knots = self.knots.clone();
        let mut pts = self.points.clone();
        insert_to_multiplicity(p, &mut knots, &mut pts, a, p)?;
        insert_to_multiplicity(p, &mut knots, &mut pts, b, p)?;
        // Drop what lies beyond b by clamping the reversed curve's start.
        let (knots, pts) = clamp_start(p, knots, pts, a);
        let rev: Vec<f64> = knots.iter().rev().map(|k| -k).collect();
        let (rev, mut pts) = clamp_start(p, rev, pts.into_iter().rev().collect(), -b);
        let knots: Vec<f64> = rev.iter().rev().map(|k| -k).collect();
        pts.reverse();
        BSplineCurve::new(p, knots, pts)
    }

    /// The same curve on the domain `[a, b]` (an affine change of
    /// parameter: the knots are mapped, the control points kept).
    ///
    /// Errors: [`Error::InvalidParameter`] unless `a < b`, both finite.
    pub fn reparametrised(&self, a: f64, b: f64) -> Result<Self> {
        if !(a.is_finite() && b.is_finite() && a < b) {
            return Err(Error::invalid("domain", format!("[{a}, {b}]")));
        }
        let (a0, b0) = self.domain();
        let scale = (b - a) / (b0 - a0);
        let knots = map_knots(&self.knots, (a0, b0), (a, b), |k| a + (k - a0) * scale);
        BSplineCurve::new(self.degree, knots, self.points.clone())
    }

    /// The same curve travelled the other way on the same domain:
    /// `C_rev(a + b - u) = C(u)`.
    pub fn reversed(&self) -> Self {
        let (a, b) = self.domain();
        let mut knots = map_knots(&self.knots, (a, b), (b, a), |k| (a + b) - k);
        knots.reverse();
        BSplineCurve {
            degree: self.degree,
            knots,
            points: self.points.iter().rev().copied().collect(),
        }
    }

    /// Move the interior knots that lie within `eps` of one of `targets`
    /// (and differ from it) onto it. Used before merging two knot vectors:
    /// knots that are equal but for rounding (`0.49999999999999994` and
    /// `0.5`) would otherwise make an element of zero width. Moving a knot
    /// by `eps` moves the curve by about `eps` times its control points'
    /// spread over the span: negligible for `eps` near the rounding of the
    /// knots themselves.
    pub fn snap_knots(&mut self, targets: &[f64], eps: f64) -> Result<()> {
        let (a, b) = self.domain();
        let mut knots = self.knots.clone();
        for k in knots.iter_mut().filter(|k| **k > a && **k < b) {
            if let Some(&t) = targets
                .iter()
                .find(|&&t| t > a && t < b && t != *k && (t - *k).abs() <= eps)
            {
                *k = t;
            }
        }
        check_knots(self.degree, &knots, self.points.len())?;
        self.knots = knots;
        Ok(())
    }

    /// The Bézier pieces of the curve, one per non-empty knot span of the
    /// domain, in order: each has `p + 1` control points, the last point of
    /// one is the first of the next. Obtained by clamping and raising every
    /// interior knot to multiplicity `p` (exact up to rounding).
    pub fn bezier_segments(&self) -> Result<Vec<Vec<[f64; 2]>>> {
        let mut c = self.clamped()?;
        let (a, b) = c.domain();
        let p = c.degree;
        for (u, _) in interior_knots(&c.knots, a, b) {
            insert_to_multiplicity(p, &mut c.knots, &mut c.points, u, p)?;
        }
        // Now n = spans * p + 1 and piece s uses points s p ..= s p + p.
        let spans = (c.points.len() - 1) / p;
        Ok((0..spans)
            .map(|s| c.points[s * p..=s * p + p].to_vec())
            .collect())
    }

    /// The same curve as a B-spline of degree `degree >= p` (clamped; every
    /// distinct knot's multiplicity raised by `degree - p`, so the
    /// continuity is kept). The new control points solve the collocation
    /// problem at the Greville abscissae of the new space, which contains
    /// the curve: exact up to rounding (about 1e-13 of the coordinates).
    ///
    /// Errors: [`Error::InvalidParameter`] for `degree < p` (a degree
    /// cannot be lowered exactly) or above [`MAX_DEGREE`].
    pub fn elevated(&self, degree: usize) -> Result<Self> {
        let p = self.degree;
        if degree < p || degree > MAX_DEGREE {
            return Err(Error::invalid(
                "degree",
                format!("cannot raise degree {p} to {degree} (must be {p} to {MAX_DEGREE})"),
            ));
        }
        let c = self.clamped()?;
        if degree == p {
            return Ok(c);
        }
        let t = degree - p;
        let (a, b) = c.domain();
        let mut knots = vec![a; degree + 1];
        for (u, m) in interior_knots(&c.knots, a, b) {
            knots.extend(std::iter::repeat_n(u, m + t));
        }
        knots.extend(std::iter::repeat_n(b, degree + 1));
        let n = knots.len() - degree - 1;
        let params = greville(degree, &knots, n);
        // Banded collocation matrix: row i holds N_j(xi_i) for the p + 1
        // functions of xi_i's span; stored densely by row offset.
        let mut rows: Vec<(usize, Vec<f64>)> = Vec::with_capacity(n);
        let mut rhs: Vec<[f64; 2]> = Vec::with_capacity(n);
        for &x in &params {
            let k = find_span(degree, &knots, n, x);
            rows.push((k - degree, basis_funs(k, x, degree, &knots)));
            rhs.push(c.point(x));
        }
        let points = solve_banded(n, &rows, rhs)?;
        BSplineCurve::new(degree, knots, points)
    }
}

/// Map knots by the monotone `f`, sending the domain `from = (a0, b0)` to
/// `to` exactly (ends swapped for a reversal: `to.0 > to.1`) and keeping
/// every knot on its side of the ends whatever the rounding.
fn map_knots(knots: &[f64], from: (f64, f64), to: (f64, f64), f: impl Fn(f64) -> f64) -> Vec<f64> {
    let (lo, hi) = (to.0.min(to.1), to.0.max(to.1));
    knots
        .iter()
        .map(|&k| {
            if k == from.0 {
                to.0
            } else if k == from.1 {
                to.1
            } else if k > from.0 && k < from.1 {
                f(k).clamp(lo, hi)
            } else if (k < from.0) == (to.0 < to.1) {
                f(k).min(lo)
            } else {
                f(k).max(hi)
            }
        })
        .collect()
}

/// Drop the knots and control points acting only before `a`, which has
/// multiplicity `m >= p` in `knots`: the first function active on
/// `[a, ...)` has index `first + m - p - 1` (`first` the index of the first
/// knot equal to `a`), and on `[a, ...)` it does not depend on the knots
/// before `a`, which can all be set to `a`.
fn clamp_start(p: usize, knots: Vec<f64>, pts: Vec<[f64; 2]>, a: f64) -> (Vec<f64>, Vec<[f64; 2]>) {
    let first = knots.iter().position(|&k| k == a).unwrap_or(0);
    let m = multiplicity(&knots, a);
    let i0 = (first + m).saturating_sub(p + 1);
    let mut new_knots = vec![a; p + 1];
    new_knots.extend_from_slice(&knots[(first + m).min(knots.len())..]);
    (new_knots, pts[i0.min(pts.len())..].to_vec())
}

/// Solve the square banded system `A X = rhs` whose row `i` is `rows[i] =
/// (j0, values)` (entries at columns `j0 ..`), by Gaussian elimination
/// without pivoting: B-spline collocation matrices at Greville abscissae
/// are totally positive, for which this is stable (de Boor & Pinkus, 1977).
fn solve_banded(
    n: usize,
    rows: &[(usize, Vec<f64>)],
    mut rhs: Vec<[f64; 2]>,
) -> Result<Vec<[f64; 2]>> {
    // Dense band storage: row i covers columns i - w ..= i + w.
    let w = rows.iter().map(|(_, v)| v.len()).max().unwrap_or(1);
    let width = 2 * w + 1;
    let mut band = vec![0.0; n * width];
    let at = |i: usize, j: usize| i * width + (j + w - i);
    for (i, (j0, vals)) in rows.iter().enumerate() {
        for (d, &v) in vals.iter().enumerate() {
            let j = j0 + d;
            if j + w < i || j > i + w || j >= n {
                return Err(Error::InvalidCurve {
                    reason: "degree elevation: collocation matrix outside its band".into(),
                });
            }
            band[at(i, j)] = v;
        }
    }
    for k in 0..n {
        let pivot = band[at(k, k)];
        if pivot.is_nan() || pivot.abs() <= 1e-300 {
            return Err(Error::NotPositiveDefinite { index: k });
        }
        for i in k + 1..(k + w + 1).min(n) {
            let f = band[at(i, k)] / pivot;
            if f == 0.0 {
                continue;
            }
            for j in k..(k + w + 1).min(n) {
                band[at(i, j)] -= f * band[at(k, j)];
            }
            let rk = rhs[k];
            rhs[i] = [rhs[i][0] - f * rk[0], rhs[i][1] - f * rk[1]];
        }
    }
    for k in (0..n).rev() {
        let mut s = rhs[k];
        for j in k + 1..(k + w + 1).min(n) {
            let b = band[at(k, j)];
            s = [s[0] - b * rhs[j][0], s[1] - b * rhs[j][1]];
        }
        let pivot = band[at(k, k)];
        rhs[k] = [s[0] / pivot, s[1] / pivot];
    }
    Ok(rhs)
}
