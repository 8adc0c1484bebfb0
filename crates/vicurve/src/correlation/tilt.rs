//! The light's tilt across the band, for the pixel profiles (pushed: an
//! edge's, a thin line's): a factor of the virtual image with varying gray
//! levels, taken out of the pixels' values with the global pair.
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
//! own values, not interpolated ones), with `r_in` past the band and the
//! profile's tail ([`tail_end`]: four blur deviations and 2 px beyond the
//! edge, or beyond a line's side), so that the tail does not pass for a
//! slope; `tau = (beta_in + beta_out) / (alpha_in + alpha_out)`. These
//! estimates are fitted by least squares twice: with one value all along
//! the curve, and with a B-spline basis along `s` (the levels' default
//! elements, whatever the levels' own), kept when it explains more than
//! the constant beyond what noise would. `tau` is held fixed during the
//! iterations (the levels and the displacement are fitted with it). The
//! fitted tilt must exceed what the pixels' noise would put into it (their
//! scatter about the fit, as a chi-square of as many degrees of freedom
//! as functions), or there is no tilt: taken out, a tilt of noise would
//! move the edge by as much as its error. Light tilts both plateaus
//! alike: the two sides' relative tilts (each slope over its plateau's
//! mean), fitted apart, must not differ by more than half the tilt (RMS)
//! beyond what their noise explains, or there is no tilt (a plateau that
//! is not flat for another reason, such as a level in the middle of a
//! quantisation step that the edge's tail tips over, would otherwise pass
//! for light). Where a plateau leaves the image the pixel gives no
//! estimate; without enough of them (or with a `tau` beyond `MAX_TILT`)
//! there is no tilt.

use crate::band::Band;
use crate::buckets::Buckets;
use crate::correlation::levels::LevelBasis;
use crate::interp::Sampler;
use crate::solver::chunked::chunked_sum;
use crate::solver::DenseCholesky;
use crate::virtual_image::Profile;
use rayon::prelude::*;

/// Band pixels within this of the curve (pixels) estimate the tilt: a
/// strip `2 NEAR` px wide, about one pixel per two of the curve's length
/// (each reads `2 PLATEAU_WIDTH / PLATEAU_STEP + 2` pixels), some 60 per
/// function of the basis (128 px elements).
const NEAR: f64 = 0.25;
/// Width of each plateau sampled, pixels: a slope's error falls as the
/// width to the power 1.5, and light changes over tens of pixels. With
/// 4 px, a 30 % vignetting's tilt (0.07 % a pixel across a disc of
/// 150 px, 1 % noise) was read a third short on one seed in three, which
/// left the disc 7e-3 px inside; with 8 px, at most 2.2e-3 px on eight.
const PLATEAU_WIDTH: f64 = 8.0;
/// Spacing of the samples on a plateau, pixels.
const PLATEAU_STEP: f64 = 0.5;
/// Samples on a plateau, from its start to its end.
const PLATEAU_SAMPLES: usize = (PLATEAU_WIDTH / PLATEAU_STEP) as usize + 1;
/// Blur deviations between the edge and the plateau samples (plus
/// `TAIL_MARGIN` px, for the pixels' size and their offset from the
/// normal): the edge's tail must not pass for a slope.
const TAIL_DEVIATIONS: f64 = 4.0;
/// See [`TAIL_DEVIATIONS`], pixels.
const TAIL_MARGIN: f64 = 2.0;
/// The two sides' tilts may differ by this fraction of the tilt (RMS).
const CONSISTENCY: f64 = 0.5;
/// Band pixels within this of the curve (pixels) give the curve's points
/// that plateaus must keep clear of ([`Plateaus::clear`]): about one a
/// pixel along it.
const FOOT_NEAR: f64 = 0.5;
/// How much nearer than its own foot another part of the curve may come
/// to a plateau's end, pixels (the curve's points are about a pixel
/// apart).
const CLEARANCE: f64 = 1.0;
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
    /// Where the profile's tail ends, pixels from the curve
    /// ([`tail_end`]): the plateaus lie beyond it (and the band).
    pub tail: f64,
    /// `tau`'s coefficients in the levels' basis; `None`: no tilt.
    pub coefs: Option<Vec<f64>>,
}

impl Measured {
    /// Whether this measurement serves a band with the levels' basis
    /// `levels` and a profile whose tail ends at `tail` px: the same tail
    /// (a wider blur or line places the plateaus further out) and as many
    /// levels functions.
    pub(crate) fn serves(&self, levels: &LevelBasis, tail: f64) -> bool {
        self.tail == tail && self.coefs.as_ref().is_none_or(|c| c.len() == levels.m())
    }

    /// A tilt measured before (`coefs`) for the pixel profile `profile`;
    /// `None` for a profile without a tilt ([`tail_end`]).
    pub(crate) fn known(profile: Profile, coefs: Option<Vec<f64>>) -> Option<Measured> {
        tail_end(profile).map(|tail| Measured { tail, coefs })
    }
}

