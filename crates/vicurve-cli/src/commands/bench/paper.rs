//! The paper's performance study (its section 7, figures 7 to 10) and a
//! harder one it did not do, as lists of cases to run and the rows they
//! give.
//!
//! The paper's test image is its own virtual profile: a 512x512 disc of
//! radius 200 rendered with the silhouette profile of half-width `R_f`,
//! sampled at pixel centres, 8-bit, noiseless
//! ([`vicurve::render::presets::paper_disc`]). It is measured in one stage
//! of half-width `R_g` from a circle 3 px too large and 2 px off centre,
//! without blur correction (the image is not a blurred step), and the error
//! is the signed normal distance of the measured samples to the true circle:
//! its mean (bias) and RMS about the mean (scatter).
//!
//! The harder study renders the same disc by exact pixel coverage (a sharp
//! edge, gray 0.2 and 0.8), blurs it, adds noise and quantises to 8 bits,
//! and measures it with the default settings.

use serde::Serialize;
use std::time::Instant;
use vicurve::curve::InitialCurve;
use vicurve::fit::{measure, Coords, Elements, FitConfig, Measurement, Stage};
use vicurve::render::{presets, render, Method, RenderSpec};
use vicurve::truth::{evaluate, Shape};
use vicurve::virtual_image::{Kind, Profile};

/// Which figure a case belongs to.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Serialize)]
#[serde(rename_all = "snake_case")]
pub enum Study {
    /// Figure 7: degree p = 1..5, `R_f = R_g = 10`.
    Degree,
    /// Figure 8: `R_f = R_g` from 6 to 30 px, p = 3.
    Width,
    /// Figures 9 and 10: `R_f = 10`, ratio `R_f / R_g` varied, p = 3.
    Ratio,
}

/// One measurement of the paper's study.
#[derive(Clone, Debug, PartialEq, Serialize)]
pub struct PaperCase {
    /// The figure.
    pub study: Study,
    /// B-spline degree.
    pub degree: usize,
    /// Half-width of the profile the image was rendered with, px.
    pub r_f: f64,
    /// Half-width of the virtual image's band, px.
    pub r_g: f64,
    /// Requested element length, px (the count is the nearest integer to
    /// the curve's length over it).
    pub element_size: f64,
    /// How the band's `(s, r)` are computed: exact projection, or the
    /// paper's levelsets on a 10 px mesh (figure 7 is run with both).
    /// In the CSV: `exact` or `levelset-<mesh>px`.
    #[serde(serialize_with = "coords_name")]
    pub coords: Coords,
}

/// `exact` or `levelset-<mesh>px`: one CSV cell.
fn coords_name<S: serde::Serializer>(c: &Coords, s: S) -> Result<S::Ok, S::Error> {
    match c {
        Coords::Exact => s.serialize_str("exact"),
        Coords::Levelset { mesh_size } => s.serialize_str(&format!("levelset-{mesh_size}px")),
    }
}

/// What a case gave.
#[derive(Clone, Debug, PartialEq, Serialize)]
pub struct PaperRow {
    /// The case.
    #[serde(flatten)]
    pub case: PaperCase,
    /// Elements used.
    pub elements: usize,
    /// "converged", "iteration limit" or "diverged: ...".
    pub outcome: String,
    /// Gauss–Newton iterations.
    pub iterations: usize,
    /// Mean signed normal distance to the true circle, px.
    pub bias: f64,
    /// RMS of that distance about its mean, px.
    pub scatter: f64,
    /// Largest absolute distance, px.
    pub max_abs: f64,
    /// Wall-clock time of the measurement (interpolation prefilter
    /// included, rendering excluded), seconds.
    pub seconds: f64,
}

/// The element lengths of the study: one decade, 10 to 100 px, in steps of
/// 10^0.1 (or three of them when `quick`).
pub fn element_sizes(quick: bool) -> Vec<f64> {
    if quick {
        return vec![10.0, 31.6, 100.0];
    }
    (0..=10)
        .map(|k| (10f64.powf(1.0 + f64::from(k) / 10.0) * 10.0).round() / 10.0)
        .collect()
}

