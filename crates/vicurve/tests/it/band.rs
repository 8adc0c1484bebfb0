//! Band coordinates against exact geometry.

use vicurve::band::Band;
use vicurve::curve::InitialCurve;
use vicurve::spline::Basis;
use vicurve::virtual_image::Kind;
use vicurve::Error;

#[test]
fn circle_band_has_exact_coordinates_and_all_pixels() {
    let (cx, cy, r0, half) = (100.4, 99.7, 50.0, 6.0);
    let curve = InitialCurve::Circle { cx, cy, r: r0 }.to_curve().unwrap();
    let basis = Basis::new(3, 10, curve.param_length(), true).unwrap();
    let band = Band::build(&curve, &basis, half, Kind::Silhouette, 200, 200).unwrap();
    // Every pixel with | |X - c| - r0 | < R, and no other.
    let mut expected = 0;
    for y in 0..200 {
        for x in 0..200 {
            let d = (x as f64 - cx).hypot(y as f64 - cy) - r0;
            if d.abs() < half - 1e-6 {
                expected += 1;
            }
        }
    }
    assert!(
        (band.len() as i64 - expected as i64).abs() <= 2,
        "{} vs {expected}",
        band.len()
    );
    for ((p, &r), &s) in band.positions().iter().zip(band.r()).zip(band.s()) {
        let d = (p[0] - cx).hypot(p[1] - cy) - r0;
        assert!((r - d).abs() < 1e-6, "r {r} vs {d}");
        // s is (to the chord-length parametrisation's ~1e-4) the arc length
        // from the rightmost point, counterclockwise on screen.
        let theta = (-(p[1] - cy))
            .atan2(p[0] - cx)
            .rem_euclid(std::f64::consts::TAU);
        let ds = (s - r0 * theta).abs();
        let ds = ds.min((ds - curve.param_length()).abs());
        assert!(ds < 1e-3, "s {s} vs {}", r0 * theta);
    }
}

#[test]
fn open_curve_band_stops_at_the_ends() {
    let curve = InitialCurve::Segment {
        x0: 20.0,
        y0: 50.3,
        x1: 80.0,
        y1: 50.3,
    }
    .to_curve()
    .unwrap();
    let basis = Basis::new(3, 4, curve.param_length(), false).unwrap();
    let band = Band::build(&curve, &basis, 5.0, Kind::Contour, 100, 100).unwrap();
    for p in band.positions() {
        assert!(
            p[0] > 20.0 - 1e-9 && p[0] < 80.0 + 1e-9,
            "pixel past an end: {p:?}"
        );
        assert!((p[1] - 50.3).abs() < 5.0);
    }
    // Rows 46..=55 (|r| < 5), columns 21..=79; the end columns 20 and 80
    // lie on the ends' boundary lines and may go either way.
    assert!(
        band.len() >= 10 * 59 && band.len() <= 10 * 61,
        "{}",
        band.len()
    );
}

#[test]
fn pixels_beyond_the_centre_of_curvature_are_left_out() {
    // A circle of radius 8 with a band of 10: the inner side stops short of
    // the centre.
    let (cx, cy) = (50.0, 50.0);
    let curve = InitialCurve::Circle { cx, cy, r: 8.0 }.to_curve().unwrap();
    let basis = Basis::new(3, 6, curve.param_length(), true).unwrap();
    let band = Band::build(&curve, &basis, 10.0, Kind::Silhouette, 100, 100).unwrap();
    for (p, &r) in band.positions().iter().zip(band.r()) {
        let d = (p[0] - cx).hypot(p[1] - cy);
        assert!(
            d > 0.5,
            "pixel at the centre of curvature kept: {p:?}, r = {r}"
        );
        // 1 - kappa r > 0.1 with kappa = -1/8 (convex, outward normal).
        assert!(r > -7.2 - 1e-6, "r = {r}");
    }
}

