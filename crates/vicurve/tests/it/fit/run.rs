//! The Gauss–Newton runs (`fit/run.rs`): a run whose steps overshoot a
//! mode many times over (an open curve's end coefficient on a cluttered
//! band) is relaxed to convergence in a few iterations, not crept along.

use super::{assert_on_edge, run};
use vicurve::curve::InitialCurve;
use vicurve::fit::{FitConfig, IterationRecord, Measurement};
use vicurve::render::{Method, RenderSpec};
use vicurve::truth::Shape;
use vicurve::virtual_image::Kind;

/// The iterations of each run of a stage: a run starts at a new reference
/// or where the run kind changes.
fn runs(history: &[IterationRecord]) -> Vec<usize> {
    let mut out: Vec<usize> = Vec::new();
    for (k, h) in history.iter().enumerate() {
        if k == 0 || h.new_reference || h.run != history[k - 1].run {
            out.push(0);
        }
        if let Some(last) = out.last_mut() {
            *last += 1;
        }
    }
    out
}

fn longest_run(m: &Measurement) -> usize {
    runs(&m.stages[0].history).into_iter().max().unwrap_or(0)
}

/// A thin sine line (2.5 px wide, blur 1, 2 % noise, 8-bit) from a
/// segment 10 to 15 px beside it. At R = 20 px the bell misfits the line,
/// the band counts as cluttered and is refitted with robust weights; the
/// last such run's step overshot the end coefficient about ten times and,
/// with the relaxation's former floor of 0.2, contracted by 0.95 an
/// iteration (217 iterations from y = 190). Every run now ends within 40.
#[test]
fn an_overshooting_run_converges_in_a_few_iterations() {
    let spec = RenderSpec {
        width: 500,
        height: 400,
        shape: Shape::Sine {
            y0: 200.3,
            amplitude: 12.0,
            wavelength: 250.0,
            phase: 0.0,
            x_min: 0.0,
            x_max: 499.0,
        },
        kind: Kind::Contour,
        line_width: 2.5,
        method: Method::Coverage,
        foreground: 0.8,
        background: 0.2,
        blur_sigma: 1.0,
        blur_sigma_y: None,
        noise: 0.02,
        seed: 5,
        bits: Some(8),
        tone: vicurve::tone::Tone::Linear,
        shading: Default::default(),
    };
    let config = FitConfig {
        kind: Kind::Contour,
        ..FitConfig::default()
    };
    for y in [190.0, 215.0] {
        let init = InitialCurve::Segment {
            x0: 0.0,
            y0: y,
            x1: 499.0,
            y1: y,
        };
        let (m, e) = run(&spec, init, config.clone());
        let label = format!("sine line from y = {y}");
        println!(
            "{label}: {}, R = 20 stage {} iterations, longest run {}; bias {:+.2e} scatter {:.2e} max {:.2e}",
            m.outcome,
            m.stages[0].iterations,
            longest_run(&m),
            e.bias,
            e.scatter,
            e.max_abs
        );
        assert_on_edge(&label, &m, &e, 1.2e-2);
        assert!(
            longest_run(&m) <= 40,
            "{label}: {:?}",
            runs(&m.stages[0].history)
        );
    }
}