/// Every case of figures 7 to 10, in the order they are run.
pub fn paper_cases(quick: bool) -> Vec<PaperCase> {
    let sizes = element_sizes(quick);
    let mut out = Vec::new();
    let degrees: &[usize] = if quick { &[1, 3] } else { &[1, 2, 3, 4, 5] };
    for coords in [Coords::Exact, LEVELSET] {
        for &degree in degrees {
            for &h in &sizes {
                out.push(PaperCase {
                    study: Study::Degree,
                    degree,
                    r_f: 10.0,
                    r_g: 10.0,
                    element_size: h,
                    coords,
                });
            }
        }
    }
    let widths: &[f64] = if quick {
        &[6.0, 30.0]
    } else {
        &[6.0, 8.0, 10.0, 12.0, 15.0, 20.0, 25.0, 30.0]
    };
    for &r in widths {
        for &h in &sizes {
            out.push(PaperCase {
                study: Study::Width,
                degree: 3,
                r_f: r,
                r_g: r,
                element_size: h,
                coords: Coords::Exact,
            });
        }
    }
    for &ratio in ratios(quick) {
        for &h in &sizes {
            out.push(PaperCase {
                study: Study::Ratio,
                degree: 3,
                r_f: 10.0,
                r_g: 10.0 / ratio,
                element_size: h,
                coords: Coords::Exact,
            });
        }
    }
    out
}

/// The paper's levelset coordinates as figure 7 runs them: a 10 px mesh,
/// the paper's size.
pub const LEVELSET: Coords = Coords::Levelset { mesh_size: 10.0 };

/// The ratios `R_f / R_g` of figures 9 and 10.
pub fn ratios(quick: bool) -> &'static [f64] {
    if quick {
        &[0.5, 1.0, 2.0]
    } else {
        &[0.5, 0.625, 0.8, 1.0, 1.25, 1.6, 2.0]
    }
}

/// The starting circle of every paper case: 3 px larger than the disc and
/// its centre about 1.7 px away.
pub fn paper_init() -> InitialCurve {
    InitialCurve::Circle {
        cx: 255.0,
        cy: 257.0,
        r: 203.0,
    }
}

/// Render the paper's disc for `r_f` and measure every case that uses it.
/// `done` is called after each case (for a progress bar).
pub fn run_paper(cases: &[PaperCase], mut done: impl FnMut()) -> Result<Vec<PaperRow>, String> {
    let mut rows = Vec::with_capacity(cases.len());
    let mut image: Option<(f64, vicurve::Image, Shape)> = None;
    for case in cases {
        if image.as_ref().map(|i| i.0) != Some(case.r_f) {
            let spec = presets::paper_disc(case.r_f);
            let img = render(&spec).map_err(|e| e.to_string())?;
            image = Some((case.r_f, img, spec.shape.clone()));
        }
        let Some((_, img, shape)) = image.as_ref() else {
            return Err("no image".into());
        };
        let config = FitConfig {
            degree: case.degree,
            stages: Some(vec![Stage {
                half_width: case.r_g,
                elements: Elements::Length(case.element_size),
            }]),
            blur_correction: false,
            coords: case.coords,
            ..FitConfig::default()
        };
        let started = Instant::now();
        let m = measure(img, &paper_init(), &config).map_err(|e| e.to_string())?;
        let seconds = started.elapsed().as_secs_f64();
        let e = evaluate(&m.points(), shape).map_err(|e| e.to_string())?;
        rows.push(PaperRow {
            case: case.clone(),
            elements: m.stages.last().map_or(0, |s| s.elements),
            outcome: m.outcome.to_string(),
            iterations: m.iterations(),
            bias: e.bias,
            scatter: e.scatter,
            max_abs: e.max_abs,
            seconds,
        });
        done();
    }
    Ok(rows)
}

/// One case of the harder study (noisy cases: averaged over several noise
/// seeds).
#[derive(Clone, Debug, PartialEq, Serialize)]
pub struct CoverageRow {
    /// Gaussian blur of the image, px.
    pub blur: f64,
    /// Noise, fraction of the contrast.
    pub noise: f64,
    /// Noise realisations measured (1 when noiseless).
    pub seeds: usize,
    /// How many of them converged.
    pub converged: usize,
    /// Half-width of the last band, px (of the first realisation).
    pub final_r: f64,
    /// Elements of the last stage (of the first realisation).
    pub elements: usize,
    /// The blur the pixel-edge stage fitted, px, mean over the realisations
    /// (NaN when the last stage used the paper's profile).
    pub fitted_blur: f64,
    /// Gauss–Newton iterations, all stages, mean.
    pub iterations: f64,
    /// Mean signed normal distance to the true circle, px, averaged over
    /// the realisations.
    pub bias: f64,
    /// Standard deviation of the realisations' biases, px (0 when one).
    pub bias_spread: f64,
    /// RMS about the mean, px (root mean square over the realisations).
    pub scatter: f64,
    /// Largest absolute distance over all realisations, px.
    pub max_abs: f64,
    /// Mean of the per-point uncertainty vicurve predicts, px.
    pub predicted_sigma: f64,
    /// Wall-clock time of one measurement, seconds (mean).
    pub seconds: f64,
}

