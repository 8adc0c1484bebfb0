//! Automatic start: find the main silhouette of an image and turn its
//! boundary into a starting curve, so that a measurement needs no click.
//!
//! 1. The search rectangle (the whole image, or a region of interest) is
//!    lightly smoothed and thresholded at Otsu's level
//!    ([`threshold::otsu`]).
//! 2. Its 4-connected regions on either side of the threshold are labelled
//!    ([`region::label`]). The chosen region is the one containing the
//!    picked point when there is one; otherwise the region whose edge is
//!    strongest: the sum of the image gradient along the part of its
//!    boundary a fit can measure (the whole boundary of an object seen
//!    whole; for a region cut by the rectangle's border, the longest
//!    stretch away from it). Contrast times length: a bright speck loses to
//!    the long edge of a dark object cut by the border, a faint texture
//!    blob to a sharp edge.
//! 3. Its outer boundary is traced pixel by pixel ([`boundary::trace`]),
//!    smoothed by a moving average and returned as a closed polyline; for a
//!    region touching the border, the longest stretch of boundary at least
//!    `OPEN_END_MARGIN` px from the border is returned as an open polyline
//!    (the border itself is not an edge of the object; the fit trims the
//!    curve where each stage's band would leave the image, so the start
//!    reaches as close to the border as the tracing allows).
//!
//! The start lies within about a pixel of the thresholded edge, well inside
//! the reach of the default schedule's first band (20 px). Holes in the
//! region are ignored (outer boundary only). Edge cases: an image without
//! contrast, a region under `MIN_REGION_PIXELS` pixels, a picked point
//! outside the rectangle, and a region whose boundary has no stretch away
//! from the border give [`Error::NoSilhouette`] or
//! [`Error::InvalidParameter`].
//!
//! ```
//! use vicurve::start::{find_silhouette, StartConfig};
//! use vicurve::Image;
//! // A bright disc of radius 30 centred at (60, 50).
//! let image = Image::from_fn(120, 100, |x, y| {
//!     let d = ((x as f64 - 60.0).powi(2) + (y as f64 - 50.0).powi(2)).sqrt();
//!     if d < 30.0 { 0.9 } else { 0.1 }
//! });
//! let start = find_silhouette(&image, &StartConfig::default())?;
//! assert!(start.closed && start.bright);
//! # Ok::<(), vicurve::Error>(())
//! ```

pub mod boundary;
pub mod region;
pub mod ridge;
pub mod threshold;

use crate::curve::InitialCurve;
use crate::error::{Error, Result};
use crate::image::Image;
use serde::{Deserialize, Serialize};
use threshold::Rect;

/// Regions smaller than this many pixels are not silhouettes (specks).
const MIN_REGION_PIXELS: usize = 50;
/// An open start keeps this far (pixels) from the search rectangle's
/// border: enough to leave out the boundary pixels that run along the
/// border itself (and the smoothing's few pixels at the ends).
pub(crate) const OPEN_END_MARGIN: f64 = 3.0;
/// Boundary pixels averaged on each side of a point (the staircase of a
/// traced boundary is smoothed to about a tenth of a pixel).
const SMOOTH_HALF_WINDOW: usize = 3;
/// A boundary needs at least this many pixels to make a curve.
pub(crate) const MIN_BOUNDARY: usize = 12;

/// Where to look for the silhouette.
#[derive(Clone, Debug, Default, PartialEq, Serialize, Deserialize)]
#[serde(default)]
pub struct StartConfig {
    /// A point `[x, y]` (pixels) inside the region to measure. Default: the
    /// main silhouette (module docs).
    pub pick: Option<[f64; 2]>,
    /// Search rectangle `[x0, y0, x1, y1]` (pixels, pixel-centre
    /// coordinates, inclusive). Default: the whole image.
    pub roi: Option<[f64; 4]>,
}

/// The start found, and how.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub struct AutoStart {
    /// The starting curve: a polyline through the smoothed boundary.
    pub curve: InitialCurve,
    /// Whether it is closed (a region seen whole) or open (an edge that
    /// leaves the search rectangle).
    pub closed: bool,
    /// The gray level the image was thresholded at.
    pub threshold: f64,
    /// Whether the chosen region is above the threshold.
    pub bright: bool,
    /// Pixels in the chosen region.
    pub region_pixels: usize,
}

