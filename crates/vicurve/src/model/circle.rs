//! The circle model: centre `(cx, cy)` and radius `r`, pixels.
//!
//! `d(q) = |q - c| - r`, normal `(q - c) / |q - c|`, curvature `-1 / r`
//! (convex, outward normal), and `dd/d(cx, cy, r) = (-n_x, -n_y, -1)`. The
//! boundary runs counterclockwise on screen, `p(t) = (cx + r cos t,
//! cy - r sin t)`, like [`crate::truth::Shape::Circle`].

use super::geometry::{plain_report, BoundaryPoint, Grad, Local};
use super::{ModelShape, Parameter};
use std::f64::consts::TAU;

/// Smallest radius a fit may reach, pixels.
const MIN_RADIUS: f64 = 1.0;

/// A circle; see the [module docs](self).
#[derive(Clone, Copy, Debug, PartialEq)]
pub(crate) struct Circle {
    /// Centre x (column), px.
    pub cx: f64,
    /// Centre y (row), px.
    pub cy: f64,
    /// Radius, px.
    pub r: f64,
}

impl Circle {
    /// `[cx, cy, r]`.
    pub fn params(&self) -> Vec<f64> {
        vec![self.cx, self.cy, self.r]
    }

    /// From `[cx, cy, r]`; `None` for a radius under a pixel.
    pub fn with_params(&self, t: &[f64]) -> Option<Circle> {
        (t.len() == 3 && t[2] >= MIN_RADIUS).then_some(Circle {
            cx: t[0],
            cy: t[1],
            r: t[2],
        })
    }

    /// See [`Local`]; by exact coverage when `exact` (an unblurred image).
    pub fn local(&self, q: [f64; 2], exact: bool) -> Local {
        let (dx, dy) = (q[0] - self.cx, q[1] - self.cy);
        let rho = dx.hypot(dy);
        if rho < 1e-9 {
            // The centre: no closest point (never in a band).
            return Local::Excluded { d: -self.r };
        }
        if exact {
            let (value, grad) = self.coverage(q);
            return Local::Coverage {
                d: rho - self.r,
                value,
                grad,
            };
        }
        let n = [dx / rho, dy / rho];
        Local::Edge {
            d: rho - self.r,
            normal: n,
            curvature: -1.0 / self.r,
            grad: Grad::from_pairs(&[(0, -n[0]), (1, -n[1]), (2, -1.0)]),
        }
    }

    /// The fraction of the pixel centred at `q` inside the circle, exact
    /// (module docs), and its derivatives by central differences (the
    /// area is exact to ~1e-12; a step of 1e-5 px leaves errors of ~1e-7
    /// in the derivatives, which only slow the iterations down).
    pub fn coverage(&self, q: [f64; 2]) -> (f64, Grad) {
        let bx = [q[0] - 0.5 - self.cx, q[0] + 0.5 - self.cx];
        let by = [q[1] - 0.5 - self.cy, q[1] + 0.5 - self.cy];
        let value = disc_box_area(self.r, bx, by);
        let h = 1e-5;
        let fd = |dx: f64, dy: f64, dr: f64| {
            let plus = disc_box_area(
                self.r + dr,
                [bx[0] - dx, bx[1] - dx],
                [by[0] - dy, by[1] - dy],
            );
            let minus = disc_box_area(
                self.r - dr,
                [bx[0] + dx, bx[1] + dx],
                [by[0] + dy, by[1] + dy],
            );
            (plus - minus) / (2.0 * h)
        };
        let grad = Grad::from_pairs(&[
            (0, fd(h, 0.0, 0.0)),
            (1, fd(0.0, h, 0.0)),
            (2, fd(0.0, 0.0, h)),
        ]);
        (value, grad)
    }

    /// See [`super::geometry::Geometry::boundary`].
    pub fn boundary(&self, step: f64) -> Vec<BoundaryPoint> {
        let count = ((TAU * self.r / step).ceil() as usize).max(8);
        (0..count)
            .map(|k| {
                let t = TAU * k as f64 / count as f64;
                let (sn, cs) = t.sin_cos();
                let n = [cs, -sn];
                BoundaryPoint {
                    p: [self.cx + self.r * cs, self.cy - self.r * sn],
                    normal: n,
                    s: self.r * t,
                    grad: Grad::from_pairs(&[(0, -n[0]), (1, -n[1]), (2, -1.0)]),
                }
            })
            .collect()
    }

