//! The edge profile an ideal pixel records across a blurred straight step.
//!
//! A square pixel of side 1 whose centre is at signed distance `t` from a
//! straight step with unit normal `(nx, ny)` integrates the image over its
//! area. Projected on the normal, the pixel's area is distributed as the sum
//! of two independent uniform variables of widths `|nx|` and `|ny|` (a
//! trapezoid); a Gaussian blur of standard deviation `sigma_b` adds a normal
//! variable. The recorded level is the probability that this sum `T` stays
//! on the bright side: `P(T < -t)`, i.e. one minus the distribution function
//! of `T` at `t`.
//!
//! With `Phi` the standard normal distribution, its antiderivatives
//! `Psi1(x) = x Phi(x) + phi(x)` and `Psi2(x) = ((x^2 + 1) Phi(x) + x phi(x))
//! / 2` give that distribution in closed form as a second difference of
//! `Psi2` over the trapezoid's four corners, and its density as the same
//! difference of `Psi1`.
//!
//! Edge cases: an axis-aligned edge (`nx` or `ny` zero) is a limit of the
//! formula (0/0); widths are raised to 0.02 px and the blur to 0.03 px,
//! which moves the profile by under 1e-4 of the contrast.

use std::f64::consts::{FRAC_1_SQRT_2, PI};

/// Smallest trapezoid width used, pixels (see the module docs).
const MIN_WIDTH: f64 = 0.02;
/// Smallest blur used, pixels.
const MIN_BLUR: f64 = 0.03;

/// Standard normal distribution function.
#[inline]
pub(crate) fn normal_cdf(x: f64) -> f64 {
    0.5 * libm::erfc(-x * FRAC_1_SQRT_2)
}

/// Standard normal density.
#[inline]
fn normal_pdf(x: f64) -> f64 {
    (-0.5 * x * x).exp() * (0.5 / PI).sqrt()
}

/// `(P(T <= t), density of T at t)` for `T` the pixel's extent along the
/// normal `(nx, ny)` plus a Gaussian blur of `sigma_b` pixels (module docs).
pub fn pixel_edge_cdf(t: f64, nx: f64, ny: f64, sigma_b: f64) -> (f64, f64) {
    let a = nx.abs().max(MIN_WIDTH);
    let b = ny.abs().max(MIN_WIDTH);
    let s = sigma_b.max(MIN_BLUR);
    let reach = 0.5 * (a + b) + 9.0 * s;
    if t >= reach {
        return (1.0, 0.0);
    }
    if t <= -reach {
        return (0.0, 0.0);
    }
    let corners = [
        (0.5 * (a + b), 1.0),
        (0.5 * (b - a), -1.0),
        (0.5 * (a - b), -1.0),
        (-0.5 * (a + b), 1.0),
    ];
    let (mut cdf, mut pdf) = (0.0, 0.0);
    for (offset, sign) in corners {
        let x = (t + offset) / s;
        let (big_phi, small_phi) = (normal_cdf(x), normal_pdf(x));
        cdf += sign * 0.5 * ((x * x + 1.0) * big_phi + x * small_phi);
        pdf += sign * (x * big_phi + small_phi);
    }
    let cdf = (cdf * s * s / (a * b)).clamp(0.0, 1.0);
    let pdf = (pdf * s / (a * b)).max(0.0);
    (cdf, pdf)
}

#[cfg(test)]
mod tests {
    use super::*;

    /// Brute force: the pixel's coverage by the half-plane, averaged over a
    /// fine grid of sub-pixels and over Gaussian-distributed shifts.
    fn brute(t: f64, nx: f64, ny: f64, sigma_b: f64) -> f64 {
        let n = 200;
        let shifts: Vec<(f64, f64)> = if sigma_b == 0.0 {
            vec![(0.0, 1.0)]
        } else {
            (-40..=40)
                .map(|k| {
                    let z = k as f64 * 0.15;
                    (z * sigma_b, normal_pdf(z) * 0.15)
                })
                .collect()
        };
        let mut total = 0.0;
        for (shift, w) in shifts {
            let mut inside = 0;
            for i in 0..n {
                for j in 0..n {
                    let x = (i as f64 + 0.5) / n as f64 - 0.5;
                    let y = (j as f64 + 0.5) / n as f64 - 0.5;
                    if x * nx + y * ny + shift <= t {
                        inside += 1;
                    }
                }
            }
            total += w * inside as f64 / (n * n) as f64;
        }
        total
    }

    #[test]
    fn matches_brute_force_coverage() {
        for &(angle, sigma_b) in &[(0.3, 0.0), (0.0, 0.5), (0.7, 0.8), (1.2, 0.0), (0.785, 0.3)] {
            let (nx, ny) = (f64::cos(angle), f64::sin(angle));
            for k in -8..=8 {
                let t = k as f64 * 0.11;
                let (cdf, _) = pixel_edge_cdf(t, nx, ny, sigma_b);
                let want = brute(t, nx, ny, sigma_b);
                assert!(
                    (cdf - want).abs() < 4e-3,
                    "{angle} {sigma_b} {t}: {cdf} vs {want}"
                );
            }
        }
    }

    #[test]
    fn density_is_the_derivative() {
        for &(nx, ny, s) in &[(0.6, 0.8, 0.0), (1.0, 0.0, 0.4), (0.28, -0.96, 1.5)] {
            for k in -20..=20 {
                let t = k as f64 * 0.07;
                let h = 1e-5;
                let fd = (pixel_edge_cdf(t + h, nx, ny, s).0 - pixel_edge_cdf(t - h, nx, ny, s).0)
                    / (2.0 * h);
                let pdf = pixel_edge_cdf(t, nx, ny, s).1;
                assert!((fd - pdf).abs() < 1e-5, "{nx} {ny} {s} {t}: {fd} vs {pdf}");
            }
        }
    }

    #[test]
    fn symmetric_and_centred() {
        for &(nx, ny, s) in &[(0.6, 0.8, 0.0), (1.0, 0.0, 0.4), (0.28, -0.96, 2.0)] {
            assert!((pixel_edge_cdf(0.0, nx, ny, s).0 - 0.5).abs() < 1e-12);
            for k in 1..30 {
                let t = k as f64 * 0.13;
                let (lo, hi) = (pixel_edge_cdf(-t, nx, ny, s), pixel_edge_cdf(t, nx, ny, s));
                assert!((lo.0 + hi.0 - 1.0).abs() < 1e-12);
                assert!((lo.1 - hi.1).abs() < 1e-12);
            }
        }
    }
}