/// A closed curve whose band leaves the image keeps the band's pixels in
/// the image, with the coordinates they have in a band that fits (the same
/// circle 50 px further from the border of a wider image); a curve that
/// leaves the image is an error.
#[test]
fn a_band_cut_by_the_border_and_a_curve_outside_the_image() {
    let circle = |cx: f64| {
        InitialCurve::Circle {
            cx,
            cy: 50.0,
            r: 15.0,
        }
        .to_curve()
        .unwrap()
    };
    let (curve, whole) = (circle(20.0), circle(70.0));
    let basis = Basis::new(3, 8, curve.param_length(), true).unwrap();
    let cut = Band::build(&curve, &basis, 10.0, Kind::Silhouette, 100, 100).unwrap();
    let fits = Band::build(&whole, &basis, 10.0, Kind::Silhouette, 150, 100).unwrap();
    assert!(cut.clipped() && !fits.clipped());
    let mut kept: Vec<([f64; 2], f64, f64)> = fits
        .positions()
        .iter()
        .zip(fits.r())
        .zip(fits.s())
        .filter(|((p, _), _)| p[0] >= 50.0)
        .map(|((p, &r), &s)| ([p[0] - 50.0, p[1]], r, s))
        .collect();
    let mut got: Vec<([f64; 2], f64, f64)> = cut
        .positions()
        .iter()
        .zip(cut.r())
        .zip(cut.s())
        .map(|((p, &r), &s)| (*p, r, s))
        .collect();
    let key = |a: &([f64; 2], f64, f64)| (a.0[1] as i64, a.0[0] as i64);
    kept.sort_by_key(key);
    got.sort_by_key(key);
    assert!(
        got.len() < fits.len() && got.len() == kept.len(),
        "{} {}",
        got.len(),
        kept.len()
    );
    let length = curve.param_length();
    for (g, k) in got.iter().zip(&kept) {
        assert_eq!(g.0, k.0);
        // `s` from the same start, to the closed curve's period.
        let ds = (g.2 - k.2).abs();
        assert!(
            (g.1 - k.1).abs() < 1e-9 && ds.min(length - ds) < 1e-9,
            "{g:?} {k:?}"
        );
    }
    let curve = InitialCurve::Circle {
        cx: 10.0,
        cy: 50.0,
        r: 15.0,
    }
    .to_curve()
    .unwrap();
    let basis = Basis::new(3, 8, curve.param_length(), true).unwrap();
    assert!(matches!(
        Band::build(&curve, &basis, 2.0, Kind::Silhouette, 100, 100),
        Err(Error::CurveOutsideImage { .. })
    ));
}

/// An open curve's pixel-edge band may be cut by the border beyond the
/// profile's transition (a noisy image's wide band, whose flat levels
/// there only fix the gray levels): it keeps the pixels in the image, the
/// same as in a wider image. The paper's profile, whose band is all
/// transition, and a transition that leaves the image, are errors.
#[test]
fn an_open_pixel_edge_band_is_cut_by_the_border_beyond_its_transition() {
    use vicurve::virtual_image::Profile;
    // Tilted by 30 degrees: at its end, x = 97, a 10 px band reaches x =
    // 102, past the last pixel centre, its transition (3.25 px at a 1 px
    // blur) x = 98.6.
    let segment = |x1: f64| {
        InitialCurve::Segment {
            x0: 30.0,
            y0: 50.3,
            x1,
            y1: 50.3 + (x1 - 30.0) * 30f64.to_radians().tan(),
        }
        .to_curve()
        .unwrap()
    };
    let curve = segment(97.0);
    let basis = Basis::new(3, 4, curve.param_length(), false).unwrap();
    let edge = Profile::pixel_edge(1.0);
    assert_eq!(edge.transition_half_width(), Some(3.25));
    let cut = Band::build(&curve, &basis, 10.0, edge, 100, 100).unwrap();
    let fits = Band::build(&curve, &basis, 10.0, edge, 150, 100).unwrap();
    assert!(cut.clipped() && !fits.clipped());
    let inside = |p: &[f64; 2]| p[0] <= 99.0;
    assert!(cut.positions().iter().all(inside));
    let kept: Vec<([f64; 2], f64)> = fits
        .positions()
        .iter()
        .zip(fits.r())
        .filter(|(p, _)| inside(p))
        .map(|(p, &r)| (*p, r))
        .collect();
    let got: Vec<([f64; 2], f64)> = cut
        .positions()
        .iter()
        .zip(cut.r())
        .map(|(p, &r)| (*p, r))
        .collect();
    assert!(got.len() < fits.len(), "{} of {}", got.len(), fits.len());
    assert_eq!(got, kept);
    assert!(matches!(
        Band::build(&curve, &basis, 10.0, Kind::Silhouette, 100, 100),
        Err(Error::BandOutsideImage { .. })
    ));
    // Ending at the last pixel centre, the transition leaves the image.
    let curve = segment(99.0);
    let basis = Basis::new(3, 4, curve.param_length(), false).unwrap();
    assert!(matches!(
        Band::build(&curve, &basis, 10.0, edge, 100, 100),
        Err(Error::BandOutsideImage { .. })
    ));
}

