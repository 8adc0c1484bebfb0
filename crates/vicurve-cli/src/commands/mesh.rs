//! `vicurve mesh`: the NURBS patch between two measured edges
//! (`vicurve::nurbs::patch`), as JSON and as VTK files for ParaView.

use crate::failure::Failure;
use crate::output::write_json;
use serde::Serialize;
use std::path::PathBuf;
use vicurve::export::read_result_curve;
use vicurve::nurbs::vtu::{control_net_vtu, patch_vtu};
use vicurve::nurbs::{NurbsPatch, PatchConfig, PatchData};

/// Build the NURBS surface patch between two open measured curves.
#[derive(clap::Args)]
pub struct Args {
    /// Result file of the first edge (`vicurve measure --out`): the patch's
    /// side v = 0.
    pub first: PathBuf,
    /// Result file of the second edge: the side v = 1 (reversed if it runs
    /// against the first).
    pub second: PathBuf,
    /// Write the patch (degrees, knot vectors, control net, weights) as
    /// JSON.
    #[arg(long, value_name = "FILE")]
    pub out: Option<PathBuf>,
    /// Write the patch sampled into quadrilateral cells as a VTK
    /// unstructured grid (.vtu, ASCII) for ParaView.
    #[arg(long, value_name = "FILE")]
    pub vtu: Option<PathBuf>,
    /// Write the control net as a VTK unstructured grid.
    #[arg(long, value_name = "FILE")]
    pub vtu_net: Option<PathBuf>,
    /// Degree across the patch (1 to 5; 1: straight lines between the
    /// edges).
    #[arg(long, default_value_t = 1)]
    pub degree_across: usize,
    /// h-refinement along the edges: split every knot span into N.
    #[arg(long, default_value_t = 1, value_name = "N")]
    pub refine_along: usize,
    /// h-refinement across: split every knot span into M.
    #[arg(long, default_value_t = 1, value_name = "M")]
    pub refine_across: usize,
    /// Cells of the .vtu per element (knot span), along and across.
    #[arg(long, default_value = "4,4", value_name = "NX,NY")]
    pub vtu_cells: String,
    /// Keep the second curve's direction even when it runs against the
    /// first (the patch then twists).
    #[arg(long)]
    pub keep_direction: bool,
}

/// The JSON record: the patch with what it was made from.
#[derive(Serialize)]
struct PatchFile<'a> {
    vicurve_version: &'static str,
    sources: [String; 2],
    coordinates: &'static str,
    parametrisation: &'static str,
    config: &'a PatchConfig,
    reversed_second: bool,
    curve_degrees: [usize; 2],
    elements: [usize; 2],
    patch: PatchData,
}

const COORDINATES: &str = "pixels; x = column, y = row (down); the centre of the pixel in row i, column j is at (x, y) = (j, i)";
const PARAMETRISATION: &str = "u in [0, 1] along: each curve's own parameter (its chord length, close to arc length) mapped affinely onto [0, 1], so the points joined across are at the same fraction of each edge's length; v in [0, 1] across: v = 0 is the first curve, v = 1 the second, exactly (both brought to a common degree and knot vector by degree elevation and knot insertion); weights all 1 (a non-rational B-spline patch)";

pub fn run(args: Args) -> Result<(), Failure> {
    let cells = parse_cells(&args.vtu_cells)?;
    let config = PatchConfig {
        degree_across: args.degree_across,
        refine_along: args.refine_along,
        refine_across: args.refine_across,
        match_direction: !args.keep_direction,
    };
    config.validate()?;
    let a = read_result_curve(&args.first)?;
    let b = read_result_curve(&args.second)?;
    let build = NurbsPatch::between_data(&a.curve, &b.curve, &config)?;
    let patch = &build.patch;
    let (ea, eb) = patch.elements();
    let sources = [
        args.first.display().to_string(),
        args.second.display().to_string(),
    ];
    let comment = format!(
        "NURBS patch between {} (v = 0) and {} (v = 1)",
        sources[0], sources[1]
    );
    let mut first_error: Option<String> = None;
    let mut note = |r: Result<(), String>| {
        if let Err(e) = r {
            first_error.get_or_insert(e);
        }
    };
    if let Some(p) = &args.out {
        let record = PatchFile {
            vicurve_version: env!("CARGO_PKG_VERSION"),
            sources: sources.clone(),
            coordinates: COORDINATES,
            parametrisation: PARAMETRISATION,
            config: &config,
            reversed_second: build.reversed_second,
            curve_degrees: build.curve_degrees,
            elements: [ea, eb],
            patch: patch.to_data(),
        };
        note(write_json(p, &record));
    }
    if let Some(p) = &args.vtu {
        let r = patch_vtu(patch, cells, &comment).map_err(|e| e.to_string());
        note(r.and_then(|text| write(p, &text)));
    }
    if let Some(p) = &args.vtu_net {
        note(write(p, &control_net_vtu(patch, &comment)));
    }
    if let Some(e) = first_error {
        return Err(Failure::Error(e));
    }
    let (p, q) = patch.degrees();
    let (nu, nv) = patch.size();
    println!(
        "patch: degree {p} along x {q} across, {ea} x {eb} elements, control net {nu} x {nv}{}",
        if build.reversed_second {
            " (second curve reversed to run with the first)"
        } else {
            ""
        }
    );
    Ok(())
}

fn write(path: &std::path::Path, text: &str) -> Result<(), String> {
    std::fs::write(path, text).map_err(|e| format!("cannot write {}: {e}", path.display()))
}

/// `--vtu-cells NX,NY`.
fn parse_cells(text: &str) -> Result<(usize, usize), Failure> {
    let v: Vec<Option<usize>> = text.split(',').map(|t| t.trim().parse().ok()).collect();
    match v.as_slice() {
        [Some(x), Some(y)] if *x > 0 && *y > 0 => Ok((*x, *y)),
        _ => Err(Failure::Error(format!(
            "malformed --vtu-cells '{text}': expected two positive integers NX,NY"
        ))),
    }
}
