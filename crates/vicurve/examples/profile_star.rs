//! Times the 1024x1024 star of the README (used for profiling; the
//! benchmark figures come from `cargo bench`).
use vicurve::curve::InitialCurve;
use vicurve::fit::{measure_from, FitConfig};
use vicurve::interp::{Interpolation, Sampler};
use vicurve::render::{render, Method, RenderSpec};
use vicurve::truth::Shape;
use vicurve::virtual_image::Kind;
fn main() {
    let spec = RenderSpec {
        width: 1024,
        height: 1024,
        shape: Shape::Star {
            cx: 512.3,
            cy: 511.6,
            r0: 300.0,
            amplitude: 0.2,
            lobes: 5,
            phase: 0.0,
        },
        kind: Kind::Silhouette,
        method: Method::Coverage,
        foreground: 0.8,
        background: 0.2,
        blur_sigma: 1.0,
        noise: 0.01,
        seed: 3,
        bits: Some(8),
        ..RenderSpec::default()
    };
    let img = render(&spec).unwrap();
    let cfg = FitConfig::default();
    for _ in 0..5 {
        let t = std::time::Instant::now();
        let s = Sampler::new(&img, Interpolation::CubicBSpline);
        let t1 = t.elapsed();
        let init = InitialCurve::Circle {
            cx: 522.3,
            cy: 511.6,
            r: 300.0,
        }
        .to_curve()
        .unwrap();
        let m = measure_from(&s, init, &cfg).unwrap();
        let stages: Vec<String> = m
            .stages
            .iter()
            .map(|s| format!("{:.1}", s.seconds * 1e3))
            .collect();
        println!(
            "sampler {t1:?} total {:?} stages {stages:?} it {}",
            t.elapsed(),
            m.iterations()
        );
    }
}
