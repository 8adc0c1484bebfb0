//! Every bad input to the library gives its typed error (never a panic), and
//! fits that fail report a typed outcome.

use vicurve::curve::InitialCurve;
use vicurve::fit::{measure, parse_stages, Divergence, Elements, FitConfig, Outcome, Stage};
use vicurve::{Error, Image};

fn disc_image() -> Image {
    Image::from_fn(120, 120, |x, y| {
        let d = (x as f64 - 60.2).hypot(y as f64 - 59.7) - 30.0;
        0.5 - 0.4 * (d / 1.5).tanh()
    })
}

fn config(stages: &str) -> FitConfig {
    FitConfig {
        stages: Some(parse_stages(stages).unwrap()),
        ..FitConfig::default()
    }
}

#[test]
fn images_reject_empty_and_non_finite_data() {
    assert!(matches!(
        Image::new(0, 5, vec![]),
        Err(Error::EmptyImage { .. })
    ));
    assert!(matches!(
        Image::new(2, 2, vec![0.0; 3]),
        Err(Error::InvalidParameter { .. })
    ));
    assert!(matches!(
        Image::new(2, 1, vec![0.0, f64::NAN]),
        Err(Error::NonFinite { .. })
    ));
}

#[test]
fn malformed_specifications_are_parse_errors() {
    for bad in [
        "", "10", "10:", ":5", "a:5", "10:-3", "10:2.5", "0.1:5", "10:0",
    ] {
        assert!(parse_stages(bad).is_err(), "'{bad}' accepted");
    }
    assert!(parse_stages("20:25,10:50,5:100").is_ok());
    assert!(parse_stages("5:20px,2:auto").is_ok());
    for bad in [
        "circle:1,2",
        "circle:1,2,3,4",
        "segment:1,2,3",
        "circle:a,b,c",
        "ellipse:1,2,3",
        "circle",
    ] {
        assert!(bad.parse::<InitialCurve>().is_err(), "'{bad}' accepted");
    }
}

#[test]
fn invalid_configurations_are_rejected() {
    let image = disc_image();
    let init = InitialCurve::Circle {
        cx: 60.0,
        cy: 60.0,
        r: 32.0,
    };
    let mut bad = FitConfig {
        degree: 0,
        ..FitConfig::default()
    };
    assert!(matches!(
        measure(&image, &init, &bad),
        Err(Error::InvalidParameter { name: "degree", .. })
    ));
    bad = FitConfig {
        tolerance: f64::NAN,
        ..FitConfig::default()
    };
    assert!(measure(&image, &init, &bad).is_err());
    bad = FitConfig {
        stages: Some(vec![]),
        ..FitConfig::default()
    };
    assert!(measure(&image, &init, &bad).is_err());
    bad = FitConfig {
        stages: Some(vec![Stage {
            half_width: 5.0,
            elements: Elements::Length(-1.0),
        }]),
        ..FitConfig::default()
    };
    assert!(measure(&image, &init, &bad).is_err());
}

#[test]
fn curves_and_bands_outside_the_image() {
    let image = disc_image();
    let outside = InitialCurve::Circle {
        cx: 60.0,
        cy: 60.0,
        r: 70.0,
    };
    assert!(matches!(
        measure(&image, &outside, &config("5:10")),
        Err(Error::CurveOutsideImage { .. })
    ));
    // A closed curve's band may be cut by the border (its pixels in the
    // image are kept); an open curve along the border has no stretch whose
    // band fits.
    let near_border = InitialCurve::Circle {
        cx: 60.0,
        cy: 60.0,
        r: 50.0,
    };
    assert!(measure(&image, &near_border, &config("15:10")).is_ok());
    let along_border = InitialCurve::Polyline {
        points: vec![[0.5, 10.0], [0.5, 110.0]],
        closed: false,
    };
    let r = measure(&image, &along_border, &config("5:10"));
    assert!(matches!(r, Err(Error::BandOutsideImage { .. })), "{r:?}");
    let nan = InitialCurve::Circle {
        cx: f64::NAN,
        cy: 60.0,
        r: 30.0,
    };
    assert!(matches!(
        measure(&image, &nan, &config("5:10")),
        Err(Error::NonFinite { .. })
    ));
    let poly = InitialCurve::Polyline {
        points: vec![[1.0, 1.0], [f64::INFINITY, 2.0]],
        closed: false,
    };
    assert!(matches!(
        measure(&image, &poly, &config("5:10")),
        Err(Error::NonFinite { .. })
    ));
}

#[test]
fn too_many_elements_for_the_band() {
    let image = disc_image();
    let init = InitialCurve::Circle {
        cx: 60.0,
        cy: 60.0,
        r: 32.0,
    };
    let r = measure(&image, &init, &config("1:400"));
    assert!(
        matches!(
            r,
            Err(Error::EmptyBand { .. }) | Err(Error::NotPositiveDefinite { .. })
        ),
        "{r:?}"
    );
}

#[test]
fn no_contrast_is_a_divergence() {
    let flat = Image::from_fn(100, 100, |_, _| 0.5);
    let init = InitialCurve::Circle {
        cx: 50.0,
        cy: 50.0,
        r: 25.0,
    };
    let m = measure(&flat, &init, &config("5:10")).unwrap();
    assert_eq!(
        m.outcome,
        Outcome::Diverged {
            divergence: Divergence::NoContrast
        }
    );
}

#[test]
fn a_fit_pulled_out_of_the_image_reports_it() {
    // The only edge is 5.5 px from the left border; the fit follows it and its
    // band leaves the image.
    let image = Image::from_fn(100, 100, |x, _| if x < 6 { 0.9 } else { 0.1 });
    let init = InitialCurve::Segment {
        x0: 12.0,
        y0: 10.0,
        x1: 12.0,
        y1: 90.0,
    };
    let m = measure(&image, &init, &config("8:4")).unwrap();
    assert!(
        matches!(
            m.outcome,
            Outcome::Diverged {
                divergence: Divergence::LeftImage { .. }
            }
        ),
        "{:?}",
        m.outcome
    );
    // The last good curve is kept, inside the image.
    assert!(m.samples.iter().all(|s| s.x.is_finite() && s.x >= 0.0));
}
