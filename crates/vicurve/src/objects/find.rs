//! Finding the objects: the regions of one phase worth measuring, each with
//! its traced boundary and the gap to its nearest neighbour.

use super::{order, AllConfig, ObjectPolarity, RegionInfo, MIN_CONTRAST_TO_NOISE};
use crate::error::{Error, Result};
use crate::fit::default_stages;
use crate::image::Image;
use crate::start::threshold::{self, Rect};
use crate::start::{boundary, edge_score, region, search_rect};
use serde::{Deserialize, Serialize};

/// How far (px) from an object's edge other regions are looked for: the
/// default schedule's first band (20 px) and a margin; beyond it an object
/// is measured with the default schedule unchanged.
pub const GAP_REACH: usize = 24;

/// Regions of fewer pixels than this are ignored as neighbours (isolated
/// noise pixels that survive the smoothing).
const NEIGHBOUR_MIN_PIXELS: usize = 3;

/// One object to measure.
#[derive(Clone, Debug, PartialEq)]
pub struct Candidate {
    /// Its number.
    pub id: usize,
    /// The region.
    pub region: RegionInfo,
    /// Its outer boundary pixels `[x, y]` in image coordinates, clockwise
    /// on screen (closed chain).
    pub chain: Vec<[f64; 2]>,
    /// The object id of the nearest other region within [`GAP_REACH`], if
    /// that region is an object.
    pub neighbour: Option<usize>,
    /// The search rectangle (for the open start of a border object).
    pub rect: Rect,
    /// Whether the object is above the threshold.
    pub bright: bool,
}

/// What the search found, and what it left out.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub struct Found {
    /// The objects, numbered.
    #[serde(skip)]
    pub candidates: Vec<Candidate>,
    /// Otsu's threshold, gray levels.
    pub threshold: f64,
    /// Whether the objects are above the threshold.
    pub bright: bool,
    /// The image noise's standard deviation, gray levels (median absolute
    /// difference of horizontal neighbours).
    pub noise: f64,
    /// Least boundary length used, px.
    pub min_length: f64,
    /// Least area used, px^2.
    pub min_area: f64,
    /// Regions of the objects' phase left out as too small or too short.
    pub small: usize,
    /// Left out as too faint (edge gradient under the noise criterion).
    pub faint: usize,
    /// Left out because cut by the border.
    pub border: usize,
}

/// Find the objects of `image` (module docs of [`super`]).
///
/// Errors: [`Error::InvalidParameter`] for a bad region of interest,
/// [`Error::NoSilhouette`] for a rectangle without contrast.
pub fn find_objects(image: &Image, config: &AllConfig) -> Result<Found> {
    let rect = search_rect(image, config.roi)?;
    let (w, h) = (rect.width(), rect.height());
    let values = threshold::smoothed(image, rect);
    let t = threshold::otsu(&values).ok_or_else(|| Error::NoSilhouette {
        reason: "the image (or region of interest) has no contrast".into(),
    })?;
    let above: Vec<bool> = values.iter().map(|&v| v > t).collect();
    let bright = match config.polarity {
        ObjectPolarity::Bright => true,
        ObjectPolarity::Dark => false,
        ObjectPolarity::Auto => 2 * above.iter().filter(|&&a| a).count() < above.len(),
    };
    let (labels, regions) = region::label(&above, w, h);
    let r_last = config
        .fit
        .stages
        .clone()
        .unwrap_or_else(default_stages)
        .last()
        .map_or(2.0, |s| s.half_width);
    let min_length = config
        .min_length
        .unwrap_or(4.0 * std::f64::consts::PI * r_last);
    let min_area = config
        .min_area
        .unwrap_or(std::f64::consts::PI * (2.0 * r_last).powi(2));
    let noise = noise_sigma(image, rect);
    let mut found = Found {
        candidates: Vec::new(),
        threshold: t,
        bright,
        noise,
        min_length,
        min_area,
        small: 0,
        faint: 0,
        border: 0,
    };
    let mut kept = Vec::new();
    for r in regions.iter().filter(|r| r.bright == bright) {
        if (r.pixels as f64) < min_area {
            found.small += 1;
            continue;
        }
        let chain = boundary::trace(&labels, w, h, r.label, r.first);
        if (chain.len() as f64) < min_length {
            found.small += 1;
            continue;
        }
        if edge_score(&chain, &values, w, h) / (chain.len() as f64) < MIN_CONTRAST_TO_NOISE * noise
        {
            found.faint += 1;
            continue;
        }
        if r.touches_border && !config.include_border {
            found.border += 1;
            continue;
        }
        kept.push((r.label, chain));
    }
    let infos: Vec<RegionInfo> = kept
        .iter()
        .map(|(label, chain)| region_info(&labels, &regions, rect, *label, chain))
        .collect();
    let ids = order::row_major(&infos);
    let mut by_label = vec![None; regions.len()];
    for (k, (label, _)) in kept.iter().enumerate() {
        by_label[*label as usize] = Some(ids[k]);
    }
    let mut candidates: Vec<Candidate> = kept
        .iter()
        .zip(infos)
        .enumerate()
        .map(|(k, ((label, chain), mut info))| {
            let (gap, other) = nearest_other(&labels, &regions, w, h, *label, chain);
            info.gap = gap;
            Candidate {
                id: ids[k],
                region: info,
                chain: chain
                    .iter()
                    .map(|&(i, j)| [(rect.x0 + i) as f64, (rect.y0 + j) as f64])
                    .collect(),
                neighbour: other.and_then(|l| by_label[l as usize]),
                rect,
                bright,
            }
        })
        .collect();
    candidates.sort_by_key(|c| c.id);
    found.candidates = candidates;
    Ok(found)
}

