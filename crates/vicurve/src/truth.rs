//! Ground truth: curves whose geometry is known exactly and the signed
//! distance of measured points to them (the truth file written next to a
//! synthetic image is [`crate::render::Truth`]).
//!
//! # Conventions
//! Coordinates are pixels (`x` = column, `y` = row, y pointing down on
//! screen). Every shape is a parametric curve `p(s)`:
//! - closed shapes run counterclockwise *as seen on screen* for `s` in
//!   `[0, 2π)`, so the unit normal `n = (-t_y, t_x)` of the unit tangent `t`
//!   points outward;
//! - a [`Shape::Polygon`] has corners: its distance is computed edge by
//!   edge, exactly, and at a vertex its normal is that of the edge starting
//!   there;
//! - the open [`Shape::Sine`] is travelled in `+x` (its parameter is `x`), so
//!   `n` points to `+y` (down on screen).
//!
//! Signed distances are positive on the `+n` side: outside closed shapes,
//! below (larger `y`) the sine.
//!
//! Closest points are exact to rounding: a coarse sampling of the parameter
//! brackets every local minimum of the distance, each is refined by a
//! safeguarded Newton iteration, and the global minimum is kept (so the
//! concave parts of a star are handled).

mod geometry;
mod polygon;
pub mod specimen;

use std::f64::consts::PI;

use serde::{Deserialize, Serialize};

use crate::error::{Error, Result};

pub use crate::virtual_image::Kind;

/// A curve of exactly known geometry. All lengths are in pixels, angles in
/// radians; see the [module documentation](self) for the orientation.
///
/// Serialised with a `"shape"` tag, e.g.
/// `{"shape": "circle", "cx": 100.0, "cy": 80.0, "r": 40.0}`.
///
/// Why not one type with [`crate::model::ModelShape`] and
/// [`crate::curve::InitialCurve`]: a truth shape is exact geometry, drawn
/// into synthetic images and measured against (exact closest points and
/// signed distances); it has stars and sines, which no model fits. A model
/// shape is a fit's parameters (lines and polygons, normalised results);
/// an initial curve is a user's rough start, turned into a B-spline. The
/// circle and ellipse have the same fields and JSON in `Shape` and
/// `ModelShape`, so a model's result reads as a truth file's shape
/// ([`crate::model::ModelShape::to_truth`]).
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
#[serde(tag = "shape", rename_all = "snake_case")]
pub enum Shape {
    /// Circle of centre `(cx, cy)` and radius `r > 0`:
    /// `p(s) = (cx + r cos s, cy - r sin s)`.
    Circle {
        /// Centre, x (column), px.
        cx: f64,
        /// Centre, y (row), px.
        cy: f64,
        /// Radius, px.
        r: f64,
    },
    /// Ellipse of centre `(cx, cy)`, semi-axes `a, b > 0`, the `a` axis at
    /// `angle` radians from `+x`, counterclockwise on screen (towards `-y`).
    /// The parameter `s` is the eccentric anomaly.
    Ellipse {
        /// Centre, x (column), px.
        cx: f64,
        /// Centre, y (row), px.
        cy: f64,
        /// Semi-axis along the direction `angle`, px.
        a: f64,
        /// The other semi-axis, px.
        b: f64,
        /// Direction of the `a` axis from `+x`, counterclockwise on screen, rad.
        angle: f64,
    },
    /// Star: in polar coordinates about `(cx, cy)`,
    /// `r(θ) = r0 (1 + amplitude cos(lobes θ + phase))`, `θ` counterclockwise
    /// on screen from `+x`, i.e. `p(θ) = (cx + r cos θ, cy - r sin θ)`.
    /// Concave parts are allowed.
    Star {
        /// Centre, x (column), px.
        cx: f64,
        /// Centre, y (row), px.
        cy: f64,
        /// Mean radius, px, `> 0`.
        r0: f64,
        /// Relative amplitude, `|amplitude| < 1`.
        amplitude: f64,
        /// Number of lobes, `>= 1`.
        lobes: u32,
        /// Phase, rad.
        phase: f64,
    },
    /// Regular polygon of centre `(cx, cy)` and circumradius `r > 0`, with
    /// `sides >= 3` straight edges: vertex `k` at the polar angle
    /// `angle + 2πk / sides`, i.e. `(cx + r cos θ_k, cy - r sin θ_k)`,
    /// counterclockwise on screen; `s` in `[2πk/n, 2π(k+1)/n]` runs linearly
    /// along the edge from vertex `k` to `k + 1`. Its corners make it the
    /// test of `FitConfig::breaks`; a line (contour) cannot be drawn along it
    /// by exact coverage (its smallest radius of curvature is 0).
    Polygon {
        /// Centre, x (column), px.
        cx: f64,
        /// Centre, y (row), px.
        cy: f64,
        /// Circumradius (centre to vertex), px.
        r: f64,
        /// Number of edges, 3 to 10000.
        sides: u32,
        /// Polar angle of vertex 0 from `+x`, counterclockwise on screen, rad.
        angle: f64,
    },
    /// Open curve `y = y0 + amplitude sin(2π x / wavelength + phase)` for `x`
    /// in `[x_min, x_max]`, travelled in `+x` (parameter `s = x`).
    ///
    /// `x_min..x_max` is the part that is *measured* ([`Shape::polyline`],
    /// [`Shape::length`]); images draw the infinite sine across the whole
    /// image, and [`Shape::signed_distance`] is the distance to the infinite
    /// sine (also for points whose closest point lies beyond `x_min` or
    /// `x_max`), so that there is no end effect.
    Sine {
        /// Mean ordinate, px.
        y0: f64,
        /// Amplitude, px (any sign; 0 is a horizontal line).
        amplitude: f64,
        /// Wavelength, px, `> 0`.
        wavelength: f64,
        /// Phase, rad.
        phase: f64,
        /// Start of the measured part, px.
        x_min: f64,
        /// End of the measured part, px, `> x_min`.
        x_max: f64,
    },
}

