//! The polygon model: `N` vertices, counterclockwise on screen (outward
//! edge normals `n = (-t_y, t_x)`), simple (no crossing edges).
//!
//! A pixel's signed distance is that to the nearest edge, negative inside.
//! Away from the vertices the pixel sees one straight edge, and the
//! pixel-edge profile of that edge is exact; its derivatives are those of
//! the distance to the segment `p = (1 - u) v_i + u v_{i+1}`:
//! `dd/dv_i = -(1 - u) n`, `dd/dv_{i+1} = -u n`.
//!
//! Near a vertex the pixel (through the blur) sees two edges and no
//! straight-edge profile is right. A pixel is a *corner pixel* when its
//! centre is within the reach of [`PixelCtx`] of a vertex or of an edge
//! other than its nearest. Corner pixels are either left out, or modelled
//! by their exact coverage: the area of the polygon clipped to the pixel's
//! square (Sutherland–Hodgman), exact for an unblurred image. Its
//! derivative with respect to a vertex is the boundary's normal velocity
//! integrated over the part of each incident edge inside the square
//! (Reynolds' transport theorem): with `[u_a, u_b]` that part of edge
//! `v_i -> v_{i+1}` (Liang–Barsky clipping), of length `L` and outward
//! normal `n`, `dA/dv_i += L n (u_b - u_a - (u_b^2 - u_a^2) / 2)` and
//! `dA/dv_{i+1} += L n (u_b^2 - u_a^2) / 2`.

use super::geometry::{edge_coverage, BoundaryPoint, Grad, Local, PixelCtx};
use super::{ModelShape, Parameter};

/// Shortest side a fit may reach, pixels.
const MIN_SIDE: f64 = 0.5;

/// A polygon; see the [module docs](self).
#[derive(Clone, Debug, PartialEq)]
pub(crate) struct Polygon {
    /// Vertices `[x, y]`, px, counterclockwise on screen.
    pub v: Vec<[f64; 2]>,
}

#[inline]
fn sub(a: [f64; 2], b: [f64; 2]) -> [f64; 2] {
    [a[0] - b[0], a[1] - b[1]]
}

#[inline]
fn cross(a: [f64; 2], b: [f64; 2]) -> f64 {
    a[0] * b[1] - a[1] * b[0]
}

/// Twice the signed area by the shoelace formula (negative for a polygon
/// counterclockwise on screen, y pointing down).
pub(crate) fn shoelace2(v: &[[f64; 2]]) -> f64 {
    let n = v.len();
    (0..n).map(|i| cross(v[i], v[(i + 1) % n])).sum()
}

/// Whether the closed segments `a b` and `c d` intersect.
fn segments_cross(a: [f64; 2], b: [f64; 2], c: [f64; 2], d: [f64; 2]) -> bool {
    let o1 = cross(sub(b, a), sub(c, a));
    let o2 = cross(sub(b, a), sub(d, a));
    let o3 = cross(sub(d, c), sub(a, c));
    let o4 = cross(sub(d, c), sub(b, c));
    (o1 * o2 <= 0.0) && (o3 * o4 <= 0.0)
}

/// Why vertices do not make a valid polygon, if they do not.
pub(crate) fn check(v: &[[f64; 2]]) -> Result<(), String> {
    let n = v.len();
    if n < 3 {
        return Err(format!("{n} vertices (a polygon needs at least 3)"));
    }
    for i in 0..n {
        let side = sub(v[(i + 1) % n], v[i]);
        if side[0].hypot(side[1]) < MIN_SIDE {
            return Err(format!("side {i} is shorter than {MIN_SIDE} px"));
        }
    }
    if shoelace2(v) >= 0.0 {
        return Err("the vertices do not run counterclockwise on screen".into());
    }
    for i in 0..n {
        for j in i + 2..n {
            if i == 0 && j == n - 1 {
                continue; // adjacent through the closing edge
            }
            if segments_cross(v[i], v[(i + 1) % n], v[j], v[(j + 1) % n]) {
                return Err(format!("sides {i} and {j} cross"));
            }
        }
    }
    Ok(())
}

