//! Honest `sigma` (issue 18, section 3, and its failure 2.2): no
//! oscillation the blur cannot resolve, the model's misfit flagged and
//! covered, and the reported `sigma` the size of the observed scatter.

use vicurve::curve::InitialCurve;
use vicurve::fit::{measure, Elements, FitConfig, Measurement, Outcome, Stage};
use vicurve::render::{render, RenderSpec};
use vicurve::truth::Shape;

use crate::common::spec;

/// The 512x512 scenes: centre (255.8, 255.3), 8 bits, seed 7.
fn scene(shape: Shape, blur: f64, noise: f64) -> RenderSpec {
    spec(shape, (512, 512), blur, noise, 7, Some(8))
}

fn star(amplitude: f64) -> Shape {
    Shape::Star {
        cx: 255.8,
        cy: 255.3,
        r0: 140.0,
        amplitude,
        lobes: 5,
        phase: 0.0,
    }
}

/// The measurement of `spec` from a circle of radius `r` near its centre,
/// and the signed normal errors of its samples against the truth.
fn measured(spec: &RenderSpec, r: f64, config: &FitConfig) -> (Measurement, Vec<f64>) {
    let init = InitialCurve::Circle {
        cx: 256.8,
        cy: 254.3,
        r,
    };
    let m = measure(&render(spec).unwrap(), &init, config).unwrap();
    let e = m
        .samples
        .iter()
        .map(|s| spec.shape.signed_distance(s.x, s.y))
        .collect();
    (m, e)
}

/// Mean and RMS about it.
fn mean_scatter(e: &[f64]) -> (f64, f64) {
    let n = e.len() as f64;
    let mean = e.iter().sum::<f64>() / n;
    let var = e.iter().map(|v| (v - mean).powi(2)).sum::<f64>() / n;
    (mean, var.sqrt())
}

fn rms(v: impl Iterator<Item = f64>) -> f64 {
    let (sum, n) = v.fold((0.0, 0.0), |(s, n), x| (s + x * x, n + 1.0));
    (sum / n).sqrt()
}

/// The largest departure of the (closed curve's) errors from their moving
/// average over 21 samples (about 20 px), pixels.
fn local_oscillation(e: &[f64]) -> f64 {
    let n = e.len();
    (0..n)
        .map(|i| {
            let avg = (0..21).map(|j| e[(i + n + j - 10) % n]).sum::<f64>() / 21.0;
            (e[i] - avg).abs()
        })
        .fold(0.0, f64::max)
}

/// Failure 2.2: a 5-lobed star (r0 = 140, amplitude 10 %) blurred by 4 px,
/// noiseless, 8 bits, from a circle. The pixel-edge stage refined to 5 px
/// elements, and its settles fed the curve's oscillations back through the
/// blur's curvature term (gain `v k^2 / 2`, 2.6 at 5 px): +-0.65 px over 10
/// px of arc, scatter 0.63 px, with sigma 1.9e-3 (measured before). Its
/// elements are now no shorter than the blur resolves: scatter 2.8e-3 px,
/// max 9.2e-3 px, local oscillation 6.5e-3 px (measured).
#[test]
fn blurred_star_does_not_oscillate() {
    let spec = scene(star(0.1), 4.0, 0.0);
    let (m, e) = measured(&spec, 140.0, &FitConfig::default());
    let (mean, scatter) = mean_scatter(&e);
    let max = e.iter().fold(0.0f64, |a, v| a.max((v - mean).abs()));
    let osc = local_oscillation(&e);
    println!(
        "blurred star: bias {mean:+.2e} scatter {scatter:.2e} max {max:.2e} oscillation {osc:.2e}"
    );
    assert_eq!(m.outcome, Outcome::Converged);
    assert!(max <= 8.0 * scatter, "max {max} vs scatter {scatter}");
    assert!(scatter <= 1e-2, "scatter {scatter}");
    assert!(osc <= 2e-2, "local oscillation {osc}");
}

