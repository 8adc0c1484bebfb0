//! The representation term of the output's `sigma`: the shape error that
//! the last stage's elements leave where the edge bends faster than they
//! can follow.
//!
//! A least-squares B-spline of degree `p` on elements `h` long leaves, on
//! a function whose derivative of order `p + 1` is `D`, an error of RMS
//! [`LEAST_SQUARES_ERROR`]`[p] h^(p + 1) |D|` (from the spline space's
//! own error kernel; tested against a dense least-squares fit). The
//! measured curve is such a spline about the edge (the reference a settle
//! refits with control points an element apart, plus a displacement on
//! the same elements), and along its normal `D` is the normal component
//! of the curve's derivative of order `p + 1`: for cubics `kappa'' -
//! kappa^3`, large in a star's bays (14 px of radius, `kappa''` of 2e-3
//! px^-3: 1.6e-3 px on elements of 5 px). That error is the same on every
//! image of the edge, so neither the noise term nor the residuals see it:
//! a fit converged on elements that cannot follow a bay leaves no request
//! the elements could take up. A pixel-edge stage's settles amplify it by
//! [`settle_shape_gain`] (each settle answers the reference's shape error
//! at the elements' scale).
//!
//! `D` is read on the measured curve itself, by the finite difference of
//! order `p + 1` of its points an element apart: the derivative averaged
//! by a B-spline of `p + 1` elements, which is what the elements hold of
//! the edge's (finer detail they do not follow at all, and its error is
//! the misfit term's). The step of an element is blind to the error this
//! term is about, which repeats itself every element: at half an element
//! the stencil also read that error's own derivative (3e-3 px at a
//! period of 5 px in a star's bays), and the term jumped tenfold and more
//! from one sample to the next (7e-5 to 2.3e-3 px two samples apart,
//! measured). Noise in the curve adds, by the stencil's weights (`sqrt(70)
//! C_3` for cubics), less than a hundredth of its `sigma` to the estimate.
//!
//! Edge cases: a stencil that would cross a corner gives no term (the
//! corner's own model and the noise term near it answer for that
//! stretch); on an open curve the stencil is moved inward at the ends;
//! a curve shorter than the stencil gives none.

use super::blur::settle_shape_gain;
use crate::curve::SplineCurve;
use crate::spline::MAX_DEGREE;
use crate::virtual_image::Profile;

/// RMS error of the least-squares spline of degree `p` (index) with unit
/// elements of `x^(p + 1) / (p + 1)!`, away from the ends: the factor on
/// `h^(p + 1) |D|` (computed on 40 elements and checked by
/// `tests::the_constants_are_the_least_squares_error`).
/// (`p = 0`, `x` on constants, is `1 / sqrt(12)`.)
const LEAST_SQUARES_ERROR: [f64; MAX_DEGREE + 1] = [
    0.288_675, 3.726_6e-2, 5.750_6e-3, 9.092_2e-4, 1.444_9e-4, 2.298_7e-5,
];

/// How far along the curve (elements) a bend's least-squares error
/// reaches ([`Representation::along`]).
const REACH: f64 = 1.0;

/// The representation term of the last stage's result, prepared once.
pub(super) struct Representation {
    /// Element length, pixels.
    h: f64,
    /// The displacement's degree.
    p: usize,
    /// `LEAST_SQUARES_ERROR[p] h^(p + 1)` times the settles' gain.
    factor: f64,
}

impl Representation {
    /// The term for elements `h` pixels long of degree `p`, under the
    /// stage's `profile` (whose settles, for a pixel edge or line, amplify
    /// it); `None` for a degree beyond the table or no elements.
    pub fn new(h: f64, p: usize, profile: Profile) -> Option<Self> {
        if !(h.is_finite() && h > 0.0) || p > MAX_DEGREE {
            return None;
        }
        let gain = match profile {
            Profile::PixelEdge { blur, .. } | Profile::PixelLine { blur, .. } => {
                settle_shape_gain(blur, h)
            }
            Profile::Paper { .. } => 1.0,
        };
        let factor = gain * LEAST_SQUARES_ERROR[p] * h.powi(p as i32 + 1);
        Some(Representation { h, p, factor })
    }

