//! Open curves that cross the image border (issue 18, failure 2.1): an
//! edge or a thin line across a 512x512 image, started from a polyline
//! 1.5 px off drawn from border to border with its end points on the
//! outermost pixels, or from a segment from border to border. The curve is
//! trimmed where its band would leave the image, the trim is reported, the
//! measured curve reaches within `R_last + 2` px of the border, and its
//! ends are as accurate as its middle. A start whose points lie outside
//! the image is still refused.

use vicurve::curve::InitialCurve;
use vicurve::fit::{measure, FitConfig, Measurement, Outcome};
use vicurve::render::{render, Method, RenderSpec};
use vicurve::truth::{evaluate, Shape};
use vicurve::virtual_image::Kind;
use vicurve::Error;

const SIZE: usize = 512;

/// The sine of `vicurve synth sine-edge` / `sine-line` (512 x 512): slope
/// 1.26 where it crosses the left and right borders, radius of curvature
/// 32 px at its crests.
fn sine() -> Shape {
    Shape::Sine {
        y0: 255.8,
        amplitude: 51.2,
        wavelength: 256.0,
        phase: 0.0,
        x_min: 0.0,
        x_max: 511.0,
    }
}

/// Blur 1 px, noise 1 %, 8-bit, exact coverage.
fn image_spec(kind: Kind, seed: u64) -> RenderSpec {
    RenderSpec {
        width: SIZE,
        height: SIZE,
        shape: sine(),
        kind,
        line_width: 3.0,
        method: Method::Coverage,
        foreground: 0.8,
        background: 0.2,
        blur_sigma: 1.0,
        blur_sigma_y: None,
        noise: 0.01,
        seed,
        bits: Some(8),
        tone: vicurve::tone::Tone::Linear,
        shading: Default::default(),
    }
}

/// A polyline `offset` px off the sine along its normal, its first and
/// last vertices at x = 0 and x = 511 (the outermost pixels).
fn offset_polyline(offset: f64) -> InitialCurve {
    let Shape::Sine {
        y0,
        amplitude,
        wavelength,
        ..
    } = sine()
    else {
        unreachable!()
    };
    let w = std::f64::consts::TAU / wavelength;
    let n = 64;
    let points = (0..=n)
        .map(|i| {
            let target = 511.0 * i as f64 / n as f64;
            // The truth's abscissa whose offset point has x = target.
            let mut x = target;
            let mut normal = [0.0, 1.0];
            for _ in 0..30 {
                let slope = amplitude * w * (w * x).cos();
                let norm = slope.hypot(1.0);
                normal = [-slope / norm, 1.0 / norm];
                x -= x + offset * normal[0] - target;
            }
            let y = y0 + amplitude * (w * x).sin();
            [x + offset * normal[0], y + offset * normal[1]]
        })
        .collect();
    InitialCurve::Polyline {
        points,
        closed: false,
    }
}

fn config(kind: Kind) -> FitConfig {
    FitConfig {
        kind,
        ..FitConfig::default()
    }
}

/// Bias, scatter and largest error (px) of the samples with arc length in
/// `[s0, s1]`, against the truth, and the RMS of their reported sigma.
fn errors(m: &Measurement, spec: &RenderSpec, s0: f64, s1: f64) -> (f64, f64, f64, f64) {
    let part: Vec<_> = m
        .samples
        .iter()
        .filter(|s| s.s >= s0 && s.s <= s1)
        .collect();
    let d: Vec<f64> = part
        .iter()
        .map(|s| spec.shape.signed_distance(s.x, s.y))
        .collect();
    let n = d.len() as f64;
    let mean = d.iter().sum::<f64>() / n;
    let scatter = (d.iter().map(|v| (v - mean).powi(2)).sum::<f64>() / n).sqrt();
    let max = d.iter().fold(0.0f64, |a, v| a.max(v.abs()));
    let sigma = (part.iter().map(|s| s.sigma * s.sigma).sum::<f64>() / n).sqrt();
    (mean, scatter, max, sigma)
}

