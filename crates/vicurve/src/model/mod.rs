//! Parametric shape models: a circle, an ellipse, a straight line or a
//! polygon of `N` vertices, measured by the same virtual-image correlation
//! as the B-spline curves but with a handful of shape parameters as the
//! unknowns, each with its uncertainty.
//!
//! ```no_run
//! use vicurve::{curve::InitialCurve, fit::{measure, FitConfig}, io::load_image};
//! use vicurve::model::{measure_model, ModelConfig, ShapeModel};
//! let image = load_image("hole.png".as_ref())?;
//! let init = InitialCurve::Circle { cx: 320.0, cy: 240.0, r: 100.0 };
//! let config = FitConfig::default();
//! let m = measure(&image, &init, &config)?;
//! let fit = measure_model(&image, &m, &config, ShapeModel::Circle, &ModelConfig::default())?;
//! for p in &fit.parameters {
//!     println!("{} = {:.5} +- {:.5} {}", p.name, p.value, p.sigma, p.unit);
//! }
//! # Ok::<(), vicurve::Error>(())
//! ```
//!
//! # How
//! 1. The ordinary B-spline measurement ([`crate::fit::measure`]) of the
//!    same image and start gives the curve; the model's start is fitted to
//!    its samples ([`initial_shape`]: moments for circles and ellipses,
//!    total least squares for a line, corners from the straight sides for
//!    a polygon).
//! 2. Every pixel centre within the band (`|d| <= R`, `d` the signed
//!    distance to the model's shape) is compared, as recorded, with the
//!    virtual image `a + c gamma(d)`: the pixel-edge profile of
//!    [`crate::virtual_image::Profile::PixelEdge`] for silhouettes (an
//!    ideal pixel through the fitted Gaussian blur, curvature shift
//!    included, so the true boundary is measured), the paper's profile of
//!    the kind otherwise. The shape parameters, `a` and `c` are found by
//!    Levenberg–Marquardt ([`solve`](self) module docs), the blur between
//!    passes.
//! 3. The uncertainties are the Gauss–Newton covariance scaled by the
//!    residual variance: noise only, no model bias.
//!
//! When the image is sharp (fitted blur up to 0.1 px) every pixel is
//! modelled by its exact coverage: the area of the pixel inside the circle
//! (closed form) or the polygon (clipping), or beside the straight edge
//! ([`CoverageModel`]); the pixel-edge profile's first-order curvature
//! term leaves errors of 2 to 3e-4 px on a circle's radius that this
//! removes. Near a polygon's vertices the straight-edge profile is wrong
//! within about a pixel plus the blur's reach: those pixels are modelled
//! by their exact coverage in a sharp image and left out of a blurred
//! one.
//!
//! Coordinates are pixels, `x` the column and `y` the row; angles are in
//! radians, counterclockwise on screen (from `+x` towards `-y`), as in
//! [`crate::truth::Shape`].
//!
//! The free B-spline curve whose control points are the unknowns
//! ([`ShapeModel::BsplineCurve`]) is fitted by [`bspline_curve`], not by
//! [`measure_model`].

pub mod bspline_curve;
mod circle;
mod ellipse;
mod geometry;
mod init;
mod line;
mod pixels;
mod polygon;
mod solve;

pub use init::initial_shape;
pub(crate) use init::principal;

use crate::error::{Error, Result};
use crate::fit::FitConfig;
use crate::image::Image;
use crate::measurement::{Measurement, Outcome, Sample};
use crate::truth::Shape;
use crate::virtual_image::pixel_edge::optical_blur;
use crate::virtual_image::{Kind, Profile};
use geometry::Geometry;
use serde::{Deserialize, Serialize};

/// Most sides of a polygon model.
pub const MAX_POLYGON_SIDES: usize = 64;

