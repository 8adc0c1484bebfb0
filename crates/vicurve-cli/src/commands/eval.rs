//! `vicurve eval`: accuracy of measured points against a truth file; a
//! scene's truth (`synth scene|grid`) scores a `measure --all` result
//! object by object ([`super::eval_objects`]).

use super::eval_objects;
use crate::failure::Failure;
use crate::output::write_json;
use serde::Serialize;
use std::path::PathBuf;
use vicurve::render::scene::Scene;
use vicurve::render::Truth;
use vicurve::truth::{evaluate, ErrorStats};

/// Compare measured points with the exact curve.
#[derive(clap::Args)]
pub struct Args {
    /// Points CSV with columns x and y (as written by `measure --points`);
    /// with an `object` column (`measure --all --points`) against a scene.
    pub points: PathBuf,
    /// Truth file (as written by `synth --truth`; a scene's from `synth
    /// scene|grid`: each object matched to the shape it fits best).
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

/// The JSON of a scene's evaluation.
#[derive(Serialize)]
struct SceneEvalFile<'a> {
    points: String,
    truth: String,
    convention: &'static str,
    #[serde(flatten)]
    score: &'a eval_objects::SceneScore,
}

const CONVENTION: &str = "signed distance from each point to the true curve along its normal, pixels; positive outside closed curves, towards +y for open sine curves";

pub fn run(args: Args) -> Result<(), Failure> {
    if let Some(scene) = scene_truth(&args.truth) {
        return run_scene(&args, &scene);
    }
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
                convention: CONVENTION,
                stats: &stats,
            },
        )?;
    }
    Ok(())
}

/// The scene in `path`, when it is a scene's truth file.
fn scene_truth(path: &std::path::Path) -> Option<Scene> {
    let text = std::fs::read_to_string(path).ok()?;
    serde_json::from_str(&text).ok()
}

/// Every object of `args.points` against `scene`.
fn run_scene(args: &Args, scene: &Scene) -> Result<(), Failure> {
    let objects = eval_objects::read_object_points(&args.points)?;
    let score = eval_objects::score(&objects, scene);
    eval_objects::print(&score);
    if let Some(p) = &args.json {
        write_json(
            p,
            &SceneEvalFile {
                points: args.points.display().to_string(),
                truth: args.truth.display().to_string(),
                convention: CONVENTION,
                score: &score,
            },
        )?;
    }
    Ok(())
}
