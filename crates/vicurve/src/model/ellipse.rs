//! The ellipse model: centre `(cx, cy)`, semi-axes `a`, `b` and the
//! direction `angle` of the `a` axis (radians from `+x`, counterclockwise
//! on screen, i.e. towards `-y`), exactly as [`crate::truth::Shape::Ellipse`]:
//! `p(s) = c + S (a cos s, b sin s)` with `S` the rotation by `angle`
//! followed by the flip of `y` (`s` the eccentric anomaly).
//!
//! The closest point of a pixel is found in the ellipse's own frame by the
//! monotone root-finding of Eberly ("Distance from a point to an ellipse"):
//! with `e0 >= e1` the semi-axes and `(y0, y1)` the point folded into the
//! first quadrant, the closest point is `x_i = e_i^2 y_i / (t + e_i^2)`
//! where `t` is the root of `F(t) = sum (e_i y_i / (t + e_i^2))^2 - 1`,
//! convex and decreasing for `t > -e1^2`; Newton's method from the left end
//! of Eberly's bracket, where `F >= 0`, climbs to the root monotonically.
//! The derivatives follow from the envelope theorem
//! (see [`super::geometry`]).

use super::geometry::{BoundaryPoint, Grad, Local};
use super::{ModelShape, Parameter};
use crate::virtual_image::ellipse::blurred_level_gradient;
use std::f64::consts::{FRAC_PI_2, PI, TAU};

/// Smallest semi-axis a fit may reach, pixels.
const MIN_AXIS: f64 = 1.0;
/// The blur's spread over the smallest radius of curvature from which the
/// model takes the blurred ellipse's exact level: where the pixel edge's
/// blurred osculating circle starts (`virtual_image/osculating.rs`).
const BLURRED_FROM: f64 = 0.1;

/// An ellipse; see the [module docs](self).
#[derive(Clone, Copy, Debug, PartialEq)]
pub(crate) struct Ellipse {
    /// Centre x (column), px.
    pub cx: f64,
    /// Centre y (row), px.
    pub cy: f64,
    /// Semi-axis along `angle`, px.
    pub a: f64,
    /// The other semi-axis, px.
    pub b: f64,
    /// Direction of the `a` axis, rad (counterclockwise on screen from `+x`).
    pub angle: f64,
}

/// The closest point to `(y0, y1)` (both `>= 0`) of the ellipse with
/// semi-axes `e0 >= e1 > 0` along x and y (module docs).
fn closest_folded(e0: f64, e1: f64, y0: f64, y1: f64) -> [f64; 2] {
    if y1 > 0.0 {
        if y0 <= 0.0 {
            return [0.0, e1];
        }
        let (a0, a1) = (e0 * y0, e1 * y1);
        let (s0, s1) = (e0 * e0, e1 * e1);
        let mut t = a1 - s1;
        for _ in 0..200 {
            let (r0, r1) = (a0 / (t + s0), a1 / (t + s1));
            let f = r0 * r0 + r1 * r1 - 1.0;
            if f <= 0.0 {
                break;
            }
            let df = -2.0 * (r0 * r0 / (t + s0) + r1 * r1 / (t + s1));
            let next = t - f / df;
            // No progress (or NaN): at the root, to rounding.
            if next.is_nan() || next <= t || next - t <= 1e-16 * (t.abs() + s0) {
                break;
            }
            t = next;
        }
        [s0 * y0 / (t + s0), s1 * y1 / (t + s1)]
    } else {
        // On the major axis: inside near the centre the closest point is
        // off the axis; farther out it is the vertex.
        let (num, den) = (e0 * y0, e0 * e0 - e1 * e1);
        if num < den {
            let x = num / den;
            [e0 * x, e1 * (1.0 - x * x).max(0.0).sqrt()]
        } else {
            [e0, 0.0]
        }
    }
}

impl Ellipse {
    /// `[cx, cy, a, b, angle]`.
    pub fn params(&self) -> Vec<f64> {
        vec![self.cx, self.cy, self.a, self.b, self.angle]
    }

    /// From `[cx, cy, a, b, angle]`; `None` for a semi-axis under a pixel.
    pub fn with_params(&self, t: &[f64]) -> Option<Ellipse> {
        (t.len() == 5 && t[2] >= MIN_AXIS && t[3] >= MIN_AXIS).then_some(Ellipse {
            cx: t[0],
            cy: t[1],
            a: t[2],
            b: t[3],
            angle: t[4],
        })
    }

    /// Local (y up, `a` axis along `u`) coordinates to a screen offset.
    #[inline]
    fn screen(&self, lx: f64, ly: f64) -> [f64; 2] {
        let (sa, ca) = self.angle.sin_cos();
        [lx * ca - ly * sa, -(lx * sa + ly * ca)]
    }

