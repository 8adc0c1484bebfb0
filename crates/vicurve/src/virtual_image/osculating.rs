//! The blurred osculating circle: what the curved edge's expansion leaves
//! out where the blur is not small against the radius of curvature.
//!
//! [`super::pixel_edge::curved_edge`] expands the blurred edge to the
//! second order in `q = s kappa` (`s^2 = v`, the whole spread's variance;
//! `kappa` the curvature). A small disc under a heavy blur is beyond it: a
//! disc a few spreads across came out too large by many times its sigma
//! (docs/benchmarks.md, "The blurred osculating circle"). Near a point of
//! the edge the image is, to the order that matters there, that of the
//! osculating disc (radius `1 / |kappa|`), whose blurred level is exact
//! where the curvature holds over the blur: under an isotropic Gaussian
//! of variance `v`, a point at distance `d` from the centre of a disc of
//! radius `rho` sees the disc with the probability `P(|Y| <= rho / s)`,
//! `Y ~ N((d / s, 0), I)` (one minus Marcum's `Q1(d / s, rho / s)`). The
//! band weighs the correction by how well the curvature holds
//! (`band/blurred_curvature.rs`). This module tabulates
//! the difference between that level and the expansion's (with the
//! pixel's own spread taken as Gaussian in both, so that the square
//! pixel's part cancels), `C(t, q)` with `t = r / s`, which the curved edge
//! adds where `|q|` exceeds [`Q_START`].
//!
//! # The exact level
//! With `Y = (a + z1, z2)`, `|Y| <= b` holds for `|z2| <= b` and `z1`
//! within `-a -+ sqrt(b^2 - z2^2)`; with `z2 = b sin theta`,
//! `P(|Y| <= b) = 2 int_0^{pi/2} [Phi(b cos - a) - Phi(-b cos - a)]
//! phi(b sin) b cos dtheta`, a smooth integrand, summed by Gauss–Legendre
//! quadrature ([`NODES`] nodes). Its derivative in `a` is the same integral
//! of `phi(-b cos - a) - phi(b cos - a)` in place of the bracket.
//!
//! # Conventions
//! As the curved edge's: `gamma` is the level of the side at negative `r`,
//! and a positive curvature has its centre on the side of positive `r`
//! (the half level of a blurred disc lies inside it). For `q > 0` the
//! pixel at `r` lies `d = rho - r` from the centre and `gamma = P(|Y| >
//! b)`; a negative `q` is the mirror image, `C(t, -q) = -C(-t, q)`.
//!
//! # Accuracy
//! The table holds `C` and `dC/dt` every [`T_STEP`] in `t` (cubic Hermite
//! between) and every [`Q_STEP`] in `q` (cubic between); tested against
//! the blurred disc's integral in `pixel_edge.rs`. Beyond [`Q_MAX`] (a
//! radius of curvature under half the spread) `q` is taken as `Q_MAX`.

use super::pixel_edge::normal_cdf_pdf;
use std::f64::consts::{FRAC_PI_2, PI};
use std::sync::OnceLock;

/// The correction starts at this `|q|` (below it the expansion holds: the
/// blurred-disc test of `pixel_edge.rs`), ...
const Q_START: f64 = 0.1;
/// ... and counts in full from this one (a smooth step between).
const Q_FULL: f64 = 0.2;
/// The table's largest `q`.
const Q_MAX: f64 = 2.0;
/// The table's step in `q`.
const Q_STEP: f64 = 0.02;
/// The table covers `t` in `[-T_REACH, T_REACH]`; beyond, both levels are
/// the plateaus' (the correction vanishes).
const T_REACH: f64 = 10.0;
/// The table's step in `t`.
const T_STEP: f64 = 0.1;
/// Gauss–Legendre nodes of the exact level's quadrature.
const NODES: usize = 64;

/// `C(t, q)` and `dC/dt` on the grid, a column of `t` per `q`, each
/// column computed the first time it is read (a curve reads the few
/// around its own `q`; the whole table took tens of milliseconds, more
/// than measuring a small disc).
struct Table {
    rule: Vec<(f64, f64)>,
    columns: Vec<OnceLock<Vec<[f64; 2]>>>,
}

const T_COUNT: usize = (2.0 * T_REACH / T_STEP) as usize + 1;
const Q_COUNT: usize = (Q_MAX / Q_STEP) as usize + 1;

