//! The blur's anisotropy ([`Anisotropy`]), fitted on the pixel-edge
//! stage's band once its isotropic blur has settled.
//!
//! The band's residual, the gray levels refitted, is a function `F(x)` of
//! the blur's covariance `x = (blur², p, q)` (px²). Around the blur in use
//! it is nearly quadratic: ten evaluations (the point, one step each way
//! along each axis, one step along each pair) give its gradient and
//! Hessian, and a Newton step (the best of it and its halvings) goes
//! towards its minimum, a few times over. Only the directions the
//! curve's normals see are fitted: along a straight edge only the blur
//! across it is measured, and a square's two edge directions leave the
//! anisotropy between them unknown (the Hessian's Schur complement on `(p,
//! q)`, compared with its term on `blur²`, says which directions a curve
//! sees). The new blur is taken when it lowers the residual by
//! [`MIN_EVIDENCE`] noise variances (the residual's own variance, which
//! counts any misfit as noise: conservative) and its anisotropy is at
//! least [`MIN_SHARE`] of the spread's variance. The stage then measures
//! the curve again with it and fits again from there
//! ([`MAX_ANISOTROPY_FITS`]).
//!
//! Edge cases: a blur below the pixel's (`blur² < 10 %` of the spread's
//! variance) leaves nothing to measure; an object a few blurs across (a
//! dot, a small ellipse: `blur_offset::few_blurs_across`) is not fitted,
//! its own elongation giving the same image as an elongated blur; a step
//! that would make the blur negative in some direction is taken to the
//! closest covariance that is not (zero blur in that direction: a motion
//! blur without other blur); `None` whenever the residual cannot be
//! evaluated or does not drop.

use crate::correlation::Correlation;
use crate::solver::DenseCholesky;
use crate::virtual_image::pixel_edge::{curved_edge, spread_variance};
use crate::virtual_image::Anisotropy;

/// The residual must drop by this many noise variances (3 parameters: a
/// chance drop of 25 under pure noise has odds of about 1e-5).
const MIN_EVIDENCE: f64 = 25.0;
/// The anisotropy is taken when its amplitude is at least this share of
/// the spread's variance: a smaller one moves the curvature's shift by less
/// than that share of it, and on noiseless images the residual's rounding
/// reads as evidence for anisotropies of 1e-3 of it.
const MIN_SHARE: f64 = 0.05;
/// A direction of `(p, q)` is fitted when the Schur complement's
/// curvature along it is at least this fraction of the curvature along
/// `blur²` (a curve whose normals turn all around: 1/2).
const MIN_SEEN: f64 = 0.15;
/// Fits of the anisotropy per stage, at most, each after a run that
/// measured the curve with the last one: on a star's lobes the curve and
/// the blur move together (a motion-blurred star took four, each lowering
/// the residual by hundreds of noise variances).
pub(super) const MAX_ANISOTROPY_FITS: usize = 5;
/// Band pixels used at most (a regular subsample).
const ANISOTROPY_PIXELS: usize = 4096;
/// The probe step, as a fraction of the spread's variance (`blur² +
/// 1/12`).
const STEP: f64 = 0.1;
/// Newton steps per fit, at most (the curve stays as it is).
const MAX_NEWTON: usize = 4;
/// Halvings of a Newton step tried.
const BACKTRACKS: usize = 3;
/// The Newton step is at most this many probe steps long.
const MAX_STEPS: f64 = 20.0;

/// The isotropic blur (pixels) and anisotropy that fit the band of `corr`
/// at `lambda` better than `(blur, current)` by [`MIN_EVIDENCE`] noise
/// variances, or `None` (module docs).
pub(super) fn fit_anisotropy(
    corr: &Correlation,
    lambda: &[f64],
    blur: f64,
    current: Anisotropy,
) -> Option<(f64, Anisotropy)> {
    let stride = corr.band().len().div_ceil(ANISOTROPY_PIXELS).max(1);
    let pixels = corr.band().len().div_ceil(stride) as f64;
    let x0 = [blur * blur, current.p, current.q];
    // The blur across the edge follows `x`; the curvature's terms keep the
    // blur along it (and the covariance) in use: the curve was fitted with
    // that shift, and
    // at a fixed curve a change of it would read as a misfit rather than
    // as the better model it may be (the next run refits the curve).
    let band = corr.band();
    let corner = band.corner_terms(blur, current);
    let residual = |x: [f64; 3]| {
        let (mean, shape) = (x[0].max(0.0).sqrt(), Anisotropy { p: x[1], q: x[2] });
        corr.pushed_ssr_by(lambda, stride, |i, r| {
            let n = band.normal[i];
            let (_, along, cross) = current.blurs(blur, n);
            let blurs = (shape.blurs(mean, n).0, along, cross);
            curved_edge(
                r,
                n[0],
                n[1],
                blurs,
                band.curvature[i],
                band.osculating_at(i),
            )
            .0 + corner.as_ref().map_or(0.0, |c| c[i])
        })
        .filter(|f| f.is_finite())
    };
    let f0 = residual(x0)?;
    let noise = f0 / pixels;
    if !worth_fitting(&residual, x0, f0, noise)? {
        return None;
    }
    let (mut x, mut f) = (x0, f0);
    for _ in 0..MAX_NEWTON {
        let Some((next, g)) = newton(&residual, x, f, STEP * spread_variance(x[0].sqrt())) else {
            break;
        };
        let gain = f - g;
        (x, f) = (next, g);
        if gain < noise {
            break;
        }
    }
    let shape = Anisotropy { p: x[1], q: x[2] };
    let matters = shape.amplitude() >= MIN_SHARE * spread_variance(x[0].sqrt());
    ((f0 - f) > MIN_EVIDENCE * noise && matters).then_some((x[0].sqrt(), shape))
}