/// Find the silhouette (module docs).
pub fn find_silhouette(image: &Image, config: &StartConfig) -> Result<AutoStart> {
    let Labelled {
        rect,
        values,
        threshold: t,
        labels,
        regions,
        ..
    } = Labelled::new(image, config.roi)?;
    let (w, h) = (rect.width(), rect.height());

    let chosen = match config.pick {
        Some([x, y]) => {
            if !(x.is_finite() && y.is_finite()) {
                return Err(Error::NonFinite {
                    what: "the picked point".into(),
                });
            }
            let (i, j) = (x.round() - rect.x0 as f64, y.round() - rect.y0 as f64);
            if i < 0.0 || j < 0.0 || i >= w as f64 || j >= h as f64 {
                return Err(Error::invalid(
                    "pick",
                    format!("({x}, {y}) is outside the searched region"),
                ));
            }
            let r = &regions[labels[j as usize * w + i as usize] as usize];
            if r.pixels < MIN_REGION_PIXELS {
                return Err(Error::NoSilhouette {
                    reason: format!(
                        "the picked region has {} pixels (a speck; at least {MIN_REGION_PIXELS} needed)",
                        r.pixels
                    ),
                });
            }
            r
        }
        None => main_region(&regions, &labels, &values, rect)?,
    };
    let chain = boundary::trace(&labels, w, h, chosen.label, chosen.first);
    let to_image = |&(i, j): &(usize, usize)| [(rect.x0 + i) as f64, (rect.y0 + j) as f64];
    let (points, closed) = if chosen.touches_border {
        let run = free_run(&chain, rect);
        if run.len() < MIN_BOUNDARY {
            return Err(Error::NoSilhouette {
                reason: format!(
                    "the region's edge stays within {OPEN_END_MARGIN} px of the border; give a region of interest or a starting curve"
                ),
            });
        }
        (run.iter().map(to_image).collect::<Vec<_>>(), false)
    } else {
        if chain.len() < MIN_BOUNDARY {
            return Err(Error::NoSilhouette {
                reason: format!("the region's boundary has only {} pixels", chain.len()),
            });
        }
        (chain.iter().map(to_image).collect::<Vec<_>>(), true)
    };
    Ok(AutoStart {
        curve: InitialCurve::Polyline {
            points: smooth(&points, closed),
            closed,
        },
        closed,
        threshold: t,
        bright: chosen.bright,
        region_pixels: chosen.pixels,
    })
}

/// The search rectangle smoothed, thresholded at Otsu's level and its
/// regions labelled: steps 1 and 2 of the module docs, shared with
/// [`crate::objects`].
pub(crate) struct Labelled {
    /// The search rectangle.
    pub rect: Rect,
    /// Its pixels smoothed ([`threshold::smoothed`]), row-major.
    pub values: Vec<f64>,
    /// Otsu's level of `values`, gray levels.
    pub threshold: f64,
    /// Whether each pixel of `values` is above the threshold.
    pub above: Vec<bool>,
    /// The region label of each pixel ([`region::label`]).
    pub labels: Vec<u32>,
    /// The regions, indexed by label.
    pub regions: Vec<region::Region>,
}

impl Labelled {
    /// Of `image` within `roi`. Errors: those of [`search_rect`];
    /// [`Error::NoSilhouette`] for a rectangle without contrast.
    pub fn new(image: &Image, roi: Option<[f64; 4]>) -> Result<Labelled> {
        let rect = search_rect(image, roi)?;
        let values = threshold::smoothed(image, rect);
        let t = threshold::otsu(&values).ok_or_else(|| Error::NoSilhouette {
            reason: "the image (or region of interest) has no contrast".into(),
        })?;
        let above: Vec<bool> = values.iter().map(|&v| v > t).collect();
        let (labels, regions) = region::label(&above, rect.width(), rect.height());
        Ok(Labelled {
            rect,
            values,
            threshold: t,
            above,
            labels,
            regions,
        })
    }
}

/// The search rectangle of `roi` clipped to the image.
pub(crate) fn search_rect(image: &Image, roi: Option<[f64; 4]>) -> Result<Rect> {
    let (w, h) = (image.width(), image.height());
    let Some([x0, y0, x1, y1]) = roi else {
        return Ok(Rect {
            x0: 0,
            y0: 0,
            x1: w,
            y1: h,
        });
    };
    if ![x0, y0, x1, y1].iter().all(|v| v.is_finite()) {
        return Err(Error::NonFinite {
            what: "the region of interest".into(),
        });
    }
    let clip = |v: f64, n: usize| v.round().clamp(0.0, n as f64 - 1.0) as usize;
    let r = Rect {
        x0: clip(x0.min(x1), w),
        y0: clip(y0.min(y1), h),
        x1: clip(x0.max(x1), w) + 1,
        y1: clip(y0.max(y1), h) + 1,
    };
    if r.width() < 8 || r.height() < 8 {
        return Err(Error::invalid(
            "region of interest",
            format!(
                "[{x0}, {y0}, {x1}, {y1}] leaves {}x{} pixels of the {w}x{h} image (at least 8x8 needed)",
                r.width(),
                r.height()
            ),
        ));
    }
    Ok(r)
}

