//! Curves with corners: knots of multiplicity `p` (the degree), where the
//! curve is only `C^0` and its tangent may break (see
//! [`SplineCurve::fit_with_corners`] and [`crate::spline::knots`]).
//!
//! # Closest points near a corner
//! On a smooth curve a point's closest point is where `(X - C(u)) . C'(u)`
//! vanishes, and Newton's method finds it. At a corner `C'` jumps, so:
//!
//! * Newton's steps never cross a corner: a step that would is stopped on
//!   it, and from the corner the iteration goes on along the side whose
//!   one-sided derivative points towards the point.
//! * When neither side does (the point lies in the wedge between the two
//!   sides' normals, beyond the corner of a convex turn) the closest point
//!   is the vertex itself. Such a point is reported like a point past the
//!   end of an open curve (`at_end` of [`SplineCurve::project`]'s result),
//!   and the band leaves it out, as the method leaves out the pixels past
//!   the ends: its distance to the curve is not along any normal, and the
//!   normal displacement `U n` does not move it.
//! * On the other side of the turn a point may have a closest point on
//!   each side. Near a corner (within four times its distance, plus two
//!   elements) the projection is also started from both sides of the
//!   corner and the nearest foot wins, so that the band assigns each pixel
//!   to the side it is really closest to, whatever its start.
//! * A pixel near a corner may see the other side's edge, which no
//!   one-edge virtual profile models: its square is crossed by both
//!   sides, or, through a blur, the other edge reaches it. A pixel on one
//!   side sees the difference between the one-edge image it is modelled
//!   by and the corner's: the region between the other side and this
//!   side's extension beyond the vertex (the wedge between the rays from
//!   the vertex along the two sides' directions, forward for a pixel
//!   before the corner and backward for one after it, for convex and
//!   concave corners alike). [`SplineCurve::corner_clearances`] gives each
//!   corner's [`Clearance`]. The pixel-edge profile adds the blurred
//!   wedge to the pixel's one-edge image ([`Clearance::wedge`],
//!   [`crate::virtual_image::corner`]), so that the sides are measured
//!   from their own pixels up to the vertex; the band leaves out only the
//!   pixels within `CORNER_CLEARANCE` of the wedge, whose square the
//!   term's Gaussian stands for poorly. The wedge's lines are the sides'
//!   secants one to two reaches (`CHORD_SPREADS` spreads of the blur and
//!   the pixel) from the vertex, and its apex where they meet: the last
//!   pixels of each side, which the terms fit, do not shape the terms.
//!   (Leaving out the pixels within two blur widths instead, and fitting
//!   the rest with one edge, put a pentagon's vertices 1.1 to 1.5 px
//!   inside at a blur of 4 px; with the wedges' lines drawn from the
//!   curve's own vertex, the sides' ends wiggled by up to 0.8 px at 2 %
//!   noise.)

/// Distance (px) kept from the region where a corner's image differs from
/// a side's one-edge model: a pixel's square reaches `sqrt(2) / 2` px from
/// its centre, plus a margin. Without a clearance the two sides' ends are
/// pulled towards each other (the pixel-edge profile's wedge term models
/// the blurred wedge, but not a square crossed by both sides).
pub(crate) const CORNER_CLEARANCE: f64 = 1.0;
/// A side's line at a corner passes through its points one and two times
/// this many spreads (blur and pixel) from the vertex ([`Clearance::into`]):
/// past the end of the side, whose pixels the wedge term fits, and within
/// the reach of the blurred wedge, where the line must stand for the side.
const CHORD_SPREADS: f64 = 3.0;
/// ... and at most half this share and this share of the side's length.
const CHORD_SHARE: f64 = 0.4;
/// Sides whose directions' cross product is under this meet at the
/// reference's vertex, not where their lines cross (nearly parallel).
const MIN_TURN_SINE: f64 = 0.05;
/// Pixels farther than this many spreads (blur and pixel) from the vertex
/// get no wedge term ([`Clearance::wedge`]): the term is the other side's
/// tangent line's, which stands for the side only near the vertex, and
/// beyond it is negligible unless the sides run side by side (a spike).
pub(crate) const WEDGE_RADIUS: f64 = 2.0 * crate::virtual_image::corner::REACH;
/// Pixels farther from the vertex than this many clearance distances are
/// never left out: along a very sharp spike the other side runs beside
/// this one for its whole length.
const MAX_CLEARANCE_RATIO: f64 = 8.0;

/// A corner as the band's pixels must clear it (see the module docs).
#[derive(Clone, Copy, Debug)]
pub struct Clearance {
    /// The vertex, pixels: where the sides' lines meet (the curve's own
    /// corner point when they are nearly parallel or meet far from it).
    pub vertex: [f64; 2],
    /// Its parameter on the curve, pixels.
    pub at: f64,
    /// Unit direction of the side that ends at the vertex (its secant near
    /// the vertex, see `curve/corners.rs`; its tangent if that is empty).
    pub into: [f64; 2],
    /// Unit direction of the side that starts there, likewise.
    pub out: [f64; 2],
    /// Distance kept from the other side's edge, pixels.
    pub distance: f64,
}

