//! Tests of image interpolation against independent oracles.

use proptest::prelude::*;
use vicurve::interp::{Interpolation, Sampler};
use vicurve::Image;

const KINDS: [Interpolation; 3] = [
    Interpolation::Bilinear,
    Interpolation::CubicBSpline,
    Interpolation::Keys,
];

fn image_from(w: usize, h: usize, f: impl Fn(f64, f64) -> f64) -> Image {
    Image::from_fn(w, h, |x, y| f(x as f64, y as f64))
}

/// Random image: size and pixel values in [0, 1].
fn random_image(max_side: usize) -> impl Strategy<Value = Image> {
    (1..=max_side, 1..=max_side).prop_flat_map(|(w, h)| {
        prop::collection::vec(0.0..1.0f64, w * h)
            .prop_map(move |data| Image::new(w, h, data).unwrap())
    })
}

/// Index k of the sequence 0..n mirrored about its end samples (written
/// independently of the library: reflect until inside).
fn reflect(mut k: i64, n: usize) -> usize {
    let last = n as i64 - 1;
    if last == 0 {
        return 0;
    }
    loop {
        if k < 0 {
            k = -k;
        } else if k > last {
            k = 2 * last - k;
        } else {
            return k as usize;
        }
    }
}

/// Solves a general dense system by Gaussian elimination with partial
/// pivoting (row-major `a`, n x n).
fn gauss_solve(mut a: Vec<f64>, mut b: Vec<f64>) -> Vec<f64> {
    let n = b.len();
    for col in 0..n {
        let piv = (col..n)
            .max_by(|&i, &j| a[i * n + col].abs().total_cmp(&a[j * n + col].abs()))
            .unwrap();
        for k in 0..n {
            a.swap(col * n + k, piv * n + k);
        }
        b.swap(col, piv);
        for r in col + 1..n {
            let f = a[r * n + col] / a[col * n + col];
            for k in col..n {
                a[r * n + k] -= f * a[col * n + k];
            }
            b[r] -= f * b[col];
        }
    }
    let mut x = vec![0.0; n];
    for r in (0..n).rev() {
        let s: f64 = (r + 1..n).map(|k| a[r * n + k] * x[k]).sum();
        x[r] = (b[r] - s) / a[r * n + r];
    }
    x
}

/// Coefficients c of the 1-D cubic spline interpolating s with mirror ends:
/// (c[k-1] + 4 c[k] + c[k+1]) / 6 = s[k], c[-1] = c[1], c[n] = c[n-2],
/// built as a dense matrix by folding the mirrored neighbours in.
fn spline_coefficients_1d(s: &[f64]) -> Vec<f64> {
    let n = s.len();
    let mut a = vec![0.0; n * n];
    for k in 0..n {
        for (off, w) in [(-1i64, 1.0 / 6.0), (0, 4.0 / 6.0), (1, 1.0 / 6.0)] {
            a[k * n + reflect(k as i64 + off, n)] += w;
        }
    }
    gauss_solve(a, s.to_vec())
}

/// The 2-D coefficients: rows, then columns.
fn spline_coefficients(img: &Image) -> Vec<f64> {
    let (w, h) = (img.width(), img.height());
    let mut c = img.data().to_vec();
    for y in 0..h {
        let row = spline_coefficients_1d(&c[y * w..(y + 1) * w]);
        c[y * w..(y + 1) * w].copy_from_slice(&row);
    }
    for x in 0..w {
        let col: Vec<f64> = (0..h).map(|y| c[y * w + x]).collect();
        let col = spline_coefficients_1d(&col);
        for y in 0..h {
            c[y * w + x] = col[y];
        }
    }
    c
}

/// The centred cubic B-spline from its textbook piecewise definition.
fn beta3(x: f64) -> f64 {
    let a = x.abs();
    if a < 1.0 {
        2.0 / 3.0 - a * a + a * a * a / 2.0
    } else if a < 2.0 {
        (2.0 - a).powi(3) / 6.0
    } else {
        0.0
    }
}

