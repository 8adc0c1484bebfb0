//! Rounded corners: a found corner that the image shows rounded by a
//! small fillet, and the `sigma` of the samples near it.
//!
//! A machined part's corners are rounded by a fillet of a pixel or a few.
//! Elements of 5 px and more cannot follow such a bend, so the smooth fit
//! misses it, and the corner the turning then finds ([`super::corner_search`])
//! wins the image's test against that smooth curve ([`super::corner_check`]).
//! Yet the sharp vertex lies `rho (1 / cos(theta / 2) - 1)` beyond a fillet
//! of radius `rho` turning by `theta` (0.41 `rho` at a right angle), and
//! the sides bend to meet it: rounded rectangles under a 0.7 to 2.5 px blur
//! came out 0.45 to 0.93 px off at their vertices while the noise `sigma`
//! there said 0.02 to 0.05.
//!
//! So each kept corner is also compared with fillets. The two sides are
//! taken as straight lines fitted to the measured curve beyond the
//! compared pixels ([`SIDE_FROM`] to [`SIDE_TO`] of their radius from the
//! vertex, where the sides no longer bend to meet the vertex), and the
//! curve between is replaced by those lines meeting at their
//! intersection, either sharply or through a circular arc of radius `rho`
//! tangent to both ([`RADII`]). Each is rendered as the camera records it
//! on the corner test's pixels ([`Patch::misfit_of`]). The corner is
//! rounded when the best fillet fits better than the sharp meeting by
//! [`SIGNIFICANCE`] standard deviations of the difference under noise
//! (and the corner test's tolerance), and leaves a residual within
//! [`MISFIT_RATIO`] of the noise. The samples within the replaced stretch
//! are then charged with their distance to that filleted curve in their
//! model term, and flagged where it exceeds their noise term. The measured
//! curve keeps its corner: its elements, as long as the rest of the
//! curve's, could not hold the arc either.
//!
//! Edge cases: a corner turning by less than [`MIN_TURN`] between its
//! side lines, or whose lines meet farther from the vertex than the
//! fitted stretch begins, is not compared; a patch the corner test could
//! not render (near the border, a thin part) is not compared; a fillet
//! that the image can hardly tell from the sharp corner (under a blur
//! larger than its radius, at the noise of the image) is not found, and
//! the corner's samples keep their `sigma`.

use super::corner_check::{compare, Patch, TOLERANCE};
use crate::curve::{dist, SplineCurve};
use crate::measurement::Measurement;

/// Radii of the fillets compared, pixels, each tried while its arc
/// leaves the sides' lines before the stretch they are fitted to.
const RADII: [f64; 9] = [0.5, 0.75, 1.0, 1.5, 2.0, 3.0, 4.0, 6.0, 8.0];
/// A fillet is taken when it fits better than the sharp corner by this
/// many standard deviations of the difference under noise (`2 sqrt(D)`,
/// `D` the two renderings' squared difference in noise variances): the
/// sharp corner is the default, and the best of several radii is
/// compared. At one deviation, a noiseless pentagon under a 4 px blur
/// took a 1.5 px fillet at one corner (2.7 deviations).
const SIGNIFICANCE: f64 = 3.0;
/// The fillet's residual may exceed what the pixels' noise leaves by at
/// most this factor (its mean square over the noise variance): the
/// rounded rectangles' fillets left 0.9 to 2.1 times the noise, a
/// noiseless 16-bit pentagon's about 2000 times its rounding.
const MISFIT_RATIO: f64 = 4.0;
/// The least turn of a corner tested for a fillet, rad.
const MIN_TURN: f64 = 0.3;
/// Spacing of the arc's points, pixels.
const ARC_STEP: f64 = 0.25;

/// A corner the image shows rounded.
#[derive(Clone, Debug)]
pub(super) struct Rounded {
    /// The vertex of the measured corner, pixels.
    pub vertex: [f64; 2],
    /// The filleted curve near the vertex (a polyline, pixels).
    pub outline: Vec<[f64; 2]>,
    /// How far from the vertex the filleted curve replaces the measured
    /// one, pixels.
    pub reach: f64,
}