    /// Point, outward unit normal, curvature and `dd/dtheta` of the
    /// boundary at eccentric anomaly `s`.
    fn at(&self, s: f64) -> ([f64; 2], [f64; 2], f64, Grad) {
        let (sn, cs) = s.sin_cos();
        let (a, b) = (self.a, self.b);
        let (lx, ly) = (a * cs, b * sn);
        let off = self.screen(lx, ly);
        let p = [self.cx + off[0], self.cy + off[1]];
        let (nlx, nly) = (b * cs, a * sn);
        let len = nlx.hypot(nly);
        let n = self.screen(nlx / len, nly / len);
        let speed2 = a * a * sn * sn + b * b * cs * cs;
        let curvature = -a * b / (speed2 * speed2.sqrt());
        let (sa, ca) = self.angle.sin_cos();
        let da = [cs * ca, -cs * sa];
        let db = [-sn * sa, -sn * ca];
        let dangle = [-lx * sa - ly * ca, -(lx * ca - ly * sa)];
        let dot = |v: [f64; 2]| -(n[0] * v[0] + n[1] * v[1]);
        let grad = Grad::from_pairs(&[
            (0, -n[0]),
            (1, -n[1]),
            (2, dot(da)),
            (3, dot(db)),
            (4, dot(dangle)),
        ]);
        (p, n, curvature, grad)
    }

    /// Eccentric anomaly of the point of the ellipse closest to `q`.
    fn closest_anomaly(&self, q: [f64; 2]) -> f64 {
        let (sa, ca) = self.angle.sin_cos();
        let (x, y) = (q[0] - self.cx, q[1] - self.cy);
        let (u, v) = (x * ca - y * sa, -x * sa - y * ca);
        let (lx, ly) = if self.a >= self.b {
            let c = closest_folded(self.a, self.b, u.abs(), v.abs());
            (c[0], c[1])
        } else {
            let c = closest_folded(self.b, self.a, v.abs(), u.abs());
            (c[1], c[0])
        };
        (ly.copysign(v) / self.b).atan2(lx.copysign(u) / self.a)
    }

    /// See [`Local`]; by exact coverage when `exact` (an unblurred image).
    pub fn local(&self, q: [f64; 2], exact: bool) -> Local {
        let s = self.closest_anomaly(q);
        let (p, n, curvature, grad) = self.at(s);
        let d = n[0] * (q[0] - p[0]) + n[1] * (q[1] - p[1]);
        if exact {
            let (value, grad) = self.coverage(q);
            return Local::Coverage { d, value, grad };
        }
        Local::Edge {
            d,
            normal: n,
            curvature,
            grad,
        }
    }

    /// Whether a blur of spread variance `variance` (px^2) reaches the
    /// ellipse's sharpest bend: the spread over the smallest radius of
    /// curvature (`min(a, b)^2 / max(a, b)`) reaches [`BLURRED_FROM`]. The
    /// pixel-edge profile is an expansion in that ratio; there the model
    /// takes the blurred ellipse's exact level ([`Self::blurred`]).
    pub fn bends_under(&self, variance: f64) -> bool {
        let (long, short) = (self.a.max(self.b), self.a.min(self.b));
        variance.sqrt() * long / (short * short) >= BLURRED_FROM
    }

    /// The level the pixel centred at `q` sees of the ellipse under an
    /// isotropic Gaussian blur of variance `variance` (px^2, the pixel's
    /// own spread included), exactly (`virtual_image/ellipse.rs`), and its
    /// derivatives in `[cx, cy, a, b, angle]` (from those in the ellipse's
    /// frame: `u = x cos - y sin`, `w = -x sin - y cos` of `(x, y) = q -
    /// centre`).
    pub fn blurred(&self, q: [f64; 2], variance: f64) -> (f64, Grad) {
        let (sa, ca) = self.angle.sin_cos();
        let (x, y) = (q[0] - self.cx, q[1] - self.cy);
        let (u, w) = (x * ca - y * sa, -x * sa - y * ca);
        let (level, [du, dw, da, db]) = blurred_level_gradient(u, w, (self.a, self.b), variance);
        let grad = Grad::from_pairs(&[
            (0, -du * ca + dw * sa),
            (1, du * sa + dw * ca),
            (2, da),
            (3, db),
            (4, du * w - dw * u),
        ]);
        (level, grad)
    }

