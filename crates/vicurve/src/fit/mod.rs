//! The measurement: multi-scale Gauss–Newton correlation of the virtual
//! image with the physical one (method, sections 5 and 6).
//!
//! [`measure`] runs the stages of the schedule in turn. In each stage the
//! curve is `x(s) = x0(s) + U(s) n(s)` with `U` a B-spline of the stage's
//! elements on the reference `x0`; the reference is replaced by the current
//! curve (new band, new matrix, `U = 0`) when a stage ends and whenever
//! `max |U|` exceeds a fraction of `R` within a stage, so that a start far
//! from the edge (a circle crossing a star) converges.
//!
//! ```no_run
//! use vicurve::{fit::{measure, FitConfig}, curve::InitialCurve, io::load_image};
//! let image = load_image("part.png".as_ref())?;
//! let init = InitialCurve::Circle { cx: 320.0, cy: 240.0, r: 100.0 };
//! let m = measure(&image, &init, &FitConfig::default())?;
//! println!("{}: length {:.4} px", m.outcome, m.length());
//! # Ok::<(), vicurve::Error>(())
//! ```

mod config;
mod correlation;
mod result;

pub use config::{default_stages, parse_stages, Elements, FitConfig, Polarity, Stage};
pub use result::{Divergence, Measurement, Outcome, Sample, StageReport};

use crate::band::Band;
use crate::curve::{InitialCurve, SplineCurve};
use crate::error::{Error, Result};
use crate::image::Image;
use crate::interp::Sampler;
use crate::spline::{Basis, MAX_DEGREE};
use correlation::{Correlation, StepFailure};
use std::f64::consts::TAU;
use std::time::Instant;

/// Spacing of the samples used to rebuild a reference curve, pixels.
const REFERENCE_SAMPLE_STEP: f64 = 0.5;
/// Control-point spacing of reference and output curves, pixels.
const CURVE_SPACING: f64 = 2.0;
/// Re-references allowed within one stage before it is declared stuck.
const MAX_REREFERENCES: usize = 100;

/// Measure the curve in `image` starting from `init`.
///
/// Errors are reserved for inputs that cannot be measured at all: an
/// invalid configuration, an initial curve or first band outside the image,
/// a band with too few pixels. A fit that starts but fails later is
/// reported as [`Outcome::Diverged`] with the last good curve.
pub fn measure(image: &Image, init: &InitialCurve, config: &FitConfig) -> Result<Measurement> {
    config.validate()?;
    let sampler = Sampler::new(image, config.interpolation);
    measure_from(&sampler, init.to_curve()?, config)
}