impl Clearance {
    /// Whether the pixel at `x`, whose closest point on the curve is at
    /// parameter `u`, sees the other side's edge; `length` and `closed`
    /// are the curve's (a closed curve's parameter wraps round).
    pub fn covers(&self, x: [f64; 2], u: f64, length: f64, closed: bool) -> bool {
        let p = [x[0] - self.vertex[0], x[1] - self.vertex[1]];
        if p[0].hypot(p[1]) >= MAX_CLEARANCE_RATIO * self.distance {
            return false;
        }
        let (a, b) = if self.before(u, length, closed) {
            (self.into, self.out)
        } else {
            (neg(self.into), neg(self.out))
        };
        distance_to_wedge(p, a, b) < self.distance
    }

    /// Whether parameter `u` lies before the vertex (on the side that ends
    /// there), `length` and `closed` being the curve's.
    fn before(&self, u: f64, length: f64, closed: bool) -> bool {
        let mut delta = u - self.at;
        if closed {
            delta = (delta + 0.5 * length).rem_euclid(length) - 0.5 * length;
        }
        delta < 0.0
    }

    /// What the other side's edge adds to the one-edge image of the pixel
    /// at `x`, whose closest point is at parameter `u`, under a spread of
    /// `spread` pixels ([`CornerWedge`]); `None` when it is negligible or
    /// the pixel lies farther from the vertex than the sides' tangents
    /// can stand for them (twice [`crate::virtual_image::corner::REACH`]
    /// spreads, plus a pixel).
    pub fn wedge(
        &self,
        x: [f64; 2],
        u: f64,
        length: f64,
        closed: bool,
        spread: f64,
    ) -> Option<CornerWedge> {
        let p = [x[0] - self.vertex[0], x[1] - self.vertex[1]];
        if p[0].hypot(p[1]) > WEDGE_RADIUS * spread + 1.0 {
            return None;
        }
        let on_into = self.before(u, length, closed);
        CornerWedge::new(x, self.vertex, self.into, self.out, on_into, spread)
    }
}

/// `-v`.
fn neg(v: [f64; 2]) -> [f64; 2] {
    [-v[0], -v[1]]
}

/// `a x b` (z component).
fn cross(a: [f64; 2], b: [f64; 2]) -> f64 {
    a[0] * b[1] - a[1] * b[0]
}

/// Distance from `p` to the wedge between the rays from the origin along
/// the unit vectors `a` and `b` (the smaller angle between them; a ray
/// when they agree), pixels.
fn distance_to_wedge(p: [f64; 2], a: [f64; 2], b: [f64; 2]) -> f64 {
    let turn = cross(a, b);
    let (pa, pb) = (cross(a, p), cross(p, b));
    let inside = if turn >= 0.0 {
        pa >= 0.0 && pb >= 0.0
    } else {
        pa <= 0.0 && pb <= 0.0
    };
    if inside {
        return 0.0;
    }
    let to_ray = |d: [f64; 2]| {
        if p[0] * d[0] + p[1] * d[1] <= 0.0 {
            p[0].hypot(p[1])
        } else {
            cross(d, p).abs()
        }
    };
    to_ray(a).min(to_ray(b))
}

/// Where the lines `p + a t` and `q + b s` cross: `(a, b)`, or `None`
/// when `|t x s|` is at most `min_sine` (nearly parallel).
pub(crate) fn crossing(
    p: [f64; 2],
    t: [f64; 2],
    q: [f64; 2],
    s: [f64; 2],
    min_sine: f64,
) -> Option<(f64, f64)> {
    let det = s[0] * t[1] - t[0] * s[1];
    if det.abs() <= min_sine {
        return None;
    }
    let gap = [q[0] - p[0], q[1] - p[1]];
    Some((
        (s[0] * gap[1] - s[1] * gap[0]) / det,
        (t[0] * gap[1] - t[1] * gap[0]) / det,
    ))
}

use super::project::Projection;
use super::{frame_from, SplineCurve};
use crate::virtual_image::corner::CornerWedge;
use crate::virtual_image::pixel_edge::spread_variance;

impl SplineCurve {
    /// Parameters of the corners (knots of multiplicity at least the
    /// degree), sorted; empty for a smooth curve.
    pub fn corners(&self) -> &[f64] {
        &self.corners
    }

