//! Small weighted nonlinear least squares (Levenberg–Marquardt) and the
//! covariance of its solution, shared by the circle and ellipse fits.
//!
//! The problems here have at most five unknowns and a few thousand
//! residuals: the normal matrix `J^T W J` is formed explicitly, scaled to a
//! unit diagonal (so that centres, radii and angles of very different sizes
//! are treated alike) and solved by a dense Cholesky factorisation.

use crate::error::{Error, Result};
use crate::solver::lm::{self, End, LmParams, Problem, Trial};
use crate::solver::DenseCholesky;

/// Largest number of Levenberg–Marquardt iterations.
const MAX_ITERATIONS: usize = 200;
/// The iteration stops when no unknown moves by more than this fraction of
/// `1 + |value|` (pixels or radians).
const STEP_TOLERANCE: f64 = 1e-13;
/// A damping this large means no step lowers the cost any more: the
/// current point is a minimum to rounding.
const MAX_DAMPING: f64 = 1e16;
/// The iteration also stops when no unknown moves by more than this
/// fraction of its standard deviation (bounded below by `s / sqrt(A_ii)`,
/// `s^2` the cost per degree of freedom and `A` the normal matrix: in the
/// Jacobi-scaled unknowns, a step under this fraction of `s`). Steps that
/// small change nothing the deviations can tell apart, and near rounding
/// most of them would be rejected one after another.
const NEGLIGIBLE_STEP: f64 = 1e-6;

/// Per-point weights from per-point standard deviations: `1 / sigma^2` when
/// every value is finite and positive, `None` (unweighted) otherwise.
///
/// Errors: [`Error::InvalidParameter`] when the lengths differ.
pub(crate) fn weights(n: usize, sigma: Option<&[f64]>) -> Result<Option<Vec<f64>>> {
    let Some(sigma) = sigma else {
        return Ok(None);
    };
    if sigma.len() != n {
        return Err(Error::invalid(
            "sigma",
            format!("{} values for {n} points", sigma.len()),
        ));
    }
    if sigma.iter().all(|s| s.is_finite() && *s > 0.0) {
        Ok(Some(sigma.iter().map(|s| 1.0 / (s * s)).collect()))
    } else {
        Ok(None)
    }
}

/// Check that there are at least `min` points, all finite.
pub(crate) fn check_points(points: &[[f64; 2]], min: usize, what: &str) -> Result<()> {
    if points
        .iter()
        .any(|p| !(p[0].is_finite() && p[1].is_finite()))
    {
        return Err(Error::NonFinite {
            what: format!("the points of the {what} fit"),
        });
    }
    if points.len() < min {
        return Err(Error::InvalidCurve {
            reason: format!("{} points: a {what} fit needs at least {min}", points.len()),
        });
    }
    Ok(())
}

/// The residuals `r` (length `n`) and Jacobian `jac` (`n x k`, row-major) of
/// a model at `params`; returns `false` when `params` is outside the model's
/// domain (a negative radius).
pub(crate) trait Model {
    /// Evaluate; see the trait documentation.
    fn eval(&self, params: &[f64], r: &mut [f64], jac: &mut [f64]) -> bool;
}

/// The converged least-squares solution.
pub(crate) struct Solution {
    /// The unknowns.
    pub params: Vec<f64>,
    /// `J^T W J` at the solution, `k x k` row-major.
    pub normal: Vec<f64>,
    /// Residuals at the solution (unweighted).
    pub residuals: Vec<f64>,
    /// `sum w r^2` at the solution.
    pub cost: f64,
}

/// The damping schedule of these fits: a heavier start than the shape
/// models' (the unknowns are scaled to a unit diagonal, so the damping is
/// relative to 1), lighter and heavier dampings allowed (`1e-15` to `1e16`
/// included, hence the float just above `1e16`), and a small step that
/// would raise the cost ends the fit instead of being taken.
const DAMPING: LmParams = LmParams {
    start_damping: 1e-3,
    grow: 10.0,
    shrink: 0.1,
    min_damping: 1e-15,
    max_damping: f64::from_bits(MAX_DAMPING.to_bits() + 1),
    max_iterations: MAX_ITERATIONS,
    take_small_steps: false,
};

/// The residuals, Jacobian and normal equations at one point.
struct Eval {
    /// Residuals (unweighted); NaN cost when outside the model's domain.
    r: Vec<f64>,
    /// `sum w r^2`.
    cost: f64,
    /// `J^T W J`, `k x k` row-major.
    a: Vec<f64>,
    /// `J^T W r`.
    g: Vec<f64>,
}

