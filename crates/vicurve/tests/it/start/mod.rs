//! Automatic start: the silhouette found without a starting curve, and the
//! measurement from it.

mod ridge;

use vicurve::curve::InitialCurve;
use vicurve::fit::{measure, FitConfig, Outcome};
use vicurve::render::render;
use vicurve::start::{find_silhouette, StartConfig};
use vicurve::truth::{evaluate, Shape};
use vicurve::{Error, Image};

use crate::common::{max_gap, spec};

/// Noise seed and quantisation of the images these tests render.
const SEED: u64 = 5;
const BITS: Option<u8> = Some(8);

/// The paper's figure 13 situation: the same star measured from two
/// different starts (the automatic one and a circle that crosses it) gives
/// the same curve, within 0.01 px everywhere; both are accurate. Noiseless:
/// with noise the two fits, whose knots fall at different places along the
/// curve, differ by their noise too (1.5e-2 px at most with 1 % noise, where
/// each scatters 7e-3 px about the truth).
#[test]
fn star_from_the_automatic_start_and_from_a_circle() {
    let shape = Shape::Star {
        cx: 300.3,
        cy: 299.6,
        r0: 170.0,
        amplitude: 0.2,
        lobes: 5,
        phase: 0.4,
    };
    let s = spec(shape.clone(), (600, 600), 1.0, 0.0, SEED, BITS);
    let image = render(&s).unwrap();
    let start = find_silhouette(&image, &StartConfig::default()).unwrap();
    assert!(start.closed && start.bright, "{start:?}");
    let auto = measure(&image, &start.curve, &FitConfig::default()).unwrap();
    let circle = InitialCurve::Circle {
        cx: 306.0,
        cy: 300.0,
        r: 170.0,
    };
    let from_circle = measure(&image, &circle, &FitConfig::default()).unwrap();
    let ea = evaluate(&auto.points(), &shape).unwrap();
    let ec = evaluate(&from_circle.points(), &shape).unwrap();
    let gap = max_gap(&auto, &from_circle).max(max_gap(&from_circle, &auto));
    println!(
        "auto: bias {:+.2e} scatter {:.2e} max {:.2e}; circle: bias {:+.2e} scatter {:.2e}; gap {gap:.2e}",
        ea.bias, ea.scatter, ea.max_abs, ec.bias, ec.scatter
    );
    assert_eq!(auto.outcome, Outcome::Converged);
    assert_eq!(from_circle.outcome, Outcome::Converged);
    assert!(ea.max_abs < 0.05 && ea.bias.abs() < 2e-3, "{ea:?}");
    assert!(gap <= 0.01, "the two starts differ by {gap} px");
}

/// A dark disc on a bright ground, noisy: the start is the disc's boundary
/// (the ground touches the border), within a pixel and a half of it, and the
/// measurement from it is as good as from a circle (with 5 % noise on 40 px
/// elements each scatters about 2e-2 px, and the mean moves by about 6e-3
/// px from one noise draw to the next).
#[test]
fn dark_disc_start_hugs_the_edge() {
    let shape = Shape::Circle {
        cx: 160.4,
        cy: 150.7,
        r: 90.0,
    };
    let mut s = spec(shape.clone(), (320, 300), 1.5, 0.05, SEED, BITS);
    (s.foreground, s.background) = (0.15, 0.9);
    let image = render(&s).unwrap();
    let start = find_silhouette(&image, &StartConfig::default()).unwrap();
    assert!(start.closed && !start.bright);
    let InitialCurve::Polyline { points, .. } = &start.curve else {
        panic!("{:?}", start.curve)
    };
    let e = evaluate(points, &shape).unwrap();
    assert!(e.max_abs < 1.5, "start off by {} px", e.max_abs);
    let m = measure(&image, &start.curve, &FitConfig::default()).unwrap();
    let em = evaluate(&m.points(), &shape).unwrap();
    let circle = InitialCurve::Circle {
        cx: 162.0,
        cy: 150.0,
        r: 93.0,
    };
    let mc = measure(&image, &circle, &FitConfig::default()).unwrap();
    let ec = evaluate(&mc.points(), &shape).unwrap();
    println!("auto start: {em:?}\ncircle: {ec:?}");
    assert!(em.bias.abs() < 2e-2 && em.max_abs < 0.1, "{em:?}");
    assert!(em.scatter < 1.3 * ec.scatter, "{em:?} vs {ec:?}");
}

