//! Synthetic images against independent oracles: analytic areas, the exact
//! area of a disc inside a rectangle, polygon clipping, the profile formulas.

use std::f64::consts::{FRAC_PI_2, PI, TAU};

use proptest::prelude::*;
use vicurve::render::blur::gaussian_blur;
use vicurve::render::coverage::polygon_coverage;
use vicurve::render::{render, Kind, Method, RenderSpec};
use vicurve::truth::Shape;
use vicurve::{Error, Image};

/// Clip a polygon by the half-plane `n·p <= c` (Sutherland-Hodgman).
fn clip(poly: &[[f64; 2]], n: [f64; 2], c: f64) -> Vec<[f64; 2]> {
    let side = |p: [f64; 2]| n[0] * p[0] + n[1] * p[1] - c;
    let mut out = Vec::new();
    for i in 0..poly.len() {
        let (a, b) = (poly[i], poly[(i + 1) % poly.len()]);
        let (sa, sb) = (side(a), side(b));
        if sa <= 0.0 {
            out.push(a);
        }
        if (sa < 0.0 && sb > 0.0) || (sa > 0.0 && sb < 0.0) {
            let t = sa / (sa - sb);
            out.push([a[0] + t * (b[0] - a[0]), a[1] + t * (b[1] - a[1])]);
        }
    }
    out
}

fn shoelace(poly: &[[f64; 2]]) -> f64 {
    let n = poly.len();
    (0..n)
        .map(|i| {
            let (a, b) = (poly[i], poly[(i + 1) % n]);
            a[0] * b[1] - b[0] * a[1]
        })
        .sum::<f64>()
        .abs()
        / 2.0
}

/// Area of `poly` inside the rectangle `[x0, x1] x [y0, y1]`.
fn area_in_rect(poly: &[[f64; 2]], x0: f64, x1: f64, y0: f64, y1: f64) -> f64 {
    let p = clip(poly, [-1.0, 0.0], -x0);
    let p = clip(&p, [1.0, 0.0], x1);
    let p = clip(&p, [0.0, -1.0], -y0);
    let p = clip(&p, [0.0, 1.0], y1);
    if p.len() < 3 {
        0.0
    } else {
        shoelace(&p)
    }
}

/// Area of the disc of radius `r` centred at the origin within
/// `[0, x] x [0, y]`, odd in `x` and in `y` (closed form).
fn disc_quadrant(r: f64, x: f64, y: f64) -> f64 {
    let sign = x.signum() * y.signum();
    let (x, y) = (x.abs().min(r), y.abs().min(r));
    let xc = (r * r - y * y).max(0.0).sqrt();
    let prim = |u: f64| 0.5 * (u * (r * r - u * u).max(0.0).sqrt() + r * r * (u / r).asin());
    let area = if x <= xc {
        x * y
    } else {
        xc * y + prim(x) - prim(xc)
    };
    sign * area
}

/// Exact area of the disc `(cx, cy, r)` inside pixel `(i, j)`.
fn disc_pixel(cx: f64, cy: f64, r: f64, i: usize, j: usize) -> f64 {
    let (x0, x1) = (j as f64 - 0.5 - cx, j as f64 + 0.5 - cx);
    let (y0, y1) = (i as f64 - 0.5 - cy, i as f64 + 0.5 - cy);
    disc_quadrant(r, x1, y1) - disc_quadrant(r, x0, y1) - disc_quadrant(r, x1, y0)
        + disc_quadrant(r, x0, y0)
}

/// `shape` as `kind` in a 128x120 image, white on black, lines 2.5 px
/// wide (the library's defaults otherwise).
fn white_on_black(shape: Shape, kind: Kind) -> RenderSpec {
    RenderSpec {
        width: 128,
        height: 120,
        shape,
        kind,
        line_width: 2.5,
        foreground: 1.0,
        background: 0.0,
        ..RenderSpec::default()
    }
}