    /// See [`ModelShape::Circle`].
    pub fn shape(&self) -> ModelShape {
        ModelShape::Circle {
            cx: self.cx,
            cy: self.cy,
            r: self.r,
        }
    }

    /// `cx, cy, r` with their covariance as it is.
    pub fn report(&self, cov: &[f64]) -> (Vec<Parameter>, Vec<f64>) {
        (
            plain_report(&["cx", "cy", "r"], &["px"; 3], &self.params(), cov),
            cov.to_vec(),
        )
    }
}

/// Area of the disc of radius `r` centred at the origin within the box
/// `bx[0] <= x <= bx[1]`, `by[0] <= y <= by[1]`: the integral over `x` of
/// the length of `[max(y0, -h), min(y1, h)]`, `h = sqrt(r^2 - x^2)`, split
/// where `h` crosses `|y0|` or `|y1|` so that each piece integrates in
/// closed form (`int h = (x h + r^2 asin(x / r)) / 2`).
fn disc_box_area(r: f64, bx: [f64; 2], by: [f64; 2]) -> f64 {
    let (lo, hi) = (bx[0].max(-r), bx[1].min(r));
    if hi <= lo || by[1] <= by[0] {
        return 0.0;
    }
    let h = |x: f64| (r * r - x * x).max(0.0).sqrt();
    let prim = |x: f64| {
        let x = x.clamp(-r, r);
        0.5 * (x * h(x) + r * r * (x / r).asin())
    };
    let mut cuts = [lo, hi, 0.0, 0.0, 0.0, 0.0];
    let mut n = 2;
    for y in by {
        if y.abs() < r {
            let x = (r * r - y * y).sqrt();
            for c in [-x, x] {
                if c > lo && c < hi {
                    cuts[n] = c;
                    n += 1;
                }
            }
        }
    }
    let cuts = &mut cuts[..n];
    cuts.sort_by(f64::total_cmp);
    let mut area = 0.0;
    for w in cuts.windows(2) {
        let (u, v) = (w[0], w[1]);
        if v <= u {
            continue;
        }
        let hm = h(0.5 * (u + v));
        let int_h = prim(v) - prim(u);
        let top = if by[1] < hm { by[1] * (v - u) } else { int_h };
        let (bottom, bottom_value) = if by[0] > -hm {
            (by[0] * (v - u), by[0])
        } else {
            (-int_h, -hm)
        };
        if by[1].min(hm) > bottom_value {
            area += top - bottom;
        }
    }
    area.clamp(0.0, (bx[1] - bx[0]) * (by[1] - by[0]))
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn disc_box_area_matches_the_renderer() {
        let c = Circle {
            cx: 20.37,
            cy: 19.71,
            r: 13.3,
        };
        let ring: Vec<[f64; 2]> = (0..200_000)
            .map(|k| {
                let t = TAU * k as f64 / 200_000.0;
                [c.cx + c.r * t.cos(), c.cy - c.r * t.sin()]
            })
            .collect();
        let cov = crate::render::coverage::polygon_coverage(40, 40, &[ring]).unwrap();
        let mut worst: f64 = 0.0;
        for row in 0..40 {
            for col in 0..40 {
                let (v, _) = c.coverage([col as f64, row as f64]);
                worst = worst.max((v - cov[row * 40 + col]).abs());
            }
        }
        // The polygon's chords (sagitta 2e-8 px) bound the difference.
        assert!(worst < 1e-7, "{worst}");
        // A box inside, a box outside, the whole disc.
        assert!((disc_box_area(2.0, [-0.5, 0.5], [-0.5, 0.5]) - 1.0).abs() < 1e-15);
        assert_eq!(disc_box_area(2.0, [3.0, 4.0], [0.0, 1.0]), 0.0);
        let whole = disc_box_area(2.0, [-3.0, 3.0], [-3.0, 3.0]);
        assert!((whole - std::f64::consts::PI * 4.0).abs() < 1e-12);
    }
}