/// The spline with coefficients c (mirror-extended) evaluated at (x, y).
fn spline_eval(c: &[f64], w: usize, h: usize, x: f64, y: f64) -> f64 {
    let (fx, fy) = (x.floor() as i64, y.floor() as i64);
    let mut v = 0.0;
    for ky in fy - 2..=fy + 2 {
        for kx in fx - 2..=fx + 2 {
            let ck = c[reflect(ky, h) * w + reflect(kx, w)];
            v += ck * beta3(x - kx as f64) * beta3(y - ky as f64);
        }
    }
    v
}

/// A point of the domain from two numbers in [0, 1].
fn point(img: &Image, u: f64, v: f64) -> (f64, f64) {
    (u * (img.width() - 1) as f64, v * (img.height() - 1) as f64)
}

proptest! {
    #![proptest_config(ProptestConfig::with_cases(128))]

    #[test]
    fn bilinear_reproduces_bilinear_functions(
        w in 1..20usize, h in 1..20usize,
        a in -5.0..5.0f64, b in -5.0..5.0f64, c in -1.0..1.0f64, d in -5.0..5.0f64,
        pts in prop::collection::vec((0.0..=1.0f64, 0.0..=1.0f64), 20),
    ) {
        let f = |x: f64, y: f64| a * x + b * y + c * x * y + d;
        let img = image_from(w, h, f);
        let s = Sampler::new(&img, Interpolation::Bilinear);
        for (u, v) in pts {
            let (x, y) = point(&img, u, v);
            let (val, g) = s.value_gradient(x, y).unwrap();
            prop_assert!((val - f(x, y)).abs() < 1e-11, "{} vs {}", val, f(x, y));
            prop_assert_eq!(s.value(x, y), Some(val));
            // A single column (row) carries no x (y) information.
            if w > 1 {
                prop_assert!((g[0] - (a + c * y)).abs() < 1e-11);
            }
            if h > 1 {
                prop_assert!((g[1] - (b + c * x)).abs() < 1e-11);
            }
        }
    }

    #[test]
    fn interpolating_kinds_are_exact_at_pixel_centres(img in random_image(60)) {
        for kind in KINDS {
            let s = Sampler::new(&img, kind);
            for y in 0..img.height() {
                for x in 0..img.width() {
                    let v = s.value(x as f64, y as f64).unwrap();
                    prop_assert!((v - img.get(x, y)).abs() < 1e-10, "{:?} at ({}, {}): {} vs {}", kind, x, y, v, img.get(x, y));
                }
            }
        }
    }

    #[test]
    fn cubic_bspline_matches_dense_oracle(
        img in random_image(60),
        pts in prop::collection::vec((0.0..=1.0f64, 0.0..=1.0f64), 30),
    ) {
        let s = Sampler::new(&img, Interpolation::CubicBSpline);
        let c = spline_coefficients(&img);
        let (w, h) = (img.width(), img.height());
        let mut probes: Vec<(f64, f64)> = pts.iter().map(|&(u, v)| point(&img, u, v)).collect();
        probes.extend([(0.0, 0.0), ((w - 1) as f64, (h - 1) as f64)]);
        for (x, y) in probes {
            let got = s.value(x, y).unwrap();
            let want = spline_eval(&c, w, h, x, y);
            prop_assert!((got - want).abs() < 1e-10, "({}, {}): {} vs {}", x, y, got, want);
        }
    }

    #[test]
    fn gradients_match_finite_differences(
        img in random_image(16),
        pts in prop::collection::vec((0.0..1.0f64, 0.0..1.0f64), 10),
    ) {
        // Points away from pixel centre lines by 0.05 px (where the bilinear
        // gradient jumps) and from the border by the step.
        let step = 1e-6;
        for kind in KINDS {
            let s = Sampler::new(&img, kind);
            for &(u, v) in &pts {
                let cell = |t: f64, n: usize| -> Option<f64> {
                    if n < 2 {
                        return None;
                    }
                    let k = ((t * (n - 1) as f64).floor()).min((n - 2) as f64);
                    Some(k + 0.05 + 0.9 * (t * (n - 1) as f64 - k).clamp(0.0, 1.0))
                };
                let (x, y) = (cell(u, img.width()), cell(v, img.height()));
                let (x0, y0) = (x.unwrap_or(0.0), y.unwrap_or(0.0));
                let (val, g) = s.value_gradient(x0, y0).unwrap();
                prop_assert_eq!(s.value(x0, y0), Some(val));
                if x.is_some() {
                    let fd = (s.value(x0 + step, y0).unwrap() - s.value(x0 - step, y0).unwrap()) / (2.0 * step);
                    prop_assert!((g[0] - fd).abs() < 1e-6 * (1.0 + fd.abs()), "{:?} d/dx at ({}, {}): {} vs {}", kind, x0, y0, g[0], fd);
                } else {
                    prop_assert_eq!(g[0], 0.0);
                }
                if y.is_some() {
                    let fd = (s.value(x0, y0 + step).unwrap() - s.value(x0, y0 - step).unwrap()) / (2.0 * step);
                    prop_assert!((g[1] - fd).abs() < 1e-6 * (1.0 + fd.abs()), "{:?} d/dy at ({}, {}): {} vs {}", kind, x0, y0, g[1], fd);
                } else {
                    prop_assert_eq!(g[1], 0.0);
                }
            }
        }
    }

    #[test]
    fn cubic_bspline_reproduces_cubics_in_the_interior(
        coef in prop::collection::vec(-1.0..1.0f64, 10),
        pts in prop::collection::vec((20.0..=43.0f64, 20.0..=43.0f64), 20),
    ) {
        // f = sum of c_ij u^i v^j over i + j <= 3, u, v = (x, y) / 32 - 1:
        // the mirrored border disturbs the spline by about |sqrt(3) - 2|^d at
        // d pixels from the border, 4e-12 at d = 20.
        let f = |x: f64, y: f64| {
            let (u, v) = (x / 32.0 - 1.0, y / 32.0 - 1.0);
            let mut acc = 0.0;
            let mut k = 0;
            for i in 0..=3 {
                for j in 0..=3 - i {
                    acc += coef[k] * u.powi(i) * v.powi(j);
                    k += 1;
                }
            }
            acc
        };
        let grad = |x: f64, y: f64| {
            let e = 1e-5;
            [(f(x + e, y) - f(x - e, y)) / (2.0 * e), (f(x, y + e) - f(x, y - e)) / (2.0 * e)]
        };
        let img = image_from(64, 64, f);
        let s = Sampler::new(&img, Interpolation::CubicBSpline);
        for (x, y) in pts {
            let (val, g) = s.value_gradient(x, y).unwrap();
            prop_assert!((val - f(x, y)).abs() < 1e-9, "{} vs {}", val, f(x, y));
            let gw = grad(x, y);
            prop_assert!((g[0] - gw[0]).abs() < 1e-8 && (g[1] - gw[1]).abs() < 1e-8);
        }
    }

    #[test]
    fn keys_reproduces_quadratics_away_from_the_border(
        coef in prop::collection::vec(-1.0..1.0f64, 6),
        w in 4..20usize, h in 4..20usize,
        pts in prop::collection::vec((0.0..=1.0f64, 0.0..=1.0f64), 20),
    ) {
        let f = |x: f64, y: f64| {
            let (u, v) = (x / 8.0, y / 8.0);
            coef[0] + coef[1] * u + coef[2] * v + coef[3] * u * u + coef[4] * u * v + coef[5] * v * v
        };
        let img = image_from(w, h, f);
        let s = Sampler::new(&img, Interpolation::Keys);
        for (a, b) in pts {
            // The stencil stays inside for points in [1, n - 2].
            let x = 1.0 + a * (w - 3) as f64;
            let y = 1.0 + b * (h - 3) as f64;
            let v = s.value(x, y).unwrap();
            prop_assert!((v - f(x, y)).abs() < 1e-12, "{} vs {}", v, f(x, y));
        }
    }
}