/// A star whose bays the blur's floor on the elements could not follow:
/// 6 lobes of amplitude 20 % (bays of 14 px radius of curvature), blurred
/// by 4 px, noiseless, 16 bits. On elements of 9 px (the blur's floor) one
/// fit left the bays a little off, and the settles made that a wiggle of
/// the elements' wavelength: scatter 1.1e-2 px, max 6.2e-2 px (measured
/// before). The pixel-edge stage now refines below the floor where the
/// curvature allows it (`fit/blur.rs`, `shortest_pixel_edge`), its rule
/// counting the settles' gains. Not asserted: its sigma, which still
/// falls short of that scatter (docs/conformance.md).
#[test]
fn a_blurred_star_follows_its_bays() {
    let shape = Shape::Star {
        cx: 255.1366,
        cy: 255.8278,
        r0: 140.0,
        amplitude: 0.2,
        lobes: 6,
        phase: 3.8562,
    };
    let spec = spec(shape, (512, 512), 4.0, 0.0, 7, Some(16));
    let (m, e) = measured(&spec, 140.0, &FitConfig::default());
    let (mean, scatter) = mean_scatter(&e);
    let max = e.iter().fold(0.0f64, |a, v| a.max((v - mean).abs()));
    println!("6-lobed star a0.2, blur 4: bias {mean:+.2e} scatter {scatter:.2e} max {max:.2e}");
    assert_eq!(m.outcome, Outcome::Converged);
    assert!(mean.abs() <= 1e-3, "bias {mean}");
    assert!(scatter <= 4e-3, "scatter {scatter}");
    assert!(max <= 2e-2, "max {max}");
    assert!(max <= 8.0 * scatter, "max {max} vs scatter {scatter}");
}

/// The oscillation check looks at the last settle's displacement, not at
/// the curve: a 6-lobed star (amplitude 10 %) blurred by 4 px, noiseless,
/// has detail at its 9 px elements' scale in its own outline, which a
/// check of the curve's second differences took for an oscillation (385
/// samples flagged, sigma 8.3e-3 px against a scatter of 3.6e-3, measured
/// before; from a circle at the star's radius, nothing flagged). Sigma is
/// the size of the scatter, no sample's more than doubled by its model
/// term. (Samples are flagged where the representation term of detail
/// as fine as the elements exceeds the noise term: 156 of 983 since that
/// term counts such detail, `fit/representation.rs`.)
#[test]
fn a_blurred_star_outline_is_not_an_oscillation() {
    let shape = Shape::Star {
        cx: 255.7668,
        cy: 255.8717,
        r0: 140.0,
        amplitude: 0.1,
        lobes: 6,
        phase: 3.4339,
    };
    let spec = scene(shape, 4.0, 0.0);
    let (m, e) = measured(&spec, 154.0, &FitConfig::default());
    let (_, scatter) = mean_scatter(&e);
    let sigma = rms(m.samples.iter().map(|s| s.sigma));
    let summary = m.misfit_summary();
    println!(
        "6-lobed star, blur 4: scatter {scatter:.2e} sigma {sigma:.2e} flagged {}",
        summary.flagged
    );
    assert_eq!(m.outcome, Outcome::Converged);
    assert!(summary.worst_inflation <= 2.0, "{summary:?}");
    assert!(
        (0.7..=1.4).contains(&(scatter / sigma)),
        "ratio {}",
        scatter / sigma
    );
}

/// A model that misfits: the 5-lobed star of amplitude 20 % (lobes of
/// radius of curvature ~25 px), 1 % noise, blur 1, measured with 40 px
/// elements only (no refinement, no pixel-edge stage), which cannot follow
/// its lobes. The samples there are flagged, and their `sigma` covers the
/// error observed there, which the noise alone does not.
#[test]
fn misfit_is_flagged_and_covered() {
    let spec = scene(star(0.2), 1.0, 0.01);
    let stages = [(10.0, 40.0), (2.0, 40.0)]
        .iter()
        .map(|&(half_width, h)| Stage {
            half_width,
            elements: Elements::Length(h),
        })
        .collect();
    let config = FitConfig {
        stages: Some(stages),
        ..FitConfig::default()
    };
    let (m, e) = measured(&spec, 140.0, &config);
    let (mean, _) = mean_scatter(&e);
    let flagged: Vec<usize> = (0..e.len()).filter(|&i| m.samples[i].misfit).collect();
    let summary = m.misfit_summary();
    let observed = rms(flagged.iter().map(|&i| e[i] - mean));
    let sigma = rms(flagged.iter().map(|&i| m.samples[i].sigma));
    let noise = rms(flagged.iter().map(|&i| m.samples[i].sigma_noise));
    println!(
        "misfit: {} flagged ({:.3}), worst inflation {:.1}; there observed {observed:.2e}, sigma {sigma:.2e}, noise only {noise:.2e}",
        summary.flagged, summary.fraction, summary.worst_inflation
    );
    assert_eq!(m.outcome, Outcome::Converged);
    assert!(summary.fraction >= 0.05, "{summary:?}");
    assert!(
        observed <= 2.0 * sigma,
        "observed {observed} vs sigma {sigma}"
    );
    assert!(
        observed >= 3.0 * noise,
        "observed {observed} vs noise {noise}"
    );
    for s in &m.samples {
        assert!(s.sigma >= s.sigma_noise);
    }
}

