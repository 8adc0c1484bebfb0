//! The result file: the JSON record of a measurement that `vicurve measure
//! --out` writes and the Python package's `Result.to_json()` returns.
//!
//! [`ResultFile`] borrows the measurement and what it was made from (the
//! initial curve, the configuration, the input's name and size) and
//! serialises them with a fixed field order, so that the same input gives
//! the same document whichever front end measured it (the input's name and
//! the stages' wall-clock `seconds` aside).
//!
//! ```no_run
//! use vicurve::{curve::InitialCurve, fit::{measure, FitConfig}, io::load_image};
//! use vicurve::report::ResultFile;
//! let image = load_image("part.png".as_ref())?;
//! let init = InitialCurve::Circle { cx: 320.0, cy: 240.0, r: 100.0 };
//! let config = FitConfig::default();
//! let m = measure(&image, &init, &config)?;
//! let size = (image.width(), image.height());
//! let record = ResultFile::new("part.png", size, &init, &config, &m);
//! std::fs::write("result.json", record.to_json()).unwrap();
//! # Ok::<(), vicurve::Error>(())
//! ```

use crate::curve::{InitialCurve, SplineCurveData};
use crate::derived::Derived;
use crate::fit::grow::GrowReport;
use crate::fit::FitConfig;
use crate::measurement::{LevelSample, Measurement, MisfitSummary, Outcome, StageReport, Trim};
use crate::psf::EdgeSpread;
use crate::tone::{Tone, ToneEstimate};
use crate::virtual_image::Kind;
use serde::Serialize;

/// The coordinate convention, written into every result file.
pub const CONVENTION: &str = "pixels; x = column, y = row; the centre of the pixel in row i, column j is at (x, y) = (j, i); \
unit normal n = (-t_y, t_x) with t the unit tangent; closed curves run counterclockwise on screen (y down) so n points outward; \
open curves keep the direction of the initial curve, n on the screen-right of travel";

/// The JSON record of a measurement; the fields are written in this order.
#[derive(Clone, Debug, Serialize)]
pub struct ResultFile<'a> {
    /// Version of the library that measured.
    pub vicurve_version: &'static str,
    /// The input image.
    pub input: InputInfo<'a>,
    /// [`CONVENTION`].
    pub coordinates: &'static str,
    /// The starting curve.
    pub initial_curve: &'a InitialCurve,
    /// The full configuration.
    pub config: &'a FitConfig,
    /// How the fit ended.
    pub outcome: Outcome,
    /// Which side is bright, in words ([`polarity_text`]).
    pub polarity: String,
    /// The virtual image's gray levels at the end of the fit.
    pub gray_levels: GrayLevels,
    /// The measured B-spline.
    pub curve: CurveRecord,
    /// Arc length of the measured curve, pixels.
    pub length: f64,
    /// Area enclosed by a closed measured curve, square pixels (`None` for
    /// open curves).
    pub area: Option<f64>,
    /// Derived measurements: closed-curve measures (best-fit circle and
    /// ellipse...) and a curvature summary, see [`crate::derived`].
    pub derived: Derived,
    /// The edge's estimated blur, see [`crate::psf`].
    pub edge_spread: Option<EdgeSpread>,
    /// Whether the blur's curvature shift was removed from the curve.
    pub blur_corrected: bool,
    /// The tone curve the gray levels were read with (`linear` unless the
    /// image was taken to linear light), see [`crate::tone`].
    pub tone: Tone,
    /// The tone curve estimated around the edge (`null` when not
    /// estimated), see [`crate::tone::estimate`].
    pub tone_estimate: Option<ToneEstimate>,
    /// Number of output samples.
    pub samples: usize,
    /// The samples where the model misfits (their `sigma` covers it).
    pub misfit: MisfitSummary,
    /// The standard deviation of a shift of the whole curve along its
    /// normals, common to every sample and not in their `sigma`, pixels
    /// ([`Measurement::sigma_shift`]: the tone curve's reading; 0 when
    /// none).
    pub sigma_shift: f64,
    /// Per-stage history.
    pub stages: &'a [StageReport],
    /// Stages of the default schedule that were skipped, with the reason.
    pub skipped_stages: &'a [String],
    /// Corners found on a first, smooth measurement, where the curve was
    /// measured again with breaks (`[x, y]`, px); absent when none.
    #[serde(skip_serializing_if = "<[_]>::is_empty")]
    pub corners_found: &'a [[f64; 2]],
    /// Open curves: where each end was trimmed because the band would
    /// leave the image (`null` for an end measured to the start's end);
    /// absent for closed curves.
    #[serde(skip_serializing_if = "Option::is_none")]
    pub trim: Option<Trim>,
    /// How the curve grew from a short start ([`crate::fit::grow`]);
    /// absent otherwise.
    #[serde(skip_serializing_if = "Option::is_none")]
    pub grow: Option<&'a GrowReport>,
}

