//! The straight-line model: an edge or thin line along a straight segment.
//!
//! The line has direction `t = (cos alpha, -sin alpha)` (`alpha` in
//! radians, counterclockwise on screen from `+x`) and normal
//! `n = (-t_y, t_x) = (sin alpha, cos alpha)`, on the screen-right of the
//! direction of travel like every open curve. Its unknowns are `alpha` and
//! the offset `o` of the line from a fixed reference point `q0` (the centre
//! of the measured curve): `d(q) = n . (q - q0) - o`, so
//! `dd/dalpha = t . (q - q0)` and `dd/do = -1`. About the span's centre the
//! two are nearly uncorrelated; the reported distance from the image
//! origin, `n . q0 + o`, and its variance follow by propagation.
//!
//! Only the pixels whose projection on the line falls within the measured
//! span `[t_start, t_end]` (tangential coordinate about `q0`) belong to the
//! band: a straight edge of an object ends somewhere.

use super::geometry::{edge_coverage, BoundaryPoint, Grad, Local};
use super::{ModelShape, Parameter};
use std::f64::consts::PI;

/// A straight line over a span; see the [module docs](self).
#[derive(Clone, Copy, Debug, PartialEq)]
pub(crate) struct Line {
    /// Reference point, px.
    pub q0: [f64; 2],
    /// Direction angle, rad.
    pub alpha: f64,
    /// Offset along the normal from `q0`, px.
    pub offset: f64,
    /// Start of the span, tangential coordinate about `q0`, px.
    pub t_start: f64,
    /// End of the span, px (`> t_start`).
    pub t_end: f64,
}

impl Line {
    /// Unit direction and normal.
    fn frame(&self) -> ([f64; 2], [f64; 2]) {
        let (sn, cs) = self.alpha.sin_cos();
        ([cs, -sn], [sn, cs])
    }

    /// `[alpha, offset]`.
    pub fn params(&self) -> Vec<f64> {
        vec![self.alpha, self.offset]
    }

    /// From `[alpha, offset]`.
    pub fn with_params(&self, t: &[f64]) -> Option<Line> {
        (t.len() == 2).then_some(Line {
            alpha: t[0],
            offset: t[1],
            ..*self
        })
    }

    /// Half the span's length, px.
    pub fn half_span(&self) -> f64 {
        0.5 * (self.t_end - self.t_start)
    }

    /// See [`Local`]; by exact coverage when `exact` (an unblurred image).
    pub fn local(&self, q: [f64; 2], exact: bool) -> Local {
        let (t, n) = self.frame();
        let v = [q[0] - self.q0[0], q[1] - self.q0[1]];
        let d = n[0] * v[0] + n[1] * v[1] - self.offset;
        let grad = Grad::from_pairs(&[(0, t[0] * v[0] + t[1] * v[1]), (1, -1.0)]);
        if exact {
            return edge_coverage(d, n, &grad);
        }
        Local::Edge {
            d,
            normal: n,
            curvature: 0.0,
            grad,
        }
    }

    /// Whether `q` projects within the span.
    pub fn in_span(&self, q: [f64; 2]) -> bool {
        let (t, _) = self.frame();
        let u = t[0] * (q[0] - self.q0[0]) + t[1] * (q[1] - self.q0[1]);
        u >= self.t_start && u <= self.t_end
    }

    /// The point of the line at tangential coordinate `u`.
    fn point(&self, u: f64) -> [f64; 2] {
        let (t, n) = self.frame();
        [
            self.q0[0] + self.offset * n[0] + u * t[0],
            self.q0[1] + self.offset * n[1] + u * t[1],
        ]
    }

    /// See [`super::geometry::Geometry::boundary`]: both ends included.
    pub fn boundary(&self, step: f64) -> Vec<BoundaryPoint> {
        let (_, n) = self.frame();
        let len = self.t_end - self.t_start;
        let count = ((len / step).ceil() as usize).max(1);
        (0..=count)
            .map(|k| {
                let u = self.t_start + len * k as f64 / count as f64;
                BoundaryPoint {
                    p: self.point(u),
                    normal: n,
                    s: u - self.t_start,
                    grad: Grad::from_pairs(&[(0, u), (1, -1.0)]),
                }
            })
            .collect()
    }

    /// See [`ModelShape::Line`]: the span's end points on the line.
    pub fn shape(&self) -> ModelShape {
        ModelShape::Line {
            start: self.point(self.t_start),
            end: self.point(self.t_end),
        }
    }

    /// `angle` (in `(-pi, pi]`) and `distance` (from the image origin along
    /// the normal), with their covariance.
    pub fn report(&self, cov: &[f64]) -> (Vec<Parameter>, Vec<f64>) {
        let (t, n) = self.frame();
        let distance = n[0] * self.q0[0] + n[1] * self.q0[1] + self.offset;
        // d distance / d (alpha, offset).
        let j = [t[0] * self.q0[0] + t[1] * self.q0[1], 1.0];
        let var_d = j[0] * j[0] * cov[0] + 2.0 * j[0] * j[1] * cov[1] + j[1] * j[1] * cov[3];
        let cov_ad = j[0] * cov[0] + j[1] * cov[1];
        let mut angle = self.alpha.rem_euclid(2.0 * PI);
        if angle > PI {
            angle -= 2.0 * PI;
        }
        let c = vec![cov[0], cov_ad, cov_ad, var_d];
        let params = super::geometry::plain_report(
            &["angle", "distance"],
            &["rad", "px"],
            &[angle, distance],
            &c,
        );
        (params, c)
    }
}