    /// The term at each of the parameters `at` (increasing) of the measured
    /// `curve`: the largest of [`Self::at`] within [`REACH`] elements,
    /// read on a grid a quarter of an element apart. The least-squares
    /// error of a bend reaches beyond the bend: on a star's elements of 5
    /// px, 8 px from the middle of a bay, an error of 1.4e-3 px where
    /// `sigma` said 2.1e-4 px without the window (measured).
    pub fn along(&self, curve: &SplineCurve, at: &[f64]) -> Vec<f64> {
        let length = curve.param_length();
        let closed = curve.is_closed();
        let step = 0.25 * self.h;
        let n = ((length / step).ceil() as usize).max(1);
        let step = length / n as f64;
        let grid: Vec<f64> = (0..=n).map(|k| self.at(curve, k as f64 * step)).collect();
        let reach = (REACH * self.h / step).ceil() as isize;
        at.iter()
            .map(|&u| {
                let centre = (u / step).round() as isize;
                (centre - reach..=centre + reach)
                    .filter_map(|k| {
                        if closed {
                            Some(grid[k.rem_euclid(n as isize) as usize])
                        } else {
                            (0..=n as isize).contains(&k).then(|| grid[k as usize])
                        }
                    })
                    .fold(0.0, f64::max)
            })
            .collect()
    }

