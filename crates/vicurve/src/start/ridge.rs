//! Automatic start for a thin line (a contour): follow the ridge (bright
//! line) or valley (dark line) through a picked point.
//!
//! 1. **Scale and polarity.** Around the picked point (within
//!    `SEARCH_RADIUS` px) the image is smoothed by Gaussians of a few
//!    standard deviations `sigma` (1 to 6 px), and the Hessian's
//!    eigenvalues are computed. The line is where `sigma^2 |lambda|` of the
//!    eigenvalue across it (negative for a bright line, positive for a dark
//!    one) is largest: this chooses the scale matched to the line's width,
//!    the polarity, and the starting point.
//! 2. **Following.** The search rectangle (the image, or `roi`) is smoothed
//!    at that scale. From the starting point, steps of 1 px go along the
//!    line (the Hessian's other eigenvector); after each, the point is moved
//!    across the line to the extremum of the smoothed image (a parabola
//!    through the best of samples 0.25 px apart). Each direction stops when
//!    the line's strength falls under `STOP_FRACTION` of the start's (the
//!    line ends or fades), when it turns by more than `MAX_TURN` in one
//!    step (a junction or a corner), at the rectangle's border, or when it
//!    comes back to the start (a closed line).
//! 3. **Ends at the border.** The smoothing and the recentring need
//!    `max(2 sigma, 3)` px of image around a point, so following stops
//!    that far inside the rectangle's border. An end stopped there (not by
//!    a fading line or a turn) is continued along an arc of its last
//!    points' curvature to the outermost pixel centres: a line crossing
//!    the image is measured from border to border (the fit trims it where
//!    its band leaves the image), not 12 px short at a 6 px scale.
//! 4. The two halves joined, lightly smoothed, make the starting polyline:
//!    on the line's axis within a few tenths of a pixel.
//!
//! Edge cases: without a picked point, with a picked point outside the
//! rectangle, or where no line stands out, and when the followed line is
//! under `MIN_POINTS` px long: [`Error::InvalidParameter`] or
//! [`Error::NoLine`]. An edge (a step, not a line) also has Hessian
//! extrema beside it; picking one follows a "line" parallel to the edge:
//! measure edges as silhouettes. Everything is in pixels.
//!
//! ```
//! use vicurve::start::{ridge::find_line, StartConfig};
//! use vicurve::Image;
//! // A bright line along y = 40, 2 px wide, across a 100 x 80 image.
//! let image = Image::from_fn(100, 80, |_, y| {
//!     0.1 + 0.8 * (-((y as f64 - 40.3).powi(2)) / 2.0).exp()
//! });
//! let config = StartConfig { pick: Some([50.0, 41.0]), roi: None };
//! let line = find_line(&image, &config)?;
//! assert!(line.bright && !line.closed);
//! # Ok::<(), vicurve::Error>(())
//! ```

use super::{search_rect, smooth, threshold::Rect, StartConfig};
use crate::curve::{dist, InitialCurve};
use crate::error::{Error, Result};
use crate::image::Image;
use crate::interp::{Interpolation, Sampler};
use crate::render::blur::gaussian_blur;
use serde::{Deserialize, Serialize};

/// Smoothing scales tried, pixels.
const SCALES: [f64; 6] = [1.0, 1.5, 2.0, 3.0, 4.0, 6.0];
/// The line is looked for this far from the picked point, pixels.
const SEARCH_RADIUS: f64 = 6.0;
/// Following stops where the strength falls under this fraction of the
/// start's.
const STOP_FRACTION: f64 = 0.3;
/// Following stops at a turn larger than this in one 1 px step, radians.
const MAX_TURN: f64 = 0.5;
/// Step along the line, pixels.
const STEP: f64 = 1.0;
/// Spacing of the samples across the line when recentring, pixels.
const ACROSS_STEP: f64 = 0.25;
/// An end continued to the border turns as its last this many points
/// (pixels) did.
const CURVATURE_SPAN: usize = 10;
/// A followed line needs this many points (pixels).
const MIN_POINTS: usize = 12;