#[test]
fn outside_the_domain_is_none() {
    let img = image_from(7, 5, |x, y| x + 2.0 * y);
    for kind in KINDS {
        let s = Sampler::new(&img, kind);
        assert_eq!(s.kind(), kind);
        assert_eq!((s.width(), s.height()), (7, 5));
        for (x, y) in [
            (-1e-9, 2.0),
            (6.0 + 1e-9, 2.0),
            (3.0, -1e-9),
            (3.0, 4.0 + 1e-9),
            (-0.5, -0.5),
            (f64::NAN, 1.0),
            (1.0, f64::NAN),
            (f64::INFINITY, 1.0),
            (f64::NEG_INFINITY, 1.0),
            (1e300, 1.0),
        ] {
            assert_eq!(s.value(x, y), None, "{kind:?} ({x}, {y})");
            assert_eq!(s.value_gradient(x, y), None, "{kind:?} ({x}, {y})");
        }
        for (x, y) in [(0.0, 0.0), (6.0, 0.0), (0.0, 4.0), (6.0, 4.0)] {
            let v = s.value(x, y).unwrap();
            assert!((v - (x + 2.0 * y)).abs() < 1e-12, "{kind:?}");
            assert!(s.value_gradient(x, y).is_some());
        }
    }
}

#[test]
fn degenerate_images_do_not_panic() {
    for (w, h) in [(1, 1), (1, 9), (9, 1), (2, 1), (1, 2)] {
        let img = image_from(w, h, |x, y| (x * 3.0 + y * 5.0).sin());
        for kind in KINDS {
            let s = Sampler::new(&img, kind);
            for i in 0..=20 {
                let t = i as f64 / 20.0;
                let (x, y) = ((w - 1) as f64 * t, (h - 1) as f64 * t);
                let (v, g) = s.value_gradient(x, y).unwrap();
                assert!(v.is_finite() && g[0].is_finite() && g[1].is_finite());
                // A single row (column) interpolates along its own axis only.
                if w == 1 {
                    assert_eq!(g[0], 0.0);
                }
                if h == 1 {
                    assert_eq!(g[1], 0.0);
                }
            }
            for y in 0..h {
                for x in 0..w {
                    let v = s.value(x as f64, y as f64).unwrap();
                    assert!((v - img.get(x, y)).abs() < 1e-12, "{kind:?} {w}x{h}");
                }
            }
        }
    }
}