/// The blurs and noise levels of the harder study.
pub fn coverage_grid(quick: bool) -> Vec<(f64, f64)> {
    let blurs: &[f64] = if quick { &[0.0, 2.0] } else { &[0.0, 1.0, 2.0] };
    let noises: &[f64] = if quick {
        &[0.0, 0.05]
    } else {
        &[0.0, 0.01, 0.02, 0.05]
    };
    blurs
        .iter()
        .flat_map(|&b| noises.iter().map(move |&n| (b, n)))
        .collect()
}

/// Noise realisations per noisy case: one seed's bias is a random draw
/// (and the same seed at another noise level is the same draw, scaled), so
/// the study averages a few and reports their spread.
pub fn coverage_seeds(noise: f64, quick: bool) -> Vec<u64> {
    if noise == 0.0 {
        vec![11]
    } else if quick {
        vec![11, 12]
    } else {
        (11..16).collect()
    }
}

/// The exact-coverage disc of the harder study.
pub fn coverage_spec(blur: f64, noise: f64, seed: u64) -> RenderSpec {
    let paper = presets::paper_disc(10.0);
    RenderSpec {
        method: Method::Coverage,
        kind: Kind::Silhouette,
        foreground: 0.8,
        background: 0.2,
        blur_sigma: blur,
        noise,
        seed,
        bits: Some(8),
        ..paper
    }
}

/// One realisation's figures.
struct Run {
    converged: bool,
    final_r: f64,
    elements: usize,
    fitted_blur: f64,
    iterations: usize,
    stats: vicurve::truth::ErrorStats,
    predicted_sigma: f64,
    seconds: f64,
}

fn run_one(spec: &RenderSpec) -> Result<Run, String> {
    let img = render(spec).map_err(|e| e.to_string())?;
    let started = Instant::now();
    let m: Measurement =
        measure(&img, &paper_init(), &FitConfig::default()).map_err(|e| e.to_string())?;
    let seconds = started.elapsed().as_secs_f64();
    let stats = evaluate(&m.points(), &spec.shape).map_err(|e| e.to_string())?;
    let last = m.stages.last();
    let sig: Vec<f64> = m
        .samples
        .iter()
        .map(|s| s.sigma)
        .filter(|s| s.is_finite())
        .collect();
    Ok(Run {
        converged: m.outcome == vicurve::fit::Outcome::Converged,
        final_r: last.map_or(f64::NAN, |s| s.half_width),
        elements: last.map_or(0, |s| s.elements),
        fitted_blur: match last.map(|s| s.profile) {
            Some(Profile::PixelEdge { blur, .. }) => blur,
            _ => f64::NAN,
        },
        iterations: m.iterations(),
        stats,
        predicted_sigma: mean(&sig),
        seconds,
    })
}

fn mean(v: &[f64]) -> f64 {
    if v.is_empty() {
        f64::NAN
    } else {
        v.iter().sum::<f64>() / v.len() as f64
    }
}

/// Run the harder study; `done` after each measurement.
pub fn run_coverage(
    grid: &[(f64, f64)],
    quick: bool,
    mut done: impl FnMut(),
) -> Result<Vec<CoverageRow>, String> {
    let mut rows = Vec::with_capacity(grid.len());
    for &(blur, noise) in grid {
        let mut runs = Vec::new();
        for seed in coverage_seeds(noise, quick) {
            runs.push(run_one(&coverage_spec(blur, noise, seed))?);
            done();
        }
        let pick = |f: fn(&Run) -> f64| runs.iter().map(f).collect::<Vec<f64>>();
        let biases = pick(|r| r.stats.bias);
        let bias = mean(&biases);
        let n = biases.len() as f64;
        let bias_spread = if biases.len() > 1 {
            (biases.iter().map(|b| (b - bias).powi(2)).sum::<f64>() / (n - 1.0)).sqrt()
        } else {
            0.0
        };
        rows.push(CoverageRow {
            blur,
            noise,
            seeds: runs.len(),
            converged: runs.iter().filter(|r| r.converged).count(),
            final_r: runs[0].final_r,
            elements: runs[0].elements,
            fitted_blur: mean(&pick(|r| r.fitted_blur)),
            iterations: mean(&pick(|r| r.iterations as f64)),
            bias,
            bias_spread,
            scatter: mean(&pick(|r| r.stats.scatter.powi(2))).sqrt(),
            max_abs: pick(|r| r.stats.max_abs).into_iter().fold(0.0, f64::max),
            predicted_sigma: mean(&pick(|r| r.predicted_sigma)),
            seconds: mean(&pick(|r| r.seconds)),
        });
    }
    Ok(rows)
}
