//! The light's tilt across the band, for the pixel-edge profile (pushed):
//! a factor of the virtual image with varying gray levels, taken out of
//! the pixels' values with the global pair.
//!
//! Uneven light does not only change the levels along the curve: across
//! it, each plateau slopes too. With the light `L` varying smoothly, the
//! image near the edge is `(a + c gamma(r)) (1 + tau r)` with `tau = dL/dr
//! / L` the light's relative slope along the normal, one function of `s`
//! for both sides (the reflectances differ, the light is the same). Left
//! out, the slope biases a blurred edge, whose band is wider: a disc under
//! light changing by +-35 % across it, blurred by 1.5 px, comes out
//! 5e-3 px inside on average (4e-2 px at worst); with light constant along
//! each normal, 2e-4 px.
//!
//! `tau` is measured on the plateaus beyond the band, where the virtual
//! image is flat: on each side of every band pixel near the curve
//! (`|r| <= NEAR` px), a line `alpha + beta r` is fitted to the pixels
//! nearest the normal from `r_in` to `r_in + PLATEAU_WIDTH` px out (their
//! own values, not interpolated ones), with `r_in` past the band and
//! four blur deviations and 2 px, so that the edge's tail does not pass
//! for a slope; `tau = (beta_in + beta_out) / (alpha_in + alpha_out)`. These
//! estimates are fitted by least squares with a B-spline basis along `s`
//! (the levels' default elements, whatever the levels' own), and `tau` is
//! held fixed during the iterations (the levels and the displacement are
//! fitted with it). The fitted tilt must exceed what the pixels' noise
//! would put into it (their scatter about the fit, as a chi-square of as
//! many degrees of freedom as functions), or there is no tilt: taken out,
//! a tilt of noise would move the edge by as much as its error. Light
//! tilts both plateaus alike: the two sides' tilts, fitted apart, must
//! agree within half the tilt (RMS) or within what their noise explains,
//! or there is no tilt (a plateau that is not flat for another reason,
//! such as a level in the middle of a quantisation step that the edge's
//! tail tips over, would otherwise pass for light). Where a plateau leaves
//! the image the pixel gives no estimate; without enough of them (or with
//! a `tau` beyond `MAX_TILT`) there is no tilt.

use crate::band::Band;
use crate::correlation::levels::LevelBasis;
use crate::interp::Sampler;
use crate::solver::chunked::chunked_sum;
use crate::solver::DenseCholesky;
use rayon::prelude::*;

/// Band pixels within this of the curve (pixels) estimate the tilt: a
/// strip `2 NEAR` px wide, about one pixel per two of the curve's length
/// (each reads `2 PLATEAU_WIDTH / PLATEAU_STEP + 2` pixels), some 60 per
/// function of the basis (128 px elements).
const NEAR: f64 = 0.25;
/// Width of each plateau sampled, pixels.
const PLATEAU_WIDTH: f64 = 4.0;
/// Spacing of the samples on a plateau, pixels.
const PLATEAU_STEP: f64 = 0.5;
/// Blur deviations between the edge and the plateau samples (plus
/// `TAIL_MARGIN` px, for the pixels' size and their offset from the
/// normal): the edge's tail must not pass for a slope.
const TAIL_DEVIATIONS: f64 = 4.0;
/// See [`TAIL_DEVIATIONS`], pixels.
const TAIL_MARGIN: f64 = 2.0;
/// The two sides' tilts may differ by this fraction of the tilt (RMS).
const CONSISTENCY: f64 = 0.5;
/// A relative slope beyond this (1/px, 5 % per pixel) is not light.
const MAX_TILT: f64 = 0.05;
/// Standard deviations of the noise's chi-square beyond its mean that a
/// tilt, and the two sides' difference, must exceed to count as such.
const NOISE_SDS: f64 = 5.0;

