//! The normal distribution's first two antiderivatives, tabulated.
//!
//! `Psi1(x) = x Phi(x) + phi(x)` and `Psi2(x) = ((x^2 + 1) Phi(x) + x
//! phi(x)) / 2` (`Phi`, `phi` the standard normal distribution and density)
//! are the pieces of the pixel-edge profile ([`super::pixel_edge`]), which
//! is evaluated at every band pixel in every iteration of the pixel-edge
//! stage. Computed directly they cost an exponential and a rational function
//! each; here they are a quintic polynomial per table
//! interval, found by Hermite interpolation of the exact values and their
//! first two derivatives at the nodes (`Psi2' = Psi1`, `Psi2'' = Psi1' =
//! Phi`, `Psi1'' = phi`): a table of 9 kB, built once, and ten fused
//! multiply-adds per evaluation.
//!
//! # Accuracy
//! Nodes every `1/16` between `-10` and `10`: the quintic Hermite error is
//! `h^6 / 46080` times the sixth derivative (`phi'''` and `phi''''`, under 3
//! in magnitude), about `4e-12`, tested against the direct formula to
//! `1e-11`. Beyond the table `Psi1` and `Psi2` are their asymptotes (`0`
//! below `-10`, `x` and `(x^2 + 1) / 2` above), exact to `1e-21`.
//!
//! The pixel-edge profile is a second difference of `Psi2` divided by the
//! trapezoid's area over the blur's variance, which amplifies these errors
//! (by up to `50 sigma^2` for an axis-aligned edge): the profile stays
//! within `1e-9 (1 + sigma^2)` of the direct formula (tested).

use super::pixel_edge::normal_cdf_pdf;
use std::sync::OnceLock;

/// The table's node spacing (a power of 2: the node index is exact).
const STEP: f64 = 1.0 / 16.0;
/// The table covers `[-REACH, REACH]`.
const REACH: f64 = 10.0;
/// Intervals in the table.
const INTERVALS: usize = (2.0 * REACH / STEP) as usize;

/// Per interval, the monomial coefficients (in the local variable `w` in
/// `[0, 1)`) of `Psi2` (the first six) and `Psi1` (the last six).
struct Table {
    coef: Vec<[f64; 12]>,
}

fn table() -> &'static Table {
    static TABLE: OnceLock<Table> = OnceLock::new();
    TABLE.get_or_init(Table::build)
}

/// `(Psi2, Psi1, Phi, phi)` at `x`, directly.
fn exact(x: f64) -> [f64; 4] {
    let (big, small) = normal_cdf_pdf(x);
    let psi1 = x * big + small;
    let psi2 = 0.5 * ((x * x + 1.0) * big + x * small);
    [psi2, psi1, big, small]
}

/// The quintic `c0 + c1 w + ... + c5 w^5` on `[0, 1]` with the given
/// values `f`, first derivatives `d` and second derivatives `s` at `w = 0`
/// and `w = 1` (derivatives with respect to `w`).
fn quintic(f: [f64; 2], d: [f64; 2], s: [f64; 2]) -> [f64; 6] {
    let e0 = f[1] - f[0] - d[0] - 0.5 * s[0];
    let e1 = d[1] - d[0] - s[0];
    let e2 = s[1] - s[0];
    [
        f[0],
        d[0],
        0.5 * s[0],
        10.0 * e0 - 4.0 * e1 + 0.5 * e2,
        -15.0 * e0 + 7.0 * e1 - e2,
        6.0 * e0 - 3.0 * e1 + 0.5 * e2,
    ]
}

impl Table {
    fn build() -> Table {
        let node = |k: usize| exact(-REACH + k as f64 * STEP);
        let (h, h2) = (STEP, STEP * STEP);
        let coef = (0..INTERVALS)
            .map(|k| {
                let (a, b) = (node(k), node(k + 1));
                let p2 = quintic([a[0], b[0]], [a[1] * h, b[1] * h], [a[2] * h2, b[2] * h2]);
                let p1 = quintic([a[1], b[1]], [a[2] * h, b[2] * h], [a[3] * h2, b[3] * h2]);
                let mut c = [0.0; 12];
                c[..6].copy_from_slice(&p2);
                c[6..].copy_from_slice(&p1);
                c
            })
            .collect();
        Table { coef }
    }
}

