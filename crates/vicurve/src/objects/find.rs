//! Finding the objects: the regions of one phase worth measuring, each with
//! its traced boundary and the gap to its nearest neighbour.

use super::{order, AllConfig, ObjectPolarity, RegionInfo, MIN_CONTRAST_TO_NOISE};
use crate::error::Result;
use crate::fit::default_stages;
use crate::image::Image;
use crate::start::threshold::Rect;
use crate::start::{boundary, edge_score, region, Labelled};
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
    /// Pixels of the regions inside it (its holes and what they hold): its
    /// outer boundary encloses `region.pixels + enclosed` pixels.
    pub enclosed: usize,
    /// The threshold it was found at (Otsu's), gray levels.
    pub threshold: f64,
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
    /// Holes measured as objects ([`AllConfig::holes`]).
    #[serde(default)]
    pub holes: usize,
}

/// Find the objects of `image` (module docs of [`super`]).
///
/// Errors: [`crate::Error::InvalidParameter`] for a bad region of interest,
/// [`crate::Error::NoSilhouette`] for a rectangle without contrast.
pub fn find_objects(image: &Image, config: &AllConfig) -> Result<Found> {
    let lab = Labelled::new(image, config.roi)?;
    let bright = match config.polarity {
        ObjectPolarity::Bright => true,
        ObjectPolarity::Dark => false,
        ObjectPolarity::Auto => 2 * lab.above.iter().filter(|&&a| a).count() < lab.above.len(),
    };
    let (min_length, min_area) = limits(config);
    let mut found = Found {
        candidates: Vec::new(),
        threshold: lab.threshold,
        bright,
        noise: noise_sigma(image, lab.rect),
        min_length,
        min_area,
        small: 0,
        faint: 0,
        border: 0,
        holes: 0,
    };
    let parents = enclosing(&lab);
    let objects = select(&lab, &mut found, config.include_border, |r| {
        r.bright == bright
    });
    let mut holes = Vec::new();
    if config.holes {
        let is_object = |l: Option<u32>| l.is_some_and(|l| objects.iter().any(|o| o.0 == l));
        holes = select(&lab, &mut found, false, |r| {
            r.bright != bright && is_object(parents[r.label as usize])
        });
        found.holes = holes.len();
    }
    found.candidates = number(&lab, &parents, &objects, &holes);
    Ok(found)
}

/// The default least boundary length and area (see [`AllConfig`]).
fn limits(config: &AllConfig) -> (f64, f64) {
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
    (min_length, min_area)
}

/// The regions `wanted` that are large, long and contrasted enough, and
/// not cut by the border unless `include_border`, with their traced
/// boundaries; those left out counted in `found`.
fn select(
    lab: &Labelled,
    found: &mut Found,
    include_border: bool,
    wanted: impl Fn(&region::Region) -> bool,
) -> Vec<(u32, Vec<(usize, usize)>)> {
    let (w, h) = (lab.rect.width(), lab.rect.height());
    let mut kept = Vec::new();
    for r in lab.regions.iter().filter(|r| wanted(r)) {
        if (r.pixels as f64) < found.min_area {
            found.small += 1;
            continue;
        }
        let chain = boundary::trace(&lab.labels, w, h, r.label, r.first);
        if (chain.len() as f64) < found.min_length {
            found.small += 1;
            continue;
        }
        let contrast = edge_score(&chain, &lab.values, w, h) / (chain.len() as f64);
        if contrast < MIN_CONTRAST_TO_NOISE * found.noise {
            found.faint += 1;
            continue;
        }
        if r.touches_border && !include_border {
            found.border += 1;
            continue;
        }
        kept.push((r.label, chain));
    }
    kept
}

/// The label of the region enclosing each region (the one left of its
/// first pixel); `None` for a region cut by the border.
fn enclosing(lab: &Labelled) -> Vec<Option<u32>> {
    let w = lab.rect.width();
    lab.regions
        .iter()
        .map(|r| {
            let (i, j) = r.first;
            (!r.touches_border && i > 0).then(|| lab.labels[j * w + i - 1])
        })
        .collect()
}

/// The pixels of the regions inside each region (enclosed, directly or
/// not), by label.
fn enclosed_pixels(lab: &Labelled, parents: &[Option<u32>]) -> Vec<usize> {
    let mut inside = vec![0; lab.regions.len()];
    for r in &lab.regions {
        let mut up = parents[r.label as usize];
        while let Some(p) = up {
            inside[p as usize] += r.pixels;
            up = parents[p as usize];
        }
    }
    inside
}

