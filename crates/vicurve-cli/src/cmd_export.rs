//! `vicurve export` and the `--dxf` / `--svg-curve` outputs of `vicurve
//! measure`: the measured B-spline as a DXF `SPLINE` (CAD) and as an SVG
//! path of exact cubic Bézier segments (`vicurve::export`).

use crate::Failure;
use std::path::{Path, PathBuf};
use vicurve::curve::SplineCurveData;
use vicurve::export::{
    curve_svg, read_result_curve, spline_dxf, ClosedForm, DxfOptions, SvgOptions, YAxis,
};

/// The CAD outputs of a measured curve.
#[derive(clap::Args, Default)]
pub struct CurveFiles {
    /// Write the measured curve as a DXF drawing (R2000) with one SPLINE
    /// entity (degree, knots, control points, closed flag), for CAD
    /// programs. y_dxf = -y by default, so that the drawing looks like the
    /// image (--dxf-y).
    #[arg(long, value_name = "FILE")]
    pub dxf: Option<PathBuf>,
    /// Write the measured curve as an SVG path of exact cubic Bézier
    /// segments (one per knot span; degree 3 or lower).
    #[arg(long, value_name = "FILE")]
    pub svg_curve: Option<PathBuf>,
    /// DXF y axis: `up` (y_dxf = -y, the drawing looks like the image) or
    /// `down` (y_dxf = y, the pixel coordinates unchanged).
    #[arg(long, value_enum, default_value = "up")]
    pub dxf_y: YArg,
    /// DXF form of closed curves: `periodic` (flagged closed and periodic,
    /// the standard form) or `clamped` (flagged open, first control point =
    /// last: for programs that ignore knots, such as LibreCAD 2.2).
    #[arg(long, value_enum, default_value = "periodic")]
    pub dxf_closed: ClosedArg,
}

/// `--dxf-y`.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq, clap::ValueEnum)]
pub enum YArg {
    /// y_dxf = -y.
    #[default]
    Up,
    /// y_dxf = y.
    Down,
}

/// `--dxf-closed`.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq, clap::ValueEnum)]
pub enum ClosedArg {
    /// Closed and periodic.
    #[default]
    Periodic,
    /// Clamped, flagged open.
    Clamped,
}

impl CurveFiles {
    /// Whether any file is asked for.
    pub fn any(&self) -> bool {
        self.dxf.is_some() || self.svg_curve.is_some()
    }

    /// Refuse before measuring what cannot be written: an SVG of cubic
    /// Béziers for a curve of degree above 3.
    pub fn check(&self, degree: usize) -> Result<(), Failure> {
        if self.svg_curve.is_some() && degree > 3 {
            return Err(Failure::Error(format!(
                "--svg-curve writes exact cubic Bézier segments, which a B-spline of degree {degree} does not have: measure with --degree 3 or lower, or use --dxf"
            )));
        }
        Ok(())
    }

    /// Write the requested files for `curve`, measured in the image named
    /// `input` of `size` pixels (the SVG's canvas). Both are attempted; the
    /// first error is returned.
    pub fn write(
        &self,
        curve: &SplineCurveData,
        input: &str,
        size: Option<(usize, usize)>,
    ) -> Result<(), Failure> {
        let mut first: Option<String> = None;
        if let Some(p) = &self.dxf {
            let options = DxfOptions {
                y_axis: match self.dxf_y {
                    YArg::Up => YAxis::Up,
                    YArg::Down => YAxis::Down,
                },
                closed_form: match self.dxf_closed {
                    ClosedArg::Periodic => ClosedForm::Periodic,
                    ClosedArg::Clamped => ClosedForm::Clamped,
                },
                comment: format!("input {input}"),
            };
            let r = spline_dxf(curve, &options)
                .map_err(|e| e.to_string())
                .and_then(|text| write(p, "DXF", &text));
            if let Err(e) = r {
                first.get_or_insert(e);
            }
        }
        if let Some(p) = &self.svg_curve {
            let options = SvgOptions {
                canvas: size,
                comment: format!("input {input}"),
                ..SvgOptions::default()
            };
            let r = curve_svg(curve, &options)
                .map_err(|e| e.to_string())
                .and_then(|text| write(p, "SVG", &text));
            if let Err(e) = r {
                first.get_or_insert(e);
            }
        }
        match first {
            Some(e) => Err(Failure::Error(e)),
            None => Ok(()),
        }
    }
}

fn write(path: &Path, what: &str, text: &str) -> Result<(), String> {
    std::fs::write(path, text).map_err(|e| format!("cannot write {what} {}: {e}", path.display()))
}

/// Export a measured curve from its result file, without measuring again.
#[derive(clap::Args)]
pub struct Args {
    /// A result file written by `vicurve measure --out`.
    pub result: PathBuf,
    #[command(flatten)]
    pub files: CurveFiles,
}

pub fn run(args: Args) -> Result<(), Failure> {
    if !args.files.any() {
        return Err(Failure::Error(
            "nothing to write: give --dxf FILE and/or --svg-curve FILE".into(),
        ));
    }
    let r = read_result_curve(&args.result)?;
    args.files.check(r.curve.degree)?;
    let input = r
        .input_path
        .clone()
        .unwrap_or_else(|| args.result.display().to_string());
    args.files.write(&r.curve, &input, r.size)
}
