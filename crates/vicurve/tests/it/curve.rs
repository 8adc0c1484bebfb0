//! Spline curves: fitting, geometry and closest-point projection against
//! exact circles and brute force.

use proptest::prelude::*;
use vicurve::curve::{Clearance, InitialCurve, SplineCurve};

fn circle(cx: f64, cy: f64, r: f64) -> SplineCurve {
    InitialCurve::Circle { cx, cy, r }.to_curve().unwrap()
}

#[test]
fn circle_is_represented_to_a_micro_pixel() {
    let (cx, cy, r) = (100.3, 80.7, 40.0);
    let c = circle(cx, cy, r);
    assert!(c.is_closed());
    let l = c.param_length();
    for i in 0..1000 {
        let u = l * i as f64 / 1000.0;
        let f = c.frame(u);
        let d = (f.point[0] - cx).hypot(f.point[1] - cy) - r;
        assert!(d.abs() < 1e-6, "radius error {d} at u = {u}");
        // Outward normal, counterclockwise on screen, curvature -1/r.
        let radial = [(f.point[0] - cx) / r, (f.point[1] - cy) / r];
        assert!((f.normal[0] * radial[0] + f.normal[1] * radial[1] - 1.0).abs() < 1e-6);
        assert!(
            (f.curvature + 1.0 / r).abs() < 1e-5,
            "curvature {}",
            f.curvature
        );
    }
    assert!((c.arc_length() - std::f64::consts::TAU * r).abs() < 1e-5);
    // Its largest curvature is the circle's.
    assert!((c.largest_curvature(1.0) - 1.0 / r).abs() < 1e-5);
    assert!((c.area().unwrap() - std::f64::consts::PI * r * r).abs() < 1e-3);
}

#[test]
fn clockwise_input_is_reoriented() {
    let pts: Vec<[f64; 2]> = (0..400)
        .map(|i| {
            let t = std::f64::consts::TAU * i as f64 / 400.0;
            [50.0 + 20.0 * t.cos(), 50.0 + 20.0 * t.sin()] // clockwise on screen
        })
        .collect();
    let c = SplineCurve::fit(&pts, true, 3, 2.0).unwrap();
    let f = c.frame(0.0);
    let radial = [(f.point[0] - 50.0) / 20.0, (f.point[1] - 50.0) / 20.0];
    assert!(
        f.normal[0] * radial[0] + f.normal[1] * radial[1] > 0.99,
        "normal must point outward"
    );
}

#[test]
fn segment_is_exact_and_straight() {
    let c = InitialCurve::Segment {
        x0: 10.0,
        y0: 20.0,
        x1: 110.0,
        y1: 20.0,
    }
    .to_curve()
    .unwrap();
    assert!(!c.is_closed());
    // The tiny regularisation of the fit shortens it by ~1e-8 px.
    assert!((c.arc_length() - 100.0).abs() < 1e-7);
    assert!(c.largest_curvature(0.5) < 1e-9);
    let f = c.frame(30.0);
    assert!((f.point[0] - 40.0).abs() < 1e-9 && (f.point[1] - 20.0).abs() < 1e-9);
    // Travelling +x, the normal points +y (down on screen).
    assert!((f.normal[1] - 1.0).abs() < 1e-12);
    assert!(f.curvature.abs() < 1e-12);
}

#[test]
fn degenerate_inputs_are_errors() {
    assert!(SplineCurve::fit(&[[0.0, 0.0]], false, 3, 2.0).is_err());
    assert!(SplineCurve::fit(&[[0.0, 0.0], [0.0, 0.0]], false, 3, 2.0).is_err());
    assert!(SplineCurve::fit(&[[0.0, 0.0], [f64::NAN, 1.0]], false, 3, 2.0).is_err());
    assert!(InitialCurve::Circle {
        cx: 0.0,
        cy: 0.0,
        r: 0.5
    }
    .to_curve()
    .is_err());
    assert!("circle:1,2".parse::<InitialCurve>().is_err());
    assert!("square:1,2,3".parse::<InitialCurve>().is_err());
    assert!("circle:1,x,3".parse::<InitialCurve>().is_err());
    assert!("segment:1,2,3,4".parse::<InitialCurve>().is_ok());
}