fn table() -> &'static Table {
    static TABLE: OnceLock<Table> = OnceLock::new();
    TABLE.get_or_init(|| Table {
        rule: legendre(NODES),
        columns: (0..Q_COUNT).map(|_| OnceLock::new()).collect(),
    })
}

impl Table {
    /// Column `j` (`q = j Q_STEP`), computed on first use.
    fn values(&self, j: usize) -> &[[f64; 2]] {
        self.columns[j].get_or_init(|| {
            let q = j as f64 * Q_STEP;
            (0..T_COUNT)
                .map(|i| {
                    if q < 0.5 * Q_START {
                        return [0.0; 2];
                    }
                    let t = -T_REACH + i as f64 * T_STEP;
                    let (exact, d_exact) = disc_level(t, q, &self.rule);
                    let (model, d_model) = expansion(t, q);
                    [exact - model, d_exact - d_model]
                })
                .collect()
        })
    }

    /// `(C, dC/dt)` at `t` on the table's column `j` of `q`.
    fn column(&self, j: usize, t: f64) -> (f64, f64) {
        let x = (t + T_REACH) / T_STEP;
        let i = (x.floor() as usize).min(T_COUNT - 2);
        let w = x - i as f64;
        let values = self.values(j);
        let [f0, d0] = values[i];
        let [f1, d1] = values[i + 1];
        let (d0, d1) = (d0 * T_STEP, d1 * T_STEP);
        // Cubic Hermite on [0, 1] and its derivative.
        let (w2, w3) = (w * w, w * w * w);
        let value = (2.0 * w3 - 3.0 * w2 + 1.0) * f0
            + (w3 - 2.0 * w2 + w) * d0
            + (-2.0 * w3 + 3.0 * w2) * f1
            + (w3 - w2) * d1;
        let slope = (6.0 * w2 - 6.0 * w) * f0
            + (3.0 * w2 - 4.0 * w + 1.0) * d0
            + (-6.0 * w2 + 6.0 * w) * f1
            + (3.0 * w2 - 2.0 * w) * d1;
        (value, slope / T_STEP)
    }
}

/// What the curved edge adds at signed distance `r` (pixels) from an edge
/// of curvature `curvature` (1/px) under a spread of variance `v` (px^2):
/// `(dgamma, d dgamma / dr)`, zero where `|q| = sqrt(v) |kappa|` is under
/// [`Q_START`] (see the module docs).
#[inline]
pub(crate) fn correction(r: f64, v: f64, curvature: f64) -> (f64, f64) {
    // Most edges: one product and a comparison.
    if !applies(v, curvature) || !r.is_finite() {
        return (0.0, 0.0);
    }
    let s = v.sqrt();
    let q = s * curvature;
    let a = q.abs();
    if !a.is_finite() {
        return (0.0, 0.0);
    }
    // The mirror image for a negative curvature.
    let t = if q > 0.0 { r / s } else { -r / s };
    if t.abs() >= T_REACH {
        return (0.0, 0.0);
    }
    // Cubic (Lagrange) in q over the four columns around it.
    let x = a.min(Q_MAX) / Q_STEP;
    let j = (x.floor() as usize).clamp(1, Q_COUNT - 3);
    let f = x - j as f64;
    let weights = [
        -f * (f - 1.0) * (f - 2.0) / 6.0,
        (f + 1.0) * (f - 1.0) * (f - 2.0) / 2.0,
        -(f + 1.0) * f * (f - 2.0) / 2.0,
        (f + 1.0) * f * (f - 1.0) / 6.0,
    ];
    let table = table();
    let (mut c, mut dc) = (0.0, 0.0);
    for (k, w) in weights.iter().enumerate() {
        let (ck, dk) = table.column(j + k - 1, t);
        c += w * ck;
        dc += w * dk;
    }
    let ramp = ((a - Q_START) / (Q_FULL - Q_START)).clamp(0.0, 1.0);
    let blend = ramp * ramp * (3.0 - 2.0 * ramp);
    if q > 0.0 {
        (blend * c, blend * dc / s)
    } else {
        // C(t, -q) = -C(-t, q): its derivative in r is dC/dt at -t over s.
        (-blend * c, blend * dc / s)
    }
}

