//! The blur of an edge, estimated from the image, and the shift it causes
//! on curved edges.
//!
//! An imaging system blurs a step edge: with a point spread function of
//! variance `s^2` per axis (optics and pixel area together; an ideal pixel
//! alone gives 1/12 px²), the half-level of a curved step lies `s^2 kappa /
//! 2` from the true boundary, towards the centre of curvature (inside a
//! convex edge, outside a concave one). Every method that locates the
//! half-level, or that matches a profile symmetric about it as the virtual
//! image does, inherits that shift: 6 to 7e-3 px for a blur of 1 px on a
//! disc of radius 80, 0.05 px for a blur of 4 px on a disc of radius 150.
//!
//! The centre line of a blurred curved thin line moves the same way.
//! [`edge_spread`] and [`line_spread`] estimate `s` (and a line's width) from
//! the pixels around a measured curve (least-squares fits of an
//! error-function edge or bar across it), and [`curvature_shift`] is the
//! shift to remove. Images that are not blurred
//! steps, such as the paper's synthetic disc (its profile is a function of
//! the distance to the circle, with no blur), must not be corrected: see
//! [`crate::fit::FitConfig::blur_correction`].

use crate::band::{Band, BandParams};
use crate::curve::SplineCurve;
use crate::interp::Sampler;
use crate::spline::Basis;
use crate::virtual_image::Kind;
use rayon::prelude::*;
use serde::{Deserialize, Serialize};

/// The blur of an edge or a line as estimated by [`edge_spread`] or
/// [`line_spread`].
#[derive(Clone, Copy, Debug, PartialEq, Serialize, Deserialize)]
pub struct EdgeSpread {
    /// Standard deviation `s` of the edge's spread function across the
    /// curve, pixels (the optics' blur and the pixel's own 1/12 px² in
    /// quadrature).
    pub sigma: f64,
    /// Thin lines: the line's full width before blurring, pixels (`None`
    /// for edges).
    pub line_width: Option<f64>,
    /// Fraction of the pixel values' variance the fitted edge explains (1:
    /// a perfect error-function edge). For a line, of the variance the
    /// pixel noise leaves to explain (the noise measured on the band's
    /// pixels themselves): 1 for a noisy but ideal blurred bar.
    pub fit_quality: f64,
    /// Pixels used.
    pub pixels: usize,
}

/// Pixels used by the fits at most (a regular subsample of a larger band).
/// The fits sum them by distance to the curve ([`Binned`]), so their cost
/// is that of the bins, not of the pixels: every pixel of an ordinary band
/// counts, which matters most for a line's blur and width (they trade off
/// along a narrow valley, see [`line_spread`]).
const MAX_PIXELS: usize = 200_000;

/// Band pixels an edge's spread is read from before its band is thinned
/// ([`edge_spread`]): plenty for one spread (the far star's, from half of
/// its 78,000 pixels, moved by 4e-4 px).
const EDGE_PIXELS: usize = 40_000;

/// Width of the distance bins of [`Binned`], pixels: a profile's value at
/// a bin's mean distance stands for its mean over the bin's pixels to
/// `g'' w^2 / 24`, which widens the fitted spread's variance by `w^2 / 12`
/// = 3e-5 px^2 at most, against at least 1/12 px^2 for any edge.
const BIN_WIDTH: f64 = 0.02;

/// Standard normal cumulative distribution.
fn phi_cdf(x: f64) -> f64 {
    0.5 * libm::erfc(-x / std::f64::consts::SQRT_2)
}

/// Estimate the spread `s` of the edge around `curve` (a measured
/// silhouette) from the pixels within `half_width` of it, by fitting
/// `f = A + C Phi(-r / s)` across the curve (`r` the signed distance;
/// `A`, `C` by linear least squares for each `s`, `s` by golden-section
/// search between 0.05 px and `half_width / 3`).
///
/// Returns `None` when the band cannot be built (curve near the border) or
/// holds too few pixels.
pub fn edge_spread(sampler: &Sampler, curve: &SplineCurve, half_width: f64) -> Option<EdgeSpread> {
    // A long edge's band is read on one pixel in two or four (its
    // projection is what the estimate costs): the 8-px band of the far
    // star (`vicurve bench speed`), 78,000 pixels, took 12 ms of its
    // measurement's 150.
    let pixels = 2.0 * half_width * curve.param_length();
    let thin = match pixels / EDGE_PIXELS as f64 {
        x if x > 4.0 => 4,
        x if x > 1.0 => 2,
        _ => 1,
    };
    let data = band_data_where(sampler, curve, (half_width, thin), MAX_PIXELS, |_| true)?;
    let total = spread_about_mean(&data)?;
    let clip = sampler
        .clip_levels()
        .filter(|&(lo, hi)| data.iter().any(|&(_, v)| v <= lo || v >= hi));
    let (s, r0, binned) = match clip {
        None => {
            let binned = Binned::new(&data);
            (best_spread(&binned, half_width), 0.0, binned)
        }
        Some(clip) => censored_spread(&data, clip, half_width),
    };
    Some(EdgeSpread {
        sigma: s,
        line_width: None,
        fit_quality: 1.0 - binned.profile_ssr(|r| phi_cdf(-(r - r0) / s)) / total,
        pixels: data.len(),
    })
}