proptest! {
    #[test]
    fn projection_onto_a_circle_is_exact(angle in 0.0f64..std::f64::consts::TAU, dist in -15.0f64..15.0) {
        let (cx, cy, r) = (60.2, 55.9, 30.0);
        let c = circle(cx, cy, r);
        let x = cx + (r + dist) * angle.cos();
        let y = cy - (r + dist) * angle.sin();
        // Start from a rough guess: the true parameter is about r * angle.
        let guess = (r * angle + 1.5).rem_euclid(c.param_length());
        let p = c.project(x, y, guess);
        prop_assert!((p.r - dist).abs() < 1e-6, "r {} vs {}", p.r, dist);
        let q = c.point(p.u);
        let expect = [cx + r * angle.cos(), cy - r * angle.sin()];
        // The 2-px spline circle tilts its normals by ~1e-7 rad: the foot of a
        // point 15 px away moves tangentially by ~1e-5 px (irrelevant for s).
        prop_assert!((q[0] - expect[0]).hypot(q[1] - expect[1]) < 1e-4);
        prop_assert!(!p.at_end);
    }

    /// Against a brute-force search on a lobed closed curve (a fitted
    /// spline, so its own points are the truth): the signed distance, the
    /// normal and the curvature at the foot, from starts up to 1.5 px of
    /// parameter off.
    #[test]
    fn projection_matches_a_brute_force_search(
        u in 0.0f64..1.0,
        dist in -6.0f64..6.0,
        off in -1.5f64..1.5,
    ) {
        let pts: Vec<[f64; 2]> = (0..400)
            .map(|k| {
                let t = k as f64 / 400.0 * std::f64::consts::TAU;
                let r = 80.0 * (1.0 + 0.2 * (5.0 * t).cos());
                [100.0 + r * t.cos(), 100.0 + r * t.sin()]
            })
            .collect();
        let c = SplineCurve::fit(&pts, true, 3, 8.0).unwrap();
        let l = c.param_length();
        let f = c.frame(u * l);
        let (x, y) = (f.point[0] + dist * f.normal[0], f.point[1] + dist * f.normal[1]);
        let p = c.project(x, y, (u * l + off).rem_euclid(l));
        // Brute force: the nearest of a fine grid near the start, then a
        // golden-section search on the squared distance.
        let d2 = |v: f64| {
            let q = c.point(v.rem_euclid(l));
            (q[0] - x).powi(2) + (q[1] - y).powi(2)
        };
        let centre = u * l;
        let mut best = centre;
        for k in -400..=400 {
            let v = centre + k as f64 * 0.01;
            if d2(v) < d2(best) {
                best = v;
            }
        }
        let (mut a, mut b) = (best - 0.01, best + 0.01);
        let g = 0.5 * (5f64.sqrt() - 1.0);
        for _ in 0..80 {
            let (m1, m2) = (b - g * (b - a), a + g * (b - a));
            if d2(m1) < d2(m2) { b = m2 } else { a = m1 }
        }
        let foot = (0.5 * (a + b)).rem_euclid(l);
        let ff = c.frame(foot);
        let r = (x - ff.point[0]) * ff.normal[0] + (y - ff.point[1]) * ff.normal[1];
        prop_assert!((p.r - r).abs() < 1e-9, "r {} vs {}", p.r, r);
        prop_assert!((p.normal[0] - ff.normal[0]).hypot(p.normal[1] - ff.normal[1]) < 1e-7);
        // The curvature is the second-order expansion's from before Newton's
        // last step (under 1e-3 px): off by up to |C'''| 1e-3 (C''' is
        // about 0.01 /px^2 at this curve's concave bends, where the
        // curvature is -0.08 /px).
        prop_assert!((p.curvature - ff.curvature).abs() < 3e-5,
            "curvature {} vs {}", p.curvature, ff.curvature);
        prop_assert!(!p.at_end);
    }

    #[test]
    fn points_past_the_end_of_an_open_curve_are_flagged(t in -20.0f64..120.0, off in -5.0f64..5.0) {
        let c = InitialCurve::Segment { x0: 0.0, y0: 0.0, x1: 100.0, y1: 0.0 }.to_curve().unwrap();
        let p = c.project(t, off, t.clamp(0.0, 100.0));
        let beyond = !(-1e-6..=100.0 + 1e-6).contains(&t);
        prop_assert_eq!(p.at_end, beyond, "t = {}", t);
        if !beyond {
            prop_assert!((p.r - off).abs() < 1e-9);
        }
    }
}

