//! `vicurve measure`.

use crate::output::{polarity_text, write_json, write_points_csv, ResultFile};
use crate::overlay::{write_png, write_svg, Layer, Style};
use crate::Failure;
use std::path::{Path, PathBuf};
use vicurve::curve::InitialCurve;
use vicurve::fit::grow::{grow, EndReason, GrowConfig, GrowReport, Grown};
use vicurve::fit::{
    measure, parse_stages, Coords, FitConfig, LevelModel, Measurement, Outcome, Polarity,
};
use vicurve::interp::{Interpolation, Sampler};
use vicurve::virtual_image::{Kind, Profile};
use vicurve::Image;

/// Measure a curve in an image.
#[derive(clap::Args)]
pub struct Args {
    /// The image: PNG, TIFF or JPEG; 8 or 16 bits; gray or colour (converted
    /// to luminance).
    pub image: PathBuf,
    /// Starting curve: `circle:CX,CY,R`, `segment:X0,Y0,X1,Y1` or
    /// `polyline:FILE.csv` (rows `x,y`, header allowed), in pixels (x =
    /// column, y = row, pixel centres at integers). It must cross or lie near
    /// the curve to measure. Without it (silhouettes), the main silhouette is
    /// found automatically: Otsu threshold, the largest region seen whole
    /// (else the longest edge crossing the image), its traced boundary.
    #[arg(long)]
    pub init: Option<String>,
    /// Automatic start: the region containing this point `X,Y` (pixels);
    /// for a contour, the line through it, followed along its ridge.
    #[arg(long, value_name = "X,Y")]
    pub pick: Option<String>,
    /// Automatic start: search only this rectangle `X0,Y0,X1,Y1` (pixels).
    #[arg(long, value_name = "X0,Y0,X1,Y1")]
    pub roi: Option<String>,
    /// Treat a `polyline:` start as closed (last point joins the first).
    #[arg(long)]
    pub closed: bool,
    /// Grow an open start (`--init segment:...` or an open polyline) along
    /// the curve, segment by segment, until it reaches the image border,
    /// closes on itself or the edge ends; `--grow LEN` stops at LEN pixels.
    #[arg(long, value_name = "LEN", num_args = 0..=1)]
    pub grow: Option<Option<f64>>,
    /// `silhouette` (an edge between a dark and a bright region) or
    /// `contour` (a thin line).
    #[arg(long, default_value = "silhouette")]
    pub kind: Kind,
    /// Force the polarity instead of estimating it: `bright-inside`,
    /// `dark-inside`, `bright-left`, `bright-right` (open curves, as seen on
    /// screen along the curve's direction), `bright-line`, `dark-line`, or
    /// `auto`.
    #[arg(long, default_value = "auto")]
    pub polarity: String,
    /// Coarse-to-fine stages `R:N,...` (band half-width in px : number of
    /// elements, `R:Lpx` for elements of length L px, or `R:auto`). Default:
    /// 20, 10, 5 and 2 px with elements of 80, 40 and 40 px, then automatic
    /// (40 px halved down to 5 px while it pays), then a band matched to the
    /// edge's blur when it is wider.
    #[arg(long)]
    pub stages: Option<String>,
    /// Degree of the B-splines (1 to 5).
    #[arg(long, default_value_t = 3)]
    pub degree: usize,
    /// Image interpolation: `cubic` (B-spline, the default), `bilinear` or
    /// `keys` (cubic convolution); see docs/benchmarks.md for the choice.
    #[arg(long)]
    pub interp: Option<String>,
    /// Convergence tolerance on the displacement update, pixels.
    #[arg(long, default_value_t = 1e-4)]
    pub tolerance: f64,
    /// Iteration limit per stage.
    #[arg(long, default_value_t = 200)]
    pub max_iter: usize,
    /// Do not estimate the blur nor end with the pixel-edge stage (edges)
    /// or remove the shift `s^2 kappa / 2` it causes (lines): report the
    /// blurred curve instead of the true one. Use it for images that are
    /// not blurred steps or lines, such as `synth paper-disc`.
    #[arg(long)]
    pub no_blur_correction: bool,
    /// Curvilinear coordinates of the band pixels: `exact` (closest-point
    /// projection of every pixel, the default) or `levelset` (the paper's:
    /// values on a mesh of square elements, interpolated; biased outward by
    /// about mesh-size^2 / (12 x radius of curvature) px).
    #[arg(long, value_enum, default_value = "exact")]
    pub coords: CoordsArg,
    /// Element side of the levelset mesh, pixels (with `--coords levelset`).
    #[arg(long, default_value_t = 10.0, value_name = "PX")]
    pub mesh_size: f64,
    /// Gray levels of the virtual image: `varying` (dark level and contrast
    /// follow uneven light along the curve, elements of 128 px; the
    /// default), `varying:LEN` (elements of LEN px) or `global` (one pair
    /// for the whole curve, the paper's).
    #[arg(long, default_value = "varying", value_name = "MODEL")]
    pub levels: String,
    /// Corners: arc lengths (pixels) along the initial curve, from its
    /// start, where the measured curve may have a corner or a tangent break
    /// (repeated knots; see docs/breaks.md), e.g. `--break 120.5,240`.
    #[arg(long = "break", value_name = "S1,S2", value_delimiter = ',')]
    pub breaks: Vec<f64>,
    /// Fit a shape to the measured curve: `circle`, `ellipse`, `line` or
    /// `polygon:N` (its parameters with uncertainties are printed and
    /// written as `model` in `--out`; `--points` samples the shape), or
    /// `bspline-curve` (a free B-spline curve, its control points the
    /// unknowns; `--dxf` and `--svg-curve` then export it).
    #[arg(long, value_name = "MODEL")]
    pub model: Option<vicurve::model::ShapeModel>,
    #[command(flatten)]
    pub outputs: Outputs,
    /// Write diagnostics into DIR (created if missing): the band unwrapped
    /// on the measured curve's (s, r) grid (band.png), the residual
    /// image - virtual image (residual.png), the robust weights
    /// (weights.png), the convergence of each stage (convergence.png) and
    /// diagnostics.json; see docs/diagnostics.md.
    #[arg(long, value_name = "DIR")]
    pub diagnostics: Option<PathBuf>,
    /// `--dxf`, `--svg-curve` (see `cmd_export`).
    #[command(flatten)]
    pub cad: crate::cmd_export::CurveFiles,
}

