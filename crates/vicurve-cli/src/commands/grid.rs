//! `vicurve grid IMAGE --diameter D0`: circle-grid strain analysis. Every
//! printed circle is measured as an ellipse (`measure --all --model
//! ellipse`); its axes give the major and minor true strains, their
//! direction and the thickness strain, each with its uncertainty.
//!
//! `vicurve grid IMAGE --pitch P0`: square grids. Every cell is measured
//! as a closed curve with breaks at its four corners; the centroids,
//! indexed on the lattice, give the local deformation gradient and the
//! same strains ([`vicurve::objects::square_grid`]).

use super::measure_all::{finish, summary};
use crate::args::all::object_polarity;
use crate::failure::Failure;
use crate::output::objects::format_value;
use crate::output::write_json;
use serde::Serialize;
use std::io::Write;
use std::path::{Path, PathBuf};
use vicurve::model::ShapeModel;
use vicurve::objects::{
    cell_polarity, cell_strains, grid_strains, measure_all, AllConfig, GridStrain,
};
use vicurve::virtual_image::Kind;

/// Measure the strains of a circle grid or a square grid.
#[derive(clap::Args)]
#[command(group(clap::ArgGroup::new("printed").required(true).args(["diameter", "pitch"])))]
pub struct Args {
    /// The image of the deformed grid.
    pub image: PathBuf,
    /// Diameter of the printed circles before forming: px, or mm with
    /// --scale (a circle grid).
    #[arg(long, value_name = "D0")]
    pub diameter: Option<f64>,
    /// Pitch of a printed square grid before forming (cell side plus line
    /// width): px, or mm with --scale. The cells are measured.
    #[arg(long, value_name = "P0")]
    pub pitch: Option<f64>,
    /// Image scale, mm per pixel: --diameter is then in mm and the table
    /// also gives the centres in mm.
    #[arg(long, value_name = "MM_PER_PX")]
    pub scale: Option<f64>,
    /// The circles' or cells' phase: `auto` (circles: the minority phase;
    /// cells: the phase with more objects), `bright` or `dark`.
    #[arg(long, default_value = "auto")]
    pub polarity: String,
    /// Search only this rectangle `X0,Y0,X1,Y1` (pixels).
    #[arg(long, value_name = "X0,Y0,X1,Y1")]
    pub roi: Option<String>,
    /// Write one row per circle as CSV: id, centre (px, and mm with
    /// --scale), semi-axes, eps1, eps2, eps3 = -(eps1 + eps2), the major
    /// axis angle (degrees, counterclockwise on screen from +x), each with
    /// its sigma. Square grids: also the cell's column and row, its
    /// centroid's sigmas, the deformation gradient F11 F12 F21 F22 and
    /// whether it is from central differences (1) or one-sided (0, the
    /// grid's edge); a and b are those of the circle of diameter P0 the
    /// cell's F turns into an ellipse.
    #[arg(long, value_name = "FILE")]
    pub table: Option<PathBuf>,
    /// Write the strains and the configuration as JSON.
    #[arg(long, value_name = "FILE")]
    pub out: Option<PathBuf>,
    /// Write the forming-limit scatter (eps2 horizontal, eps1 vertical,
    /// two-sigma error bars): PNG when FILE ends in .png, else SVG.
    #[arg(long, value_name = "FILE.svg|FILE.png")]
    pub fld: Option<PathBuf>,
    /// Write the strain map: every measured circle over the image in a
    /// colour by eps1 (six bins, blue lowest to red highest; the SVG's
    /// legend gives their ranges), with its id: PNG when FILE ends in
    /// .png, else SVG.
    #[arg(long, value_name = "FILE.svg|FILE.png")]
    pub map: Option<PathBuf>,
}

/// The JSON of `grid --out`.
#[derive(Serialize)]
struct GridFile<'a> {
    vicurve_version: &'static str,
    input: &'a str,
    coordinates: &'static str,
    strains: &'static str,
    #[serde(skip_serializing_if = "Option::is_none")]
    diameter_px: Option<f64>,
    #[serde(skip_serializing_if = "Option::is_none")]
    pitch_px: Option<f64>,
    scale_mm_per_px: Option<f64>,
    config: &'a AllConfig,
    #[serde(skip_serializing_if = "Option::is_none")]
    circles: Option<Vec<&'a GridStrain>>,
    #[serde(skip_serializing_if = "Option::is_none")]
    cells: Option<Vec<&'a GridStrain>>,
    failed: Vec<usize>,
}