    /// The fraction of the pixel centred at `q` inside the ellipse: in the
    /// ellipse's frame scaled to the unit disc the pixel is a parallelogram,
    /// and the area of the disc within a convex polygon is the sum over its
    /// edges of the signed areas of the disc within the triangles (centre,
    /// edge) ([`disc_triangle`]); times `a b`. Derivatives by central
    /// differences (steps of 1e-5 px; the angle's scaled by the size).
    pub fn coverage(&self, q: [f64; 2]) -> (f64, Grad) {
        let value = |e: &Ellipse| {
            let (sa, ca) = e.angle.sin_cos();
            let corner = |dx: f64, dy: f64| {
                let (x, y) = (q[0] + dx - e.cx, q[1] + dy - e.cy);
                [(x * ca - y * sa) / e.a, (-x * sa - y * ca) / e.b]
            };
            let p = [
                corner(-0.5, -0.5),
                corner(0.5, -0.5),
                corner(0.5, 0.5),
                corner(-0.5, 0.5),
            ];
            let sum: f64 = (0..4).map(|k| disc_triangle(p[k], p[(k + 1) % 4])).sum();
            (e.a * e.b * sum.abs()).clamp(0.0, 1.0)
        };
        (value(self), self.central_differences(value))
    }

    /// The derivatives of `value` in `[cx, cy, a, b, angle]` by central
    /// differences (steps of 1e-5 px; the angle's scaled by the size).
    fn central_differences(&self, value: impl Fn(&Ellipse) -> f64) -> Grad {
        let theta = self.params();
        let mut grad = Grad::new();
        for (i, h) in [1e-5, 1e-5, 1e-5, 1e-5, 1e-5 / self.a.max(self.b)]
            .into_iter()
            .enumerate()
        {
            let shifted = |sign: f64| {
                let mut t = theta.clone();
                t[i] += sign * h;
                Ellipse {
                    cx: t[0],
                    cy: t[1],
                    a: t[2],
                    b: t[3],
                    angle: t[4],
                }
            };
            grad.add(
                i,
                (value(&shifted(1.0)) - value(&shifted(-1.0))) / (2.0 * h),
            );
        }
        grad
    }

    /// See [`super::geometry::Geometry::boundary`]: uniform in the
    /// anomaly, fine enough at the fastest part; `s` by chords.
    pub fn boundary(&self, step: f64) -> Vec<BoundaryPoint> {
        let count = ((TAU * self.a.max(self.b) / step).ceil() as usize).max(16);
        let mut out: Vec<BoundaryPoint> = Vec::with_capacity(count);
        for k in 0..count {
            let (p, normal, _, grad) = self.at(TAU * k as f64 / count as f64);
            let s = out.last().map_or(0.0, |prev| {
                prev.s + (p[0] - prev.p[0]).hypot(p[1] - prev.p[1])
            });
            out.push(BoundaryPoint { p, normal, s, grad });
        }
        out
    }

    /// The same ellipse with `a >= b` and `angle` in `(-pi/2, pi/2]`.
    pub fn normalised(&self) -> Ellipse {
        let mut e = *self;
        if e.b > e.a {
            std::mem::swap(&mut e.a, &mut e.b);
            e.angle += FRAC_PI_2;
        }
        e.angle = e.angle.rem_euclid(PI);
        if e.angle > FRAC_PI_2 {
            e.angle -= PI;
        }
        e
    }

    /// See [`ModelShape::Ellipse`].
    pub fn shape(&self) -> ModelShape {
        ModelShape::Ellipse {
            cx: self.cx,
            cy: self.cy,
            a: self.a,
            b: self.b,
            angle: self.angle,
        }
    }

    /// The normalised parameters, the covariance permuted when the axes
    /// were swapped.
    pub fn report(&self, cov: &[f64]) -> (Vec<Parameter>, Vec<f64>) {
        let e = self.normalised();
        let perm: [usize; 5] = if e.a == self.a {
            [0, 1, 2, 3, 4]
        } else {
            [0, 1, 3, 2, 4]
        };
        let mut c = vec![0.0; 25];
        for i in 0..5 {
            for j in 0..5 {
                c[i * 5 + j] = cov[perm[i] * 5 + perm[j]];
            }
        }
        let params = super::geometry::plain_report(
            &["cx", "cy", "a", "b", "angle"],
            &["px", "px", "px", "px", "rad"],
            &e.params(),
            &c,
        );
        (params, c)
    }
}

/// Signed area of the unit disc within the triangle `(0, a, b)`: the
/// segment `a b` is cut where it crosses the circle; a piece inside adds
/// its triangle with the origin, a piece outside the circular sector it
/// subtends.
fn disc_triangle(a: [f64; 2], b: [f64; 2]) -> f64 {
    let d = [b[0] - a[0], b[1] - a[1]];
    let qa = d[0] * d[0] + d[1] * d[1];
    if qa == 0.0 {
        return 0.0;
    }
    let qb = a[0] * d[0] + a[1] * d[1];
    let qc = a[0] * a[0] + a[1] * a[1] - 1.0;
    let disc = qb * qb - qa * qc;
    let mut cuts = [0.0, 1.0, 1.0, 1.0];
    let mut n = 1;
    if disc > 0.0 {
        let root = disc.sqrt();
        for t in [(-qb - root) / qa, (-qb + root) / qa] {
            if t > 0.0 && t < 1.0 {
                cuts[n] = t;
                n += 1;
            }
        }
    }
    cuts[n] = 1.0;
    let at = |t: f64| [a[0] + t * d[0], a[1] + t * d[1]];
    let mut area = 0.0;
    for w in cuts[..=n].windows(2) {
        let (p, q) = (at(w[0]), at(w[1]));
        let m = at(0.5 * (w[0] + w[1]));
        let cross = p[0] * q[1] - p[1] * q[0];
        if m[0] * m[0] + m[1] * m[1] <= 1.0 {
            area += 0.5 * cross;
        } else {
            area += 0.5 * cross.atan2(p[0] * q[0] + p[1] * q[1]);
        }
    }
    area
}

