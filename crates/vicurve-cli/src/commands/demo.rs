//! `vicurve demo`: the whole job on a synthetic star, end to end.

use crate::args::Outputs;
use crate::failure::{finish, Failure};
use crate::output::measurement::{print_summary, write_outputs, Measured};
use std::path::PathBuf;
use std::time::Instant;
use vicurve::curve::InitialCurve;
use vicurve::fit::{measure, FitConfig};
use vicurve::render::Truth;
use vicurve::render::{presets, render};
use vicurve::truth::{evaluate, Shape};

/// Synthesise a star, measure it from a circle, report the accuracy.
#[derive(clap::Args)]
pub struct Args {
    /// Folder for the image, truth, result, points and overlays.
    #[arg(long, default_value = "vicurve-demo")]
    pub out_dir: PathBuf,
}

pub fn run(args: Args) -> Result<(), Failure> {
    let dir = &args.out_dir;
    std::fs::create_dir_all(dir).map_err(|e| format!("cannot create {}: {e}", dir.display()))?;
    let spec = presets::star_1024();
    let Shape::Star { cx, cy, .. } = spec.shape else {
        return Err(Failure::Error("the demo preset is not a star".into()));
    };
    println!("1. rendering a 1024x1024 star r = 300 (1 + 0.2 cos 5θ), exact pixel coverage, blur 1 px, noise 1 %, 8-bit");
    let image = render(&spec)?;
    let image_path = dir.join("star.png");
    vicurve::io::save_image(&image_path, &image, 8)?;
    let truth = Truth::from_spec(&spec);
    truth.save(&dir.join("truth.json"))?;
    // Measure what was saved, as a user would.
    let image = vicurve::io::load_image(&image_path)?;
    let init = InitialCurve::Circle {
        cx: cx + 10.0,
        cy,
        r: 300.0,
    };
    println!(
        "2. measuring from a circle of radius 300 whose centre is 10 px off, default settings"
    );
    let config = FitConfig::default();
    let started = Instant::now();
    let m = measure(&image, &init, &config)?;
    let seconds = started.elapsed().as_secs_f64();
    print_summary(&config, &m);
    println!("time:        {:.1} ms", seconds * 1e3);
    let stats = evaluate(&m.points(), &truth.shape)?;
    println!(
        "3. accuracy against the exact star ({} points):",
        stats.count
    );
    println!("   bias    {:+.2e} px", stats.bias);
    println!("   scatter {:.2e} px", stats.scatter);
    println!("   max     {:.2e} px", stats.max_abs);
    let outputs = Outputs {
        out: Some(dir.join("result.json")),
        points: Some(dir.join("points.csv")),
        svg: Some(dir.join("overlay.svg")),
        png: Some(dir.join("overlay.png")),
        png_scale: 1,
    };
    let input = image_path.display().to_string();
    let measured = Measured {
        input: &input,
        image: &image,
        init: &init,
        config: &config,
        m: &m,
    };
    write_outputs(&outputs, measured, None)?;
    println!(
        "4. wrote star.png, truth.json, result.json, points.csv, overlay.svg and overlay.png in {}",
        dir.display()
    );
    finish(&m)
}