/// A closed curve with corners starts at one of them, whatever point the
/// polyline starts at, so that no element is cut short at the origin.
#[test]
fn closed_curve_with_corners_starts_at_a_corner() {
    // A square, counterclockwise on screen, its first point just short of
    // the corner at index 4.
    let mut pts = Vec::new();
    let corners_xy = [[10.0, 10.0], [10.0, 50.0], [50.0, 50.0], [50.0, 10.0]];
    for k in 0..4 {
        let (a, b) = (corners_xy[k], corners_xy[(k + 1) % 4]);
        for i in 0..40 {
            let t = i as f64 / 40.0;
            pts.push([a[0] + t * (b[0] - a[0]), a[1] + t * (b[1] - a[1])]);
        }
    }
    pts.rotate_left(39);
    let corners: Vec<usize> = [1, 41, 81, 121].to_vec();
    let curve = SplineCurve::fit_with_corners(&pts, true, 3, 2.0, &corners).unwrap();
    assert_eq!(curve.corners().len(), 4);
    assert_eq!(curve.corners()[0], 0.0, "corners at {:?}", curve.corners());
    let p = curve.point(0.0);
    let nearest = corners_xy
        .iter()
        .map(|c| (p[0] - c[0]).hypot(p[1] - c[1]))
        .fold(f64::INFINITY, f64::min);
    assert!(nearest < 1e-9, "origin {p:?} is no vertex");
}

/// The pixels a corner's clearance leaves out: those near the region
/// between the other side and this side's extension, on either side of
/// the vertex; not those along the side, away from the vertex.
#[test]
fn a_corner_clears_the_pixels_that_see_the_other_side() {
    // A right-angled corner at the origin: the side along +x ends there,
    // the next leaves along +y (a left turn); 1 px kept clear.
    let c = Clearance {
        vertex: [0.0, 0.0],
        at: 100.0,
        into: [1.0, 0.0],
        out: [0.0, 1.0],
        distance: 1.0,
    };
    let (length, closed) = (400.0, true);
    // Before the corner (foot on the first side): near the vertex, and
    // beside the second side, inside.
    assert!(c.covers([-0.5, 0.3], 99.5, length, closed));
    assert!(c.covers([-0.8, 3.0], 99.2, length, closed));
    // Before it but 2 px from the vertex, along the side: clear.
    assert!(!c.covers([-2.0, 0.0], 98.0, length, closed));
    assert!(!c.covers([-2.0, -0.5], 98.0, length, closed));
    // After the corner (foot on the second side): mirrored.
    assert!(c.covers([0.3, -0.5], 100.5, length, closed));
    assert!(!c.covers([0.0, 2.0], 102.0, length, closed));
    // A closed curve's parameter wraps: a corner at 0 and a foot at 399.
    let at_origin = Clearance { at: 0.0, ..c };
    assert!(at_origin.covers([-0.5, 0.3], 399.5, length, closed));
    assert!(!at_origin.covers([-3.0, 0.0], 397.0, length, closed));
    // An almost straight corner clears about the distance round the vertex.
    let straight = Clearance {
        out: [0.9998, 0.02],
        ..c
    };
    assert!(straight.covers([-0.9, 0.0], 99.1, length, closed));
    assert!(!straight.covers([-1.1, 0.0], 98.9, length, closed));
}
