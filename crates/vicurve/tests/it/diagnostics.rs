//! The unwrapped band and the iteration history, on discs of exactly known
//! geometry (exact pixel coverage).

use vicurve::curve::InitialCurve;
use vicurve::diagnostics::{unwrap_band, UnwrapConfig, UnwrappedBand};
use vicurve::fit::{measure, FitConfig, Measurement, Outcome};
use vicurve::render::{render, RenderSpec};
use vicurve::Image;

use crate::common::disc;

const INSIDE: f64 = 0.8;
const OUTSIDE: f64 = 0.2;

fn measured_disc() -> (Image, Measurement, FitConfig) {
    measured_disc_blurred(0.0)
}

fn measured_disc_blurred(blur_sigma: f64) -> (Image, Measurement, FitConfig) {
    let spec = RenderSpec {
        foreground: INSIDE,
        background: OUTSIDE,
        ..disc(200, (100.37, 99.71, 60.0), blur_sigma, 0.0, 0, None)
    };
    let image = render(&spec).unwrap();
    let init = InitialCurve::Circle {
        cx: 102.0,
        cy: 98.0,
        r: 64.0,
    };
    let config = FitConfig::default();
    let m = measure(&image, &init, &config).unwrap();
    assert_eq!(m.outcome, Outcome::Converged);
    (image, m, config)
}

/// `r` where column `j` crosses `level`, linear between rows (the first
/// crossing from the inside).
fn crossing(b: &UnwrappedBand, j: usize, level: f64) -> Option<f64> {
    (1..b.rows).find_map(|i| {
        let (v0, v1) = (b.image[b.index(i - 1, j)], b.image[b.index(i, j)]);
        ((v0 - level) * (v1 - level) <= 0.0 && v0 != v1).then(|| {
            let t = (v0 - level) / (v0 - v1);
            b.r(i - 1) + t * b.dr
        })
    })
}

/// What the unwrapped band of a clean disc shows.
struct Summary {
    /// Largest deviation from the flat levels at `|r| > 1.5` px and at
    /// `|r| >= 2.5` px, gray levels.
    plateau: [f64; 2],
    /// Mean and largest `|r|` of the columns' 50 % crossings, pixels.
    crossing: [f64; 2],
    /// RMS of the residual on the grid, and of the fit (at the band's
    /// pixel centres), gray levels.
    rms: [f64; 2],
}

fn summarise(blur: f64) -> Summary {
    let (image, m, config) = measured_disc_blurred(blur);
    let b = unwrap_band(&image, &m, &config, &UnwrapConfig::default()).unwrap();
    let length = m.curve.param_length();
    assert_eq!(b.columns, (length / 0.5).floor() as usize);
    assert_eq!(b.rows % 2, 1);
    assert!(b.half_width >= 3.0 && b.r(b.rows / 2) == 0.0);
    assert_eq!(b.outside, 0);
    // Clean: nothing is down-weighted.
    assert_eq!(b.robust_scale, None);
    assert!(b.weight.iter().all(|w| *w == 1.0));

    // Plateaus: the inside (r < 0, first rows) is the bright level.
    let mut plateau = [0.0f64; 2];
    for i in 0..b.rows {
        let r = b.r(i);
        let level = if r < 0.0 { INSIDE } else { OUTSIDE };
        for j in 0..b.columns {
            let e = (b.image[b.index(i, j)] - level).abs();
            if r.abs() > 1.5 {
                plateau[0] = plateau[0].max(e);
            }
            if r.abs() >= 2.5 {
                plateau[1] = plateau[1].max(e);
            }
        }
    }
    let half = 0.5 * (INSIDE + OUTSIDE);
    let cross: Vec<f64> = (0..b.columns)
        .map(|j| crossing(&b, j, half).expect("a crossing"))
        .collect();
    let mean = cross.iter().sum::<f64>() / cross.len() as f64;
    let max = cross.iter().fold(0.0f64, |m, c| m.max(c.abs()));
    let out = Summary {
        plateau,
        crossing: [mean, max],
        rms: [b.residual_rms(), m.residual_rms()],
    };
    println!(
        "disc, blur {blur} px ({}): plateau error {:.2e} beyond 1.5 px, {:.2e} beyond 2.5 px; 50 % crossing mean {:+.2e} max {:.2e} px; residual RMS {:.2e} on the grid, {:.2e} in the fit",
        b.profile, plateau[0], plateau[1], mean, max, out.rms[0], out.rms[1]
    );

    for stage in &m.stages {
        assert!(!stage.history.is_empty());
        assert_eq!(stage.history.len(), stage.iterations);
        assert!(stage.history[0].new_reference);
        for (k, rec) in stage.history.iter().enumerate() {
            assert_eq!(rec.iteration, k);
        }
        if stage.outcome == Outcome::Converged {
            // A step under the tolerance, or one after two others that
            // contract fast enough (the fit's rule, `error_left`).
            let steps: Vec<f64> = stage.history.iter().map(|h| h.max_step).collect();
            let last = steps[steps.len() - 1];
            let contracted = steps.len() >= 3 && {
                let [a, b] = [steps[steps.len() - 3], steps[steps.len() - 2]];
                let q = (last / b).max(b / a);
                q < 0.25 && 2.0 * last * q / (1.0 - q) < config.tolerance
            };
            assert!(
                last < config.tolerance || contracted,
                "R = {}: steps {:?}",
                stage.half_width,
                steps
            );
        }
    }
    out
}

