//! Every line of an image (`FitConfig::kind` contour): each ridge (bright
//! line) or valley (dark line) above a strength, followed and measured.
//!
//! 1. The search rectangle is smoothed by a Gaussian of [`SEED_SCALE`] px
//!    and its line strength `s^2 |lambda|` (the Hessian's eigenvalue across
//!    a line, as [`crate::start::ridge`] measures it) computed at every
//!    pixel. The lines' polarity is the one asked for, or (auto) that of
//!    the strongest pixel. The least strength is [`AllConfig::min_strength`]
//!    or, by default, [`STRENGTH_TO_NOISE`] times the strength's noise (its
//!    median absolute deviation over the rectangle) and at least
//!    [`STRENGTH_FLOOR`] of the strongest.
//! 2. From the strongest pixel not yet covered, the line through it is
//!    followed ([`crate::start::ridge::find_line`]: its own scale and
//!    polarity, smoothed start); the pixels within two of its scales and
//!    two pixels of it are covered. A line mostly on covered pixels (found
//!    again), of the other polarity, or shorter than the least length is
//!    left out. Repeat until no pixel above the least strength is left.
//! 3. Each line is measured from its followed polyline, its stages capped
//!    by the gap to the nearest other line (as an object's by its
//!    neighbour), in parallel; numbered row-major by centre.

use super::measure::{capped_config, measure_from_start, unmeasured};
use super::{order, AllConfig, AllResult, Found, ObjectFailure, ObjectPolarity, RegionInfo};
use crate::curve::InitialCurve;
use crate::error::Result;
use crate::fit::Measurement;
use crate::image::Image;
use crate::interp::Sampler;
use crate::render::blur::gaussian_blur;
use crate::start::ridge::find_line;
use crate::start::threshold::Rect;
use crate::start::{search_rect, StartConfig};
use rayon::prelude::*;

/// Smoothing of the strength map, px.
pub const SEED_SCALE: f64 = 1.5;
/// The default least strength is this many times the strength's noise.
pub const STRENGTH_TO_NOISE: f64 = 8.0;
/// ... and at least this fraction of the strongest pixel's.
pub const STRENGTH_FLOOR: f64 = 0.1;
/// Lines followed at most (a bound on the work of a cluttered image).
const MAX_LINES: usize = 1000;
/// A measured line whose samples lie farther than this (px, RMS) from the
/// followed polyline ran to another line.
const MAX_STRAY: f64 = 2.0;

/// One line to measure.
struct Line {
    region: RegionInfo,
    start: InitialCurve,
    points: Vec<[f64; 2]>,
    neighbour: Option<usize>,
}

/// Find and measure every line of `image` (module docs). Errors: a bad
/// region of interest ([`crate::Error::InvalidParameter`]).
pub(crate) fn measure_all_lines(image: &Image, config: &AllConfig) -> Result<AllResult> {
    let rect = search_rect(image, config.roi)?;
    let (map, bright, noise) = strength_map(image, rect, config.polarity)?;
    let strongest = map.iter().copied().fold(0.0, f64::max);
    let least = config
        .min_strength
        .unwrap_or((STRENGTH_TO_NOISE * noise).max(STRENGTH_FLOOR * strongest));
    let min_length = config
        .min_length
        .unwrap_or(4.0 * std::f64::consts::PI * 2.0);
    let mut found = Found {
        candidates: Vec::new(),
        threshold: least,
        bright,
        noise,
        min_length,
        min_area: 0.0,
        small: 0,
        faint: 0,
        border: 0,
        holes: 0,
    };
    let mut lines = follow_all(image, config, rect, &map, least, bright, &mut found);
    number_and_gap(&mut lines);
    let sampler = Sampler::new(image, config.fit.interpolation);
    let objects = lines
        .par_iter()
        .enumerate()
        .map(|(id, l)| {
            let out = unmeasured(id, &l.region, config);
            let fit = capped_config(&l.region, l.neighbour, &config.fit, f64::INFINITY);
            let check = |m: &Measurement| strayed(m, &l.points);
            measure_from_start(image, &sampler, out, l.start.clone(), fit, config, check)
        })
        .collect();
    Ok(AllResult { objects, found })
}