/// Whether the anisotropy may lower `residual` (`f0` at `x0`) by enough
/// to be worth the Newton steps: the drop that the residual's slope and
/// curvature along `p` and along `q` promise (four evaluations), at least
/// a quarter of [`MIN_EVIDENCE`] noise variances; a residual that is not
/// convex along either is worth them. `None`: the blur is below the
/// probes' reach or the residual cannot be evaluated.
fn worth_fitting(
    residual: &impl Fn([f64; 3]) -> Option<f64>,
    x0: [f64; 3],
    f0: f64,
    noise: f64,
) -> Option<bool> {
    let delta = STEP * spread_variance(x0[0].sqrt());
    if x0[0] < delta {
        return None;
    }
    let mut promise = 0.0;
    for axis in [1, 2] {
        let at = |s: f64| {
            residual(std::array::from_fn(|i| {
                x0[i] + if i == axis { s * delta } else { 0.0 }
            }))
        };
        let (plus, minus) = (at(1.0)?, at(-1.0)?);
        let (slope, curvature) = (0.5 * (plus - minus), plus - 2.0 * f0 + minus);
        if curvature <= 0.0 {
            return Some(true);
        }
        promise += 0.5 * slope * slope / curvature;
    }
    Some(promise > 0.25 * MIN_EVIDENCE * noise)
}

/// One Newton step of `residual` from `x` (where it is `f`), with probes
/// `delta` px² apart: the best of the step and its halvings (down to
/// `2^-BACKTRACKS` of it; the quadratic can overshoot, and a step beyond
/// the blurs' cone is cut back to it), if it lowers the residual.
fn newton(
    residual: &impl Fn([f64; 3]) -> Option<f64>,
    x: [f64; 3],
    f: f64,
    delta: f64,
) -> Option<([f64; 3], f64)> {
    if x[0] < delta {
        return None;
    }
    let at = |u: [f64; 3]| residual(std::array::from_fn(|i| x[i] + delta * u[i]));
    let (gradient, hessian, _) = quadratic(at)?;
    let step = newton_step(&gradient, &hessian)?;
    let mut best: Option<([f64; 3], f64)> = None;
    for halvings in 0..=BACKTRACKS {
        let scale = 0.5f64.powi(halvings as i32);
        let next = feasible(std::array::from_fn(|i| x[i] + delta * scale * step[i]));
        if let Some(g) = residual(next) {
            if g < best.map_or(f, |b| b.1) {
                best = Some((next, g));
            }
        }
    }
    best
}

/// Gradient, Hessian (in probe steps) and value of `f` at the origin, from
/// ten evaluations: the origin, `+-1` along each axis and `+1` along each
/// pair of axes.
fn quadratic(f: impl Fn([f64; 3]) -> Option<f64>) -> Option<([f64; 3], [[f64; 3]; 3], f64)> {
    let f0 = f([0.0; 3])?;
    let unit = |i: usize, s: f64| std::array::from_fn(|k| if k == i { s } else { 0.0 });
    let mut plus = [0.0; 3];
    let mut gradient = [0.0; 3];
    let mut hessian = [[0.0; 3]; 3];
    for i in 0..3 {
        let (fp, fm) = (f(unit(i, 1.0))?, f(unit(i, -1.0))?);
        plus[i] = fp;
        gradient[i] = 0.5 * (fp - fm);
        hessian[i][i] = fp - 2.0 * f0 + fm;
    }
    for i in 0..3 {
        for j in i + 1..3 {
            let both = std::array::from_fn(|k| if k == i || k == j { 1.0 } else { 0.0 });
            let h = f(both)? - plus[i] - plus[j] + f0;
            hessian[i][j] = h;
            hessian[j][i] = h;
        }
    }
    Some((gradient, hessian, f0))
}

