//! Gray levels that vary along the curve: a silhouette under uneven light.

use vicurve::curve::InitialCurve;
use vicurve::fit::{measure, FitConfig, LevelModel, Measurement, Outcome};
use vicurve::render::{render, Method, RenderSpec};
use vicurve::truth::{evaluate, ErrorStats, Shape};
use vicurve::virtual_image::Kind;
use vicurve::Image;

const CX: f64 = 160.3;
const CY: f64 = 159.6;
const R: f64 = 110.0;

/// An exact-coverage disc (gray 0.7 on 0.15, blur `blur` px) under light
/// that changes linearly by `gradient` (relative) per disc radius along
/// the direction (0.8, 0.6), quantised to 8 bits (nothing saturates).
fn lit_disc(blur: f64, gradient: f64, noise: f64, seed: u64) -> Image {
    let spec = RenderSpec {
        width: 320,
        height: 320,
        shape: Shape::Circle {
            cx: CX,
            cy: CY,
            r: R,
        },
        kind: Kind::Silhouette,
        method: Method::Coverage,
        foreground: 0.7,
        background: 0.15,
        blur_sigma: blur,
        noise,
        seed,
        bits: None,
        ..RenderSpec::default()
    };
    let image = render(&spec).unwrap();
    Image::from_fn(320, 320, |x, y| {
        let t = (0.8 * (x as f64 - CX) + 0.6 * (y as f64 - CY)) / R;
        let light = 1.0 + gradient * t;
        (image.get(x, y) * light * 255.0).round() / 255.0
    })
}

fn measure_with(image: &Image, levels: LevelModel) -> (Measurement, ErrorStats) {
    let config = FitConfig {
        levels,
        ..FitConfig::default()
    };
    let init = InitialCurve::Circle {
        cx: CX + 3.0,
        cy: CY - 2.0,
        r: R + 4.0,
    };
    let m = measure(image, &init, &config).unwrap();
    if m.outcome != Outcome::Converged {
        for s in &m.stages {
            eprintln!(
                "R {} {:?} el {} it {} reref {} outcome {}",
                s.half_width, s.profile, s.elements, s.iterations, s.rereferences, s.outcome
            );
        }
    }
    assert_eq!(m.outcome, Outcome::Converged);
    let stats = evaluate(
        &m.points(),
        &Shape::Circle {
            cx: CX,
            cy: CY,
            r: R,
        },
    )
    .unwrap();
    (m, stats)
}

/// Light changing by +-35 % across the disc: with the varying levels the
/// bias stays within 2e-3 px (the bound) on a sharp edge and
/// blurred by 1.5 px; the global pair is off by 0.15 and 0.6 px. The
/// levels found follow the light.
///
/// The light also tilts each plateau across the band; the pixel-edge stage
/// measures that tilt beyond the band and models it (see
/// `fit::correlation::tilt`). Without it the blurred disc came out
/// -5.1e-3 px on average and 3.8e-2 px at worst; with it, -6.2e-4 and
/// 1.1e-2 px (sharp: -1.2e-4 and 2.3e-3 px).
#[test]
fn disc_under_an_illumination_gradient() {
    for (blur, max_bias, max_error) in [(0.0, 2e-3, 5e-3), (1.5, 2e-3, 2e-2)] {
        let image = lit_disc(blur, 0.35, 0.0, 0);
        let (m, varying) = measure_with(&image, LevelModel::default());
        let (_, global) = measure_with(&image, LevelModel::Global);
        eprintln!(
            "blur {blur}: varying bias {:+.2e} max {:.2e} scatter {:.2e}; \
             global bias {:+.2e} max {:.2e}",
            varying.bias, varying.max_abs, varying.scatter, global.bias, global.max_abs
        );
        assert!(varying.bias.abs() <= max_bias, "{varying:?}");
        assert!(varying.max_abs <= max_error, "{varying:?}");
        assert!(global.bias.abs() > 20.0 * max_bias, "{global:?}");
        // The contrast found along the curve follows the light: 0.55 times
        // it, within 2 %.
        assert!(!m.levels.is_empty());
        let curve = &m.curve;
        for l in &m.levels {
            let [x, y] = curve.point(l.s.min(curve.param_length()));
            let t = (0.8 * (x - CX) + 0.6 * (y - CY)) / R;
            let expected = 0.55 * (1.0 + 0.35 * t);
            assert!(
                (l.c - expected).abs() < 0.02 * 0.55,
                "c = {} at s = {}, expected {expected}",
                l.c,
                l.s
            );
        }
    }
}

