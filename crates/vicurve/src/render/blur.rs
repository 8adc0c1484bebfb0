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
use crate::virtual_image::Anisotropy;

/// Fine samples per pixel and axis of [`blurred_coverage`]: the error of
/// a pixel's value is about `0.02 / (k sigma)^2` of the contrast (on an
/// edge along a column, the worst case; tested), so a blur under
/// [`FINER_BELOW`] px takes twice as many.
const SUPERSAMPLE: usize = 4;
/// See [`SUPERSAMPLE`], pixels.
const FINER_BELOW: f64 = 1.0;
/// See [`selling`].
const SELLING_FLOOR: f64 = 1e-6;
/// Steps of [`selling`] at most.
const SELLING_STEPS: usize = 1000;
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
    blurred_coverage_xy(width, height, rings, (sigma, sigma))
}

/// [`blurred_coverage`] through a Gaussian blur of standard deviations
/// `(sigma_x, sigma_y)` px along the rows and along the columns: an
/// astigmatic lens whose axes are the pixel grid's (its covariance is
/// `diag(sigma_x², sigma_y²)`). Both at most 1000; a blur of 0 along one
/// axis leaves that axis sharp.
///
/// Errors: those of [`blurred_coverage`].
pub fn blurred_coverage_xy(
    width: usize,
    height: usize,
    rings: &[Vec<[f64; 2]>],
    (sigma_x, sigma_y): (f64, f64),
) -> Result<Vec<f64>> {
    for sigma in [sigma_x, sigma_y] {
        if sigma.is_nan() || sigma > 1000.0 {
            return Err(Error::invalid(
                "blur_sigma",
                format!("{sigma} px: must be between 0 and 1000"),
            ));
        }
    }
    if sigma_x <= 0.0 && sigma_y <= 0.0 {
        return polygon_coverage(width, height, rings);
    }
    let (small, large) = (sigma_x.min(sigma_y), sigma_x.max(sigma_y));
    let mut k = if small < FINER_BELOW {
        2 * SUPERSAMPLE
    } else {
        SUPERSAMPLE
    };
    let margin = reach(large);
    let (pw, ph) = (width + 2 * margin, height + 2 * margin);
    while k > 2 && (k * k).saturating_mul(pw).saturating_mul(ph) > MAX_FINE_PIXELS {
        k /= 2;
    }
    let (fw, fh) = (pw * k, ph * k);
    let cov = fine_coverage(rings, (fw, fh), k, margin)?;
    // Pixel `x` of the image is pixel `x + margin` of the fine grid's.
    let kernel_of = |sigma: f64| {
        let (kernel, start) = pixel_kernel(sigma, k);
        (kernel, start + (k * margin) as isize)
    };
    let (kernel_x, start_x) = kernel_of(sigma_x);
    // Rows: each fine row to the pixels' columns.
    let mut rows = vec![0.0; fh * width];
    rows.par_chunks_mut(width).enumerate().for_each(|(y, out)| {
        let line = &cov[y * fw..(y + 1) * fw];
        for (x, o) in out.iter_mut().enumerate() {
            let first = (x * k) as isize + start_x;
            *o = kernel_x
                .iter()
                .enumerate()
                .map(|(j, w)| w * line[(first + j as isize).clamp(0, fw as isize - 1) as usize])
                .sum();
        }
    });
    // Columns: the fine rows to the pixels' rows.
    let (kernel_y, start_y) = kernel_of(sigma_y);
    let mut out = vec![0.0; width * height];
    out.par_chunks_mut(width).enumerate().for_each(|(y, o)| {
        let first = (y * k) as isize + start_y;
        for (j, w) in kernel_y.iter().enumerate() {
            let yy = (first + j as isize).clamp(0, fh as isize - 1) as usize;
            for (v, s) in o.iter_mut().zip(&rows[yy * width..(yy + 1) * width]) {
                *v += w * s;
            }
        }
    });
    Ok(out)
}

