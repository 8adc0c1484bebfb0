//! Ground-truth geometry against independent oracles: closed forms, brute
//! force (dense sampling of independently written parametrisations, refined
//! by golden section), and hand-computed statistics.

use std::f64::consts::{PI, TAU};

use proptest::prelude::*;
use vicurve::render::Truth;
use vicurve::render::{Kind, Method, RenderSpec};
use vicurve::truth::{evaluate, Shape};
use vicurve::Error;

/// Independent parametrisation of each shape (written from the
/// documentation, not from the library code).
fn param_point(shape: &Shape, s: f64) -> [f64; 2] {
    match *shape {
        Shape::Circle { cx, cy, r } => [cx + r * s.cos(), cy - r * s.sin()],
        Shape::Ellipse {
            cx,
            cy,
            a,
            b,
            angle,
        } => {
            // a-axis unit vector on screen, counterclockwise on screen.
            let ua = [angle.cos(), -angle.sin()];
            // b-axis: a-axis turned by +90° counterclockwise on screen.
            let ub = [-angle.sin(), -angle.cos()];
            let (c, sn) = (a * s.cos(), b * s.sin());
            [cx + c * ua[0] + sn * ub[0], cy + c * ua[1] + sn * ub[1]]
        }
        Shape::Star {
            cx,
            cy,
            r0,
            amplitude,
            lobes,
            phase,
        } => {
            let r = r0 * (1.0 + amplitude * (lobes as f64 * s + phase).cos());
            [cx + r * s.cos(), cy - r * s.sin()]
        }
        Shape::Polygon { sides, .. } => {
            // Linear between the vertices, edge k over [2πk/n, 2π(k+1)/n].
            let h = TAU / sides as f64;
            let k = (s / h).floor();
            let t = s / h - k;
            let (a, b) = (polygon_vertex(shape, k), polygon_vertex(shape, k + 1.0));
            [a[0] + t * (b[0] - a[0]), a[1] + t * (b[1] - a[1])]
        }
        Shape::Sine {
            y0,
            amplitude,
            wavelength,
            phase,
            ..
        } => [s, y0 + amplitude * (TAU * s / wavelength + phase).sin()],
    }
}

/// Vertex `k` of a polygon, from its documentation.
fn polygon_vertex(shape: &Shape, k: f64) -> [f64; 2] {
    let Shape::Polygon {
        cx,
        cy,
        r,
        sides,
        angle,
    } = *shape
    else {
        panic!("not a polygon");
    };
    let th = angle + TAU * k / sides as f64;
    [cx + r * th.cos(), cy - r * th.sin()]
}

/// Brute-force unsigned distance: `n` samples over `[lo, hi]`, golden
/// section around the best one.
fn brute_distance(shape: &Shape, q: [f64; 2], lo: f64, hi: f64, n: usize) -> f64 {
    let d2 = |s: f64| {
        let p = param_point(shape, s);
        (p[0] - q[0]).powi(2) + (p[1] - q[1]).powi(2)
    };
    let h = (hi - lo) / n as f64;
    let best = (0..=n)
        .map(|i| lo + i as f64 * h)
        .min_by(|a, b| d2(*a).total_cmp(&d2(*b)))
        .unwrap();
    let (mut a, mut b) = (best - h, best + h);
    let g = 0.5 * (5f64.sqrt() - 1.0);
    for _ in 0..120 {
        let c = b - g * (b - a);
        let d = a + g * (b - a);
        if d2(c) < d2(d) {
            b = d;
        } else {
            a = c;
        }
    }
    d2(0.5 * (a + b)).min(d2(best)).sqrt()
}