#[test]
fn names_round_trip() {
    assert_eq!(Interpolation::default(), Interpolation::Bilinear);
    for kind in KINDS {
        let json = serde_json::to_string(&kind).unwrap();
        assert_eq!(json, format!("\"{}\"", kind.name()));
        assert_eq!(serde_json::from_str::<Interpolation>(&json).unwrap(), kind);
        assert_eq!(kind.to_string().parse::<Interpolation>().unwrap(), kind);
    }
    assert_eq!(
        "Cubic-B-Spline".parse::<Interpolation>().unwrap(),
        Interpolation::CubicBSpline
    );
    assert!("bicubic".parse::<Interpolation>().is_err());
}

proptest! {
    /// `pixel` reads the recorded value (to the last bit, not through the
    /// cubic B-spline's coefficients), which `value` interpolates at the
    /// pixel centre, for every kind and image size (including one-pixel
    /// sides, where a bilinear sampler keeps a padded copy); `None`
    /// outside.
    #[test]
    fn pixel_is_the_value_at_the_centre(img in random_image(7)) {
        for kind in KINDS {
            let s = Sampler::new(&img, kind);
            for y in 0..img.height() {
                for x in 0..img.width() {
                    let p = s.pixel(x, y).unwrap();
                    prop_assert_eq!(p.to_bits(), img.get(x, y).to_bits(), "{:?} ({}, {})", kind, x, y);
                    let v = s.value(x as f64, y as f64).unwrap();
                    prop_assert!((p - v).abs() < 1e-9, "{kind:?} ({x}, {y})");
                }
            }
            prop_assert!(s.pixel(img.width(), 0).is_none());
            prop_assert!(s.pixel(0, img.height()).is_none());
        }
    }
}

proptest! {
    /// The gray range is the 99.5th minus the 0.5th percentile of the
    /// pixels (all of them in an image this small), each the value a sort
    /// puts at that rank.
    #[test]
    fn the_gray_range_is_between_two_percentiles(img in random_image(40)) {
        let mut sorted = img.data().to_vec();
        sorted.sort_by(f64::total_cmp);
        let at = |q: f64| sorted[((sorted.len() - 1) as f64 * q).round() as usize];
        let range = Sampler::new(&img, Interpolation::Bilinear).gray_range();
        prop_assert_eq!(range.to_bits(), (at(0.995) - at(0.005)).to_bits());
    }
}