/// [`measure`] with a prepared image sampler and reference curve (for
/// sequences and benchmarks: the sampler's prefilter is done once).
pub fn measure_from(sampler: &Sampler, reference: SplineCurve, config: &FitConfig) -> Result<Measurement> {
    config.validate()?;
    if sampler.kind() != config.interpolation {
        return Err(Error::invalid(
            "interpolation",
            "the sampler was prepared for another interpolation than the configuration's",
        ));
    }
    let closed = reference.is_closed();
    let (width, height) = (sampler.width(), sampler.height());
    let (stages, auto) = match &config.stages {
        Some(s) => (s.clone(), false),
        None => (default_stages(), true),
    };
    let p = config.degree;
    let min_el = if closed { p + 1 } else { 1 };

    let mut current = reference;
    let mut reports = Vec::new();
    let mut skipped = Vec::new();
    let mut last: Option<Final> = None;
    let mut outcome = Outcome::Converged;

    'stages: for (k, stage) in stages.iter().enumerate() {
        let is_last = k + 1 == stages.len();
        let r = stage.half_width;
        if auto && !is_last {
            let length = current.arc_length();
            let size = if closed { length / TAU } else { length };
            if r > 0.5 * size {
                skipped.push(format!("R = {r} px: too wide for a curve of length {length:.1} px"));
                continue;
            }
        }
        let started = Instant::now();
        let mut iterations = 0;
        let mut rereferences = 0;
        let mut step = None;
        loop {
            let length = current.param_length();
            let basis = Basis::new(p, stage.element_count(length, min_el), length, closed)?;
            let first_band = last.is_none() && iterations == 0;
            let band = match Band::build(&current, &basis, r, config.kind, width, height) {
                Ok(b) => b,
                Err(e @ (Error::BandOutsideImage { .. } | Error::CurveOutsideImage { .. })) => {
                    if first_band && auto && !is_last {
                        skipped.push(format!("R = {r} px: {e}"));
                        continue 'stages;
                    }
                    if first_band {
                        return Err(e);
                    }
                    let (x, y) = match e {
                        Error::BandOutsideImage { x, y, .. } | Error::CurveOutsideImage { x, y, .. } => (x, y),
                        _ => (f64::NAN, f64::NAN),
                    };
                    outcome = Outcome::Diverged {
                        divergence: Divergence::LeftImage { x, y },
                    };
                    reports.push(report(stage, &basis, 0, iterations, rereferences, step, started, outcome));
                    break 'stages;
                }
                Err(e) => return Err(e),
            };
            let band_pixels = band.len();
            let mut corr = match Correlation::new(band, basis.clone()) {
                Ok(c) => c,
                Err(e) if first_band => return Err(e),
                Err(_) => {
                    outcome = Outcome::Diverged {
                        divergence: Divergence::Degenerate,
                    };
                    reports.push(report(stage, &basis, band_pixels, iterations, rereferences, step, started, outcome));
                    break 'stages;
                }
            };
            let mut lambda = vec![0.0; corr.n_unknowns()];
            let cap = config.max_step_fraction * r;
            let stage_end = loop {
                match corr.iterate(&lambda, sampler, config.polarity) {
                    Err(failure) => {
                        break Some(Outcome::Diverged {
                            divergence: match failure {
                                StepFailure::LeftImage([x, y]) => Divergence::LeftImage { x, y },
                                StepFailure::NoContrast => Divergence::NoContrast,
                                StepFailure::NonFinite => Divergence::NonFinite,
                            },
                        })
                    }
                    Ok(s) => {
                        iterations += 1;
                        if std::env::var("VIC_DEBUG").is_ok() { eprintln!("it {iterations} step {:.3e} a {:.4} c {:.4} res {:.3e}", s.max_step, s.a, s.c, s.residual_rms); }
                        step = Some(s);
                        let scale = if s.max_step > cap { cap / s.max_step } else { 1.0 };
                        for (l, d) in lambda.iter_mut().zip(&corr.delta) {
                            *l += scale * d;
                        }
                        if s.max_step < config.tolerance {
                            break Some(Outcome::Converged);
                        }
                        if iterations >= config.max_iterations || rereferences >= MAX_REREFERENCES {
                            break Some(Outcome::IterationLimit);
                        }
                        let max_u = lambda.iter().fold(0.0f64, |m, l| m.max(l.abs()));
                        if max_u > config.rereference_fraction * r {
                            break None;
                        }
                    }
                }
            };
            match stage_end {
                None => {
                    current = displaced(&current, &corr.basis, &lambda)?;
                    rereferences += 1;
                }
                Some(o @ Outcome::Diverged { .. }) => {
                    outcome = o;
                    reports.push(report(stage, &corr.basis, band_pixels, iterations, rereferences, step, started, o));
                    break 'stages;
                }
                Some(o) => {
                    outcome = o;
                    let next = displaced(&current, &corr.basis, &lambda)?;
                    reports.push(report(stage, &corr.basis, band_pixels, iterations, rereferences, step, started, o));
                    last = Some(Final {
                        reference: std::mem::replace(&mut current, next),
                        c: step.map_or(1.0, |s| s.c),
                        corr,
                        lambda,
                    });
                    break;
                }
            }
        }
    }
    let fin = match last {
        Some(f) => f,
        None => {
            // Not even one stage completed: report the start as the result.
            return Ok(Measurement {
                outcome,
                curve_fit_error: 0.0,
                samples: plain_samples(&current, config.sample_spacing),
                curve: current,
                stages: reports,
                skipped,
            });
        }
    };
    let (curve, curve_fit_error, samples) = fin.samples(config.sample_spacing, p.max(3))?;
    Ok(Measurement {
        outcome,
        curve,
        curve_fit_error,
        samples,
        stages: reports,
        skipped,
    })
}

/// The last completed stage, kept to produce the output samples and their
/// uncertainty.
struct Final {
    reference: SplineCurve,
    corr: Correlation,
    lambda: Vec<f64>,
    c: f64,
}

