//! The exact level of a blurred ellipse, for the ellipse model's small
//! ellipses (oblique dots of a circle grid, holes seen at an angle).
//!
//! The curved edge (`pixel_edge::curved_edge`) expands the blurred edge in
//! `q = s kappa`, and the blurred osculating circle (`osculating.rs`)
//! holds where the curvature is steady over the blur; at the ends of a
//! small ellipse's major axis neither does (radius of curvature `b^2 / a`:
//! 2.2 px for semi-axes 6 and 3.6 px), and its axes came out too long by
//! many times their sigma (docs/benchmarks.md). The level itself is one
//! smooth integral: in the ellipse's frame, a point `(u0, w0)` under an
//! isotropic Gaussian of variance `v` (`s^2`) sees the ellipse with the
//! probability
//!
//! ```text
//! int_{-a}^{a} phi_s(u - u0) [Phi((h(u) - w0) / s) - Phi((-h(u) - w0) / s)] du,
//! h(u) = b sqrt(1 - u^2 / a^2),
//! ```
//!
//! and with `u = a sin t` the integrand `phi_s(a sin t - u0) [...] a cos t`
//! is smooth in `t`. It is summed by Gauss–Legendre quadrature over the
//! `t` where `phi_s` reaches ([`REACH`] deviations).
//!
//! Edge cases: a point farther than the reach from the ellipse along `u`
//! sees 0; the pixel's own spread is taken as Gaussian (its variance
//! `1/12` in `v`), as the osculating circle's table does.

use super::pixel_edge::normal_cdf_pdf;
use std::f64::consts::PI;
use std::sync::OnceLock;

/// Deviations of the blur along `u` beyond which the Gaussian's weight
/// is left out (`phi` is below 1e-14 of its peak there).
const REACH: f64 = 8.0;
/// Nodes of the quadrature over the reached `t`.
const NODES: usize = 48;

/// The Gauss–Legendre rule of [`NODES`] nodes on `[-1, 1]`, made once.
fn rule() -> &'static [(f64, f64)] {
    static RULE: OnceLock<Vec<(f64, f64)>> = OnceLock::new();
    RULE.get_or_init(|| super::osculating::gauss_legendre(NODES))
}

/// `Phi(x1) - Phi(x2)` for `x1 >= x2`, without the cancellation of two
/// values near 1.
fn between(x1: f64, x2: f64) -> f64 {
    if x2 > 0.0 {
        normal_cdf_pdf(-x2).0 - normal_cdf_pdf(-x1).0
    } else {
        normal_cdf_pdf(x1).0 - normal_cdf_pdf(x2).0
    }
}

/// The level (0 to 1) that the point `(u0, w0)` of the ellipse's frame
/// (pixels; `u` along the semi-axis `a`, `w` along `b`) sees of the
/// ellipse of semi-axes `(a, b)` (pixels, positive) under an isotropic
/// Gaussian blur of variance `variance` (px^2, positive): the probability
/// that the blurred point falls inside (module docs); and its derivatives
/// in `(u0, w0, a, b)`, from the same sum (the reach's ends, where the
/// Gaussian is negligible, held).
pub(crate) fn blurred_level_gradient(
    u0: f64,
    w0: f64,
    (a, b): (f64, f64),
    variance: f64,
) -> (f64, [f64; 4]) {
    let s = variance.sqrt();
    let reach = REACH * s;
    let lo = ((u0 - reach) / a).clamp(-1.0, 1.0).asin();
    let hi = ((u0 + reach) / a).clamp(-1.0, 1.0).asin();
    if hi <= lo {
        return (0.0, [0.0; 4]);
    }
    let (mid, half) = (0.5 * (hi + lo), 0.5 * (hi - lo));
    let norm = 1.0 / (s * (2.0 * PI).sqrt());
    let (mut level, mut grad) = (0.0, [0.0; 4]);
    for &(x, weight) in rule() {
        let (st, ct) = (mid + half * x).sin_cos();
        let du = (a * st - u0) / s;
        // The Gaussian along `u` and its derivative in `a sin t`.
        let gauss = norm * (-0.5 * du * du).exp();
        let dgauss = -gauss * du / s;
        let h = b * ct;
        let (x1, x2) = ((h - w0) / s, (-h - w0) / s);
        let inside = between(x1, x2);
        let (p1, p2) = (normal_cdf_pdf(x1).1, normal_cdf_pdf(x2).1);
        let w = weight * a * ct;
        level += w * gauss * inside;
        grad[0] -= w * dgauss * inside;
        grad[1] += w * gauss * (p2 - p1) / s;
        // `a` in the Gaussian's argument and in the Jacobian `a cos t`.
        grad[2] += weight * ct * (dgauss * a * st + gauss) * inside;
        grad[3] += w * gauss * (p1 + p2) * ct / s;
    }
    ((level * half).clamp(0.0, 1.0), grad.map(|g| g * half))
}