/// The line strength `s^2 |lambda|` of the wanted polarity at every pixel
/// of `rect` (row-major), the polarity, and the strength's noise (median
/// absolute deviation over `0.6745`).
fn strength_map(
    image: &Image,
    rect: Rect,
    polarity: ObjectPolarity,
) -> Result<(Vec<f64>, bool, f64)> {
    let (w, h) = (rect.width(), rect.height());
    let crop = Image::from_fn(w, h, |i, j| image.get(rect.x0 + i, rect.y0 + j));
    let b = gaussian_blur(&crop, SEED_SCALE)?;
    let at = |i: usize, j: usize| b.get(i.clamp(1, w - 2), j.clamp(1, h - 2));
    let s2 = SEED_SCALE * SEED_SCALE;
    let (mut ridge, mut valley) = (vec![0.0; w * h], vec![0.0; w * h]);
    for j in 1..h.saturating_sub(1) {
        for i in 1..w.saturating_sub(1) {
            let xx = at(i + 1, j) - 2.0 * at(i, j) + at(i - 1, j);
            let yy = at(i, j + 1) - 2.0 * at(i, j) + at(i, j - 1);
            let xy =
                0.25 * (at(i + 1, j + 1) - at(i + 1, j - 1) - at(i - 1, j + 1) + at(i - 1, j - 1));
            let m = 0.5 * (xx + yy);
            let d = (0.25 * (xx - yy).powi(2) + xy * xy).sqrt();
            ridge[j * w + i] = (-s2 * (m - d)).max(0.0);
            valley[j * w + i] = (s2 * (m + d)).max(0.0);
        }
    }
    let top = |v: &[f64]| v.iter().copied().fold(0.0, f64::max);
    let bright = match polarity {
        ObjectPolarity::Bright => true,
        ObjectPolarity::Dark => false,
        ObjectPolarity::Auto => top(&ridge) >= top(&valley),
    };
    let map = if bright { ridge } else { valley };
    let noise = mad(&map) / 0.6745;
    Ok((map, bright, noise))
}

/// Median absolute deviation of `v` about its median.
fn mad(v: &[f64]) -> f64 {
    if v.is_empty() {
        return 0.0;
    }
    let mut a = v.to_vec();
    let mid = a.len() / 2;
    let median = *a.select_nth_unstable_by(mid, f64::total_cmp).1;
    let mut d: Vec<f64> = v.iter().map(|x| (x - median).abs()).collect();
    *d.select_nth_unstable_by(mid, f64::total_cmp).1
}

/// Step 2 of the module docs: the lines, strongest first.
fn follow_all(
    image: &Image,
    config: &AllConfig,
    rect: Rect,
    map: &[f64],
    least: f64,
    bright: bool,
    found: &mut Found,
) -> Vec<Line> {
    let w = rect.width();
    let mut seeds: Vec<usize> = (0..map.len()).filter(|&k| map[k] >= least).collect();
    seeds.sort_by(|&a, &b| map[b].total_cmp(&map[a]));
    let mut covered = vec![false; map.len()];
    let mut lines = Vec::new();
    for k in seeds {
        if covered[k] || lines.len() >= MAX_LINES {
            continue;
        }
        let pick = [(rect.x0 + k % w) as f64, (rect.y0 + k / w) as f64];
        let start = StartConfig {
            pick: Some(pick),
            roi: config.roi,
        };
        let Ok(line) = find_line(image, &start) else {
            cover(&mut covered, rect, &[pick], 2.0);
            found.faint += 1;
            continue;
        };
        let InitialCurve::Polyline { points, .. } = &line.curve else {
            continue;
        };
        let seen = points
            .iter()
            .filter(|p| is_covered(&covered, rect, p))
            .count();
        cover(&mut covered, rect, points, 2.0 * line.scale + 2.0);
        cover(&mut covered, rect, &[pick], 2.0);
        if 2 * seen > points.len() || line.bright != bright {
            continue;
        }
        if line.length < found.min_length {
            found.small += 1;
            continue;
        }
        lines.push(Line {
            region: line_region(points, line.length),
            start: line.curve.clone(),
            points: points.clone(),
            neighbour: None,
        });
    }
    lines
}

