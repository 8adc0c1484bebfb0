//! Automatic start for thin lines: the ridge (or valley) followed from a
//! picked point, and the measurement from it.

use vicurve::curve::InitialCurve;
use vicurve::fit::{measure, FitConfig, Measurement, Outcome};
use vicurve::render::{render, Method, RenderSpec};
use vicurve::start::ridge::find_line;
use vicurve::start::StartConfig;
use vicurve::truth::{evaluate, Shape};
use vicurve::virtual_image::Kind;
use vicurve::{Error, Image};

fn line_image(width: usize, height: usize, shape: Shape, line_width: f64, bright: bool) -> Image {
    blurred_line_image((width, height), shape, line_width, bright, 1.0)
}

fn blurred_line_image(
    (width, height): (usize, usize),
    shape: Shape,
    line_width: f64,
    bright: bool,
    blur_sigma: f64,
) -> Image {
    let (fg, bg) = if bright { (0.8, 0.2) } else { (0.15, 0.7) };
    render(&RenderSpec {
        width,
        height,
        shape,
        kind: Kind::Contour,
        method: Method::Coverage,
        line_width,
        foreground: fg,
        background: bg,
        blur_sigma,
        blur_sigma_y: None,
        noise: 0.02,
        seed: 3,
        bits: Some(8),
        tone: vicurve::tone::Tone::Linear,
        shading: Default::default(),
    })
    .unwrap()
}

fn pick(x: f64, y: f64) -> StartConfig {
    StartConfig {
        pick: Some([x, y]),
        roi: None,
    }
}

/// A bright closed line (a star drawn 3 px wide): picked 1.5 px off its
/// axis, the followed line closes, lies on the axis within half a pixel,
/// and measures the star.
#[test]
fn a_closed_bright_line_is_followed_all_round() {
    let shape = Shape::Star {
        cx: 160.3,
        cy: 159.8,
        r0: 100.0,
        amplitude: 0.12,
        lobes: 4,
        phase: 0.2,
    };
    let image = line_image(320, 320, shape.clone(), 3.0, true);
    // The star's point at theta = 0: x = cx + r0 (1 + a cos(phase)).
    let x = 160.3 + 100.0 * (1.0 + 0.12 * 0.2f64.cos());
    let found = find_line(&image, &pick(x + 1.5, 159.8)).unwrap();
    let start_points = found.curve.dense_points(1.0).unwrap();
    let e0 = evaluate(&start_points, &shape).unwrap();
    println!(
        "star line: closed {}, bright {}, scale {}, length {:.1} px (true ~{:.1}), start max {:.2}",
        found.closed,
        found.bright,
        found.scale,
        found.length,
        shape.length(),
        e0.max_abs
    );
    assert!(found.closed && found.bright);
    assert!(e0.max_abs < 0.5, "{e0:?}");
    measure_from_the_start(&image, &found.curve, &shape, 0.05);
}

/// Measure the line from `start` as a contour: converged, |bias| under
/// 5e-3 px and every point within `max_error` px of `shape`; the
/// measurement.
fn measure_from_the_start(
    image: &Image,
    start: &InitialCurve,
    shape: &Shape,
    max_error: f64,
) -> Measurement {
    let config = FitConfig {
        kind: Kind::Contour,
        ..FitConfig::default()
    };
    let m = measure(image, start, &config).unwrap();
    let e = evaluate(&m.points(), shape).unwrap();
    println!(
        "measured: bias {:+.2e} scatter {:.2e} max {:.2e}",
        e.bias, e.scatter, e.max_abs
    );
    assert_eq!(m.outcome, Outcome::Converged);
    assert!(e.bias.abs() < 5e-3 && e.max_abs < max_error, "{e:?}");
    m
}

/// A dark line across the image (a sine, 4 px wide; 2.5 px wide under a
/// 4 px blur, where the ridge is followed at a 6 px scale and stops 12 px
/// inside the border): the start reaches both borders' outermost pixel
/// centres from a point on the line, within half a pixel of the axis (a
/// pixel at the 6 px scale, whose smoothing moves a ridge of 50 px radius
/// by 0.6 px towards its centre), and the measured curve comes within 10 px
/// of them (the conformance sweep's bound; the band's reach at 4 px of
/// blur is 7.7 px). The 2 % noise leaves a scatter of 0.01 px
/// at 1 px of blur, 0.05 at 4.
#[test]
fn an_open_dark_line_is_followed_to_the_borders() {
    let shape = Shape::Sine {
        y0: 100.4,
        amplitude: 20.0,
        wavelength: 200.0,
        phase: 0.0,
        x_min: 0.0,
        x_max: 399.0,
    };
    for (line_width, blur, start_max, max_error) in [(4.0, 1.0, 0.5, 0.05), (2.5, 4.0, 1.0, 0.25)] {
        let image = blurred_line_image((400, 200), shape.clone(), line_width, false, blur);
        let found = find_line(&image, &pick(200.0, 100.4 + 1.0)).unwrap();
        let pts = found.curve.dense_points(1.0).unwrap();
        let span = |pts: &[[f64; 2]]| {
            pts.iter()
                .fold((f64::MAX, f64::MIN), |(a, b), p| (a.min(p[0]), b.max(p[0])))
        };
        let (lo, hi) = span(&pts);
        let e0 = evaluate(&pts, &shape).unwrap();
        println!(
            "sine line, blur {blur}: closed {}, bright {}, scale {}, x {lo:.1}..{hi:.1}, start max {:.2}",
            found.closed, found.bright, found.scale, e0.max_abs
        );
        assert!(!found.closed && !found.bright);
        assert!(lo < 0.5 && hi > 398.5, "{lo} {hi}");
        assert!(e0.max_abs < start_max, "{e0:?}");
        let m = measure_from_the_start(&image, &found.curve, &shape, max_error);
        let (lo, hi) = span(&m.points());
        println!("measured x {lo:.1}..{hi:.1}");
        assert!(lo < 10.0 && hi > 389.0, "{lo} {hi}");
    }
}

/// No picked point, a point outside, a point on a blank ground.
#[test]
fn errors_say_what_to_do() {
    let blank = Image::from_fn(100, 100, |i, j| 0.5 + 0.001 * ((i * 7 + j * 13) % 5) as f64);
    let e = find_line(&blank, &StartConfig::default()).unwrap_err();
    assert!(
        matches!(e, Error::InvalidParameter { .. }) && e.to_string().contains("pick"),
        "{e}"
    );
    let e = find_line(&blank, &pick(150.0, 20.0)).unwrap_err();
    assert!(e.to_string().contains("outside"), "{e}");
    let flat = Image::from_fn(100, 100, |_, _| 0.5);
    let e = find_line(&flat, &pick(50.0, 50.0)).unwrap_err();
    assert!(matches!(e, Error::NoLine { .. }), "{e}");
}
