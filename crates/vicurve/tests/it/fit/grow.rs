//! Segment-by-segment start (`vicurve::fit::grow`): from a short segment on
//! the edge, the curve grows to the image border, closes on itself, stops
//! where a line ends, or stops at the length asked for; and it gives the
//! same curve as another start (the paper's figure 13 comparison).

use vicurve::curve::InitialCurve;
use vicurve::fit::grow::{grow, EndReason, GrowConfig, Grown};
use vicurve::fit::{measure, FitConfig, Outcome};
use vicurve::interp::Sampler;
use vicurve::render::render;
use vicurve::truth::{evaluate, Shape};
use vicurve::virtual_image::Kind;
use vicurve::{Error, Image};

use crate::common::{max_gap, spec};

/// Noise seed and quantisation of the images these tests render.
const SEED: u64 = 11;
const BITS: Option<u8> = Some(8);

fn grown(image: &Image, segment: [f64; 4], config: &FitConfig, g: &GrowConfig) -> Grown {
    let [x0, y0, x1, y1] = segment;
    let start = InitialCurve::Segment { x0, y0, x1, y1 }.to_curve().unwrap();
    let sampler = Sampler::new(image, config.interpolation);
    grow(&sampler, start, config, g).unwrap()
}

/// A 30 px segment on a star's edge grows all the way round and closes;
/// the result is the star, and the same curve as measured from a circle
/// crossing it (within 0.01 px everywhere, the paper's figure 13 check).
#[test]
fn a_segment_on_a_star_grows_into_the_closed_star() {
    let shape = Shape::Star {
        cx: 200.4,
        cy: 199.7,
        r0: 120.0,
        amplitude: 0.15,
        lobes: 5,
        phase: 0.3,
    };
    let image = render(&spec(shape.clone(), (400, 400), 1.0, 0.0, SEED, BITS)).unwrap();
    // The star's rightmost point is near (200.4 + 120 (1 + 0.15 cos 0.3),
    // 199.7); a vertical segment through it, 2 px off the edge.
    let x = 200.4 + 120.0 * (1.0 + 0.15 * 0.3f64.cos()) - 2.0;
    let config = FitConfig::default();
    let g = grown(
        &image,
        [x, 215.0, x, 185.0],
        &config,
        &GrowConfig::default(),
    );
    let m = &g.measurement;
    let e = evaluate(&m.points(), &shape).unwrap();
    let kept = g.report.steps.iter().filter(|s| s.kept).count();
    println!(
        "star grown: {} steps ({kept} kept), ends {:?}, length {:.1} px, bias {:+.2e} max {:.2e}",
        g.report.steps.len(),
        g.report.ends,
        m.length(),
        e.bias,
        e.max_abs
    );
    assert_eq!(g.report.ends, [EndReason::Closed; 2]);
    assert!(m.curve.is_closed());
    assert_eq!(m.outcome, Outcome::Converged);
    assert!(e.bias.abs() < 2e-3 && e.max_abs < 0.02, "{e:?}");
    let circle = InitialCurve::Circle {
        cx: 205.0,
        cy: 200.0,
        r: 120.0,
    };
    let from_circle = measure(&image, &circle, &config).unwrap();
    let gap = max_gap(m, &from_circle).max(max_gap(&from_circle, m));
    println!("gap to the measurement from a circle: {gap:.2e} px");
    assert!(gap <= 0.01, "the two starts differ by {gap} px");
}