/// Whether the pixel nearest `p` (image coordinates) is covered.
fn is_covered(covered: &[bool], rect: Rect, p: &[f64; 2]) -> bool {
    let (i, j) = (p[0].round() - rect.x0 as f64, p[1].round() - rect.y0 as f64);
    let (w, h) = (rect.width() as f64, rect.height() as f64);
    i >= 0.0 && j >= 0.0 && i < w && j < h && covered[j as usize * rect.width() + i as usize]
}

/// Cover the pixels within `radius` px of any of `points`.
fn cover(covered: &mut [bool], rect: Rect, points: &[[f64; 2]], radius: f64) {
    let (w, h) = (rect.width() as i64, rect.height() as i64);
    let r = radius.ceil() as i64;
    for p in points {
        let (ci, cj) = (
            p[0].round() as i64 - rect.x0 as i64,
            p[1].round() as i64 - rect.y0 as i64,
        );
        for j in (cj - r).max(0)..=(cj + r).min(h - 1) {
            for i in (ci - r).max(0)..=(ci + r).min(w - 1) {
                if ((i - ci).pow(2) + (j - cj).pow(2)) as f64 <= radius * radius {
                    covered[(j * w + i) as usize] = true;
                }
            }
        }
    }
}

/// The region record of a line: centre (mean point), length as its
/// boundary, bounding box; no pixels.
fn line_region(points: &[[f64; 2]], length: f64) -> RegionInfo {
    let n = points.len().max(1) as f64;
    let c = points
        .iter()
        .fold([0.0, 0.0], |m, p| [m[0] + p[0] / n, m[1] + p[1] / n]);
    let fold =
        |f: fn(f64, f64) -> f64, k: usize, init: f64| points.iter().map(|p| p[k]).fold(init, f);
    let bbox = [
        fold(f64::min, 0, f64::INFINITY),
        fold(f64::min, 1, f64::INFINITY),
        fold(f64::max, 0, 0.0),
        fold(f64::max, 1, 0.0),
    ]
    .map(|v| v.max(0.0) as usize);
    RegionInfo {
        centroid: c,
        pixels: 0,
        boundary: length.round() as usize,
        bbox,
        touches_border: false,
        gap: f64::INFINITY,
        parent: None,
    }
}

/// Number the lines row-major by centre (sorting them so) and give each
/// its gap to the nearest other line: the least distance between their
/// polylines less the lines' own spread, `MIN_GAP`'s sense.
fn number_and_gap(lines: &mut Vec<Line>) {
    let infos: Vec<RegionInfo> = lines.iter().map(|l| l.region.clone()).collect();
    let ids = order::row_major(&infos);
    let mut sorted: Vec<(usize, Line)> = ids.into_iter().zip(lines.drain(..)).collect();
    sorted.sort_by_key(|(id, _)| *id);
    *lines = sorted.into_iter().map(|(_, l)| l).collect();
    let n = lines.len();
    for a in 0..n {
        let mut best = (f64::INFINITY, None);
        for b in (0..n).filter(|&b| b != a) {
            let d = polyline_gap(&lines[a].points, &lines[b].points);
            if d < best.0 {
                best = (d, Some(b));
            }
        }
        lines[a].region.gap = best.0 - 1.0;
        lines[a].neighbour = best.1;
    }
}

/// The least distance between the points of `a` and of `b`, px.
fn polyline_gap(a: &[[f64; 2]], b: &[[f64; 2]]) -> f64 {
    let mut best = f64::INFINITY;
    for p in a {
        for q in b {
            best = best.min((p[0] - q[0]).hypot(p[1] - q[1]));
        }
    }
    best
}

/// A measured line whose samples lie, RMS, farther than [`MAX_STRAY`] px
/// from the followed polyline `points`: it ran to another line.
fn strayed(m: &Measurement, points: &[[f64; 2]]) -> Option<ObjectFailure> {
    let n = m.samples.len().max(1) as f64;
    let sum: f64 = m
        .samples
        .iter()
        .map(|s| {
            points
                .iter()
                .map(|p| (p[0] - s.x).powi(2) + (p[1] - s.y).powi(2))
                .fold(f64::INFINITY, f64::min)
        })
        .sum();
    let rms = (sum / n).sqrt();
    (rms > MAX_STRAY).then_some(ObjectFailure::Strayed { distance: rms })
}
