//! Coarse stages on a binned image (`fit/pyramid.rs`): the wide stages of
//! a far start run on 8 x 8, 4 x 4 and 2 x 2 block means and hand the narrower
//! stages a reference as good as their own would have; a thin line,
//! which keeping one pixel in 16 missed, is still found; an open curve is
//! not binned.

use super::{assert_on_edge, run};
use vicurve::curve::InitialCurve;
use vicurve::fit::{FitConfig, Measurement};
use vicurve::render::{Method, RenderSpec};
use vicurve::truth::{ErrorStats, Shape};
use vicurve::virtual_image::Kind;

use crate::common::spec;

/// The binning of each stage, in order.
fn binnings(m: &Measurement) -> Vec<usize> {
    m.stages.iter().map(|s| s.binning).collect()
}

fn check(label: &str, m: &Measurement, e: &ErrorStats, scatter: f64) {
    println!(
        "{label}: {}, binnings {:?}, bias {:+.2e} scatter {:.2e} max {:.2e} ({} it)",
        m.outcome,
        binnings(m),
        e.bias,
        e.scatter,
        e.max_abs,
        m.iterations()
    );
    assert_on_edge(label, m, e, scatter);
}

/// A 5-lobed star (mean radius 200 px, amplitude 0.25, blur 1, noise 1 %,
/// 8-bit) from the circle of 0.85 of its mean radius: the R = 20 px stage
/// runs on 8 x 8 blocks, the R = 10 px stage on 4 x 4, the R = 5 px stage
/// (a coarse one: the start is beyond its reach) on 2 x 2, the rest on the
/// image, and the result is the edge to the noise's scatter. The binned
/// stages report full-resolution steps: their last ones are under the
/// band's re-referencing reach.
#[test]
fn a_far_start_s_wide_stages_run_on_the_binned_image() {
    let (cx, cy, r0) = (300.4, 299.7, 200.0);
    let shape = Shape::Star {
        cx,
        cy,
        r0,
        amplitude: 0.25,
        lobes: 5,
        phase: 0.3,
    };
    let spec = spec(shape, (600, 600), 1.0, 0.01, 5, Some(8));
    let init = InitialCurve::Circle {
        cx,
        cy,
        r: 0.85 * r0,
    };
    let (m, e) = run(&spec, init, FitConfig::default());
    check("far star", &m, &e, 1.5e-2);
    let b = binnings(&m);
    assert_eq!(&b[..3], &[8, 4, 2], "{b:?}");
    assert!(b[3..].iter().all(|&k| k == 1), "{b:?}");
    for s in &m.stages[..3] {
        let last = s.history.last().expect("history");
        assert!(last.max_step < 0.75 * s.half_width, "{last:?}");
    }
}

/// A thin dark ring (2.5 px wide, blur 1, noise 2 %, 8-bit, radius 150
/// px) from the circle of its radius centred 15 px off (as the sweep's
/// `circle-10pct` starts): on 8 x 8 blocks the line fills under a third
/// of a binned pixel, which the R = 20 px stage still follows (a band
/// keeping one pixel in 16 lost it, 4 to 13 px off).
#[test]
fn a_thin_line_is_found_through_the_binned_stages() {
    let (cx, cy, r) = (250.3, 249.6, 150.0);
    let spec = RenderSpec {
        width: 500,
        height: 500,
        shape: Shape::Circle { cx, cy, r },
        kind: Kind::Contour,
        line_width: 2.5,
        method: Method::Coverage,
        foreground: 0.2,
        background: 0.8,
        blur_sigma: 1.0,
        blur_sigma_y: None,
        noise: 0.02,
        seed: 7,
        bits: Some(8),
        tone: vicurve::tone::Tone::Linear,
        shading: Default::default(),
    };
    let init = InitialCurve::Circle {
        cx: cx + 9.0,
        cy: cy - 12.0,
        r,
    };
    let config = FitConfig {
        kind: Kind::Contour,
        ..FitConfig::default()
    };
    let (m, e) = run(&spec, init, config);
    check("ring line", &m, &e, 1.5e-2);
    assert_eq!(binnings(&m)[0], 8);
}

/// An open curve reaches the border, where a binned image has no pixel
/// centre: a sine edge from a segment 12 px off it runs every stage on
/// the image.
#[test]
fn an_open_curve_is_not_binned() {
    let shape = Shape::Sine {
        y0: 200.3,
        amplitude: 10.0,
        wavelength: 200.0,
        phase: 0.2,
        x_min: 0.0,
        x_max: 399.0,
    };
    let spec = spec(shape, (400, 400), 1.0, 0.01, 3, Some(8));
    let init = InitialCurve::Segment {
        x0: 0.0,
        y0: 212.0,
        x1: 399.0,
        y1: 212.0,
    };
    let (m, e) = run(&spec, init, FitConfig::default());
    check("sine edge", &m, &e, 1.5e-2);
    assert!(m.stages.iter().any(|s| s.half_width >= 20.0), "{m:?}");
    assert!(binnings(&m).iter().all(|&k| k == 1), "{:?}", binnings(&m));
}