impl Shape {
    /// Check the parameters: all finite, radii, semi-axes, wavelength `> 0`,
    /// `|amplitude| < 1` and `1 <= lobes <= 10000` for a star (which makes it
    /// star-shaped about its centre, with a smooth boundary of finite
    /// curvature), `3 <= sides <= 10000` for a polygon, `x_min < x_max` for a
    /// sine.
    ///
    /// Errors: [`Error::InvalidParameter`] naming the parameter.
    pub fn validate(&self) -> Result<()> {
        fn finite(name: &'static str, v: f64) -> Result<()> {
            if v.is_finite() {
                Ok(())
            } else {
                Err(Error::invalid(name, format!("{v} is not a finite number")))
            }
        }
        fn positive(name: &'static str, v: f64) -> Result<()> {
            finite(name, v)?;
            if v > 0.0 {
                Ok(())
            } else {
                Err(Error::invalid(name, format!("{v} must be > 0 px")))
            }
        }
        match *self {
            Shape::Circle { cx, cy, r } => {
                finite("cx", cx)?;
                finite("cy", cy)?;
                positive("r", r)
            }
            Shape::Ellipse {
                cx,
                cy,
                a,
                b,
                angle,
            } => {
                finite("cx", cx)?;
                finite("cy", cy)?;
                positive("a", a)?;
                positive("b", b)?;
                finite("angle", angle)
            }
            Shape::Star {
                cx,
                cy,
                r0,
                amplitude,
                lobes,
                phase,
            } => {
                finite("cx", cx)?;
                finite("cy", cy)?;
                positive("r0", r0)?;
                finite("phase", phase)?;
                finite("amplitude", amplitude)?;
                if amplitude.abs() >= 1.0 {
                    return Err(Error::invalid(
                        "amplitude",
                        format!(
                            "{amplitude}: a star needs |amplitude| < 1 so that its radius stays > 0"
                        ),
                    ));
                }
                if !(1..=10_000).contains(&lobes) {
                    return Err(Error::invalid(
                        "lobes",
                        format!("{lobes}: a star needs 1 to 10000 lobes (use a circle for 0)"),
                    ));
                }
                Ok(())
            }
            Shape::Polygon {
                cx,
                cy,
                r,
                sides,
                angle,
            } => {
                finite("cx", cx)?;
                finite("cy", cy)?;
                positive("r", r)?;
                finite("angle", angle)?;
                if !(3..=10_000).contains(&sides) {
                    return Err(Error::invalid(
                        "sides",
                        format!("{sides}: a polygon needs 3 to 10000 sides"),
                    ));
                }
                Ok(())
            }
            Shape::Sine {
                y0,
                amplitude,
                wavelength,
                phase,
                x_min,
                x_max,
            } => {
                finite("y0", y0)?;
                finite("amplitude", amplitude)?;
                positive("wavelength", wavelength)?;
                finite("phase", phase)?;
                finite("x_min", x_min)?;
                finite("x_max", x_max)?;
                if x_min < x_max {
                    Ok(())
                } else {
                    Err(Error::invalid(
                        "x_max",
                        format!("x_max ({x_max}) must be greater than x_min ({x_min})"),
                    ))
                }
            }
        }
    }