/// A misfit of pixels, as the paper's far start leaves with its stages: a
/// 6-lobed star (r0 = 300, amplitude 30 %, blur 1.5, 1 % noise) from a
/// circle at 85 % of its radius, with R = 20, 10, 5 and 40 px elements,
/// which leave its lobes up to 5.7 px off. The residuals' linearised
/// requests said about half of that (sigma 0.52 px against a scatter of
/// 0.82; 118 of the 728 samples more than 0.5 px off lay beyond 3 sigma,
/// measured before); the level crossing along the normal finds the edge
/// itself: sigma is the size of the scatter, and few such samples lie
/// beyond 3 sigma.
#[test]
fn a_misfit_of_pixels_is_covered() {
    let (m, spec) =
        super::star_with_long_elements((511.8, 512.3), 300.0, 1024, (511.8, 512.3), 40.0);
    let e: Vec<f64> = m
        .samples
        .iter()
        .map(|s| spec.shape.signed_distance(s.x, s.y))
        .collect();
    let (mean, scatter) = mean_scatter(&e);
    let sigma = rms(m.samples.iter().map(|s| s.sigma));
    let off: Vec<usize> = (0..e.len())
        .filter(|&i| (e[i] - mean).abs() > 0.5)
        .collect();
    let beyond = off
        .iter()
        .filter(|&&i| (e[i] - mean).abs() > 3.0 * m.samples[i].sigma)
        .count();
    println!(
        "misfit of pixels: scatter {scatter:.3} sigma {sigma:.3}; {} samples more than 0.5 px off, {beyond} of them beyond 3 sigma",
        off.len()
    );
    assert!(off.len() >= 200, "the elements should not follow the lobes");
    assert!(
        (0.7..=1.4).contains(&(scatter / sigma)),
        "ratio {}",
        scatter / sigma
    );
    assert!(
        beyond as f64 <= 0.05 * off.len() as f64,
        "{beyond} of {}",
        off.len()
    );
}

/// The reported `sigma` (RMS over the samples) against the observed
/// scatter (RMS of the errors about their mean) on exact-coverage discs and
/// stars, noise 1 and 5 %, blur 1 and 4 px, default settings: the ratio
/// within [0.7, 1.4] (measured: 0.78 to 1.14).
#[test]
fn sigma_is_the_size_of_the_scatter() {
    let disc = Shape::Circle {
        cx: 255.8,
        cy: 255.3,
        r: 150.0,
    };
    for (name, shape, r) in [("disc", disc, 151.5), ("star", star(0.1), 141.5)] {
        for blur in [1.0, 4.0] {
            for noise in [0.01, 0.05] {
                let spec = scene(shape.clone(), blur, noise);
                let (m, e) = measured(&spec, r, &FitConfig::default());
                let (_, scatter) = mean_scatter(&e);
                let sigma = rms(m.samples.iter().map(|s| s.sigma));
                let ratio = scatter / sigma;
                println!("{name}, blur {blur}, noise {noise}: scatter {scatter:.2e} sigma {sigma:.2e} ratio {ratio:.2}");
                assert_eq!(m.outcome, Outcome::Converged);
                assert!(
                    (0.7..=1.4).contains(&ratio),
                    "{name}, blur {blur}, noise {noise}: ratio {ratio}"
                );
            }
        }
    }
}

/// An 8-bit image without any other noise still has the rounding to its
/// 255 steps, noise of variance `q^2 / 12` on an edge's pixels that the
/// noise estimate (differences of residuals sorted by `r`, equal for
/// pixels of equal level) misses. A noiseless 8-bit disc and star at
/// blurs of 1 and 2 px: the ratio within [0.7, 1.4].
#[test]
fn sigma_covers_the_rounding_of_eight_bit_levels() {
    let disc = Shape::Circle {
        cx: 255.8,
        cy: 255.3,
        r: 150.0,
    };
    for (name, shape, r) in [("disc", disc, 151.5), ("star", star(0.1), 141.5)] {
        for blur in [1.0, 2.0] {
            let spec = scene(shape.clone(), blur, 0.0);
            let (m, e) = measured(&spec, r, &FitConfig::default());
            let (_, scatter) = mean_scatter(&e);
            let sigma = rms(m.samples.iter().map(|s| s.sigma));
            let ratio = scatter / sigma;
            println!(
                "{name}, blur {blur}: scatter {scatter:.2e} sigma {sigma:.2e} ratio {ratio:.2}"
            );
            assert_eq!(m.outcome, Outcome::Converged);
            assert!(
                (0.7..=1.4).contains(&ratio),
                "{name}, blur {blur}: ratio {ratio}"
            );
        }
    }
}