/// The five-lobed star these tests render, radius 40 +- 8 px.
const STAR: Shape = Shape::Star {
    cx: 63.7,
    cy: 58.2,
    r0: 40.0,
    amplitude: 0.2,
    lobes: 5,
    phase: 0.3,
};

fn sum(img: &Image) -> f64 {
    img.data().iter().sum()
}

// ---------------------------------------------------------------- coverage

#[test]
fn pixel_aligned_square_gives_exact_zeros_and_ones() {
    let sq = vec![[9.5, 4.5], [20.5, 4.5], [20.5, 12.5], [9.5, 12.5]];
    let c = polygon_coverage(32, 16, &[sq]).unwrap();
    for i in 0..16 {
        for j in 0..32 {
            let expect = if (10..=20).contains(&j) && (5..=12).contains(&i) {
                1.0
            } else {
                0.0
            };
            assert_eq!(c[i * 32 + j], expect, "pixel ({i}, {j})");
        }
    }
}

#[test]
fn holes_drawn_backwards_are_empty() {
    let outer = vec![[0.5, 0.5], [10.5, 0.5], [10.5, 10.5], [0.5, 10.5]];
    let hole = vec![[3.5, 3.5], [3.5, 6.5], [6.5, 6.5], [6.5, 3.5]];
    let c = polygon_coverage(12, 12, &[outer, hole]).unwrap();
    assert_eq!(c[5 * 12 + 5], 0.0);
    assert_eq!(c[2 * 12 + 2], 1.0);
    assert!((c.iter().sum::<f64>() - 91.0).abs() < 1e-12);
}

proptest! {
    #![proptest_config(ProptestConfig::with_cases(40))]

    #[test]
    fn coverage_sums_to_polygon_area(
        radii in proptest::collection::vec(2.0f64..25.0, 40),
        cx in -5.0f64..45.0, cy in -5.0f64..35.0,
    ) {
        // A star-shaped random polygon, possibly crossing the image border.
        let n = radii.len();
        let poly: Vec<[f64; 2]> = radii
            .iter()
            .enumerate()
            .map(|(k, r)| {
                let t = TAU * k as f64 / n as f64;
                [cx + r * t.cos(), cy - r * t.sin()]
            })
            .collect();
        let (w, h) = (40, 30);
        let c = polygon_coverage(w, h, std::slice::from_ref(&poly)).unwrap();
        let expect = area_in_rect(&poly, -0.5, w as f64 - 0.5, -0.5, h as f64 - 0.5);
        let total: f64 = c.iter().sum();
        prop_assert!((total - expect).abs() < 1e-9 * (1.0 + expect), "{} vs {}", total, expect);
        // Per pixel, for a few pixels.
        for (i, j) in [(0, 0), (h / 2, w / 2), (7, 33), (h - 1, w - 1), (12, 3)] {
            let e = area_in_rect(&poly, j as f64 - 0.5, j as f64 + 0.5, i as f64 - 0.5, i as f64 + 0.5);
            prop_assert!((c[i * w + j] - e).abs() < 1e-12, "pixel ({}, {}): {} vs {}", i, j, c[i * w + j], e);
        }
    }

    #[test]
    fn half_plane_pixels_are_exact(angle in 0.0f64..TAU, offset in -3.0f64..3.0) {
        // Half-plane n·p <= c through the image at any angle and sub-pixel
        // offset, as a big polygon.
        let n = [angle.cos(), angle.sin()];
        let c = n[0] * 8.0 + n[1] * 7.0 + offset;
        let big = vec![[-100.0, -100.0], [100.0, -100.0], [100.0, 100.0], [-100.0, 100.0]];
        let poly = clip(&big, n, c);
        let cov = polygon_coverage(16, 14, &[poly]).unwrap();
        for i in 0..14 {
            for j in 0..16 {
                let px = vec![
                    [j as f64 - 0.5, i as f64 - 0.5],
                    [j as f64 + 0.5, i as f64 - 0.5],
                    [j as f64 + 0.5, i as f64 + 0.5],
                    [j as f64 - 0.5, i as f64 + 0.5],
                ];
                let kept = clip(&px, n, c);
                let e = if kept.len() < 3 { 0.0 } else { shoelace(&kept) };
                prop_assert!((cov[i * 16 + j] - e).abs() < 1e-12);
            }
        }
    }
}