/// The start found, and how.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub struct LineStart {
    /// The starting polyline along the line's axis.
    pub curve: InitialCurve,
    /// Whether the line closes on itself.
    pub closed: bool,
    /// Whether the line is brighter than its ground.
    pub bright: bool,
    /// The smoothing scale matched to the line, pixels.
    pub scale: f64,
    /// Length of the followed line, pixels.
    pub length: f64,
}

/// Follow the line through `config.pick` (module docs).
pub fn find_line(image: &Image, config: &StartConfig) -> Result<LineStart> {
    let rect = search_rect(image, config.roi)?;
    let Some(pick) = config.pick else {
        return Err(Error::invalid(
            "pick",
            "a line's automatic start follows the line through a picked point: give one (--pick X,Y)",
        ));
    };
    if !(pick[0].is_finite() && pick[1].is_finite()) {
        return Err(Error::NonFinite {
            what: "the picked point".into(),
        });
    }
    let inside_rect = |p: [f64; 2]| {
        p[0] >= rect.x0 as f64
            && p[1] >= rect.y0 as f64
            && p[0] <= (rect.x1 - 1) as f64
            && p[1] <= (rect.y1 - 1) as f64
    };
    if !inside_rect(pick) {
        return Err(Error::invalid(
            "pick",
            format!("({}, {}) is outside the searched region", pick[0], pick[1]),
        ));
    }
    let seed = choose_scale(image, rect, pick)?;
    let smoothed = Smoothed::new(image, rect, seed.scale)?;
    let margin = (2.0 * seed.scale).max(3.0);
    let start = smoothed.recentre(seed.point, seed.bright, margin);
    let Some(start) = start else {
        return Err(no_line(
            "the picked point is too close to the border of the searched region",
        ));
    };
    let strength0 = start.strength;
    let forward = smoothed.follow(&start, 1.0, strength0, margin);
    let (mut points, closed) = if forward.closed {
        let mut p = vec![start.point];
        p.extend(forward.points);
        (p, true)
    } else {
        let backward = smoothed.follow(&start, -1.0, strength0, margin);
        let border = |half: &Followed| {
            let reach = 2.0 * margin + STEP;
            let mut points = vec![start.point];
            points.extend(half.points.iter());
            half.border
                .map(|d| to_border(&points, d, rect, reach))
                .unwrap_or_default()
        };
        let mut p: Vec<[f64; 2]> = border(&backward).into_iter().rev().collect();
        p.extend(backward.points.iter().rev());
        p.push(start.point);
        p.extend(forward.points.iter());
        p.extend(border(&forward));
        (p, false)
    };
    if points.len() < MIN_POINTS {
        return Err(no_line(&format!(
            "the line through the picked point could be followed over {} px only (at least {MIN_POINTS} needed); pick a point on the line, or give a starting curve",
            points.len()
        )));
    }
    points = smooth(&points, closed);
    let length = points.windows(2).map(|w| dist(w[0], w[1])).sum::<f64>()
        + if closed {
            dist(points[0], points[points.len() - 1])
        } else {
            0.0
        };
    Ok(LineStart {
        curve: InitialCurve::Polyline { points, closed },
        closed,
        bright: seed.bright,
        scale: seed.scale,
        length,
    })
}

fn no_line(reason: &str) -> Error {
    Error::NoLine {
        reason: reason.into(),
    }
}

/// Where and at which scale the line is strongest near the picked point.
struct Seed {
    point: [f64; 2],
    scale: f64,
    bright: bool,
}

