//! Robust weights: clutter crossing the band does not drag the curve.

use vicurve::curve::InitialCurve;
use vicurve::fit::{measure, FitConfig, Outcome};
use vicurve::render::{render, Method, RenderSpec};
use vicurve::truth::{evaluate, Shape};
use vicurve::virtual_image::Kind;
use vicurve::Image;

/// Distances (px) of a point to the two dark lines drawn over the disc.
fn line_distances(x: f64, y: f64) -> [f64; 2] {
    [
        (0.3 * x - y + 40.0).abs() / 1.09f64.sqrt(),
        (x - 0.1 * y - 200.0).abs() / 1.01f64.sqrt(),
    ]
}

/// A disc (blur 1, 1 % noise) crossed by two dark lines 3 px wide, each
/// cutting its edge twice: every point stays within 0.05 px of the truth,
/// the scatter away from the crossings within twice the clean image's, and
/// the samples at the crossings report their down-weighting.
#[test]
fn two_dark_lines_crossing_a_disc() {
    let shape = Shape::Circle {
        cx: 150.3,
        cy: 149.6,
        r: 90.0,
    };
    let spec = RenderSpec {
        width: 300,
        height: 300,
        shape: shape.clone(),
        kind: Kind::Silhouette,
        method: Method::Coverage,
        foreground: 0.8,
        background: 0.2,
        blur_sigma: 1.0,
        noise: 0.01,
        seed: 3,
        bits: None,
        ..RenderSpec::default()
    };
    let clean = render(&spec).unwrap();
    let quantise = |v: f64| (v * 255.0).round() / 255.0;
    let crossed = Image::from_fn(300, 300, |x, y| {
        let d = line_distances(x as f64, y as f64);
        let k = d
            .iter()
            .map(|d| (1.5 - d).clamp(0.0, 1.0))
            .fold(0.0, f64::max);
        quantise(clean.get(x, y) * (1.0 - k) + 0.05 * k)
    });
    let clean8 = Image::from_fn(300, 300, |x, y| quantise(clean.get(x, y)));
    let init = InitialCurve::Circle {
        cx: 152.0,
        cy: 148.0,
        r: 93.0,
    };
    let far = |p: &[f64; 2]| line_distances(p[0], p[1]).iter().all(|d| *d > 6.0);
    let mc = measure(&clean8, &init, &FitConfig::default()).unwrap();
    let m = measure(&crossed, &init, &FitConfig::default()).unwrap();
    assert_eq!(m.outcome, Outcome::Converged);
    let all = evaluate(&m.points(), &shape).unwrap();
    let away: Vec<[f64; 2]> = m.points().into_iter().filter(far).collect();
    let away_clean: Vec<[f64; 2]> = mc.points().into_iter().filter(far).collect();
    let e = evaluate(&away, &shape).unwrap();
    let ec = evaluate(&away_clean, &shape).unwrap();
    println!("crossed: {all:?}\naway from the lines: {e:?}\nclean, same part: {ec:?}");
    assert!(all.max_abs <= 0.05, "max {}", all.max_abs);
    assert!(
        e.scatter <= 2.0 * ec.scatter,
        "{} vs {}",
        e.scatter,
        ec.scatter
    );
    // The crossings are flagged, the rest is not.
    let near: Vec<f64> = m
        .samples
        .iter()
        .filter(|s| line_distances(s.x, s.y).iter().any(|d| *d < 1.0))
        .map(|s| s.weight)
        .collect();
    assert!(
        !near.is_empty() && near.iter().all(|w| *w < 0.9),
        "{near:?}"
    );
    let clean_weights = mc.samples.iter().all(|s| s.weight == 1.0);
    assert!(clean_weights, "the clean image was reweighted");
}