#[test]
fn disc_pixels_match_the_analytic_oracle() {
    let (cx, cy, r) = (61.37, 58.81, 37.3);
    let s = white_on_black(Shape::Circle { cx, cy, r }, Kind::Silhouette);
    let img = render(&s).unwrap();
    let mut worst = 0.0f64;
    for i in 0..s.height {
        for j in 0..s.width {
            worst = worst.max((img.get(j, i) - disc_pixel(cx, cy, r, i, j)).abs());
        }
    }
    eprintln!("disc worst {worst:e}");
    assert!(worst < 1e-6, "worst pixel error {worst}");
    let total = sum(&img);
    assert!((total - PI * r * r).abs() / (PI * r * r) < 1e-8, "{total}");
}

#[test]
fn silhouette_sums_equal_the_areas() {
    let ellipse = Shape::Ellipse {
        cx: 60.2,
        cy: 57.9,
        a: 45.0,
        b: 20.0,
        angle: 0.7,
    };
    for shape in [STAR, ellipse] {
        let img = render(&white_on_black(shape.clone(), Kind::Silhouette)).unwrap();
        let area = shape.area().unwrap();
        assert!(
            (sum(&img) - area).abs() / area < 1e-8,
            "{shape:?}: {} vs {area}",
            sum(&img)
        );
    }
}

#[test]
fn contour_sums_equal_width_times_length() {
    // The band between the offsets ±h has area 2h L exactly (the curvature
    // terms cancel), for any closed curve without overlap.
    for shape in [
        STAR,
        Shape::Circle {
            cx: 64.1,
            cy: 60.4,
            r: 30.0,
        },
    ] {
        let s = white_on_black(shape.clone(), Kind::Contour);
        let img = render(&s).unwrap();
        let expect = s.line_width * shape.length();
        assert!(
            (sum(&img) - expect).abs() / expect < 1e-8,
            "{} vs {expect}",
            sum(&img)
        );
    }
}

#[test]
fn straight_edge_and_line_give_exact_ramps() {
    let line = |amplitude: f64, y0: f64| Shape::Sine {
        y0,
        amplitude,
        wavelength: 50.0,
        phase: 0.0,
        x_min: 0.0,
        x_max: 100.0,
    };
    let y0 = 30.37;
    let img = render(&white_on_black(line(0.0, y0), Kind::Silhouette)).unwrap();
    let cont = render(&white_on_black(line(0.0, y0), Kind::Contour)).unwrap();
    for i in 0..120 {
        let (top, bottom) = (i as f64 - 0.5, i as f64 + 0.5);
        let edge = (y0 - top).clamp(0.0, 1.0);
        let band = ((y0 + 1.25).min(bottom) - (y0 - 1.25).max(top)).max(0.0);
        for j in [0, 17, 127] {
            assert!((img.get(j, i) - edge).abs() < 1e-12, "row {i}");
            assert!((cont.get(j, i) - band).abs() < 1e-12, "row {i}");
        }
    }
    // A real sine: the foreground (above) has the analytic area.
    let (a, lambda, phase) = (7.0, 37.0, 0.4);
    let shape = Shape::Sine {
        y0: 60.2,
        amplitude: a,
        wavelength: lambda,
        phase,
        x_min: 0.0,
        x_max: 100.0,
    };
    let img = render(&white_on_black(shape, Kind::Silhouette)).unwrap();
    let w = TAU / lambda;
    let (xa, xb) = (-0.5, 127.5);
    let expect = (60.2 + 0.5) * 128.0 + a / w * ((w * xa + phase).cos() - (w * xb + phase).cos());
    assert!((sum(&img) - expect).abs() / expect < 1e-8);
}