/// The input image.
#[derive(Clone, Debug, Serialize)]
pub struct InputInfo<'a> {
    /// The image's name as the user gave it (a path, or a description of
    /// an in-memory image).
    pub path: &'a str,
    /// Width, pixels.
    pub width: usize,
    /// Height, pixels.
    pub height: usize,
}

/// The virtual image's gray levels at the end of the fit.
#[derive(Clone, Debug, Serialize)]
pub struct GrayLevels {
    /// Level at `gamma = 0` (outside / line ground); the mean over the band
    /// when the levels vary.
    pub a: f64,
    /// Contrast: the level at `gamma = 1` is `a + c`; the mean over the
    /// band when the levels vary.
    pub c: f64,
    /// The levels along the curve when they vary (see
    /// [`crate::fit::LevelModel`]); absent for the global pair.
    #[serde(skip_serializing_if = "Vec::is_empty")]
    pub along: Vec<LevelSample>,
}

/// The measured B-spline and how closely it follows the samples.
#[derive(Clone, Debug, Serialize)]
pub struct CurveRecord {
    /// Degree, knots and control points.
    #[serde(flatten)]
    pub spline: SplineCurveData,
    /// Largest distance from the B-spline to the measured samples, pixels.
    pub fit_error: f64,
}

impl<'a> ResultFile<'a> {
    /// The record of `m`, measured on the image named `path` of `size =
    /// (width, height)` pixels from `init` with `config`.
    pub fn new(
        path: &'a str,
        size: (usize, usize),
        init: &'a InitialCurve,
        config: &'a FitConfig,
        m: &'a Measurement,
    ) -> Self {
        let last = m.stages.last();
        let a = last.map_or(f64::NAN, |s| s.a);
        let c = last.map_or(f64::NAN, |s| s.c);
        ResultFile {
            vicurve_version: env!("CARGO_PKG_VERSION"),
            input: InputInfo {
                path,
                width: size.0,
                height: size.1,
            },
            coordinates: CONVENTION,
            initial_curve: init,
            config,
            outcome: m.outcome,
            polarity: polarity_text(config.kind, m.curve.is_closed(), c),
            gray_levels: GrayLevels {
                a,
                c,
                along: m.levels.clone(),
            },
            curve: CurveRecord {
                spline: m.curve_data(),
                fit_error: m.curve_fit_error,
            },
            length: m.length(),
            area: m.area(),
            derived: Derived::new(m),
            edge_spread: m.edge_spread,
            blur_corrected: m.blur_corrected,
            tone: m.tone,
            tone_estimate: m.tone_estimate,
            samples: m.samples.len(),
            misfit: m.misfit_summary(),
            sigma_shift: m.sigma_shift(),
            stages: &m.stages,
            skipped_stages: &m.skipped,
            corners_found: &m.corners_found,
            trim: (!m.curve.is_closed()).then_some(m.trim),
            grow: None,
        }
    }

    /// The document as pretty-printed JSON with a final newline, exactly as
    /// `vicurve measure --out` writes it. Non-finite numbers become `null`.
    pub fn to_json(&self) -> String {
        // Plain data with string keys: serialisation cannot fail (serde_json
        // writes non-finite floats as null).
        serde_json::to_string_pretty(self).unwrap_or_default() + "\n"
    }
}

/// Which side is bright, in words, from the sign of the contrast `c` of a
/// curve of `kind` (closed or not); `"unknown"` when `c` is not finite.
pub fn polarity_text(kind: Kind, closed: bool, c: f64) -> String {
    if !c.is_finite() {
        return "unknown".into();
    }
    let positive = c > 0.0;
    match (kind, closed, positive) {
        (Kind::Contour, _, true) => "bright line on a dark ground",
        (Kind::Contour, _, false) => "dark line on a bright ground",
        (Kind::Silhouette, true, true) => "bright inside",
        (Kind::Silhouette, true, false) => "dark inside",
        (Kind::Silhouette, false, true) => "bright on the left of the curve's direction (screen)",
        (Kind::Silhouette, false, false) => "bright on the right of the curve's direction (screen)",
    }
    .into()
}