/// Distance of a point to the nearest image border, px.
fn to_border(x: f64, y: f64) -> f64 {
    let far = SIZE as f64 - 1.0;
    x.min(y).min(far - x).min(far - y)
}

/// Measures `init` on the image of `spec` and checks what every start
/// across the image must give: converged, both ends trimmed and reported
/// at the measured ends, within `R_last + 2` px of the border, and ends
/// whose last 10 px are unbiased within their reported sigma and free of
/// wiggles. Returns the measurement's bias and scatter over the whole
/// curve.
fn check_across(name: &str, spec: &RenderSpec, init: InitialCurve, kind: Kind) -> (f64, f64) {
    let image = render(spec).expect("render");
    let m = measure(&image, &init, &config(kind)).expect(name);
    assert_eq!(m.outcome, Outcome::Converged, "{name}");
    let stats = evaluate(&m.points(), &spec.shape).expect("evaluate");
    let r_last = m.stages.last().unwrap().half_width;
    let (first, last) = (m.samples[0], m.samples[m.samples.len() - 1]);
    let length = last.s;
    let (start, end) = (
        errors(&m, spec, 0.0, 10.0),
        errors(&m, spec, length - 10.0, length),
    );
    println!(
        "{name}: {stats:?}; ends ({:.2}, {:.2}) and ({:.2}, {:.2}), R_last {r_last}; \
         last 10 px: start bias {:+.2e} scatter {:.2e} max {:.2e} sigma {:.2e}, \
         end bias {:+.2e} scatter {:.2e} max {:.2e} sigma {:.2e}; trim {:?}",
        first.x,
        first.y,
        last.x,
        last.y,
        start.0,
        start.1,
        start.2,
        start.3,
        end.0,
        end.1,
        end.2,
        end.3,
        m.trim
    );
    for (which, sample, trimmed) in [("start", first, m.trim.start), ("end", last, m.trim.end)] {
        let t = trimmed.unwrap_or_else(|| panic!("{name}: the {which} is not reported trimmed"));
        assert_eq!((t.x, t.y), (sample.x, sample.y), "{name}: {which}");
        assert!(
            t.removed > 0.0 && t.removed < 3.0 * t.half_width + 5.0,
            "{name}: {t:?}"
        );
        let gap = to_border(sample.x, sample.y);
        assert!(
            gap <= r_last + 2.0,
            "{name}: the {which} is {gap:.2} px from the border"
        );
    }
    assert!(stats.scatter <= 1e-2, "{name}: scatter {}", stats.scatter);
    assert!(
        stats.max_abs <= 8.0 * stats.scatter,
        "{name}: max {}",
        stats.max_abs
    );
    for (which, (bias, _, max, sigma)) in [("start", start), ("end", end)] {
        // Ten pixels hold about one element: their mean error is one
        // sample of the noise, whose deviation sigma reports.
        assert!(
            bias.abs() <= 3.0 * sigma,
            "{name}: {which} bias {bias} (sigma {sigma})"
        );
        assert!(max <= 8.0 * stats.scatter, "{name}: {which} max {max}");
    }
    (stats.bias, stats.scatter)
}

/// Six images (seeds), each from a polyline 1.5 px off, on alternate
/// sides: every run checks out, and the mean bias over the images is
/// within 2e-3 px (one image's bias is one sample of the noise along ~30
/// elements, of deviation ~1.5e-3 px).
fn across_from_polylines(kind: Kind) {
    let mut biases = Vec::new();
    for seed in 1..=6 {
        let spec = image_spec(kind, seed);
        let offset = if seed % 2 == 0 { -1.5 } else { 1.5 };
        let name = format!("{kind:?} seed {seed}, polyline {offset:+} px off");
        let (bias, _) = check_across(&name, &spec, offset_polyline(offset), kind);
        biases.push(bias);
    }
    let mean = biases.iter().sum::<f64>() / biases.len() as f64;
    println!("{kind:?}: mean bias {mean:+.2e}");
    assert!(mean.abs() <= 2e-3, "{kind:?}: mean bias {mean}");
}

