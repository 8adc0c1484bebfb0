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
//! Detail about as fine as the elements reads less than its own `D`
//! (the stencil averages it away) and leaves more than the asymptote
//! says; how fine it is shows in the ratio of the reads at steps `2h` and
//! `h`, and the least-squares error of a sinusoid of that ratio is
//! charged ([`NARROW`]).
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

/// Cubic elements on detail about as fine as they are: the ratio `rho`
/// of the stencil's reads at steps `2h` and `h` about a crest of a
/// sinusoidal offset, and the RMS least-squares error within an element
/// of the crest over the smooth asymptote `LEAST_SQUARES_ERROR[3] h^4
/// D(h)` (`D(h)` the read at step `h`), for wavenumbers `k` from `0.3 /
/// h` (where the asymptote holds) to `2.4 / h` (under three elements a
/// period). Computed by least squares on elements at three offsets to
/// the crest and checked by
/// `tests::fine_detail_is_read_by_the_ratio_of_steps`. An isolated bend
/// (a Gaussian bump of curvature) of the same ratio leaves up to twice
/// as much (5.2 against 2.2 at a ratio of 0.28): the sinusoid is the
/// lower of the two, which keeps the smooth shapes' `sigma` from
/// growing where the asymptote held (the conformance sweep's stars).
const NARROW: [(f64, f64); 10] = [
    (0.017, 9.37),
    (0.061, 5.47),
    (0.114, 3.93),
    (0.190, 2.90),
    (0.287, 2.21),
    (0.402, 1.76),
    (0.528, 1.46),
    (0.657, 1.26),
    (0.833, 1.10),
    (0.956, 1.02),
];