/// Independent inside test (true: on the -n side).
fn inside(shape: &Shape, q: [f64; 2]) -> bool {
    match *shape {
        Shape::Circle { cx, cy, r } => (q[0] - cx).hypot(q[1] - cy) < r,
        Shape::Ellipse {
            cx,
            cy,
            a,
            b,
            angle,
        } => {
            let (x, y) = (q[0] - cx, q[1] - cy);
            let u = x * angle.cos() - y * angle.sin();
            let v = -x * angle.sin() - y * angle.cos();
            (u / a).powi(2) + (v / b).powi(2) < 1.0
        }
        Shape::Star {
            cx,
            cy,
            r0,
            amplitude,
            lobes,
            phase,
        } => {
            let (x, y) = (q[0] - cx, -(q[1] - cy));
            let th = y.atan2(x);
            x.hypot(y) < r0 * (1.0 + amplitude * (lobes as f64 * th + phase).cos())
        }
        Shape::Polygon {
            cx,
            cy,
            r,
            sides,
            angle,
        } => {
            // Inside the inscribed circle of every edge's half-plane: the
            // polar angle of q relative to the middle of its sector.
            let (x, y) = (q[0] - cx, -(q[1] - cy));
            let h = TAU / sides as f64;
            let rel = (y.atan2(x) - angle).rem_euclid(h) - 0.5 * h;
            x.hypot(y) * rel.cos() < r * (0.5 * h).cos()
        }
        Shape::Sine { .. } => q[1] < param_point(shape, q[0])[1],
    }
}

fn check_against_brute(shape: &Shape, q: [f64; 2], lo: f64, hi: f64) {
    let d = shape.signed_distance(q[0], q[1]);
    let brute = brute_distance(shape, q, lo, hi, 100_000);
    assert!(
        (d.abs() - brute).abs() < 1e-9,
        "{shape:?} at {q:?}: {d} vs brute {brute}"
    );
    if brute > 1e-9 {
        assert_eq!(d < 0.0, inside(shape, q), "sign at {q:?}: {d}");
    }
    // The closest point is on the curve at that distance, along the normal.
    let (p, n) = shape.closest_point(q[0], q[1]);
    assert!(((q[0] - p[0]).hypot(q[1] - p[1]) - d.abs()).abs() < 1e-9);
    assert!((n[0].hypot(n[1]) - 1.0).abs() < 1e-12);
    let along = (q[0] - p[0]) * n[0] + (q[1] - p[1]) * n[1];
    assert!((along - d).abs() < 1e-8, "{along} vs {d}");
}

/// A five-lobed star, radius 40 +- 10 px.
const STAR: Shape = Shape::Star {
    cx: 60.3,
    cy: 58.9,
    r0: 40.0,
    amplitude: 0.25,
    lobes: 5,
    phase: 0.4,
};

fn ellipse() -> Shape {
    Shape::Ellipse {
        cx: 50.2,
        cy: 40.7,
        a: 35.0,
        b: 12.0,
        angle: 0.6,
    }
}

/// A pentagon, circumradius 30 px.
const PENTAGON: Shape = Shape::Polygon {
    cx: 50.4,
    cy: 49.7,
    r: 30.0,
    sides: 5,
    angle: 0.3,
};

fn sine() -> Shape {
    Shape::Sine {
        y0: 50.3,
        amplitude: 6.0,
        wavelength: 40.0,
        phase: 0.7,
        x_min: 10.0,
        x_max: 90.0,
    }
}

proptest! {
    #![proptest_config(ProptestConfig::with_cases(48))]

    #[test]
    fn circle_matches_closed_form(x in -50.0f64..150.0, y in -50.0f64..150.0) {
        let (cx, cy, r) = (50.3, 49.6, 31.7);
        let shape = Shape::Circle { cx, cy, r };
        let exact = (x - cx).hypot(y - cy) - r;
        prop_assert!((shape.signed_distance(x, y) - exact).abs() < 1e-12);
    }

    #[test]
    fn ellipse_matches_brute_force(x in -10.0f64..110.0, y in -10.0f64..100.0) {
        check_against_brute(&ellipse(), [x, y], 0.0, TAU);
    }

    #[test]
    fn star_matches_brute_force(x in 0.0f64..120.0, y in 0.0f64..120.0) {
        check_against_brute(&STAR, [x, y], 0.0, TAU);
    }

    #[test]
    fn star_near_curve_matches_brute_force(s in 0.0f64..TAU, off in -6.0f64..6.0) {
        // Points near the curve, where the concave bays are.
        let shape = STAR;
        let p = param_point(&shape, s);
        let p2 = param_point(&shape, s + 1e-6);
        let t = [(p2[0] - p[0]) / 1e-6, (p2[1] - p[1]) / 1e-6];
        let v = t[0].hypot(t[1]);
        let n = [-t[1] / v, t[0] / v];
        check_against_brute(&shape, [p[0] + off * n[0], p[1] + off * n[1]], 0.0, TAU);
    }

    #[test]
    fn polygon_matches_brute_force(x in 0.0f64..100.0, y in 0.0f64..100.0) {
        // Includes the wedges beyond the corners, where the closest point
        // is a vertex.
        check_against_brute(&PENTAGON, [x, y], 0.0, TAU);
    }

    #[test]
    fn sine_matches_brute_force(x in -30.0f64..130.0, y in 20.0f64..80.0) {
        // Includes points beyond x_min / x_max: distance to the infinite sine.
        check_against_brute(&sine(), [x, y], x - 80.0, x + 80.0);
    }
}