/// The part `[u_a, u_b]` of the segment `a -> b` inside the box
/// `[x0, x1] x [y0, y1]` (Liang–Barsky), if any of positive length.
fn clip_segment(a: [f64; 2], b: [f64; 2], bx: [f64; 4]) -> Option<(f64, f64)> {
    let d = sub(b, a);
    let (mut lo, mut hi) = (0.0f64, 1.0f64);
    for (p, q) in [
        (-d[0], a[0] - bx[0]),
        (d[0], bx[1] - a[0]),
        (-d[1], a[1] - bx[2]),
        (d[1], bx[3] - a[1]),
    ] {
        if p == 0.0 {
            if q < 0.0 {
                return None;
            }
        } else {
            let r = q / p;
            if p < 0.0 {
                lo = lo.max(r);
            } else {
                hi = hi.min(r);
            }
        }
    }
    (hi > lo).then_some((lo, hi))
}

/// The polygon `v` clipped to the half-plane `coord(axis) * sign <= limit *
/// sign` (one Sutherland–Hodgman pass).
fn clip_half(v: &[[f64; 2]], axis: usize, limit: f64, keep_below: bool) -> Vec<[f64; 2]> {
    let inside = |p: [f64; 2]| {
        if keep_below {
            p[axis] <= limit
        } else {
            p[axis] >= limit
        }
    };
    let mut out = Vec::with_capacity(v.len() + 4);
    let n = v.len();
    for i in 0..n {
        let (p, q) = (v[i], v[(i + 1) % n]);
        let (ip, iq) = (inside(p), inside(q));
        if ip {
            out.push(p);
        }
        if ip != iq {
            let t = (limit - p[axis]) / (q[axis] - p[axis]);
            let mut x = [p[0] + t * (q[0] - p[0]), p[1] + t * (q[1] - p[1])];
            x[axis] = limit;
            out.push(x);
        }
    }
    out
}

impl Polygon {
    /// `[x0, y0, x1, y1, ...]`.
    pub fn params(&self) -> Vec<f64> {
        self.v.iter().flat_map(|p| [p[0], p[1]]).collect()
    }

    /// From `[x0, y0, ...]`; `None` for an invalid polygon ([`check`]).
    pub fn with_params(&self, t: &[f64]) -> Option<Polygon> {
        if t.len() != 2 * self.v.len() {
            return None;
        }
        let v: Vec<[f64; 2]> = t.chunks_exact(2).map(|c| [c[0], c[1]]).collect();
        check(&v).ok()?;
        Some(Polygon { v })
    }

    /// Outward unit normal and length of edge `i`.
    fn edge_normal(&self, i: usize) -> ([f64; 2], f64) {
        let e = sub(self.v[(i + 1) % self.v.len()], self.v[i]);
        let len = e[0].hypot(e[1]);
        ([-e[1] / len, e[0] / len], len)
    }

    /// Whether `q` is inside (crossing number).
    fn contains(&self, q: [f64; 2]) -> bool {
        crate::curve::polygon_contains(&self.v, q)
    }