#[test]
fn edge_across_the_image_from_border_to_border_polylines() {
    across_from_polylines(Kind::Silhouette);
}

#[test]
fn line_across_the_image_from_border_to_border_polylines() {
    across_from_polylines(Kind::Contour);
}

/// From a segment from border to border: the sine edge (up to 51 px off
/// the segment: the wide stages bring it in), and a sine line of 12 px
/// amplitude (a thin line is seen only within the band: one 51 px off a
/// segment is a far start, not this failure's).
#[test]
fn edge_and_line_across_the_image_from_a_segment() {
    let segment = InitialCurve::Segment {
        x0: 0.0,
        y0: 255.8,
        x1: 511.0,
        y1: 255.8,
    };
    let edge = image_spec(Kind::Silhouette, 7);
    let line = RenderSpec {
        shape: Shape::Sine {
            y0: 255.8,
            amplitude: 12.0,
            wavelength: 256.0,
            phase: 0.0,
            x_min: 0.0,
            x_max: 511.0,
        },
        ..image_spec(Kind::Contour, 7)
    };
    for (spec, kind) in [(edge, Kind::Silhouette), (line, Kind::Contour)] {
        let name = format!("{kind:?} from a segment");
        let (bias, _) = check_across(&name, &spec, segment.clone(), kind);
        assert!(bias.abs() <= 3e-3, "{name}: bias {bias}");
    }
}

/// A start with points outside the image is refused with the point, and
/// one along the border (its band leaves the image all along) too.
#[test]
fn starts_outside_the_image_are_still_refused() {
    let spec = image_spec(Kind::Silhouette, 1);
    let image = render(&spec).expect("render");
    let outside = InitialCurve::Segment {
        x0: -12.0,
        y0: 255.8,
        x1: 511.0,
        y1: 255.8,
    };
    match measure(&image, &outside, &FitConfig::default()) {
        Err(e @ Error::CurveOutsideImage { x, .. }) => {
            assert!(x < -0.5, "{e}");
            assert!(e.to_string().contains("leaves the image"), "{e}");
        }
        other => panic!("a start outside the image: {other:?}"),
    }
    let along = InitialCurve::Segment {
        x0: 0.0,
        y0: 0.5,
        x1: 511.0,
        y1: 0.5,
    };
    match measure(&image, &along, &FitConfig::default()) {
        Err(Error::BandOutsideImage { .. }) => {}
        other => panic!("a start along the border: {other:?}"),
    }
}