/// The table, for [`Psi::at`].
#[derive(Clone, Copy)]
pub(crate) struct Psi(&'static Table);

impl Psi {
    /// The table (built on first use).
    #[inline]
    pub(crate) fn get() -> Psi {
        Psi(table())
    }

    /// `(Psi2(x), Psi1(x))` (module docs); NaN for NaN.
    #[inline(always)]
    pub(crate) fn at(self, x: f64) -> (f64, f64) {
        at(self.0, x)
    }
}

/// `(Psi2(x), Psi1(x))` from the table (module docs); NaN for NaN.
#[cfg(test)]
fn psi(x: f64) -> (f64, f64) {
    at(table(), x)
}

#[inline(always)]
fn at(table: &Table, x: f64) -> (f64, f64) {
    if x >= REACH {
        return (0.5 * (x * x + 1.0), x);
    }
    if x.is_nan() {
        return (x, x);
    }
    if x <= -REACH {
        return (0.0, 0.0);
    }
    let u = (x + REACH) * (1.0 / STEP);
    // `u` in `(0, INTERVALS)`: the truncation is the floor.
    let k = (u as usize).min(INTERVALS - 1);
    let w = u - k as f64;
    let c = &table.coef[k];
    let p2 = c[0] + w * (c[1] + w * (c[2] + w * (c[3] + w * (c[4] + w * c[5]))));
    let p1 = c[6] + w * (c[7] + w * (c[8] + w * (c[9] + w * (c[10] + w * c[11]))));
    (p2, p1)
}

#[cfg(test)]
mod tests {
    use super::*;

    proptest::proptest! {
        /// The table against the direct formula, over the table and past
        /// its ends.
        #[test]
        fn matches_the_direct_formula(x in -12.0f64..12.0) {
            let (p2, p1) = psi(x);
            let [e2, e1, _, _] = exact(x);
            proptest::prop_assert!((p2 - e2).abs() <= 1e-11 * (1.0 + e2), "{x}: {p2} vs {e2}");
            proptest::prop_assert!((p1 - e1).abs() <= 1e-11 * (1.0 + e1), "{x}: {p1} vs {e1}");
        }
    }

    #[test]
    fn exact_at_the_nodes_and_ends() {
        for k in 0..=INTERVALS {
            let x = -REACH + k as f64 * STEP;
            let (p2, p1) = psi(x);
            let [e2, e1, _, _] = exact(x);
            assert!((p2 - e2).abs() <= 1e-13 * (1.0 + e2), "{x}");
            assert!((p1 - e1).abs() <= 1e-13 * (1.0 + e1), "{x}");
        }
        assert_eq!(psi(-30.0), (0.0, 0.0));
        assert_eq!(psi(30.0), (450.5, 30.0));
        assert!(psi(f64::NAN).0.is_nan());
    }

    #[test]
    fn hermite_reproduces_a_quintic() {
        // p(w) = 1 + 2w - w^2 + 3w^3 - 2w^4 + w^5.
        let p = |w: f64| 1.0 + 2.0 * w - w * w + 3.0 * w.powi(3) - 2.0 * w.powi(4) + w.powi(5);
        let d = |w: f64| 2.0 - 2.0 * w + 9.0 * w * w - 8.0 * w.powi(3) + 5.0 * w.powi(4);
        let s = |w: f64| -2.0 + 18.0 * w - 24.0 * w * w + 20.0 * w.powi(3);
        let c = quintic([p(0.0), p(1.0)], [d(0.0), d(1.0)], [s(0.0), s(1.0)]);
        let want = [1.0, 2.0, -1.0, 3.0, -2.0, 1.0];
        for (a, b) in c.iter().zip(want) {
            assert!((a - b).abs() < 1e-12, "{c:?}");
        }
    }
}