/// [`blurred_coverage`] through a Gaussian blur of any covariance: the
/// isotropic `blur` (px, the mean deviation over the directions) with
/// `anisotropy` (its covariance `blur² I + [[p, q], [q, -p]]`, px²; see
/// [`Anisotropy`]), such as motion along a slanted direction.
///
/// The covariance on the fine grid is split (Selling's decomposition) into
/// three non-negative multiples of `e eᵀ` for integer directions `e` of the
/// grid, and the coverage blurred by a sampled Gaussian along each (steps
/// of `e` land on fine pixels: no interpolation), then averaged over each
/// pixel's `k x k` fine pixels. `k` is 4 (8 when the blur's smallest
/// deviation is under 1 px). A blur of zero in one direction leaves it
/// sharp. For a small patch (the corners' check): a full image takes `k²`
/// times its size in memory.
///
/// Errors: those of [`blurred_coverage`]; [`Error::InvalidParameter`] for
/// a covariance that is not positive semi-definite.
pub fn blurred_coverage_anisotropic(
    width: usize,
    height: usize,
    rings: &[Vec<[f64; 2]>],
    (blur, anisotropy): (f64, Anisotropy),
) -> Result<Vec<f64>> {
    if anisotropy.is_none() {
        return blurred_coverage(width, height, rings, blur);
    }
    let mean = blur * blur;
    let amplitude = anisotropy.amplitude();
    if !(mean.is_finite()
        && amplitude.is_finite()
        && amplitude <= mean * (1.0 + 1e-9)
        && mean <= 1e6)
    {
        return Err(Error::invalid(
            "blur",
            format!("{blur} px with {anisotropy}: not a covariance"),
        ));
    }
    let smallest = (mean - amplitude).max(0.0).sqrt();
    let k = if smallest < FINER_BELOW {
        2 * SUPERSAMPLE
    } else {
        SUPERSAMPLE
    };
    let margin = reach((mean + amplitude).sqrt());
    let (pw, ph) = (width + 2 * margin, height + 2 * margin);
    let (fw, fh) = (pw * k, ph * k);
    let mut cov = fine_coverage(rings, (fw, fh), k, margin)?;
    let kk = (k * k) as f64;
    let covariance = [
        kk * (mean + anisotropy.p),
        kk * anisotropy.q,
        kk * (mean - anisotropy.p),
    ];
    for (direction, variance) in selling(covariance) {
        cov = blur_along(&cov, (fw, fh), direction, variance);
    }
    // Each pixel: the mean of its k x k fine pixels.
    let mut out = vec![0.0; width * height];
    out.par_chunks_mut(width).enumerate().for_each(|(y, row)| {
        for (x, o) in row.iter_mut().enumerate() {
            let (fx, fy) = ((x + margin) * k, (y + margin) * k);
            let mut sum = 0.0;
            for j in 0..k {
                let line = &cov[(fy + j) * fw + fx..(fy + j) * fw + fx + k];
                sum += line.iter().sum::<f64>();
            }
            *o = sum / kk;
        }
    });
    Ok(out)
}

/// The exact coverage of the region bounded by `rings` on the `fw x fh`
/// grid `k` times finer than the pixels, which reaches `margin` pixels
/// beyond the image: fine pixel `X` has its centre at `(X + 1/2) / k - 1/2
/// - margin` in pixels. Errors: those of [`polygon_coverage`].
fn fine_coverage(
    rings: &[Vec<[f64; 2]>],
    (fw, fh): (usize, usize),
    k: usize,
    margin: usize,
) -> Result<Vec<f64>> {
    let offset = 0.5 * (k as f64 - 1.0) + (k * margin) as f64;
    let fine: Vec<Vec<[f64; 2]>> = rings
        .iter()
        .map(|ring| {
            ring.iter()
                .map(|p| [k as f64 * p[0] + offset, k as f64 * p[1] + offset])
                .collect()
        })
        .collect();
    polygon_coverage(fw, fh, &fine)
}