    /// The term (pixels, RMS) at parameter `u` of the measured `curve`
    /// (parametrised by about its arc length); 0 where the stencil would
    /// cross a corner or does not fit on the curve.
    pub fn at(&self, curve: &SplineCurve, u: f64) -> f64 {
        let order = self.p + 1;
        let delta = self.h;
        let span = order as f64 * delta;
        let length = curve.param_length();
        let closed = curve.is_closed();
        if span >= length {
            return 0.0;
        }
        // The stencil's first point.
        let mut start = u - 0.5 * span;
        if !closed {
            start = start.clamp(0.0, length - span);
        }
        let wrap = |v: f64| if closed { v.rem_euclid(length) } else { v };
        let crosses = curve
            .corners()
            .iter()
            .any(|&c| (0.0..=span).contains(&wrap(c - start)));
        if crosses {
            return 0.0;
        }
        let normal = curve.frame(wrap(u.clamp(start, start + span))).normal;
        // The finite difference of order `p + 1`, binomial weights of
        // alternating sign.
        let (mut dx, mut dy, mut weight) = (0.0, 0.0, 1.0);
        for k in 0..=order {
            let q = curve.point(wrap(start + k as f64 * delta));
            let sign = if (order - k).is_multiple_of(2) {
                1.0
            } else {
                -1.0
            };
            dx += sign * weight * q[0];
            dy += sign * weight * q[1];
            weight = weight * (order - k) as f64 / (k + 1) as f64;
        }
        let d = (dx * normal[0] + dy * normal[1]) / delta.powi(order as i32);
        self.factor * d.abs()
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::spline::Basis;

    /// The least-squares fit on `basis` (uniform, open) of `f` sampled
    /// every 1/64 of an element, by normal equations on the basis's own
    /// evaluation: the RMS of the residual over the middle half.
    fn least_squares_rms(basis: &Basis, f: impl Fn(f64) -> f64) -> f64 {
        let n = basis.n_functions();
        let p = basis.degree();
        let l = basis.length();
        let m = (l * 64.0) as usize;
        let xs: Vec<f64> = (0..=m).map(|i| l * i as f64 / m as f64).collect();
        let mut ata = vec![vec![0.0; n]; n];
        let mut atb = vec![0.0; n];
        let mut v = [0.0; MAX_DEGREE + 1];
        for &x in &xs {
            let first = basis.eval(x, &mut v);
            for a in 0..=p {
                let i = basis.index(first, a);
                atb[i] += v[a] * f(x);
                for b in 0..=p {
                    ata[i][basis.index(first, b)] += v[a] * v[b];
                }
            }
        }
        // Gaussian elimination with partial pivoting (a small dense
        // system: an oracle independent of the crate's banded solver).
        for c in 0..n {
            let pivot = (c..n)
                .max_by(|&i, &j| ata[i][c].abs().total_cmp(&ata[j][c].abs()))
                .unwrap();
            ata.swap(c, pivot);
            atb.swap(c, pivot);
            for r in c + 1..n {
                let k = ata[r][c] / ata[c][c];
                let pivot_row = ata[c].clone();
                for (a, b) in ata[r][c..].iter_mut().zip(&pivot_row[c..]) {
                    *a -= k * b;
                }
                atb[r] -= k * atb[c];
            }
        }
        let mut coef = vec![0.0; n];
        for c in (0..n).rev() {
            let s: f64 = (c + 1..n).map(|j| ata[c][j] * coef[j]).sum();
            coef[c] = (atb[c] - s) / ata[c][c];
        }
        let (mut sum, mut count) = (0.0, 0.0);
        for &x in xs.iter().filter(|&&x| x > 0.25 * l && x < 0.75 * l) {
            let first = basis.eval(x, &mut v);
            let g: f64 = (0..=p).map(|a| coef[basis.index(first, a)] * v[a]).sum();
            sum += (f(x) - g).powi(2);
            count += 1.0;
        }
        (sum / count).sqrt()
    }

    #[test]
    fn the_constants_are_the_least_squares_error() {
        for (p, &table) in LEAST_SQUARES_ERROR.iter().enumerate().skip(1) {
            let basis = Basis::new(p, 24, 24.0, false).unwrap();
            let factorial: f64 = (1..=p + 1).map(|k| k as f64).product();
            let rms = least_squares_rms(&basis, |x| x.powi(p as i32 + 1) / factorial);
            assert!(
                (rms / table - 1.0).abs() < 0.01,
                "degree {p}: {rms:e} against {table:e}"
            );
        }
    }

    /// The stencil reads `D` on a circle of radius `r` (`-kappa^3` along
    /// the normal) and at a sine's crest.
    #[test]
    fn the_stencil_reads_the_fourth_derivative() {
        use crate::curve::SplineCurve;
        use std::f64::consts::TAU;
        let r = 50.0;
        let pts: Vec<[f64; 2]> = (0..2000)
            .map(|i| {
                let t = TAU * i as f64 / 2000.0;
                [100.0 + r * t.cos(), 100.0 + r * t.sin()]
            })
            .collect();
        let circle = SplineCurve::fit(&pts, true, 3, 2.0).unwrap();
        let h = 8.0;
        let paper = Profile::Paper {
            kind: crate::virtual_image::Kind::Silhouette,
        };
        let rep = Representation::new(h, 3, paper).unwrap();
        let expected = LEAST_SQUARES_ERROR[3] * h.powi(4) / r.powi(3);
        for u in [0.0, 40.0, 150.0] {
            let got = rep.at(&circle, u);
            assert!(
                (got / expected - 1.0).abs() < 0.02,
                "{got:e} against {expected:e}"
            );
        }
        // A gentle sine (slope at most 0.04), where `kappa'' - kappa^3`
        // is `a k^4 sin(k x)` to within 0.3 %; its crest at x = 75.
        let (a, k) = (2.0, TAU / 300.0);
        let pts: Vec<[f64; 2]> = (0..=6000)
            .map(|i| {
                let x = i as f64 / 10.0;
                [x, 200.0 + a * (k * x).sin()]
            })
            .collect();
        let sine = SplineCurve::fit(&pts, false, 3, 2.0).unwrap();
        let crest = (0..=60000)
            .map(|i| i as f64 * sine.param_length() / 60000.0)
            .min_by(|&u, &v| {
                let (xu, xv) = (sine.point(u)[0], sine.point(v)[0]);
                (xu - 75.0).abs().total_cmp(&(xv - 75.0).abs())
            })
            .unwrap();
        let got = rep.at(&sine, crest);
        let expected = LEAST_SQUARES_ERROR[3] * h.powi(4) * a * k.powi(4);
        assert!(
            (got / expected - 1.0).abs() < 0.03,
            "{got:e} against {expected:e}"
        );
    }
}
