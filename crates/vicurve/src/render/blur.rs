//! Separable Gaussian blur, the optical blur of synthetic images.
//!
//! A camera's optics blur the scene and then each pixel integrates the
//! blurred light over its square. Blurring an image whose pixels already
//! integrated the scene ([`gaussian_blur`] on exact coverage) is not the
//! same: the pixel grid samples the coverage, whose kinks are not band
//! limited, and the blur of those samples differs from the blur of the
//! scene by a term that depends on where an edge crosses the pixels. Where
//! an edge runs along a row or a column every pixel shares that phase and
//! the term adds up to hundredths of a pixel in a measured position (the
//! figures are in the commit that brought [`blurred_coverage`], which
//! renders the image a camera records).

use rayon::prelude::*;

use crate::error::{Error, Result};
use crate::image::Image;
use crate::render::coverage::polygon_coverage;

/// Fine samples per pixel and axis of [`blurred_coverage`]: the error of
/// a pixel's value is about `0.02 / (k sigma)^2` of the contrast (on an
/// edge along a column, the worst case; tested), so a blur under
/// [`FINER_BELOW`] px takes twice as many.
const SUPERSAMPLE: usize = 4;
/// See [`SUPERSAMPLE`], pixels.
const FINER_BELOW: f64 = 1.0;
/// Reach of [`gaussian_kernel`], in standard deviations.
const KERNEL_SIGMAS: f64 = 5.0;
/// Fine pixels at most (their coverage is held in memory, 8 bytes each):
/// larger images take fewer fine samples, down to 2 per axis.
const MAX_FINE_PIXELS: usize = 1 << 24;

/// The region bounded by `rings` (as [`polygon_coverage`] takes them) as a
/// `width x height` camera records it through a Gaussian blur of `sigma`
/// px: the fraction of each pixel's light that comes from the region,
/// the blur acting on the scene before the pixel integrates (module docs).
///
/// The coverage is computed exactly on a grid `k` times finer (`k` = 4,
/// 8 under a blur of 1 px, fewer on large images: a pixel is then about
/// `0.02 / (k sigma)^2` of the contrast off), blurred there by a Gaussian
/// of `sigma k` fine pixels, and each pixel is the mean of its `k x k` fine
/// pixels (the two steps as one separable kernel). The scene is rendered
/// on a margin as wide as the kernel around the image, so that the light
/// from beyond the border is the scene's, as in a camera (repeating the
/// border's pixels instead bends an edge that crosses the border within
/// the blur's reach). `sigma <= 0` gives the coverage itself.
///
/// Errors: those of [`polygon_coverage`]; [`Error::InvalidParameter`]
/// unless `sigma <= 1000`.
pub fn blurred_coverage(
    width: usize,
    height: usize,
    rings: &[Vec<[f64; 2]>],
    sigma: f64,
) -> Result<Vec<f64>> {
    if sigma.is_nan() || sigma > 1000.0 {
        return Err(Error::invalid(
            "blur_sigma",
            format!("{sigma} px: must be between 0 and 1000"),
        ));
    }
    if sigma <= 0.0 {
        return polygon_coverage(width, height, rings);
    }
    let mut k = if sigma < FINER_BELOW {
        2 * SUPERSAMPLE
    } else {
        SUPERSAMPLE
    };
    let margin = reach(sigma);
    let (pw, ph) = (width + 2 * margin, height + 2 * margin);
    while k > 2 && (k * k).saturating_mul(pw).saturating_mul(ph) > MAX_FINE_PIXELS {
        k /= 2;
    }
    // Fine pixel `X` has its centre at `(X + 1/2) / k - 1/2 - margin` in
    // pixels.
    let offset = 0.5 * (k as f64 - 1.0) + (k * margin) as f64;
    let fine: Vec<Vec<[f64; 2]>> = rings
        .iter()
        .map(|ring| {
            ring.iter()
                .map(|p| [k as f64 * p[0] + offset, k as f64 * p[1] + offset])
                .collect()
        })
        .collect();
    let (fw, fh) = (pw * k, ph * k);
    let cov = polygon_coverage(fw, fh, &fine)?;
    let (kernel, start) = pixel_kernel(sigma, k);
    // Pixel `x` of the image is pixel `x + margin` of the fine grid's.
    let start = start + (k * margin) as isize;
    // Rows: each fine row to the pixels' columns.
    let mut rows = vec![0.0; fh * width];
    rows.par_chunks_mut(width).enumerate().for_each(|(y, out)| {
        let line = &cov[y * fw..(y + 1) * fw];
        for (x, o) in out.iter_mut().enumerate() {
            let first = (x * k) as isize + start;
            *o = kernel
                .iter()
                .enumerate()
                .map(|(j, w)| w * line[(first + j as isize).clamp(0, fw as isize - 1) as usize])
                .sum();
        }
    });
    // Columns: the fine rows to the pixels' rows.
    let mut out = vec![0.0; width * height];
    out.par_chunks_mut(width).enumerate().for_each(|(y, o)| {
        let first = (y * k) as isize + start;
        for (j, w) in kernel.iter().enumerate() {
            let yy = (first + j as isize).clamp(0, fh as isize - 1) as usize;
            for (v, s) in o.iter_mut().zip(&rows[yy * width..(yy + 1) * width]) {
                *v += w * s;
            }
        }
    });
    Ok(out)
}