/// Which shape model is fitted, as the user names it (`circle`,
/// `polygon:4`, `bspline-curve`; [`std::str::FromStr`] and `Display` are
/// each other's inverse).
///
/// A separate type from [`ModelShape`] because it is chosen before any
/// parameter exists (a polygon's number of sides, not its vertices) and
/// because the free B-spline model has no `ModelShape`: its result is a
/// curve ([`bspline_curve`]). [`ModelShape::model`] gives a shape's model.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash)]
pub enum ShapeModel {
    /// A circle: centre and radius.
    Circle,
    /// An ellipse: centre, semi-axes, direction of the first axis.
    Ellipse,
    /// A straight line (an edge or a thin line): direction and distance.
    Line,
    /// A polygon of `sides` vertices (3 to [`MAX_POLYGON_SIDES`]).
    Polygon {
        /// Number of vertices.
        sides: usize,
    },
    /// A free B-spline curve, its control points the unknowns
    /// ([`bspline_curve`]).
    BsplineCurve,
}

impl std::fmt::Display for ShapeModel {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        match self {
            ShapeModel::Circle => f.write_str("circle"),
            ShapeModel::Ellipse => f.write_str("ellipse"),
            ShapeModel::Line => f.write_str("line"),
            ShapeModel::Polygon { sides } => write!(f, "polygon:{sides}"),
            ShapeModel::BsplineCurve => f.write_str("bspline-curve"),
        }
    }
}

impl std::str::FromStr for ShapeModel {
    type Err = Error;
    /// `circle`, `ellipse`, `line`, `polygon:N` (`N` from 3 to
    /// [`MAX_POLYGON_SIDES`]) or `bspline-curve`.
    fn from_str(s: &str) -> Result<Self> {
        let bad = |reason: String| Error::invalid("model", reason);
        match s.trim() {
            "circle" => Ok(ShapeModel::Circle),
            "ellipse" => Ok(ShapeModel::Ellipse),
            "line" => Ok(ShapeModel::Line),
            "bspline-curve" => Ok(ShapeModel::BsplineCurve),
            other => {
                let Some(n) = other.strip_prefix("polygon:") else {
                    return Err(bad(format!(
                        "'{other}' (expected circle, ellipse, line, polygon:N or bspline-curve)"
                    )));
                };
                let sides: usize = n
                    .trim()
                    .parse()
                    .map_err(|_| bad(format!("'{other}': N must be a whole number of sides")))?;
                if !(3..=MAX_POLYGON_SIDES).contains(&sides) {
                    return Err(bad(format!(
                        "'{other}': a polygon needs 3 to {MAX_POLYGON_SIDES} sides"
                    )));
                }
                Ok(ShapeModel::Polygon { sides })
            }
        }
    }
}

impl Serialize for ShapeModel {
    fn serialize<S: serde::Serializer>(&self, s: S) -> std::result::Result<S::Ok, S::Error> {
        s.serialize_str(&self.to_string())
    }
}

impl<'de> Deserialize<'de> for ShapeModel {
    fn deserialize<D: serde::Deserializer<'de>>(d: D) -> std::result::Result<Self, D::Error> {
        let text = String::deserialize(d)?;
        text.parse().map_err(serde::de::Error::custom)
    }
}

/// A shape with its parameters, pixels and radians (module docs for the
/// conventions): a model's start and its fitted result. Serialised with a
/// `"shape"` tag; circles and ellipses read as [`crate::truth::Shape`]
/// ([`ModelShape::to_truth`]), which is a separate type because it holds
/// exact geometry for rendering and error measurement, with shapes (stars,
/// sines) that no model fits and without lines or polygons.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
#[serde(tag = "shape", rename_all = "snake_case")]
pub enum ModelShape {
    /// Centre `(cx, cy)` and radius `r`.
    Circle {
        /// Centre x (column), px.
        cx: f64,
        /// Centre y (row), px.
        cy: f64,
        /// Radius, px.
        r: f64,
    },
    /// Centre, semi-axes (`a >= b` in results) and the direction of the
    /// `a` axis.
    Ellipse {
        /// Centre x (column), px.
        cx: f64,
        /// Centre y (row), px.
        cy: f64,
        /// Semi-axis along `angle`, px.
        a: f64,
        /// The other semi-axis, px.
        b: f64,
        /// Direction of the `a` axis, rad, counterclockwise on screen from
        /// `+x` (in `(-pi/2, pi/2]` in results).
        angle: f64,
    },
    /// The straight line through `start` and `end`, directed from one to
    /// the other (normal on the screen-right of that direction); they are
    /// the ends of the measured span.
    Line {
        /// First end `[x, y]`, px.
        start: [f64; 2],
        /// Second end `[x, y]`, px.
        end: [f64; 2],
    },
    /// The vertices `[x, y]`, px, counterclockwise on screen.
    Polygon {
        /// Vertices in order.
        vertices: Vec<[f64; 2]>,
    },
}