#[test]
fn concave_star_points_find_the_global_minimum() {
    // Deep bays: points on the bisector of a bay, just outside and inside,
    // and far inside near the centre, have two or more equally good local
    // minima nearby; brute force decides.
    let shape = Shape::Star {
        cx: 0.0,
        cy: 0.0,
        r0: 50.0,
        amplitude: 0.4,
        lobes: 6,
        phase: 0.0,
    };
    // Bays (r minimal) at lobes*θ = π.
    for k in 0..6 {
        let th = (PI + TAU * k as f64) / 6.0;
        for rho in [5.0, 20.0, 29.0, 30.0, 30.5, 33.0, 40.0, 60.0] {
            let q = [rho * th.cos() + 1e-3 * k as f64, -rho * th.sin()];
            check_against_brute(&shape, q, 0.0, TAU);
        }
    }
    check_against_brute(&shape, [0.0, 0.0], 0.0, TAU);
}

#[test]
fn eccentric_ellipse_near_its_evolute() {
    let shape = Shape::Ellipse {
        cx: 0.0,
        cy: 0.0,
        a: 100.0,
        b: 5.0,
        angle: 0.0,
    };
    // The evolute's cusp on the major axis is at (a² - b²)/a = 99.75.
    for x in [0.0, 10.0, 50.0, 99.0, 99.7, 99.75, 99.8, 100.0, 101.0] {
        for y in [0.0, 0.01, 0.5, -2.0, 4.9, 6.0] {
            check_against_brute(&shape, [x, y], 0.0, TAU);
        }
    }
}

#[test]
fn sign_and_normal_conventions() {
    let c = Shape::Circle {
        cx: 10.0,
        cy: 20.0,
        r: 5.0,
    };
    assert!((c.signed_distance(10.0, 10.0) - 5.0).abs() < 1e-12);
    assert!((c.signed_distance(11.0, 20.0) + 4.0).abs() < 1e-12);
    // Top of the circle on screen: outward normal points up (-y).
    let (p, n) = c.closest_point(10.0, 0.0);
    assert!((p[0] - 10.0).abs() < 1e-12 && (p[1] - 15.0).abs() < 1e-12);
    assert!(n[0].abs() < 1e-12 && (n[1] + 1.0).abs() < 1e-12);
    // The sine: positive below (larger y), normal (-y', 1)/|.|.
    let s = sine();
    assert!(s.signed_distance(30.0, 200.0) > 0.0);
    assert!(s.signed_distance(30.0, -200.0) < 0.0);
    let (p, n) = s.closest_point(25.0, param_point(&s, 25.0)[1] + 1e-3);
    let slope = 6.0 * TAU / 40.0 * (TAU * p[0] / 40.0 + 0.7).cos();
    let v = slope.hypot(1.0);
    assert!((n[0] + slope / v).abs() < 1e-6 && (n[1] - 1.0 / v).abs() < 1e-6);
    // Ellipse with angle π/2: the a axis points up on screen.
    let e = Shape::Ellipse {
        cx: 0.0,
        cy: 0.0,
        a: 10.0,
        b: 2.0,
        angle: PI / 2.0,
    };
    assert!(e.signed_distance(0.0, -10.0).abs() < 1e-12);
    assert!((e.signed_distance(2.0, 0.0)).abs() < 1e-12);
    assert!(e.signed_distance(5.0, 0.0) > 0.0);
}

