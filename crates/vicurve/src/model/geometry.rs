//! What a pixel sees of a shape model, and the dispatch over the models.
//!
//! Every model answers, for a pixel centre `q`, its signed distance `d` to
//! the shape (pixels, positive on the normal's side: outside a closed
//! shape, on the screen-right of a line's direction), the unit normal and
//! signed curvature at the closest point (the pixel-edge profile needs
//! them), and the derivatives `dd/dtheta` of the distance with respect to
//! the shape parameters. For a parametric boundary `p(s; theta)` these
//! follow from the envelope theorem: at the closest point `(q - p)` is
//! normal to the curve, so `dd/dtheta = -n . dp/dtheta` at fixed `s`.
//!
//! Near a polygon's vertex the straight-edge profile is wrong; there a
//! pixel is either modelled by its exact coverage ([`Local::Coverage`]) or
//! left out ([`Local::Excluded`]), see [`PixelCtx`]. In an unblurred image
//! the pixels of circles and straight edges are modelled by their exact
//! coverage too.

use super::circle::Circle;
use super::ellipse::Ellipse;
use super::line::Line;
use super::polygon::Polygon;
use super::{ModelShape, Parameter};

/// Most parameters one pixel depends on.
pub(crate) const MAX_GRAD: usize = 16;

/// A sparse gradient: parameter indices and values.
#[derive(Clone, Copy, Debug)]
pub(crate) struct Grad {
    idx: [usize; MAX_GRAD],
    val: [f64; MAX_GRAD],
    len: usize,
}

impl Grad {
    /// No entry.
    pub fn new() -> Self {
        Grad {
            idx: [0; MAX_GRAD],
            val: [0.0; MAX_GRAD],
            len: 0,
        }
    }

    /// From `(index, value)` pairs (at most [`MAX_GRAD`]).
    pub fn from_pairs(pairs: &[(usize, f64)]) -> Self {
        let mut g = Grad::new();
        for &(i, v) in pairs {
            g.add(i, v);
        }
        g
    }

    /// Add `v` to entry `i`; `false` when the gradient is full.
    pub fn add(&mut self, i: usize, v: f64) -> bool {
        if let Some(k) = self.idx[..self.len].iter().position(|&j| j == i) {
            self.val[k] += v;
            return true;
        }
        if self.len == MAX_GRAD {
            return false;
        }
        self.idx[self.len] = i;
        self.val[self.len] = v;
        self.len += 1;
        true
    }

    /// The entries.
    pub fn iter(&self) -> impl Iterator<Item = (usize, f64)> + '_ {
        self.idx[..self.len]
            .iter()
            .copied()
            .zip(self.val[..self.len].iter().copied())
    }
}

/// What one pixel sees of the shape.
#[derive(Clone, Copy, Debug)]
pub(crate) enum Local {
    /// Modelled by the edge (or line) profile of its signed distance.
    Edge {
        /// Signed distance, pixels.
        d: f64,
        /// Unit normal at the closest point.
        normal: [f64; 2],
        /// Signed curvature there, 1/px (negative on a convex closed shape).
        curvature: f64,
        /// `dd/dtheta`.
        grad: Grad,
    },
    /// Modelled by the exact fraction of the pixel inside the shape
    /// (polygon corners, blur neglected).
    Coverage {
        /// Signed distance, pixels (for the band's selection).
        d: f64,
        /// Covered fraction of the pixel, in `[0, 1]`.
        value: f64,
        /// `d value / d theta`.
        grad: Grad,
    },
    /// Left out of the fit (a polygon corner that no profile models).
    Excluded {
        /// Signed distance, pixels.
        d: f64,
    },
}

impl Local {
    /// The signed distance.
    pub fn distance(&self) -> f64 {
        match *self {
            Local::Edge { d, .. } | Local::Coverage { d, .. } | Local::Excluded { d } => d,
        }
    }
}

/// How the pixels are modelled.
#[derive(Clone, Copy, Debug, PartialEq)]
pub(crate) struct PixelCtx {
    /// A pixel whose centre is closer than this to a vertex, or to an edge
    /// other than its nearest, is a corner pixel (pixels): the pixel's
    /// footprint through the blur reaches another edge.
    pub reach: f64,
    /// The image is taken as unblurred: pixels are modelled by their exact
    /// coverage where the model has it (the whole circle, straight edges,
    /// polygon corners).
    pub exact: bool,
    /// Corner pixels are left out even when `exact`.
    pub exclude_corners: bool,
}