/// The fine detail's factor ([`NARROW`]) counts on the part of the read
/// at step `h` beyond this many times what the curve's noise (`sqrt(70)
/// sigma / h^4` for cubics) or its texture at the pixels' scale makes of
/// it: noise alone reads a small ratio too.
const NARROW_SIGNIFICANCE: f64 = 3.0;

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
    /// `curve`, whose position noise there is `noise` (pixels, one per
    /// parameter): the largest of the grid's terms within [`REACH`]
    /// elements, the grid a quarter of an element apart. The least-squares
    /// error of a bend reaches beyond the bend: on a star's elements of 5
    /// px, 8 px from the middle of a bay, an error of 1.4e-3 px where
    /// `sigma` said 2.1e-4 px without the window (measured).
    ///
    /// Detail about as fine as the elements ([`Self::narrow`]) is charged
    /// the least-squares error of such detail, on the part of its read
    /// that the noise and the curve's texture cannot make
    /// ([`NARROW_SIGNIFICANCE`]); the ratio that says how fine it is
    /// compares the largest reads near the sample (pointwise, a zero of
    /// one read beside a peak of the other gave factors of 20, measured),
    /// or, at an open curve's ends, near the nearest place where the read
    /// at step `2h` is about itself ([`Self::centred`]).
    pub fn along(&self, curve: &SplineCurve, at: &[f64], noise: &[f64]) -> Vec<f64> {
        let length = curve.param_length();
        let closed = curve.is_closed();
        let step = 0.25 * self.h;
        let n = ((length / step).ceil() as usize).max(1);
        let step = length / n as f64;
        let grid: Vec<(f64, f64, f64)> = (0..=n)
            .map(|k| self.reads(curve, k as f64 * step))
            .collect();
        let reach = (REACH * self.h / step).ceil() as isize;
        // The read's standard deviation per pixel of position noise.
        let order = self.p + 1;
        let weights: f64 = (0..=order).map(|k| binomial(order, k).powi(2)).sum();
        let per_noise = weights.sqrt() / self.h.powi(order as i32);
        let window = |centre: isize, reach: isize| {
            (centre - reach..=centre + reach).filter_map(move |k| {
                if closed {
                    Some(k.rem_euclid(n as isize) as usize)
                } else {
                    (0..=n as isize).contains(&k).then_some(k as usize)
                }
            })
        };
        at.iter()
            .zip(noise)
            .map(|(&u, &sigma)| {
                let centre = (u / step).round() as isize;
                // The bend's reads: the largest within the window at step
                // `h` and the texture's there.
                let (mut fine, mut d) = (0.0f64, 0.0f64);
                for k in window(centre, reach) {
                    fine = fine.max(grid[k].0);
                    d = d.max(grid[k].1);
                }
                // How fine the detail is, where the read at step `2h` is
                // centred: the largest reads at steps `h` and `2h`, within
                // the window and twice the window (a read's extent grows
                // with its step).
                let inner = (self.centred(u, length, closed, 2.0) / step).round() as isize;
                let (mut near, mut wide) = (0.0f64, 0.0f64);
                for k in window(inner, reach) {
                    near = near.max(grid[k].1);
                }
                for k in window(inner, 2 * reach) {
                    wide = wide.max(grid[k].2);
                }
                // What the noise, and the texture of the curve at the
                // pixels' scale, make of the read: the read at half the
                // step over `2^(p + 1)` (a texture's read grows so as the
                // step shrinks; a bend's far less).
                let texture = fine / 2f64.powi(order as i32);
                let floor = NARROW_SIGNIFICANCE * (per_noise * sigma).max(texture);
                let narrow = self.narrow(near, wide);
                self.factor * (d + (narrow - 1.0) * (d - floor).max(0.0))
            })
            .collect()
    }

    /// The term (pixels, RMS) at parameter `u` of the measured `curve`
    /// (parametrised by about its arc length) by the smooth asymptote; 0
    /// where the stencil would cross a corner or does not fit on the
    /// curve.
    #[cfg(test)]
    pub fn at(&self, curve: &SplineCurve, u: f64) -> f64 {
        self.factor * self.read(curve, u, self.h).unwrap_or(0.0)
    }

    /// The reads `|D|` about `u` at steps `h / 2`, `h` and `2h` (0 where
    /// one does not fit or crosses a corner; all 0 when the read at `h`
    /// does not; only the read at `h` for degrees other than 3).
    fn reads(&self, curve: &SplineCurve, u: f64) -> (f64, f64, f64) {
        match self.read(curve, u, self.h) {
            // [`NARROW`] is for cubics: other degrees need no more reads.
            Some(d) if self.p != 3 => (0.0, d, 0.0),
            Some(d) => (
                self.read(curve, u, 0.5 * self.h).unwrap_or(0.0),
                d,
                self.read(curve, u, 2.0 * self.h).unwrap_or(0.0),
            ),
            None => (0.0, 0.0, 0.0),
        }
    }

    /// The parameter nearest `u` about which the read at `steps` element
    /// lengths is centred: on an open curve the stencil is moved inward
    /// at the ends ([`Self::read`]), and reads there are about another
    /// place; `u` itself on a closed curve or one shorter than the
    /// stencil.
    fn centred(&self, u: f64, length: f64, closed: bool, steps: f64) -> f64 {
        let half = 0.5 * (self.p + 1) as f64 * steps * self.h;
        if closed || 2.0 * half >= length {
            u
        } else {
            u.clamp(half, length - half)
        }
    }

    /// How much more than the smooth asymptote the elements leave on
    /// detail whose reads at steps `h` and `2h` are `d` and `wide`
    /// ([`NARROW`], cubic elements; 1 for other degrees, or where the
    /// wide read is missing).
    ///
    /// Why: the stencil reads `D` averaged over `p + 1` elements, and
    /// detail finer than that reads far less than its own: a 7-lobed
    /// star's bays of 6 px radius read 3.7e-3 px^-3 at a step of 6.7 px
    /// where `D` reaches 2.9e-2, on the exact curve as on the measured
    /// one, and its samples lay 0.05 to 0.09 px off where the term said
    /// 0.015. Fine detail reads little more at step `2h` than at `h`
    /// (the ratio falls from 1 towards 0 as it gets finer), which tells
    /// how fine it is, and with it the least-squares error it leaves.
    fn narrow(&self, d: f64, wide: f64) -> f64 {
        if self.p != 3 || !(d > 0.0 && wide > 0.0) {
            return 1.0;
        }
        let rho = wide / d;
        if rho <= NARROW[0].0 {
            return NARROW[0].1;
        }
        if rho >= 1.0 {
            return 1.0;
        }
        // The table's points about `rho` (beyond its last, 1 at 1).
        let k = NARROW.partition_point(|&(r, _)| r < rho);
        let lo = NARROW[k - 1];
        let hi = NARROW.get(k).copied().unwrap_or((1.0, 1.0));
        // Between the table's points, linear in the logarithms (the
        // factor grows as a power of the ratio where it is small).
        let t = (rho / lo.0).ln() / (hi.0 / lo.0).ln();
        lo.1 * (hi.1 / lo.1).powf(t)
    }

    /// The stencil's read `|D|` (px^-p) about parameter `u`: the finite
    /// difference of order `p + 1` of the curve's points `delta` apart,
    /// along the normal, over `delta^(p + 1)`; `None` where it would cross
    /// a corner or does not fit on the curve.
    fn read(&self, curve: &SplineCurve, u: f64, delta: f64) -> Option<f64> {
        let order = self.p + 1;
        let span = order as f64 * delta;
        let length = curve.param_length();
        let closed = curve.is_closed();
        if span >= length {
            return None;
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
            return None;
        }
        let normal = curve.frame(wrap(u.clamp(start, start + span))).normal;
        // The finite difference of order `p + 1`, binomial weights of
        // alternating sign.
        let (mut dx, mut dy) = (0.0, 0.0);
        for k in 0..=order {
            let q = curve.point(wrap(start + k as f64 * delta));
            let sign = if (order - k).is_multiple_of(2) {
                1.0
            } else {
                -1.0
            };
            let weight = binomial(order, k);
            dx += sign * weight * q[0];
            dy += sign * weight * q[1];
        }
        Some((dx * normal[0] + dy * normal[1]).abs() / delta.powi(order as i32))
    }
}