    /// See [`Local`] and the [module docs](self).
    pub fn local(&self, q: [f64; 2], ctx: PixelCtx) -> Local {
        let n = self.v.len();
        // Nearest and second-nearest edges.
        let (mut best, mut best_u, mut best_i) = (f64::INFINITY, 0.0, 0);
        let mut second = f64::INFINITY;
        let mut nearest_vertex = f64::INFINITY;
        for i in 0..n {
            let (a, b) = (self.v[i], self.v[(i + 1) % n]);
            let e = sub(b, a);
            let w = sub(q, a);
            let u = ((w[0] * e[0] + w[1] * e[1]) / (e[0] * e[0] + e[1] * e[1])).clamp(0.0, 1.0);
            let dist = (w[0] - u * e[0]).hypot(w[1] - u * e[1]);
            if dist < best {
                second = best;
                (best, best_u, best_i) = (dist, u, i);
            } else if dist < second {
                second = dist;
            }
            nearest_vertex = nearest_vertex.min(w[0].hypot(w[1]));
        }
        let sign = if self.contains(q) { -1.0 } else { 1.0 };
        let d = sign * best;
        if nearest_vertex < ctx.reach || second < ctx.reach {
            if !ctx.exact || ctx.exclude_corners {
                return Local::Excluded { d };
            }
            return match self.coverage(q) {
                Some((value, grad)) => Local::Coverage { d, value, grad },
                None => Local::Excluded { d },
            };
        }
        let j = (best_i + 1) % n;
        let (normal, grad) = if best_u > 0.0 && best_u < 1.0 {
            let (nrm, _) = self.edge_normal(best_i);
            let g = Grad::from_pairs(&[
                (2 * best_i, -(1.0 - best_u) * nrm[0]),
                (2 * best_i + 1, -(1.0 - best_u) * nrm[1]),
                (2 * j, -best_u * nrm[0]),
                (2 * j + 1, -best_u * nrm[1]),
            ]);
            (nrm, g)
        } else {
            // The closest point is a vertex: d = sign |q - v|.
            let k = if best_u <= 0.0 { best_i } else { j };
            let w = sub(q, self.v[k]);
            let len = w[0].hypot(w[1]).max(1e-12);
            let nrm = [sign * w[0] / len, sign * w[1] / len];
            (
                nrm,
                Grad::from_pairs(&[(2 * k, -nrm[0]), (2 * k + 1, -nrm[1])]),
            )
        };
        if ctx.exact {
            return edge_coverage(d, normal, &grad);
        }
        Local::Edge {
            d,
            normal,
            curvature: 0.0,
            grad,
        }
    }

    /// Exact covered fraction of the pixel centred at `q` and its
    /// derivatives (module docs); `None` when more vertices than a
    /// [`Grad`] holds are involved.
    pub fn coverage(&self, q: [f64; 2]) -> Option<(f64, Grad)> {
        let bx = [q[0] - 0.5, q[0] + 0.5, q[1] - 0.5, q[1] + 0.5];
        let mut poly = clip_half(&self.v, 0, bx[0], false);
        poly = clip_half(&poly, 0, bx[1], true);
        poly = clip_half(&poly, 1, bx[2], false);
        poly = clip_half(&poly, 1, bx[3], true);
        let value = if poly.len() < 3 {
            0.0
        } else {
            (-0.5 * shoelace2(&poly)).clamp(0.0, 1.0)
        };
        let n = self.v.len();
        let mut grad = Grad::new();
        for i in 0..n {
            let Some((ua, ub)) = clip_segment(self.v[i], self.v[(i + 1) % n], bx) else {
                continue;
            };
            let (nrm, len) = self.edge_normal(i);
            let i1 = 0.5 * (ub * ub - ua * ua);
            let w0 = len * (ub - ua - i1);
            let w1 = len * i1;
            let j = (i + 1) % n;
            let ok = grad.add(2 * i, w0 * nrm[0])
                && grad.add(2 * i + 1, w0 * nrm[1])
                && grad.add(2 * j, w1 * nrm[0])
                && grad.add(2 * j + 1, w1 * nrm[1]);
            if !ok {
                return None;
            }
        }
        Some((value, grad))
    }

    /// See [`super::geometry::Geometry::boundary`]: every vertex, then
    /// points along its edge.
    pub fn boundary(&self, step: f64) -> Vec<BoundaryPoint> {
        let n = self.v.len();
        let mut out = Vec::new();
        let mut s0 = 0.0;
        for i in 0..n {
            let (nrm, len) = self.edge_normal(i);
            let (a, b) = (self.v[i], self.v[(i + 1) % n]);
            let count = ((len / step).ceil() as usize).max(1);
            let j = (i + 1) % n;
            for k in 0..count {
                let u = k as f64 / count as f64;
                out.push(BoundaryPoint {
                    p: [a[0] + u * (b[0] - a[0]), a[1] + u * (b[1] - a[1])],
                    normal: nrm,
                    s: s0 + u * len,
                    grad: Grad::from_pairs(&[
                        (2 * i, -(1.0 - u) * nrm[0]),
                        (2 * i + 1, -(1.0 - u) * nrm[1]),
                        (2 * j, -u * nrm[0]),
                        (2 * j + 1, -u * nrm[1]),
                    ]),
                });
            }
            s0 += len;
        }
        out
    }