/// Whether [`correction`] adds anything at a curvature `curvature` (1/px)
/// under a spread of variance `v` (px^2): `|q|` beyond [`Q_START`]
/// (false for NaN).
#[inline]
pub(crate) fn applies(v: f64, curvature: f64) -> bool {
    v * curvature * curvature > Q_START * Q_START
}

/// Whether [`correction`] counts in full at a curvature `curvature`
/// (1/px) under a spread of variance `v` (px^2): `|q|` at least
/// [`Q_FULL`].
#[inline]
pub(crate) fn in_full(v: f64, curvature: f64) -> bool {
    v * curvature * curvature >= Q_FULL * Q_FULL
}

/// The exact level `gamma` of the side at negative `t` of the blurred
/// osculating circle, for `q > 0` (centre at `t = 1 / q`), and its
/// derivative in `t`, in units of the spread (module docs).
fn disc_level(t: f64, q: f64, rule: &[(f64, f64)]) -> (f64, f64) {
    let b = 1.0 / q;
    let a = b - t;
    let (mut inside, mut d_inside) = (0.0, 0.0);
    for &(theta, weight) in rule {
        let (sin, cos) = theta.sin_cos();
        let (reach, across) = (b * cos, b * sin);
        let (hi, d_hi) = normal_cdf_pdf(reach - a);
        let (lo, d_lo) = normal_cdf_pdf(-reach - a);
        let density = (-0.5 * across * across).exp() / (2.0 * PI).sqrt() * reach;
        inside += weight * (hi - lo) * density;
        d_inside += weight * (d_lo - d_hi) * density;
    }
    // gamma = 1 - P(inside); d/dt = -dP/da * da/dt = dP/da.
    (1.0 - 2.0 * inside, 2.0 * d_inside)
}

/// The curved edge's expansion of the same level, the pixel's own spread
/// taken as Gaussian (`pixel_edge::curved_edge` with an isotropic blur),
/// in units of the spread: the shift `q (1 + 3 q^2 / 4) / 2`, the width
/// `sqrt(1 + q^2 / 2)` and the skew `q^3 / 6`.
fn expansion(t: f64, q: f64) -> (f64, f64) {
    let shifted = t - 0.5 * q * (1.0 + 0.75 * q * q);
    let width = (1.0 + 0.5 * q * q).sqrt();
    let (cdf, pdf) = normal_cdf_pdf(shifted / width);
    let skew = q * q * q / 6.0;
    let (_, phi) = normal_cdf_pdf(shifted);
    let gamma = 1.0 - cdf + skew * (shifted * shifted - 1.0) * phi;
    let slope = -pdf / width + skew * shifted * (3.0 - shifted * shifted) * phi;
    (gamma, slope)
}

/// The `n`-point Gauss–Legendre rule on `[0, pi / 2]`: `(node, weight)`.
fn legendre(n: usize) -> Vec<(f64, f64)> {
    gauss_legendre(n)
        .into_iter()
        .map(|(x, weight)| (FRAC_PI_2 * 0.5 * (x + 1.0), FRAC_PI_2 * 0.5 * weight))
        .collect()
}

/// The `n`-point Gauss–Legendre rule on `[-1, 1]`: `(node, weight)`.
pub(crate) fn gauss_legendre(n: usize) -> Vec<(f64, f64)> {
    (0..n)
        .map(|i| {
            // Newton on P_n from the usual first guess.
            let mut x = (PI * (i as f64 + 0.75) / (n as f64 + 0.5)).cos();
            let mut dp = 1.0;
            for _ in 0..100 {
                let (mut p0, mut p1) = (1.0, x);
                for k in 2..=n {
                    let k = k as f64;
                    (p0, p1) = (p1, ((2.0 * k - 1.0) * x * p1 - (k - 1.0) * p0) / k);
                }
                dp = n as f64 * (x * p1 - p0) / (x * x - 1.0);
                let step = p1 / dp;
                x -= step;
                if step.abs() < 1e-16 {
                    break;
                }
            }
            (x, 2.0 / ((1.0 - x * x) * dp * dp))
        })
        .collect()
}

#[cfg(test)]
mod tests {
    use super::*;

