//! Result files: the JSON record of a measurement and the points CSV.

use serde::Serialize;
use std::io::Write;
use std::path::Path;
use vicurve::curve::{InitialCurve, SplineCurveData};
use vicurve::fit::{FitConfig, Measurement, Outcome, StageReport};

/// The coordinate convention, written into every output file.
pub const CONVENTION: &str = "pixels; x = column, y = row; the centre of the pixel in row i, column j is at (x, y) = (j, i); \
unit normal n = (-t_y, t_x) with t the unit tangent; closed curves run counterclockwise on screen (y down) so n points outward; \
open curves keep the direction of the initial curve, n on the screen-right of travel";

/// What `measure --out` writes.
#[derive(Serialize)]
pub struct ResultFile<'a> {
    pub vicurve_version: &'static str,
    pub input: InputInfo<'a>,
    pub coordinates: &'static str,
    pub initial_curve: &'a InitialCurve,
    pub config: &'a FitConfig,
    pub outcome: Outcome,
    pub polarity: String,
    pub gray_levels: GrayLevels,
    pub curve: CurveRecord,
    pub length: f64,
    pub area: Option<f64>,
    /// The edge's estimated blur (silhouettes), see `vicurve::psf`.
    pub edge_spread: Option<vicurve::psf::EdgeSpread>,
    /// Whether the blur's curvature shift was removed from the curve.
    pub blur_corrected: bool,
    pub samples: usize,
    pub stages: &'a [StageReport],
    pub skipped_stages: &'a [String],
}

/// The input image.
#[derive(Serialize)]
pub struct InputInfo<'a> {
    pub path: &'a str,
    pub width: usize,
    pub height: usize,
}

/// The virtual image's gray levels at the end of the fit.
#[derive(Serialize)]
pub struct GrayLevels {
    /// Level at `gamma = 0` (outside / line ground).
    pub a: f64,
    /// Contrast: the level at `gamma = 1` is `a + c`.
    pub c: f64,
}

/// The measured B-spline and how closely it follows the samples.
#[derive(Serialize)]
pub struct CurveRecord {
    #[serde(flatten)]
    pub spline: SplineCurveData,
    /// Largest distance from the B-spline to the measured samples, pixels.
    pub fit_error: f64,
}

impl<'a> ResultFile<'a> {
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
            gray_levels: GrayLevels { a, c },
            curve: CurveRecord {
                spline: m.curve_data(),
                fit_error: m.curve_fit_error,
            },
            length: m.length(),
            area: m.area(),
            edge_spread: m.edge_spread,
            blur_corrected: m.blur_corrected,
            samples: m.samples.len(),
            stages: &m.stages,
            skipped_stages: &m.skipped,
        }
    }
}

/// Which side is bright, in words, from the sign of the contrast.
pub fn polarity_text(kind: vicurve::virtual_image::Kind, closed: bool, c: f64) -> String {
    use vicurve::virtual_image::Kind;
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

/// Write any serialisable value as pretty JSON.
pub fn write_json<T: Serialize>(path: &Path, value: &T) -> Result<(), String> {
    let text = serde_json::to_string_pretty(value)
        .map_err(|e| format!("cannot encode JSON for {}: {e}", path.display()))?;
    std::fs::write(path, text + "\n").map_err(|e| format!("cannot write {}: {e}", path.display()))
}

/// Write the samples as CSV: the header `s,x,y,nx,ny,sigma` (a contract:
/// other tools read the columns by these names), then one row per sample.
pub fn write_points_csv(path: &Path, m: &Measurement) -> Result<(), String> {
    let err = |e: std::io::Error| format!("cannot write {}: {e}", path.display());
    let file = std::fs::File::create(path).map_err(err)?;
    let mut w = std::io::BufWriter::new(file);
    writeln!(w, "s,x,y,nx,ny,sigma").map_err(err)?;
    for s in &m.samples {
        writeln!(
            w,
            "{:.6},{:.6},{:.6},{:.6},{:.6},{:.3e}",
            s.s, s.x, s.y, s.nx, s.ny, s.sigma
        )
        .map_err(err)?;
    }
    w.flush().map_err(err)
}