    /// The corners of the curve, px: a polygon's vertices (counterclockwise
    /// on screen, vertex 0 first), none for the smooth shapes.
    pub fn corners(&self) -> Vec<[f64; 2]> {
        polygon::vertices(self)
    }

    /// Whether the curve is closed (every shape but [`Shape::Sine`]).
    pub fn is_closed(&self) -> bool {
        !matches!(self, Shape::Sine { .. })
    }

    /// Signed distance, px, from the point `(x, y)` to the curve: positive on
    /// the `+n` side (outside closed shapes, larger `y` for the sine), zero
    /// on the curve. Exact to rounding (about `1e-13` relative to the
    /// coordinates). For the sine, the distance to the *infinite* sine.
    ///
    /// The shape must be valid ([`Shape::validate`]); NaN for a non-finite
    /// point or an invalid shape.
    pub fn signed_distance(&self, x: f64, y: f64) -> f64 {
        let q = [x, y];
        if let Shape::Polygon { sides, .. } = *self {
            return polygon::signed_distance(self, sides, q);
        }
        let s = self.closest_param(q);
        let e = self.eval(s);
        let d = [x - e.p[0], y - e.p[1]];
        let dist = d[0].hypot(d[1]);
        let n = e.normal();
        if d[0] * n[0] + d[1] * n[1] < 0.0 {
            -dist
        } else {
            dist
        }
    }

    /// The point of the curve closest to `(x, y)` and the curve's unit
    /// normal `n` there (outward for closed shapes, `+y`-ish for the sine),
    /// px. When several points are equally close (the centre of a circle),
    /// one of them. For a polygon whose closest point is a vertex, the unit
    /// vector from it to `(x, y)` (so that the point is always the closest
    /// point plus the signed distance times `n`). Same accuracy and
    /// preconditions as [`Shape::signed_distance`].
    pub fn closest_point(&self, x: f64, y: f64) -> ([f64; 2], [f64; 2]) {
        if let Shape::Polygon { sides, .. } = *self {
            return polygon::closest_point(self, sides, [x, y]);
        }
        let e = self.eval(self.closest_param([x, y]));
        (e.p, e.normal())
    }

    /// Points along the curve in its orientation, evenly spaced in arc
    /// length, consecutive points at most `max_step` px apart. Closed
    /// shapes: starts at `s = 0`, the last point differs from the first (the
    /// closing chord is also `<= max_step`). Sine: from `x_min` to `x_max`
    /// included.
    ///
    /// Errors: [`Error::InvalidParameter`] when `max_step` is not a positive
    /// finite number, would give more than 50 million points, or the shape is
    /// invalid.
    pub fn polyline(&self, max_step: f64) -> Result<Vec<[f64; 2]>> {
        self.validate()?;
        if !(max_step.is_finite() && max_step > 0.0) {
            return Err(Error::invalid(
                "max_step",
                format!("{max_step} must be a positive number of pixels"),
            ));
        }
        self.polyline_unchecked(max_step, 50_000_000)
    }