    /// See [`ModelShape::Polygon`].
    pub fn shape(&self) -> ModelShape {
        ModelShape::Polygon {
            vertices: self.v.clone(),
        }
    }

    /// `x0, y0, x1, y1, ...` with their covariance as it is.
    pub fn report(&self, cov: &[f64]) -> (Vec<Parameter>, Vec<f64>) {
        let names: Vec<String> = (0..self.v.len())
            .flat_map(|i| [format!("x{i}"), format!("y{i}")])
            .collect();
        let refs: Vec<&str> = names.iter().map(String::as_str).collect();
        let units = vec!["px"; refs.len()];
        (
            super::geometry::plain_report(&refs, &units, &self.params(), cov),
            cov.to_vec(),
        )
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn square() -> Polygon {
        // Counterclockwise on screen: right, up (y decreasing), left, down.
        Polygon {
            v: vec![[10.3, 20.2], [30.1, 19.7], [29.6, 0.4], [9.8, 1.1]],
        }
    }

    #[test]
    fn orientation_and_validity() {
        assert!(check(&square().v).is_ok());
        let mut rev = square().v;
        rev.reverse();
        assert!(check(&rev).is_err());
        let bow = vec![[0.0, 0.0], [10.0, 10.0], [10.0, 0.0], [0.0, 10.0]];
        assert!(check(&bow).is_err());
    }

    #[test]
    fn coverage_matches_the_renderer() {
        let p = square();
        let cov =
            crate::render::coverage::polygon_coverage(40, 25, std::slice::from_ref(&p.v)).unwrap();
        for (row, col) in [
            (20, 10),
            (1, 10),
            (0, 30),
            (20, 30),
            (10, 10),
            (10, 20),
            (5, 30),
        ] {
            let (value, _) = p.coverage([col as f64, row as f64]).unwrap();
            let want = cov[row * 40 + col];
            assert!(
                (value - want).abs() < 1e-12,
                "({row}, {col}): {value} vs {want}"
            );
        }
    }

    #[test]
    fn coverage_derivatives_match_finite_differences() {
        let p = square();
        let theta = p.params();
        for q in [
            [10.0, 20.0],
            [30.0, 20.0],
            [30.0, 0.0],
            [10.0, 1.0],
            [20.0, 20.0],
        ] {
            let (_, grad) = p.coverage(q).unwrap();
            for i in 0..theta.len() {
                let g = grad.iter().find(|e| e.0 == i).map_or(0.0, |e| e.1);
                let h = 1e-6;
                let value = |sign: f64| {
                    let mut t = theta.clone();
                    t[i] += sign * h;
                    p.with_params(&t).unwrap().coverage(q).unwrap().0
                };
                let fd = (value(1.0) - value(-1.0)) / (2.0 * h);
                assert!((fd - g).abs() < 1e-6, "{q:?} param {i}: {fd} vs {g}");
            }
        }
    }

    #[test]
    fn distance_derivatives_match_finite_differences() {
        let p = square();
        let theta = p.params();
        let ctx = PixelCtx {
            reach: 0.0,
            exact: false,
            exclude_corners: false,
        };
        for q in [
            [20.0, 21.0],
            [20.0, 19.0],
            [31.0, 10.0],
            [8.0, 22.0],
            [15.0, 1.5],
        ] {
            let Local::Edge { grad, d, .. } = p.local(q, ctx) else {
                panic!()
            };
            assert!(d.is_finite());
            for i in 0..theta.len() {
                let g = grad.iter().find(|e| e.0 == i).map_or(0.0, |e| e.1);
                let h = 1e-6;
                let dist = |sign: f64| {
                    let mut t = theta.clone();
                    t[i] += sign * h;
                    p.with_params(&t).unwrap().local(q, ctx).distance()
                };
                let fd = (dist(1.0) - dist(-1.0)) / (2.0 * h);
                assert!((fd - g).abs() < 1e-6, "{q:?} param {i}: {fd} vs {g}");
            }
        }
    }
}
