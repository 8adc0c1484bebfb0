//! The other objects whose light reaches the whole-object fit's window (a
//! dot of a grid, its neighbours a few pixels away): found so that the
//! fit renders them with the object, instead of taking their light for
//! the object's.
//!
//! Around the object, a box is thresholded between its two levels
//! (Otsu's classes' means) and its 4-connected regions labelled. The
//! object's region is the one with most pixels inside its curve; where it
//! runs far beyond the curve (the blur merged it with a neighbour at the
//! half level), a threshold nearer the object's level is tried. Every
//! other region of the object's phase whose pixels come within the
//! window's reach is a neighbour, its traced boundary its start.
//!
//! Edge cases: `None` (the neighbours cannot be told) where the object's
//! region stays merged at every threshold, or a neighbour runs out of the
//! box inside the image (it is larger than the box allows for). A speck of
//! a few pixels starts from the circle of its area.

use super::render::{near, points_box, spread};
use super::MAX_SHIFT;
use crate::curve::{polygon_contains, SplineCurve};
use crate::fit::reference::CURVE_SPACING;
use crate::interp::Sampler;
use crate::start::{boundary, region, smooth, threshold};

/// A region of fewer pixels (or boundary pixels) is a speck: its start
/// is the circle of its area, as its traced boundary has too few points
/// for a curve. Its light is in the window all the same: a speck of
/// radius 2 px, 2 px beyond the tip of a 6 x 3.6 px ellipse under a
/// 1.2 px blur, left it 0.32 px off unmodelled, 0.07 px rendered.
const SPECK: usize = 16;
/// A speck's start is a circle of this radius at least, px.
const MIN_SPECK_RADIUS: f64 = 0.7;
/// The thresholds tried, as shares of the way from the other phase's
/// level to the object's (the means of Otsu's classes, which take in the
/// blurred edges: an object's own peak lies beyond its class's mean): from
/// the half level towards the object's, until its region stands apart
/// from its neighbours'.
const LEVELS: [f64; 5] = [0.5, 0.65, 0.8, 0.95, 1.1];
/// The object's region stands apart when every pixel of it lies inside
/// the curve or within `MAX_SHIFT` and this many spreads of it (a blur
/// moves the thresholded edge of a small object by about a spread).
const APART_SPREADS: f64 = 2.0;

/// The traced starts of the neighbours of the object whose curve passes
/// through `points` (closed, dense), whose light reaches within `margin`
/// px of it, under a blur of about `blur` px; empty without any, `None`
/// when they cannot be told (module docs).
pub(super) fn around(
    sampler: &Sampler,
    points: &[[f64; 2]],
    margin: f64,
    blur: f64,
) -> Option<Vec<SplineCurve>> {
    let spread = spread(blur);
    // A neighbour counts when its edge lies within the window and the
    // reach of its own blurred light (three spreads) beyond.
    let reach = margin + 3.0 * spread;
    let b = Searched::around(sampler, points, reach)?;
    let values: Vec<f64> = (0..b.w * b.h)
        .map(|k| sampler.pixel(b.x0 + k % b.w, b.y0 + k / b.w).unwrap_or(0.0))
        .collect();
    let t = threshold::otsu(&values)?;
    let mean = |below: bool| {
        let (sum, n) = values
            .iter()
            .filter(|&&v| (v < t) == below)
            .fold((0.0, 0.0), |(s, n), v| (s + v, n + 1.0));
        sum / n
    };
    let (low, high) = (mean(true), mean(false));
    let inside = b.inside(points);
    // The object's phase: the mean inside its curve's.
    let inner: Vec<f64> = inside.iter().map(|&k| values[k]).collect();
    let bright = inner.iter().sum::<f64>() / (inner.len().max(1) as f64) > t;
    let (other, own) = if bright { (low, high) } else { (high, low) };
    let near_own = MAX_SHIFT + APART_SPREADS * spread;
    for share in LEVELS {
        let level = other + share * (own - other);
        let above: Vec<bool> = values.iter().map(|&v| (v > level) == bright).collect();
        let (labels, regions) = region::label(&above, b.w, b.h);
        let mine = b.own_label(&labels, &regions, &inside)?;
        let apart = labels
            .iter()
            .enumerate()
            .filter(|(_, &l)| l == mine)
            .all(|(k, _)| b.within(k, points, near_own));
        if !apart {
            continue;
        }
        return b.neighbours(&labels, &regions, mine, points, reach);
    }
    None
}

