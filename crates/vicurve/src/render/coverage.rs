//! Exact area coverage of pixels by polygons.
//!
//! The signed-area accumulation technique of font rasterisers: every polygon
//! edge is cut at the pixel borders; each piece, inside one pixel, adds to
//! that pixel the exact area between itself and the pixel's right border
//! (times the sign of its vertical direction), and adds its full height to
//! every pixel further right, through a difference stored in the next cell.
//! A prefix sum along each row then gives, for every pixel, the integral of
//! the winding number over the pixel. The result is exact (to rounding) for
//! any polygon whose winding number is 0 or ±1 everywhere, which includes
//! regions with holes drawn in the opposite direction (non-zero rule).
//! No supersampling is involved, so no position is quantised.

use rayon::prelude::*;

use crate::error::{Error, Result};

/// Fraction of each pixel covered by the region bounded by `rings`, row
/// after row (`width * height` values in `[0, 1]`).
///
/// Each ring is a closed polygon (the edge from the last vertex back to the
/// first is implied) in pixel coordinates: the pixel in row `i`, column `j`
/// covers `[j - 1/2, j + 1/2] x [i - 1/2, i + 1/2]`. Rings may extend beyond
/// the image. A hole is a ring drawn in the opposite direction to its outer
/// ring; the value is `min(1, |∫ winding|)`, exact where the winding number
/// is 0 or ±1.
///
/// Errors: [`Error::EmptyImage`] for a zero size, [`Error::NonFinite`] for a
/// NaN or infinite vertex.
pub fn polygon_coverage(width: usize, height: usize, rings: &[Vec<[f64; 2]>]) -> Result<Vec<f64>> {
    if width == 0 || height == 0 {
        return Err(Error::EmptyImage { width, height });
    }
    for (r, ring) in rings.iter().enumerate() {
        if let Some(i) = ring
            .iter()
            .position(|p| !(p[0].is_finite() && p[1].is_finite()))
        {
            return Err(Error::NonFinite {
                what: format!("vertex {i} of polygon ring {r}"),
            });
        }
    }
    let mut acc = vec![0.0; width * height];
    for ring in rings {
        let n = ring.len();
        for i in 0..n {
            add_edge(&mut acc, width, height, ring[i], ring[(i + 1) % n]);
        }
    }
    acc.par_chunks_mut(width).for_each(|row| {
        let mut sum = 0.0;
        for v in row.iter_mut() {
            sum += *v;
            *v = sum.abs().min(1.0);
        }
    });
    Ok(acc)
}