/// The candidates of `objects` (numbered row-major) and of `holes`
/// (numbered after them, by enclosing object, then row-major), each with
/// its gap and nearest neighbour.
fn number(
    lab: &Labelled,
    parents: &[Option<u32>],
    objects: &[(u32, Vec<(usize, usize)>)],
    holes: &[(u32, Vec<(usize, usize)>)],
) -> Vec<Candidate> {
    let rect = lab.rect;
    let info = |(label, chain): &(u32, Vec<(usize, usize)>)| {
        region_info(&lab.labels, &lab.regions, rect, *label, chain)
    };
    let object_infos: Vec<RegionInfo> = objects.iter().map(info).collect();
    let mut ids = order::row_major(&object_infos);
    let mut by_label = vec![None; lab.regions.len()];
    for (k, (label, _)) in objects.iter().enumerate() {
        by_label[*label as usize] = Some(ids[k]);
    }
    let mut hole_infos: Vec<RegionInfo> = holes.iter().map(info).collect();
    for (k, (label, _)) in holes.iter().enumerate() {
        hole_infos[k].parent = parents[*label as usize].and_then(|p| by_label[p as usize]);
    }
    let within = order::row_major(&hole_infos);
    let mut hole_order: Vec<usize> = (0..holes.len()).collect();
    hole_order.sort_by_key(|&k| (hole_infos[k].parent, within[k]));
    let mut hole_ids = vec![0; holes.len()];
    for (n, &k) in hole_order.iter().enumerate() {
        hole_ids[k] = objects.len() + n;
        by_label[holes[k].0 as usize] = Some(objects.len() + n);
    }
    ids.extend(hole_ids);
    let enclosed = enclosed_pixels(lab, parents);
    let mut candidates: Vec<Candidate> = objects
        .iter()
        .chain(holes)
        .zip(object_infos.into_iter().chain(hole_infos))
        .zip(ids)
        .map(|((item, mut info), id)| {
            let (label, chain) = item;
            let (gap, other) = nearest_other(lab, parents, *label, chain);
            info.gap = gap;
            Candidate {
                id,
                bright: lab.regions[*label as usize].bright,
                region: info,
                chain: chain
                    .iter()
                    .map(|&(i, j)| [(rect.x0 + i) as f64, (rect.y0 + j) as f64])
                    .collect(),
                neighbour: other.and_then(|l| by_label[l as usize]),
                rect,
                enclosed: enclosed[*label as usize],
                threshold: lab.threshold,
            }
        })
        .collect();
    candidates.sort_by_key(|c| c.id);
    candidates
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
    let [x0, y0, x1, y1] = chain_bbox(chain);
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
        parent: None,
    }
}

/// The bounding box `[x0, y0, x1, y1]` of `chain` (inclusive; empty,
/// `x0 > x1`, for an empty chain).
fn chain_bbox(chain: &[(usize, usize)]) -> [usize; 4] {
    let (mut x0, mut y0, mut x1, mut y1) = (usize::MAX, usize::MAX, 0, 0);
    for &(i, j) in chain {
        (x0, y0, x1, y1) = (x0.min(i), y0.min(j), x1.max(i), y1.max(j));
    }
    [x0, y0, x1, y1]
}

/// The gap (px) from the boundary `chain` of region `own` to the nearest
/// pixel of another edge within [`GAP_REACH`]: another region of the same
/// phase, or a region inside `own` (a hole of an object, an island of a
/// hole), of at least `NEIGHBOUR_MIN_PIXELS` pixels; and that region's
/// label. The gap is the distance between pixel centres less one pixel
/// (each thresholded edge lies about half a pixel beyond its boundary
/// pixel); infinite when there is none.
///
/// Only the other regions' boundary pixels in the chain's bounding box
/// widened by the reach are compared ([`near_boundaries`]): a region's
/// pixel nearest to a point outside it is always on its boundary.
fn nearest_other(
    lab: &Labelled,
    parents: &[Option<u32>],
    own: u32,
    chain: &[(usize, usize)],
) -> (f64, Option<u32>) {
    let reach = GAP_REACH as i64;
    let others = near_boundaries(lab, parents, own, chain);
    let mut best = (i64::MAX, None);
    for &(i, j) in chain {
        let (i, j) = (i as i64, j as i64);
        for &(x, y, l) in &others {
            let d2 = (x - i).pow(2) + (y - j).pow(2);
            if d2 < best.0 && d2 <= reach * reach {
                best = (d2, Some(l));
            }
        }
    }
    match best {
        (d2, Some(l)) => ((d2 as f64).sqrt() - 1.0, Some(l)),
        _ => (f64::INFINITY, None),
    }
}

/// The boundary pixels `(x, y, label)` (a 4-neighbour of another label, or
/// on the rectangle's edge), in raster order, of the other edges of `own`
/// (see [`nearest_other`]) within [`GAP_REACH`] of the bounding box of
/// `chain`.
fn near_boundaries(
    lab: &Labelled,
    parents: &[Option<u32>],
    own: u32,
    chain: &[(usize, usize)],
) -> Vec<(i64, i64, u32)> {
    let (w, h) = (lab.rect.width(), lab.rect.height());
    let labels = &lab.labels;
    let bright = lab.regions[own as usize].bright;
    let other = |l: u32| {
        let r = &lab.regions[l as usize];
        let edge = (l != own && r.bright == bright) || parents[l as usize] == Some(own);
        edge && r.pixels >= NEIGHBOUR_MIN_PIXELS
    };
    let [x0, y0, x1, y1] = chain_bbox(chain);
    let (x0, y0) = (x0.saturating_sub(GAP_REACH), y0.saturating_sub(GAP_REACH));
    let (x1, y1) = ((x1 + GAP_REACH).min(w - 1), (y1 + GAP_REACH).min(h - 1));
    let mut out = Vec::new();
    for y in y0..=y1 {
        for x in x0..=x1 {
            let k = y * w + x;
            let l = labels[k];
            if !other(l) {
                continue;
            }
            let edge = x == 0 || y == 0 || x + 1 == w || y + 1 == h;
            let differs = |k: usize| labels[k] != l;
            if edge || differs(k - 1) || differs(k + 1) || differs(k - w) || differs(k + w) {
                out.push((x as i64, y as i64, l));
            }
        }
    }
    out
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