fn choose_scale(image: &Image, rect: Rect, pick: [f64; 2]) -> Result<Seed> {
    let largest = SCALES[SCALES.len() - 1];
    let half = (SEARCH_RADIUS + 5.0 * largest + 3.0).ceil() as usize;
    let (px, py) = (pick[0].round() as usize, pick[1].round() as usize);
    let window = Rect {
        x0: px.saturating_sub(half).max(rect.x0),
        y0: py.saturating_sub(half).max(rect.y0),
        x1: (px + half + 1).min(rect.x1),
        y1: (py + half + 1).min(rect.y1),
    };
    let mut best: Option<(f64, Seed)> = None;
    for &scale in &SCALES {
        let s = Smoothed::new(image, window, scale)?;
        let r = SEARCH_RADIUS as i64;
        for dj in -r..=r {
            for di in -r..=r {
                if ((di * di + dj * dj) as f64).sqrt() > SEARCH_RADIUS {
                    continue;
                }
                let p = [pick[0] + di as f64, pick[1] + dj as f64];
                let Some(h) = s.hessian(p, 1.0) else { continue };
                let (lo, hi) = h.eigenvalues();
                for (bright, strength) in [(true, -lo), (false, hi)] {
                    let normalised = scale * scale * strength;
                    if normalised > best.as_ref().map_or(0.0, |b| b.0) {
                        best = Some((
                            normalised,
                            Seed {
                                point: p,
                                scale,
                                bright,
                            },
                        ));
                    }
                }
            }
        }
    }
    best.map(|b| b.1)
        .ok_or_else(|| no_line("no line stands out near the picked point"))
}

/// The search rectangle smoothed at one scale, in image coordinates.
struct Smoothed {
    sampler: Sampler,
    origin: [f64; 2],
    scale: f64,
}

/// A symmetric 2x2 Hessian `[[xx, xy], [xy, yy]]`.
#[derive(Clone, Copy)]
struct Hessian {
    xx: f64,
    xy: f64,
    yy: f64,
}

impl Hessian {
    /// `(smaller, larger)` eigenvalues.
    fn eigenvalues(self) -> (f64, f64) {
        let m = 0.5 * (self.xx + self.yy);
        let d = (0.25 * (self.xx - self.yy).powi(2) + self.xy * self.xy).sqrt();
        (m - d, m + d)
    }

    /// Unit eigenvector of the eigenvalue `lambda`.
    fn eigenvector(self, lambda: f64) -> [f64; 2] {
        let a = [self.xy, lambda - self.xx];
        let b = [lambda - self.yy, self.xy];
        let v = if a[0].hypot(a[1]) >= b[0].hypot(b[1]) {
            a
        } else {
            b
        };
        let n = v[0].hypot(v[1]);
        if n > 0.0 {
            [v[0] / n, v[1] / n]
        } else {
            [1.0, 0.0]
        }
    }
}

/// A point on the line's axis.
struct OnLine {
    point: [f64; 2],
    /// Unit vector along the line.
    along: [f64; 2],
    /// `sigma^2 |lambda|` across the line.
    strength: f64,
    /// Whether the line is bright.
    bright: bool,
}

/// One direction of following.
struct Followed {
    points: Vec<[f64; 2]>,
    closed: bool,
    /// The direction along the line at the last point, when following
    /// stopped at the rectangle's margin (not at the line's end).
    border: Option<[f64; 2]>,
}

