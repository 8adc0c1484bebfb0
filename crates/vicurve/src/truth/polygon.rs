//! The regular polygon: its vertices, the parametrisation by edges and its
//! exact distance (a polygon has corners, so the smooth curves' Newton
//! search of [`super::geometry`] is not used for it).
//!
//! Vertex `k` (of `n`) is at the polar angle `angle + 2πk/n` about the
//! centre, counterclockwise on screen; parameter `s` in `[2πk/n, 2π(k+1)/n]`
//! runs linearly along the edge from vertex `k` to vertex `k + 1`, so the
//! speed is the same on every edge and the outward normal `n = (-t_y, t_x)`
//! is that of the edge.

use std::f64::consts::TAU;

use super::geometry::CurvePoint;
use super::Shape;

/// The vertices of a [`Shape::Polygon`], counterclockwise on screen, px
/// (empty for any other shape).
pub(crate) fn vertices(shape: &Shape) -> Vec<[f64; 2]> {
    let Shape::Polygon { sides, .. } = *shape else {
        return Vec::new();
    };
    (0..i64::from(sides)).map(|k| vertex(shape, k)).collect()
}

/// Vertex `k` (taken modulo the number of sides).
fn vertex(shape: &Shape, k: i64) -> [f64; 2] {
    let Shape::Polygon {
        cx,
        cy,
        r,
        sides,
        angle,
    } = *shape
    else {
        return [f64::NAN; 2];
    };
    let k = k.rem_euclid(i64::from(sides));
    let th = angle + TAU * k as f64 / f64::from(sides);
    [cx + r * th.cos(), cy - r * th.sin()]
}

/// Parameter length of one edge, `2π / sides`.
fn step(sides: u32) -> f64 {
    TAU / f64::from(sides)
}

/// The polygon at parameter `s` (the edge containing it; a vertex belongs
/// to the edge it starts). The second derivative is zero.
pub(crate) fn eval(shape: &Shape, sides: u32, s: f64) -> CurvePoint {
    let h = step(sides);
    let k = (s / h).floor();
    let t = s / h - k;
    let (a, b) = (vertex(shape, k as i64), vertex(shape, k as i64 + 1));
    CurvePoint {
        p: [a[0] + t * (b[0] - a[0]), a[1] + t * (b[1] - a[1])],
        d1: [(b[0] - a[0]) / h, (b[1] - a[1]) / h],
        d2: [0.0, 0.0],
    }
}

/// Squared distance from `q` to the edge `a -> b` and the fraction `t` in
/// `[0, 1]` of its closest point.
fn edge_closest(a: [f64; 2], b: [f64; 2], q: [f64; 2]) -> (f64, f64) {
    let (ex, ey) = (b[0] - a[0], b[1] - a[1]);
    let len2 = ex * ex + ey * ey;
    let t = ((q[0] - a[0]) * ex + (q[1] - a[1]) * ey) / len2;
    let t = t.clamp(0.0, 1.0);
    let (dx, dy) = (a[0] + t * ex - q[0], a[1] + t * ey - q[1]);
    (dx * dx + dy * dy, t)
}

/// Parameter of the point of the polygon closest to `q`: the best of the
/// exact projections onto every edge.
pub(crate) fn closest_param(shape: &Shape, sides: u32, q: [f64; 2]) -> f64 {
    let (mut best, mut s_best) = (f64::INFINITY, f64::NAN);
    for k in 0..i64::from(sides) {
        let (d2, t) = edge_closest(vertex(shape, k), vertex(shape, k + 1), q);
        if d2 < best {
            best = d2;
            s_best = (k as f64 + t) * step(sides);
        }
    }
    s_best
}

/// Signed distance from `q` to the polygon, px: the distance to the
/// nearest edge, negative inside. Inside is where `q` is on the inner side
/// of every edge's line (the polygon is convex); the sign does not come from
/// the normal at the closest point, which is ambiguous at a vertex.
pub(crate) fn signed_distance(shape: &Shape, sides: u32, q: [f64; 2]) -> f64 {
    let mut best = f64::INFINITY;
    let mut outside = false;
    for k in 0..i64::from(sides) {
        let (a, b) = (vertex(shape, k), vertex(shape, k + 1));
        best = best.min(edge_closest(a, b, q).0);
        // Outward normal of the edge a -> b: (-t_y, t_x).
        let n = [-(b[1] - a[1]), b[0] - a[0]];
        outside |= (q[0] - a[0]) * n[0] + (q[1] - a[1]) * n[1] > 0.0;
    }
    if outside {
        best.sqrt()
    } else {
        -best.sqrt()
    }
}

/// The closest point of the polygon to `q` and the unit normal there: the
/// edge's outward normal, or at a vertex the direction from the vertex to
/// `q` (outside, within the vertex's wedge), so that `q = p + d n` holds
/// with `d` the signed distance.
pub(crate) fn closest_point(shape: &Shape, sides: u32, q: [f64; 2]) -> ([f64; 2], [f64; 2]) {
    let s = closest_param(shape, sides, q);
    let e = eval(shape, sides, s);
    let (dx, dy) = (q[0] - e.p[0], q[1] - e.p[1]);
    let d = dx.hypot(dy);
    let n = e.normal();
    let along = dx * n[0] + dy * n[1];
    // Off the edge's normal line: the foot is a vertex.
    if d > 0.0 && (d - along.abs()) > 1e-12 * (1.0 + d) {
        return (e.p, [dx / d, dy / d]);
    }
    (e.p, n)
}