/// The grid's kind and its size before forming, px.
#[derive(Clone, Copy)]
enum Printed {
    Circles { d0: f64 },
    Squares { pitch: f64 },
}

impl Printed {
    fn from_args(args: &Args, scale: f64) -> Result<Printed, Failure> {
        match (args.diameter, args.pitch) {
            (Some(d), _) => {
                let d0 = d / scale;
                if !(d0.is_finite() && d0 >= 4.0) {
                    return Err(Failure::Error(format!(
                        "--diameter {d}: the circles must be at least 4 px across"
                    )));
                }
                Ok(Printed::Circles { d0 })
            }
            (None, Some(p)) => {
                let pitch = p / scale;
                if !(pitch.is_finite() && pitch >= 10.0) {
                    return Err(Failure::Error(format!(
                        "--pitch {p}: the cells must be at least 10 px apart"
                    )));
                }
                Ok(Printed::Squares { pitch })
            }
            (None, None) => Err(Failure::Error(
                "give --diameter D0 (a circle grid) or --pitch P0 (a square grid)".into(),
            )),
        }
    }
}

const CIRCLE_STRAINS: &str = "true strains: eps1 = ln(2a/D0), eps2 = ln(2b/D0), eps3 = -(eps1 + eps2); angle of the major axis in rad, counterclockwise on screen from +x";
const CELL_STRAINS: &str = "true strains from the cells' centroids: F = [dx/dcolumn, dx/drow] / P0 (central differences; one-sided where central is false), eps1, eps2 = ln of the principal stretches of F, eps3 = -(eps1 + eps2); angle of the major direction in rad, counterclockwise on screen from +x; a, b = the ellipse a circle of diameter P0 becomes";

pub fn run(args: Args) -> Result<(), Failure> {
    let scale = args.scale.unwrap_or(1.0);
    if !(scale.is_finite() && scale > 0.0) {
        return Err(Failure::Error(format!(
            "--scale {scale}: give a positive number of mm per pixel"
        )));
    }
    let printed = Printed::from_args(&args, scale)?;
    let start = crate::args::StartArgs {
        init: None,
        pick: None,
        roi: args.roi.clone(),
        grow: None,
    };
    let mut config = AllConfig {
        polarity: object_polarity(&args.polarity)?,
        roi: start.automatic()?.roi,
        ..AllConfig::default()
    };
    let image = vicurve::io::load_image(&args.image)?;
    match printed {
        Printed::Circles { .. } => config.model = Some(ShapeModel::Ellipse),
        Printed::Squares { .. } => {
            config.corners = Some(4);
            config.polarity = cell_polarity(&image, &config)?;
        }
    }
    let all = measure_all(&image, &config)?;
    let (strains, size, what) = match printed {
        Printed::Circles { d0 } => (grid_strains(&all, d0), d0, "circles"),
        Printed::Squares { pitch } => (cell_strains(&all, pitch), pitch, "cells"),
    };
    let input = args.image.display().to_string();
    let mut first: Option<String> = None;
    if let Some(p) = &args.table {
        if let Err(e) = write_table(
            p,
            &strains,
            args.scale,
            matches!(printed, Printed::Squares { .. }),
        ) {
            first.get_or_insert(e);
        }
    }
    if let Some(p) = &args.out {
        let file = GridFile {
            vicurve_version: env!("CARGO_PKG_VERSION"),
            input: &input,
            coordinates: vicurve::report::CONVENTION,
            strains: match printed {
                Printed::Circles { .. } => CIRCLE_STRAINS,
                Printed::Squares { .. } => CELL_STRAINS,
            },
            diameter_px: matches!(printed, Printed::Circles { .. }).then_some(size),
            pitch_px: matches!(printed, Printed::Squares { .. }).then_some(size),
            scale_mm_per_px: args.scale,
            config: &config,
            circles: matches!(printed, Printed::Circles { .. })
                .then(|| strains.iter().flatten().collect()),
            cells: matches!(printed, Printed::Squares { .. })
                .then(|| strains.iter().flatten().collect()),
            failed: all
                .objects
                .iter()
                .filter(|o| o.failure.is_some())
                .map(|o| o.id)
                .collect(),
        };
        if let Err(e) = write_json(p, &file) {
            first.get_or_insert(e);
        }
    }
    if let Some(p) = &args.fld {
        let measured: Vec<&GridStrain> = strains.iter().flatten().collect();
        let title = match printed {
            Printed::Circles { .. } => {
                format!("{input}: {} circles, D0 = {size:.2} px", measured.len())
            }
            Printed::Squares { .. } => {
                format!("{input}: {} cells, P0 = {size:.2} px", measured.len())
            }
        };
        if let Err(e) = crate::plot::fld::write_fld(p, &measured, &title) {
            first.get_or_insert(e);
        }
    }
    if let Some(p) = &args.map {
        let drawn = crate::output::strain_map::write_strain_map(p, &image, &all, &strains);
        if let Err(e) = drawn {
            first.get_or_insert(e);
        }
    }
    summary(&all, Kind::Silhouette);
    let with = strains.iter().flatten().count();
    let central = strains
        .iter()
        .flatten()
        .filter(|s| s.central == Some(true))
        .count();
    match printed {
        Printed::Circles { .. } => eprintln!("vicurve: strains of {with} of {} {what}", all.objects.len()),
        Printed::Squares { .. } => eprintln!(
            "vicurve: strains of {with} of {} {what} ({central} from central differences, {} one-sided at the grid's edge)",
            all.objects.len(),
            with - central
        ),
    }
    if args.table.is_none() && args.out.is_none() && args.fld.is_none() && args.map.is_none() {
        print_strains(&strains);
    }
    if let Some(e) = first {
        return Err(Failure::Error(e));
    }
    finish(&all)
}