/// How far beyond the image [`blurred_coverage`] renders the scene under
/// a blur of `sigma` px: the kernel's reach ([`gaussian_kernel`]'s `5
/// sigma`) and one pixel for the pixel's own width, pixels. A region that
/// should look unbounded (an edge crossing the image) must extend at least
/// this far beyond the image.
pub fn reach(sigma: f64) -> usize {
    if sigma > 0.0 && sigma.is_finite() {
        (KERNEL_SIGMAS * sigma).ceil() as usize + 1
    } else {
        0
    }
}

/// The weights of the fine samples that make one pixel of
/// [`blurred_coverage`], `k` fine samples per pixel: the Gaussian of
/// `sigma k` fine pixels averaged over the pixel's `k` samples. Returns the
/// weights and the offset of the first from the pixel's first fine sample.
fn pixel_kernel(sigma: f64, k: usize) -> (Vec<f64>, isize) {
    let g = gaussian_kernel(sigma * k as f64);
    let radius = (g.len() / 2) as isize;
    let mut weights = vec![0.0; g.len() + k - 1];
    for q in 0..k {
        for (j, w) in g.iter().enumerate() {
            weights[q + j] += w / k as f64;
        }
    }
    (weights, -radius)
}

/// The normalised Gaussian kernel of standard deviation `sigma` px, sampled
/// at integer offsets `-R..=R` with `R = ceil(5 sigma)`; it sums to 1 and is
/// symmetric, so it moves no edge. `[1.0]` (no blur) when `sigma <= 0`
/// or is not finite.
pub fn gaussian_kernel(sigma: f64) -> Vec<f64> {
    if !(sigma > 0.0 && sigma.is_finite()) {
        return vec![1.0];
    }
    let radius = (KERNEL_SIGMAS * sigma).ceil() as usize;
    let mut k: Vec<f64> = (0..=2 * radius)
        .map(|i| {
            let x = i as f64 - radius as f64;
            (-x * x / (2.0 * sigma * sigma)).exp()
        })
        .collect();
    let sum: f64 = k.iter().sum();
    k.iter_mut().for_each(|v| *v /= sum);
    k
}

/// `image` blurred by a Gaussian of standard deviation `sigma` px
/// (separable: rows then columns; the pixels beyond the border repeat the
/// border pixel). `sigma == 0` returns a copy.
///
/// Errors: [`Error::InvalidParameter`] unless `0 <= sigma <= 1000`.
pub fn gaussian_blur(image: &Image, sigma: f64) -> Result<Image> {
    if !(0.0..=1000.0).contains(&sigma) {
        return Err(Error::invalid(
            "blur_sigma",
            format!("{sigma} px: must be between 0 and 1000"),
        ));
    }
    if sigma == 0.0 {
        return Ok(image.clone());
    }
    let (w, h) = (image.width(), image.height());
    let kernel = gaussian_kernel(sigma);
    let radius = (kernel.len() / 2) as isize;
    let src = image.data();
    let clamp = |i: isize, n: usize| i.clamp(0, n as isize - 1) as usize;

    let mut rows = vec![0.0; w * h];
    rows.par_chunks_mut(w).enumerate().for_each(|(y, out)| {
        let line = &src[y * w..(y + 1) * w];
        for (x, o) in out.iter_mut().enumerate() {
            let mut s = 0.0;
            for (k, wk) in kernel.iter().enumerate() {
                s += wk * line[clamp(x as isize + k as isize - radius, w)];
            }
            *o = s;
        }
    });
    let mut out = vec![0.0; w * h];
    out.par_chunks_mut(w).enumerate().for_each(|(y, o)| {
        for (k, wk) in kernel.iter().enumerate() {
            let yy = clamp(y as isize + k as isize - radius, h);
            for (v, s) in o.iter_mut().zip(&rows[yy * w..(yy + 1) * w]) {
                *v += wk * s;
            }
        }
    });
    Image::new(w, h, out)
}
