//! Separable Gaussian blur, the optical blur of synthetic images.

use rayon::prelude::*;

use crate::error::{Error, Result};
use crate::image::Image;

/// The normalised Gaussian kernel of standard deviation `sigma` px, sampled
/// at integer offsets `-R..=R` with `R = ceil(5 sigma)`; it sums to 1 and is
/// symmetric, so it moves no edge. `[1.0]` (no blur) when `sigma <= 0`
/// or is not finite.
pub fn gaussian_kernel(sigma: f64) -> Vec<f64> {
    if !(sigma > 0.0 && sigma.is_finite()) {
        return vec![1.0];
    }
    let radius = (5.0 * sigma).ceil() as usize;
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