/// Selling's decomposition of the positive semi-definite `[[a, b], [b,
/// c]]` (given as `[a, b, c]`): three integer directions `e` and
/// non-negative weights `w` with `sum w e eᵀ` the matrix. From the
/// superbase `(1, 0), (0, 1), (-1, -1)`, a pair `e_i, e_j` with `e_i' M
/// e_j > 0` becomes `-e_i, e_j` (the third `e_k + 2 e_i`) until none is
/// left; then the weights are `-e_i' M e_j` on the direction
/// perpendicular to the third vector `e_k`. A singular matrix (a motion
/// blur) along a direction the grid does not hold would need ever longer
/// directions: `SELLING_FLOOR` of its trace is added to its diagonal
/// first, a blur of a thousandth of its size across.
fn selling([a, b, c]: [f64; 3]) -> Vec<([i64; 2], f64)> {
    let floor = SELLING_FLOOR * (a + c);
    let (a, c) = (a + floor, c + floor);
    let form = |u: [i64; 2], v: [i64; 2]| {
        let (u, v) = ([u[0] as f64, u[1] as f64], [v[0] as f64, v[1] as f64]);
        a * u[0] * v[0] + b * (u[0] * v[1] + u[1] * v[0]) + c * u[1] * v[1]
    };
    let mut e = [[1i64, 0], [0, 1], [-1, -1]];
    // Each step lowers `sum |e_i|_M^2`; a covariance as elongated as the
    // floor allows takes a few dozen.
    for _ in 0..SELLING_STEPS {
        let pair = [(0, 1), (0, 2), (1, 2)]
            .into_iter()
            .find(|&(i, j)| form(e[i], e[j]) > 1e-12 * (a + c));
        let Some((i, j)) = pair else { break };
        let kth = 3 - i - j;
        e[kth] = [e[kth][0] + 2 * e[i][0], e[kth][1] + 2 * e[i][1]];
        e[i] = [-e[i][0], -e[i][1]];
    }
    [(0, 1), (0, 2), (1, 2)]
        .into_iter()
        .map(|(i, j)| {
            let kth = e[3 - i - j];
            ([-kth[1], kth[0]], (-form(e[i], e[j])).max(0.0))
        })
        .filter(|&(_, w)| w > 0.0)
        .collect()
}

/// `image` (`w x h`) blurred along the integer direction `d` by a sampled
/// Gaussian of variance `variance` in steps of `d` (the pixels beyond the
/// border repeat the border's).
fn blur_along(image: &[f64], (w, h): (usize, usize), d: [i64; 2], variance: f64) -> Vec<f64> {
    let kernel = gaussian_kernel(variance.sqrt());
    let radius = (kernel.len() / 2) as i64;
    let mut out = vec![0.0; w * h];
    out.par_chunks_mut(w).enumerate().for_each(|(y, row)| {
        for (x, o) in row.iter_mut().enumerate() {
            *o = kernel
                .iter()
                .enumerate()
                .map(|(t, weight)| {
                    let t = t as i64 - radius;
                    let xx = (x as i64 + t * d[0]).clamp(0, w as i64 - 1) as usize;
                    let yy = (y as i64 + t * d[1]).clamp(0, h as i64 - 1) as usize;
                    weight * image[yy * w + xx]
                })
                .sum();
        }
    });
    out
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

#[cfg(test)]
mod tests {
    use super::selling;
    use proptest::prelude::*;

    proptest! {
        /// Selling's decomposition rebuilds any positive semi-definite
        /// matrix from non-negative weights on integer directions, singular
        /// ones (a motion blur) included.
        #[test]
        fn selling_rebuilds_the_matrix(
            major in 0.0f64..50.0,
            ratio in prop_oneof![Just(0.0f64), 0.0f64..1.0],
            angle in 0.0f64..std::f64::consts::PI,
        ) {
            let minor = major * ratio;
            let (c, s) = (angle.cos(), angle.sin());
            let m = [
                major * c * c + minor * s * s,
                (major - minor) * c * s,
                major * s * s + minor * c * c,
            ];
            let parts = selling(m);
            let mut sum = [0.0; 3];
            for (e, w) in &parts {
                prop_assert!(*w >= 0.0);
                let (x, y) = (e[0] as f64, e[1] as f64);
                sum[0] += w * x * x;
                sum[1] += w * x * y;
                sum[2] += w * y * y;
            }
            for k in 0..3 {
                // The floor: 1e-6 of the trace on the diagonal. Checked to
                // 1e-8 of the trace: a singular matrix near a rational
                // direction takes directions ~200 long, whose weights come
                // from a cancellation in the form (5e-8 on a trace of 42).
                let floor = if k == 1 { 0.0 } else { 1e-6 * (m[0] + m[2]) };
                prop_assert!((sum[k] - m[k] - floor).abs() <= 1e-8 * (1.0 + major), "{m:?} {parts:?}");
            }
        }
    }
}