/// The main silhouette (module docs): of the regions of at least
/// `MIN_REGION_PIXELS` pixels, the one whose measurable edge is strongest,
/// scored by [`edge_score`]. A region seen whole offers its whole boundary;
/// one cut by the rectangle's border its longest stretch away from the
/// border (`free_run`), so that an object cut by the border competes on the
/// edge a fit can measure and a small bright speck never outweighs the long
/// edge of a real object.
fn main_region<'a>(
    regions: &'a [region::Region],
    labels: &[u32],
    values: &[f64],
    rect: Rect,
) -> Result<&'a region::Region> {
    let (w, h) = (rect.width(), rect.height());
    regions
        .iter()
        .filter(|r| r.pixels >= MIN_REGION_PIXELS)
        .filter_map(|r| {
            let chain = boundary::trace(labels, w, h, r.label, r.first);
            let edge = if r.touches_border {
                free_run(&chain, rect)
            } else {
                chain
            };
            (edge.len() >= MIN_BOUNDARY).then(|| (edge_score(&edge, values, w, h), r))
        })
        .max_by(|a, b| a.0.total_cmp(&b.0))
        .map(|(_, r)| r)
        .ok_or_else(|| Error::NoSilhouette {
            reason: "no region stands out from the background (thresholded at Otsu's level)".into(),
        })
}

/// How much edge a boundary run offers a fit: its length (pixels) times the
/// mean gradient magnitude of the smoothed `values` (`w x h`, gray levels
/// per pixel, central differences) on its pixels, i.e. about the contrast
/// integrated along the edge. Both factors matter: a faint texture blob can
/// be large, a speck can be sharp; a real object's edge is long and sharp.
pub(crate) fn edge_score(run: &[(usize, usize)], values: &[f64], w: usize, h: usize) -> f64 {
    let at = |i: usize, j: usize| values[j * w + i];
    let gradient = |&(i, j): &(usize, usize)| {
        let (il, ir) = (i.saturating_sub(1), (i + 1).min(w - 1));
        let (ju, jd) = (j.saturating_sub(1), (j + 1).min(h - 1));
        let gx = (at(ir, j) - at(il, j)) / (ir - il).max(1) as f64;
        let gy = (at(i, jd) - at(i, ju)) / (jd - ju).max(1) as f64;
        gx.hypot(gy)
    };
    run.iter().map(gradient).sum()
}

/// The longest cyclic stretch of `chain` whose pixels are all at least
/// `OPEN_END_MARGIN` px from the border of `rect` (positions within it).
pub(crate) fn free_run(chain: &[(usize, usize)], rect: Rect) -> Vec<(usize, usize)> {
    let (w, h) = (rect.width() as f64, rect.height() as f64);
    let free = |&(i, j): &(usize, usize)| {
        let (x, y) = (i as f64, j as f64);
        x.min(y).min(w - 1.0 - x).min(h - 1.0 - y) >= OPEN_END_MARGIN
    };
    let n = chain.len();
    let Some(blocked) = chain.iter().position(|p| !free(p)) else {
        return Vec::new(); // all free: the region does not touch the border
    };
    // Walk once around from a blocked pixel, collecting free runs.
    let mut best: Vec<(usize, usize)> = Vec::new();
    let mut run: Vec<(usize, usize)> = Vec::new();
    for k in 1..=n {
        let p = chain[(blocked + k) % n];
        if free(&p) {
            run.push(p);
        } else {
            if run.len() > best.len() {
                best = std::mem::take(&mut run);
            }
            run.clear();
        }
    }
    if run.len() > best.len() {
        best = run;
    }
    best
}

/// Moving average over `2 SMOOTH_HALF_WINDOW + 1` points (cyclic when
/// `closed`, shrinking at the ends of an open chain so that they stay put).
pub(crate) fn smooth(points: &[[f64; 2]], closed: bool) -> Vec<[f64; 2]> {
    let n = points.len();
    (0..n)
        .map(|k| {
            let half = if closed {
                SMOOTH_HALF_WINDOW
            } else {
                SMOOTH_HALF_WINDOW.min(k).min(n - 1 - k)
            };
            let (mut sx, mut sy) = (0.0, 0.0);
            for d in 0..=2 * half {
                let q = points[(k + n + d - half) % n];
                sx += q[0];
                sy += q[1];
            }
            let m = (2 * half + 1) as f64;
            [sx / m, sy / m]
        })
        .collect()
}