impl ModelShape {
    /// The model this shape belongs to.
    pub fn model(&self) -> ShapeModel {
        match self {
            ModelShape::Circle { .. } => ShapeModel::Circle,
            ModelShape::Ellipse { .. } => ShapeModel::Ellipse,
            ModelShape::Line { .. } => ShapeModel::Line,
            ModelShape::Polygon { vertices } => ShapeModel::Polygon {
                sides: vertices.len(),
            },
        }
    }

    /// The same curve as a [`crate::truth::Shape`] (circles and
    /// ellipses), e.g. to compare with a truth file.
    pub fn to_truth(&self) -> Option<Shape> {
        match *self {
            ModelShape::Circle { cx, cy, r } => Some(Shape::Circle { cx, cy, r }),
            ModelShape::Ellipse {
                cx,
                cy,
                a,
                b,
                angle,
            } => Some(Shape::Ellipse {
                cx,
                cy,
                a,
                b,
                angle,
            }),
            _ => None,
        }
    }

    /// The model's internal form; errors on an unusable shape.
    fn geometry(&self) -> Result<Geometry> {
        let bad = |reason: String| Error::invalid("model start", reason);
        let finite = |v: &[f64]| v.iter().all(|x| x.is_finite());
        match self {
            ModelShape::Circle { cx, cy, r } => {
                if !finite(&[*cx, *cy, *r]) || *r < 1.0 {
                    return Err(bad(format!(
                        "circle ({cx}, {cy}), radius {r}: need a radius of at least 1 px"
                    )));
                }
                Ok(Geometry::Circle(circle::Circle {
                    cx: *cx,
                    cy: *cy,
                    r: *r,
                }))
            }
            ModelShape::Ellipse {
                cx,
                cy,
                a,
                b,
                angle,
            } => {
                if !finite(&[*cx, *cy, *a, *b, *angle]) || *a < 1.0 || *b < 1.0 {
                    return Err(bad(format!(
                        "ellipse with semi-axes {a}, {b}: need at least 1 px"
                    )));
                }
                Ok(Geometry::Ellipse(ellipse::Ellipse {
                    cx: *cx,
                    cy: *cy,
                    a: *a,
                    b: *b,
                    angle: *angle,
                }))
            }
            ModelShape::Line { start, end } => {
                let (dx, dy) = (end[0] - start[0], end[1] - start[1]);
                let len = dx.hypot(dy);
                if !finite(&[start[0], start[1], end[0], end[1]]) || len < 2.0 {
                    return Err(bad(format!(
                        "line from {start:?} to {end:?}: need at least 2 px"
                    )));
                }
                Ok(Geometry::Line(line::Line {
                    q0: [0.5 * (start[0] + end[0]), 0.5 * (start[1] + end[1])],
                    alpha: (-dy).atan2(dx),
                    offset: 0.0,
                    t_start: -0.5 * len,
                    t_end: 0.5 * len,
                }))
            }
            ModelShape::Polygon { vertices } => {
                if vertices.iter().any(|v| !finite(v)) {
                    return Err(Error::NonFinite {
                        what: "polygon vertices".into(),
                    });
                }
                polygon::check(vertices).map_err(bad)?;
                Ok(Geometry::Polygon(polygon::Polygon {
                    v: vertices.clone(),
                }))
            }
        }
    }
}

/// The virtual image's profile across the model's boundary.
#[derive(Clone, Copy, Debug, PartialEq, Serialize, Deserialize)]
#[serde(tag = "type", rename_all = "snake_case")]
pub enum ModelProfile {
    /// A silhouette as an ideal pixel records it through a Gaussian blur
    /// ([`Profile::PixelEdge`]); the blur is refitted when
    /// [`ModelConfig::fit_blur`].
    PixelEdge {
        /// Optical blur, px (standard deviation).
        blur: f64,
    },
    /// The paper's profile of `kind` over the band `half_width`, centred
    /// `blur_variance kappa / 2` from the shape (the shift a blur of that
    /// variance, px^2, causes on a boundary of curvature `kappa`; 0 for
    /// none).
    Paper {
        /// Silhouette or contour.
        kind: Kind,
        /// Band half-width `R`, px.
        half_width: f64,
        /// Variance of the blur whose curvature shift is modelled, px^2.
        blur_variance: f64,
    },
}

