//! Accuracy table for docs/benchmarks.md: bias, scatter and max error
//! (pixels) of vicurve on images of exactly known geometry, for both image
//! interpolations.
//!
//! `cargo run --release -p vicurve --example accuracy`

use vicurve::curve::InitialCurve;
use vicurve::fit::{measure, Elements, FitConfig, Stage};
use vicurve::interp::Interpolation;
use vicurve::render::{presets, render, Method, RenderSpec};
use vicurve::truth::{evaluate, Shape};
use vicurve::virtual_image::Kind;

struct Case {
    name: &'static str,
    spec: RenderSpec,
    init: InitialCurve,
    config: FitConfig,
}

fn one_stage(r: f64, h: f64) -> Option<Vec<Stage>> {
    Some(vec![Stage {
        half_width: r,
        elements: Elements::Length(h),
    }])
}

fn cases() -> Vec<Case> {
    let paper = presets::paper_disc(10.0);
    let paper_init = InitialCurve::Circle {
        cx: 255.0,
        cy: 257.0,
        r: 203.0,
    };
    let coverage = |noise: f64, blur: f64| RenderSpec {
        width: 400,
        height: 400,
        shape: Shape::Circle {
            cx: 200.37,
            cy: 199.71,
            r: 150.0,
        },
        kind: Kind::Silhouette,
        method: Method::Coverage,
        foreground: 0.8,
        background: 0.2,
        blur_sigma: blur,
        noise,
        seed: 7,
        bits: Some(8),
        ..RenderSpec::default()
    };
    let disc_init = InitialCurve::Circle {
        cx: 203.0,
        cy: 198.0,
        r: 145.0,
    };
    let star = presets::star_1024();
    let mut out = Vec::new();
    for h in [10.0, 20.0, 40.0, 100.0] {
        out.push(Case {
            name: match h as u32 {
                10 => "paper disc (R_f = R_g = 10, 8-bit), 10 px elements",
                20 => "paper disc, 20 px elements",
                40 => "paper disc, 40 px elements",
                _ => "paper disc, 100 px elements",
            },
            spec: paper.clone(),
            init: paper_init.clone(),
            config: FitConfig {
                stages: one_stage(10.0, h),
                // The paper's image is the virtual profile itself, not a
                // blurred step: nothing to correct.
                blur_correction: false,
                ..FitConfig::default()
            },
        });
    }
    for (name, noise, blur) in [
        (
            "coverage disc r = 150, noiseless, default schedule",
            0.0,
            0.0,
        ),
        ("coverage disc r = 150, blur 1, default", 0.0, 1.0),
        ("coverage disc r = 150, 10 % noise, default", 0.1, 0.0),
    ] {
        out.push(Case {
            name,
            spec: coverage(noise, blur),
            init: disc_init.clone(),
            config: FitConfig::default(),
        });
    }
    let blur1 = |shape: Shape, kind: Kind, fg: f64, bg: f64| RenderSpec {
        width: 300,
        height: 300,
        shape,
        kind,
        line_width: 3.0,
        method: Method::Coverage,
        foreground: fg,
        background: bg,
        blur_sigma: 1.0,
        bits: Some(8),
        ..RenderSpec::default()
    };
    let sine = |y0: f64, amplitude: f64, wavelength: f64, phase: f64| Shape::Sine {
        y0,
        amplitude,
        wavelength,
        phase,
        x_min: 30.0,
        x_max: 270.0,
    };
    out.push(Case {
        name: "open sine edge (A = 12, λ = 150), blur 1, from a segment, default",
        spec: blur1(sine(150.2, 12.0, 150.0, 0.3), Kind::Silhouette, 0.8, 0.2),
        init: InitialCurve::Segment {
            x0: 30.0,
            y0: 150.0,
            x1: 270.0,
            y1: 150.0,
        },
        config: FitConfig::default(),
    });
    out.push(Case {
        name: "ring line r = 90, 3 px wide, blur 1, contour, default",
        spec: blur1(
            Shape::Circle {
                cx: 150.3,
                cy: 149.8,
                r: 90.0,
            },
            Kind::Contour,
            0.9,
            0.1,
        ),
        init: InitialCurve::Circle {
            cx: 152.0,
            cy: 148.0,
            r: 93.0,
        },
        config: FitConfig {
            kind: Kind::Contour,
            ..FitConfig::default()
        },
    });
    out.push(Case {
        name: "dark sine line (A = 10, λ = 120), 3 px wide, blur 1, contour, default",
        spec: blur1(sine(149.6, 10.0, 120.0, 1.0), Kind::Contour, 0.15, 0.85),
        init: InitialCurve::Segment {
            x0: 30.0,
            y0: 151.0,
            x1: 270.0,
            y1: 151.0,
        },
        config: FitConfig {
            kind: Kind::Contour,
            ..FitConfig::default()
        },
    });
    out.push(Case {
        name: "star 1024², blur 1, 1 % noise, from a circle 10 px off, default",
        spec: star,
        init: InitialCurve::Circle {
            cx: 522.3,
            cy: 511.6,
            r: 300.0,
        },
        config: FitConfig::default(),
    });
    out
}

fn main() {
    println!("| case | interpolation | outcome | iterations | bias (px) | scatter (px) | max (px) | mean predicted σ (px) |");
    println!("|---|---|---|---|---|---|---|---|");
    for case in cases() {
        let image = render(&case.spec).expect("render");
        for interp in [Interpolation::CubicBSpline, Interpolation::Bilinear] {
            let config = FitConfig {
                interpolation: interp,
                ..case.config.clone()
            };
            let m = measure(&image, &case.init, &config).expect("measure");
            let s = evaluate(&m.points(), &case.spec.shape).expect("evaluate");
            let sigma = m.samples.iter().map(|s| s.sigma).sum::<f64>() / m.samples.len() as f64;
            println!(
                "| {} | {} | {} | {} | {:+.2e} | {:.2e} | {:.2e} | {:.2e} |",
                case.name,
                interp,
                m.outcome,
                m.iterations(),
                s.bias,
                s.scatter,
                s.max_abs,
                sigma
            );
        }
    }
}