// ---------------------------------------------------------------- profile

fn gamma_s(r: f64) -> f64 {
    if r <= -1.0 {
        1.0
    } else if r >= 1.0 {
        0.0
    } else {
        (1.0 - (FRAC_PI_2 * r).sin()) / 2.0
    }
}

fn gamma_c(r: f64) -> f64 {
    if r.abs() < 1.0 {
        (1.0 + (PI * r).cos()) / 2.0
    } else {
        0.0
    }
}

#[test]
fn profile_pixels_follow_the_formula() {
    let (cx, cy, r, rf) = (60.3, 57.6, 30.2, 4.0);
    let (fg, bg) = (0.9, 0.15);
    for kind in [Kind::Silhouette, Kind::Contour] {
        let s = RenderSpec {
            method: Method::Profile { half_width: rf },
            foreground: fg,
            background: bg,
            ..white_on_black(Shape::Circle { cx, cy, r }, kind)
        };
        let img = render(&s).unwrap();
        for i in 0..s.height {
            for j in 0..s.width {
                let d = (j as f64 - cx).hypot(i as f64 - cy) - r;
                let g = match kind {
                    Kind::Silhouette => gamma_s(d / rf),
                    Kind::Contour => gamma_c(d / rf),
                };
                assert!((img.get(j, i) - (bg + (fg - bg) * g)).abs() < 1e-12);
            }
        }
    }
    // Star: every pixel, including those of skipped far blocks, is exactly
    // the formula of the signed distance.
    let shape = STAR;
    let s = RenderSpec {
        method: Method::Profile { half_width: 3.0 },
        ..white_on_black(shape.clone(), Kind::Silhouette)
    };
    let img = render(&s).unwrap();
    for i in 0..s.height {
        for j in 0..s.width {
            let d = shape.signed_distance(j as f64, i as f64);
            assert_eq!(img.get(j, i), gamma_s(d / 3.0), "({j}, {i})");
        }
    }
}

// ---------------------------------------------------------------- blur

#[test]
fn blur_preserves_mass_and_edge_position() {
    // A disc far from the borders: the total is preserved.
    let disc = render(&white_on_black(
        Shape::Circle {
            cx: 60.0,
            cy: 60.0,
            r: 20.0,
        },
        Kind::Silhouette,
    ))
    .unwrap();
    let blurred = gaussian_blur(&disc, 2.5).unwrap();
    assert!((sum(&blurred) - sum(&disc)).abs() < 1e-9);
    assert!(blurred.get(60, 60) > 0.99 && blurred.get(60, 30) < blurred.get(60, 45));
    // A constant image stays constant.
    let flat = Image::new(9, 7, vec![0.3; 63]).unwrap();
    assert!(gaussian_blur(&flat, 1.7)
        .unwrap()
        .data()
        .iter()
        .all(|v| (v - 0.3).abs() < 1e-15));
    // A horizontal edge on a pixel centre keeps its 50 % level there and
    // stays antisymmetric; at any sub-pixel position the column sum (the
    // edge position) is unchanged.
    for y0 in [40.0, 40.5, 40.23] {
        let s = RenderSpec {
            blur_sigma: 2.0,
            ..white_on_black(
                Shape::Sine {
                    y0,
                    amplitude: 0.0,
                    wavelength: 10.0,
                    phase: 0.0,
                    x_min: 0.0,
                    x_max: 10.0,
                },
                Kind::Silhouette,
            )
        };
        let img = render(&s).unwrap();
        let column: f64 = (0..s.height).map(|i| img.get(5, i)).sum();
        assert!((column - (y0 + 0.5)).abs() < 1e-12, "{column}");
        if y0 == 40.0 {
            assert!((img.get(5, 40) - 0.5).abs() < 1e-15);
            for k in 1..15 {
                assert!((img.get(5, 40 - k) + img.get(5, 40 + k) - 1.0).abs() < 1e-14);
            }
        }
        if y0 == 40.5 {
            for k in 0..15 {
                assert!((img.get(5, 40 - k) + img.get(5, 41 + k) - 1.0).abs() < 1e-14);
            }
        }
    }
}