/// A model, its weights and its size, as a Levenberg–Marquardt problem.
struct Fit<'a, M> {
    model: &'a M,
    n: usize,
    k: usize,
    w: Option<&'a [f64]>,
}

/// Why [`Fit`] stops the iteration: the normal matrix has no positive
/// diagonal entry.
struct Undetermined;

impl<M: Model> Fit<'_, M> {
    /// The evaluation at `params`; `None` outside the model's domain.
    fn evaluate(&self, params: &[f64]) -> Option<Eval> {
        let mut r = vec![0.0; self.n];
        let mut jac = vec![0.0; self.n * self.k];
        if !self.model.eval(params, &mut r, &mut jac) {
            return None;
        }
        let cost = weighted_cost(&r, self.w);
        let (a, g) = normal_equations(&r, &jac, self.w, self.k);
        Some(Eval { r, cost, a, g })
    }

    /// The largest diagonal entry of the normal matrix.
    fn max_diag(&self, eval: &Eval) -> f64 {
        let k = self.k;
        (0..k).map(|i| eval.a[i * k + i]).fold(0.0, f64::max)
    }
}

impl<M: Model> Problem for Fit<'_, M> {
    type Point = Vec<f64>;
    type Eval = Eval;
    type Stop = Undetermined;

    fn cost(&self, eval: &Eval) -> f64 {
        eval.cost
    }

    fn before_iteration(&self, _p: &Vec<f64>, eval: &Eval) -> Option<Undetermined> {
        let max_diag = self.max_diag(eval);
        (max_diag <= 0.0 || !max_diag.is_finite()).then_some(Undetermined)
    }

    fn trial(&self, p: &Vec<f64>, cur: &Eval, lambda: f64) -> Trial<Vec<f64>, Eval, Undetermined> {
        let (k, n) = (self.k, self.n);
        let (a, g) = (&cur.a, &cur.g);
        // Jacobi scaling: unit diagonal; a column that vanishes (the angle of
        // a circle-like ellipse) keeps a tiny scale instead of dividing by 0.
        let max_diag = self.max_diag(cur);
        let d: Vec<f64> = (0..k)
            .map(|i| a[i * k + i].max(1e-30 * max_diag).sqrt())
            .collect();
        let mut m = vec![0.0; k * k];
        for i in 0..k {
            for j in 0..k {
                m[i * k + j] = a[i * k + j] / (d[i] * d[j]);
            }
            m[i * k + i] += lambda;
        }
        let mut step: Vec<f64> = (0..k).map(|i| -g[i] / d[i]).collect();
        match DenseCholesky::factor(&m, k) {
            Ok(chol) => chol.solve_in_place(&mut step),
            Err(_) => return Trial::Retry,
        }
        let trial: Vec<f64> = p
            .iter()
            .zip(&step)
            .zip(&d)
            .map(|((v, s), di)| v + s / di)
            .collect();
        let negligible = NEGLIGIBLE_STEP * (cur.cost / n.saturating_sub(k).max(1) as f64).sqrt();
        let small = step.iter().all(|s| s.abs() <= negligible)
            || p.iter()
                .zip(&trial)
                .all(|(a, b)| (a - b).abs() <= STEP_TOLERANCE * (1.0 + a.abs()));
        // Outside the model's domain: a NaN cost, never accepted.
        let eval = self.evaluate(&trial).unwrap_or(Eval {
            r: Vec::new(),
            cost: f64::NAN,
            a: Vec::new(),
            g: Vec::new(),
        });
        Trial::Step {
            point: trial,
            eval,
            small,
        }
    }
}

/// Minimise `sum w_i r_i(p)^2` from `start` by Levenberg–Marquardt
/// ([`crate::solver::lm`] with [`DAMPING`]).
///
/// Errors: [`Error::InvalidCurve`] when the start is outside the model's
/// domain or gives non-finite residuals, or when the points do not
/// determine the unknowns.
pub(crate) fn minimise(
    model: &impl Model,
    start: Vec<f64>,
    n: usize,
    w: Option<&[f64]>,
    what: &str,
) -> Result<Solution> {
    let fit = Fit {
        model,
        n,
        k: start.len(),
        w,
    };
    let degenerate = |why: &str| Error::InvalidCurve {
        reason: format!("the {what} fit failed: {why}"),
    };
    let Some(eval) = fit.evaluate(&start) else {
        return Err(degenerate("no valid starting point"));
    };
    if !eval.cost.is_finite() {
        return Err(degenerate("non-finite residuals"));
    }
    let end = lm::minimise(&fit, start, eval, &DAMPING);
    if let End::Stopped(Undetermined) = end.end {
        return Err(degenerate("the points do not determine the unknowns"));
    }
    Ok(Solution {
        params: end.point,
        normal: end.eval.a,
        residuals: end.eval.r,
        cost: end.eval.cost,
    })
}

