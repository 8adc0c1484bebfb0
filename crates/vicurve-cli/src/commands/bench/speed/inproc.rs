//! The parts of one measurement timed in this process, by calling the
//! library as `vicurve measure` does: decoding the file, the sampler's
//! prefilter, the fit (its stages' own `seconds`, and the rest of
//! `measure_from`), a separate call of the blur estimate on the measured
//! curve, and writing the result files.

use super::cases::SpeedCase;
use crate::args::Outputs;
use crate::output::measurement::{write_outputs, Measured};
use std::path::Path;
use std::time::Instant;
use vicurve::fit::{measure_from, parse_stages, FitConfig, Measurement};
use vicurve::interp::Sampler;

/// Band half-width of the fit's blur estimate, pixels (`fit::blur`'s
/// first search band).
const EDGE_SPREAD_BAND: f64 = 8.0;

/// The timings of one in-process measurement, seconds.
#[derive(Clone, Debug)]
pub struct Parts {
    /// `io::load_image` of the PNG.
    pub decode: f64,
    /// `Sampler::new` (the cubic B-spline prefilter of the whole image).
    pub prefilter: f64,
    /// `InitialCurve::to_curve` and `measure_from`: the whole fit.
    pub fit: f64,
    /// Each stage's `StageReport::seconds`, in order.
    pub stages: Vec<f64>,
    /// `psf::edge_spread` on the measured curve, band 8 px: what the fit's
    /// blur estimate costs (it runs after the last explicit stage, outside
    /// the stages' times).
    pub blur_estimate: f64,
    /// Writing the JSON result and the CSV samples.
    pub output: f64,
}

impl Parts {
    /// The fit's time outside its stages: the blur estimate, the samples
    /// with their sigma, the measured B-spline, the checks.
    pub fn fit_outside_stages(&self) -> f64 {
        self.fit - self.stages.iter().sum::<f64>()
    }
}

/// The fit configuration `vicurve measure` uses for `case`.
pub fn config(case: &SpeedCase) -> Result<FitConfig, String> {
    let mut config = FitConfig::default();
    if let Some(s) = case.stages {
        config.stages = Some(parse_stages(s).map_err(|e| e.to_string())?);
    }
    config.validate().map_err(|e| e.to_string())?;
    Ok(config)
}

/// Measure `case` from its image file `image`, writing into `dir`
/// (`NAME.inproc.json`, `NAME.inproc.csv`); the timings and the
/// measurement.
pub fn run(case: &SpeedCase, image: &Path, dir: &Path) -> Result<(Parts, Measurement), String> {
    let config = config(case)?;
    let init = case.initial_curve()?;
    let t0 = Instant::now();
    let img = vicurve::io::load_image(image).map_err(|e| e.to_string())?;
    let t1 = Instant::now();
    let sampler = Sampler::new(&img, config.interpolation);
    let t2 = Instant::now();
    let start = init.to_curve().map_err(|e| e.to_string())?;
    let m = measure_from(&sampler, start, &config).map_err(|e| e.to_string())?;
    let t3 = Instant::now();
    let outputs = Outputs {
        out: Some(dir.join(format!("{}.inproc.json", case.name))),
        points: Some(dir.join(format!("{}.inproc.csv", case.name))),
        ..Outputs::default()
    };
    let input = image.display().to_string();
    let measured = Measured {
        input: &input,
        image: &img,
        init: &init,
        config: &config,
        m: &m,
    };
    write_outputs(&outputs, measured, None).map_err(|e| e.message())?;
    let t4 = Instant::now();
    let b0 = Instant::now();
    let _spread = vicurve::psf::edge_spread(&sampler, &m.curve, EDGE_SPREAD_BAND);
    let blur_estimate = b0.elapsed().as_secs_f64();
    let secs = |a: Instant, b: Instant| (b - a).as_secs_f64();
    let parts = Parts {
        decode: secs(t0, t1),
        prefilter: secs(t1, t2),
        fit: secs(t2, t3),
        stages: m.stages.iter().map(|s| s.seconds).collect(),
        blur_estimate,
        output: secs(t3, t4),
    };
    Ok((parts, m))
}