// ---------------------------------------------------------------- noise

#[test]
fn noise_is_reproducible_with_the_right_level() {
    let base = RenderSpec {
        width: 256,
        height: 256,
        foreground: 0.7,
        background: 0.3,
        ..RenderSpec::default()
    };
    let clean = render(&base).unwrap();
    let noisy = RenderSpec {
        noise: 0.1,
        seed: 1234,
        ..base.clone()
    };
    let a = render(&noisy).unwrap();
    let b = render(&noisy).unwrap();
    assert_eq!(a, b);
    let c = render(&RenderSpec {
        seed: 1235,
        ..noisy.clone()
    })
    .unwrap();
    assert_ne!(a, c);
    let diff: Vec<f64> = a
        .data()
        .iter()
        .zip(clean.data())
        .map(|(x, y)| x - y)
        .collect();
    let n = diff.len() as f64;
    let mean = diff.iter().sum::<f64>() / n;
    let std = (diff.iter().map(|d| (d - mean).powi(2)).sum::<f64>() / n).sqrt();
    assert!(mean.abs() < 0.002, "{mean}");
    assert!((std - 0.04).abs() / 0.04 < 0.02, "{std}");
}

#[test]
fn quantisation_gives_integer_levels() {
    for (bits, levels) in [(8u8, 255.0), (16, 65535.0)] {
        let img = render(&RenderSpec {
            bits: Some(bits),
            noise: 0.5,
            blur_sigma: 0.8,
            ..RenderSpec::default()
        })
        .unwrap();
        for &v in img.data() {
            assert!((0.0..=1.0).contains(&v));
            let k = v * levels;
            assert!((k - k.round()).abs() < 1e-9, "{v}");
        }
    }
}

// ---------------------------------------------------------------- spec

#[test]
fn invalid_specs_are_rejected_with_the_field_name() {
    let ok = RenderSpec::default();
    let cases: Vec<(RenderSpec, &str)> = vec![
        (
            RenderSpec {
                width: 0,
                ..ok.clone()
            },
            "width",
        ),
        (
            RenderSpec {
                height: 20_001,
                ..ok.clone()
            },
            "height",
        ),
        (
            RenderSpec {
                foreground: 1.5,
                ..ok.clone()
            },
            "foreground",
        ),
        (
            RenderSpec {
                background: f64::NAN,
                ..ok.clone()
            },
            "background",
        ),
        (
            RenderSpec {
                blur_sigma: -1.0,
                ..ok.clone()
            },
            "blur_sigma",
        ),
        (
            RenderSpec {
                noise: f64::INFINITY,
                ..ok.clone()
            },
            "noise",
        ),
        (
            RenderSpec {
                bits: Some(12),
                ..ok.clone()
            },
            "bits",
        ),
        (
            RenderSpec {
                method: Method::Profile { half_width: 0.0 },
                ..ok.clone()
            },
            "half_width",
        ),
        (
            RenderSpec {
                kind: Kind::Contour,
                line_width: 0.0,
                ..ok.clone()
            },
            "line_width",
        ),
        (
            RenderSpec {
                shape: Shape::Circle {
                    cx: 1.0,
                    cy: 1.0,
                    r: -1.0,
                },
                ..ok.clone()
            },
            "r",
        ),
        // Wider than twice the smallest radius of curvature of a star tip.
        (
            RenderSpec {
                kind: Kind::Contour,
                line_width: 2.0 * STAR.min_curvature_radius() + 0.1,
                shape: STAR,
                ..ok.clone()
            },
            "line_width",
        ),
        // Narrow ellipse: a line wider than the ellipse's thickness overlaps
        // itself across the minor axis but still has a proper local width.
        (
            RenderSpec {
                kind: Kind::Contour,
                line_width: 1.9,
                shape: Shape::Ellipse {
                    cx: 100.0,
                    cy: 100.0,
                    a: 60.0,
                    b: 0.9,
                    angle: 0.0,
                },
                ..ok.clone()
            },
            "line_width",
        ),
    ];
    for (s, field) in cases {
        match render(&s) {
            Err(Error::InvalidParameter { name, .. }) => assert_eq!(name, field),
            other => panic!("{field}: {:?}", other.map(|_| ())),
        }
    }
}

