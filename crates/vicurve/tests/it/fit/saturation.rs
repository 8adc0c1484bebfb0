//! Pixels the camera clipped (`correlation::censor`): a dark part on a
//! backlight brighter than the sensor's brightest level, as such images
//! are usually exposed.

use vicurve::curve::InitialCurve;
use vicurve::fit::{measure, FitConfig, Outcome};
use vicurve::render::{render, RenderSpec};
use vicurve::truth::{evaluate, Shape};
use vicurve::Image;

use crate::common::spec;

/// The discs' truth: radius 60 px in a 200 x 200 image.
const DISC: Shape = Shape::Circle {
    cx: 100.4,
    cy: 99.7,
    r: 60.0,
};

/// Where the discs are measured from: a circle 1 px off.
const START: InitialCurve = InitialCurve::Circle {
    cx: 101.2,
    cy: 99.0,
    r: 61.0,
};

/// A dark disc (a sixteenth of the backlight) of radius 60 px on a backlight of light
/// `backlight` (1: the 8-bit range's top), blurred by 2 px, noise 1 % of
/// the contrast, recorded in 8 bits: the backlight and the top of the
/// edge's profile clipped at 255.
fn backlit_disc(backlight: f64, seed: u64) -> Image {
    let spec = RenderSpec {
        foreground: 0.05,
        background: 0.8,
        ..spec(DISC, (200, 200), 2.0, 0.01, seed, None)
    };
    let light = render(&spec).unwrap();
    let scale = backlight / 0.8;
    Image::from_fn(200, 200, |x, y| {
        ((light.get(x, y) * scale).clamp(0.0, 1.0) * 255.0).round() / 255.0
    })
}

/// Backlights 1.2 and 1.5 times the clip level: measured as values, the
/// clipped plateau held the profile's top down and the disc came out 0.52
/// px too small at 82 times its sigma (backlight 1.2). As censored pixels:
/// 1.9e-3 px (max 2.9e-2, 3.2 sigma) and 1.9e-2 px (max 6.0e-2, but 6.2
/// sigma: the sigma does not yet hold what the clip leaves of the profile,
/// see docs/benchmarks.md, "Saturated backlights").
#[test]
fn a_disc_on_a_saturated_backlight_is_measured_through_the_clip() {
    for (backlight, seed, bias, max, ratio) in
        [(1.2, 1, 5e-3, 0.04, 4.0), (1.5, 2, 0.03, 0.08, 8.0)]
    {
        let image = backlit_disc(backlight, seed);
        let m = measure(&image, &START, &FitConfig::default()).unwrap();
        let stats = evaluate(&m.points(), &DISC).unwrap();
        let worst = m
            .samples
            .iter()
            .map(|s| DISC.signed_distance(s.x, s.y).abs() / s.sigma)
            .fold(0.0, f64::max);
        eprintln!(
            "backlight {backlight}: {:?}, bias {:+.2e} max {:.2e} px, worst |error| / sigma {worst:.1}",
            m.outcome, stats.bias, stats.max_abs
        );
        assert_eq!(m.outcome, Outcome::Converged);
        // The clipped pixels are said.
        assert!(m.stages.last().unwrap().clipped > 100);
        assert!(stats.bias.abs() < bias, "{stats:?}");
        assert!(stats.max_abs < max, "{stats:?}");
        assert!(worst < ratio, "worst |error| / sigma {worst}");
    }
}

/// A disc whose levels are exactly the 8-bit range's ends (0 and 255,
/// nothing clipped: a rendered black-and-white scene) is not moved by
/// its plateaus' pixels being taken as clipped: noiseless, bias -3.6e-4
/// px and max 3.8e-3 (-3.0e-4 and 1.9e-3 fitted as values); with noise
/// that clips half of each plateau, 2.8e-4 and 1.1e-2 (-3.3e-4 and
/// 1.1e-2).
#[test]
fn a_black_and_white_disc_is_not_taken_for_a_clipped_one() {
    for (noise, bias, max) in [(0.0, 2e-3, 1e-2), (0.01, 3e-3, 3e-2)] {
        let spec = RenderSpec {
            foreground: 1.0,
            background: 0.0,
            ..spec(DISC, (200, 200), 1.0, noise, 3, Some(8))
        };
        let m = measure(&render(&spec).unwrap(), &START, &FitConfig::default()).unwrap();
        let stats = evaluate(&m.points(), &DISC).unwrap();
        eprintln!("black and white, noise {noise}: {stats:?}");
        assert_eq!(m.outcome, Outcome::Converged);
        // The clipped pixels are said.
        assert!(m.stages.last().unwrap().clipped > 100);
        assert!(stats.bias.abs() < bias, "{stats:?}");
        assert!(stats.max_abs < max, "{stats:?}");
    }
}