    /// The rule integrates `cos` over `[0, pi / 2]` (1) and a polynomial
    /// of degree `2n - 1` exactly.
    #[test]
    fn the_quadrature_is_gauss_legendre() {
        let rule = legendre(NODES);
        let cos: f64 = rule.iter().map(|&(x, w)| w * x.cos()).sum();
        assert!((cos - 1.0).abs() < 1e-14, "{cos}");
        let p: f64 = rule.iter().map(|&(x, w)| w * x.powi(127)).sum();
        let exact = FRAC_PI_2.powi(128) / 128.0;
        assert!((p / exact - 1.0).abs() < 1e-12, "{p} {exact}");
    }

    /// At the centre of the disc (`t = 1 / q`) the level inside is the
    /// Rayleigh distribution's, `1 - exp(-b^2 / 2)`, and its slope there
    /// vanishes (the level is even about the centre); far outside it is
    /// 1, far inside the disc (for a large disc) 0.
    #[test]
    fn the_disc_level_has_its_closed_forms() {
        let rule = legendre(NODES);
        for q in [0.1, 0.3, 0.7, 1.5] {
            let b = 1.0 / q;
            let (gamma, slope) = disc_level(b, q, &rule);
            let rayleigh = (-0.5 * b * b).exp();
            assert!(
                (gamma - rayleigh).abs() < 1e-13,
                "q {q}: {gamma} {rayleigh}"
            );
            assert!(slope.abs() < 1e-13, "q {q}: {slope}");
            let (far, _) = disc_level(-12.0, q, &rule);
            assert!((far - 1.0).abs() < 1e-13, "q {q}: {far}");
        }
        let (deep, _) = disc_level(8.0, 0.1, &rule);
        assert!(deep.abs() < 1e-13, "{deep}");
    }

    /// The slope is the derivative of the level (central differences), and
    /// matches its closed form `-b exp(-(a^2 + b^2) / 2) I1(a b)` (`I1` by
    /// the trapezoidal rule on its integral over a period, exact to
    /// rounding for these arguments).
    #[test]
    fn the_disc_slope_is_its_derivative() {
        let rule = legendre(NODES);
        let i1e = |z: f64| {
            let n = 400;
            (0..n)
                .map(|k| {
                    let th = PI * (k as f64 + 0.5) / n as f64;
                    (z * (th.cos() - 1.0)).exp() * th.cos()
                })
                .sum::<f64>()
                / n as f64
        };
        for q in [0.06, 0.12, 0.4, 0.9, 2.0] {
            let b = 1.0 / q;
            for t in [-3.0, -1.0, 0.0, 0.5, 2.0] {
                let (_, slope) = disc_level(t, q, &rule);
                let h = 1e-4;
                let numeric =
                    (disc_level(t + h, q, &rule).0 - disc_level(t - h, q, &rule).0) / (2.0 * h);
                assert!(
                    (slope - numeric).abs() < 1e-8,
                    "q {q} t {t}: {slope} {numeric}"
                );
                let a = b - t;
                let closed = -b * (-0.5 * (a - b) * (a - b)).exp() * i1e(a * b);
                assert!(
                    (slope - closed).abs() < 1e-12,
                    "q {q} t {t}: {slope} {closed}"
                );
            }
        }
    }

    /// The expansion's slope is its derivative, and the table's
    /// interpolation stays within 5e-6 of the direct difference between
    /// its nodes (in `t` and in `q`, either sign), where band pixels lie
    /// (nearer than 0.9 of the radius of curvature on its side).
    #[test]
    fn the_table_interpolates_the_correction() {
        let rule = legendre(NODES);
        for q in [0.2, 0.5, 1.1] {
            for t in [-2.0, 0.3, 1.7] {
                let h = 1e-5;
                let numeric = (expansion(t + h, q).0 - expansion(t - h, q).0) / (2.0 * h);
                assert!((expansion(t, q).1 - numeric).abs() < 1e-8);
            }
        }
        let mut worst: f64 = 0.0;
        for q in [0.213, 0.377, 0.651, 1.239, 1.93] {
            for k in 0..80 {
                let t = -6.0 + 0.1537 * k as f64;
                // Band pixels keep `1 - kappa r` above 0.1.
                if t >= 0.9 / q {
                    continue;
                }
                let direct = disc_level(t, q, &rule).0 - expansion(t, q).0;
                for sign in [1.0, -1.0] {
                    let (c, _) = correction(sign * t, 1.0, sign * q);
                    worst = worst.max((sign * c - direct).abs());
                }
            }
        }
        println!("table within {worst:.1e} of the direct correction");
        assert!(worst < 5e-6, "{worst}");
    }
}