/// A straight start across a wavy thin line sees the line only where it
/// crosses it: elsewhere the varying levels' contrast changes sign and
/// their steps push the curve away from the line, until it crosses itself
/// (32 of the sweep's 64 sine lines from a segment diverged so). The band
/// is then taken as lost and the global pair brings the curve in, as on a
/// closed curve. Eight phases of a line of 12 px amplitude and 300 px
/// wavelength (the sweep's), blur 1 px, noise 1 %, from the segment along
/// its mean line 1.5 px off: each converges, reaches the borders and is
/// accurate. (Their last 10 px are held neither to `check_across`'s 3
/// sigma nor to the largest error's 8 times the scatter: a line's ends
/// scatter up to 3 times their sigma, reaching 0.05 px where the middle
/// scatters by 6e-3 px, noted in issue 18.)
#[test]
fn a_wavy_line_from_a_straight_start_at_any_phase() {
    let mut diverged = Vec::new();
    for k in 0..8 {
        let phase = std::f64::consts::TAU * k as f64 / 8.0 + 0.3;
        let spec = RenderSpec {
            shape: Shape::Sine {
                y0: 251.6,
                amplitude: 12.0,
                wavelength: 300.0,
                phase,
                x_min: 0.0,
                x_max: 511.0,
            },
            line_width: 2.5,
            ..image_spec(Kind::Contour, 20 + k)
        };
        let segment = InitialCurve::Segment {
            x0: 0.0,
            y0: 251.6 + if k % 2 == 0 { 1.5 } else { -1.5 },
            x1: 511.0,
            y1: 251.6 + if k % 2 == 0 { 1.5 } else { -1.5 },
        };
        let image = render(&spec).expect("render");
        let m = measure(&image, &segment, &config(Kind::Contour)).expect("measure");
        if m.outcome != Outcome::Converged {
            diverged.push(format!("phase {phase:.2}: {}", m.outcome));
            continue;
        }
        let stats = evaluate(&m.points(), &spec.shape).expect("evaluate");
        let r_last = m.stages.last().unwrap().half_width;
        println!("phase {phase:.2}: {stats:?}, R_last {r_last}, {:?}", m.trim);
        for end in [m.trim.start, m.trim.end] {
            let t = end.unwrap_or_else(|| panic!("phase {phase:.2}: an end not trimmed"));
            let gap = to_border(t.x, t.y);
            assert!(
                gap <= r_last + 2.0,
                "phase {phase:.2}: end {gap} px from the border"
            );
        }
        assert!(stats.scatter <= 1e-2, "phase {phase:.2}: {stats:?}");
        assert!(stats.bias.abs() <= 3e-3, "phase {phase:.2}: {stats:?}");
        // No wiggle away from the ends (see the note on the ends above).
        let length = m.samples[m.samples.len() - 1].s;
        let (_, _, inner_max, _) = errors(&m, &spec, 10.0, length - 10.0);
        assert!(
            inner_max <= 8.0 * stats.scatter,
            "phase {phase:.2}: max {inner_max} within the ends, {stats:?}"
        );
    }
    assert!(diverged.is_empty(), "{diverged:?}");
}

/// A disc 9 px from the image border, blur 2 px, noise 1 %: the noisy
/// image's wide pixel-edge band (10.75 px) would leave the image, so the
/// border cuts it rather than the stage being lost. When the stage was
/// skipped, the curve stayed the sine profile's, the blurred edge inside
/// the true one: -0.034 px mean here (`vicurve synth disc` of the same
/// image), 0.11 px on a scene's object at 44 of its sigma.
#[test]
fn a_disc_near_the_border_keeps_its_pixel_edge() {
    use vicurve::virtual_image::Profile;
    let shape = Shape::Circle {
        cx: 100.3,
        cy: 149.6,
        r: 40.0,
    };
    let spec = crate::common::spec(shape.clone(), (200, 200), 2.0, 0.01, 4, Some(8));
    let init = InitialCurve::Circle {
        cx: 101.2,
        cy: 148.5,
        r: 40.0,
    };
    let m = measure(&render(&spec).unwrap(), &init, &FitConfig::default()).unwrap();
    let last = m.stages.last().map(|s| s.profile);
    assert!(matches!(last, Some(Profile::PixelEdge { .. })), "{last:?}");
    let bias = evaluate(&m.points(), &shape).unwrap().bias;
    println!("bias {bias:+.4} px, {} stages", m.stages.len());
    assert!(bias.abs() < 0.01, "{bias}");
}