/// An edge across the whole image (a sine): a short segment in the middle
/// grows to both borders, and is accurate all along.
#[test]
fn a_segment_on_an_open_edge_grows_to_both_borders() {
    let shape = Shape::Sine {
        y0: 150.3,
        amplitude: 25.0,
        wavelength: 260.0,
        phase: 0.4,
        x_min: 0.0,
        x_max: 499.0,
    };
    let image = render(&spec(shape.clone(), (500, 300), 1.5, 0.01, SEED, BITS)).unwrap();
    let y = |x: f64| 150.3 + 25.0 * (std::f64::consts::TAU * x / 260.0 + 0.4).sin();
    let g = grown(
        &image,
        [240.0, y(240.0) + 1.5, 270.0, y(270.0) + 1.5],
        &FitConfig::default(),
        &GrowConfig::default(),
    );
    let m = &g.measurement;
    let e = evaluate(&m.points(), &shape).unwrap();
    let (first, last) = (m.samples[0], *m.samples.last().unwrap());
    println!(
        "sine grown: {} steps, ends {:?}, x from {:.1} to {:.1}, bias {:+.2e} scatter {:.2e} max {:.2e}",
        g.report.steps.len(),
        g.report.ends,
        first.x.min(last.x),
        first.x.max(last.x),
        e.bias,
        e.scatter,
        e.max_abs
    );
    assert_eq!(g.report.ends, [EndReason::Border; 2]);
    assert_eq!(m.outcome, Outcome::Converged);
    // The ends stop one growing band (6 px) plus 2 px from the border, give
    // or take the last step's pixel.
    assert!(first.x.min(last.x) < 12.0 && first.x.max(last.x) > 487.0);
    // The last pixels of an open end are measured less well (the band is
    // cut there, and here the image ends too): 4.5e-2 px at x = 8.
    let inner: Vec<[f64; 2]> = m
        .points()
        .into_iter()
        .filter(|p| p[0] > 15.0 && p[0] < 485.0)
        .collect();
    let ei = evaluate(&inner, &shape).unwrap();
    println!("away from the ends: max {:.2e}", ei.max_abs);
    assert!(e.bias.abs() < 3.5e-3 && e.max_abs < 0.08, "{e:?}");
    assert!(ei.max_abs < 0.035, "{ei:?}");
}

/// A thin bright line that ends inside the image (a scratch): grown from a
/// segment on it, the curve stops where the line ends (within a few
/// pixels), not at the border.
#[test]
fn a_line_that_ends_stops_the_growth() {
    // A bright line of width ~3 px along y = 100 + 0.002 (x - 150)^2 for x in
    // [60, 260], fading out over 2 px at its ends, on a dark ground.
    let axis = |x: f64| 100.0 + 0.002 * (x - 150.0).powi(2);
    let image = Image::from_fn(320, 200, |i, j| {
        let (x, y) = (i as f64, j as f64);
        let d = (y - axis(x)) / (1.0 + (0.004 * (x - 150.0)).powi(2)).sqrt();
        let across = (-d * d / (2.0 * 1.2 * 1.2)).exp();
        let along = ((x - 60.0).min(260.0 - x) / 2.0).clamp(0.0, 1.0);
        0.15 + 0.6 * across * along
    });
    let config = FitConfig {
        kind: Kind::Contour,
        ..FitConfig::default()
    };
    let g = grown(
        &image,
        [140.0, axis(140.0) + 1.0, 160.0, axis(160.0) + 1.0],
        &config,
        &GrowConfig::default(),
    );
    let m = &g.measurement;
    let (a, b) = (m.samples[0], *m.samples.last().unwrap());
    let (lo, hi) = (a.x.min(b.x), a.x.max(b.x));
    let worst = m
        .samples
        .iter()
        .filter(|s| s.x > 70.0 && s.x < 250.0)
        .map(|s| (s.y - axis(s.x)).abs())
        .fold(0.0, f64::max);
    println!(
        "line grown: ends {:?}, x from {lo:.1} to {hi:.1}, worst |dy| on [70, 250]: {worst:.2e}",
        g.report.ends
    );
    assert_eq!(g.report.ends, [EndReason::EdgeEnds; 2]);
    assert!(
        (lo - 60.0).abs() < 8.0 && (hi - 260.0).abs() < 8.0,
        "{lo} {hi}"
    );
    assert!(worst < 0.05, "{worst}");
}