/// Under even light the varying levels explain nothing beyond the noise:
/// the fit drops them (kept, they would only add noise) and gives the
/// global pair's result.
#[test]
fn even_light_same_result_as_global_pair() {
    let image = lit_disc(1.0, 0.0, 0.01, 4);
    let (m, varying) = measure_with(&image, LevelModel::default());
    let (_, global) = measure_with(&image, LevelModel::Global);
    eprintln!("even light: varying {varying:?}\nglobal {global:?}");
    assert!(m.levels.is_empty(), "the levels were kept");
    assert!((varying.bias - global.bias).abs() < 1e-6);
    assert!((varying.scatter - global.scatter).abs() < 1e-6);
}

/// `lit_disc` under light that falls off from the disc's centre by
/// `falloff` (relative) at its radius, quadratically, as a vignetting lens
/// centred on a round part does: even along the curve, tilted across it.
fn vignetted_disc(blur: f64, falloff: f64, noise: f64, seed: u64) -> Image {
    vignetted(&lit_disc(blur, 0.0, noise, seed), falloff)
}

/// `image` (320 x 320) under light that falls off by `falloff` at `R`
/// from `(CX, CY)`, quadratically, quantised to 8 bits.
fn vignetted(image: &Image, falloff: f64) -> Image {
    Image::from_fn(320, 320, |x, y| {
        let rho2 = ((x as f64 - CX).powi(2) + (y as f64 - CY).powi(2)) / (R * R);
        (image.get(x, y) * (1.0 - falloff * rho2) * 255.0).round() / 255.0
    })
}

/// Light falling off by 20 % from the disc's centre to its edge: the
/// levels are even along the curve, so the levels' test may drop the
/// varying levels, but each plateau tilts across the band (by 0.45 % a
/// pixel). The global pair takes the tilt out too: with either model the
/// blurred disc is within 3e-3 px of the truth on average (-2.4e-3 to
/// +1.6e-4 px measured). Before, the levels' test dropped the varying
/// levels, the global pair had no tilt, and the disc came out 5.5e-2 px
/// inside at 1 % noise (scatter 3.7e-3 px: 15 of it, unflagged).
/// Noiseless 8-bit levels are left out: their rounding is concentric with
/// the disc, so the plateaus' staircases tilt the two sides apart and
/// there is no tilt.
#[test]
fn disc_under_light_falling_off_from_its_centre() {
    for (noise, seed) in [(0.01, 5), (0.01, 6), (0.005, 7)] {
        let image = vignetted_disc(1.5, 0.2, noise, seed);
        for levels in [LevelModel::default(), LevelModel::Global] {
            let (m, stats) = measure_with(&image, levels);
            eprintln!(
                "noise {noise} {levels:?}: bias {:+.2e} max {:.2e} scatter {:.2e} \
                 (levels kept: {})",
                stats.bias,
                stats.max_abs,
                stats.scatter,
                !m.levels.is_empty()
            );
            assert!(stats.bias.abs() <= 3e-3, "{levels:?}: {stats:?}");
        }
    }
}

/// A 5-lobed star (mean radius 110 px, amplitude 0.15, blur 1.5 px, noise
/// 1 %, 8 bits) under light falling off by 10 % from its centre to its
/// mean radius: its edge runs in and out of the light five times, so the
/// levels change over 156 px of its 779, and the default elements (128 px)
/// explain too little of that to pass the levels' test. The test also
/// tries shorter elements and keeps them (32 px here). Before, the global
/// pair was kept and the edge followed the light: bias -2.3e-2 px, scatter
/// 9.6e-2 px (9 times its sigma, no sample flagged), 0.18 px at worst.
/// Now: bias -1e-3 px, scatter 1.3e-2 px, 1.5 times its sigma (the same
/// star under even light: 9.4e-3 px, 1.06 times).
#[test]
fn star_in_a_vignetted_field_gets_shorter_level_elements() {
    let star = Shape::Star {
        cx: CX,
        cy: CY,
        r0: R,
        amplitude: 0.15,
        lobes: 5,
        phase: 0.3,
    };
    let spec = RenderSpec {
        width: 320,
        height: 320,
        shape: star.clone(),
        kind: Kind::Silhouette,
        method: Method::Coverage,
        foreground: 0.7,
        background: 0.15,
        blur_sigma: 1.5,
        noise: 0.01,
        seed: 8,
        bits: None,
        ..RenderSpec::default()
    };
    let image = vignetted(&render(&spec).unwrap(), 0.1);
    let init = InitialCurve::Circle {
        cx: CX + 1.0,
        cy: CY - 1.0,
        r: R,
    };
    let m = measure(&image, &init, &FitConfig::default()).unwrap();
    assert_eq!(m.outcome, Outcome::Converged);
    let stats = evaluate(&m.points(), &star).unwrap();
    let sigma = crate::common::rms_sigma(&m);
    eprintln!(
        "vignetted star: bias {:+.2e} scatter {:.2e} max {:.2e} sigma {sigma:.2e}, \
         {} level samples",
        stats.bias,
        stats.scatter,
        stats.max_abs,
        m.levels.len()
    );
    assert!(!m.levels.is_empty(), "the global pair was kept");
    assert!(stats.scatter < 1.7 * sigma, "{stats:?} sigma {sigma}");
    assert!(stats.bias.abs() < 3e-3, "{stats:?}");
    assert!(stats.max_abs < 0.06, "{stats:?}");
}

