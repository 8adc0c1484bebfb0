//! The first stage chosen from the start (`fit/probe.rs`): a start a pixel
//! or two off skips the wide stages; a start near the edge in most places
//! but far from it in one still gets them, and either way the result is
//! the edge.

use super::assert_on_edge;
use vicurve::curve::InitialCurve;
use vicurve::fit::{measure, FitConfig, Measurement};
use vicurve::render::render;
use vicurve::truth::{evaluate, ErrorStats, Shape};

use crate::common::{disc, spec};

/// Whether the fit skipped the wide stages because its start was near.
fn probed(m: &Measurement) -> bool {
    m.skipped.iter().any(|s| s.contains("within reach"))
}

/// A closed polyline around the circle `(cx, cy, r)`, `offset(theta)`
/// pixels outside it, vertices 3 px apart.
fn around(cx: f64, cy: f64, r: f64, offset: impl Fn(f64) -> f64) -> InitialCurve {
    let n = (std::f64::consts::TAU * r / 3.0).round() as usize;
    let points = (0..n)
        .map(|k| {
            let t = std::f64::consts::TAU * k as f64 / n as f64;
            let rr = r + offset(t);
            [cx + rr * t.cos(), cy - rr * t.sin()]
        })
        .collect();
    InitialCurve::Polyline {
        points,
        closed: true,
    }
}

/// A bump of `height` pixels centred at angle 1 rad, `width` rad wide.
fn bump(height: f64, width: f64) -> impl Fn(f64) -> f64 {
    move |t: f64| {
        let d = (t - 1.0) / width;
        if d.abs() < 1.0 {
            height * 0.5 * (1.0 + (std::f64::consts::PI * d).cos())
        } else {
            0.0
        }
    }
}

fn check(label: &str, m: &Measurement, s: &ErrorStats, scatter: f64) {
    let stages: Vec<String> = m
        .stages
        .iter()
        .map(|s| format!("R{}:{}el", s.half_width, s.elements))
        .collect();
    println!(
        "{label}: {}, probed {}, stages {}, bias {:+.2e} scatter {:.2e} max {:.2e} ({} it)",
        m.outcome,
        probed(m),
        stages.join(" "),
        s.bias,
        s.scatter,
        s.max_abs,
        m.iterations()
    );
    assert_on_edge(label, m, s, scatter);
}

/// From a start 1.5 px off the disc, the fit starts at the last coarse
/// stage and reaches the accuracy of the full schedule.
#[test]
fn a_near_start_skips_the_wide_stages() {
    let (cx, cy, r) = (200.37, 199.71, 120.0);
    let spec = disc(400, (cx, cy, r), 1.0, 0.01, 11, Some(8));
    let image = render(&spec).expect("render");
    let init = around(cx, cy, r, |t| 1.5 * (2.0 * t).cos());
    let m = measure(&image, &init, &FitConfig::default()).expect("measure");
    let s = evaluate(&m.points(), &spec.shape).expect("evaluate");
    check("near start", &m, &s, 6e-3);
    assert!(probed(&m), "skipped: {:?}", m.skipped);
}

/// A start 1 px off except for a bump reaching 12 px (beyond the probe's
/// 5 px band) out, or in: the probe gives way to the full schedule, whose
/// wide bands bring the bump onto the edge.
#[test]
fn a_start_far_in_one_place_gets_the_wide_stages() {
    let (cx, cy, r) = (200.37, 199.71, 120.0);
    let spec = disc(400, (cx, cy, r), 1.0, 0.01, 12, Some(8));
    let image = render(&spec).expect("render");
    for height in [12.0, -12.0] {
        let offset = bump(height, 0.4);
        let init = around(cx, cy, r, move |t| 1.0 + offset(t));
        let m = measure(&image, &init, &FitConfig::default()).expect("measure");
        let s = evaluate(&m.points(), &spec.shape).expect("evaluate");
        check(&format!("bump {height:+} px"), &m, &s, 6e-3);
        assert!(!probed(&m), "bump {height}: skipped {:?}", m.skipped);
    }
}

/// The same for an open edge: a sine edge across the image from a segment
/// start 1.5 px off its mean line but for a bump of 12 px.
#[test]
fn an_open_start_far_in_one_place_gets_the_wide_stages() {
    let shape = Shape::Sine {
        y0: 200.4,
        amplitude: 3.0,
        wavelength: 300.0,
        phase: 0.3,
        x_min: 0.0,
        x_max: 399.0,
    };
    let spec = spec(shape, (400, 400), 1.0, 0.01, 13, Some(8));
    let image = render(&spec).expect("render");
    let line = |x: f64| 200.4 + 3.0 * (std::f64::consts::TAU * x / 300.0 + 0.3).sin();
    for height in [0.0, 12.0] {
        let offset = bump(height, 40.0);
        let points = (0..=133)
            .map(|k| {
                let x = 3.0 * k as f64;
                [x, line(x) + 1.5 + offset(1.0 + (x - 200.0))]
            })
            .collect();
        let init = InitialCurve::Polyline {
            points,
            closed: false,
        };
        let m = measure(&image, &init, &FitConfig::default()).expect("measure");
        let s = evaluate(&m.points(), &spec.shape).expect("evaluate");
        check(&format!("open, bump {height} px"), &m, &s, 8e-3);
    }
}

/// A long curve's probe runs on the image binned by 2, as its stage then
/// does (`fit/pyramid.rs`): from a start 1.5 px off, the binned probe
/// completes and the wide stages are skipped; with a bump 12 px out it
/// does not, and the full schedule runs. Either way the result is the
/// edge.
#[test]
fn a_long_curve_is_probed_on_the_binned_image() {
    let (cx, cy, r) = (320.37, 319.71, 280.0);
    let spec = disc(640, (cx, cy, r), 1.0, 0.01, 14, Some(8));
    let image = render(&spec).expect("render");
    for height in [0.0, 12.0] {
        let offset = bump(height, 0.4);
        let init = around(cx, cy, r, move |t| 1.5 * (2.0 * t).cos() + offset(t));
        let m = measure(&image, &init, &FitConfig::default()).expect("measure");
        let s = evaluate(&m.points(), &spec.shape).expect("evaluate");
        let label = format!("long curve, bump {height} px");
        check(&label, &m, &s, 6e-3);
        let first = &m.stages[0];
        if height == 0.0 {
            assert!(probed(&m), "{label}: skipped {:?}", m.skipped);
            assert_eq!((first.half_width, first.binning), (5.0, 2), "{label}");
        } else {
            assert!(!probed(&m), "{label}: skipped {:?}", m.skipped);
            assert_eq!((first.half_width, first.binning), (20.0, 8), "{label}");
        }
    }
}