/// The fillet that the image near the vertex of `curve` at `u` prefers to
/// a sharp corner between the same straight sides, if any (module docs);
/// `noise` is the pixels' noise variance.
pub(super) fn rounded(patch: &Patch, curve: &SplineCurve, u: f64, noise: f64) -> Option<Rounded> {
    let ring = patch.ring(curve, u)?;
    let vertex = curve.point(u);
    let at = ring.iter().position(|&p| p == vertex)?;
    let sides = Sides::new(&ring, at, patch.radius())?;
    let sharp = patch.misfit_of(&sides.outline(&ring, 0.0))?;
    let (filleted, best) = RADII
        .iter()
        .take_while(|&&rho| rho * sides.half_tan <= sides.reach)
        .filter_map(|&rho| {
            let outline = sides.outline(&ring, rho);
            let fit = patch.misfit_of(&outline)?;
            Some((outline, fit))
        })
        .min_by(|a, b| a.1 .0.total_cmp(&b.1 .0))?;
    let (evidence, spread) = compare(&sharp, &best, noise);
    let (ssr, values) = best;
    // The fillet must also fit the pixels about as well as their noise
    // allows: where no rendering does (a noiseless image that every
    // rendering misses by far more than its rounding), a fillet can
    // absorb some of the misfit at the vertex without being there.
    let dof = values.len().saturating_sub(2).max(1) as f64;
    let fits_noise = ssr / noise <= MISFIT_RATIO * dof;
    if !fits_noise || evidence <= TOLERANCE.max(SIGNIFICANCE * spread) {
        return None;
    }
    // The filleted curve where it replaced the measured one.
    let outline = filleted[sides.first..sides.first + sides.replaced(&filleted, &ring)].to_vec();
    Some(Rounded {
        vertex,
        outline,
        reach: sides.reach,
    })
}

/// The two sides of a corner as straight lines: each fitted to the ring's
/// points between [`SIDE_FROM`] and [`SIDE_TO`] of the compared radius
/// from the vertex, measured along the ring.
struct Sides {
    /// Index of the ring's last point kept before the corner, and of its
    /// first point kept after it.
    first: usize,
    last: usize,
    /// The lines' intersection (the idealised vertex), pixels.
    vertex: [f64; 2],
    /// Unit directions of the incoming and outgoing sides.
    incoming: [f64; 2],
    outgoing: [f64; 2],
    /// The turn from the one to the other, rad (signed).
    theta: f64,
    /// `tan(|theta| / 2)`: a fillet of radius `rho` leaves each side
    /// `rho` times this from the vertex.
    half_tan: f64,
    /// The largest distance from the vertex at which a fillet may leave
    /// the sides, pixels.
    reach: f64,
}

/// The stretch of each side its line is fitted to, as multiples of the
/// compared radius from the vertex, along the ring: beyond where a fit
/// with a sharp corner bends its sides to meet a rounded one (up to 15 px
/// from the vertex under a 2.5 px blur, where that radius is 17 px).
const SIDE_FROM: f64 = 1.0;
const SIDE_TO: f64 = 1.6;

impl Sides {
    fn new(ring: &[[f64; 2]], at: usize, radius: f64) -> Option<Sides> {
        let (from, to) = (SIDE_FROM * radius, SIDE_TO * radius);
        // Arc length along the ring from the vertex, backwards and
        // forwards; the ring's first and last two points close it far off.
        let walk = |indices: &mut dyn Iterator<Item = usize>| {
            let (mut walked, mut last) = (0.0, at);
            let mut side = Vec::new();
            let mut inner = None;
            for i in indices {
                walked += dist(ring[i], ring[last]);
                last = i;
                if walked >= from && inner.is_none() {
                    inner = Some(i);
                }
                if walked >= from {
                    side.push(ring[i]);
                }
                if walked >= to {
                    return Some((inner?, side));
                }
            }
            None
        };
        let (first, before) = walk(&mut (1..at).rev())?;
        let (last, after) = walk(&mut (at + 1..ring.len().saturating_sub(2)))?;
        let (pa, mut incoming) = line(&before)?;
        let (pb, mut outgoing) = line(&after)?;
        // Orient both along the ring.
        let toward = |d: [f64; 2], a: [f64; 2], b: [f64; 2]| {
            if d[0] * (b[0] - a[0]) + d[1] * (b[1] - a[1]) < 0.0 {
                [-d[0], -d[1]]
            } else {
                d
            }
        };
        incoming = toward(incoming, ring[first], ring[at]);
        outgoing = toward(outgoing, ring[at], ring[last]);
        let cross = incoming[0] * outgoing[1] - incoming[1] * outgoing[0];
        let dot = incoming[0] * outgoing[0] + incoming[1] * outgoing[1];
        let theta = cross.atan2(dot);
        if theta.abs() < MIN_TURN {
            return None;
        }
        // pa + s incoming = pb + t outgoing.
        let (rx, ry) = (pb[0] - pa[0], pb[1] - pa[1]);
        let s = (rx * outgoing[1] - ry * outgoing[0]) / cross;
        let vertex = [pa[0] + s * incoming[0], pa[1] + s * incoming[1]];
        if dist(vertex, ring[at]) > from {
            return None;
        }
        Some(Sides {
            first,
            last,
            vertex,
            incoming,
            outgoing,
            theta,
            half_tan: (0.5 * theta.abs()).tan(),
            reach: from
                .min(dist(vertex, ring[first]))
                .min(dist(vertex, ring[last])),
        })
    }