/// Centroid, bounding box and size of the region `label` (its pixels in
/// `labels`, `rect` coordinates), in image coordinates.
fn region_info(
    labels: &[u32],
    regions: &[region::Region],
    rect: Rect,
    label: u32,
    chain: &[(usize, usize)],
) -> RegionInfo {
    let w = rect.width();
    let (mut sx, mut sy, mut n) = (0.0, 0.0, 0usize);
    let (mut x0, mut y0, mut x1, mut y1) = (usize::MAX, usize::MAX, 0, 0);
    for &(i, j) in chain {
        (x0, y0, x1, y1) = (x0.min(i), y0.min(j), x1.max(i), y1.max(j));
    }
    for j in y0..=y1 {
        for i in x0..=x1 {
            if labels[j * w + i] == label {
                sx += i as f64;
                sy += j as f64;
                n += 1;
            }
        }
    }
    let r = &regions[label as usize];
    RegionInfo {
        centroid: [
            rect.x0 as f64 + sx / n.max(1) as f64,
            rect.y0 as f64 + sy / n.max(1) as f64,
        ],
        pixels: r.pixels,
        boundary: chain.len(),
        bbox: [rect.x0 + x0, rect.y0 + y0, rect.x0 + x1, rect.y0 + y1],
        touches_border: r.touches_border,
        gap: f64::INFINITY,
    }
}

/// The gap (px) from the boundary `chain` of region `own` to the nearest
/// pixel of another region of the same phase (of at least
/// `NEIGHBOUR_MIN_PIXELS` pixels) within [`GAP_REACH`], and that region's
/// label: the distance between pixel centres less one pixel (each
/// thresholded edge lies about half a pixel beyond its boundary pixel).
/// Infinite when there is none.
fn nearest_other(
    labels: &[u32],
    regions: &[region::Region],
    w: usize,
    h: usize,
    own: u32,
    chain: &[(usize, usize)],
) -> (f64, Option<u32>) {
    let bright = regions[own as usize].bright;
    let reach = GAP_REACH as i64;
    let mut best = (i64::MAX, None);
    for &(i, j) in chain {
        let (i, j) = (i as i64, j as i64);
        for y in (j - reach).max(0)..=(j + reach).min(h as i64 - 1) {
            for x in (i - reach).max(0)..=(i + reach).min(w as i64 - 1) {
                let d2 = (x - i).pow(2) + (y - j).pow(2);
                if d2 >= best.0 || d2 > reach * reach {
                    continue;
                }
                let l = labels[y as usize * w + x as usize];
                let r = &regions[l as usize];
                if l != own && r.bright == bright && r.pixels >= NEIGHBOUR_MIN_PIXELS {
                    best = (d2, Some(l));
                }
            }
        }
    }
    match best {
        (d2, Some(l)) => ((d2 as f64).sqrt() - 1.0, Some(l)),
        _ => (f64::INFINITY, None),
    }
}

/// The noise's standard deviation in `rect` of `image`, gray levels: the
/// median absolute difference of horizontal neighbours over `0.6745
/// sqrt(2)` (edges are too few to move the median).
fn noise_sigma(image: &Image, rect: Rect) -> f64 {
    let mut d: Vec<f64> = (rect.y0..rect.y1)
        .flat_map(|y| (rect.x0 + 1..rect.x1).map(move |x| (x, y)))
        .map(|(x, y)| (image.get(x, y) - image.get(x - 1, y)).abs())
        .collect();
    if d.is_empty() {
        return 0.0;
    }
    let mid = d.len() / 2;
    let (_, m, _) = d.select_nth_unstable_by(mid, f64::total_cmp);
    *m / (0.6745 * std::f64::consts::SQRT_2)
}