/// A focused exact-coverage disc unwraps to a straight edge on r = 0 with
/// flat levels on both sides. The grid interpolates the image (cubic
/// B-spline), whose ringing on a sharp step (1.6e-2, 2.7 % of the contrast,
/// beyond 1.5 px) the fit does not see (it compares the pixel-edge profile
/// at pixel centres): the grid's residual is mostly that interpolation
/// error, not the fit's (see docs/diagnostics.md).
#[test]
fn clean_disc_unwraps_to_a_straight_edge() {
    let s = summarise(0.0);
    assert!(s.plateau[0] < 0.025, "{:?}", s.plateau);
    assert!(s.plateau[1] < 0.01, "{:?}", s.plateau);
    assert!(s.crossing[0].abs() < 0.01, "{:?}", s.crossing);
    assert!(s.crossing[1] < 0.12, "{:?}", s.crossing);
    assert!(s.rms[0] < 0.03, "{:?}", s.rms);
}

/// On a blurred disc (1 px), which the interpolation follows, the grid's
/// residual is small: the virtual image on the grid is the fitted one.
/// The measured curve is the true boundary, so the blurred image's
/// half-level lies `v / (2 rho)` inside it (`v = 1 + 1/12` px^2 the
/// variance of blur and pixel, `rho = 60` px): the band shows it at
/// `r = -9.0e-3` px. The image blurred as a camera blurs (before the
/// pixels integrate, `render::blur`) is the pixel-edge profile itself: the
/// fit's residual is 4.5e-5 of the gray range and the grid's, 3.8e-4, is
/// the interpolation's.
#[test]
fn blurred_disc_residual_is_the_fits() {
    let s = summarise(1.0);
    let shift = -(1.0 + 1.0 / 12.0) / (2.0 * 60.0);
    assert!((s.crossing[0] - shift).abs() < 2e-3, "{:?}", s.crossing);
    assert!(s.crossing[1] < 0.05, "{:?}", s.crossing);
    assert!(s.rms[0] < 1e-3, "{:?}", s.rms);
    assert!(s.rms[1] < 1e-4, "{:?}", s.rms);
}

/// A dark line across the disc's edge: the band finds clutter, and the
/// cells on the line get weights near 0 while the rest keep weights
/// near 1.
#[test]
fn a_line_across_the_edge_is_down_weighted() {
    let (clean, _, config) = measured_disc();
    // A horizontal dark bar 3 px wide through the centre, across the
    // disc's edge on both sides.
    let bar = |y: usize| (y as f64 - 99.71).abs() < 1.5;
    let image = Image::from_fn(200, 200, |x, y| if bar(y) { 0.05 } else { clean.get(x, y) });
    let init = InitialCurve::Circle {
        cx: 102.0,
        cy: 98.0,
        r: 64.0,
    };
    let m = measure(&image, &init, &config).unwrap();
    let b = unwrap_band(&image, &m, &config, &UnwrapConfig::default()).unwrap();
    assert!(b.robust_scale.is_some(), "clutter not seen");
    let (mut on, mut off) = (Vec::new(), Vec::new());
    for j in 0..b.columns {
        for i in 0..b.rows {
            let k = b.index(i, j);
            let r = b.r(i);
            // The grid point, to tell whether it is on the bar.
            let f = m.curve.frame(b.s(j));
            let y = f.point[1] + r * f.normal[1];
            if (y - 99.71).abs() < 0.5 {
                on.push(b.weight[k]);
            } else if (y - 99.71).abs() > 4.0 {
                off.push(b.weight[k]);
            }
        }
    }
    let mean = |v: &[f64]| v.iter().sum::<f64>() / v.len() as f64;
    println!(
        "bar: {} cells on it, mean weight {:.3}; {} away, mean {:.3}",
        on.len(),
        mean(&on),
        off.len(),
        mean(&off)
    );
    assert!(!on.is_empty());
    assert!(mean(&on) < 0.1, "on the bar {}", mean(&on));
    assert!(mean(&off) > 0.9, "away {}", mean(&off));
}

#[test]
fn bad_grids_are_errors() {
    let (image, m, config) = measured_disc();
    for grid in [
        UnwrapConfig {
            ds: 0.0,
            ..UnwrapConfig::default()
        },
        UnwrapConfig {
            dr: f64::NAN,
            ..UnwrapConfig::default()
        },
        UnwrapConfig {
            half_width: Some(-1.0),
            ..UnwrapConfig::default()
        },
        UnwrapConfig {
            ds: 1e-6,
            dr: 1e-6,
            half_width: None,
        },
    ] {
        let e = unwrap_band(&image, &m, &config, &grid).unwrap_err();
        assert!(matches!(e, vicurve::Error::InvalidParameter { .. }), "{e}");
    }
}