/// Dots and an ellipse whose edge passes 1 to 6 px from the image border
/// (a hole near the edge of a plate, a dot at the edge of a grid's crop),
/// blurred by 2.5 px, from a polyline 0.8 px inside and from the
/// automatic start.
/// Their bands (and the 8-px band that measures the blur) are cut by the
/// border: they keep their pixels in the image, the blur is measured and
/// the pixel edge takes over. Before, the dots 1 px away were refused
/// ("the band ... leaves the image") and those 3 to 6 px away kept the
/// sine profile's curve, up to 0.42 px inside, reported as converged with
/// a sigma of 0.01 px.
#[test]
fn dots_near_the_border_are_measured_with_their_blur() {
    use vicurve::start::{find_silhouette, StartConfig};
    use vicurve::virtual_image::Profile;
    let shapes = |gap: f64| {
        let r = 10.0;
        [
            Shape::Circle {
                cx: r + gap + 0.3,
                cy: 32.2,
                r,
            },
            Shape::Ellipse {
                cx: 32.4,
                cy: 12.0 + gap + 0.2,
                a: 18.0,
                b: 12.0,
                angle: 0.05,
            },
        ]
    };
    for gap in [1.0, 3.0, 6.0] {
        for (k, shape) in shapes(gap).into_iter().enumerate() {
            let spec =
                crate::common::spec(shape.clone(), (64, 64), 2.5, 0.005, 7 + k as u64, Some(8));
            let image = render(&spec).unwrap();
            // The truth 0.8 px inside, vertices 3 px apart.
            let mut points: Vec<[f64; 2]> = shape
                .polyline(3.0)
                .unwrap()
                .iter()
                .map(|p| {
                    let (_, n) = shape.closest_point(p[0], p[1]);
                    [p[0] - 0.8 * n[0], p[1] - 0.8 * n[1]]
                })
                .collect();
            points.pop();
            let inside = InitialCurve::Polyline {
                points,
                closed: true,
            };
            let auto = find_silhouette(&image, &StartConfig::default())
                .unwrap()
                .curve;
            for (start, init) in [("polyline", inside), ("auto", auto)] {
                let name = format!("gap {gap} shape {k} {start}");
                let m = measure(&image, &init, &FitConfig::default()).unwrap();
                let e = evaluate(&m.points(), &shape).unwrap();
                let sigma = crate::common::median_sigma(&m);
                println!(
                    "{name}: {} bias {:+.4} max {:.4} sigma {sigma:.4}",
                    m.outcome, e.bias, e.max_abs
                );
                assert!(m.outcome.is_converged(), "{name}: {}", m.outcome);
                let last = m.stages.last().map(|s| s.profile);
                assert!(
                    matches!(last, Some(Profile::PixelEdge { .. })),
                    "{name}: {last:?}"
                );
                assert!(
                    e.bias.abs() < 0.015 && e.max_abs < 5.0 * sigma,
                    "{name}: {e:?} sigma {sigma}"
                );
            }
        }
    }
}

/// A dot whose edge passes through the first column of pixel centres:
/// the curve touches the border, the stage matched to the edge's blur
/// cannot be built, and the narrow band's curve keeps part of the blur's
/// curvature shift (up to `blur^2 / 2r` inside the disc). Its `sigma` now
/// covers that shift (`fit/output.rs`): a disc of radius 8, 0.5 % noise,
/// 8 bits, from a circle 0.6 px off and 0.5 px too large. Under a 2.5 px
/// blur the samples came out 0.50 px off at up to 51 times their `sigma`
/// (measured on the same case; now 1.2); under 1.5 px the pixel-edge
/// stage is reached, before and after (2.2).
#[test]
fn a_dot_touching_the_border_covers_its_blur_shift() {
    let (r, cy) = (8.0, 32.17);
    let shape = Shape::Circle { cx: r, cy, r };
    let mut worst = 0.0f64;
    for (k, blur) in [1.5, 2.5].into_iter().enumerate() {
        let spec = crate::common::spec(shape.clone(), (64, 64), blur, 0.005, 3 + k as u64, Some(8));
        let image = render(&spec).unwrap();
        let init = InitialCurve::Circle {
            cx: r + 0.6,
            cy: cy - 0.2,
            r: r + 0.5,
        };
        let m = measure(&image, &init, &FitConfig::default()).unwrap();
        let (error, ratio) = m
            .samples
            .iter()
            .map(|s| {
                let e = ((s.x - r).hypot(s.y - cy) - r).abs();
                (e, e / s.sigma)
            })
            .fold((0.0f64, 0.0f64), |a, b| (a.0.max(b.0), a.1.max(b.1)));
        println!(
            "blur {blur}: {}, last profile {:?}, largest error {error:.3} px, \
             largest error / sigma {ratio:.1}",
            m.outcome,
            m.stages.last().map(|s| s.profile)
        );
        assert_eq!(m.outcome, Outcome::Converged);
        worst = worst.max(ratio);
    }
    assert!(worst <= 3.0, "largest error / sigma {worst}");
}