#[cfg(test)]
mod tests {
    use super::*;

    fn blurred_level(u0: f64, w0: f64, axes: (f64, f64), v: f64) -> f64 {
        blurred_level_gradient(u0, w0, axes, v).0
    }

    /// The same level by a different route: the Gaussian summed over the
    /// ellipse in polar coordinates about its centre (Simpson's rule in
    /// both, the radius to the boundary exact at each angle).
    fn polar(u0: f64, w0: f64, (a, b): (f64, f64), v: f64) -> f64 {
        let (n_theta, n_rho) = (2000, 400);
        let simpson = |k: usize, n: usize| match k {
            0 => 1.0,
            k if k == n => 1.0,
            k if k % 2 == 1 => 4.0,
            _ => 2.0,
        };
        let mut total = 0.0;
        for i in 0..=n_theta {
            let th = 2.0 * PI * i as f64 / n_theta as f64;
            let (st, ct) = th.sin_cos();
            let edge = 1.0 / ((ct / a).powi(2) + (st / b).powi(2)).sqrt();
            let mut inner = 0.0;
            for j in 0..=n_rho {
                let rho = edge * j as f64 / n_rho as f64;
                let (du, dw) = (rho * ct - u0, rho * st - w0);
                let g = (-(du * du + dw * dw) / (2.0 * v)).exp() / (2.0 * PI * v);
                inner += simpson(j, n_rho) * g * rho;
            }
            inner *= edge / n_rho as f64 / 3.0;
            total += simpson(i, n_theta) * inner;
        }
        total * 2.0 * PI / n_theta as f64 / 3.0
    }

    /// Against the polar sum, inside, on and beyond a small ellipse under
    /// a heavy blur and a long one under a light blur: within 1e-7.
    #[test]
    fn the_level_is_the_blurred_ellipse() {
        for (axes, v) in [((6.0, 3.6), 6.33), ((20.0, 5.0), 1.1), ((3.0, 3.0), 2.3)] {
            for (u0, w0) in [(0.0, 0.0), (5.5, 0.7), (-6.8, 1.9), (1.0, -4.2), (9.0, 9.0)] {
                let (ours, theirs) = (blurred_level(u0, w0, axes, v), polar(u0, w0, axes, v));
                assert!(
                    (ours - theirs).abs() < 1e-7,
                    "{axes:?} {v} at ({u0}, {w0}): {ours} vs {theirs}"
                );
            }
        }
    }

    /// The derivatives against central differences of the level.
    #[test]
    fn the_gradient_is_the_level_s() {
        let h = 1e-5;
        for (axes, v) in [((6.0, 3.6), 6.33), ((20.0, 5.0), 1.1)] {
            for (u0, w0) in [(0.0, 0.0), (5.5, 0.7), (-6.8, 1.9), (1.0, -4.2)] {
                let (_, g) = blurred_level_gradient(u0, w0, axes, v);
                let at = |du: f64, dw: f64, da: f64, db: f64| {
                    blurred_level(u0 + du, w0 + dw, (axes.0 + da, axes.1 + db), v)
                };
                let fd = [
                    (at(h, 0.0, 0.0, 0.0) - at(-h, 0.0, 0.0, 0.0)) / (2.0 * h),
                    (at(0.0, h, 0.0, 0.0) - at(0.0, -h, 0.0, 0.0)) / (2.0 * h),
                    (at(0.0, 0.0, h, 0.0) - at(0.0, 0.0, -h, 0.0)) / (2.0 * h),
                    (at(0.0, 0.0, 0.0, h) - at(0.0, 0.0, 0.0, -h)) / (2.0 * h),
                ];
                for (k, (g, f)) in g.iter().zip(&fd).enumerate() {
                    assert!(
                        (g - f).abs() < 1e-6,
                        "{axes:?} ({u0}, {w0}) d{k}: {g} vs {f}"
                    );
                }
            }
        }
    }

    /// Far from the ellipse the level is 0, deep inside a large one 1.
    #[test]
    fn far_and_deep() {
        assert_eq!(blurred_level(40.0, 0.0, (6.0, 3.6), 1.0), 0.0);
        assert!((blurred_level(0.0, 0.0, (60.0, 40.0), 1.0) - 1.0).abs() < 1e-12);
    }
}