impl ModelProfile {
    /// The profile matching a B-spline measurement: its last stage's
    /// pixel edge (or, for a silhouette with blur correction, the pixel
    /// edge through the blur estimated on the edge), else the paper's
    /// profile over the last band that had it (a line's pixel-line stage
    /// has no model counterpart: the one before it), shifted by the blur
    /// it corrected.
    pub fn from_measurement(m: &Measurement, config: &FitConfig) -> ModelProfile {
        let last = m.stages.last();
        let last_paper = m.last_paper_stage().or(last);
        match (config.kind, last.map(|s| s.profile)) {
            (Kind::Silhouette, Some(Profile::PixelEdge { blur, .. })) => {
                ModelProfile::PixelEdge { blur }
            }
            (Kind::Silhouette, _) if config.blur_correction => ModelProfile::PixelEdge {
                blur: m.edge_spread.map_or(0.0, |e| optical_blur(e.sigma)),
            },
            (kind, _) => ModelProfile::Paper {
                kind,
                half_width: last_paper.map_or(2.0, |s| s.half_width),
                blur_variance: match (kind, m.blur_corrected, m.edge_spread) {
                    (Kind::Contour, true, Some(e)) => e.sigma * e.sigma,
                    _ => 0.0,
                },
            },
        }
    }

    fn validate(&self) -> Result<()> {
        match *self {
            ModelProfile::PixelEdge { blur } if !(blur.is_finite() && (0.0..=100.0).contains(&blur)) => {
                Err(Error::invalid("blur", format!("{blur} px: must be between 0 and 100")))
            }
            ModelProfile::Paper {
                half_width,
                blur_variance,
                ..
            } if !(half_width.is_finite() && half_width > 0.0 && blur_variance.is_finite() && blur_variance >= 0.0) => {
                Err(Error::invalid(
                    "profile",
                    format!("half-width {half_width} px (> 0) and blur variance {blur_variance} px^2 (>= 0)"),
                ))
            }
            _ => Ok(()),
        }
    }
}

/// How the pixels are modelled when the image is sharp.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq, Serialize, Deserialize)]
#[serde(rename_all = "snake_case")]
pub enum CoverageModel {
    /// By their exact coverage when the fitted blur is at most 0.1 px, by
    /// the pixel-edge profile through the blur otherwise.
    #[default]
    Auto,
    /// Always by their exact coverage (the blur neglected).
    Exact,
    /// Always by the pixel-edge profile (a polygon's corner pixels are
    /// then left out).
    PixelEdge,
}

/// Settings of a model fit. `ModelConfig::default()` gives the documented
/// defaults.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
#[serde(default)]
pub struct ModelConfig {
    /// Iteration limit over all passes. Default: 200.
    pub max_iterations: usize,
    /// Stop when the largest parameter step is under this, pixels (angles
    /// count times the shape's size). Default: 1e-6.
    pub tolerance: f64,
    /// Refit the blur of the pixel-edge profile between passes. Default:
    /// true.
    pub fit_blur: bool,
    /// How the pixels of a sharp image are modelled. Default: auto.
    pub coverage: CoverageModel,
    /// Leave out the pixels near a polygon's vertices even when they could
    /// be modelled by their exact coverage (the vertices then follow from
    /// the straight edges only). Default: false.
    pub exclude_corners: bool,
}

impl Default for ModelConfig {
    fn default() -> Self {
        ModelConfig {
            max_iterations: 200,
            tolerance: 1e-6,
            fit_blur: true,
            coverage: CoverageModel::Auto,
            exclude_corners: false,
        }
    }
}

impl ModelConfig {
    /// Check the fields. Errors: [`Error::InvalidParameter`].
    pub fn validate(&self) -> Result<()> {
        if self.max_iterations == 0 {
            return Err(Error::invalid("max_iterations", "must be at least 1"));
        }
        if !(self.tolerance.is_finite() && self.tolerance > 0.0) {
            return Err(Error::invalid(
                "tolerance",
                format!("{}: must be a positive number of pixels", self.tolerance),
            ));
        }
        Ok(())
    }
}