/// Points about `STEP` apart continuing the followed `points` (whose
/// last one stopped at the margin, heading along the unit direction `d`)
/// up to the outermost pixel centres of `rect`, the last one on them: an
/// arc of the curvature the last `CURVATURE_SPAN` points turn by. Empty
/// when that is farther than `reach` px (an end stopped at the margin is
/// that near the border, unless it runs along it).
fn to_border(points: &[[f64; 2]], d: [f64; 2], rect: Rect, reach: f64) -> Vec<[f64; 2]> {
    let Some(&end) = points.last() else {
        return Vec::new();
    };
    let lo = [rect.x0 as f64, rect.y0 as f64];
    let hi = [(rect.x1 - 1) as f64, (rect.y1 - 1) as f64];
    let inside = |p: [f64; 2]| (0..2).all(|k| p[k] >= lo[k] && p[k] <= hi[k]);
    // The turn per pixel of the last points' chords.
    let heading = |a: [f64; 2], b: [f64; 2]| (b[1] - a[1]).atan2(b[0] - a[0]);
    let n = points.len();
    let curvature = if n > CURVATURE_SPAN {
        let (a, m, b) = (
            points[n - 1 - CURVATURE_SPAN],
            points[n - 1 - CURVATURE_SPAN / 2],
            end,
        );
        let turn = heading(m, b) - heading(a, m);
        let turn =
            (turn + std::f64::consts::PI).rem_euclid(std::f64::consts::TAU) - std::f64::consts::PI;
        turn / (0.5 * (dist(a, m) + dist(m, b)))
    } else {
        0.0
    };
    let mut out = Vec::new();
    let (mut p, mut angle) = (end, d[1].atan2(d[0]));
    let mut travelled = 0.0;
    while travelled < reach {
        let next = [p[0] + STEP * angle.cos(), p[1] + STEP * angle.sin()];
        if !inside(next) {
            // The last point on the border: where this step crosses it.
            let t = (0..2)
                .filter_map(|k| {
                    let v = next[k] - p[k];
                    (v > 0.0 && next[k] > hi[k])
                        .then(|| (hi[k] - p[k]) / v)
                        .or_else(|| (v < 0.0 && next[k] < lo[k]).then(|| (lo[k] - p[k]) / v))
                })
                .fold(1.0f64, f64::min);
            out.push([p[0] + t * (next[0] - p[0]), p[1] + t * (next[1] - p[1])]);
            return out;
        }
        out.push(next);
        p = next;
        angle += curvature * STEP;
        travelled += STEP;
    }
    Vec::new()
}

impl Smoothed {
    fn new(image: &Image, rect: Rect, scale: f64) -> Result<Smoothed> {
        let crop = Image::from_fn(rect.width(), rect.height(), |i, j| {
            image.get(rect.x0 + i, rect.y0 + j)
        });
        let blurred = gaussian_blur(&crop, scale)?;
        Ok(Smoothed {
            sampler: Sampler::new(&blurred, Interpolation::CubicBSpline),
            origin: [rect.x0 as f64, rect.y0 as f64],
            scale,
        })
    }

    fn value(&self, p: [f64; 2]) -> Option<f64> {
        self.sampler
            .value(p[0] - self.origin[0], p[1] - self.origin[1])
    }

    /// Hessian at `p` (image coordinates) from central differences of the
    /// gradient, `delta` px apart on each side.
    fn hessian(&self, p: [f64; 2], delta: f64) -> Option<Hessian> {
        let g = |dx: f64, dy: f64| {
            self.sampler
                .value_gradient(p[0] - self.origin[0] + dx, p[1] - self.origin[1] + dy)
                .map(|v| v.1)
        };
        let (xp, xm, yp, ym) = (
            g(delta, 0.0)?,
            g(-delta, 0.0)?,
            g(0.0, delta)?,
            g(0.0, -delta)?,
        );
        let k = 0.5 / delta;
        Some(Hessian {
            xx: k * (xp[0] - xm[0]),
            yy: k * (yp[1] - ym[1]),
            xy: 0.5 * k * ((xp[1] - xm[1]) + (yp[0] - ym[0])),
        })
    }

    /// Whether `p` is at least `margin` px inside the smoothed rectangle.
    fn inside(&self, p: [f64; 2], margin: f64) -> bool {
        let (x, y) = (p[0] - self.origin[0], p[1] - self.origin[1]);
        let (w, h) = (self.sampler.width() as f64, self.sampler.height() as f64);
        x >= margin && y >= margin && x <= w - 1.0 - margin && y <= h - 1.0 - margin
    }

