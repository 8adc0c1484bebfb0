//! The band of a shape model: the pixels whose centre lies within `R` of
//! the shape (and, for a line, projects within its span), with their
//! values as recorded (no interpolation: the virtual image is evaluated at
//! the pixel centres, see [`super::solve`]).
//!
//! Candidates are the pixels within `R + 1` (in each axis) of points of the
//! boundary 0.5 px apart, marked on a bitmap over their bounding box; each
//! is then kept on its exact signed distance. A closed shape's band must
//! lie inside the image; a line's is cut by the image border.

use super::geometry::{Geometry, PixelCtx};
use crate::image::Image;

/// Spacing of the boundary points that seed the candidates, px.
const SEED_STEP: f64 = 0.5;

/// A band pixel: its centre and recorded value.
#[derive(Clone, Copy, Debug, PartialEq)]
pub(crate) struct BandPixel {
    /// Centre `[x, y]`, px.
    pub q: [f64; 2],
    /// Gray level.
    pub f: f64,
}

/// The band of `geometry` of half-width `half_width` in `image`, in row
/// order; `Err([x, y])` with a band pixel outside the image for a closed
/// shape that leaves it.
pub(crate) fn select(
    image: &Image,
    geometry: &Geometry,
    half_width: f64,
    ctx: PixelCtx,
) -> Result<Vec<BandPixel>, [f64; 2]> {
    let seeds = geometry.boundary(SEED_STEP);
    let reach = (half_width + 1.0).ceil() as i64;
    let (mut x0, mut y0, mut x1, mut y1) = (i64::MAX, i64::MAX, i64::MIN, i64::MIN);
    for b in &seeds {
        if !(b.p[0].is_finite() && b.p[1].is_finite()) || b.p[0].abs() > 1e9 || b.p[1].abs() > 1e9 {
            return Err(b.p);
        }
        let (x, y) = (b.p[0].round() as i64, b.p[1].round() as i64);
        x0 = x0.min(x - reach);
        x1 = x1.max(x + reach);
        y0 = y0.min(y - reach);
        y1 = y1.max(y + reach);
    }
    if seeds.is_empty() {
        return Ok(Vec::new());
    }
    let (w, h) = (image.width() as i64, image.height() as i64);
    if geometry.is_closed() {
        // A boundary point outside the image has band pixels outside it
        // (and this bounds the bitmap by the image's size).
        let (wf, hf) = (w as f64 - 0.5, h as f64 - 0.5);
        if let Some(b) = seeds
            .iter()
            .find(|b| b.p[0] < -0.5 || b.p[1] < -0.5 || b.p[0] > wf || b.p[1] > hf)
        {
            return Err(b.p);
        }
    }
    if !geometry.is_closed() {
        // A line's band is cut by the image.
        x0 = x0.max(0);
        y0 = y0.max(0);
        x1 = x1.min(w - 1);
        y1 = y1.min(h - 1);
        if x1 < x0 || y1 < y0 {
            return Ok(Vec::new());
        }
    }
    let bw = (x1 - x0 + 1) as usize;
    let bh = (y1 - y0 + 1) as usize;
    let mut mark = vec![false; bw * bh];
    for b in &seeds {
        let (x, y) = (b.p[0].round() as i64, b.p[1].round() as i64);
        for row in (y - reach).max(y0)..=(y + reach).min(y1) {
            let base = (row - y0) as usize * bw;
            let (c0, c1) = ((x - reach).max(x0), (x + reach).min(x1));
            if c0 > c1 {
                continue;
            }
            mark[base + (c0 - x0) as usize..=base + (c1 - x0) as usize].fill(true);
        }
    }
    let mut out = Vec::new();
    for row in 0..bh {
        for col in 0..bw {
            if !mark[row * bw + col] {
                continue;
            }
            let (x, y) = (x0 + col as i64, y0 + row as i64);
            let q = [x as f64, y as f64];
            let d = geometry.local(q, ctx).distance();
            if d.abs() > half_width || !geometry.in_span(q) {
                continue;
            }
            if x < 0 || y < 0 || x >= w || y >= h {
                return Err(q);
            }
            out.push(BandPixel {
                q,
                f: image.get(x as usize, y as usize),
            });
        }
    }
    Ok(out)
}
