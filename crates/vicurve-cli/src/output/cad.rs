//! The measured B-spline as a DXF `SPLINE` (CAD) and as an SVG path of
//! exact cubic Bézier segments (`vicurve::export`): `measure --dxf
//! --svg-curve` and `vicurve export`.

use crate::args::files::{ClosedArg, YArg};
use crate::args::CurveFiles;
use crate::failure::Failure;
use std::path::Path;
use vicurve::curve::SplineCurveData;
use vicurve::export::{curve_svg, spline_dxf, ClosedForm, DxfOptions, SvgOptions, YAxis};

/// Write the requested files for `curve`, measured in the image named
/// `input` of `size` pixels (the SVG's canvas). Both are attempted; the
/// first error is returned.
pub fn write(
    files: &CurveFiles,
    curve: &SplineCurveData,
    input: &str,
    size: Option<(usize, usize)>,
) -> Result<(), Failure> {
    let mut first: Option<String> = None;
    if let Some(p) = &files.dxf {
        let options = DxfOptions {
            y_axis: match files.dxf_y {
                YArg::Up => YAxis::Up,
                YArg::Down => YAxis::Down,
            },
            closed_form: match files.dxf_closed {
                ClosedArg::Periodic => ClosedForm::Periodic,
                ClosedArg::Clamped => ClosedForm::Clamped,
            },
            comment: format!("input {input}"),
        };
        let r = spline_dxf(curve, &options)
            .map_err(|e| e.to_string())
            .and_then(|text| write_text(p, "DXF", &text));
        if let Err(e) = r {
            first.get_or_insert(e);
        }
    }
    if let Some(p) = &files.svg_curve {
        let options = SvgOptions {
            canvas: size,
            comment: format!("input {input}"),
            ..SvgOptions::default()
        };
        let r = curve_svg(curve, &options)
            .map_err(|e| e.to_string())
            .and_then(|text| write_text(p, "SVG", &text));
        if let Err(e) = r {
            first.get_or_insert(e);
        }
    }
    match first {
        Some(e) => Err(Failure::Error(e)),
        None => Ok(()),
    }
}

fn write_text(path: &Path, what: &str, text: &str) -> Result<(), String> {
    std::fs::write(path, text).map_err(|e| format!("cannot write {what} {}: {e}", path.display()))
}