/// The box searched, in the image.
struct Searched {
    x0: usize,
    y0: usize,
    w: usize,
    h: usize,
    /// Whether each side (left, top, right, bottom) is the image's border.
    at_border: [bool; 4],
}

impl Searched {
    /// The box of `points` widened by `reach` and by their own extent (a
    /// neighbour as large as the object fits in it), within the image.
    fn around(sampler: &Sampler, points: &[[f64; 2]], reach: f64) -> Option<Searched> {
        let [x0, y0, x1, y1] = points_box(points);
        let grow = reach + (x1 - x0).max(y1 - y0);
        let (w, h) = (sampler.width() as f64, sampler.height() as f64);
        let lo = |v: f64| (v - grow).floor().max(0.0);
        let (bx0, by0) = (lo(x0), lo(y0));
        let bx1 = (x1 + grow).ceil().min(w - 1.0);
        let by1 = (y1 + grow).ceil().min(h - 1.0);
        if !(bx1 > bx0 && by1 > by0) {
            return None;
        }
        Some(Searched {
            x0: bx0 as usize,
            y0: by0 as usize,
            w: (bx1 - bx0) as usize + 1,
            h: (by1 - by0) as usize + 1,
            at_border: [bx0 == 0.0, by0 == 0.0, bx1 == w - 1.0, by1 == h - 1.0],
        })
    }

    /// The image position of the box's pixel `k`.
    fn at(&self, k: usize) -> [f64; 2] {
        [(self.x0 + k % self.w) as f64, (self.y0 + k / self.w) as f64]
    }

    /// The box's pixels inside the closed polygon `points`.
    fn inside(&self, points: &[[f64; 2]]) -> Vec<usize> {
        let [x0, y0, x1, y1] = points_box(points);
        (0..self.w * self.h)
            .filter(|&k| {
                let p = self.at(k);
                (x0..=x1).contains(&p[0])
                    && (y0..=y1).contains(&p[1])
                    && polygon_contains(points, p)
            })
            .collect()
    }

    /// Whether pixel `k` lies inside `points` or within `d` px of them.
    fn within(&self, k: usize, points: &[[f64; 2]], d: f64) -> bool {
        let p = self.at(k);
        polygon_contains(points, p) || near(points, p, d)
    }

    /// The label of the region of the object's phase with most of the
    /// pixels `inside` its curve.
    fn own_label(
        &self,
        labels: &[u32],
        regions: &[region::Region],
        inside: &[usize],
    ) -> Option<u32> {
        let mut count = vec![0usize; regions.len()];
        for &k in inside {
            count[labels[k] as usize] += 1;
        }
        let (best, n) = count
            .iter()
            .enumerate()
            .filter(|(l, _)| regions[*l].bright)
            .max_by_key(|(_, &n)| n)?;
        (*n > 0).then_some(best as u32)
    }