#[cfg(test)]
mod tests {
    use super::*;

    /// The blurred level's derivatives in the parameters match central
    /// differences of the level.
    #[test]
    fn blurred_derivatives_match_differences() {
        let e = Ellipse {
            cx: 20.3,
            cy: 19.6,
            a: 6.0,
            b: 3.6,
            angle: 0.7,
        };
        let v = 6.33;
        for q in [[20.0, 20.0], [25.0, 22.0], [14.5, 17.0], [21.0, 13.0]] {
            let (_, grad) = e.blurred(q, v);
            let fd = e.central_differences(|f: &Ellipse| f.blurred(q, v).0);
            let value = |g: &Grad, i: usize| g.iter().find(|p| p.0 == i).map_or(0.0, |p| p.1);
            for i in 0..5 {
                let (g, f) = (value(&grad, i), value(&fd, i));
                assert!((g - f).abs() < 1e-6, "{q:?} d{i}: {g} vs {f}");
            }
        }
    }

    /// Brute force: the distance to a fine polygon of the ellipse.
    fn brute(e: &Ellipse, q: [f64; 2]) -> f64 {
        let n = 200_000;
        (0..n)
            .map(|k| {
                let (p, ..) = e.at(TAU * k as f64 / n as f64);
                (p[0] - q[0]).hypot(p[1] - q[1])
            })
            .fold(f64::INFINITY, f64::min)
    }

    #[test]
    fn distance_matches_brute_force() {
        for e in [
            Ellipse {
                cx: 50.3,
                cy: 40.1,
                a: 30.0,
                b: 12.0,
                angle: 0.4,
            },
            Ellipse {
                cx: 50.3,
                cy: 40.1,
                a: 9.0,
                b: 25.0,
                angle: -1.1,
            },
        ] {
            for k in 0..40 {
                let t = k as f64 * 0.37;
                let r = 0.6 + 0.05 * k as f64;
                let q = [e.cx + 20.0 * r * t.cos(), e.cy + 20.0 * r * t.sin()];
                let Local::Edge { d, .. } = e.local(q, false) else {
                    panic!("not an edge")
                };
                let want = brute(&e, q);
                assert!((d.abs() - want).abs() < 1e-6, "{q:?}: {d} vs {want}");
            }
        }
    }

    #[test]
    fn coverage_matches_the_renderer() {
        let e = Ellipse {
            cx: 20.37,
            cy: 19.71,
            a: 14.3,
            b: 6.2,
            angle: 0.7,
        };
        let ring: Vec<[f64; 2]> = (0..200_000)
            .map(|k| e.at(TAU * k as f64 / 200_000.0).0)
            .collect();
        let cov = crate::render::coverage::polygon_coverage(40, 40, &[ring]).unwrap();
        let mut worst: f64 = 0.0;
        for row in 0..40 {
            for col in 0..40 {
                let (v, _) = e.coverage([col as f64, row as f64]);
                worst = worst.max((v - cov[row * 40 + col]).abs());
            }
        }
        // The polygon's chords (sagitta under 1e-7 px) bound the difference.
        assert!(worst < 1e-6, "{worst}");
    }

    #[test]
    fn derivatives_match_finite_differences() {
        let e = Ellipse {
            cx: 50.3,
            cy: 40.1,
            a: 30.0,
            b: 12.0,
            angle: 0.4,
        };
        let theta = e.params();
        for q in [[80.0, 35.0], [50.0, 27.5], [30.0, 60.0], [62.0, 44.0]] {
            let Local::Edge { grad, .. } = e.local(q, false) else {
                panic!()
            };
            for (i, g) in grad.iter() {
                let h = 1e-6;
                let dist = |sign: f64| {
                    let mut t = theta.clone();
                    t[i] += sign * h;
                    e.with_params(&t).unwrap().local(q, false).distance()
                };
                let fd = (dist(1.0) - dist(-1.0)) / (2.0 * h);
                assert!((fd - g).abs() < 1e-6, "{q:?} param {i}: {fd} vs {g}");
            }
        }
    }
}
