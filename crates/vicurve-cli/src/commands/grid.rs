//! `vicurve grid IMAGE --diameter D0`: circle-grid strain analysis. Every
//! printed circle is measured as an ellipse (`measure --all --model
//! ellipse`); its axes give the major and minor true strains, their
//! direction and the thickness strain, each with its uncertainty.

use super::measure_all::{finish, summary};
use crate::args::all::object_polarity;
use crate::failure::Failure;
use crate::output::objects::format_value;
use crate::output::write_json;
use serde::Serialize;
use std::io::Write;
use std::path::{Path, PathBuf};
use vicurve::model::ShapeModel;
use vicurve::objects::{grid_strains, measure_all, AllConfig, GridStrain};
use vicurve::virtual_image::Kind;

/// Measure the strains of a circle grid.
#[derive(clap::Args)]
pub struct Args {
    /// The image of the deformed grid.
    pub image: PathBuf,
    /// Diameter of the printed circles before forming: px, or mm with
    /// --scale.
    #[arg(long, value_name = "D0")]
    pub diameter: f64,
    /// Image scale, mm per pixel: --diameter is then in mm and the table
    /// also gives the centres in mm.
    #[arg(long, value_name = "MM_PER_PX")]
    pub scale: Option<f64>,
    /// The circles' phase: `auto` (the minority phase), `bright` or `dark`.
    #[arg(long, default_value = "auto")]
    pub polarity: String,
    /// Search only this rectangle `X0,Y0,X1,Y1` (pixels).
    #[arg(long, value_name = "X0,Y0,X1,Y1")]
    pub roi: Option<String>,
    /// Write one row per circle as CSV: id, centre (px, and mm with
    /// --scale), semi-axes, eps1, eps2, eps3 = -(eps1 + eps2), the major
    /// axis angle (degrees, counterclockwise on screen from +x), each with
    /// its sigma.
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
    diameter_px: f64,
    scale_mm_per_px: Option<f64>,
    config: &'a AllConfig,
    circles: Vec<&'a GridStrain>,
    failed: Vec<usize>,
}

pub fn run(args: Args) -> Result<(), Failure> {
    let scale = args.scale.unwrap_or(1.0);
    if !(scale.is_finite() && scale > 0.0) {
        return Err(Failure::Error(format!(
            "--scale {scale}: give a positive number of mm per pixel"
        )));
    }
    let d0 = args.diameter / scale;
    if !(d0.is_finite() && d0 >= 4.0) {
        return Err(Failure::Error(format!(
            "--diameter {}: the circles must be at least 4 px across",
            args.diameter
        )));
    }
    let start = crate::args::StartArgs {
        init: None,
        pick: None,
        roi: args.roi.clone(),
        grow: None,
    };
    let config = AllConfig {
        polarity: object_polarity(&args.polarity)?,
        roi: start.automatic()?.roi,
        model: Some(ShapeModel::Ellipse),
        ..AllConfig::default()
    };
    let image = vicurve::io::load_image(&args.image)?;
    let all = measure_all(&image, &config)?;
    let strains = grid_strains(&all, d0);
    let input = args.image.display().to_string();
    let mut first: Option<String> = None;
    if let Some(p) = &args.table {
        if let Err(e) = write_table(p, &strains, args.scale) {
            first.get_or_insert(e);
        }
    }
    if let Some(p) = &args.out {
        let file = GridFile {
            vicurve_version: env!("CARGO_PKG_VERSION"),
            input: &input,
            coordinates: vicurve::report::CONVENTION,
            strains: "true strains: eps1 = ln(2a/D0), eps2 = ln(2b/D0), eps3 = -(eps1 + eps2); angle of the major axis in rad, counterclockwise on screen from +x",
            diameter_px: d0,
            scale_mm_per_px: args.scale,
            config: &config,
            circles: strains.iter().flatten().collect(),
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
        let title = format!("{input}: {} circles, D0 = {d0:.2} px", measured.len());
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
) -> Result<(), String> {
    let err = |e: std::io::Error| format!("cannot write {}: {e}", path.display());
    let file = std::fs::File::create(path).map_err(err)?;
    let mut w = std::io::BufWriter::new(file);
    let mm = if scale.is_some() { ",x_mm,y_mm" } else { "" };
    writeln!(
        w,
        "id,x,y{mm},a,b,eps1,sigma_eps1,eps2,sigma_eps2,eps3,sigma_eps3,angle_deg,sigma_angle_deg"
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
        let text: Vec<String> = v.into_iter().map(format_value).collect();
        writeln!(w, "{},{}", s.id, text.join(",")).map_err(err)?;
    }
    w.flush().map_err(err)
}