/// `sum w r^2`.
fn weighted_cost(r: &[f64], w: Option<&[f64]>) -> f64 {
    match w {
        Some(w) => r.iter().zip(w).map(|(r, w)| w * r * r).sum(),
        None => r.iter().map(|r| r * r).sum(),
    }
}

/// `J^T W J` and `J^T W r`.
fn normal_equations(r: &[f64], jac: &[f64], w: Option<&[f64]>, k: usize) -> (Vec<f64>, Vec<f64>) {
    let mut a = vec![0.0; k * k];
    let mut g = vec![0.0; k];
    for (i, ri) in r.iter().enumerate() {
        let wi = w.map_or(1.0, |w| w[i]);
        let row = &jac[i * k..(i + 1) * k];
        for a_ in 0..k {
            g[a_] += wi * row[a_] * ri;
            for b in 0..=a_ {
                a[a_ * k + b] += wi * row[a_] * row[b];
            }
        }
    }
    for a_ in 0..k {
        for b in 0..a_ {
            a[b * k + a_] = a[a_ * k + b];
        }
    }
    (a, g)
}

/// Standard deviations of the unknowns: `sqrt(diag(s^2 (J^T W J)^-1 N / n_eff))`.
///
/// `s^2` is the reduced chi-square `cost / dof`. The points are taken to
/// carry `n_eff = independent` (at most `n`) independent pieces of
/// information, spread evenly: the residuals then have `dof = n (n_eff - k)
/// / n_eff` degrees of freedom and the naive covariance (which counts `n`
/// independent points) is `n / n_eff` times too small (see the module
/// documentation of [`crate::derived`]). The unknowns listed in `drop` are
/// left out of the inversion (their deviation is then NaN) when `force` is
/// set or the matrix is singular with them: the angle of an ellipse that is
/// a circle. All NaN when `dof <= 0` or the matrix is singular.
pub(crate) fn deviations(
    sol: &Solution,
    independent: Option<f64>,
    drop: &[usize],
    force: bool,
) -> Vec<f64> {
    let k = sol.params.len();
    let n = sol.residuals.len() as f64;
    let n_eff = independent.map_or(n, |v| v.min(n));
    let nan = vec![f64::NAN; k];
    if n_eff.is_nan() || n_eff <= k as f64 {
        return nan;
    }
    let dof = n * (n_eff - k as f64) / n_eff;
    let scale = sol.cost / dof * (n / n_eff);
    let keep_all: Vec<usize> = (0..k).collect();
    let keep_some: Vec<usize> = (0..k).filter(|i| !drop.contains(i)).collect();
    for keep in [&keep_all, &keep_some] {
        if keep.is_empty() || (force && keep.len() == k && !drop.is_empty()) {
            continue;
        }
        if let Some(diag) = inverse_diagonal(&sol.normal, k, keep) {
            let mut out = nan.clone();
            for (&i, v) in keep.iter().zip(diag) {
                out[i] = (scale * v).max(0.0).sqrt();
            }
            return out;
        }
    }
    nan
}

/// Diagonal of the inverse of the sub-matrix of `a` (`k x k`) on the rows and
/// columns `keep`, computed with unit-diagonal scaling; `None` if singular.
fn inverse_diagonal(a: &[f64], k: usize, keep: &[usize]) -> Option<Vec<f64>> {
    let m = keep.len();
    let d: Vec<f64> = keep.iter().map(|&i| a[i * k + i].sqrt()).collect();
    if d.iter().any(|v| !(v.is_finite() && *v > 0.0)) {
        return None;
    }
    let mut sub = vec![0.0; m * m];
    for (x, &i) in keep.iter().enumerate() {
        for (y, &j) in keep.iter().enumerate() {
            sub[x * m + y] = a[i * k + j] / (d[x] * d[y]);
        }
    }
    let inv = DenseCholesky::factor(&sub, m).ok()?.inverse();
    Some((0..m).map(|x| inv[x * m + x] / (d[x] * d[x])).collect())
}
