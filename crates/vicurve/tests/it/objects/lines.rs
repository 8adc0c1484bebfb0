//! Every line of an image (`kind` contour): each ring followed and
//! measured, none found twice, none extra.

use vicurve::fit::FitConfig;
use vicurve::objects::{measure_all, AllConfig};
use vicurve::render::{render, Method, RenderSpec};
use vicurve::truth::Shape;
use vicurve::virtual_image::Kind;
use vicurve::Image;

/// Three bright rings (3 px wide) on a dark ground, rendered each by exact
/// coverage and blurred by 1 px, summed (they do not overlap), 16 bits.
fn rings() -> (Image, Vec<[f64; 3]>) {
    let truth = vec![
        [90.3, 100.6, 50.0],
        [250.7, 90.2, 40.0],
        [180.4, 230.9, 45.0],
    ];
    let (w, h) = (340, 300);
    let mut sum = vec![0.0; w * h];
    for &[cx, cy, r] in &truth {
        let spec = RenderSpec {
            width: w,
            height: h,
            shape: Shape::Circle { cx, cy, r },
            kind: Kind::Contour,
            line_width: 3.0,
            foreground: 0.8,
            background: 0.2,
            method: Method::Coverage,
            blur_sigma: 1.0,
            noise: 0.0,
            bits: None,
            ..RenderSpec::default()
        };
        let one = render(&spec).unwrap();
        for (s, v) in sum.iter_mut().zip(one.data()) {
            *s += v - 0.2;
        }
    }
    let image = Image::from_fn(w, h, |x, y| {
        ((0.2 + sum[y * w + x]) * 65535.0).round() / 65535.0
    });
    (image, truth)
}

#[test]
fn every_ring_is_followed_and_measured() {
    let (image, truth) = rings();
    let config = AllConfig {
        fit: FitConfig {
            kind: Kind::Contour,
            ..FitConfig::default()
        },
        ..AllConfig::default()
    };
    let all = measure_all(&image, &config).unwrap();
    assert!(all.found.bright);
    assert_eq!(all.objects.len(), 3, "{:?}", all.found);
    assert_eq!(
        all.failed(),
        0,
        "{:?}",
        all.objects.iter().map(|o| &o.failure).collect::<Vec<_>>()
    );
    let mut worst = 0.0f64;
    for t in &truth {
        let c = all
            .objects
            .iter()
            .filter_map(|o| o.closed.as_ref().map(|c| c.circle))
            .find(|c| (c.cx - t[0]).hypot(c.cy - t[1]) < 2.0)
            .unwrap_or_else(|| panic!("ring at {t:?} not measured"));
        let e = (c.cx - t[0]).hypot(c.cy - t[1]).max((c.r - t[2]).abs());
        eprintln!("ring {t:?}: centre/radius error {e:.2e} px");
        worst = worst.max(e);
    }
    assert!(worst < 0.01, "{worst}");
}

/// The same rings dark on a bright ground, with noise of 1 % of the
/// contrast: the valleys are found (auto polarity), each once, and
/// measured within the noise.
#[test]
fn dark_noisy_rings_are_found_as_valleys() {
    let (bright, truth) = rings();
    let mut image = Image::from_fn(bright.width(), bright.height(), |x, y| {
        1.0 - bright.get(x, y)
    });
    vicurve::render::noise::add_gaussian_noise(image.data_mut(), 0.006, 5);
    let config = AllConfig {
        fit: FitConfig {
            kind: Kind::Contour,
            ..FitConfig::default()
        },
        ..AllConfig::default()
    };
    let all = measure_all(&image, &config).unwrap();
    assert!(!all.found.bright);
    assert_eq!(all.objects.len(), 3, "{:?}", all.found);
    assert_eq!(all.failed(), 0);
    for t in &truth {
        let ok = all
            .objects
            .iter()
            .filter_map(|o| o.closed.as_ref().map(|c| c.circle))
            .any(|c| (c.cx - t[0]).hypot(c.cy - t[1]) < 0.02 && (c.r - t[2]).abs() < 0.02);
        assert!(ok, "ring at {t:?}");
    }
}