/// One fitted parameter.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub struct Parameter {
    /// Name: `cx`, `cy`, `r`, `a`, `b`, `angle`, `distance`, `x0`, `y0`, ...
    pub name: String,
    /// Value.
    pub value: f64,
    /// Standard deviation from the noise (Gauss–Newton covariance scaled
    /// by the residual variance, plus the fitted blur's part where it moves
    /// the shape); NaN when the parameter is not determined.
    pub sigma: f64,
    /// `px` or `rad`.
    pub unit: &'static str,
}

/// The result of a model fit.
#[derive(Clone, Debug, Serialize)]
pub struct ModelFit {
    /// The model.
    pub model: ShapeModel,
    /// How the fit ended (a diverged fit keeps its last shape).
    pub outcome: Outcome,
    /// The fitted shape.
    pub shape: ModelShape,
    /// The shape's parameters with their uncertainties: `cx, cy, r`;
    /// `cx, cy, a, b, angle`; `angle, distance` (the line's direction and
    /// its signed distance from the image origin along the normal); `x0,
    /// y0, x1, y1, ...` (a polygon's vertices).
    pub parameters: Vec<Parameter>,
    /// Covariance of `parameters`, same order, units squared.
    pub covariance: Vec<Vec<f64>>,
    /// Dark level `a` of the virtual image (gray level at `gamma = 0`).
    pub a: f64,
    /// Contrast `c` (the level at `gamma = 1` is `a + c`; its sign is the
    /// polarity: positive for a bright inside or left side, or a bright
    /// line).
    pub c: f64,
    /// The profile at the end (with the fitted blur for a pixel edge).
    pub profile: ModelProfile,
    /// Band half-width of the last pass, px.
    pub half_width: f64,
    /// Band pixels used.
    pub band_pixels: usize,
    /// Of which modelled by their exact coverage (a sharp image).
    pub exact_pixels: usize,
    /// Band pixels left out (polygon corners of a blurred image).
    pub excluded_pixels: usize,
    /// RMS of the residual, gray levels.
    pub residual_rms: f64,
    /// Residual standard deviation per pixel, `sqrt(sum e^2 / (n - m))`,
    /// gray levels: the noise the uncertainties are scaled by.
    pub noise_sigma: f64,
    /// Iterations over all passes.
    pub iterations: usize,
    /// Band selections.
    pub passes: usize,
    /// The start.
    pub start: ModelShape,
    /// The settings.
    pub config: ModelConfig,
    #[serde(skip)]
    geometry: Geometry,
    /// Covariance of the internal parameters, row-major.
    #[serde(skip)]
    internal_cov: Vec<f64>,
}

impl ModelFit {
    /// The parameter called `name`.
    pub fn parameter(&self, name: &str) -> Option<&Parameter> {
        self.parameters.iter().find(|p| p.name == name)
    }

    /// Samples of the fitted shape at most `spacing` px apart, in the
    /// shape's direction (from `start` for a line; counterclockwise on
    /// screen from an arbitrary point for closed shapes, each polygon
    /// vertex included), with the outward (or screen-right) normal, the
    /// standard deviation of the boundary's position along it (`sigma`,
    /// px) and `weight` 1.
    ///
    /// Errors: [`Error::InvalidParameter`] for a spacing that is not a
    /// positive number.
    pub fn samples(&self, spacing: f64) -> Result<Vec<Sample>> {
        if !(spacing.is_finite() && spacing > 0.0) {
            return Err(Error::invalid(
                "sample spacing",
                format!("{spacing}: must be a positive number of pixels"),
            ));
        }
        let p = self.geometry.params().len();
        Ok(self
            .geometry
            .boundary(spacing)
            .iter()
            .map(|b| Sample {
                s: b.s,
                x: b.p[0],
                y: b.p[1],
                nx: b.normal[0],
                ny: b.normal[1],
                sigma: geometry::quadratic_sigma(&b.grad, &self.internal_cov, p),
                sigma_noise: geometry::quadratic_sigma(&b.grad, &self.internal_cov, p),
                misfit: false,
                weight: 1.0,
            })
            .collect())
    }
}