fn print_strains(strains: &[Option<GridStrain>]) {
    println!("id  x  y  eps1 +- s  eps2 +- s  eps3 +- s  angle_deg");
    for s in strains.iter().flatten() {
        let e = strain_values(s);
        println!(
            "{} {:.3} {:.3} {:.5} {:.1e} {:.5} {:.1e} {:.5} {:.1e} {:.2}",
            s.id,
            s.centre[0],
            s.centre[1],
            e[0],
            e[1],
            e[2],
            e[3],
            e[4],
            e[5],
            s.angle.to_degrees()
        );
    }
}

/// `eps1, sigma_eps1, eps2, sigma_eps2, eps3, sigma_eps3` of `s`.
fn strain_values(s: &GridStrain) -> [f64; 6] {
    [
        s.eps1,
        s.sigma_eps1,
        s.eps2,
        s.sigma_eps2,
        s.eps3,
        s.sigma_eps3,
    ]
}

/// The strain table (`--table`), one row per measured circle.
fn write_table(
    path: &Path,
    strains: &[Option<GridStrain>],
    scale: Option<f64>,
    cells: bool,
) -> Result<(), String> {
    let err = |e: std::io::Error| format!("cannot write {}: {e}", path.display());
    let file = std::fs::File::create(path).map_err(err)?;
    let mut w = std::io::BufWriter::new(file);
    let mm = if scale.is_some() { ",x_mm,y_mm" } else { "" };
    let extra = if cells {
        ",column,row,sigma_x,sigma_y,F11,F12,F21,F22,central"
    } else {
        ""
    };
    writeln!(
        w,
        "id,x,y{mm},a,b,eps1,sigma_eps1,eps2,sigma_eps2,eps3,sigma_eps3,angle_deg,sigma_angle_deg{extra}"
    )
    .map_err(err)?;
    for s in strains.iter().flatten() {
        let mut v = vec![s.centre[0], s.centre[1]];
        if let Some(k) = scale {
            v.extend([s.centre[0] * k, s.centre[1] * k]);
        }
        v.extend([s.a, s.b]);
        v.extend(strain_values(s));
        v.extend([s.angle.to_degrees(), s.sigma_angle.to_degrees()]);
        let mut text: Vec<String> = v.into_iter().map(format_value).collect();
        if cells {
            let ij = s.cell.map_or([String::new(), String::new()], |ij| {
                ij.map(|k| k.to_string())
            });
            text.extend(ij);
            let sc = s.sigma_centre.unwrap_or([f64::NAN; 2]);
            let f = s.gradient.unwrap_or([[f64::NAN; 2]; 2]);
            let floats = [sc[0], sc[1], f[0][0], f[0][1], f[1][0], f[1][1]];
            text.extend(floats.into_iter().map(format_value));
            text.push(u8::from(s.central == Some(true)).to_string());
        }
        writeln!(w, "{},{}", s.id, text.join(",")).map_err(err)?;
    }
    w.flush().map_err(err)
}