/// `--coords`.
#[derive(Clone, Copy, Debug, PartialEq, Eq, clap::ValueEnum)]
pub enum CoordsArg {
    /// Exact projection of every band pixel.
    Exact,
    /// The paper's finite-element levelsets.
    Levelset,
}

/// The optional output files of a measurement.
#[derive(clap::Args, Default)]
pub struct Outputs {
    /// Write the result (B-spline, history, outcome, configuration) as JSON.
    #[arg(long)]
    pub out: Option<PathBuf>,
    /// Write the samples as CSV with columns s,x,y,nx,ny,sigma,weight.
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
    fn any(&self) -> bool {
        self.out.is_some() || self.points.is_some() || self.svg.is_some() || self.png.is_some()
    }
}

pub fn run(args: Args) -> Result<(), Failure> {
    let config = build_config(&args)?;
    args.cad.check(config.degree)?;
    let start = start_config(&args)?;
    let explicit = match &args.init {
        Some(spec) => Some(parse_init(spec, args.closed)?),
        None => None,
    };
    let image = vicurve::io::load_image(&args.image)?;
    let init = match explicit {
        Some(init) => init,
        None => {
            if args.kind == Kind::Contour {
                let found =
                    vicurve::start::ridge::find_line(&image, &start).map_err(|e| match e {
                        // Its reasons already say what to try.
                        vicurve::Error::NoLine { .. } => e.to_string(),
                        _ => format!("{e}; or give a starting curve with --init"),
                    })?;
                eprintln!(
                    "vicurve: automatic start: {} line followed from the picked point over {:.0} px (scale {} px), {} curve",
                    if found.bright { "bright" } else { "dark" },
                    found.length,
                    found.scale,
                    if found.closed { "closed" } else { "open" }
                );
                found.curve
            } else {
                let found = vicurve::start::find_silhouette(&image, &start).map_err(|e| {
                format!("{e}; give a starting curve with --init, or point at the object with --pick X,Y")
            })?;
                eprintln!(
                "vicurve: automatic start: {} {} region of {} pixels (threshold {:.4}), {} curve",
                if found.bright { "bright" } else { "dark" },
                if start.pick.is_some() {
                    "picked"
                } else {
                    "main"
                },
                found.region_pixels,
                found.threshold,
                if found.closed { "closed" } else { "open" }
            );
                found.curve
            }
        }
    };
    let (m, grown) = match args.grow {
        Some(length) => {
            let g = grow_from(&image, &init, &config, length)?;
            (g.measurement, Some(g.report))
        }
        None => (measure(&image, &init, &config)?, None),
    };
    let path_text = args.image.display().to_string();
    // Written whatever the outcome (a diverged fit is what they are for);
    // a failure does not prevent the other outputs.
    let diagnostics = match &args.diagnostics {
        Some(dir) => crate::diagnostics::write(dir, &path_text, &image, &init, &config, &m),
        None => Ok(()),
    };
    if args.model == Some(vicurve::model::ShapeModel::BsplineCurve) {
        // `--dxf` and `--svg-curve` then write the fitted curve.
        let (o, p) = (&args.outputs, path_text.as_str());
        let written =
            crate::model_output::run_bspline_curve(o, &args.cad, p, &image, &init, &config, &m);
        return written.and(diagnostics.map_err(Failure::Error));
    }
    let size = Some((image.width(), image.height()));
    let cad = args.cad.write(&m.curve_data(), &path_text, size);
    if let Some(model) = args.model {
        let (o, p) = (&args.outputs, path_text.as_str());
        let written = crate::model_output::run(model, o, p, &image, &init, &config, &m);
        return written.and(cad).and(diagnostics.map_err(Failure::Error));
    }
    let written = (path_text.as_str(), &image, &init, &config, &m);
    write_outputs_grown(&args.outputs, written, grown.as_ref())?;
    cad?;
    diagnostics?;
    if !args.outputs.any() && !args.cad.any() {
        print_summary(&config, &m);
    }
    finish(&m)
}

