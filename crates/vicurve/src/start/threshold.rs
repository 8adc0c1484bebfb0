//! Otsu's threshold and the light smoothing before it.

use crate::image::Image;

/// Histogram bins of [`otsu`].
const BINS: usize = 256;

/// The rectangle of pixels `x0..x1`, `y0..y1` (exclusive ends) of an image.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct Rect {
    /// First column.
    pub x0: usize,
    /// First row.
    pub y0: usize,
    /// One past the last column.
    pub x1: usize,
    /// One past the last row.
    pub y1: usize,
}

impl Rect {
    /// Width in pixels.
    pub fn width(&self) -> usize {
        self.x1 - self.x0
    }

    /// Height in pixels.
    pub fn height(&self) -> usize {
        self.y1 - self.y0
    }
}

/// The pixels of `rect` smoothed by a 3x3 box filter applied twice (a
/// 5x5 tent), row-major, `rect.width() * rect.height()` values. Borders
/// repeat the edge pixels. Noise of a few percent would otherwise cut the
/// thresholded region into specks along its edge.
pub fn smoothed(image: &Image, rect: Rect) -> Vec<f64> {
    let (w, h) = (rect.width(), rect.height());
    let mut a: Vec<f64> = (0..h)
        .flat_map(|j| (0..w).map(move |i| (i, j)))
        .map(|(i, j)| image.get(rect.x0 + i, rect.y0 + j))
        .collect();
    let mut b = vec![0.0; w * h];
    for _ in 0..2 {
        // Rows, then columns: a 3-tap box each way.
        for j in 0..h {
            for i in 0..w {
                let l = a[j * w + i.saturating_sub(1)];
                let r = a[j * w + (i + 1).min(w - 1)];
                b[j * w + i] = (l + a[j * w + i] + r) / 3.0;
            }
        }
        for j in 0..h {
            for i in 0..w {
                let u = b[j.saturating_sub(1) * w + i];
                let d = b[(j + 1).min(h - 1) * w + i];
                a[j * w + i] = (u + b[j * w + i] + d) / 3.0;
            }
        }
    }
    a
}

/// Otsu's threshold of `values`: the level that maximises the between-class
/// variance of a 256-bin histogram spanning their range. `None` when they
/// are all equal (no contrast) or empty.
pub fn otsu(values: &[f64]) -> Option<f64> {
    let (lo, hi) = values
        .iter()
        .fold((f64::INFINITY, f64::NEG_INFINITY), |(lo, hi), &v| {
            (lo.min(v), hi.max(v))
        });
    if hi.partial_cmp(&lo) != Some(std::cmp::Ordering::Greater) {
        return None;
    }
    let scale = (BINS as f64 - 1e-9) / (hi - lo);
    let mut hist = [0usize; BINS];
    for &v in values {
        hist[((v - lo) * scale) as usize] += 1;
    }
    let total = values.len() as f64;
    let sum_all: f64 = hist
        .iter()
        .enumerate()
        .map(|(k, &n)| k as f64 * n as f64)
        .sum();
    let (mut w0, mut sum0) = (0.0, 0.0);
    let (mut best, mut best_k) = (-1.0, 0);
    for (k, &n) in hist.iter().enumerate().take(BINS - 1) {
        w0 += n as f64;
        sum0 += k as f64 * n as f64;
        let w1 = total - w0;
        if w0 == 0.0 || w1 == 0.0 {
            continue;
        }
        let m0 = sum0 / w0;
        let m1 = (sum_all - sum0) / w1;
        let between = w0 * w1 * (m0 - m1) * (m0 - m1);
        if between > best {
            best = between;
            best_k = k;
        }
    }
    // The threshold is the upper edge of the last bin of the dark class.
    Some(lo + (best_k as f64 + 1.0) / scale)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn otsu_splits_two_levels() {
        let mut v = vec![0.2; 600];
        v.extend(std::iter::repeat_n(0.8, 400));
        let t = otsu(&v).unwrap();
        assert!(t > 0.2 && t <= 0.8, "{t}");
        assert!(otsu(&[0.5; 10]).is_none());
        assert!(otsu(&[]).is_none());
    }

    #[test]
    fn smoothing_keeps_flat_images_flat() {
        let img = Image::from_fn(7, 5, |_, _| 0.3);
        let r = Rect {
            x0: 1,
            y0: 0,
            x1: 6,
            y1: 5,
        };
        assert!(smoothed(&img, r).iter().all(|v| (v - 0.3).abs() < 1e-15));
    }
}