/// A pentagon (circumradius 160 px) blurred by 2 px, noiseless, 16 bits,
/// from a circle 10 % off its centre (its corners found, as the sweep's
/// `polygon` cases). Its errors gather at the corners, where the wedge
/// model leaves them (6.0e-4 px RMS within 3 px of a vertex); along the
/// sides, farther than 30 px from a vertex, they are 1.35e-5 px. `sigma`
/// kept the unlowered noise estimate everywhere: 2.0e-4 px on the sides,
/// 15 times their errors (measured before). Only the corners' reach keeps
/// it now: 3.5e-5 px on the sides, and near the vertices (5.0e-4 px) it
/// still covers their errors (measured).
#[test]
fn a_polygon_s_sides_are_not_charged_for_its_corners() {
    let (cx, cy, r) = (255.8, 255.3, 160.0);
    let angle = 0.4;
    let shape = Shape::Polygon {
        cx,
        cy,
        r,
        sides: 5,
        angle,
    };
    let spec = spec(shape, (512, 512), 2.0, 0.0, 7, Some(16));
    let init = InitialCurve::Circle {
        cx: cx + 12.0,
        cy: cy - 9.6,
        r: 0.9 * r,
    };
    let m = measure(&render(&spec).unwrap(), &init, &FitConfig::default()).unwrap();
    assert_eq!(m.outcome, Outcome::Converged);
    let vertices: Vec<[f64; 2]> = (0..5)
        .map(|k| {
            let t = angle + std::f64::consts::TAU * k as f64 / 5.0;
            [cx + r * t.cos(), cy - r * t.sin()]
        })
        .collect();
    let from_vertex = |x: f64, y: f64| {
        vertices
            .iter()
            .map(|v| (x - v[0]).hypot(y - v[1]))
            .fold(f64::INFINITY, f64::min)
    };
    let (mut side, mut near) = (Vec::new(), Vec::new());
    for s in &m.samples {
        let e = spec.shape.signed_distance(s.x, s.y);
        match from_vertex(s.x, s.y) {
            d if d > 30.0 => side.push((e, s.sigma)),
            d if d < 3.0 => near.push((e, s.sigma)),
            _ => {}
        }
    }
    let error = |v: &[(f64, f64)]| rms(v.iter().map(|p| p.0));
    let sigma = |v: &[(f64, f64)]| rms(v.iter().map(|p| p.1));
    println!(
        "pentagon, blur 2: {} corners found; sides: error {:.2e} sigma {:.2e}; near the vertices: error {:.2e} sigma {:.2e}",
        m.curve.corners().len(),
        error(&side),
        sigma(&side),
        error(&near),
        sigma(&near)
    );
    assert!(!side.is_empty() && !near.is_empty());
    assert!(
        sigma(&side) < 5.0 * error(&side),
        "sides: sigma {:.2e} for errors of {:.2e}",
        sigma(&side),
        error(&side)
    );
    assert!(
        sigma(&near) > 0.7 * error(&near),
        "near the vertices: sigma {:.2e} for errors of {:.2e}",
        sigma(&near),
        error(&near)
    );
}

/// Where the edge bends faster than the elements follow, `sigma` says so
/// (`fit/representation.rs`): a 6-lobed star (amplitude 20 %, bays of 14
/// px radius) blurred by 2 px, noiseless, 16 bits, whose elements of 5 px
/// leave 3e-3 px in its bays (its curvature's second derivative 2e-3
/// px^-3 there). The noise term alone said 1.9e-4 px against a scatter
/// of 7.0e-4 (ratio 3.6), and the bays' samples erred by up to 36 times
/// their own sigma (measured before, this test on 9e63007). The ratio
/// within [0.7, 1.5], and no sample beyond 4 of its sigma.
#[test]
fn a_star_s_bays_are_charged_for_what_the_elements_cannot_follow() {
    let shape = Shape::Star {
        cx: 255.4137,
        cy: 255.6921,
        r0: 140.0,
        amplitude: 0.2,
        lobes: 6,
        phase: 1.2345,
    };
    let spec = spec(shape, (512, 512), 2.0, 0.0, 7, Some(16));
    let (m, e) = measured(&spec, 140.0, &FitConfig::default());
    let (mean, scatter) = mean_scatter(&e);
    let sigma = rms(m.samples.iter().map(|s| s.sigma));
    let worst = m
        .samples
        .iter()
        .zip(&e)
        .map(|(s, v)| (v - mean).abs() / s.sigma)
        .fold(0.0f64, f64::max);
    let ratio = scatter / sigma;
    println!(
        "6-lobed star a0.2, blur 2, 16 bits: scatter {scatter:.2e} sigma {sigma:.2e} ratio {ratio:.2}, worst {worst:.1} sigma"
    );
    assert_eq!(m.outcome, Outcome::Converged);
    assert!((0.7..=1.5).contains(&ratio), "ratio {ratio}");
    assert!(worst <= 4.0, "a sample {worst} of its sigma off");
}