/// Map the outcome to the exit status: diverged is a failure, an iteration
/// limit a warning.
pub fn finish(m: &Measurement) -> Result<(), Failure> {
    match m.outcome {
        Outcome::Converged => Ok(()),
        Outcome::IterationLimit => {
            eprintln!(
                "vicurve: warning: the iteration limit was reached before convergence; raise --max-iter or start closer to the curve"
            );
            Ok(())
        }
        Outcome::Diverged { divergence } => Err(Failure::Diverged(format!(
            "the fit diverged: {divergence}; start from a curve closer to the edge, or use a narrower band (--stages)"
        ))),
    }
}

/// `--pick` and `--roi`, which only make sense without `--init`.
fn start_config(args: &Args) -> Result<vicurve::start::StartConfig, Failure> {
    if args.init.is_some() && (args.pick.is_some() || args.roi.is_some()) {
        return Err(Failure::Error(
            "--pick and --roi choose an automatic start: drop --init, or drop them".into(),
        ));
    }
    let numbers = |what: &str, text: &str, n: usize| -> Result<Vec<f64>, Failure> {
        let v: Result<Vec<f64>, _> = text.split(',').map(|t| t.trim().parse::<f64>()).collect();
        match v {
            Ok(v) if v.len() == n && v.iter().all(|x| x.is_finite()) => Ok(v),
            _ => Err(Failure::Error(format!(
                "malformed {what} '{text}': expected {n} numbers separated by commas"
            ))),
        }
    };
    let pick = match &args.pick {
        Some(t) => {
            let v = numbers("--pick", t, 2)?;
            Some([v[0], v[1]])
        }
        None => None,
    };
    let roi = match &args.roi {
        Some(t) => {
            let v = numbers("--roi", t, 4)?;
            Some([v[0], v[1], v[2], v[3]])
        }
        None => None,
    };
    Ok(vicurve::start::StartConfig { pick, roi })
}

