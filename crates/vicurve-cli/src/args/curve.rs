//! The options of one curve to measure, and the fit configuration they
//! describe.

use crate::failure::Failure;
use clap::builder::{PossibleValue, PossibleValuesParser, TypedValueParser as _};
use vicurve::curve::InitialCurve;
use vicurve::fit::{Coords, FitConfig, LevelModel};
use vicurve::sequence::run::CurveOptions;

/// The options of one curve: `measure`'s and `track`'s flags, and the keys
/// of a job file's `[[curve]]` (same names, `_` for `-`).
#[derive(clap::Args, Clone, Debug)]
pub struct CurveArgs {
    /// Treat a `polyline:` start as closed (last point joins the first).
    #[arg(long)]
    pub closed: bool,
    /// `silhouette` (an edge between a dark and a bright region) or
    /// `contour` (a thin line).
    #[arg(long, default_value = "silhouette")]
    pub kind: String,
    /// Force the polarity instead of estimating it: `bright-inside`,
    /// `dark-inside`, `bright-left`, `bright-right` (open curves, as seen on
    /// screen along the curve's direction), `bright-line`, `dark-line`, or
    /// `auto`.
    #[arg(long, default_value = "auto")]
    pub polarity: String,
    /// Coarse-to-fine stages `R:N,...` (band half-width in px : number of
    /// elements, `R:Lpx` for elements of length L px, or `R:auto`). Default:
    /// 20, 10, 5 and 2 px with elements of 80, 40 and 40 px, then automatic
    /// (40 px halved down to 5 px while it pays), then the edge (or line) as
    /// a pixel records it through the blur estimated on the image.
    #[arg(long)]
    pub stages: Option<String>,
    /// Degree of the B-splines (1 to 5).
    #[arg(long, default_value_t = 3)]
    pub degree: usize,
    /// Image interpolation: `cubic` (B-spline, the default), `bilinear` or
    /// `keys` (cubic convolution); see docs/benchmarks.md for the choice.
    #[arg(long)]
    pub interp: Option<String>,
    /// Convergence tolerance on the displacement update, pixels.
    #[arg(long, default_value_t = 1e-4)]
    pub tolerance: f64,
    /// Iteration limit per stage.
    #[arg(long, default_value_t = 200)]
    pub max_iter: usize,
    /// Do not estimate the blur nor end with the pixel-edge stage (edges)
    /// or remove the shift `s^2 kappa / 2` it causes (lines): report the
    /// blurred curve instead of the true one. Use it for images that are
    /// not blurred steps or lines, such as `synth paper-disc`.
    #[arg(long)]
    pub no_blur_correction: bool,
}

impl Default for CurveArgs {
    /// The flags' defaults (those of the command line, read from the
    /// declarations above): what a job file's curve gets for a key it
    /// leaves out.
    fn default() -> Self {
        #[derive(clap::Parser)]
        struct Defaults {
            #[command(flatten)]
            curve: CurveArgs,
        }
        <Defaults as clap::Parser>::parse_from(["vicurve"]).curve
    }
}

impl CurveArgs {
    /// The options as the library's job runner takes them.
    pub fn options(&self) -> CurveOptions {
        CurveOptions {
            closed: self.closed,
            kind: self.kind.clone(),
            polarity: self.polarity.clone(),
            stages: self.stages.clone(),
            degree: self.degree,
            interp: self.interp.clone(),
            tolerance: self.tolerance,
            max_iter: self.max_iter,
            no_blur_correction: self.no_blur_correction,
        }
    }

    /// The fit configuration (not yet validated: callers add their own
    /// options first); see [`CurveOptions::config`].
    pub fn config(&self) -> Result<FitConfig, Failure> {
        Ok(self.options().config()?)
    }

    /// The starting curve `spec`; see [`CurveOptions::init`].
    pub fn init(&self, spec: &str) -> Result<InitialCurve, Failure> {
        Ok(self.options().init(spec)?)
    }
}

/// The band's coordinates, the gray-level model and corners: options that
/// `measure` has and sequences do not.
#[derive(clap::Args, Clone, Debug)]
pub struct BandArgs {
    /// Curvilinear coordinates of the band pixels: `exact` (closest-point
    /// projection of every pixel, the default) or `levelset` (the paper's:
    /// values on a mesh of square elements, interpolated; biased outward by
    /// about mesh-size^2 / (12 x radius of curvature) px).
    #[arg(long, default_value = "exact", value_parser = coords_parser())]
    pub coords: Coords,
    /// Element side of the levelset mesh, pixels (with `--coords levelset`).
    #[arg(long, default_value_t = 10.0, value_name = "PX")]
    pub mesh_size: f64,
    /// Gray levels of the virtual image: `varying` (dark level and contrast
    /// follow uneven light along the curve, elements of 128 px, or of a
    /// half or a quarter of that when the light changes faster; the
    /// default), `varying:LEN` (elements of LEN px at most) or `global`
    /// (one pair for the whole curve, the paper's).
    #[arg(long, default_value = "varying", value_name = "MODEL")]
    pub levels: String,
    /// Corners: arc lengths (pixels) along the initial curve, from its
    /// start, where the measured curve may have a corner or a tangent break
    /// (repeated knots; see docs/breaks.md), e.g. `--break 120.5,240`.
    #[arg(long = "break", value_name = "S1,S2", value_delimiter = ',')]
    pub breaks: Vec<f64>,
    /// Do not look for corners: without --break, a curve that turns sharply
    /// within a few pixels and hardly beside (a polygon's vertex) is
    /// measured again with breaks there (the JSON's `corners_found`); this
    /// keeps the smooth measurement.
    #[arg(long)]
    pub no_find_corners: bool,
    /// How the gray levels relate to the light: `auto` (estimate the tone
    /// curve around the measured edge and, when the image is clearly not
    /// linear, measure again on it taken back to linear light; the JSON's
    /// `tone` and `tone_estimate`; the default), `linear` (raw or linear
    /// data), `srgb` (the sRGB encoding of most JPEG files) or a gamma,
    /// e.g. `2.2` (the light is the gray level, on [0, 1], to that power).
    #[arg(long, default_value = "auto", value_name = "CURVE")]
    pub tone: String,
}