#[test]
fn spec_json_forms() {
    let s: RenderSpec = serde_json::from_str(
        r#"{"width": 64, "height": 48, "method": {"profile": {"half_width": 5.0}},
            "shape": {"shape": "ellipse", "cx": 30, "cy": 20, "a": 10, "b": 5, "angle": 0.1},
            "kind": "contour"}"#,
    )
    .unwrap();
    assert_eq!(s.method, Method::Profile { half_width: 5.0 });
    assert_eq!(s.kind, Kind::Contour);
    assert_eq!(s.foreground, RenderSpec::default().foreground);
    let json = serde_json::to_string(&RenderSpec::default()).unwrap();
    assert!(json.contains(r#""method":"coverage""#), "{json}");
    let back: RenderSpec = serde_json::from_str(&json).unwrap();
    assert_eq!(back, RenderSpec::default());
}

#[test]
fn large_star_renders_quickly() {
    let s = RenderSpec {
        width: 1024,
        height: 1024,
        shape: Shape::Star {
            cx: 511.3,
            cy: 512.8,
            r0: 380.0,
            amplitude: 0.2,
            lobes: 8,
            phase: 0.1,
        },
        ..RenderSpec::default()
    };
    let t = std::time::Instant::now();
    let img = render(&s).unwrap();
    let secs = t.elapsed().as_secs_f64();
    // Well under a second in release; generous bound for a busy machine.
    eprintln!("star 1024: {secs} s");
    assert!(secs < 5.0, "{secs} s");
    let area = s.shape.area().unwrap();
    let frac = (sum(&img) - 0.2 * 1024.0 * 1024.0) / 0.6;
    assert!((frac - area).abs() / area < 1e-8);
}

/// The pixel value of a straight edge `x < x0` (bright) through a Gaussian
/// blur `sigma` as a camera records it: the blurred step `Phi((x0 - x) /
/// sigma)` integrated over the pixel `[j - 1/2, j + 1/2]`, with `int Phi =
/// t Phi(t) + phi(t)`.
fn blurred_edge_pixel(x0: f64, sigma: f64, j: f64) -> f64 {
    let phi = |t: f64| (-0.5 * t * t).exp() / (2.0 * PI).sqrt();
    let cdf = |t: f64| 0.5 * libm::erfc(-t / std::f64::consts::SQRT_2);
    let prim = |t: f64| t * cdf(t) + phi(t);
    sigma * (prim((x0 - (j - 0.5)) / sigma) - prim((x0 - (j + 0.5)) / sigma))
}

/// An edge along a column (the worst case: every pixel of a column shares
/// where the edge crosses it) blurred before the pixels integrate
/// ([`vicurve::render::blur::blurred_coverage`]) matches the analytic
/// pixel values at every sub-pixel position to about `0.02 / (k sigma)^2`
/// of the contrast (`k` fine samples per pixel, 8 under a blur of 1 px, 4
/// from 1 px on; measured 9.0e-4, 1.2e-3, 3.1e-4 and 7.9e-5 at blurs of
/// 0.5, 1, 2 and 4 px); blurring the pixel-integrated coverage instead
/// ([`gaussian_blur`]) errs by 1.6e-2 at a blur of 1 px.
#[test]
fn blur_before_the_pixels_integrate_matches_the_analytic_edge() {
    let (w, h) = (80, 8);
    let mut worst_old: f64 = 0.0;
    for (sigma, bound) in [(0.5, 1.4e-3), (1.0, 1.8e-3), (2.0, 5e-4), (4.0, 1.2e-4)] {
        let mut worst: f64 = 0.0;
        for phase in [0.0, 0.13, 0.25, 0.5, 0.77] {
            let x0 = 39.5 + phase;
            let ring = vec![[-50.0, -50.0], [x0, -50.0], [x0, 60.0], [-50.0, 60.0]];
            let got =
                vicurve::render::blur::blurred_coverage(w, h, std::slice::from_ref(&ring), sigma)
                    .unwrap();
            let cov = polygon_coverage(w, h, &[ring]).unwrap();
            let old = gaussian_blur(&Image::new(w, h, cov).unwrap(), sigma).unwrap();
            // Columns whose blur does not reach the image's border.
            for j in 0..w {
                let x = j as f64;
                if x < 5.0 * sigma + 1.0 || x > w as f64 - 2.0 - 5.0 * sigma {
                    continue;
                }
                let want = blurred_edge_pixel(x0, sigma, x);
                worst = worst.max((got[3 * w + j] - want).abs());
                if sigma == 1.0 {
                    worst_old = worst_old.max((old.data()[3 * w + j] - want).abs());
                }
            }
        }
        println!("blur {sigma}: largest error {worst:.1e}");
        assert!(worst > 0.0, "blur {sigma}: no column checked");
        assert!(worst < bound, "blur {sigma}: {worst}");
    }
    println!("blurred after the pixels integrate, blur 1: {worst_old:.1e}");
    assert!(worst_old > 1e-2, "{worst_old}");
}

/// The region below the line `y = 11.3 + 0.3 (x - 20)`, far beyond a
/// 40 x 24 image: an oblique edge, and what a pixel of it holds.
struct ObliqueEdge;

impl ObliqueEdge {
    const Y0: f64 = 11.3;
    const SLOPE: f64 = 0.3;

    fn line(x: f64) -> f64 {
        Self::Y0 + Self::SLOPE * (x - 20.0)
    }

    /// The region, as the renderers take it.
    fn ring() -> Vec<[f64; 2]> {
        vec![
            [-100.0, Self::line(-100.0)],
            [140.0, Self::line(140.0)],
            [140.0, 200.0],
            [-100.0, 200.0],
        ]
    }

    /// The unit normal, towards the region.
    fn normal() -> [f64; 2] {
        let norm = Self::SLOPE.hypot(1.0);
        [-Self::SLOPE / norm, 1.0 / norm]
    }

    /// Pixel `(i, j)` of the edge blurred by a Gaussian of deviation `sd`
    /// px across it: the mean of `Phi(d / sd)` over the pixel's square
    /// (`d` the signed distance), by an `n x n` midpoint rule.
    fn pixel(i: usize, j: usize, sd: f64, n: usize) -> f64 {
        let norm = Self::SLOPE.hypot(1.0);
        let cdf = |t: f64| 0.5 * libm::erfc(-t / std::f64::consts::SQRT_2);
        let mut sum = 0.0;
        for a in 0..n {
            for b in 0..n {
                let x = i as f64 - 0.5 + (a as f64 + 0.5) / n as f64;
                let y = j as f64 - 0.5 + (b as f64 + 0.5) / n as f64;
                sum += cdf((y - Self::line(x)) / norm / sd);
            }
        }
        sum / (n * n) as f64
    }
}

/// A camera sees the scene beyond the image's border too: an oblique
/// blurred edge that crosses the border has, in the border's pixels, the
/// values of the infinite edge (each pixel the mean of `Phi(d / sigma)`
/// over its square, `d` the signed distance to the edge, by a 200 x 200
/// midpoint rule), as in the middle. Repeating the border's pixels
/// instead bends the edge within the blur's reach.
#[test]
fn an_edge_crossing_the_border_stays_straight_to_the_border() {
    let (w, h) = (40, 24);
    let ring = ObliqueEdge::ring();
    for sigma in [1.0, 2.0, 4.0] {
        let got = vicurve::render::blur::blurred_coverage(w, h, std::slice::from_ref(&ring), sigma)
            .unwrap();
        let (mut worst_border, mut worst_middle): (f64, f64) = (0.0, 0.0);
        for j in 0..h {
            for i in 0..w {
                let err = (got[j * w + i] - ObliqueEdge::pixel(i, j, sigma, 200)).abs();
                if i < 3 || i + 3 >= w {
                    worst_border = worst_border.max(err);
                } else {
                    worst_middle = worst_middle.max(err);
                }
            }
        }
        println!("blur {sigma}: border {worst_border:.1e}, middle {worst_middle:.1e}");
        assert!(worst_border < 2e-3, "blur {sigma}: border {worst_border}");
        assert!(worst_border < 3.0 * worst_middle + 1e-4, "blur {sigma}");
    }
}

/// An anisotropic blur (`blurred_coverage_anisotropic`): an oblique straight
/// edge blurred by a Gaussian of covariance `blur² I + [[p, q], [q, -p]]`
/// is the edge blurred across by the covariance's variance along its
/// normal, `n' C n`, each pixel the mean of `Phi(d / sqrt(n' C n))` over
/// its square (`d` the signed distance; a 100 x 100 midpoint rule). An
/// astigmatism along a diagonal and a motion blur (no blur across the
/// motion, the covariance singular) both take Selling's non-axial
/// directions. Within 5e-4 of the contrast (measured 1.3e-6 and 1.4e-4:
/// the blur across is about 1 px, 8 fine samples per pixel); with `q = 0`
/// it is the separable `blurred_coverage_xy` to within the decomposition's
/// floor (a blur of 1e-3 of its size added across: measured 3.4e-7).
#[test]
fn an_anisotropic_blur_renders_an_edge_blurred_along_its_normal() {
    use vicurve::render::blur::{blurred_coverage_anisotropic, blurred_coverage_xy};
    use vicurve::virtual_image::Anisotropy;
    let (w, h) = (40, 24);
    let ring = ObliqueEdge::ring();
    let normal = ObliqueEdge::normal();
    for (blur, a) in [
        (1.5f64, Anisotropy { p: 0.8, q: 1.2 }),
        (1.0, Anisotropy { p: 0.54, q: -0.84 }),
    ] {
        let got =
            blurred_coverage_anisotropic(w, h, std::slice::from_ref(&ring), (blur, a)).unwrap();
        let across = (blur * blur + a.along(normal)).sqrt();
        let mut worst: f64 = 0.0;
        for j in 0..h {
            for i in 6..w - 6 {
                let want = ObliqueEdge::pixel(i, j, across, 100);
                worst = worst.max((got[j * w + i] - want).abs());
            }
        }
        println!("blur {blur}, {a}: blur across {across:.3}, largest error {worst:.1e}");
        assert!(worst < 5e-4, "{worst}");
    }
    // Axis-aligned: the separable renderer's image.
    let (blur, p) = (1.8f64, 1.2);
    let a = Anisotropy { p, q: 0.0 };
    let got = blurred_coverage_anisotropic(w, h, std::slice::from_ref(&ring), (blur, a)).unwrap();
    let xy = ((blur * blur + p).sqrt(), (blur * blur - p).sqrt());
    let want = blurred_coverage_xy(w, h, std::slice::from_ref(&ring), xy).unwrap();
    let worst = got
        .iter()
        .zip(&want)
        .fold(0.0f64, |m, (g, w)| m.max((g - w).abs()));
    assert!(worst < 1e-6, "{worst}");
}