/// `--grow [LEN]`: grow the open start segment by segment, then measure.
fn grow_from(
    image: &Image,
    init: &InitialCurve,
    config: &FitConfig,
    length: Option<f64>,
) -> Result<Grown, Failure> {
    if init.is_closed() {
        return Err(Failure::Error(
            "--grow extends the two ends of an open start: give --init segment:X0,Y0,X1,Y1 or an open polyline".into(),
        ));
    }
    let sampler = Sampler::new(image, config.interpolation);
    let settings = GrowConfig {
        max_length: length,
        ..GrowConfig::default()
    };
    let g = grow(&sampler, init.to_curve()?, config, &settings)?;
    let kept = g.report.steps.iter().filter(|s| s.kept).count();
    let why = |e: EndReason| match e {
        EndReason::Border => "the image border",
        EndReason::EdgeEnds => "the end of the edge",
        EndReason::Length => "the length asked",
        EndReason::Closed => "closure",
        EndReason::MetUnclosed => "the other end (the loop did not converge)",
        EndReason::StepLimit => "the step limit",
        EndReason::StartFailed => "a start that did not converge",
    };
    let [a, b] = g.report.ends;
    if a == EndReason::Closed {
        eprintln!("vicurve: grown in {kept} step(s) into a closed curve");
    } else {
        eprintln!(
            "vicurve: grown in {kept} step(s); the start stopped at {}, the end at {}",
            why(a),
            why(b)
        );
    }
    Ok(g)
}

/// Parse `--init`; polylines are read from their file.
pub fn parse_init(spec: &str, closed: bool) -> Result<InitialCurve, Failure> {
    if let Some(file) = spec.strip_prefix("polyline:") {
        let points = vicurve::io::read_polyline_csv(Path::new(file))?;
        return Ok(InitialCurve::Polyline { points, closed });
    }
    if closed {
        return Err(Failure::Error(
            "--closed applies to polyline: starts only".into(),
        ));
    }
    Ok(spec.parse::<InitialCurve>()?)
}

fn build_config(args: &Args) -> Result<FitConfig, Failure> {
    let mut config = FitConfig {
        kind: args.kind,
        polarity: parse_polarity(&args.polarity)?,
        degree: args.degree,
        tolerance: args.tolerance,
        max_iterations: args.max_iter,
        blur_correction: !args.no_blur_correction,
        coords: match args.coords {
            CoordsArg::Exact => Coords::Exact,
            CoordsArg::Levelset => Coords::Levelset {
                mesh_size: args.mesh_size,
            },
        },
        ..FitConfig::default()
    };
    if let Some(s) = &args.stages {
        config.stages = Some(parse_stages(s)?);
    }
    if let Some(i) = &args.interp {
        config.interpolation = parse_interp(i)?;
    }
    config.levels = parse_levels(&args.levels)?;
    config.breaks = args.breaks.clone();
    config.validate()?;
    Ok(config)
}

/// `--levels global|varying|varying:LEN`.
pub fn parse_levels(s: &str) -> Result<LevelModel, Failure> {
    s.parse::<LevelModel>()
        .map_err(|e| Failure::Error(format!("--levels: {e}")))
}

