//! The options of one curve of a job, as text: a job file's `[[curve]]`
//! keys and the command line's flags of `measure` and `track` (same names,
//! `_` for `-`), and the start and fit configuration they describe.

use crate::curve::InitialCurve;
use crate::error::{Error, Result};
use crate::fit::{parse_stages, FitConfig};
use std::path::Path;

/// One curve's options; [`Default`] gives the command line's defaults
/// (what a job file's curve gets for a key it leaves out).
#[derive(Clone, Debug, PartialEq)]
pub struct CurveOptions {
    /// Treat a `polyline:` start as closed (last point joins the first).
    pub closed: bool,
    /// `silhouette` or `contour`.
    pub kind: String,
    /// `auto`, `bright-inside`, `dark-inside`, `bright-left`,
    /// `bright-right`, `bright-line` or `dark-line`.
    pub polarity: String,
    /// Coarse-to-fine stages `R:N,...`; `None`: the default schedule.
    pub stages: Option<String>,
    /// Degree of the B-splines (1 to 5).
    pub degree: usize,
    /// Image interpolation (`cubic`, `bilinear`, `keys`); `None`: cubic.
    pub interp: Option<String>,
    /// Convergence tolerance on the displacement update, pixels.
    pub tolerance: f64,
    /// Iteration limit per stage.
    pub max_iter: usize,
    /// Report the blurred curve (no blur estimate, no pixel-edge stage).
    pub no_blur_correction: bool,
}

impl Default for CurveOptions {
    fn default() -> Self {
        CurveOptions {
            closed: false,
            kind: "silhouette".into(),
            polarity: "auto".into(),
            stages: None,
            degree: 3,
            interp: None,
            tolerance: 1e-4,
            max_iter: 200,
            no_blur_correction: false,
        }
    }
}

impl CurveOptions {
    /// The fit configuration (not yet validated: callers add their own
    /// options first). The values are parsed by the library's `FromStr`.
    ///
    /// Errors: [`Error::Parse`] for a value that does not parse.
    pub fn config(&self) -> Result<FitConfig> {
        let mut config = FitConfig {
            kind: self.kind.parse()?,
            polarity: self.polarity.parse()?,
            degree: self.degree,
            tolerance: self.tolerance,
            max_iterations: self.max_iter,
            blur_correction: !self.no_blur_correction,
            ..FitConfig::default()
        };
        if let Some(s) = &self.stages {
            config.stages = Some(parse_stages(s)?);
        }
        if let Some(i) = &self.interp {
            config.interpolation = i.parse()?;
        }
        Ok(config)
    }

    /// The starting curve `spec` (`circle:...`, `segment:...` or
    /// `polyline:FILE`, whose file is read), closed with `closed`.
    ///
    /// Errors: the file's or the text's, and `closed` given for a start
    /// that is not a polyline.
    pub fn init(&self, spec: &str) -> Result<InitialCurve> {
        if let Some(file) = spec.strip_prefix("polyline:") {
            let points = crate::io::read_polyline_csv(Path::new(file))?;
            return Ok(InitialCurve::Polyline {
                points,
                closed: self.closed,
            });
        }
        if self.closed {
            return Err(Error::job("--closed applies to polyline: starts only"));
        }
        spec.parse::<InitialCurve>()
    }
}