/// The binomial coefficient `n` choose `k`.
fn binomial(n: usize, k: usize) -> f64 {
    (0..k).fold(1.0, |c, i| c * (n - i) as f64 / (i + 1) as f64)
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::spline::Basis;

    /// The least-squares fit on `basis` (uniform, open) of `f` sampled
    /// every 1/64 of an element, by normal equations on the basis's own
    /// evaluation: the RMS of the residual over the middle half.
    fn least_squares_rms(basis: &Basis, f: impl Fn(f64) -> f64) -> f64 {
        let l = basis.length();
        least_squares_rms_in(basis, f, 0.25 * l, 0.75 * l)
    }

    /// [`least_squares_rms`] over `(lo, hi)`.
    fn least_squares_rms_in(basis: &Basis, f: impl Fn(f64) -> f64, lo: f64, hi: f64) -> f64 {
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
        for &x in xs.iter().filter(|&&x| x > lo && x < hi) {
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

    /// The narrow detail's factor is what least squares leaves: on unit
    /// elements, a sinusoidal offset `cos(k (x - c))`, the RMS error of
    /// the cubic fit within an element of its crest `c` (averaged over
    /// three offsets of the crest to the knots) over
    /// `LEAST_SQUARES_ERROR[3] D(1)`, against the factor the ratio of the
    /// stencil's reads at steps 2 and 1 gives.
    #[test]
    fn fine_detail_is_read_by_the_ratio_of_steps() {
        let paper = Profile::Paper {
            kind: crate::virtual_image::Kind::Silhouette,
        };
        let rep = Representation::new(1.0, 3, paper).unwrap();
        for k in [0.45, 1.0, 1.4, 1.8, 2.2] {
            let (mut error, mut ratio, mut factor) = (0.0, 0.0, 0.0);
            let offsets = [0.0, 0.25, 0.5];
            for offset in offsets {
                let c = 20.0 + offset;
                let f = |x: f64| (k * (x - c)).cos();
                // The largest read about the crest at a step.
                let read = |step: f64| {
                    (0..=512)
                        .map(|i| {
                            let x0 = c - 2.0 + 4.0 * i as f64 / 512.0 - 2.0 * step;
                            let d: f64 = [1.0, -4.0, 6.0, -4.0, 1.0]
                                .iter()
                                .enumerate()
                                .map(|(j, a)| a * f(x0 + j as f64 * step))
                                .sum();
                            d.abs() / step.powi(4)
                        })
                        .fold(0.0, f64::max)
                };
                let (d, wide) = (read(1.0), read(2.0));
                let basis = Basis::new(3, 40, 40.0, false).unwrap();
                let rms = least_squares_rms_in(&basis, f, c - 1.0, c + 1.0);
                error += rms / (LEAST_SQUARES_ERROR[3] * d);
                ratio += wide / d;
                factor += rep.narrow(d, wide);
            }
            let n = offsets.len() as f64;
            let (error, ratio, factor) = (error / n, ratio / n, factor / n);
            println!("k {k}: ratio {ratio:.3}, factor {factor:.2}, least squares {error:.2}");
            assert!(
                (factor / error - 1.0).abs() < 0.05,
                "k {k}: ratio {ratio:.3}, factor {factor:.2} against {error:.2}"
            );
        }
    }

    /// At an open curve's ends the stencils are moved inward, and the read
    /// at step `2h` is about another place than the one at `h`: on a
    /// sine edge crossing a 512 px image (wavelength 300 px, elements of
    /// 39.5 px) the wide read 160 px from an end fell near a zero of `D`
    /// while the narrow one was at a crest, and the smooth sine was
    /// charged as detail far finer than its elements (3.9 times the
    /// asymptote). How fine the detail is must be read where both
    /// stencils are about the same place.
    #[test]
    fn an_open_curves_ends_read_the_detail_where_it_is_read() {
        use crate::curve::SplineCurve;
        use std::f64::consts::TAU;
        let (a, k) = (12.0, TAU / 300.0);
        for phase in [0.0, 1.0, 2.0, 3.0, 4.0, 5.0] {
            let pts: Vec<[f64; 2]> = (0..=5110)
                .map(|i| {
                    let x = i as f64 / 10.0;
                    [x, 256.0 + a * (k * x + phase).sin()]
                })
                .collect();
            let sine = SplineCurve::fit(&pts, false, 3, 2.0).unwrap();
            let h = 39.5;
            let paper = Profile::Paper {
                kind: crate::virtual_image::Kind::Silhouette,
            };
            let rep = Representation::new(h, 3, paper).unwrap();
            let at: Vec<f64> = (0..=250)
                .map(|i| sine.param_length() * i as f64 / 250.0)
                .collect();
            let terms = rep.along(&sine, &at, &vec![0.0; at.len()]);
            // The asymptote at the crests, and what least squares leaves
            // of a sinusoid of `k h = 0.83` over it (1.2).
            let asymptote = LEAST_SQUARES_ERROR[3] * h.powi(4) * a * k.powi(4);
            let worst = terms.iter().fold(0.0f64, |m, &t| m.max(t / asymptote));
            assert!(worst < 1.5, "phase {phase}: {worst:.2} times the asymptote");
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