pub fn parse_interp(s: &str) -> Result<Interpolation, Failure> {
    match s {
        "cubic" | "cubic-bspline" => Ok(Interpolation::CubicBSpline),
        "bilinear" | "linear" => Ok(Interpolation::Bilinear),
        "keys" => Ok(Interpolation::Keys),
        _ => Err(Failure::Error(format!(
            "unknown interpolation '{s}' (expected cubic, bilinear or keys)"
        ))),
    }
}

pub fn parse_polarity(s: &str) -> Result<Polarity, Failure> {
    match s {
        "auto" => Ok(Polarity::Auto),
        "bright-inside" | "bright-left" | "bright-line" | "positive" => Ok(Polarity::Positive),
        "dark-inside" | "bright-right" | "dark-line" | "negative" => Ok(Polarity::Negative),
        _ => Err(Failure::Error(format!(
            "unknown polarity '{s}' (expected auto, bright-inside, dark-inside, bright-left, bright-right, bright-line or dark-line)"
        ))),
    }
}

/// Write every requested output; they are independent, so one failing does
/// not prevent the others (the first error is reported).
pub fn write_outputs(
    args: &Outputs,
    path_text: &str,
    image: &Image,
    init: &InitialCurve,
    config: &FitConfig,
    m: &Measurement,
) -> Result<(), Failure> {
    write_outputs_grown(args, (path_text, image, init, config, m), None)
}

/// What a measurement's outputs are made from: the input's name, the
/// image, the start, the configuration and the measurement.
type Written<'a> = (
    &'a str,
    &'a Image,
    &'a InitialCurve,
    &'a FitConfig,
    &'a Measurement,
);

/// [`write_outputs`], with the record of a grown start (`--grow`).
fn write_outputs_grown(
    args: &Outputs,
    (path_text, image, init, config, m): Written,
    grown: Option<&GrowReport>,
) -> Result<(), Failure> {
    let mut first_error: Option<String> = None;
    let mut note = |r: Result<(), String>| {
        if let Err(e) = r {
            first_error.get_or_insert(e);
        }
    };
    if let Some(p) = &args.out {
        let mut record =
            ResultFile::new(path_text, (image.width(), image.height()), init, config, m);
        record.grow = grown;
        note(write_json(p, &record));
    }
    if let Some(p) = &args.points {
        note(write_points_csv(p, m));
    }
    if args.svg.is_some() || args.png.is_some() {
        let layers = overlay_layers(init, config, m)?;
        if let Some(p) = &args.svg {
            note(write_svg(p, image, &layers));
        }
        if let Some(p) = &args.png {
            note(write_png(p, image, &layers, args.png_scale));
        }
    }
    match first_error {
        Some(e) => Err(Failure::Error(e)),
        None => Ok(()),
    }
}

/// The initial curve (dashed blue), the final band's borders (thin yellow)
/// and the measured curve (red).
pub fn overlay_layers(
    init: &InitialCurve,
    config: &FitConfig,
    m: &Measurement,
) -> Result<Vec<Layer>, Failure> {
    let closed = m.curve.is_closed();
    let init_pts = init.dense_points(1.0)?;
    let r = m.stages.last().map_or(0.0, |s| s.half_width);
    let offset = |k: f64| -> Vec<[f64; 2]> {
        m.samples
            .iter()
            .map(|s| [s.x + k * r * s.nx, s.y + k * r * s.ny])
            .collect()
    };
    let style = |color: [u8; 4], width: f32, dash: Option<[f32; 2]>| Style { color, width, dash };
    let mut layers = vec![Layer {
        label: "initial curve".into(),
        points: init_pts,
        closed: init.is_closed(),
        style: style([40, 120, 255, 255], 1.0, Some([4.0, 3.0])),
    }];
    if r > 0.0 {
        for (k, label) in [
            (-1.0, "band border (inner side)"),
            (1.0, "band border (outer side)"),
        ] {
            layers.push(Layer {
                label: format!("{label}, R = {r} px"),
                points: offset(k),
                closed,
                style: style([255, 210, 0, 200], 0.5, None),
            });
        }
    }
    layers.push(Layer {
        label: format!("measured {} ({})", config.kind, m.outcome),
        points: m.points(),
        closed,
        style: style([255, 40, 40, 255], 1.0, None),
    });
    Ok(layers)
}