/// The spread `s` of the best `A + C Phi(-r / s)` through the binned
/// pixels, for a band of `half_width`: golden-section search on `log s`
/// between 0.05 px and `half_width / 3`; 30 steps shrink its interval by
/// 0.618^30 ~ 5e-7.
fn best_spread(binned: &Binned, half_width: f64) -> f64 {
    let ssr = |s: f64| binned.profile_ssr(|r| phi_cdf(-r / s));
    golden(0.05f64.ln(), (half_width / 3.0).max(0.1).ln(), 30, |x| {
        ssr(x.exp())
    })
    .exp()
}

/// Rounds of [`censored_spread`] at most.
const CENSOR_ROUNDS: usize = 6;

/// [`edge_spread`]'s fit on a band some of whose pixels the image's
/// encoding clipped (levels `clip`): as the pixel-edge fit (`correlation`),
/// a clipped pixel counts only where the fitted profile falls short of its
/// clip, all of them left out at first; and the profile's centre `r0` is
/// fitted too, since the coarse stages' curve, which the clip moved, may
/// lie a pixel off the edge. Returns the spread, that centre and the bins
/// of the pixels that count. A saturated backlight at 1.6 times the clip
/// level read as a spread of 1.38 px an edge blurred by 2.17 px, its
/// clipped plateau holding the profile's top down.
fn censored_spread(
    data: &[(f64, f64)],
    (lo, hi): (f64, f64),
    half_width: f64,
) -> (f64, f64, Binned) {
    let fit = |kept: &[(f64, f64)]| {
        let binned = Binned::new(kept);
        let reach = half_width / 3.0;
        let centre = |s: f64| {
            golden(-reach, reach, 24, |r0| {
                binned.profile_ssr(|r| phi_cdf(-(r - r0) / s))
            })
        };
        let ssr = |s: f64| {
            let r0 = centre(s);
            binned.profile_ssr(|r| phi_cdf(-(r - r0) / s))
        };
        let s = golden(0.05f64.ln(), reach.max(0.1).ln(), 30, |x| ssr(x.exp())).exp();
        (s, centre(s), binned)
    };
    let clipped = |v: f64| v <= lo || v >= hi;
    let mut kept: Vec<(f64, f64)> = data.iter().copied().filter(|d| !clipped(d.1)).collect();
    let mut best = fit(&kept);
    for _ in 0..CENSOR_ROUNDS {
        let (s, r0) = (best.0, best.1);
        let Some((_, (a, c))) = best.2.profile_fit(|r| phi_cdf(-(r - r0) / s)) else {
            break;
        };
        let counts = |&(r, v): &(f64, f64)| {
            let g = a + c * phi_cdf(-(r - r0) / s);
            !clipped(v) || (v >= hi && g < hi) || (v <= lo && g > lo)
        };
        let next: Vec<(f64, f64)> = data.iter().copied().filter(counts).collect();
        if next.len() == kept.len() {
            break;
        }
        kept = next;
        best = fit(&kept);
    }
    best
}

/// The integral of `f` over `[lo, hi]` by Simpson's rule on `n`
/// intervals (`n` even): exact for cubics, error `(hi - lo) h^4 f'''' /
/// 180` with `h = (hi - lo) / n`.
pub(crate) fn simpson(lo: f64, hi: f64, n: usize, f: impl Fn(f64) -> f64) -> f64 {
    let h = (hi - lo) / n as f64;
    let sum: f64 = (0..=n)
        .map(|i| {
            let w = if i == 0 || i == n {
                1.0
            } else if i % 2 == 1 {
                4.0
            } else {
                2.0
            };
            w * f(lo + i as f64 * h)
        })
        .sum();
    sum * (hi - lo) / (3.0 * n as f64)
}