/// A disc too short for four level elements of the default length (radius
/// 40 px: 251 px round, under 4 x 128 px) under light that changes by
/// +-10 % across it, blurred by 1.5 px. The pixel-edge stage tries the
/// longest elements such a curve can have (a quarter of it) and keeps
/// them: with the global pair, as every stage used before, the whole edge
/// came out 0.45 px off at worst (0.026 px with the varying levels).
#[test]
fn small_disc_under_a_gradient_gets_varying_levels() {
    let (c, r, size) = ([64.3, 63.6], 40.0, 128);
    let spec = RenderSpec {
        width: size,
        height: size,
        shape: Shape::Circle {
            cx: c[0],
            cy: c[1],
            r,
        },
        kind: Kind::Silhouette,
        method: Method::Coverage,
        foreground: 0.7,
        background: 0.15,
        blur_sigma: 1.5,
        ..RenderSpec::default()
    };
    let lit = render(&spec).unwrap();
    let image = Image::from_fn(size, size, |x, y| {
        let t = (0.8 * (x as f64 - c[0]) + 0.6 * (y as f64 - c[1])) / r;
        (lit.get(x, y) * (1.0 + 0.1 * t) * 255.0).round() / 255.0
    });
    let init = InitialCurve::Circle {
        cx: c[0] + 1.0,
        cy: c[1] - 0.5,
        r: r + 1.0,
    };
    let truth = Shape::Circle {
        cx: c[0],
        cy: c[1],
        r,
    };
    let run = |levels| {
        let config = FitConfig {
            levels,
            ..FitConfig::default()
        };
        let m = measure(&image, &init, &config).unwrap();
        assert_eq!(m.outcome, Outcome::Converged);
        let stats = evaluate(&m.points(), &truth).unwrap();
        (m, stats)
    };
    let (m, varying) = run(LevelModel::default());
    let (_, global) = run(LevelModel::Global);
    eprintln!(
        "varying: bias {:+.2e} max {:.2e}, {} levels; global: bias {:+.2e} max {:.2e}",
        varying.bias,
        varying.max_abs,
        m.levels.len(),
        global.bias,
        global.max_abs
    );
    assert!(!m.levels.is_empty(), "the levels stayed global");
    assert!(varying.bias.abs() < 2e-3, "{varying:?}");
    assert!(varying.max_abs < 4e-2, "{varying:?}");
    assert!(global.max_abs > 4.0 * varying.max_abs, "{global:?}");
}

/// The circle of radius 150 px near the centre of a 512 x 512 field
/// whose corners are 30 % darker (`render::Shading`, with a gradient of
/// 4 and 3 %), drawn dark on a bright ground (0.2 on 0.8) as an edge or
/// as a line 2.5 px wide (`kind`), blur 2 px, 1 % noise (`seed`), 8 bits,
/// measured from a circle 1.9 px off: its errors.
fn in_the_vignetted_field(kind: Kind, seed: u64) -> ErrorStats {
    let circle = Shape::Circle {
        cx: 255.8,
        cy: 255.3,
        r: 150.0,
    };
    let spec = RenderSpec {
        width: 512,
        height: 512,
        shape: circle.clone(),
        kind,
        line_width: 2.5,
        foreground: 0.2,
        background: 0.8,
        blur_sigma: 2.0,
        noise: 0.01,
        seed,
        bits: Some(8),
        shading: vicurve::render::Shading {
            gradient: [0.04, 0.03],
            vignetting: 0.3,
        },
        ..RenderSpec::default()
    };
    let image = render(&spec).unwrap();
    let init = InitialCurve::Circle {
        cx: 257.0,
        cy: 254.0,
        r: 150.0,
    };
    let config = FitConfig {
        kind,
        ..FitConfig::default()
    };
    let m = measure(&image, &init, &config).unwrap();
    assert_eq!(m.outcome, Outcome::Converged);
    let stats = evaluate(&m.points(), &circle).unwrap();
    eprintln!(
        "{kind:?} seed {seed}: bias {:+.2e} scatter {:.2e}",
        stats.bias, stats.scatter
    );
    stats
}