/// A bilinear sampler shares the image's pixels; changing the image
/// afterwards copies them first, so the sampler keeps what it was made from.
#[test]
fn a_sampler_keeps_its_pixels_when_the_image_changes() {
    let mut img = image_from(4, 3, |x, y| x + 10.0 * y);
    let s = Sampler::new(&img, Interpolation::Bilinear);
    img.data_mut()[5] = -1.0;
    assert_eq!(img.get(1, 1), -1.0);
    assert_eq!(s.pixel(1, 1), Some(11.0));
    assert!((s.value(1.5, 1.0).unwrap() - 11.5).abs() < 1e-12);
}

/// The gray-level step of an image read from an integer format is found
/// for every interpolation kind (the cubic one reads its pixels back
/// through the prefilter); rescaled or floating data have none.
#[test]
fn the_quantum_of_integer_levels_is_found() {
    let levels = |q: f64| image_from(37, 23, move |x, y| ((x * 7.0 + y * 13.0) % 200.0 + 3.0) * q);
    for kind in KINDS {
        let at = |img: &Image| Sampler::new(img, kind).quantum();
        assert_eq!(at(&levels(1.0 / 255.0)), Some(1.0 / 255.0), "{kind:?}");
        assert_eq!(at(&levels(1.0 / 65535.0)), Some(1.0 / 65535.0), "{kind:?}");
        assert_eq!(at(&levels(1.0)), Some(1.0), "{kind:?}");
        // 8-bit levels in a 16-bit file (steps of 257): still 1/255.
        assert_eq!(at(&levels(257.0 / 65535.0)), Some(1.0 / 255.0), "{kind:?}");
        assert_eq!(at(&levels(0.9 / 255.0)), None, "{kind:?}");
        let float = image_from(37, 23, |x, y| (0.1 * x).sin() * (0.07 * y).cos());
        assert_eq!(at(&float), None, "{kind:?}");
    }
}

/// The pixels' noise is found on an image with an edge: within 5 % of the
/// rendered noise without quantisation and in 16 bits, within 8 % in 8
/// bits (1.5 gray levels, with the rounding's own `q^2 / 12`; the trimmed
/// share falls among whole levels), and 0 on a noiseless image (to the
/// floating-point rounding of its levels).
#[test]
fn the_pixel_noise_is_found_beside_an_edge() {
    use vicurve::render::{render, RenderSpec};
    use vicurve::truth::Shape;
    let noise_of = |noise: f64, bits: Option<u8>| {
        let spec = RenderSpec {
            width: 256,
            height: 256,
            shape: Shape::Circle {
                cx: 128.3,
                cy: 127.6,
                r: 80.0,
            },
            blur_sigma: 1.0,
            noise,
            seed: 3,
            bits,
            ..RenderSpec::default()
        };
        let img = render(&spec).unwrap();
        Sampler::new(&img, Interpolation::CubicBSpline).pixel_noise()
    };
    // Contrast 0.6 (the default 0.8 on 0.2).
    for (noise, bits, tolerance) in [
        (0.02, None, 0.05),
        (0.01, Some(16), 0.05),
        (0.01, Some(8), 0.08),
    ] {
        let found = noise_of(noise, bits);
        let q = bits.map_or(0.0, |b| 1.0 / ((1u32 << b) - 1) as f64);
        let expected = ((0.6 * noise).powi(2) + q * q / 12.0).sqrt();
        assert!(
            (found / expected - 1.0).abs() < tolerance,
            "{noise} {bits:?}: {found:e} for {expected:e}"
        );
    }
    assert!(noise_of(0.0, None) < 1e-9);
    assert!(noise_of(0.0, Some(8)) < 1e-9);
}

/// Beyond the border the clamped value is the border's: the image extended
/// by its border's values.
#[test]
fn clamped_values_extend_the_border() {
    let image = Image::from_fn(5, 4, |x, y| (x * x) as f64 + 0.3 * y as f64);
    let sampler = Sampler::new(&image, Interpolation::CubicBSpline);
    for (x, y, at) in [
        (-2.0, 1.5, (0.0, 1.5)),
        (7.5, -1.0, (4.0, 0.0)),
        (2.25, 9.0, (2.25, 3.0)),
    ] {
        assert_eq!(sampler.value_clamped(x, y), sampler.value(at.0, at.1));
    }
    assert_eq!(sampler.value_clamped(1.0, 1.0), sampler.value(1.0, 1.0));
    assert_eq!(sampler.value_clamped(f64::NAN, 1.0), None);
}