/// The exact coverage of a pixel by the half-plane `d < 0` of a straight
/// edge with unit normal `normal`, as [`Local::Coverage`], with `dd/dtheta`
/// `grad` (see [`step_coverage`]).
pub(crate) fn edge_coverage(d: f64, normal: [f64; 2], grad: &Grad) -> Local {
    let (value, density) = step_coverage(-d, normal);
    let mut g = Grad::new();
    for (i, v) in grad.iter() {
        g.add(i, -density * v);
    }
    Local::Coverage { d, value, grad: g }
}

/// `(P(T <= s), density of T at s)` for `T` the extent of a unit square
/// pixel along the unit vector `normal`: the sum of two uniform variables
/// of widths `|n_x|` and `|n_y|` (a trapezoid; the pixel-edge profile of
/// [`crate::virtual_image::pixel_edge`] without blur, exact down to
/// axis-aligned edges).
pub(crate) fn step_coverage(s: f64, normal: [f64; 2]) -> (f64, f64) {
    let (a, b) = {
        let (x, y) = (normal[0].abs(), normal[1].abs());
        if x >= y {
            (x, y)
        } else {
            (y, x)
        }
    };
    let (outer, inner) = (0.5 * (a + b), 0.5 * (a - b));
    if s <= -outer {
        (0.0, 0.0)
    } else if s >= outer {
        (1.0, 0.0)
    } else if s < -inner {
        let u = s + outer;
        (u * u / (2.0 * a * b), u / (a * b))
    } else if s <= inner {
        ((s + 0.5 * a) / a, 1.0 / a)
    } else {
        let u = outer - s;
        (1.0 - u * u / (2.0 * a * b), u / (a * b))
    }
}

/// A point of a fitted boundary, for output samples.
#[derive(Clone, Copy, Debug)]
pub(crate) struct BoundaryPoint {
    /// Position, pixels.
    pub p: [f64; 2],
    /// Unit normal (outward, or screen-right of a line).
    pub normal: [f64; 2],
    /// Arc length from the start, pixels.
    pub s: f64,
    /// `dd/dtheta` of a point on the boundary: minus the normal
    /// displacement of the boundary there per unit of each parameter.
    pub grad: Grad,
}

/// A shape model with its current parameters.
#[derive(Clone, Debug, PartialEq)]
pub(crate) enum Geometry {
    /// See [`Circle`].
    Circle(Circle),
    /// See [`Ellipse`].
    Ellipse(Ellipse),
    /// See [`Line`].
    Line(Line),
    /// See [`Polygon`].
    Polygon(Polygon),
}

impl Geometry {
    /// The parameter vector `theta`.
    pub fn params(&self) -> Vec<f64> {
        match self {
            Geometry::Circle(g) => g.params(),
            Geometry::Ellipse(g) => g.params(),
            Geometry::Line(g) => g.params(),
            Geometry::Polygon(g) => g.params(),
        }
    }

    /// The same model with parameters `theta`; `None` when they describe
    /// no valid shape (a radius under a pixel, a self-intersecting polygon).
    pub fn with_params(&self, theta: &[f64]) -> Option<Geometry> {
        if theta.iter().any(|v| !v.is_finite()) {
            return None;
        }
        Some(match self {
            Geometry::Circle(g) => Geometry::Circle(g.with_params(theta)?),
            Geometry::Ellipse(g) => Geometry::Ellipse(g.with_params(theta)?),
            Geometry::Line(g) => Geometry::Line(g.with_params(theta)?),
            Geometry::Polygon(g) => Geometry::Polygon(g.with_params(theta)?),
        })
    }

    /// What the pixel centred at `q` sees.
    pub fn local(&self, q: [f64; 2], ctx: PixelCtx) -> Local {
        match self {
            Geometry::Circle(g) => g.local(q, ctx.exact),
            Geometry::Ellipse(g) => g.local(q, ctx.exact),
            Geometry::Line(g) => g.local(q, ctx.exact),
            Geometry::Polygon(g) => g.local(q, ctx),
        }
    }

    /// Whether the pixel at `q` belongs to the part of the shape that is
    /// measured (a line's span; everything for closed shapes).
    pub fn in_span(&self, q: [f64; 2]) -> bool {
        match self {
            Geometry::Line(g) => g.in_span(q),
            _ => true,
        }
    }

