//! Synthetic images of exactly known curves.
//!
//! [`render`] paints a [`Shape`] as a silhouette (a region of one gray level
//! on a background) or a contour (a thin line), then optionally blurs,
//! adds noise and quantises. The truth written next to the image is
//! [`Truth::from_spec`].
//!
//! Two painting methods:
//! - [`Method::Coverage`]: each pixel gets the exact fraction of its area
//!   covered by the region (a dense polygon hugging the true curve to within
//!   [`shapes::SAGITTA`] px, rasterised exactly by
//!   [`coverage::polygon_coverage`]): an ideal area-integrating sensor.
//! - [`Method::Profile`]: each pixel centre gets an analytic profile of its
//!   signed distance to the curve ([`profile`]), as in the paper's tests.

pub mod blur;
pub mod coverage;
pub mod noise;
pub mod presets;
pub mod profile;
pub mod scene;
pub mod shading;
pub mod shapes;
pub mod specimen;
pub mod square_grid;
mod truth_file;

pub use shading::Shading;
pub use truth_file::Truth;

use crate::tone::Tone;
use serde::{Deserialize, Serialize};

use crate::error::{Error, Result};
use crate::image::Image;
pub use crate::truth::Kind;
use crate::truth::Shape;

/// How the gray levels are computed before blur and noise.
///
/// Serialised as `"coverage"` or `{"profile": {"half_width": 5.0}}`.
#[derive(Clone, Copy, Debug, PartialEq, Serialize, Deserialize)]
#[serde(rename_all = "snake_case")]
pub enum Method {
    /// Exact fraction of each pixel's area inside the region.
    Coverage,
    /// Analytic profile of the signed distance at each pixel centre.
    Profile {
        /// Half-width `R` of the profile, px (> 0): the transition (edge) or
        /// the whole line (contour) spans `[-R, R]` across the curve.
        half_width: f64,
    },
}

/// Everything that defines a synthetic image. Serialisable; missing fields
/// take the [`Default`] values.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
#[serde(default)]
pub struct RenderSpec {
    /// Image width, px (1 to 20000).
    pub width: usize,
    /// Image height, px (1 to 20000).
    pub height: usize,
    /// The true curve.
    pub shape: Shape,
    /// Silhouette or contour.
    pub kind: Kind,
    /// Contours with [`Method::Coverage`] only: full width of the line, px
    /// (> 0, narrower than twice the smallest radius of curvature).
    pub line_width: f64,
    /// Gray level inside closed shapes, above (`-n` side, smaller `y`) the
    /// sine, and of the line for contours; in `[0, 1]`.
    pub foreground: f64,
    /// Gray level elsewhere, in `[0, 1]`.
    pub background: f64,
    /// How the gray levels are computed.
    pub method: Method,
    /// Standard deviation of the Gaussian blur, px (0: none); with
    /// `blur_sigma_y`, along the rows only.
    pub blur_sigma: f64,
    /// [`Method::Coverage`] only: the blur's standard deviation along the
    /// columns, px, when it differs from `blur_sigma` (an astigmatic lens
    /// whose axes are the pixel grid's; see
    /// [`blur::blurred_coverage_xy`]). `None`: the same.
    #[serde(skip_serializing_if = "Option::is_none")]
    pub blur_sigma_y: Option<f64>,
    /// Standard deviation of the additive Gaussian noise, as a fraction of
    /// `|foreground - background|` (0: none).
    pub noise: f64,
    /// Seed of the noise.
    pub seed: u64,
    /// `Some(8)` or `Some(16)`: quantise like an integer image of that depth
    /// (values stay real numbers in `[0, 1]`); `None`: keep full precision.
    pub bits: Option<u8>,
    /// How the recorded gray levels encode the light: `foreground` and
    /// `background` are light, blurred and integrated as such, and each
    /// pixel is then encoded by this tone curve (sRGB, a gamma) before
    /// the noise (a fraction of the encoded contrast) and the
    /// quantisation, as a camera writing JPEG files does. Default: linear
    /// ([`Tone::Auto`] is linear too).
    pub tone: Tone,
    /// Uneven light multiplying the levels before the tone curve (a
    /// gradient, vignetting); default even. Left out of files when even.
    #[serde(skip_serializing_if = "Shading::is_even")]
    pub shading: Shading,
}

impl Default for RenderSpec {
    /// A 256x256 silhouette of an off-grid circle of radius 80 px, gray 0.8
    /// on 0.2, exact coverage, no blur, noise or quantisation.
    fn default() -> Self {
        RenderSpec {
            width: 256,
            height: 256,
            shape: Shape::Circle {
                cx: 127.3,
                cy: 128.6,
                r: 80.0,
            },
            kind: Kind::Silhouette,
            line_width: 3.0,
            foreground: 0.8,
            background: 0.2,
            method: Method::Coverage,
            blur_sigma: 0.0,
            blur_sigma_y: None,
            noise: 0.0,
            seed: 0,
            bits: None,
            tone: Tone::Linear,
            shading: Shading::default(),
        }
    }
}

/// Largest image side, px.
const MAX_SIDE: usize = 20_000;

