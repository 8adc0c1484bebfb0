//! `vicurve measure`: one curve in one image.

use crate::args::{AllArgs, BandArgs, CurveArgs, CurveFiles, Outputs, StartArgs};
use crate::failure::{finish, Failure};
use crate::measure_start::{explicit, grow_from, initial_curve};
use crate::output::measurement::{print_summary, write_outputs, Measured};
use crate::output::{cad, diagnostics, model};
use std::path::PathBuf;
use vicurve::fit::measure;
use vicurve::model::ShapeModel;

/// Measure a curve in an image.
#[derive(clap::Args)]
pub struct Args {
    /// The image: PNG, TIFF or JPEG; 8 or 16 bits; gray or colour (converted
    /// to luminance).
    pub image: PathBuf,
    #[command(flatten)]
    pub start: StartArgs,
    #[command(flatten)]
    pub curve: CurveArgs,
    #[command(flatten)]
    pub band: BandArgs,
    /// Fit a shape to the measured curve: `circle`, `ellipse`, `line` or
    /// `polygon:N` (its parameters with uncertainties are printed and
    /// written as `model` in `--out`; `--points` samples the shape), or
    /// `bspline-curve` (a free B-spline curve, its control points the
    /// unknowns; `--dxf` and `--svg-curve` then export it).
    #[arg(long, value_name = "MODEL")]
    pub model: Option<ShapeModel>,
    #[command(flatten)]
    pub outputs: Outputs,
    /// Write diagnostics into DIR (created if missing): the band unwrapped
    /// on the measured curve's (s, r) grid (band.png), the residual
    /// image - virtual image (residual.png), the robust weights
    /// (weights.png), the convergence of each stage (convergence.png) and
    /// diagnostics.json; see docs/diagnostics.md.
    #[arg(long, value_name = "DIR")]
    pub diagnostics: Option<PathBuf>,
    #[command(flatten)]
    pub cad: CurveFiles,
    #[command(flatten)]
    pub all: AllArgs,
}

pub fn run(args: Args) -> Result<(), Failure> {
    args.all.check()?;
    if args.all.all {
        return super::measure_all::run(args);
    }
    let mut config = args.curve.config()?;
    args.band.apply(&mut config)?;
    config.validate()?;
    args.cad.check(config.degree)?;
    let auto = args.start.automatic()?;
    let explicit = explicit(&args.start, &args.curve)?;
    let image = vicurve::io::load_image(&args.image)?;
    let init = initial_curve(explicit, &auto, config.kind, &image)?;
    let (m, grown) = match args.start.grow {
        Some(length) => {
            let g = grow_from(&image, &init, &config, length)?;
            (g.measurement, Some(g.report))
        }
        None => (measure(&image, &init, &config)?, None),
    };
    let input = args.image.display().to_string();
    // Written whatever the outcome (a diverged fit is what they are for);
    // a failure does not prevent the other outputs.
    let diagnostics = match &args.diagnostics {
        Some(dir) => diagnostics::write(dir, &input, &image, &init, &config, &m),
        None => Ok(()),
    };
    let measured = Measured {
        input: &input,
        image: &image,
        init: &init,
        config: &config,
        m: &m,
    };
    if args.model == Some(ShapeModel::BsplineCurve) {
        // `--dxf` and `--svg-curve` then write the fitted curve.
        let written = model::run_bspline_curve(&args.outputs, &args.cad, measured);
        return written.and(diagnostics.map_err(Failure::Error));
    }
    let size = Some((image.width(), image.height()));
    let cad = cad::write(&args.cad, &m.curve_data(), &input, size);
    if let Some(shape) = args.model {
        let written = model::run(shape, &args.outputs, measured);
        return written.and(cad).and(diagnostics.map_err(Failure::Error));
    }
    write_outputs(&args.outputs, measured, grown.as_ref())?;
    cad?;
    diagnostics?;
    if !args.outputs.any() && !args.cad.any() {
        print_summary(&config, &m);
    }
    finish(&m)
}