/// Fit `model` to the curve a B-spline measurement `m` of `image` found
/// (with `fit_config`): [`initial_shape`] of its samples, the profile
/// [`ModelProfile::from_measurement`], then [`fit_shape`].
///
/// Errors: those of [`initial_shape`] and [`fit_shape`].
pub fn measure_model(
    image: &Image,
    m: &Measurement,
    fit_config: &FitConfig,
    model: ShapeModel,
    config: &ModelConfig,
) -> Result<ModelFit> {
    let start = initial_shape(&m.points(), m.curve.is_closed(), model)?;
    fit_shape(
        image,
        &start,
        ModelProfile::from_measurement(m, fit_config),
        config,
    )
}

/// Fit the shape of `start`'s model to `image`, from `start`, comparing
/// with the virtual image of `profile`.
///
/// Errors are for inputs that cannot be fitted at all:
/// [`Error::InvalidParameter`] for an invalid start, profile or
/// configuration; [`Error::BandOutsideImage`] when a closed shape's band
/// leaves the image at the start; [`Error::EmptyBand`] for too few band
/// pixels; [`Error::ModelMismatch`] when the band sees no contrast. A fit
/// that starts but fails later is reported in [`ModelFit::outcome`].
pub fn fit_shape(
    image: &Image,
    start: &ModelShape,
    profile: ModelProfile,
    config: &ModelConfig,
) -> Result<ModelFit> {
    config.validate()?;
    profile.validate()?;
    let model = start.model();
    let geom = start.geometry()?;
    let solved = solve::run(image, geom, profile, config).map_err(|f| match f {
        solve::StartFailure::Outside([x, y], half_width) => {
            Error::BandOutsideImage { half_width, x, y }
        }
        solve::StartFailure::Empty(pixels, unknowns) => Error::EmptyBand { pixels, unknowns },
        solve::StartFailure::NoContrast => Error::ModelMismatch {
            model: model.to_string(),
            reason: "the band around the start sees no contrast".into(),
        },
    })?;
    let p = solved.geom.params().len();
    let m = p + 2;
    let ev = &solved.eval;
    let dof = ev.used.saturating_sub(m).max(1) as f64;
    let s2 = ev.cost / dof;
    let inverse = invert(&ev.h, m);
    let mut internal_cov: Vec<f64> = (0..p * p)
        .map(|k| s2 * inverse[(k / p) * m + k % p])
        .collect();
    // The fitted blur's uncertainty moves the shape too (a dot a blur or
    // so across trades its size for the blur).
    if let Some(coupling) = &solved.blur_coupling {
        coupling.add_to(&mut internal_cov, s2);
    }
    let (parameters, cov) = solved.geom.report(&internal_cov);
    let q = parameters.len();
    Ok(ModelFit {
        model,
        outcome: solved.outcome,
        shape: solved.geom.shape(),
        covariance: (0..q).map(|i| cov[i * q..(i + 1) * q].to_vec()).collect(),
        parameters,
        a: solved.a,
        c: solved.c,
        profile: solved.profile,
        half_width: solved.half_width,
        band_pixels: ev.used,
        exact_pixels: ev.coverage,
        excluded_pixels: ev.excluded,
        residual_rms: (ev.cost / ev.used.max(1) as f64).sqrt(),
        noise_sigma: s2.sqrt(),
        iterations: solved.iterations,
        passes: solved.passes,
        start: start.clone(),
        config: config.clone(),
        geometry: solved.geom,
        internal_cov,
    })
}

/// `h^-1` (row-major `m x m`); a singular direction (a parameter the band
/// does not determine) gets a huge variance through a tiny ridge, and NaN
/// everywhere when even that fails.
fn invert(h: &[f64], m: usize) -> Vec<f64> {
    if let Ok(c) = crate::solver::DenseCholesky::factor(h, m) {
        return c.inverse();
    }
    let max_diag = (0..m).map(|i| h[i * m + i]).fold(0.0, f64::max);
    let mut ridged = h.to_vec();
    for i in 0..m {
        ridged[i * m + i] += 1e-10 * max_diag;
    }
    match crate::solver::DenseCholesky::factor(&ridged, m) {
        Ok(c) => c.inverse(),
        Err(_) => vec![f64::NAN; m * m],
    }
}