impl RenderSpec {
    /// Check every field (see their documentation) and the shape.
    ///
    /// For a contour painted by coverage, also checks that the line does not
    /// overlap itself: half the width must be below the smallest radius of
    /// curvature, and offset points sampled every ~0.25 px along the curve
    /// (at least 4096 of them) must be exactly `line_width / 2` from it.
    ///
    /// Errors: [`Error::InvalidParameter`] naming the field.
    pub fn validate(&self) -> Result<()> {
        for (name, side) in [("width", self.width), ("height", self.height)] {
            if side == 0 || side > MAX_SIDE {
                return Err(Error::invalid(
                    name,
                    format!("{side} px: must be between 1 and {MAX_SIDE}"),
                ));
            }
        }
        for (name, level) in [
            ("foreground", self.foreground),
            ("background", self.background),
        ] {
            if !(0.0..=1.0).contains(&level) {
                return Err(Error::invalid(
                    name,
                    format!("{level}: gray levels must be between 0 and 1"),
                ));
            }
        }
        if !(self.blur_sigma.is_finite() && (0.0..=1000.0).contains(&self.blur_sigma)) {
            return Err(Error::invalid(
                "blur_sigma",
                format!("{} px: must be between 0 and 1000", self.blur_sigma),
            ));
        }
        if let Some(y) = self.blur_sigma_y {
            if !(y.is_finite() && (0.0..=1000.0).contains(&y)) {
                return Err(Error::invalid(
                    "blur_sigma_y",
                    format!("{y} px: must be between 0 and 1000"),
                ));
            }
            if self.method != Method::Coverage {
                return Err(Error::invalid(
                    "blur_sigma_y",
                    "an astigmatic blur is rendered with exact coverage only (method coverage)",
                ));
            }
        }
        if !(self.noise.is_finite() && self.noise >= 0.0) {
            return Err(Error::invalid(
                "noise",
                format!("{}: must be a finite number >= 0", self.noise),
            ));
        }
        if let Some(bits) = self.bits {
            if bits != 8 && bits != 16 {
                return Err(Error::invalid(
                    "bits",
                    format!("{bits}: only 8 or 16 bits are supported"),
                ));
            }
        }
        if let Method::Profile { half_width } = self.method {
            if !(half_width.is_finite() && half_width > 0.0) {
                return Err(Error::invalid(
                    "half_width",
                    format!("{half_width} px: the profile half-width must be > 0"),
                ));
            }
        }
        self.shading.validate()?;
        self.shape.validate()?;
        if self.kind == Kind::Contour && self.method == Method::Coverage {
            self.validate_line()?;
        }
        Ok(())
    }

    /// The contour's line must be a proper band: no cusp of its borders and
    /// no overlap of distant parts.
    fn validate_line(&self) -> Result<()> {
        let lw = self.line_width;
        if !(lw.is_finite() && lw > 0.0) {
            return Err(Error::invalid(
                "line_width",
                format!("{lw} px: a contour needs a line width > 0"),
            ));
        }
        let h = 0.5 * lw;
        let rho = self.shape.min_curvature_radius();
        if h >= rho {
            return Err(Error::invalid(
                "line_width",
                format!(
                    "{lw} px is too wide: half of it must stay below the smallest radius of curvature of the curve ({rho:.4} px)"
                ),
            ));
        }
        let (s0, s1) = match self.shape {
            Shape::Sine { .. } => (-0.5 - h, self.width as f64 - 0.5 + h),
            _ => (0.0, std::f64::consts::TAU),
        };
        let count = ((self.shape.length_between(s0, s1) / 0.25).ceil() as usize).max(4096);
        for i in 0..count {
            let s = s0 + (s1 - s0) * (i as f64 / count as f64);
            let e = self.shape.eval(s);
            let n = e.normal();
            for side in [-h, h] {
                let d = self
                    .shape
                    .signed_distance(e.p[0] + side * n[0], e.p[1] + side * n[1]);
                if (d - side).abs() > 1e-6 * (1.0 + h) {
                    return Err(Error::invalid(
                        "line_width",
                        format!(
                            "{lw} px is too wide: the line overlaps itself near ({:.1}, {:.1})",
                            e.p[0], e.p[1]
                        ),
                    ));
                }
            }
        }
        Ok(())
    }
}

/// Render the synthetic image described by `spec`.
///
/// Pipeline: exact coverage through the Gaussian blur of `blur_sigma`
/// ([`blur::blurred_coverage`]: the blur acts on the scene, then the pixel
/// integrates, as in a camera) or the profile ([`Method`]) then blurred
/// ([`blur::gaussian_blur`]), value `background + (foreground -
/// background) * fraction`; then noise of standard
/// deviation `noise * |foreground - background|` ([`noise::add_gaussian_noise`]);
/// then quantisation ([`noise::quantise`]) if `bits` is set. The light is
/// multiplied by the `shading` after the blur, and with a `tone` the
/// values are encoded by it before the noise.
///
/// Errors: those of [`RenderSpec::validate`].
pub fn render(spec: &RenderSpec) -> Result<Image> {
    spec.validate()?;
    let size = (spec.width, spec.height);
    let rendering = scene::Rendering::of(spec);
    match spec.method {
        Method::Coverage => scene::paint(&shapes::region_rings(spec)?, size, &rendering),
        Method::Profile { half_width } => {
            let mut image = Image::new(size.0, size.1, profile::profile_pixels(spec, half_width))?;
            if spec.blur_sigma > 0.0 {
                image = blur::gaussian_blur(&image, spec.blur_sigma)?;
            }
            Ok(scene::finish(image, &rendering))
        }
    }
}
