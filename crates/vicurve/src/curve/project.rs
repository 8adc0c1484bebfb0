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

/// Newton's last step, pixels of parameter. After a step `h` under this the
/// foot is exact to about `kappa h^2` (quadratic convergence: 1e-6 kappa px),
/// which moves `r` by far less (`r` is stationary at the foot), and the
/// frame there is the second-order Taylor expansion from the point before
/// the step: its position is off by `|C'''| h^3 / 6` (2e-10 px for
/// `|C'''|` up to 1), its tangent by `|C'''| h^2 / 2` (a rotation that
/// changes `r` by its square) and its curvature by `|C'''| h` (1e-3
/// `|C'''|` per px: 1e-8 for a radius of 300 px, which the pixel-edge
/// profile's curvature term scales by half the edge's variance).
const FINISH_STEP: f64 = 1e-3;

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
        // The derivatives at the last point evaluated, and the step taken
        // from there to `u`: the frame at `u` is their Taylor expansion
        // once that step is under `FINISH_STEP` (saves an evaluation per
        // pixel).
        let mut last = [[0.0; 2]; 3];
        let mut taken = f64::INFINITY;
        for _ in 0..12 {
            last = self.derivatives(u);
            taken = f64::INFINITY;
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
            // The move along the curve (a closed curve's wrap is no move;
            // an open curve's end may cut the step short).
            taken = if closed { step } else { next - u };
            u = next;
            if taken.abs() < FINISH_STEP {
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
        let f = if taken.abs() < FINISH_STEP {
            let [p, d1, d2] = last;
            let h = taken;
            super::frame_from(
                [
                    p[0] + h * (d1[0] + 0.5 * h * d2[0]),
                    p[1] + h * (d1[1] + 0.5 * h * d2[1]),
                ],
                [d1[0] + h * d2[0], d1[1] + h * d2[1]],
                d2,
            )
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