impl Final {
    /// Dense samples of `x0 + U n`, the B-spline fitted to them and its
    /// largest deviation from them, and the output samples with `sigma`.
    fn samples(&self, spacing: f64, degree: usize) -> Result<(SplineCurve, f64, Vec<Sample>)> {
        let fine_step = (0.25f64).min(spacing);
        let l = self.reference.param_length();
        let closed = self.reference.is_closed();
        let count = (l / fine_step).ceil() as usize;
        let params = self.reference.sample_params(if closed { count } else { count + 1 });
        let mut scratch = vec![0.0; self.corr.n_unknowns()];
        let pts: Vec<[f64; 2]> = params
            .iter()
            .map(|&u| displaced_point(&self.reference, &self.corr.basis, &self.lambda, u))
            .collect();
        let curve = SplineCurve::fit(&pts, closed, degree, CURVE_SPACING)?;
        // Chord-length parameters, as the fit used them.
        let mut s = Vec::with_capacity(pts.len());
        let mut acc = 0.0;
        let mut max_chord: f64 = 0.0;
        for (i, q) in pts.iter().enumerate() {
            if i > 0 {
                let d = crate::curve::dist(pts[i - 1], *q);
                max_chord = max_chord.max(d);
                acc += d;
            }
            s.push(acc);
        }
        let every = ((spacing / max_chord.max(1e-9)).floor() as usize).max(1);
        let mut fit_error: f64 = 0.0;
        let mut out = Vec::with_capacity(pts.len() / every + 2);
        for (i, q) in pts.iter().enumerate() {
            let on_curve = curve.point(s[i]);
            fit_error = fit_error.max(crate::curve::dist(on_curve, *q));
            let keep = i % every == 0 || (!closed && i + 1 == pts.len());
            if keep {
                let f = curve.frame(s[i]);
                out.push(Sample {
                    s: s[i],
                    x: q[0],
                    y: q[1],
                    nx: f.normal[0],
                    ny: f.normal[1],
                    sigma: self.corr.position_sigma(params[i], self.c, &mut scratch),
                });
            }
        }
        Ok((curve, fit_error, out))
    }
}

/// `x0(u) + U(u) n(u)`.
fn displaced_point(reference: &SplineCurve, basis: &Basis, lambda: &[f64], u: f64) -> [f64; 2] {
    let f = reference.frame(u);
    let mut v = [0.0; MAX_DEGREE + 1];
    let first = basis.eval(u, &mut v);
    let disp: f64 = (0..=basis.degree()).map(|k| lambda[basis.index(first, k)] * v[k]).sum();
    [f.point[0] + disp * f.normal[0], f.point[1] + disp * f.normal[1]]
}

/// The new reference curve `x0 + U n`.
fn displaced(reference: &SplineCurve, basis: &Basis, lambda: &[f64]) -> Result<SplineCurve> {
    let l = reference.param_length();
    let count = (l / REFERENCE_SAMPLE_STEP).ceil() as usize;
    let params = reference.sample_params(if reference.is_closed() { count } else { count + 1 });
    let pts: Vec<[f64; 2]> = params
        .iter()
        .map(|&u| displaced_point(reference, basis, lambda, u))
        .collect();
    SplineCurve::fit(&pts, reference.is_closed(), 3, CURVE_SPACING)
}

/// Samples of a curve without a fit behind them (sigma unknown: NaN).
fn plain_samples(curve: &SplineCurve, spacing: f64) -> Vec<Sample> {
    let l = curve.param_length();
    let count = (l / spacing).ceil() as usize;
    let params = curve.sample_params(if curve.is_closed() { count } else { count + 1 });
    params
        .iter()
        .map(|&u| {
            let f = curve.frame(u);
            Sample {
                s: u,
                x: f.point[0],
                y: f.point[1],
                nx: f.normal[0],
                ny: f.normal[1],
                sigma: f64::NAN,
            }
        })
        .collect()
}

#[allow(clippy::too_many_arguments)]
fn report(
    stage: &Stage,
    basis: &Basis,
    band_pixels: usize,
    iterations: usize,
    rereferences: usize,
    step: Option<correlation::Step>,
    started: Instant,
    outcome: Outcome,
) -> StageReport {
    StageReport {
        half_width: stage.half_width,
        elements: basis.n_elements(),
        iterations,
        rereferences,
        band_pixels,
        residual_rms: step.map_or(f64::NAN, |s| s.residual_rms),
        a: step.map_or(f64::NAN, |s| s.a),
        c: step.map_or(f64::NAN, |s| s.c),
        seconds: started.elapsed().as_secs_f64(),
        outcome,
    }
}