#[test]
fn polyline_spacing_orientation_and_closure() {
    for shape in [
        STAR,
        ellipse(),
        Shape::Circle {
            cx: 3.0,
            cy: 4.0,
            r: 7.0,
        },
    ] {
        let pts = shape.polyline(0.5).unwrap();
        let n = pts.len();
        assert!(n > 10);
        let mut twice_area = 0.0;
        for i in 0..n {
            let (a, b) = (pts[i], pts[(i + 1) % n]);
            let step = (a[0] - b[0]).hypot(a[1] - b[1]);
            assert!(step <= 0.5 && step > 0.45, "{step}");
            assert!(shape.signed_distance(a[0], a[1]).abs() < 1e-9);
            twice_area += a[0] * b[1] - b[0] * a[1];
        }
        // Counterclockwise on screen (y down) is clockwise for the usual
        // shoelace formula: negative.
        let area = -0.5 * twice_area;
        let exact = shape.area().unwrap();
        assert!((area - exact).abs() / exact < 1e-3, "{area} vs {exact}");
        assert!(area > 0.0);
    }
    let s = sine();
    let pts = s.polyline(0.25).unwrap();
    assert!((pts[0][0] - 10.0).abs() < 1e-12);
    assert!((pts.last().unwrap()[0] - 90.0).abs() < 1e-12);
    assert!(pts
        .windows(2)
        .all(|w| w[1][0] > w[0][0] && (w[1][0] - w[0][0]).hypot(w[1][1] - w[0][1]) <= 0.25));
    assert!(matches!(
        s.polyline(0.0),
        Err(Error::InvalidParameter { .. })
    ));
    assert!(matches!(
        s.polyline(1e-9),
        Err(Error::InvalidParameter { .. })
    ));
}

/// Sum of chords of a very fine independent sampling.
fn chord_length(shape: &Shape, lo: f64, hi: f64, n: usize) -> f64 {
    let mut prev = param_point(shape, lo);
    let mut total = 0.0;
    for i in 1..=n {
        let p = param_point(shape, lo + (hi - lo) * i as f64 / n as f64);
        total += (p[0] - prev[0]).hypot(p[1] - prev[1]);
        prev = p;
    }
    total
}

#[test]
fn polygon_corners_lengths_and_area() {
    let sides = 5.0;
    let r: f64 = 30.0;
    let side = 2.0 * r * (PI / sides).sin();
    assert!((PENTAGON.length() - sides * side).abs() < 1e-10);
    let area = 0.5 * sides * r * r * (TAU / sides).sin();
    assert!((PENTAGON.area().unwrap() - area).abs() < 1e-10);
    assert_eq!(PENTAGON.min_curvature_radius(), 0.0);
    let corners = PENTAGON.corners();
    assert_eq!(corners.len(), 5);
    for (k, c) in corners.iter().enumerate() {
        let v = polygon_vertex(&PENTAGON, k as f64);
        assert!((c[0] - v[0]).abs() < 1e-12 && (c[1] - v[1]).abs() < 1e-12);
        assert!(PENTAGON.signed_distance(c[0], c[1]).abs() < 1e-12);
    }
    assert!(STAR.corners().is_empty());
    // Beyond a vertex along its bisector: distance to the vertex, outside,
    // the normal pointing away from the centre.
    let v = corners[2];
    let q = [
        v[0] + 4.0 * (v[0] - 50.4) / r,
        v[1] + 4.0 * (v[1] - 49.7) / r,
    ];
    assert!((PENTAGON.signed_distance(q[0], q[1]) - 4.0).abs() < 1e-12);
    let (p, n) = PENTAGON.closest_point(q[0], q[1]);
    assert!((p[0] - v[0]).abs() < 1e-9 && (p[1] - v[1]).abs() < 1e-9);
    assert!((n[0] - (v[0] - 50.4) / r).abs() < 1e-9);
    // The centre is inside, at the inradius.
    let inradius = r * (PI / sides).cos();
    assert!((PENTAGON.signed_distance(50.4, 49.7) + inradius).abs() < 1e-12);
}

