//! Corners nobody gave ([`super::FitConfig::find_corners`]): a smooth
//! measurement of a polygon rounds each corner, misses it by up to a pixel
//! and rings beside it, while its noise `sigma` says a hundredth. The
//! measured curve shows where: its direction turns by most of the corner's
//! angle within a few pixels, and hardly at all on either side.
//!
//! Over windows of [`WINDOW`] px of arc, a sample is a corner when the
//! curve turns by at least [`MIN_TURN`] in the window centred on it and by
//! [`CONCENTRATION`] times less in each of the two windows beside it. A
//! smooth curve turns alike in neighbouring windows (a disc of any radius:
//! ratio 1), a blurred polygon's rounded corner almost only in one (the
//! thresholds against the conformance stars and pentagons:
//! docs/breaks.md). The curve is then measured again from the smooth
//! result with breaks at those corners, and the new result kept when it
//! converges (`mod.rs`).

use crate::measurement::Sample;

/// Arc length of the windows, px: wider than a corner's rounding by a blur
/// of a few pixels, narrower than the sides of the polygons measured.
const WINDOW: f64 = 10.0;
/// Least turn in the centre window, rad (45 degrees).
const MIN_TURN: f64 = std::f64::consts::FRAC_PI_4;
/// The centre window turns at least this many times more than either
/// neighbour.
const CONCENTRATION: f64 = 3.0;

/// Arc lengths (px, along the polyline of `samples` from the first one) of
/// the corners of the measured curve (module docs), increasing; empty for
/// fewer than 8 samples. Open curves: only where the three windows lie
/// within the curve.
pub(super) fn find_corners(samples: &[Sample], closed: bool) -> Vec<f64> {
    let n = samples.len();
    if n < 8 {
        return Vec::new();
    }
    let turning = Turning::new(samples, closed);
    let w = WINDOW;
    let mut candidates: Vec<(f64, f64)> = Vec::new();
    for &t in &turning.s[..n] {
        if !closed && (t - 1.5 * w < 0.0 || t + 1.5 * w > turning.length) {
            continue;
        }
        let centre = (turning.at(t + 0.5 * w) - turning.at(t - 0.5 * w)).abs();
        let left = (turning.at(t - 0.5 * w) - turning.at(t - 1.5 * w)).abs();
        let right = (turning.at(t + 1.5 * w) - turning.at(t + 0.5 * w)).abs();
        if centre >= MIN_TURN && centre >= CONCENTRATION * left.max(right) {
            candidates.push((centre, t));
        }
    }
    candidates.sort_by(|a, b| b.0.total_cmp(&a.0));
    let mut corners: Vec<f64> = Vec::new();
    for (_, t) in candidates {
        let apart = |c: &f64| {
            let d = (t - c).abs();
            let d = if closed { d.min(turning.length - d) } else { d };
            d >= w
        };
        if corners.iter().all(apart) {
            corners.push(t);
        }
    }
    corners.sort_by(f64::total_cmp);
    corners
}

/// The direction of the samples' normals, unwrapped, against the arc
/// length along their polyline.
struct Turning {
    /// Arc length of each sample (and, closed, of the first one again).
    s: Vec<f64>,
    /// Normal direction, rad, continuous (closed: the first again, plus the
    /// total turn).
    phi: Vec<f64>,
    /// Length of the polyline (closed: with the closing chord).
    length: f64,
    closed: bool,
}

impl Turning {
    fn new(samples: &[Sample], closed: bool) -> Turning {
        let n = samples.len();
        let mut s = Vec::with_capacity(n + 1);
        let mut phi = Vec::with_capacity(n + 1);
        let mut last = 0.0;
        for (k, q) in samples.iter().enumerate() {
            let a = q.ny.atan2(q.nx);
            let a = if k == 0 { a } else { unwrap(a, last) };
            if k > 0 {
                let p = &samples[k - 1];
                s.push(s[k - 1] + (q.x - p.x).hypot(q.y - p.y));
            } else {
                s.push(0.0);
            }
            phi.push(a);
            last = a;
        }
        let mut length = s[n - 1];
        if closed {
            let (p, q) = (&samples[n - 1], &samples[0]);
            length += (q.x - p.x).hypot(q.y - p.y);
            s.push(length);
            phi.push(unwrap(q.ny.atan2(q.nx), last));
        }
        Turning {
            s,
            phi,
            length,
            closed,
        }
    }

    /// The direction at arc length `t` (linear between samples; closed
    /// curves periodically continued with the total turn, open ones held
    /// at their ends).
    fn at(&self, t: f64) -> f64 {
        let (t, offset) = if self.closed && self.length > 0.0 {
            let turns = (t / self.length).floor();
            let total = self.phi[self.phi.len() - 1] - self.phi[0];
            (t - turns * self.length, turns * total)
        } else {
            (t.clamp(0.0, self.length), 0.0)
        };
        let k = self
            .s
            .partition_point(|&v| v <= t)
            .clamp(1, self.s.len() - 1);
        let (s0, s1) = (self.s[k - 1], self.s[k]);
        let f = if s1 > s0 { (t - s0) / (s1 - s0) } else { 0.0 };
        offset + self.phi[k - 1] + f * (self.phi[k] - self.phi[k - 1])
    }
}

/// `a` moved by whole turns to within half a turn of `reference`.
fn unwrap(a: f64, reference: f64) -> f64 {
    let tau = std::f64::consts::TAU;
    a - ((a - reference) / tau).round() * tau
}
