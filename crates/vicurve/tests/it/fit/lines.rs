//! Thin lines measured with the pixel line (`Profile::PixelLine`): a
//! focused line a few pixels wide, where the paper's bell aliased with the
//! pixel grid.

use super::run;
use vicurve::curve::InitialCurve;
use vicurve::fit::{FitConfig, Outcome};
use vicurve::render::{Method, RenderSpec};
use vicurve::truth::Shape;
use vicurve::virtual_image::{Kind, Profile};

/// A ring of radius 110 px in a 300x300 image, and a circle 1.2 px off it
/// to start from.
fn ring() -> (Shape, InitialCurve) {
    (
        Shape::Circle {
            cx: 150.3,
            cy: 149.8,
            r: 110.0,
        },
        InitialCurve::Circle {
            cx: 151.0,
            cy: 148.8,
            r: 111.0,
        },
    )
}

/// A focused line 2.5 px wide, exact coverage, 8-bit, noiseless.
fn focused_line(shape: Shape) -> RenderSpec {
    RenderSpec {
        width: 300,
        height: 300,
        shape,
        kind: Kind::Contour,
        line_width: 2.5,
        method: Method::Coverage,
        foreground: 0.8,
        background: 0.2,
        blur_sigma: 0.0,
        bits: Some(8),
        ..RenderSpec::default()
    }
}

/// A ring and a sine, both running along pixel rows in places (where the
/// bell's misfit aliased most, one sign over tens of pixels; its figures
/// are in docs/benchmarks.md). The last stage is the pixel line through
/// the estimated width, and the curve lies on the line's axis within
/// 1.5e-3 px of scatter.
#[test]
fn a_focused_thin_line_is_measured_with_the_pixel_line() {
    let config = FitConfig {
        kind: Kind::Contour,
        ..FitConfig::default()
    };
    let sine = (
        Shape::Sine {
            y0: 150.35,
            amplitude: 12.0,
            wavelength: 300.0,
            phase: 0.4,
            x_min: 0.0,
            x_max: 299.0,
        },
        InitialCurve::Segment {
            x0: 0.0,
            y0: 151.5,
            x1: 299.0,
            y1: 151.5,
        },
    );
    for (name, (shape, init)) in [("ring", ring()), ("sine", sine)] {
        let spec = focused_line(shape);
        let (m, e) = run(&spec, init, config.clone());
        let last = m.stages.last().unwrap();
        let profile = last.profile;
        println!(
            "{name}: {profile}, {} elements; bias {:+.2e} scatter {:.2e} max {:.2e}",
            last.elements, e.bias, e.scatter, e.max_abs
        );
        assert_eq!(m.outcome, Outcome::Converged, "{name}");
        let Profile::PixelLine { width, .. } = profile else {
            panic!("{name}: last stage {profile}");
        };
        assert!((width - 2.5).abs() < 0.05, "{name}: width {width}");
        assert!(e.bias.abs() < 1e-3, "{name}: bias {}", e.bias);
        assert!(e.scatter < 1.5e-3, "{name}: scatter {}", e.scatter);
        assert!(e.max_abs < 6e-3, "{name}: max {}", e.max_abs);
    }
}

/// A ring line 2.5 px wide, radius 110 px, under a 2 px blur, noiseless,
/// 16 bits, from a circle 1.2 px off: the last stage's sine profile
/// stopped its elements at about 20 px, and the pixel-line stage kept
/// them, leaving their shape error in the result with a sigma that did
/// not count it: 34 elements, scatter 1.18e-4 px (measured before). A
/// closed blurred line's pixel-line stage now refines its elements as a
/// pixel edge's does: 68 elements, 1.26e-5 px (measured).
#[test]
fn a_blurred_ring_line_refines_its_elements() {
    let config = FitConfig {
        kind: Kind::Contour,
        ..FitConfig::default()
    };
    let (shape, init) = ring();
    let spec = RenderSpec {
        blur_sigma: 2.0,
        bits: Some(16),
        ..focused_line(shape)
    };
    let (m, e) = run(&spec, init, config);
    let last = m.stages.last().unwrap();
    println!(
        "blurred ring line: {}, {} elements; bias {:+.2e} scatter {:.2e} max {:.2e}",
        last.profile, last.elements, e.bias, e.scatter, e.max_abs
    );
    assert_eq!(m.outcome, Outcome::Converged);
    assert!(
        matches!(last.profile, Profile::PixelLine { .. }),
        "{}",
        last.profile
    );
    assert!(e.scatter < 3e-5, "scatter {}", e.scatter);
    assert!(e.bias.abs() < 5e-5, "bias {}", e.bias);
}