/// Minimum of `f` over `[lo, hi]` by golden-section search (`steps`
/// steps); `f` unimodal.
pub(crate) fn golden(lo: f64, hi: f64, steps: usize, f: impl Fn(f64) -> f64) -> f64 {
    let ratio = 0.5 * (5f64.sqrt() - 1.0);
    let (mut lo, mut hi) = (lo, hi);
    let mut x1 = hi - ratio * (hi - lo);
    let mut x2 = lo + ratio * (hi - lo);
    let (mut f1, mut f2) = (f(x1), f(x2));
    for _ in 0..steps {
        if f1 <= f2 {
            hi = x2;
            x2 = x1;
            f2 = f1;
            x1 = hi - ratio * (hi - lo);
            f1 = f(x1);
        } else {
            lo = x1;
            x1 = x2;
            f1 = f2;
            x2 = lo + ratio * (hi - lo);
            f2 = f(x2);
        }
    }
    0.5 * (lo + hi)
}

/// Estimate the blur `s` and the width `w` of a thin line around `curve`
/// (a measured contour) by fitting `f = A + C [Phi((r + w/2)/s) -
/// Phi((r - w/2)/s)]` across it (`A`, `C` by linear least squares; `s` and
/// `w` by nested golden-section searches). For a line much thinner
/// than its blur, `w` and `s` are hard to tell apart (the profile is then
/// a Gaussian of variance `s^2 + w^2 / 12`): the estimate is returned with
/// its fit quality and the caller decides.
pub fn line_spread(sampler: &Sampler, curve: &SplineCurve, half_width: f64) -> Option<EdgeSpread> {
    let data = band_data(sampler, curve, half_width, MAX_PIXELS)?;
    let total = spread_about_mean(&data)?;
    let binned = Binned::new(&data);
    let ssr = |s: f64, w: f64| {
        binned.profile_ssr(|r| phi_cdf((r + 0.5 * w) / s) - phi_cdf((r - 0.5 * w) / s))
    };
    let (s_lo, s_hi) = (0.05f64.ln(), (half_width / 3.0).max(0.1).ln());
    // Nested searches (w outside, s inside): the two trade off against
    // each other along a narrow valley, where alternating searches crawl.
    let best_s = |w: f64| golden(s_lo, s_hi, 18, |x| ssr(x.exp(), w)).exp();
    let valley = |w: f64| ssr(best_s(w), w);
    let w_best = golden(W_MIN, half_width, 18, valley);
    let pixel_noise = noise_variance(&data);
    // What the fit leaves unexplained per pixel, noise or the model's own
    // error (a noiseless image), sets which differences are meaningful.
    let best = valley(w_best);
    let unexplained = pixel_noise.max(best / data.len() as f64);
    let limit = best + VALLEY_CHI2 * unexplained;
    let w = valley_middle(valley, w_best, (W_MIN, half_width), limit);
    let s = best_s(w);
    // The fraction of the variance the noise leaves to explain: a faint
    // line under noise (5 % of the contrast on a line whose blurred peak is
    // a quarter of it) is still a blurred bar, only a noisy one.
    let noise = data.len() as f64 * pixel_noise;
    let explainable = total - noise;
    let fit_quality = if explainable > 0.0 {
        1.0 - (ssr(s, w) - noise).max(0.0) / explainable
    } else {
        0.0
    };
    Some(EdgeSpread {
        sigma: s,
        line_width: Some(w),
        fit_quality,
        pixels: data.len(),
    })
}

/// Narrowest line width [`line_spread`] searches, pixels.
const W_MIN: f64 = 0.05;
/// Widths whose best fit exceeds the best one's residual sum of squares by
/// less than this many times a pixel's unexplained variance (its noise, or
/// what the fit leaves when that is larger) are as likely: a change of
/// chi-square of 4, two standard deviations of one parameter.
const VALLEY_CHI2: f64 = 4.0;
/// Bisection steps that find each end of the widths as likely as the best.
const VALLEY_STEPS: usize = 12;

