//! Best-fit circle: geometric least squares (orthogonal distances) started
//! from the algebraic (Kåsa) fit.

use super::lsq::{self, Model};
use crate::error::{Error, Result};
use serde::{Deserialize, Serialize};

/// A circle fitted to points, with the standard deviations of its
/// parameters. All in pixels.
#[derive(Clone, Copy, Debug, PartialEq, Serialize, Deserialize)]
pub struct CircleFit {
    /// Centre, x (column), px.
    pub cx: f64,
    /// Centre, y (row), px.
    pub cy: f64,
    /// Radius, px (`> 0`).
    pub r: f64,
    /// Standard deviation of `cx`, px (NaN when it cannot be estimated: no
    /// more points, or independent points, than unknowns).
    pub sigma_cx: f64,
    /// Standard deviation of `cy`, px.
    pub sigma_cy: f64,
    /// Standard deviation of `r`, px.
    pub sigma_r: f64,
    /// RMS of the points' orthogonal distances to the circle, px
    /// (unweighted): how far the shape is from a circle.
    pub rms: f64,
}

/// The circle that minimises the (weighted) sum of squared orthogonal
/// distances `(|p_i - c| - r)^2 / sigma_i^2` to `points` (pixels).
///
/// `sigma` gives each point's standard deviation (px): used as weights when
/// every value is finite and positive, ignored (unweighted fit) otherwise.
/// The points are taken as independent; for the correlated samples of a
/// measured curve use [`fit_circle_with`]. The parameters' deviations are
/// `sqrt(diag(s^2 (J^T W J)^-1))` with `s^2` the reduced chi-square: they
/// reflect the scatter of the points about the circle.
///
/// Errors: [`Error::NonFinite`] for a NaN or infinite coordinate;
/// [`Error::InvalidCurve`] for fewer than 3 points or points that determine
/// no circle (all collinear or coincident); [`Error::InvalidParameter`] when
/// `sigma` and `points` differ in length.
pub fn fit_circle(points: &[[f64; 2]], sigma: Option<&[f64]>) -> Result<CircleFit> {
    fit_circle_with(points, sigma, None)
}

/// [`fit_circle`] for points that carry only `independent` independent
/// pieces of information (e.g. the samples of a measured curve, which follow
/// a B-spline displacement with that many unknowns): the covariance is
/// scaled up by `points.len() / independent` and the residuals' degrees of
/// freedom scaled down accordingly (see [`crate::derived`]). `None` is
/// [`fit_circle`].
pub fn fit_circle_with(
    points: &[[f64; 2]],
    sigma: Option<&[f64]>,
    independent: Option<f64>,
) -> Result<CircleFit> {
    lsq::check_points(points, 3, "circle")?;
    let w = lsq::weights(points.len(), sigma)?;
    let start = kasa(points)?;
    let sol = lsq::minimise(
        &CircleModel { points },
        start.to_vec(),
        points.len(),
        w.as_deref(),
        "circle",
    )?;
    let [cx, cy, r] = [sol.params[0], sol.params[1], sol.params[2]];
    if !(r.is_finite() && r > 0.0 && cx.is_finite() && cy.is_finite()) {
        return Err(Error::InvalidCurve {
            reason: "the circle fit diverged (the points determine no circle)".into(),
        });
    }
    let dev = lsq::deviations(&sol, independent, &[], false);
    Ok(CircleFit {
        cx,
        cy,
        r,
        sigma_cx: dev[0],
        sigma_cy: dev[1],
        sigma_r: dev[2],
        rms: rms(&sol.residuals),
    })
}

/// Unweighted RMS.
pub(crate) fn rms(r: &[f64]) -> f64 {
    (r.iter().map(|v| v * v).sum::<f64>() / r.len().max(1) as f64).sqrt()
}

/// Centroid and RMS distance to it of `points`, and whether they span two
/// dimensions (the smaller principal spread is not negligible).
pub(crate) fn normalisation(points: &[[f64; 2]]) -> ([f64; 2], f64, bool) {
    let n = points.len() as f64;
    let m = points
        .iter()
        .fold([0.0, 0.0], |a, p| [a[0] + p[0] / n, a[1] + p[1] / n]);
    let (mut sxx, mut sxy, mut syy) = (0.0, 0.0, 0.0);
    for p in points {
        let (x, y) = (p[0] - m[0], p[1] - m[1]);
        sxx += x * x / n;
        sxy += x * y / n;
        syy += y * y / n;
    }
    let tr = sxx + syy;
    let det = sxx * syy - sxy * sxy;
    // Smaller eigenvalue over the trace, computed without cancellation.
    let disc = ((sxx - syy).powi(2) + 4.0 * sxy * sxy).sqrt();
    let big = 0.5 * (tr + disc);
    let small = if big > 0.0 { det / big } else { 0.0 };
    let planar = tr > 0.0 && small > 1e-12 * tr;
    (m, tr.sqrt(), planar)
}

/// Kåsa's algebraic fit: least squares on `x^2 + y^2 + D x + E y + F = 0`,
/// on centred and scaled coordinates.
fn kasa(points: &[[f64; 2]]) -> Result<[f64; 3]> {
    let (m, scale, planar) = normalisation(points);
    if !planar {
        return Err(Error::InvalidCurve {
            reason: "the points are collinear (or coincident): no circle fits them".into(),
        });
    }
    let mut a = [0.0; 9];
    let mut b = [0.0; 3];
    for p in points {
        let x = (p[0] - m[0]) / scale;
        let y = (p[1] - m[1]) / scale;
        let row = [x, y, 1.0];
        let rhs = -(x * x + y * y);
        for i in 0..3 {
            b[i] += row[i] * rhs;
            for j in 0..3 {
                a[i * 3 + j] += row[i] * row[j];
            }
        }
    }
    let chol = crate::solver::DenseCholesky::factor(&a, 3).map_err(|_| Error::InvalidCurve {
        reason: "the points determine no circle".into(),
    })?;
    chol.solve_in_place(&mut b);
    let (cx, cy) = (-0.5 * b[0], -0.5 * b[1]);
    let r2 = cx * cx + cy * cy - b[2];
    if !(r2 > 0.0 && r2.is_finite()) {
        return Err(Error::InvalidCurve {
            reason: "the points determine no circle".into(),
        });
    }
    Ok([m[0] + scale * cx, m[1] + scale * cy, scale * r2.sqrt()])
}

/// Orthogonal distances `|p - c| - r` (positive outside) and their
/// derivatives with respect to `(cx, cy, r)`.
struct CircleModel<'a> {
    points: &'a [[f64; 2]],
}

impl Model for CircleModel<'_> {
    fn eval(&self, p: &[f64], r: &mut [f64], jac: &mut [f64]) -> bool {
        let (cx, cy, rad) = (p[0], p[1], p[2]);
        if rad.is_nan() || rad <= 0.0 {
            return false;
        }
        for (i, q) in self.points.iter().enumerate() {
            let (dx, dy) = (q[0] - cx, q[1] - cy);
            let rho = dx.hypot(dy);
            r[i] = rho - rad;
            let (ux, uy) = if rho > 0.0 {
                (dx / rho, dy / rho)
            } else {
                (0.0, 0.0)
            };
            jac[3 * i] = -ux;
            jac[3 * i + 1] = -uy;
            jac[3 * i + 2] = -1.0;
        }
        true
    }
}