/// An edge crossing the image gives an open start, kept 3 px from the
/// border, and measures the edge (1 % noise: a bias within its noise,
/// about 3e-3 px on this short edge).
#[test]
fn edge_across_the_image_gives_an_open_start() {
    let shape = Shape::Sine {
        y0: 120.2,
        amplitude: 10.0,
        wavelength: 140.0,
        phase: 0.3,
        x_min: 0.0,
        x_max: 299.0,
    };
    let image = render(&spec(shape.clone(), (300, 240), 1.0, 0.01, SEED, BITS)).unwrap();
    let start = find_silhouette(&image, &StartConfig::default()).unwrap();
    assert!(!start.closed);
    let InitialCurve::Polyline { points, .. } = &start.curve else {
        panic!()
    };
    assert!(points.iter().all(|p| p[0] >= 3.0 && p[0] <= 296.0));
    assert!(points.iter().any(|p| p[0] <= 5.0) && points.iter().any(|p| p[0] >= 294.0));
    assert!(points.len() > 200, "{} points", points.len());
    let m = measure(&image, &start.curve, &FitConfig::default()).unwrap();
    assert_eq!(m.outcome, Outcome::Converged);
    let inner: Vec<[f64; 2]> = m
        .points()
        .into_iter()
        .filter(|p| p[0] > 40.0 && p[0] < 260.0)
        .collect();
    let e = evaluate(&inner, &shape).unwrap();
    assert!(e.max_abs < 0.05 && e.bias.abs() < 6e-3, "{e:?}");
}

/// Two discs: without a pick the larger one, with a pick the one under it;
/// a region of interest limits the search to the other.
#[test]
fn pick_and_region_of_interest_choose_the_object() {
    let image = Image::from_fn(300, 200, |x, y| {
        let (x, y) = (x as f64, y as f64);
        let a = (x - 80.0).hypot(y - 100.0) < 50.0;
        let b = (x - 220.0).hypot(y - 100.0) < 35.0;
        if a || b {
            0.8
        } else {
            0.2
        }
    });
    let centre = |s: &vicurve::start::AutoStart| {
        let InitialCurve::Polyline { points, .. } = &s.curve else {
            panic!()
        };
        let n = points.len() as f64;
        points
            .iter()
            .fold([0.0, 0.0], |a, p| [a[0] + p[0] / n, a[1] + p[1] / n])
    };
    let big = find_silhouette(&image, &StartConfig::default()).unwrap();
    assert!((centre(&big)[0] - 80.0).abs() < 2.0);
    let picked = find_silhouette(
        &image,
        &StartConfig {
            pick: Some([220.0, 100.0]),
            roi: None,
        },
    )
    .unwrap();
    assert!((centre(&picked)[0] - 220.0).abs() < 2.0);
    let roi = find_silhouette(
        &image,
        &StartConfig {
            pick: None,
            roi: Some([160.0, 20.0, 290.0, 180.0]),
        },
    )
    .unwrap();
    assert!((centre(&roi)[0] - 220.0).abs() < 2.0 && roi.closed);
}

#[test]
fn errors_say_what_is_wrong() {
    let flat = Image::from_fn(50, 40, |_, _| 0.4);
    assert!(matches!(
        find_silhouette(&flat, &StartConfig::default()),
        Err(Error::NoSilhouette { .. })
    ));
    let disc = Image::from_fn(100, 100, |x, y| {
        if (x as f64 - 50.0).hypot(y as f64 - 50.0) < 20.0 {
            1.0
        } else {
            0.0
        }
    });
    let outside = StartConfig {
        pick: Some([500.0, 5.0]),
        roi: None,
    };
    assert!(matches!(
        find_silhouette(&disc, &outside),
        Err(Error::InvalidParameter { .. })
    ));
    let nan = StartConfig {
        pick: Some([f64::NAN, 5.0]),
        roi: None,
    };
    assert!(matches!(
        find_silhouette(&disc, &nan),
        Err(Error::NonFinite { .. })
    ));
    let tiny = StartConfig {
        pick: None,
        roi: Some([10.0, 10.0, 12.0, 60.0]),
    };
    assert!(matches!(
        find_silhouette(&disc, &tiny),
        Err(Error::InvalidParameter { .. })
    ));
    // A speck picked: too small to be a silhouette.
    let speck = Image::from_fn(100, 100, |x, y| if x == 50 && y == 50 { 1.0 } else { 0.0 });
    let at_speck = StartConfig {
        pick: Some([50.0, 50.0]),
        roi: None,
    };
    assert!(matches!(
        find_silhouette(&speck, &at_speck),
        Err(Error::NoSilhouette { .. })
    ));
}