/// A dark disc in the vignetted field (`in_the_vignetted_field`): across
/// the band the light falls by 0.07 % a pixel, the same all round.
/// Measured on all the plateau pixels at once that tilt stands out of
/// the noise; through the levels' functions one by one it did not, and
/// the dark side's relative tilt, its level extrapolated to the edge,
/// leaned with the noise to several times the bright side's: the tilt
/// was left out and the disc came out 1.7e-2 px inside on two seeds in
/// three (noiseless: 2e-4 px).
#[test]
fn a_weak_tilt_the_same_all_round_is_taken_out() {
    for seed in [1, 3, 4, 5] {
        let stats = in_the_vignetted_field(Kind::Silhouette, seed);
        assert!(stats.bias.abs() < 4e-3, "seed {seed}: {stats:?}");
    }
}

/// A dark line 2.5 px wide along the same circle in the vignetted field
/// (`in_the_vignetted_field`): the light's tilt across the band, linear
/// across the line, moves its centre as it moves an edge. Thin lines had
/// no tilt model (only the pixel edge had), and the line came out
/// 2.7e-2 px outside (4.6 of its sigma); its tilt is now measured beyond
/// both sides of the line.
#[test]
fn a_line_in_a_vignetted_field_is_not_moved_by_the_tilt() {
    for seed in [1, 2, 3] {
        let stats = in_the_vignetted_field(Kind::Contour, seed);
        assert!(stats.bias.abs() < 6e-3, "seed {seed}: {stats:?}");
    }
}

/// A seven-lobed star (mean radius 95 px, amplitude 0.12: bays of 15 px
/// radius) under light falling by 10 % across the 264 px image, blur 2.5
/// px, 0.5 % noise, 8 bits, from a circle 5 px inside it. Along its
/// lobes the light changes faster than levels of 128 px elements follow.
/// The pixel-edge stage tested shorter levels only on its first fit,
/// whose curve was still off in the bays, and kept the 128 px ones: the
/// edge came out 3.2e-2 px RMS off its true curve, 2.6 times its `sigma`
/// (1.2e-2 px; seed 1). Tested again on its later runs, it takes shorter
/// levels: 1.2e-2 to 1.3e-2 px, within its `sigma`.
#[test]
fn levels_are_shortened_once_the_curve_fits() {
    let (cx, cy) = (132.3, 131.8);
    let star = Shape::Star {
        cx,
        cy,
        r0: 95.0,
        amplitude: 0.12,
        lobes: 7,
        phase: 0.4,
    };
    for seed in 1..=3 {
        let spec = RenderSpec {
            width: 264,
            height: 264,
            shape: star.clone(),
            kind: Kind::Silhouette,
            foreground: 0.88,
            background: 0.47,
            blur_sigma: 2.5,
            noise: 0.005,
            seed,
            bits: Some(8),
            shading: vicurve::render::Shading {
                gradient: [-0.1, 0.0],
                vignetting: 0.0,
            },
            ..RenderSpec::default()
        };
        let image = render(&spec).unwrap();
        let init = InitialCurve::Circle { cx, cy, r: 90.0 };
        let m = measure(&image, &init, &FitConfig::default()).unwrap();
        assert_eq!(m.outcome, Outcome::Converged);
        let stats = evaluate(&m.points(), &star).unwrap();
        let sigma = crate::common::rms_sigma(&m);
        eprintln!(
            "seed {seed}: scatter {:.2e} sigma {sigma:.2e} bias {:+.2e}",
            stats.scatter, stats.bias
        );
        assert!(stats.scatter < 1.8e-2, "seed {seed}: {stats:?}");
        assert!(
            stats.scatter < 1.4 * sigma,
            "seed {seed}: {stats:?} sigma {sigma:.2e}"
        );
    }
}