    /// The corners' [`Clearance`]s for an edge seen through a Gaussian blur
    /// of `blur` px (0: sharp), which sets how far from the vertex the
    /// sides' secants are taken (the reasons are in `curve/corners.rs`).
    pub fn corner_clearances(&self, blur: f64) -> Vec<Clearance> {
        let spread = spread_variance(blur.max(0.0)).sqrt();
        let reach = CHORD_SPREADS * spread;
        (0..self.corners.len())
            .map(|k| {
                let c = self.corners[k];
                let [vertex, right, _] = self.derivatives(c);
                let left = self.derivatives_left(c)[1];
                // Each side's line through its points one and two reaches
                // from the vertex, and the vertex where the lines meet: the
                // ends of the sides, which the wedge terms fit, do not
                // enter the terms themselves (through them the noise of one
                // side's end moved the other's, which answered in
                // opposition).
                let (before, after) = self.sides_at(k);
                let (p_in, into) = self.side_line(c, before, -1.0, reach, left);
                let (p_out, out) = self.side_line(c, after, 1.0, reach, right);
                let vertex = crossing(p_in, into, p_out, out, MIN_TURN_SINE)
                    .map(|(a, _)| [p_in[0] + a * into[0], p_in[1] + a * into[1]])
                    .filter(|m| (m[0] - vertex[0]).hypot(m[1] - vertex[1]) < reach)
                    .unwrap_or(vertex);
                Clearance {
                    vertex,
                    at: c,
                    into,
                    out,
                    distance: CORNER_CLEARANCE,
                }
            })
            .collect()
    }

    /// The parameter lengths of the sides before and after corner `k`: to
    /// the neighbouring corners, or to the ends of an open curve (a closed
    /// curve's only corner has the whole curve on each side).
    fn sides_at(&self, k: usize) -> (f64, f64) {
        let (l, closed, n) = (self.param_length(), self.is_closed(), self.corners.len());
        let c = self.corners[k];
        let gap = |a: f64, b: f64| if closed { (b - a).rem_euclid(l) } else { b - a };
        let before = match (k, closed) {
            (0, false) => c,
            (0, true) if n == 1 => l,
            (0, true) => gap(self.corners[n - 1], c),
            _ => gap(self.corners[k - 1], c),
        };
        let after = match (k + 1 < n, closed) {
            (true, _) => gap(c, self.corners[k + 1]),
            (false, false) => l - c,
            (false, true) if n == 1 => l,
            (false, true) => gap(c, self.corners[0]),
        };
        (before, after)
    }

    /// The line standing for the side of parameter length `len` that ends
    /// (`sign` -1) or starts (+1) at the corner at parameter `c`: its point
    /// `reach` from the vertex and its unit direction, along the curve's
    /// travel, to its point `2 reach` away (at most half `CHORD_SHARE` and
    /// `CHORD_SHARE` of the side); the side's `tangent` at the vertex when
    /// those points coincide.
    fn side_line(
        &self,
        c: f64,
        len: f64,
        sign: f64,
        reach: f64,
        tangent: [f64; 2],
    ) -> ([f64; 2], [f64; 2]) {
        let (l, closed) = (self.param_length(), self.is_closed());
        let at = |share: f64, times: f64| {
            let mut u = c + sign * (times * reach).min(share * len);
            if closed {
                u = u.rem_euclid(l);
            }
            self.point(u.clamp(0.0, l))
        };
        let (near, far) = (at(0.5 * CHORD_SHARE, 1.0), at(CHORD_SHARE, 2.0));
        let d = [sign * (far[0] - near[0]), sign * (far[1] - near[1])];
        let unit = |v: [f64; 2]| {
            let n = v[0].hypot(v[1]).max(1e-300);
            [v[0] / n, v[1] / n]
        };
        (
            near,
            unit(if d[0].hypot(d[1]) > 1e-6 { d } else { tangent }),
        )
    }

    /// `C(u)`, `C'(u)` and `C''(u)` as the limits from the left (at a knot,
    /// the element that ends there).
    pub fn derivatives_left(&self, u: f64) -> [[f64; 2]; 3] {
        let (e, t) = self.basis.locate_left(u);
        self.derivatives_at(e, t)
    }

    /// Closest point on a curve with corners (see the [module docs](self)).
    pub(crate) fn project_cornered(&self, x: f64, y: f64, u0: f64) -> Projection {
        let mut best = self.newton_cornered(x, y, u0);
        let mut best_d = self.distance_to(x, y, best.u);
        let reach = 4.0 * best_d + 2.0 * self.basis.element_length();
        let l = self.param_length();
        for &c in &self.corners {
            let v = self.point(c);
            if (x - v[0]).hypot(y - v[1]) > reach {
                continue;
            }
            let delta = 1e-6 * self.basis.element_length();
            for start in [c - delta, c + delta] {
                if !self.is_closed() && !(0.0..=l).contains(&start) {
                    continue;
                }
                let pr = self.newton_cornered(x, y, start);
                let d = self.distance_to(x, y, pr.u);
                if d < best_d - 1e-12 {
                    best = pr;
                    best_d = d;
                }
            }
        }
        best
    }

