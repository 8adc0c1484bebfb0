//! `measure --model`: a parametric shape (circle, ellipse, line, polygon)
//! fitted after the B-spline measurement that starts it, printed, written
//! as the `model` object of the result file, and sampled for `--points`
//! and the overlays.

use super::cad;
use super::measurement::{print_summary, write_outputs, Measured};
use super::{write_json, ResultFile};
use crate::args::{CurveFiles, Outputs};
use crate::failure::{finish, Failure};
use serde::Serialize;
use vicurve::fit::Outcome;
use vicurve::model::bspline_curve::{measure_bspline_curve, BsplineCurveConfig};
use vicurve::model::{measure_model, ModelConfig, ModelFit, ModelProfile, ShapeModel};

/// A model whose residual RMS exceeds the B-spline curve's by this factor
/// is reported as a likely misfit.
const MISFIT: f64 = 2.0;

/// The result file of a measurement with a model (a shape or the free
/// B-spline curve): the B-spline record as `measure --out` writes it (its
/// `samples` those of the model), then `model`.
#[derive(Serialize)]
struct WithModel<'a, M> {
    #[serde(flatten)]
    result: ResultFile<'a>,
    model: &'a M,
}

/// Write the outputs of a measurement shown through a model's samples
/// (`--points`, the overlays; `--out` with the `model` object), and print
/// the measurement's summary when nothing is written. Returns the overlay
/// and points writing's result, then the record's, for the caller to
/// report after its own printing.
fn write_with_model<M: Serialize>(
    outputs: &Outputs,
    w: Measured,
    samples: Vec<vicurve::fit::Sample>,
    model: &M,
) -> (Result<(), Failure>, Result<(), Failure>) {
    let mut shown = w.m.clone();
    shown.samples = samples;
    let others = Outputs {
        out: None,
        ..outputs.clone()
    };
    let written = write_outputs(&others, Measured { m: &shown, ..w }, None);
    let json = match &outputs.out {
        Some(p) => {
            let size = (w.image.width(), w.image.height());
            let record = WithModel {
                result: ResultFile::new(w.input, size, w.init, w.config, &shown),
                model,
            };
            write_json(p, &record).map_err(Failure::Error)
        }
        None => Ok(()),
    };
    if !outputs.any() {
        print_summary(w.config, w.m);
    }
    (written, json)
}

/// The exit status of a model fit that ended as `outcome` (`what` names
/// it): a warning at the iteration limit, an error (3) when it diverged.
fn model_outcome(what: &str, outcome: Outcome) -> Result<(), Failure> {
    match outcome {
        Outcome::Converged => Ok(()),
        Outcome::IterationLimit => {
            eprintln!(
                "vicurve: warning: the {what} fit reached its iteration limit before converging"
            );
            Ok(())
        }
        Outcome::Diverged { divergence } => Err(Failure::Diverged(format!(
            "the {what} fit diverged: {divergence}"
        ))),
    }
}

/// Fit `model` on the measurement `m`, write the outputs (`--points`, the
/// overlays: the fitted shape's samples; `--out`: the record with `model`)
/// and print the parameters. Exit status: an error when the model cannot be
/// fitted (1), a diverged B-spline or model fit (3).
pub fn run(model: ShapeModel, outputs: &Outputs, w: Measured) -> Result<(), Failure> {
    let (m, config) = (w.m, w.config);
    let fit = measure_model(w.image, m, config, model, &ModelConfig::default())?;
    let samples = fit.samples(config.sample_spacing)?;
    let (written, json) = write_with_model(outputs, w, samples, &fit);
    print_model(&fit);
    // A shape that does not describe the edge leaves much more residual
    // than the free B-spline curve.
    let curve_rms = m.residual_rms();
    if fit.residual_rms > MISFIT * curve_rms {
        eprintln!(
            "vicurve: warning: the {model} leaves a residual {:.1} times the measured curve's ({:.2e} against {:.2e}): it may not describe this edge",
            fit.residual_rms / curve_rms,
            fit.residual_rms,
            curve_rms
        );
    }
    written?;
    json?;
    finish(m)?;
    model_outcome(&model.to_string(), fit.outcome)
}

/// `--model bspline-curve`: the free B-spline curve fitted on the
/// measurement `m`; `--points` and the overlays show its samples, `--out`
/// adds it as `model`, `--dxf` / `--svg-curve` export it. Exit status as
/// [`run`].
pub fn run_bspline_curve(
    outputs: &Outputs,
    files: &CurveFiles,
    w: Measured,
) -> Result<(), Failure> {
    let (m, config) = (w.m, w.config);
    let fit = measure_bspline_curve(w.image, m, config, &BsplineCurveConfig::default())?;
    let size = (w.image.width(), w.image.height());
    let cad_written = cad::write(files, &fit.curve, w.input, Some(size));
    let samples = fit.samples(config.sample_spacing)?;
    let (written, json) = write_with_model(outputs, w, samples, &fit);
    let sigmas: Vec<f64> = fit.control_points.iter().map(|p| p.sigma_n).collect();
    let max_sigma = sigmas.iter().copied().fold(0.0, f64::max);
    let rms_sigma = (sigmas.iter().map(|s| s * s).sum::<f64>() / sigmas.len().max(1) as f64).sqrt();
    println!(
        "model:       bspline-curve ({}, {} iterations, {} band pixels)",
        fit.outcome, fit.iterations, fit.band_pixels
    );
    println!(
        "  curve:    degree {}, {} control points {:.2} px apart, {}",
        fit.curve.degree,
        fit.control_points.len(),
        fit.control_spacing,
        if fit.curve.closed { "closed" } else { "open" }
    );
    println!(
        "  sigma:    {rms_sigma:.2e} px RMS, {max_sigma:.2e} px at most (control points, along the normal)"
    );
    println!(
        "  residual: {:.3e} (RMS gray level); gray levels a = {:.4}, c = {:+.4}",
        fit.residual_rms, fit.a, fit.c
    );
    written?;
    json?;
    cad_written?;
    finish(m)?;
    model_outcome("bspline-curve", fit.outcome)
}

/// The model's parameters, one a line, then how it was fitted.
fn print_model(fit: &ModelFit) {
    println!(
        "model:       {} ({}, {} iterations, {} band pixels)",
        fit.model, fit.outcome, fit.iterations, fit.band_pixels
    );
    for p in &fit.parameters {
        let degrees = if p.unit == "rad" {
            format!(
                " ({:.5} +- {:.5} deg)",
                p.value.to_degrees(),
                p.sigma.to_degrees()
            )
        } else {
            String::new()
        };
        println!(
            "  {:<9} = {:.6} +- {:.6} {}{degrees}",
            p.name, p.value, p.sigma, p.unit
        );
    }
    let profile = match fit.profile {
        ModelProfile::PixelEdge { blur } if fit.exact_pixels == fit.band_pixels => {
            format!("exact pixel coverage (sharp edge; fitted blur {blur:.3} px)")
        }
        ModelProfile::PixelEdge { blur } => format!("pixel edge through a blur of {blur:.3} px"),
        ModelProfile::Paper {
            kind, half_width, ..
        } => {
            format!("{kind} profile over +-{half_width} px")
        }
    };
    println!("  profile:  {profile}");
    if fit.excluded_pixels > 0 {
        println!(
            "  corners:  {} pixels near the vertices left out",
            fit.excluded_pixels
        );
    }
    println!(
        "  residual: {:.3e} (RMS gray level); gray levels a = {:.4}, c = {:+.4}",
        fit.residual_rms, fit.a, fit.c
    );
}