    /// `ring` with its points strictly between `first` and `last` replaced
    /// by the sides' lines meeting at the vertex, filleted to a radius
    /// `rho` (0: sharp).
    fn outline(&self, ring: &[[f64; 2]], rho: f64) -> Vec<[f64; 2]> {
        let (v, a, b) = (self.vertex, self.incoming, self.outgoing);
        let d = rho * self.half_tan;
        let mut out = ring[..=self.first].to_vec();
        let start = dot(ring[self.first], v, a);
        out.push([v[0] + start * a[0], v[1] + start * a[1]]);
        let ta = [v[0] - d * a[0], v[1] - d * a[1]];
        if rho > 0.0 {
            let sign = self.theta.signum();
            let centre = [ta[0] - sign * rho * a[1], ta[1] + sign * rho * a[0]];
            let phi0 = (ta[1] - centre[1]).atan2(ta[0] - centre[0]);
            let steps = ((rho * self.theta.abs() / ARC_STEP).ceil() as usize).max(2);
            out.extend((0..=steps).map(|k| {
                let phi = phi0 + self.theta * k as f64 / steps as f64;
                [centre[0] + rho * phi.cos(), centre[1] + rho * phi.sin()]
            }));
        } else {
            out.push(v);
        }
        let end = dot(ring[self.last], v, b);
        out.push([v[0] + end * b[0], v[1] + end * b[1]]);
        out.extend_from_slice(&ring[self.last..]);
        out
    }

    /// How many points of `outline` (made by [`Sides::outline`] on `ring`)
    /// from `first` on replace the ring's: the kept points of both ends
    /// included.
    fn replaced(&self, outline: &[[f64; 2]], ring: &[[f64; 2]]) -> usize {
        outline.len() - (ring.len() - self.last) - self.first + 1
    }
}

/// The total-least-squares line through `points`: a point on it and its
/// unit direction; `None` for fewer than two points.
fn line(points: &[[f64; 2]]) -> Option<([f64; 2], [f64; 2])> {
    (points.len() >= 2).then(|| crate::model::principal(points))
}

/// The coordinate of `p` along the unit direction `d` from `origin`.
fn dot(p: [f64; 2], origin: [f64; 2], d: [f64; 2]) -> f64 {
    (p[0] - origin[0]) * d[0] + (p[1] - origin[1]) * d[1]
}

/// The samples of `m` within the reach of a rounded corner's filleted
/// curve charged with their distance to it in their model term, and
/// flagged where that exceeds their noise term.
pub(super) fn cover_rounded(m: &mut Measurement, rounded: &[Rounded]) {
    for r in rounded {
        for s in m.samples.iter_mut() {
            if dist([s.x, s.y], r.vertex) > r.reach {
                continue;
            }
            if let Some(apart) = distance_to(&r.outline, [s.x, s.y]) {
                s.cover(apart);
            }
        }
    }
}

/// The distance from `p` to the polyline `line`, pixels; `None` for fewer
/// than two points.
fn distance_to(line: &[[f64; 2]], p: [f64; 2]) -> Option<f64> {
    line.windows(2)
        .map(|w| {
            let (a, b) = (w[0], w[1]);
            let ab = [b[0] - a[0], b[1] - a[1]];
            let len2 = ab[0] * ab[0] + ab[1] * ab[1];
            let t = if len2 > 0.0 {
                (((p[0] - a[0]) * ab[0] + (p[1] - a[1]) * ab[1]) / len2).clamp(0.0, 1.0)
            } else {
                0.0
            };
            dist(p, [a[0] + t * ab[0], a[1] + t * ab[1]])
        })
        .min_by(f64::total_cmp)
}
