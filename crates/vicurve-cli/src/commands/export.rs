//! `vicurve export`: a measured curve from its result file, as a DXF
//! `SPLINE` and an SVG of cubic Béziers, without measuring again.

use crate::args::CurveFiles;
use crate::failure::Failure;
use crate::output::cad;
use std::path::PathBuf;
use vicurve::export::read_result_curve;

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
    cad::write(&args.files, &r.curve, &input, r.size)
}
