//! A line's polarity from its start (`fit/polarity.rs`): a start beside a
//! thin ring, on one side of it everywhere, converges on the ring as the
//! same start with the polarity given does; before, the contrast fitted
//! on the bell's flank could take the wrong sign and the curve walked away
//! from the line (diverged).

use super::{assert_on_edge, run};
use vicurve::curve::InitialCurve;
use vicurve::fit::FitConfig;
use vicurve::render::{Method, RenderSpec};
use vicurve::truth::Shape;
use vicurve::virtual_image::{Kind, Polarity};

/// A ring 2.5 px wide of radius 150 px (8-bit), `line` on `ground`.
fn ring(line: f64, ground: f64, blur: f64, noise: f64, seed: u64) -> RenderSpec {
    RenderSpec {
        width: 500,
        height: 500,
        shape: Shape::Circle {
            cx: 250.3,
            cy: 249.6,
            r: 150.0,
        },
        kind: Kind::Contour,
        line_width: 2.5,
        method: Method::Coverage,
        foreground: line,
        background: ground,
        blur_sigma: blur,
        blur_sigma_y: None,
        noise,
        seed,
        bits: Some(8),
        tone: vicurve::tone::Tone::Linear,
        shading: Default::default(),
    }
}

/// Starts 10 to 20 px outside and inside a dark ring (blur 1, noise 2 %)
/// and a bright one (blur 2, noise 5 %), each a circle off the ring's
/// centre by (2, -1) px: every one converges on the ring, with the result
/// of the start given the polarity.
#[test]
fn a_start_beside_a_line_finds_its_polarity() {
    let cases = [
        (
            "dark",
            ring(0.2, 0.8, 1.0, 0.02, 7),
            Polarity::Negative,
            6e-3,
        ),
        (
            "bright",
            ring(0.8, 0.2, 2.0, 0.05, 3),
            Polarity::Positive,
            3e-2,
        ),
    ];
    for (name, spec, polarity, scatter) in cases {
        for r in [130.0, 140.0, 160.0, 170.0] {
            let init = InitialCurve::Circle {
                cx: 252.3,
                cy: 248.6,
                r,
            };
            let config = FitConfig {
                kind: Kind::Contour,
                ..FitConfig::default()
            };
            let (m, e) = run(&spec, init.clone(), config.clone());
            let label = format!("{name} ring from r = {r}");
            println!(
                "{label}: {}, bias {:+.2e} scatter {:.2e} max {:.2e}",
                m.outcome, e.bias, e.scatter, e.max_abs
            );
            assert_on_edge(&label, &m, &e, scatter);
            let given = FitConfig { polarity, ..config };
            let (_, g) = run(&spec, init, given);
            assert!((e.bias - g.bias).abs() < 1e-4, "{label}: {e:?} {g:?}");
            assert!((e.scatter - g.scatter).abs() < 1e-4, "{label}: {e:?} {g:?}");
        }
    }
}