/// Where the tail of the pixel profile `profile` ends, pixels from the
/// curve: `TAIL_DEVIATIONS` blur deviations and `TAIL_MARGIN` beyond the
/// edge, or beyond each side of a thin line (its half-width out), so that
/// the tail does not pass for a slope. `None` for the paper's profiles,
/// whose band is their whole extent (no tilt).
pub(crate) fn tail_end(profile: Profile) -> Option<f64> {
    let (blur, half_line) = match profile {
        Profile::PixelEdge { blur, .. } => (blur, 0.0),
        Profile::PixelLine { blur, width } => (blur, 0.5 * width),
        Profile::Paper { .. } => return None,
    };
    Some(half_line + TAIL_DEVIATIONS * blur + TAIL_MARGIN)
}

/// `tau`'s coefficients in the levels' basis (module docs), `None` when it
/// cannot be measured. `tail`: where the profile's tail ends, pixels
/// ([`tail_end`]).
pub(crate) fn estimate(band: &Band, sampler: &Sampler, levels: &LevelBasis, tail: f64) -> Measured {
    Measured {
        tail,
        coefs: coefficients(band, sampler, levels, tail),
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
    tail: f64,
) -> Option<Vec<f64>> {
    let r_in = (band.half_width() + 0.5).max(tail);
    let plateaus = Plateaus::new(band, r_in);
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
                let Some(taus) = pixel_tilts(&plateaus, sampler, i) else {
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
    let n = used.len() as f64;
    // The same tilt all along the curve: the pixels' mean (the basis sums
    // to one, so these are its coefficients too).
    let mut mean = [0.0; 3];
    for (_, raw) in &used {
        mean.iter_mut().zip(raw).for_each(|(a, r)| *a += r / n);
    }
    let along = Fit::of(&used, m, |i| {
        let at = |coefs: &[f64]| levels.value(i, coefs);
        [at(&rhs[0]), at(&rhs[1]), at(&rhs[2])]
    });
    let constant = Fit::of(&used, 1, |_| mean);
    // The tilt that changes along the curve when it explains more than
    // the constant one beyond what noise would; else the constant one. A
    // tilt the light makes everywhere alike (vignetting about the object,
    // a lamp's fall-off) is measured on all the pixels at once: through
    // the functions one by one it may not stand out of their noise, and
    // left out it moves the whole edge (1.7e-2 px for a disc of 150 px
    // blurred by 2 px, corners 30 % darker, at 1 % noise).
    let varies =
        m > 1 && constant.residual - along.residual > along.by_noise(along.residual, m - 1);
    let [coefs, _, _] = rhs;
    match varies {
        true => along.is_light().then_some(coefs),
        false => constant.is_light().then(|| vec![mean[0]; m]),
    }
}

/// Where the plateaus lie: from `r_in` px out, and
/// the curve's points (the feet of the band pixels near it) to tell
/// whether a plateau stays clear of the curve's other parts.
struct Plateaus<'a> {
    band: &'a Band,
    r_in: f64,
    feet: Vec<[f64; 2]>,
    buckets: Buckets,
}

impl<'a> Plateaus<'a> {
    fn new(band: &'a Band, r_in: f64) -> Plateaus<'a> {
        let feet: Vec<[f64; 2]> = (0..band.len())
            .filter(|&i| band.r[i].abs() <= FOOT_NEAR)
            .map(|i| {
                let ([x, y], [nx, ny], r) = (band.pos[i], band.normal[i], band.r[i]);
                [x - r * nx, y - r * ny]
            })
            .collect();
        let reach = r_in + PLATEAU_WIDTH;
        let buckets = Buckets::new(feet.iter().copied(), reach);
        Plateaus {
            band,
            r_in,
            feet,
            buckets,
        }
    }

    /// Whether the plateau from `foot` along the unit vector `dir` ends
    /// nearer its own foot than any other part of the curve (by
    /// `CLEARANCE` px): beyond a bay's or a lobe's centre of curvature, or
    /// past a corner, it would read the other side of another edge.
    fn clear(&self, foot: [f64; 2], dir: [f64; 2]) -> bool {
        let reach = self.r_in + PLATEAU_WIDTH;
        let end = [foot[0] + reach * dir[0], foot[1] + reach * dir[1]];
        self.buckets
            .within(|k| self.feet[k], end, reach - CLEARANCE)
            .next()
            .is_none()
    }
}

/// A tilt fitted to the pixels' estimates: its sums of squares over the
/// pixels, of both sides' tilt and of the two sides' difference, and
/// what the estimates leave about them (their noise).
struct Fit {
    /// Pixels.
    n: f64,
    /// Functions of the fit.
    m: usize,
    /// Sums of squares of the fitted tilt and of the sides' difference.
    both: f64,
    diff: f64,
    /// The pixels' estimates about them.
    residual: f64,
    residual_diff: f64,
}

impl Fit {
    /// The sums of the fit whose `[both, outer, inner]` tilts at pixel `i`
    /// are `at(i)`, with `m` functions, over the pixels `used`.
    fn of(used: &[(usize, [f64; 3])], m: usize, at: impl Fn(usize) -> [f64; 3]) -> Fit {
        let mut f = Fit {
            n: used.len() as f64,
            m,
            both: 0.0,
            diff: 0.0,
            residual: 0.0,
            residual_diff: 0.0,
        };
        for &(i, [raw, raw_out, raw_in]) in used {
            let [t, t_out, t_in] = at(i);
            f.diff += (t_out - t_in).powi(2);
            f.both += t * t;
            f.residual_diff += (raw_out - raw_in - (t_out - t_in)).powi(2);
            f.residual += (raw - t).powi(2);
        }
        f
    }

    /// What noise alone puts into `dof` fitted functions' sum of squares
    /// over the pixels, given the estimates' `residual` about this fit:
    /// the variance of one pixel's estimate times a chi-square of `dof`
    /// degrees of freedom, here its mean and 5 standard deviations, and
    /// at least 25 (5 standard deviations of one function: with the
    /// chi-square's own, 2.8 for a single one, 15 of the conformance
    /// sweep's 664 images under even light had a tilt of noise taken out;
    /// with 5, 4).
    fn by_noise(&self, residual: f64, dof: usize) -> f64 {
        let d = dof as f64;
        let chi2 = (d + NOISE_SDS * (2.0 * d).sqrt()).max(NOISE_SDS * NOISE_SDS);
        residual / (self.n - self.m as f64) * chi2
    }

    /// Whether the fitted tilt is the light's: beyond what the noise could
    /// have made (taken out, a tilt of noise would move the edge by as
    /// much as its error), and alike on both sides. Light tilts both
    /// sides alike (relatively): a difference that exceeds half the tilt
    /// by more than the noise explains (the dark side's relative tilt is
    /// the noisier) is something else (a plateau that is not flat, a
    /// level at a quantisation step's middle). Noise that merely makes the
    /// difference look larger does not (at 1 % noise, a disc's dark side
    /// read a 30 % vignetting's tilt half as large as its bright side did,
    /// and the tilt was left out). NaN sums are no tilt.
    fn is_light(&self) -> bool {
        let significant = self.both > self.by_noise(self.residual, self.m);
        let beyond = self.diff.sqrt() - self.by_noise(self.residual_diff, self.m).sqrt();
        let consistent = beyond <= CONSISTENCY * self.both.sqrt();
        significant && consistent
    }
}

/// The three relative tilts `[both sides, outer side, inner side]`
/// estimated at band pixel `i` (module docs), or `None` when it is not near
/// the curve, or a plateau leaves the image or comes near another part
/// of the curve.
fn pixel_tilts(plateaus: &Plateaus, sampler: &Sampler, i: usize) -> Option<[f64; 3]> {
    let Plateaus { band, r_in, .. } = *plateaus;
    let r0 = band.r[i];
    if r0.abs() > NEAR {
        return None;
    }
    let [x, y] = band.pos[i];
    let [nx, ny] = band.normal[i];
    let foot = [x - r0 * nx, y - r0 * ny];
    let side = |sign: f64| -> Option<(f64, f64, f64)> {
        if !plateaus.clear(foot, [sign * nx, sign * ny]) {
            return None;
        }
        // Least-squares line v = alpha + beta r over the plateau, and its
        // mean.
        let (mut s1, mut sr, mut srr, mut sv, mut srv) = (0.0, 0.0, 0.0, 0.0, 0.0);
        for k in 0..PLATEAU_SAMPLES {
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
        (det > 0.0).then(|| {
            let mean = sv / s1;
            (
                (srr * sv - sr * srv) / det,
                (s1 * srv - sr * sv) / det,
                mean,
            )
        })
    };
    let (Some((a_out, b_out, m_out)), Some((a_in, b_in, m_in))) = (side(1.0), side(-1.0)) else {
        return None;
    };
    let level = a_out + a_in;
    if level == 0.0 || m_out == 0.0 || m_in == 0.0 {
        return None;
    }
    // Each side's own relative tilt is its slope over the plateau's mean,
    // not over its level extrapolated to the edge: that level's error is
    // the slope's times the plateau's distance, and their ratio would
    // lean with the noise (a dark side at 1 % noise, by 1.1 to 2.8 times
    // a 30 % vignetting's tilt on three seeds), failing the sides'
    // agreement. The two sides' errors cancel, to first order, in the
    // sum's ratio.
    Some([(b_out + b_in) / level, b_out / m_out, b_in / m_in])
}
