//! Observed scatter / reported sigma over a spread of exact-coverage cases
//! (issue 18, section 3; figures in docs/benchmarks.md): disc, ellipse and
//! stars of two amplitudes; blur 0, 1, 2, 4 px; noise 0, 1, 2, 5 %; 8 and
//! 16 bits; a circle start 1.5 px off. One CSV row per case on stdout:
//! `ratio` is the scatter (RMS of the normal errors about their mean)
//! over the RMS of `sigma`, `osc` the largest departure of the errors from
//! their moving average over 21 samples, `flagged` the fraction of samples
//! flagged as misfit, `noise_ratio` the ratio against `sigma_noise` alone.
//!
//! `cargo run --release -p vicurve --example sigma_sweep [SHAPE...]`, with
//! `BLUR`, `NOISE`, `BITS` to select, `DUMP=1` for the samples on stderr.
use vicurve::curve::InitialCurve;
use vicurve::fit::{measure, FitConfig};
use vicurve::render::{render, Method, RenderSpec};
use vicurve::truth::Shape;
use vicurve::virtual_image::Kind;

fn main() {
    let args: Vec<String> = std::env::args().skip(1).collect();
    let dump = std::env::var("DUMP").is_ok();
    let (cx, cy) = (255.8, 255.3);
    let shapes: Vec<(&str, Shape, f64)> = vec![
        ("disc", Shape::Circle { cx, cy, r: 150.0 }, 150.0),
        (
            "ellipse",
            Shape::Ellipse {
                cx,
                cy,
                a: 180.0,
                b: 100.0,
                angle: 0.35,
            },
            140.0,
        ),
        (
            "star",
            Shape::Star {
                cx,
                cy,
                r0: 140.0,
                amplitude: 0.1,
                lobes: 5,
                phase: 0.0,
            },
            140.0,
        ),
        (
            "star2",
            Shape::Star {
                cx,
                cy,
                r0: 140.0,
                amplitude: 0.2,
                lobes: 5,
                phase: 0.0,
            },
            140.0,
        ),
    ];
    let blurs = [0.0, 1.0, 2.0, 4.0];
    let noises = [0.0, 0.01, 0.02, 0.05];
    let bitss = [8u8, 16];
    println!(
        "case,blur,noise,bits,outcome,bias,scatter,max,sigma_rms,ratio,osc,flagged,noise_ratio"
    );
    for (name, shape, r) in &shapes {
        if !args.is_empty() && !args.iter().any(|a| a == name) {
            continue;
        }
        for &blur in &blurs {
            if let Ok(b) = std::env::var("BLUR") {
                if b.parse::<f64>().unwrap() != blur {
                    continue;
                }
            }
            for &noise in &noises {
                if let Ok(b) = std::env::var("NOISE") {
                    if b.parse::<f64>().unwrap() != noise {
                        continue;
                    }
                }
                for &bits in &bitss {
                    if let Ok(b) = std::env::var("BITS") {
                        if b.parse::<u8>().unwrap() != bits {
                            continue;
                        }
                    }
                    let spec = RenderSpec {
                        width: 512,
                        height: 512,
                        shape: shape.clone(),
                        kind: Kind::Silhouette,
                        method: Method::Coverage,
                        foreground: 0.8,
                        background: 0.2,
                        blur_sigma: blur,
                        noise,
                        seed: 7,
                        bits: Some(bits),
                        ..RenderSpec::default()
                    };
                    let img = render(&spec).unwrap();
                    let init = InitialCurve::Circle {
                        cx: cx + 1.0,
                        cy: cy - 1.0,
                        r: r + 1.5,
                    };
                    let m = match measure(&img, &init, &FitConfig::default()) {
                        Ok(m) => m,
                        Err(e) => {
                            println!("{name},{blur},{noise},{bits},error {e}");
                            continue;
                        }
                    };
                    let d: Vec<f64> = m
                        .samples
                        .iter()
                        .map(|s| shape.signed_distance(s.x, s.y))
                        .collect();
                    let n = d.len() as f64;
                    let mean = d.iter().sum::<f64>() / n;
                    let scatter = (d.iter().map(|v| (v - mean).powi(2)).sum::<f64>() / n).sqrt();
                    let max = d.iter().fold(0.0f64, |a, v| a.max((v - mean).abs()));
                    let srms =
                        (m.samples.iter().map(|s| s.sigma * s.sigma).sum::<f64>() / n).sqrt();
                    // local oscillation: d minus its moving average over +-10 samples
                    let k = 10usize;
                    let len = d.len();
                    let mut osc = 0.0f64;
                    for i in 0..len {
                        let mut acc = 0.0;
                        for j in 0..=2 * k {
                            acc += d[(i + len + j - k) % len];
                        }
                        osc = osc.max((d[i] - acc / (2 * k + 1) as f64).abs());
                    }
                    let ms = m.misfit_summary();
                    let nrms = (m
                        .samples
                        .iter()
                        .map(|s| s.sigma_noise * s.sigma_noise)
                        .sum::<f64>()
                        / n)
                        .sqrt();
                    println!(
                        "{name},{blur},{noise},{bits},{},{mean:.2e},{scatter:.2e},{max:.2e},{srms:.2e},{:.2},{osc:.2e},{:.3},{:.2}",
                        m.outcome.is_converged(),
                        scatter / srms,
                        ms.fraction,
                        scatter / nrms
                    );
                    if dump {
                        for (s, e) in m.samples.iter().zip(&d) {
                            eprintln!(
                                "{:.3},{:.3},{:.3},{:.5},{:.3e},{:.3}",
                                s.s, s.x, s.y, e, s.sigma, s.weight
                            );
                        }
                        let st: Vec<_> = m
                            .stages
                            .iter()
                            .map(|s| (s.half_width, s.elements, s.iterations))
                            .collect();
                        eprintln!("{st:?}");
                    }
                }
            }
        }
    }
}