#[test]
fn polygon_silhouette_sums_to_its_area() {
    let spec = RenderSpec {
        width: 100,
        height: 100,
        shape: PENTAGON,
        foreground: 1.0,
        background: 0.0,
        ..RenderSpec::default()
    };
    let img = vicurve::render::render(&spec).unwrap();
    let sum: f64 = img.data().iter().sum();
    assert!((sum - PENTAGON.area().unwrap()).abs() < 1e-9, "{sum}");
    // A line along it cannot be drawn by coverage (its corners).
    let line = RenderSpec {
        kind: Kind::Contour,
        ..spec
    };
    assert!(vicurve::render::render(&line).is_err());
}

#[test]
fn lengths_and_areas() {
    let c = Shape::Circle {
        cx: 1.0,
        cy: 2.0,
        r: 33.3,
    };
    assert!((c.length() - TAU * 33.3).abs() < 1e-11);
    // Ellipse perimeter by the arithmetic-geometric mean (Gauss-Kummer).
    let (a, b) = (35.0f64, 12.0f64);
    let (mut an, mut bn) = (a, b);
    let mut sum = (a * a - b * b) / 2.0;
    let mut pow = 1.0;
    for _ in 0..10 {
        let cn = (an - bn) / 2.0;
        let (a1, b1) = ((an + bn) / 2.0, (an * bn).sqrt());
        an = a1;
        bn = b1;
        sum += pow * cn * cn;
        pow *= 2.0;
    }
    let perimeter = TAU / an * (a * a - sum);
    assert!(
        (ellipse().length() - perimeter).abs() / perimeter < 1e-12,
        "{} vs {perimeter}",
        ellipse().length()
    );
    for (shape, lo, hi) in [(STAR, 0.0, TAU), (sine(), 10.0, 90.0)] {
        let fine = chord_length(&shape, lo, hi, 2_000_000);
        assert!(
            (shape.length() - fine).abs() / fine < 1e-9,
            "{} vs {fine}",
            shape.length()
        );
    }
    // Star area by an independent dense shoelace.
    let shape = STAR;
    let n = 200_000;
    let mut twice = 0.0;
    for i in 0..n {
        let a = param_point(&shape, TAU * i as f64 / n as f64);
        let b = param_point(&shape, TAU * (i + 1) as f64 / n as f64);
        twice += a[0] * b[1] - b[0] * a[1];
    }
    let area = shape.area().unwrap();
    assert!(((-0.5 * twice) - area).abs() / area < 1e-8);
    assert_eq!(sine().area(), None);
}

#[test]
fn min_curvature_radius() {
    // Star: brute force over the independent parametrisation by finite
    // differences of the turning angle.
    let shape = STAR;
    let n = 400_000;
    let mut best = f64::INFINITY;
    let h = TAU / n as f64;
    for i in 0..n {
        let s = i as f64 * h;
        let (p0, p1, p2) = (
            param_point(&shape, s - h),
            param_point(&shape, s),
            param_point(&shape, s + h),
        );
        // Circumradius of three consecutive points.
        let a = (p0[0] - p1[0]).hypot(p0[1] - p1[1]);
        let b = (p1[0] - p2[0]).hypot(p1[1] - p2[1]);
        let c = (p0[0] - p2[0]).hypot(p0[1] - p2[1]);
        let cross = ((p1[0] - p0[0]) * (p2[1] - p0[1]) - (p1[1] - p0[1]) * (p2[0] - p0[0])).abs();
        best = best.min(a * b * c / (2.0 * cross));
    }
    let r = shape.min_curvature_radius();
    assert!((r - best).abs() / best < 1e-6, "{r} vs {best}");
    let e = ellipse();
    assert!((e.min_curvature_radius() - 144.0 / 35.0).abs() < 1e-12);
}