/// The line width (pixels) in the middle of those around `w_best` whose
/// `ssr` (the residual of the best blur for a width) is at most `limit`
/// (the best's plus [`VALLEY_CHI2`] unexplained variances), searched
/// within `bounds`.
///
/// Why: under a blur wider than the line, the profile is about a Gaussian
/// of variance `s^2 + w^2 / 12`, so the data fix that sum and leave `w`
/// free over a range, where the best `w` is set by the noise and by the
/// model's small errors (the pixel's square, the curve's curvature). The
/// curvature correction takes `s^2`: the middle of the range in `w^2` (in
/// `s^2`) errs by at most half of it, the best one by all of it (tested
/// on noisy rings). Where the width is well determined the range is narrow
/// and its middle is the best width.
fn valley_middle(ssr: impl Fn(f64) -> f64, w_best: f64, bounds: (f64, f64), limit: f64) -> f64 {
    // The end of the range between `inside` (fits) and `outside`.
    let end = |mut inside: f64, mut outside: f64| {
        if ssr(outside) <= limit {
            return outside;
        }
        for _ in 0..VALLEY_STEPS {
            let mid = 0.5 * (inside + outside);
            if ssr(mid) <= limit {
                inside = mid;
            } else {
                outside = mid;
            }
        }
        0.5 * (inside + outside)
    };
    let (lo, hi) = (end(w_best, bounds.0), end(w_best, bounds.1));
    (0.5 * (lo * lo + hi * hi)).sqrt()
}

/// The variance of the pixel noise in `(r, f)` data, without a model of the
/// profile: half the mean squared difference of `f` between pixels
/// neighbouring in `r` (pixels at the same distance from the curve expect
/// the same value; a band of a few thousand pixels puts neighbours a few
/// thousandths of a pixel apart, where the profile does not change).
/// Variation along the curve at equal `r` (texture) counts as noise.
/// `data` sorted by `r`, as [`band_data`] gives it.
pub(crate) fn noise_variance(data: &[(f64, f64)]) -> f64 {
    let pairs = data.len().saturating_sub(1).max(1) as f64;
    let sum: f64 = data.windows(2).map(|p| (p[1].1 - p[0].1).powi(2)).sum();
    0.5 * sum / pairs
}

/// Pixel values summed by distance to the curve, in bins of [`BIN_WIDTH`]:
/// all that a profile fit `f ~ A + C g(r)` needs, in as many terms as there
/// are bins whatever the number of pixels.
pub(crate) struct Binned {
    /// Per non-empty bin: pixels, mean `r`, sum of `f`, sum of `f^2`.
    pub(crate) bins: Vec<[f64; 4]>,
}

impl Binned {
    /// Bin `data`, sorted by `r` ([`band_data`]).
    pub(crate) fn new(data: &[(f64, f64)]) -> Binned {
        Binned::with_width(data, BIN_WIDTH)
    }

    /// Bin `data`, sorted by `r`, in bins `width` pixels wide.
    pub(crate) fn with_width(data: &[(f64, f64)], width: f64) -> Binned {
        let mut bins: Vec<[f64; 4]> = Vec::new();
        let mut current = None;
        for &(r, f) in data {
            let index = (r / width).floor();
            if current != Some(index) {
                current = Some(index);
                bins.push([0.0; 4]);
            }
            if let Some(b) = bins.last_mut() {
                b[0] += 1.0;
                b[1] += r;
                b[2] += f;
                b[3] += f * f;
            }
        }
        for b in &mut bins {
            b[1] /= b[0];
        }
        Binned { bins }
    }

    /// Residual sum of squares of the best `A + C g(r)` through the pixels
    /// (linear least squares in `A`, `C`), `g` taken at each bin's mean
    /// distance.
    fn profile_ssr(&self, g: impl Fn(f64) -> f64) -> f64 {
        self.profile_fit(g).map_or(f64::INFINITY, |(ssr, _)| ssr)
    }

    /// The best `A + C g(r)` through the pixels, as [`Binned::profile_ssr`]:
    /// its residual sum of squares and `(A, C)`; `None` when `g` does not
    /// vary over the bins.
    fn profile_fit(&self, g: impl Fn(f64) -> f64) -> Option<(f64, (f64, f64))> {
        let (mut n, mut sg, mut sgg, mut sf, mut sfg, mut sff) = (0.0, 0.0, 0.0, 0.0, 0.0, 0.0);
        for &[count, r, f, ff] in &self.bins {
            let v = g(r);
            n += count;
            sg += count * v;
            sgg += count * v * v;
            sf += f;
            sfg += f * v;
            sff += ff;
        }
        let det = n * sgg - sg * sg;
        if det.abs() < 1e-300 {
            return None;
        }
        let a = (sgg * sf - sg * sfg) / det;
        let c = (n * sfg - sg * sf) / det;
        Some(((sff - a * sf - c * sfg).max(0.0), (a, c)))
    }
}