/// `--coords`: the two names with their help, read by
/// [`Coords`]'s `FromStr`.
fn coords_parser() -> impl clap::builder::TypedValueParser<Value = Coords> {
    PossibleValuesParser::new([
        PossibleValue::new("exact").help("Exact projection of every band pixel"),
        PossibleValue::new("levelset").help("The paper's finite-element levelsets"),
    ])
    .try_map(|name| name.parse::<Coords>())
}

impl BandArgs {
    /// Set these options in `config`.
    pub fn apply(&self, config: &mut FitConfig) -> Result<(), Failure> {
        config.coords = match self.coords {
            Coords::Exact => Coords::Exact,
            Coords::Levelset { .. } => Coords::Levelset {
                mesh_size: self.mesh_size,
            },
        };
        config.levels = parse_levels(&self.levels)?;
        config.breaks = self.breaks.clone();
        config.find_corners = !self.no_find_corners;
        config.tone = self
            .tone
            .parse()
            .map_err(|e| Failure::Error(format!("--tone: {e}")))?;
        Ok(())
    }
}

/// `--levels global|varying|varying:LEN`.
fn parse_levels(s: &str) -> Result<LevelModel, Failure> {
    s.parse::<LevelModel>()
        .map_err(|e| Failure::Error(format!("--levels: {e}")))
}

#[cfg(test)]
mod tests {
    use super::*;
    use vicurve::fit::Polarity;
    use vicurve::interp::Interpolation;
    use vicurve::virtual_image::Kind;

    /// A job file's curve gets the command line's defaults for the keys it
    /// leaves out: the library's defaults are the flags'.
    #[test]
    fn the_librarys_curve_defaults_are_the_flags() {
        assert_eq!(CurveArgs::default().options(), CurveOptions::default());
    }

    #[test]
    fn levels_argument() {
        assert_eq!(parse_levels("global").ok(), Some(LevelModel::Global));
        assert_eq!(parse_levels("varying").ok(), Some(LevelModel::default()));
        assert_eq!(
            parse_levels("varying:200").ok(),
            Some(LevelModel::Varying {
                element_length: 200.0
            })
        );
        for bad in ["", "vary", "varying:", "varying:x", "global:3"] {
            assert!(parse_levels(bad).is_err(), "{bad}");
        }
    }

    #[test]
    fn defaults_are_the_libraries() {
        let config = CurveArgs::default().config().ok().unwrap();
        let library = FitConfig::default();
        assert_eq!(config.kind, library.kind);
        assert_eq!(config.polarity, library.polarity);
        assert_eq!(config.degree, library.degree);
        assert_eq!(config.interpolation, library.interpolation);
        assert_eq!(config.tolerance, library.tolerance);
        assert_eq!(config.max_iterations, library.max_iterations);
        assert_eq!(config.stages, None);
        assert!(config.blur_correction);
    }

    #[test]
    fn the_command_lines_words_parse() {
        let parse = |kind: &str, polarity: &str, interp: &str| {
            let a = CurveArgs {
                kind: kind.into(),
                polarity: polarity.into(),
                interp: Some(interp.into()),
                ..CurveArgs::default()
            };
            a.config()
                .ok()
                .map(|c| (c.kind, c.polarity, c.interpolation))
        };
        use Interpolation::*;
        use Polarity::*;
        assert_eq!(
            parse("contour", "bright-line", "cubic"),
            Some((Kind::Contour, Positive, CubicBSpline))
        );
        assert_eq!(
            parse("Silhouette", "Dark-Inside", "bilinear"),
            Some((Kind::Silhouette, Negative, Bilinear))
        );
        assert_eq!(
            parse("silhouette", "bright-right", "keys"),
            Some((Kind::Silhouette, Negative, Keys))
        );
        assert_eq!(
            parse("silhouette", "auto", "cubic-bspline"),
            Some((Kind::Silhouette, Auto, CubicBSpline))
        );
        assert!(parse("edge", "auto", "cubic").is_none());
        assert!(parse("silhouette", "up", "cubic").is_none());
        assert!(parse("silhouette", "auto", "nearest").is_none());
    }
}