/// The Newton step (in probe steps) of the quadratic `g`, `h` restricted to
/// `blur²` and the directions of `(p, q)` the curve sees (`MIN_SEEN`), at
/// most [`MAX_STEPS`] long; `None` when the quadratic is not convex along
/// `blur²` or no direction of `(p, q)` is seen.
fn newton_step(g: &[f64; 3], h: &[[f64; 3]; 3]) -> Option<[f64; 3]> {
    let h00 = h[0][0];
    if h00.is_nan() || h00 <= 0.0 {
        return None;
    }
    // The Schur complement on (p, q): what the curve sees of them once
    // blur² has taken its share.
    let s = |i: usize, j: usize| h[i][j] - h[i][0] * h[0][j] / h00;
    let (a, b, d) = (s(1, 1), s(1, 2), s(2, 2));
    let half_gap = (0.25 * (a - d) * (a - d) + b * b).sqrt();
    let (high, low) = (0.5 * (a + d) + half_gap, 0.5 * (a + d) - half_gap);
    // Unit eigenvectors of the 2 x 2 complement, largest eigenvalue first.
    let eigvec = |lambda: f64| {
        let v = if b.abs() > 1e-300 {
            [b, lambda - a]
        } else if (lambda - a).abs() <= (lambda - d).abs() {
            [1.0, 0.0]
        } else {
            [0.0, 1.0]
        };
        let n = v[0].hypot(v[1]);
        [v[0] / n, v[1] / n]
    };
    let mut basis: Vec<[f64; 3]> = vec![[1.0, 0.0, 0.0]];
    for lambda in [high, low] {
        if lambda >= MIN_SEEN * h00 {
            let v = eigvec(lambda);
            basis.push([0.0, v[0], v[1]]);
        }
    }
    if basis.len() < 2 {
        return None;
    }
    // The reduced system P' H P c = -P' g.
    let k = basis.len();
    let dot = |u: &[f64; 3], v: &[f64; 3]| u.iter().zip(v).map(|(x, y)| x * y).sum::<f64>();
    let hv = |v: &[f64; 3]| -> [f64; 3] { std::array::from_fn(|i| dot(&h[i], v)) };
    let mut mat = vec![0.0; k * k];
    let mut rhs = vec![0.0; k];
    for (i, u) in basis.iter().enumerate() {
        rhs[i] = -dot(u, g);
        for (j, v) in basis.iter().enumerate() {
            mat[i * k + j] = dot(u, &hv(v));
        }
    }
    DenseCholesky::factor(&mat, k)
        .ok()?
        .solve_in_place(&mut rhs);
    let mut step = [0.0; 3];
    for (c, u) in rhs.iter().zip(&basis) {
        for i in 0..3 {
            step[i] += c * u[i];
        }
    }
    let length = dot(&step, &step).sqrt();
    if !length.is_finite() {
        return None;
    }
    let scale = if length > MAX_STEPS {
        MAX_STEPS / length
    } else {
        1.0
    };
    Some(step.map(|s| s * scale))
}

/// `x` in the blurs' cone, the anisotropy's amplitude at most `blur²` (the
/// blur at least zero in every direction): its closest point there.
fn feasible(x: [f64; 3]) -> [f64; 3] {
    let amplitude = x[1].hypot(x[2]);
    if amplitude <= x[0] {
        return x;
    }
    if amplitude <= -x[0] {
        return [0.0; 3];
    }
    let t = 0.5 * (x[0] + amplitude);
    [t, x[1] * t / amplitude, x[2] * t / amplitude]
}

#[cfg(test)]
mod tests {
    use super::{newton_step, quadratic};

    /// A quadratic is recovered exactly and its minimum reached in one
    /// step when it is convex in every direction.
    #[test]
    fn the_step_reaches_a_convex_quadratics_minimum() {
        let h = [[4.0, 1.0, 0.5], [1.0, 3.0, 0.2], [0.5, 0.2, 2.0]];
        let m = [0.7, -0.4, 0.3];
        let f = |u: [f64; 3]| {
            let d: [f64; 3] = std::array::from_fn(|i| u[i] - m[i]);
            let mut s = 1.0;
            for i in 0..3 {
                for j in 0..3 {
                    s += 0.5 * d[i] * h[i][j] * d[j];
                }
            }
            Some(s)
        };
        let (g, hh, _) = quadratic(f).unwrap();
        for i in 0..3 {
            for j in 0..3 {
                assert!((hh[i][j] - h[i][j]).abs() < 1e-9, "{hh:?}");
            }
        }
        let step = newton_step(&g, &hh).unwrap();
        for i in 0..3 {
            assert!((step[i] - m[i]).abs() < 1e-9, "{step:?}");
        }
    }

    /// A straight edge sees one blur: the residual depends on `blur² + p`
    /// alone (a normal along x) and no anisotropy is fitted; a square's two
    /// directions see `p` but not `q`, and the step leaves `q` alone.
    #[test]
    fn only_the_directions_the_curve_sees_are_fitted() {
        let line = |u: [f64; 3]| Some((u[0] + u[1] - 1.0).powi(2));
        let (g, h, _) = quadratic(line).unwrap();
        assert!(newton_step(&g, &h).is_none());
        // Two edge directions, normals along x and y: blur² + p and blur² - p.
        let square = |u: [f64; 3]| Some((u[0] + u[1] - 1.0).powi(2) + (u[0] - u[1] - 0.2).powi(2));
        let (g, h, _) = quadratic(square).unwrap();
        let step = newton_step(&g, &h).unwrap();
        assert!(
            (step[0] - 0.6).abs() < 1e-9 && (step[1] - 0.4).abs() < 1e-9,
            "{step:?}"
        );
        assert_eq!(step[2], 0.0);
    }
}