/// Sum of squared deviations of the gray levels from their mean (`None`
/// for a flat band).
fn spread_about_mean(data: &[(f64, f64)]) -> Option<f64> {
    let mean = data.iter().map(|d| d.1).sum::<f64>() / data.len() as f64;
    let total: f64 = data.iter().map(|d| (d.1 - mean).powi(2)).sum();
    (total > 0.0).then_some(total)
}

/// `(r, f)` for the pixels within `half_width` of `curve` (at most about
/// `max` of them, a regular subsample), sorted by `r`.
pub(crate) fn band_data(
    sampler: &Sampler,
    curve: &SplineCurve,
    half_width: f64,
    max: usize,
) -> Option<Vec<(f64, f64)>> {
    band_data_where(sampler, curve, (half_width, 1), max, |_| true)
}

/// [`band_data`] of the pixels whose centre `keep` accepts, on a band of
/// `(half_width, thin)` (one pixel in `thin` projected, see
/// [`BandParams::thin`]).
pub(crate) fn band_data_where(
    sampler: &Sampler,
    curve: &SplineCurve,
    band: (f64, usize),
    max: usize,
    keep: impl Fn([f64; 2]) -> bool,
) -> Option<Vec<(f64, f64)>> {
    let data = oriented_band_data_where(sampler, curve, band, max, keep)?;
    Some(data.into_iter().map(|(r, f, _)| (r, f)).collect())
}

/// [`band_data_where`] with the curve's unit normal at each pixel's foot:
/// `(r, f, normal)`, sorted by `r` (pixels of equal `r` in raster order).
pub(crate) fn oriented_band_data_where(
    sampler: &Sampler,
    curve: &SplineCurve,
    (half_width, thin): (f64, usize),
    max: usize,
    keep: impl Fn([f64; 2]) -> bool,
) -> Option<Vec<(f64, f64, [f64; 2])>> {
    let basis = Basis::new(
        1,
        if curve.is_closed() { 2 } else { 1 },
        curve.param_length(),
        curve.is_closed(),
    )
    .ok()?;
    let params = BandParams {
        thin,
        ..BandParams::new(
            half_width,
            Kind::Silhouette,
            sampler.width(),
            sampler.height(),
        )
    };
    let band = Band::distances(curve, &basis, &params).ok()?;
    if band.len() < 50 {
        return None;
    }
    // The band's pixels are pixel centres in the image: their recorded
    // values (what the interpolant returns there).
    let stride = band.len().div_ceil(max).max(1);
    let mut data: Vec<(f64, f64, [f64; 2])> = band
        .iter()
        .step_by(stride)
        .filter(|&&(p, _, _)| keep(p))
        .filter_map(|&(p, r, n)| {
            sampler
                .pixel(p[0] as usize, p[1] as usize)
                .map(|f| (r, f, n))
        })
        .collect();
    // Stable, as `sort_by`: pixels of equal `r` stay in raster order.
    data.par_sort_by(|a, b| a.0.total_cmp(&b.0));
    Some(data)
}

/// The displacement, along the unit normal, from the half-level of a
/// blurred curved edge to the true boundary: `-s^2 kappa / 2` (pixels, with
/// the signed curvature `kappa` of the curve's convention, negative on a
/// convex closed curve whose normal points outward).
pub fn curvature_shift(sigma: f64, curvature: f64) -> f64 {
    -0.5 * sigma * sigma * curvature
}

#[cfg(test)]
mod tests {
    use super::simpson;

    /// Exact for a cubic; `exp` over `[0, 1]` on 16 intervals within the
    /// rule's error bound (`e / 180 / 16^4`, 2.3e-7).
    #[test]
    fn simpson_integrates_cubics_exactly() {
        let cubic = simpson(-1.0, 2.0, 4, |x| x * x * x - 2.0 * x + 1.0);
        assert!((cubic - 3.75).abs() < 1e-12, "{cubic}");
        let e = simpson(0.0, 1.0, 16, f64::exp);
        assert!((e - (std::f64::consts::E - 1.0)).abs() < 2.3e-7, "{e}");
    }
}