#[test]
fn evaluate_statistics_by_hand() {
    let c = Shape::Circle {
        cx: 0.0,
        cy: 0.0,
        r: 10.0,
    };
    // Signed distances +1, -1, +2, 0.
    let pts = [[11.0, 0.0], [0.0, -9.0], [0.0, 12.0], [-10.0, 0.0]];
    let s = evaluate(&pts, &c).unwrap();
    assert_eq!(s.count, 4);
    assert!((s.bias - 0.5).abs() < 1e-12);
    assert!((s.rms - 1.5f64.sqrt()).abs() < 1e-12);
    assert!((s.scatter - 1.25f64.sqrt()).abs() < 1e-12);
    assert!((s.max_abs - 2.0).abs() < 1e-12);
    assert!(matches!(
        evaluate(&[], &c),
        Err(Error::InvalidParameter { .. })
    ));
    assert!(matches!(
        evaluate(&[[f64::NAN, 0.0]], &c),
        Err(Error::NonFinite { .. })
    ));
}

#[test]
fn validation_names_the_parameter() {
    let bad = [
        (
            Shape::Circle {
                cx: 0.0,
                cy: 0.0,
                r: 0.0,
            },
            "r",
        ),
        (
            Shape::Circle {
                cx: f64::NAN,
                cy: 0.0,
                r: 1.0,
            },
            "cx",
        ),
        (
            Shape::Star {
                cx: 0.0,
                cy: 0.0,
                r0: 10.0,
                amplitude: 1.0,
                lobes: 3,
                phase: 0.0,
            },
            "amplitude",
        ),
        (
            Shape::Star {
                cx: 0.0,
                cy: 0.0,
                r0: 10.0,
                amplitude: 0.1,
                lobes: 0,
                phase: 0.0,
            },
            "lobes",
        ),
        (
            Shape::Ellipse {
                cx: 0.0,
                cy: 0.0,
                a: 1.0,
                b: -1.0,
                angle: 0.0,
            },
            "b",
        ),
        (
            Shape::Sine {
                y0: 0.0,
                amplitude: 1.0,
                wavelength: 10.0,
                phase: 0.0,
                x_min: 5.0,
                x_max: 5.0,
            },
            "x_max",
        ),
        (
            Shape::Polygon {
                cx: 0.0,
                cy: 0.0,
                r: 10.0,
                sides: 2,
                angle: 0.0,
            },
            "sides",
        ),
    ];
    for (shape, name) in bad {
        match shape.validate() {
            Err(Error::InvalidParameter { name: n, .. }) => assert_eq!(n, name),
            other => panic!("{shape:?}: {other:?}"),
        }
    }
    assert!(STAR.validate().is_ok() && sine().validate().is_ok());
}

#[test]
fn truth_json_round_trip() {
    let spec = RenderSpec {
        shape: STAR,
        kind: Kind::Contour,
        line_width: 2.5,
        method: Method::Coverage,
        ..RenderSpec::default()
    };
    let t = Truth::from_spec(&spec);
    assert_eq!(t.line_width, Some(2.5));
    let json = t.to_json();
    assert!(json.contains("\"shape\": \"star\""), "{json}");
    assert!(json.contains("\"kind\": \"contour\""), "{json}");
    assert_eq!(Truth::from_json(&json, "test").unwrap(), t);
    let dir = std::env::temp_dir().join(format!("vicurve-truth-{}", std::process::id()));
    std::fs::create_dir_all(&dir).unwrap();
    let path = dir.join("t.json");
    t.save(&path).unwrap();
    assert_eq!(Truth::load(&path).unwrap(), t);
    std::fs::remove_dir_all(&dir).unwrap();
    assert!(matches!(
        Truth::load(&dir.join("missing.json")),
        Err(Error::NotFound { .. })
    ));
    assert!(matches!(
        Truth::from_json("{", "x"),
        Err(Error::Parse { .. })
    ));
    // A polygon written by hand.
    let s: Shape = serde_json::from_str(
        r#"{"shape": "polygon", "cx": 1.0, "cy": 2.0, "r": 3.0, "sides": 6, "angle": 0.5}"#,
    )
    .unwrap();
    assert_eq!(s.corners().len(), 6);
    // A shape written by hand.
    let s: Shape =
        serde_json::from_str(r#"{"shape": "circle", "cx": 1.0, "cy": 2.0, "r": 3.0}"#).unwrap();
    assert_eq!(
        s,
        Shape::Circle {
            cx: 1.0,
            cy: 2.0,
            r: 3.0
        }
    );
}