/// Accumulate the edge `a -> b` (pixel coordinates) into `acc`.
///
/// Works in shifted coordinates where pixel `(i, j)` is `[j, j+1] x [i, i+1]`.
/// The edge is clipped to the rows of the image; beyond the left border it
/// is projected onto the border (it still changes the winding number of
/// every pixel on its right), beyond the right border it is dropped.
fn add_edge(acc: &mut [f64], width: usize, height: usize, a: [f64; 2], b: [f64; 2]) {
    let (x0, y0) = (a[0] + 0.5, a[1] + 0.5);
    let (x1, y1) = (b[0] + 0.5, b[1] + 0.5);
    let (dx, dy) = (x1 - x0, y1 - y0);
    if dy == 0.0 {
        return; // horizontal edges do not change any winding number
    }
    let (wf, hf) = (width as f64, height as f64);
    let (ta, tb) = ((0.0 - y0) / dy, (hf - y0) / dy);
    let t_lo = ta.min(tb).max(0.0);
    let t_hi = ta.max(tb).min(1.0);
    if t_lo >= t_hi {
        return;
    }
    let at = |t: f64| -> [f64; 2] {
        if t == 1.0 {
            return [x1, y1];
        }
        let y = if t == ta {
            0.0
        } else if t == tb {
            hf
        } else {
            y0 + t * dy
        };
        [x0 + t * dx, y]
    };
    let mut t = t_lo;
    let [mut x, mut y] = if t == 0.0 { [x0, y0] } else { at(t) };
    loop {
        // Next vertical pixel border (only those inside [0, width] matter).
        let (nx, tx) = if dx > 0.0 {
            let nx = if x < 0.0 { 0.0 } else { x.floor() + 1.0 };
            (
                nx,
                if nx > wf {
                    f64::INFINITY
                } else {
                    (nx - x0) / dx
                },
            )
        } else if dx < 0.0 {
            let nx = if x > wf { wf } else { x.ceil() - 1.0 };
            (
                nx,
                if nx < 0.0 {
                    f64::INFINITY
                } else {
                    (nx - x0) / dx
                },
            )
        } else {
            (0.0, f64::INFINITY)
        };
        // Next horizontal pixel border.
        let ny = if dy > 0.0 {
            y.floor() + 1.0
        } else {
            y.ceil() - 1.0
        };
        let ty = (ny - y0) / dy;
        let t_next = tx.min(ty).min(t_hi).max(t);
        let [mut xn, mut yn] = if t_next == t_hi { at(t_hi) } else { at(t_next) };
        if t_next == tx {
            xn = nx;
        }
        if t_next == ty {
            yn = ny;
        }
        deposit(acc, width, height, [x, y], [xn, yn]);
        if t_next >= t_hi {
            break;
        }
        t = t_next;
        x = xn;
        y = yn;
    }
}

/// Add a piece of edge lying inside one pixel row and one pixel column (or
/// wholly left or right of the image), shifted coordinates.
#[inline]
fn deposit(acc: &mut [f64], width: usize, height: usize, a: [f64; 2], b: [f64; 2]) {
    let dy = b[1] - a[1];
    if dy == 0.0 {
        return;
    }
    let wf = width as f64;
    let xm = 0.5 * (a[0] + b[0]);
    if xm >= wf {
        return;
    }
    let xm = xm.max(0.0);
    let ym = 0.5 * (a[1] + b[1]);
    let row = (ym.max(0.0) as usize).min(height - 1);
    let col = (xm as usize).min(width - 1);
    let area = dy * (col as f64 + 1.0 - xm);
    let idx = row * width + col;
    acc[idx] += area;
    if col + 1 < width {
        acc[idx + 1] += dy - area;
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn unit_square_on_one_pixel() {
        let sq = vec![[0.5, 0.5], [1.5, 0.5], [1.5, 1.5], [0.5, 1.5]];
        let c = polygon_coverage(3, 3, &[sq]).unwrap();
        assert_eq!(c, vec![0.0, 0.0, 0.0, 0.0, 1.0, 0.0, 0.0, 0.0, 0.0]);
    }

    #[test]
    fn triangle_half_pixel() {
        // Triangle covering the lower-left half of pixel (0, 0).
        let tri = vec![[-0.5, -0.5], [0.5, 0.5], [-0.5, 0.5]];
        let c = polygon_coverage(2, 2, &[tri]).unwrap();
        assert!((c[0] - 0.5).abs() < 1e-15, "{c:?}");
        assert_eq!(&c[1..], &[0.0, 0.0, 0.0]);
    }

    #[test]
    fn far_left_vertex_is_cheap_and_exact() {
        // Nearly the whole image lies between the top edge y = -0.5 and the
        // hypotenuse to (3.5, 3.5); the sliver below the hypotenuse has area
        // 4 * 8 / (1e9 + 3.5). Walking 1e9 columns would hang this test.
        let tri = vec![[-1e9, -0.5], [3.5, -0.5], [3.5, 3.5]];
        let c = polygon_coverage(4, 4, &[tri]).unwrap();
        let total: f64 = c.iter().sum();
        let expect = 16.0 - 32.0 / (1e9 + 3.5);
        assert!((total - expect).abs() < 1e-9, "{total} vs {expect}");
    }
}