/// A band with a margin holds the pixels out to `R + margin` and counts
/// those within `R` of the curve displaced by `U` (here uniform: the basis
/// is a partition of unity), with their full weights.
#[test]
fn a_windowed_band_counts_the_pixels_around_the_displaced_curve() {
    use vicurve::fit::Coords;
    let (cx, cy, r0, half, margin) = (100.4, 99.7, 50.0, 3.0, 0.5);
    let curve = InitialCurve::Circle { cx, cy, r: r0 }.to_curve().unwrap();
    let basis = Basis::new(3, 10, curve.param_length(), true).unwrap();
    let mut band = Band::build_windowed(
        &curve,
        &basis,
        half,
        margin,
        Kind::Silhouette,
        200,
        200,
        Coords::Exact,
    )
    .unwrap();
    let wide = Band::build(&curve, &basis, half + margin, Kind::Silhouette, 200, 200).unwrap();
    assert_eq!(band.positions(), wide.positions());
    assert_eq!(band.half_width(), half);
    assert_eq!(band.margin(), margin);
    let (r, full) = (band.r().to_vec(), band.full_weights().to_vec());
    let counted = |u: f64| {
        let inside: Vec<usize> = (0..r.len()).filter(|&i| (r[i] - u).abs() < half).collect();
        let sum: f64 = inside.iter().map(|&i| full[i]).sum();
        (inside.len(), sum)
    };
    assert_eq!(band.inside(), counted(0.0).0);
    assert!(band.inside() < band.len());
    for u in [0.3, -0.45] {
        let lambda = vec![u; basis.n_functions()];
        let sum = band.recentre(&basis, &lambda);
        let (inside, expected) = counted(u);
        assert_eq!(band.inside(), inside, "U = {u}");
        assert!(
            (sum - expected).abs() < 1e-9 * expected,
            "U = {u}: {sum} vs {expected}"
        );
    }
    for bad in [-0.1, f64::NAN] {
        let err = Band::build_windowed(
            &curve,
            &basis,
            half,
            bad,
            Kind::Silhouette,
            200,
            200,
            Coords::Exact,
        );
        assert!(matches!(err, Err(Error::InvalidParameter { .. })), "{bad}");
    }
}

/// A windowed band's weight sum has the same bits however many threads
/// share the work (a band of several of the window's chunks).
#[test]
fn a_windowed_band_sums_alike_on_any_number_of_threads() {
    use vicurve::fit::Coords;
    let curve = InitialCurve::Circle {
        cx: 1600.4,
        cy: 1599.7,
        r: 1500.0,
    }
    .to_curve()
    .unwrap();
    let basis = Basis::new(3, 200, curve.param_length(), true).unwrap();
    let mut band = Band::build_windowed(
        &curve,
        &basis,
        6.0,
        1.0,
        Kind::Silhouette,
        3200,
        3200,
        Coords::Exact,
    )
    .unwrap();
    assert!(band.len() > 20 * 4096, "{} pixels", band.len());
    let lambda: Vec<f64> = (0..basis.n_functions())
        .map(|k| 0.4 * (k as f64 * 0.7).sin())
        .collect();
    let sums: Vec<u64> = [1, 2, 3, 4, 5, 7, 8]
        .into_iter()
        .map(|threads| {
            let pool = rayon::ThreadPoolBuilder::new()
                .num_threads(threads)
                .build()
                .unwrap();
            pool.install(|| band.recentre(&basis, &lambda)).to_bits()
        })
        .collect();
    assert!(sums.iter().all(|s| *s == sums[0]), "{sums:?}");
}