/// A tilt as [`estimate`] measured it, kept for the next references of a
/// stage: the light does not change when the reference moves a fraction of
/// a pixel, so they evaluate it ([`at_pixels`]) instead of measuring it
/// again.
#[derive(Clone, Debug, PartialEq)]
pub(crate) struct Measured {
    /// The edge's blur the plateaus were placed with, pixels.
    pub blur: f64,
    /// `tau`'s coefficients in the levels' basis; `None`: no tilt.
    pub coefs: Option<Vec<f64>>,
}

impl Measured {
    /// Whether this measurement serves a band with the levels' basis
    /// `levels` and the edge's `blur`: the same blur (a wider one places
    /// the plateaus further out) and as many levels functions.
    pub(crate) fn serves(&self, levels: &LevelBasis, blur: f64) -> bool {
        self.blur == blur && self.coefs.as_ref().is_none_or(|c| c.len() == levels.m())
    }
}

/// `tau`'s coefficients in the levels' basis (module docs), `None` when it
/// cannot be measured. `blur` is the edge's blur (pixels).
pub(crate) fn estimate(band: &Band, sampler: &Sampler, levels: &LevelBasis, blur: f64) -> Measured {
    Measured {
        blur,
        coefs: coefficients(band, sampler, levels, blur),
    }
}

/// `tau` at every band pixel of the levels' basis `levels` (its pixels are
/// the band's), from its coefficients; `None` when it is not finite or
/// beyond `MAX_TILT` somewhere (not light).
pub(crate) fn at_pixels(levels: &LevelBasis, coefs: &[f64]) -> Option<Vec<f64>> {
    let tilt: Vec<f64> = (0..levels.first.len())
        .into_par_iter()
        .map(|i| levels.value(i, coefs))
        .collect();
    tilt.iter()
        .all(|t: &f64| t.is_finite() && t.abs() <= MAX_TILT)
        .then_some(tilt)
}

/// The coefficients of [`estimate`].
fn coefficients(
    band: &Band,
    sampler: &Sampler,
    levels: &LevelBasis,
    blur: f64,
) -> Option<Vec<f64>> {
    let r_in = (band.half_width() + 0.5).max(TAIL_DEVIATIONS * blur + TAIL_MARGIN);
    let count = (PLATEAU_WIDTH / PLATEAU_STEP).round() as usize + 1;
    let m = levels.m();
    let width = levels.width();
    // Right-hand sides of the three fits: both sides together, the outer
    // side alone, the inner side alone. Accumulated over fixed chunks of
    // pixels in parallel (`solver::chunked`).
    let sums = chunked_sum(
        band.len(),
        |range| {
            let mut mat = vec![0.0; m * m];
            let mut rhs = [vec![0.0; m], vec![0.0; m], vec![0.0; m]];
            let mut used = Vec::new();
            for i in range {
                let Some(taus) = pixel_tilts(band, sampler, i, r_in, count) else {
                    continue;
                };
                let first = levels.first[i] as usize;
                let vals = &levels.vals[i * width..(i + 1) * width];
                for (k, vk) in vals.iter().enumerate() {
                    let jk = levels.basis.index(first, k);
                    for (r, t) in rhs.iter_mut().zip(taus) {
                        r[jk] += vk * t;
                    }
                    for (l, vl) in vals.iter().enumerate() {
                        mat[jk * m + levels.basis.index(first, l)] += vk * vl;
                    }
                }
                used.push((i, taus));
            }
            (mat, rhs, used)
        },
        |t, mut part| {
            t.0.iter_mut().zip(&part.0).for_each(|(a, b)| *a += b);
            for (r, q) in t.1.iter_mut().zip(&part.1) {
                r.iter_mut().zip(q).for_each(|(a, b)| *a += b);
            }
            t.2.append(&mut part.2);
        },
    );
    let (mat, mut rhs, used) = sums?;
    // At least a few estimates per function of the basis.
    if used.len() < 4 * m {
        return None;
    }
    let factor = DenseCholesky::factor(&mat, m).ok()?;
    rhs.iter_mut().for_each(|r| factor.solve_in_place(r));
    let at = |coefs: &[f64], i: usize| levels.value(i, coefs);
    // The fitted tilt and the two sides' difference over the pixels, and
    // what the pixels' own estimates leave about them (their noise).
    let (mut diff, mut both, mut noise_diff, mut noise_both) = (0.0, 0.0, 0.0, 0.0);
    for &(i, [raw, raw_out, raw_in]) in &used {
        let (t, t_out, t_in) = (at(&rhs[0], i), at(&rhs[1], i), at(&rhs[2], i));
        diff += (t_out - t_in).powi(2);
        both += t * t;
        noise_diff += (raw_out - raw_in - (t_out - t_in)).powi(2);
        noise_both += (raw - t).powi(2);
    }
    // What noise alone puts into a fitted function's sum of squares over
    // the pixels: the variance of one pixel's estimate times a chi-square
    // of `m` degrees of freedom, here its mean and 5 standard deviations.
    let (n, mf) = (used.len() as f64, m as f64);
    let by_noise = |residual: f64| residual / (n - mf) * (mf + NOISE_SDS * (2.0 * mf).sqrt());
    // A tilt the noise could have made is none: taken out, it would move
    // the edge by as much as its error.
    let significant = both > by_noise(noise_both);
    // Light tilts both sides alike (relatively): a difference as large as
    // half the tilt, and beyond what the noise explains (the dark side's
    // relative tilt is the noisier), is something else (a plateau that is
    // not flat, a level at a quantisation step's middle), and then there
    // is no tilt.
    let consistent = diff <= CONSISTENCY * CONSISTENCY * both || diff <= by_noise(noise_diff);
    // (NaN sums give no tilt.)
    let [coefs, _, _] = rhs;
    (significant && consistent).then_some(coefs)
}