pub fn print_summary(config: &FitConfig, m: &Measurement) {
    let c = m.stages.last().map_or(f64::NAN, |s| s.c);
    println!("outcome:     {}", m.outcome);
    println!(
        "iterations:  {} over {} stage(s)",
        m.iterations(),
        m.stages.len()
    );
    println!("residual:    {:.3e} (RMS gray level)", m.residual_rms());
    println!(
        "polarity:    {}",
        polarity_text(config.kind, m.curve.is_closed(), c)
    );
    println!("length:      {:.4} px", m.length());
    if let Some(a) = m.area() {
        println!("area:        {:.4} px^2", a);
    }
    print_closed_measures(m);
    let last_profile = m.stages.last().map(|s| s.profile);
    if let Some(Profile::PixelEdge { blur }) = last_profile {
        println!(
            "edge blur:   {blur:.3} px optical (fitted; the last stage's virtual edge is a pixel through it, so the true boundary is measured)"
        );
    } else if let Some(e) = m.edge_spread {
        println!(
            "edge blur:   {:.3} px ({}; fit quality {:.3})",
            e.sigma,
            if m.blur_corrected {
                "its curvature shift removed"
            } else {
                "not corrected: the edge is not a clean blurred step"
            },
            e.fit_quality
        );
    }
    let sig: Vec<f64> = m
        .samples
        .iter()
        .map(|s| s.sigma)
        .filter(|v| v.is_finite())
        .collect();
    if !sig.is_empty() {
        let mean = sig.iter().sum::<f64>() / sig.len() as f64;
        println!(
            "sigma:       {:.2e} px (mean noise uncertainty of the position)",
            mean
        );
    }
}

/// The best-fit circle and ellipse of a closed curve (or why there are
/// none), for the summary.
fn print_closed_measures(m: &Measurement) {
    if !m.curve.is_closed() {
        return;
    }
    match vicurve::derived::closed_measures(m) {
        Ok(d) => {
            let (c, e) = (d.circle, d.ellipse);
            println!(
                "centroid:    ({:.4}, {:.4}) px; equivalent diameter {:.4} px",
                d.centroid[0], d.centroid[1], d.equivalent_diameter
            );
            println!(
                "circle:      centre ({:.4} +- {:.1e}, {:.4} +- {:.1e}), radius {:.4} +- {:.1e} px (rms distance {:.2e})",
                c.cx, c.sigma_cx, c.cy, c.sigma_cy, c.r, c.sigma_r, c.rms
            );
            println!(
                "ellipse:     centre ({:.4}, {:.4}), semi-axes {:.4} +- {:.1e} and {:.4} +- {:.1e} px, angle {:.3} deg +- {:.1e} (counterclockwise on screen from +x; rms distance {:.2e})",
                e.cx, e.cy, e.a, e.sigma_a, e.b, e.sigma_b, e.angle.to_degrees(), e.sigma_angle.to_degrees(), e.rms
            );
        }
        Err(err) => println!("circle:      none ({err})"),
    }
}

#[cfg(test)]
mod levels_tests {
    use super::parse_levels;
    use vicurve::fit::LevelModel;

    #[test]
    fn levels_argument() {
        assert_eq!(parse_levels("global").ok(), Some(LevelModel::Global));
        assert_eq!(parse_levels("varying").ok(), Some(LevelModel::default()));
        assert_eq!(
            parse_levels("varying:200").ok(),
            Some(LevelModel::Varying {
                element_length: 200.0
            })
        );
        for bad in ["", "vary", "varying:", "varying:x", "global:3"] {
            assert!(parse_levels(bad).is_err(), "{bad}");
        }
    }
}
