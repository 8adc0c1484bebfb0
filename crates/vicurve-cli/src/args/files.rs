//! The output files of a measurement, and its CAD exports (written by
//! [`crate::output`]).

use crate::failure::Failure;
use std::path::PathBuf;

/// The optional output files of a measurement.
#[derive(clap::Args, Clone, Default)]
pub struct Outputs {
    /// Write the result (B-spline, history, outcome, configuration) as JSON.
    #[arg(long)]
    pub out: Option<PathBuf>,
    /// Write the samples as CSV with columns s,x,y,nx,ny,sigma,weight,sigma_noise,misfit.
    #[arg(long)]
    pub points: Option<PathBuf>,
    /// Write an SVG overlay (image, initial curve, band, measured curve).
    #[arg(long)]
    pub svg: Option<PathBuf>,
    /// Write a PNG overlay.
    #[arg(long)]
    pub png: Option<PathBuf>,
    /// Magnification of the PNG overlay (integer).
    #[arg(long, default_value_t = 1)]
    pub png_scale: u32,
}

impl Outputs {
    /// Whether any file is asked for.
    pub fn any(&self) -> bool {
        self.out.is_some() || self.points.is_some() || self.svg.is_some() || self.png.is_some()
    }
}

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
}