/// A line bent into a C (an arc of 300 deg, its ends 80 px apart): grown
/// from a segment on it, it stops at its two ends; the gap is not bridged.
#[test]
fn a_c_shaped_line_is_not_closed_across_its_gap() {
    let (cx, cy, radius) = (150.3, 149.8, 80.0);
    // The gap is centred on the +x direction: angles within 30 deg of it.
    let image = Image::from_fn(300, 300, |i, j| {
        let (dx, dy) = (i as f64 - cx, j as f64 - cy);
        let d = dx.hypot(dy) - radius;
        let angle = dy.atan2(dx).abs().to_degrees();
        let along = ((angle - 30.0) * radius.to_radians() / 2.0).clamp(0.0, 1.0);
        0.15 + 0.6 * (-d * d / (2.0 * 1.2 * 1.2)).exp() * along
    });
    let config = FitConfig {
        kind: Kind::Contour,
        ..FitConfig::default()
    };
    // A segment across the leftmost part of the arc, 1 px off it.
    let x = cx - radius + 1.0;
    let g = grown(
        &image,
        [x, cy + 15.0, x, cy - 15.0],
        &config,
        &GrowConfig::default(),
    );
    let m = &g.measurement;
    let worst = m
        .samples
        .iter()
        .map(|q| ((q.x - cx).hypot(q.y - cy) - radius).abs())
        .fold(0.0, f64::max);
    let ends: Vec<f64> = [m.samples[0], *m.samples.last().unwrap()]
        .iter()
        .map(|q| (q.y - cy).atan2(q.x - cx).abs().to_degrees())
        .collect();
    println!(
        "C grown: ends {:?} at {:.1} and {:.1} deg from the gap's axis, worst radius error {worst:.2e}",
        g.report.ends, ends[0], ends[1]
    );
    assert_eq!(g.report.ends, [EndReason::EdgeEnds; 2]);
    assert!(!m.curve.is_closed());
    assert!(ends.iter().all(|a| (a - 30.0).abs() < 6.0), "{ends:?}");
    assert!(worst < 0.1, "{worst}");
}

/// A length limit stops the growth near that length, on both ends.
#[test]
fn growth_stops_at_the_length_asked() {
    let shape = Shape::Circle {
        cx: 160.2,
        cy: 159.6,
        r: 110.0,
    };
    let image = render(&spec(shape, (320, 320), 0.8, 0.0, SEED, BITS)).unwrap();
    let g = grown(
        &image,
        [268.0, 175.0, 268.0, 145.0],
        &FitConfig::default(),
        &GrowConfig {
            max_length: Some(200.0),
            ..GrowConfig::default()
        },
    );
    let length = g.measurement.length();
    println!(
        "length asked 200 px, grown {length:.2} px, ends {:?}",
        g.report.ends
    );
    assert_eq!(g.report.ends, [EndReason::Length; 2]);
    assert!((length - 200.0).abs() < 3.0, "{length}");
}

/// A closed start has no ends; a bad configuration is refused.
#[test]
fn errors_name_the_problem() {
    let image = render(&spec(
        Shape::Circle {
            cx: 100.0,
            cy: 100.0,
            r: 60.0,
        },
        (200, 200),
        0.0,
        0.0,
        SEED,
        BITS,
    ))
    .unwrap();
    let sampler = Sampler::new(&image, FitConfig::default().interpolation);
    let circle = InitialCurve::Circle {
        cx: 100.0,
        cy: 100.0,
        r: 60.0,
    }
    .to_curve()
    .unwrap();
    let e = grow(
        &sampler,
        circle,
        &FitConfig::default(),
        &GrowConfig::default(),
    )
    .unwrap_err();
    assert!(
        matches!(e, Error::InvalidParameter { .. }) && e.to_string().contains("closed"),
        "{e}"
    );
    let segment = InitialCurve::Segment {
        x0: 158.0,
        y0: 90.0,
        x1: 158.0,
        y1: 110.0,
    }
    .to_curve()
    .unwrap();
    let bad = GrowConfig {
        min_step: 50.0,
        ..GrowConfig::default()
    };
    let e = grow(&sampler, segment.clone(), &FitConfig::default(), &bad).unwrap_err();
    assert!(e.to_string().contains("grow steps"), "{e}");
    // Break positions are along the initial curve, which growing replaces.
    let with_breaks = FitConfig {
        breaks: vec![10.0],
        ..FitConfig::default()
    };
    let e = grow(&sampler, segment, &with_breaks, &GrowConfig::default()).unwrap_err();
    assert!(e.to_string().contains("breaks"), "{e}");
}