    /// The regions of the object's phase other than `mine` with a pixel
    /// within `reach` of `points`, as closed curves: along their traced
    /// boundaries, or for a speck of fewer than [`SPECK`] pixels, the
    /// circle of its area about its centroid; `None` if one runs out of
    /// the box inside the image.
    fn neighbours(
        &self,
        labels: &[u32],
        regions: &[region::Region],
        mine: u32,
        points: &[[f64; 2]],
        reach: f64,
    ) -> Option<Vec<SplineCurve>> {
        let mut reached = vec![false; regions.len()];
        let mut out_of_box = vec![false; regions.len()];
        let mut centroid = vec![[0.0; 2]; regions.len()];
        for (k, &l) in labels.iter().enumerate() {
            let r = &regions[l as usize];
            if l == mine || !r.bright {
                continue;
            }
            let (i, j) = (k % self.w, k / self.w);
            let edge = [i == 0, j == 0, i + 1 == self.w, j + 1 == self.h];
            if edge.iter().zip(&self.at_border).any(|(&e, &b)| e && !b) {
                out_of_box[l as usize] = true;
            }
            let p = self.at(k);
            let c = &mut centroid[l as usize];
            c[0] += p[0] / r.pixels as f64;
            c[1] += p[1] / r.pixels as f64;
            if !reached[l as usize] && near(points, p, reach) {
                reached[l as usize] = true;
            }
        }
        let mut curves = Vec::new();
        for r in regions.iter().filter(|r| reached[r.label as usize]) {
            if out_of_box[r.label as usize] {
                return None;
            }
            let chain = boundary::trace(labels, self.w, self.h, r.label, r.first);
            let outline: Vec<[f64; 2]> = if r.pixels < SPECK || chain.len() < SPECK {
                let radius = (r.pixels as f64 / std::f64::consts::PI)
                    .sqrt()
                    .max(MIN_SPECK_RADIUS);
                let c = centroid[r.label as usize];
                (0..SPECK)
                    .map(|k| {
                        let t = std::f64::consts::TAU * k as f64 / SPECK as f64;
                        [c[0] + radius * t.cos(), c[1] + radius * t.sin()]
                    })
                    .collect()
            } else {
                let traced: Vec<[f64; 2]> = chain
                    .iter()
                    .map(|&(i, j)| [(self.x0 + i) as f64, (self.y0 + j) as f64])
                    .collect();
                smooth(&traced, true)
            };
            if let Ok(c) = SplineCurve::fit(&outline, true, 3, CURVE_SPACING) {
                curves.push(c);
            }
        }
        Some(curves)
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::image::Image;
    use crate::interp::Interpolation;

    /// Discs of radius 5 at `centres` on a 64 x 64 image, 0.8 on 0.2,
    /// sharp, and the dense outline of the first.
    fn discs(centres: &[[f64; 2]]) -> (Sampler, Vec<[f64; 2]>) {
        let image = Image::from_fn(64, 64, |x, y| {
            let inside = centres
                .iter()
                .any(|c| (x as f64 - c[0]).hypot(y as f64 - c[1]) <= 5.0);
            if inside {
                0.8
            } else {
                0.2
            }
        });
        (
            Sampler::new(&image, Interpolation::Bilinear),
            outline(centres[0]),
        )
    }

    /// 64 points of the circle of radius 5 about `c`.
    fn outline(c: [f64; 2]) -> Vec<[f64; 2]> {
        (0..64)
            .map(|k| {
                let t = k as f64 / 64.0 * std::f64::consts::TAU;
                [c[0] + 5.0 * t.cos(), c[1] + 5.0 * t.sin()]
            })
            .collect()
    }

    /// Two discs 4 px beyond the first are its neighbours; one 30 px away
    /// is not; a disc alone has none.
    #[test]
    fn the_neighbours_within_reach_are_found() {
        let (sampler, outline) = discs(&[[30.3, 30.6], [44.3, 30.6], [30.3, 44.6], [30.3, 0.0]]);
        let found = around(&sampler, &outline, 4.0, 1.0).unwrap();
        assert_eq!(found.len(), 2);
        for (curve, centre) in found.iter().zip([[44.3, 30.6], [30.3, 44.6]]) {
            let c = curve.point(0.0);
            let d = (c[0] - centre[0]).hypot(c[1] - centre[1]);
            assert!((3.0..6.0).contains(&d), "{c:?}: {d}");
        }
        let (sampler, outline) = discs(&[[30.3, 30.6]]);
        assert_eq!(around(&sampler, &outline, 4.0, 1.0).unwrap().len(), 0);
    }

    /// A disc joined to another by a bridge as bright as they are cannot
    /// be told from it: `None`.
    #[test]
    fn an_object_merged_with_another_is_not_told_apart() {
        let image = Image::from_fn(64, 64, |x, y| {
            let (x, y) = (x as f64, y as f64);
            let disc = |cx: f64| (x - cx).hypot(y - 30.6) <= 5.0;
            if disc(30.3) || disc(44.3) || ((30.0..45.0).contains(&x) && (y - 30.6).abs() < 1.5) {
                0.8
            } else {
                0.2
            }
        });
        let sampler = Sampler::new(&image, Interpolation::Bilinear);
        assert!(around(&sampler, &outline([30.3, 30.6]), 4.0, 1.0).is_none());
    }
}
