//! Closest-point projection onto a [`SplineCurve`].

use super::SplineCurve;

/// Where a point projects onto a curve.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Projection {
    /// Parameter of the closest point, pixels.
    pub u: f64,
    /// Signed distance along the normal at that point (positive on the
    /// normal's side), pixels.
    pub r: f64,
    /// Signed curvature at the closest point, 1/pixels.
    pub curvature: f64,
    /// Unit normal at the closest point.
    pub normal: [f64; 2],
    /// True when the closest point is an end of an open curve (the point is
    /// past the end, not beside the curve), or the vertex of a corner (the
    /// point is in the wedge beyond it; see `curve/corners.rs`).
    pub at_end: bool,
}

impl SplineCurve {
    /// Closest point of the curve to `(x, y)` by Newton's method on
    /// `(X - C(u)) . C'(u) = 0`, started at `u0` (which must be near the
    /// global closest point: the band builder gets it from a polyline
    /// search). Converges to ~1e-10 px in 2 to 3 steps from a start within a
    /// fraction of a pixel; steps are limited to one element
    /// so that a poor start cannot jump across the curve.
    pub fn project(&self, x: f64, y: f64, u0: f64) -> Projection {
        if !self.corners.is_empty() {
            return self.project_cornered(x, y, u0);
        }
        let l = self.param_length();
        let closed = self.is_closed();
        let max_step = self.basis().element_length();
        let mut u = u0;
        let mut at_end = false;
        // The derivatives at `evaluated_at`, reused for the frame when the
        // last Newton step was negligible (saves an evaluation per pixel).
        let mut evaluated_at = f64::NAN;
        let mut last = [[0.0; 2]; 3];
        for _ in 0..12 {
            last = self.derivatives(u);
            evaluated_at = u;
            let [p, d1, d2] = last;
            let dx = x - p[0];
            let dy = y - p[1];
            let g = dx * d1[0] + dy * d1[1];
            let hess = d1[0] * d1[0] + d1[1] * d1[1] - (dx * d2[0] + dy * d2[1]);
            // Outside the convex region (near a focal point) Newton's
            // direction is wrong: fall back to a gradient step.
            let step = if hess > 1e-12 {
                g / hess
            } else {
                g / (d1[0] * d1[0] + d1[1] * d1[1]).max(1e-12)
            };
            let step = step.clamp(-max_step, max_step);
            let mut next = u + step;
            if closed {
                if !(0.0..l).contains(&next) {
                    next = next.rem_euclid(l);
                }
            } else if next <= 0.0 || next >= l {
                next = next.clamp(0.0, l);
                if next == u {
                    at_end = true;
                    break;
                }
            }
            u = next;
            // Quadratic convergence: after a step under 1e-5 px the foot is
            // exact to ~kappa 1e-10 px, and the frame kept from before the
            // step is off by 1e-5 px along the tangent only, which changes r
            // by ~kappa 1e-10 px.
            if step.abs() < 1e-5 {
                break;
            }
        }
        if !closed && (u <= 0.0 || u >= l) {
            // At an end: beside the curve only if the tangential offset vanishes.
            let [p, d1, _] = self.derivatives(u);
            let g = (x - p[0]) * d1[0] + (y - p[1]) * d1[1];
            let speed = (d1[0] * d1[0] + d1[1] * d1[1]).sqrt();
            at_end = at_end || g.abs() > 1e-9 * speed.max(1.0);
        }
        let f = if (u - evaluated_at).abs() < 1e-5 {
            super::frame_from(last[0], last[1], last[2])
        } else {
            self.frame(u)
        };
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