    /// Length of the curve, px (of the `x_min..x_max` part for the sine).
    /// Numerical (composite Gauss-Legendre), relative accuracy about `1e-13`.
    /// NaN for an invalid shape.
    pub fn length(&self) -> f64 {
        let (s0, s1) = self.param_span();
        self.length_between(s0, s1)
    }

    /// Area enclosed by a closed shape, px² (exact closed form:
    /// `π r²`, `π a b`, `π r0² (1 + amplitude²/2)` for a star,
    /// `n r² sin(2π/n) / 2` for a polygon); `None` for the sine.
    pub fn area(&self) -> Option<f64> {
        match *self {
            Shape::Circle { r, .. } => Some(PI * r * r),
            Shape::Ellipse { a, b, .. } => Some(PI * a * b),
            Shape::Star { r0, amplitude, .. } => {
                Some(PI * r0 * r0 * (1.0 + 0.5 * amplitude * amplitude))
            }
            Shape::Polygon { r, sides, .. } => {
                let n = f64::from(sides);
                Some(0.5 * n * r * r * (2.0 * PI / n).sin())
            }
            Shape::Sine { .. } => None,
        }
    }

    /// Smallest absolute radius of curvature along the curve, px (for the
    /// sine, along the infinite curve; `f64::INFINITY` for a straight line;
    /// 0 for a polygon, whose corners are sharp).
    /// Closed forms except for the star (dense sampling refined by golden
    /// section, relative accuracy about `1e-9`). A line drawn along the curve
    /// must be narrower than twice this.
    pub fn min_curvature_radius(&self) -> f64 {
        match *self {
            Shape::Circle { r, .. } => r,
            Shape::Ellipse { a, b, .. } => a.min(b) * a.min(b) / a.max(b),
            Shape::Sine {
                amplitude,
                wavelength,
                ..
            } => {
                let w = 2.0 * PI / wavelength;
                1.0 / (amplitude.abs() * w * w)
            }
            Shape::Star { .. } => geometry::star_min_curvature_radius(self),
            Shape::Polygon { .. } => 0.0,
        }
    }
}

/// Error statistics of measured points against a true curve, px.
#[derive(Clone, Copy, Debug, PartialEq, Serialize, Deserialize)]
pub struct ErrorStats {
    /// Number of points.
    pub count: usize,
    /// Mean signed distance (positive: on the `+n` side, outside), px.
    pub bias: f64,
    /// Root mean square of the signed distance about its mean, px.
    pub scatter: f64,
    /// Root mean square of the signed distance, px
    /// (`rms² = bias² + scatter²`).
    pub rms: f64,
    /// Largest absolute distance, px.
    pub max_abs: f64,
}

/// Statistics of the signed distances of `points` (px) to `shape`.
///
/// Errors: [`Error::InvalidParameter`] for no point or an invalid shape,
/// [`Error::NonFinite`] for a NaN or infinite coordinate.
pub fn evaluate(points: &[[f64; 2]], shape: &Shape) -> Result<ErrorStats> {
    shape.validate()?;
    if points.is_empty() {
        return Err(Error::invalid("points", "no point to evaluate"));
    }
    if let Some(i) = points
        .iter()
        .position(|p| !(p[0].is_finite() && p[1].is_finite()))
    {
        return Err(Error::NonFinite {
            what: format!("measured point {i}"),
        });
    }
    let n = points.len() as f64;
    let d: Vec<f64> = points
        .iter()
        .map(|p| shape.signed_distance(p[0], p[1]))
        .collect();
    let bias = d.iter().sum::<f64>() / n;
    let scatter = (d.iter().map(|v| (v - bias) * (v - bias)).sum::<f64>() / n).sqrt();
    let rms = (d.iter().map(|v| v * v).sum::<f64>() / n).sqrt();
    let max_abs = d.iter().fold(0.0f64, |m, v| m.max(v.abs()));
    Ok(ErrorStats {
        count: points.len(),
        bias,
        scatter,
        rms,
        max_abs,
    })
}