    /// Whether the shape is closed (its band must lie inside the image).
    pub fn is_closed(&self) -> bool {
        !matches!(self, Geometry::Line(_))
    }

    /// Points of the boundary at most `step` pixels apart, with their
    /// normals and parameter derivatives.
    pub fn boundary(&self, step: f64) -> Vec<BoundaryPoint> {
        match self {
            Geometry::Circle(g) => g.boundary(step),
            Geometry::Ellipse(g) => g.boundary(step),
            Geometry::Line(g) => g.boundary(step),
            Geometry::Polygon(g) => g.boundary(step),
        }
    }

    /// Pixels per unit of each parameter (1 for lengths; a length for
    /// angles), to express a step in pixels.
    pub fn scales(&self) -> Vec<f64> {
        match self {
            Geometry::Ellipse(g) => vec![1.0, 1.0, 1.0, 1.0, g.a.max(g.b)],
            Geometry::Line(g) => vec![g.half_span().max(1.0), 1.0],
            other => vec![1.0; other.params().len()],
        }
    }

    /// The typed shape, normalised (an ellipse's `a >= b`, angles in their
    /// principal range).
    pub fn shape(&self) -> ModelShape {
        match self {
            Geometry::Circle(g) => g.shape(),
            Geometry::Ellipse(g) => g.normalised().shape(),
            Geometry::Line(g) => g.shape(),
            Geometry::Polygon(g) => g.shape(),
        }
    }

    /// The reported parameters and their covariance (row-major, same
    /// order) from the covariance `cov` of `theta` (row-major, `p x p`).
    pub fn report(&self, cov: &[f64]) -> (Vec<Parameter>, Vec<f64>) {
        match self {
            Geometry::Circle(g) => g.report(cov),
            Geometry::Ellipse(g) => g.report(cov),
            Geometry::Line(g) => g.report(cov),
            Geometry::Polygon(g) => g.report(cov),
        }
    }
}

/// `sqrt(g^T C g)` for a sparse `g` and a row-major `p x p` covariance.
pub(crate) fn quadratic_sigma(grad: &Grad, cov: &[f64], p: usize) -> f64 {
    let mut q = 0.0;
    for (i, gi) in grad.iter() {
        for (j, gj) in grad.iter() {
            q += gi * gj * cov[i * p + j];
        }
    }
    q.max(0.0).sqrt()
}

/// Parameters named `names` with the diagonal of `cov` as variances.
pub(crate) fn plain_report(
    names: &[&str],
    units: &[&'static str],
    values: &[f64],
    cov: &[f64],
) -> Vec<Parameter> {
    let p = values.len();
    names
        .iter()
        .zip(units)
        .zip(values)
        .enumerate()
        .map(|(i, ((name, unit), value))| Parameter {
            name: (*name).to_string(),
            value: *value,
            sigma: cov[i * p + i].max(0.0).sqrt(),
            unit,
        })
        .collect()
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::model::polygon::Polygon;
    use proptest::prelude::*;

    proptest! {
        /// The trapezoid's distribution is the exact coverage of the pixel
        /// by a half-plane (a large polygon clipped to the pixel), its
        /// density the derivative, for any direction and offset.
        #[test]
        fn step_coverage_is_the_half_plane_coverage(angle in -3.2f64..3.2, d in -1.2f64..1.2) {
            let n = [angle.cos(), angle.sin()];
            let t = [-n[1], n[0]];
            // The half-plane n . q <= -d as a large square, counterclockwise
            // on screen (its edges' outward normals (-t_y, t_x)).
            let (far, p) = (50.0, [-d * n[0], -d * n[1]]);
            let corner = |u: f64, w: f64| [p[0] + u * t[0] + w * n[0], p[1] + u * t[1] + w * n[1]];
            let mut v = vec![corner(-far, 0.0), corner(far, 0.0), corner(far, -2.0 * far), corner(-far, -2.0 * far)];
            if crate::model::polygon::shoelace2(&v) > 0.0 {
                v.reverse();
            }
            let (want, _) = Polygon { v }.coverage([0.0, 0.0]).unwrap();
            let (got, density) = step_coverage(-d, n);
            prop_assert!((got - want).abs() < 1e-12, "{} vs {}", got, want);
            let h = 1e-6;
            let fd = (step_coverage(-d + h, n).0 - step_coverage(-d - h, n).0) / (2.0 * h);
            prop_assert!((fd - density).abs() < 1e-4, "{} vs {}", fd, density);
        }
    }
}
