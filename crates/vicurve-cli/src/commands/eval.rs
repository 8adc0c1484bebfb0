//! `vicurve eval`: accuracy of measured points against a truth file.

use crate::failure::Failure;
use crate::output::write_json;
use serde::Serialize;
use std::path::PathBuf;
use vicurve::render::Truth;
use vicurve::truth::{evaluate, ErrorStats};

/// Compare measured points with the exact curve.
#[derive(clap::Args)]
pub struct Args {
    /// Points CSV with columns x and y (as written by `measure --points`).
    pub points: PathBuf,
    /// Truth file (as written by `synth --truth`).
    pub truth: PathBuf,
    /// Also write the statistics as JSON.
    #[arg(long)]
    pub json: Option<PathBuf>,
}

#[derive(Serialize)]
struct EvalFile<'a> {
    points: String,
    truth: String,
    /// Distances are signed along the true curve's normal: positive outside
    /// a closed curve, towards +y for a sine travelled in +x.
    convention: &'static str,
    #[serde(flatten)]
    stats: &'a ErrorStats,
}

pub fn run(args: Args) -> Result<(), Failure> {
    let points = vicurve::io::read_polyline_csv(&args.points)?;
    let truth = Truth::load(&args.truth)?;
    let stats = evaluate(&points, &truth.shape)?;
    println!("points:  {}", stats.count);
    println!(
        "bias:    {:+.3e} px (mean signed normal distance; + = outside / +n side)",
        stats.bias
    );
    println!("scatter: {:.3e} px (RMS about the mean)", stats.scatter);
    println!("max:     {:.3e} px (largest |distance|)", stats.max_abs);
    if let Some(p) = &args.json {
        write_json(
            p,
            &EvalFile {
                points: args.points.display().to_string(),
                truth: args.truth.display().to_string(),
                convention: "signed distance from each point to the true curve along its normal, pixels; positive outside closed curves, towards +y for open sine curves",
                stats: &stats,
            },
        )?;
    }
    Ok(())
}
