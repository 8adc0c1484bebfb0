//! The per-point uncertainty vicurve reports (`sigma`) against the scatter
//! actually observed over many noise draws.

use vicurve::curve::InitialCurve;
use vicurve::fit::{measure, FitConfig};
use vicurve::render::{render, RenderSpec};
use vicurve::truth::evaluate;

use crate::common::disc;

/// The disc these tests measure: 160x160, radius 55 px, blur 1 px, noise
/// `noise` from `seed`, 8 bits.
fn scene(noise: f64, seed: u64) -> RenderSpec {
    disc(160, (80.3, 79.6, 55.0), 1.0, noise, seed, Some(8))
}

/// Over 50 noise draws at 1, 2 and 5 % noise, the mean predicted sigma is
/// within 25 % of the observed RMS error due to the noise: the RMS distance
/// to the truth over all draws and points, with the noiseless run's own
/// (systematic) RMS removed in quadrature.
#[test]
fn predicted_sigma_matches_the_observed_scatter() {
    let init = InitialCurve::Circle {
        cx: 82.0,
        cy: 78.0,
        r: 57.0,
    };
    let config = FitConfig::default();
    let rms = |spec: &RenderSpec| {
        let m = measure(&render(spec).unwrap(), &init, &config).unwrap();
        let e = evaluate(&m.points(), &spec.shape).unwrap();
        let sigma = m.samples.iter().map(|s| s.sigma).sum::<f64>() / m.samples.len() as f64;
        (e.rms, sigma)
    };
    let (rms0, _) = rms(&scene(0.0, 0));
    for noise in [0.01, 0.02, 0.05] {
        let draws: Vec<(f64, f64)> = (1..=50).map(|seed| rms(&scene(noise, seed))).collect();
        let n = draws.len() as f64;
        let mean_sq = draws.iter().map(|d| d.0 * d.0).sum::<f64>() / n;
        let observed = (mean_sq - rms0 * rms0).max(0.0).sqrt();
        let predicted = draws.iter().map(|d| d.1).sum::<f64>() / n;
        let ratio = predicted / observed;
        println!(
            "noise {noise}: observed {observed:.3e} px, predicted {predicted:.3e} px, ratio {ratio:.3}"
        );
        assert!(
            (0.75..=1.25).contains(&ratio),
            "noise {noise}: ratio {ratio}"
        );
    }
}