    fn distance_to(&self, x: f64, y: f64, u: f64) -> f64 {
        let p = self.point(u);
        (x - p[0]).hypot(y - p[1])
    }

    /// Newton's method that stops on corners (see the module docs).
    fn newton_cornered(&self, x: f64, y: f64, u0: f64) -> Projection {
        let l = self.param_length();
        let closed = self.is_closed();
        let max_step = self.basis().element_length();
        // Whether `u` is on a corner. Iterates are set onto corners, but on
        // a closed curve onto a copy `c + k l`, whose wrapped value may
        // differ from `c` by rounding: compare within a tolerance.
        let tol = 1e-9 * l.max(1.0);
        let corner_at = |u: f64| {
            let w = if closed { u.rem_euclid(l) } else { u };
            self.corners.iter().any(|&c| {
                let d = (w - c).abs();
                d <= tol || (closed && l - d <= tol)
            })
        };
        // The first corner strictly between a and b (either order), with
        // its periodic copies for closed curves.
        let crossed = |a: f64, b: f64| -> Option<f64> {
            let (lo, hi) = if a < b { (a, b) } else { (b, a) };
            let shifts: &[f64] = if closed {
                &[-l, 0.0, l, 2.0 * l]
            } else {
                &[0.0]
            };
            let mut hit: Option<f64> = None;
            for &c in &self.corners {
                for &k in shifts {
                    let cc = c + k;
                    // A corner the iterate sits on (to rounding) is not
                    // crossed.
                    let beyond = (cc - a).abs() > tol;
                    if beyond
                        && cc > lo
                        && cc < hi
                        && hit.is_none_or(|h| (cc - a).abs() < (h - a).abs())
                    {
                        hit = Some(cc);
                    }
                }
            }
            hit
        };
        let newton = |d: [[f64; 2]; 3]| -> f64 {
            let [p, d1, d2] = d;
            let (dx, dy) = (x - p[0], y - p[1]);
            let g = dx * d1[0] + dy * d1[1];
            let hess = d1[0] * d1[0] + d1[1] * d1[1] - (dx * d2[0] + dy * d2[1]);
            if hess > 1e-12 {
                g / hess
            } else {
                g / (d1[0] * d1[0] + d1[1] * d1[1]).max(1e-12)
            }
        };
        let tangential = |d: [[f64; 2]; 3]| (x - d[0][0]) * d[1][0] + (y - d[0][1]) * d[1][1];
        let mut u = if closed { u0 } else { u0.clamp(0.0, l) };
        let mut at_end = false;
        let mut left_side = false;
        for _ in 0..30 {
            let mut step;
            if corner_at(u) {
                let right = self.derivatives(u);
                let left = self.derivatives_left(u);
                let (gl, gr) = (tangential(left), tangential(right));
                if gl >= 0.0 && gr <= 0.0 {
                    // The vertex is the closest point (a wedge point).
                    at_end = gl > 1e-9 || gr < -1e-9;
                    left_side = false;
                    break;
                }
                left_side = gr <= 0.0;
                step = if left_side {
                    newton(left).min(0.0)
                } else {
                    newton(right).max(0.0)
                };
                if step == 0.0 {
                    // A wrong-signed Newton step: take the gradient's.
                    let d = if left_side { left } else { right };
                    step = tangential(d) / (d[1][0] * d[1][0] + d[1][1] * d[1][1]).max(1e-12);
                }
            } else {
                left_side = false;
                step = newton(self.derivatives(u));
            }
            let step = step.clamp(-max_step, max_step);
            let mut next = u + step;
            if let Some(c) = crossed(u, next) {
                next = c;
            }
            if !closed && (next <= 0.0 || next >= l) {
                next = next.clamp(0.0, l);
                if next == u {
                    at_end = true;
                    break;
                }
            }
            let moved = (next - u).abs();
            u = next;
            if moved < 1e-5 && !corner_at(u) {
                break;
            }
        }
        if closed {
            u = u.rem_euclid(l);
            if u >= l {
                u = 0.0;
            }
        } else if u <= 0.0 || u >= l {
            let d = self.derivatives(u);
            let speed = d[1][0].hypot(d[1][1]);
            at_end = at_end || tangential(d).abs() > 1e-9 * speed.max(1.0);
        }
        let d = if left_side {
            self.derivatives_left(u)
        } else {
            self.derivatives(u)
        };
        let f = frame_from(d[0], d[1], d[2]);
        let r = (x - f.point[0]) * f.normal[0] + (y - f.point[1]) * f.normal[1];
        Projection {
            u,
            r,
            curvature: f.curvature,
            normal: f.normal,
            at_end,
        }
    }
}