    /// The line's axis near `p`: moved across the line to the extremum of
    /// the smoothed image; `None` outside the rectangle's margin.
    fn recentre(&self, p: [f64; 2], bright: bool, margin: f64) -> Option<OnLine> {
        if !self.inside(p, margin) {
            return None;
        }
        let across = |p: [f64; 2]| -> Option<(Hessian, [f64; 2])> {
            let h = self.hessian(p, 0.5)?;
            let (lo, hi) = h.eigenvalues();
            Some((h, h.eigenvector(if bright { lo } else { hi })))
        };
        let (_, n) = across(p)?;
        let reach = (self.scale.max(1.5) / ACROSS_STEP).round() as i64;
        let sign = if bright { 1.0 } else { -1.0 };
        let values: Vec<Option<f64>> = (-reach..=reach)
            .map(|k| {
                let t = k as f64 * ACROSS_STEP;
                self.value([p[0] + t * n[0], p[1] + t * n[1]])
                    .map(|v| sign * v)
            })
            .collect();
        let best = (0..values.len())
            .filter(|&k| values[k].is_some())
            .max_by(|&a, &b| {
                values[a]
                    .unwrap_or(f64::MIN)
                    .total_cmp(&values[b].unwrap_or(f64::MIN))
            })?;
        let mut t = (best as i64 - reach) as f64 * ACROSS_STEP;
        if best > 0 && best + 1 < values.len() {
            if let (Some(a), Some(b), Some(c)) = (values[best - 1], values[best], values[best + 1])
            {
                let curv = a - 2.0 * b + c;
                if curv < 0.0 {
                    t += (0.5 * (a - c) / curv) * ACROSS_STEP;
                }
            }
        }
        let q = [p[0] + t * n[0], p[1] + t * n[1]];
        if !self.inside(q, margin) {
            return None;
        }
        let (h, n) = across(q)?;
        let (lo, hi) = h.eigenvalues();
        let strength = self.scale * self.scale * if bright { -lo } else { hi };
        Some(OnLine {
            point: q,
            along: [-n[1], n[0]],
            strength,
            bright,
        })
    }

    /// Follow the line from `start` in the direction `sign * start.along`.
    fn follow(&self, start: &OnLine, sign: f64, strength0: f64, margin: f64) -> Followed {
        let mut points = Vec::new();
        let mut p = start.point;
        let mut d = [sign * start.along[0], sign * start.along[1]];
        let limit = 4 * (self.sampler.width() + self.sampler.height());
        for _ in 0..limit {
            let ahead = [p[0] + STEP * d[0], p[1] + STEP * d[1]];
            let Some(next) = self.recentre(ahead, start.bright, margin) else {
                // Near the border the smoothed image runs out, not the line.
                let edge = margin + self.scale.max(1.5) + STEP;
                let at_border = !self.inside(ahead, edge);
                return Followed {
                    points,
                    closed: false,
                    border: at_border.then_some(d),
                };
            };
            if next.strength < STOP_FRACTION * strength0 {
                break;
            }
            let mut along = next.along;
            if along[0] * d[0] + along[1] * d[1] < 0.0 {
                along = [-along[0], -along[1]];
            }
            let turn = (d[0] * along[1] - d[1] * along[0])
                .atan2(d[0] * along[0] + d[1] * along[1])
                .abs();
            if turn > MAX_TURN {
                break;
            }
            // Back at the start, heading the same way: a closed line.
            let home = dist(next.point, start.point);
            let same_way = sign * (along[0] * start.along[0] + along[1] * start.along[1]);
            if points.len() > 10 && home < 1.5 * STEP && same_way > 0.5 {
                return Followed {
                    points,
                    closed: true,
                    border: None,
                };
            }
            points.push(next.point);
            p = next.point;
            d = along;
        }
        Followed {
            points,
            closed: false,
            border: None,
        }
    }
}