/// The three relative tilts `[both sides, outer side, inner side]`
/// estimated at band pixel `i` (module docs), or `None` when it is not near
/// the curve or a plateau leaves the image. `r_in`: where the plateau
/// samples start, pixels; `count`: samples per plateau.
fn pixel_tilts(
    band: &Band,
    sampler: &Sampler,
    i: usize,
    r_in: f64,
    count: usize,
) -> Option<[f64; 3]> {
    let r0 = band.r[i];
    if r0.abs() > NEAR {
        return None;
    }
    let [x, y] = band.pos[i];
    let [nx, ny] = band.normal[i];
    let foot = [x - r0 * nx, y - r0 * ny];
    let side = |sign: f64| -> Option<(f64, f64)> {
        // Least-squares line v = alpha + beta r over the plateau.
        let (mut s1, mut sr, mut srr, mut sv, mut srv) = (0.0, 0.0, 0.0, 0.0, 0.0);
        for k in 0..count {
            let t = sign * (r_in + k as f64 * PLATEAU_STEP);
            // The nearest pixel centre: between centres the cubic
            // interpolant rings after the edge (by ~0.27^d of the
            // contrast at d px), which would pass for a slope.
            let (px, py) = ((foot[0] + t * nx).round(), (foot[1] + t * ny).round());
            let r = (px - foot[0]) * nx + (py - foot[1]) * ny;
            if px < 0.0 || py < 0.0 {
                return None;
            }
            let v = sampler.pixel(px as usize, py as usize)?;
            s1 += 1.0;
            sr += r;
            srr += r * r;
            sv += v;
            srv += r * v;
        }
        let det = s1 * srr - sr * sr;
        (det > 0.0).then(|| ((srr * sv - sr * srv) / det, (s1 * srv - sr * sv) / det))
    };
    let (Some((a_out, b_out)), Some((a_in, b_in))) = (side(1.0), side(-1.0)) else {
        return None;
    };
    let level = a_out + a_in;
    if level == 0.0 || a_out == 0.0 || a_in == 0.0 {
        return None;
    }
    Some([(b_out + b_in) / level, b_out / a_out, b_in / a_in])
}
