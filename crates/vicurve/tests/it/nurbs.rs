//! NURBS geometry (`vicurve::nurbs`): the changes of representation leave
//! the measured curves' points unchanged to 1e-9 px, the patch between two
//! measured edges has exactly those edges as boundaries, h-refinement does
//! not move the surface, and the `.vtu` file is well-formed with consistent
//! counts.

use proptest::prelude::*;
use vicurve::curve::{InitialCurve, SplineCurve, SplineCurveData};
use vicurve::fit::{measure, FitConfig, Measurement, Outcome};
use vicurve::nurbs::vtu::{control_net_vtu, patch_vtu, VTK_QUAD};
use vicurve::nurbs::{BSplineCurve, NurbsPatch, PatchConfig, PatchData};
use vicurve::render::{render, Method, RenderSpec};
use vicurve::truth::{evaluate, Kind, Shape};
use vicurve::Error;

const TOL: f64 = 1e-9;

fn dist(a: [f64; 2], b: [f64; 2]) -> f64 {
    (a[0] - b[0]).hypot(a[1] - b[1])
}

/// A measured-like curve: the least-squares B-spline of `degree` through a
/// wavy open line or a star-shaped closed one, with control points about
/// `spacing` px apart.
fn wavy(closed: bool, degree: usize, spacing: f64, phase: f64) -> SplineCurve {
    let pts: Vec<[f64; 2]> = if closed {
        (0..720)
            .map(|i| {
                let t = i as f64 / 720.0 * std::f64::consts::TAU;
                let r = 90.0 * (1.0 + 0.15 * (5.0 * t + phase).cos());
                [150.3 + r * t.cos(), 149.6 - r * t.sin()]
            })
            .collect()
    } else {
        (0..=600)
            .map(|i| {
                let x = 20.0 + 0.4 * i as f64;
                [x, 80.0 + 9.0 * (x / 31.0 + phase).sin()]
            })
            .collect()
    };
    SplineCurve::fit(&pts, closed, degree, spacing).unwrap()
}

/// `count + 1` parameters over `[a, b]`, ends included.
fn params(a: f64, b: f64, count: usize) -> impl Iterator<Item = f64> {
    (0..=count).map(move |i| a + (b - a) * i as f64 / count as f64)
}

fn max_gap(f: impl Fn(f64) -> [f64; 2], g: impl Fn(f64) -> [f64; 2], a: f64, b: f64) -> f64 {
    params(a, b, 2000)
        .map(|u| dist(f(u), g(u)))
        .fold(0.0, f64::max)
}

#[test]
fn result_data_is_read_as_the_same_curve() {
    for closed in [false, true] {
        for degree in 1..=5 {
            let c = wavy(closed, degree, 12.0, 0.3);
            let b = BSplineCurve::from_data(&c.to_data()).unwrap();
            let l = c.param_length();
            assert_eq!(b.domain(), (0.0, l));
            let gap = max_gap(|u| c.point(u), |u| b.point(u), 0.0, l);
            assert!(gap < TOL, "closed {closed} degree {degree}: {gap:e}");
        }
    }
}

#[test]
fn clamping_elevation_reversal_and_bezier_pieces_keep_the_points() {
    for closed in [false, true] {
        for degree in 1..=5 {
            let c = wavy(closed, degree, 15.0, 1.1);
            let b = BSplineCurve::from_data(&c.to_data()).unwrap();
            let l = c.param_length();
            let name = format!("closed {closed} degree {degree}");

            let cl = b.clamped().unwrap();
            assert!(cl.is_clamped(), "{name}");
            assert_eq!(cl.domain(), (0.0, l));
            assert!(dist(cl.control_points()[0], c.point(0.0)) < TOL, "{name}");
            let gap = max_gap(|u| c.point(u), |u| cl.point(u), 0.0, l);
            assert!(gap < TOL, "{name} clamped: {gap:e}");

            for up in 1..=2 {
                let e = b.elevated(degree + up).unwrap();
                assert_eq!(e.degree(), degree + up);
                let gap = max_gap(|u| c.point(u), |u| e.point(u), 0.0, l);
                assert!(gap < TOL, "{name} elevated by {up}: {gap:e}");
            }
            assert!(b.elevated(degree - 1).is_err() || degree == 1);

            let r = b.reversed();
            assert_eq!(r.domain(), (0.0, l));
            let gap = max_gap(|u| c.point(u), |u| r.point(l - u), 0.0, l);
            assert!(gap < TOL, "{name} reversed: {gap:e}");

            let s = b.reparametrised(0.0, 1.0).unwrap();
            let gap = max_gap(|u| c.point(u), |u| s.point(u / l), 0.0, l);
            assert!(gap < TOL, "{name} on [0, 1]: {gap:e}");

            // Piece k is span [k h, (k + 1) h]; evaluate it by de Casteljau.
            let pieces = b.bezier_segments().unwrap();
            let h = c.basis().element_length();
            assert_eq!(pieces.len(), c.basis().n_elements(), "{name}");
            let mut worst: f64 = 0.0;
            for (k, piece) in pieces.iter().enumerate() {
                for t in params(0.0, 1.0, 50) {
                    let u = (k as f64 + t) * h;
                    worst = worst.max(dist(de_casteljau(piece, t), c.point(u.min(l))));
                }
            }
            assert!(worst < TOL, "{name} Bézier pieces: {worst:e}");
        }
    }
}

fn de_casteljau(ctrl: &[[f64; 2]], t: f64) -> [f64; 2] {
    let mut q = ctrl.to_vec();
    for r in 1..q.len() {
        for i in 0..q.len() - r {
            q[i] = [
                (1.0 - t) * q[i][0] + t * q[i + 1][0],
                (1.0 - t) * q[i][1] + t * q[i + 1][1],
            ];
        }
    }
    q[0]
}

proptest! {
    #![proptest_config(ProptestConfig::with_cases(48))]

    /// Boehm's insertion at random places (up to full multiplicity) leaves
    /// the curve where it was.
    #[test]
    fn knot_insertion_keeps_the_curve(
        degree in 1usize..=5,
        closed in any::<bool>(),
        at in prop::collection::vec((0.0f64..=1.0, 1usize..=3), 1..8),
    ) {
        let c = wavy(closed, degree, 20.0, 0.7);
        let mut b = BSplineCurve::from_data(&c.to_data()).unwrap();
        let l = c.param_length();
        let n0 = b.control_points().len();
        let mut inserted = 0;
        for (f, times) in at {
            // Up to the multiplicity allowed at that place; more must fail.
            let u = f * l;
            let have = b.knots().iter().filter(|&&k| k == u).count();
            let limit = if u > 0.0 && u < l { degree } else { degree + 1 };
            let ok = (limit - have.min(limit)).min(times);
            b.insert_knot(u, ok).unwrap();
            inserted += ok;
            if have + ok >= limit {
                prop_assert!(b.insert_knot(u, 1).is_err());
            }
        }
        prop_assert_eq!(b.control_points().len(), n0 + inserted);
        let gap = max_gap(|u| c.point(u), |u| b.point(u), 0.0, l);
        prop_assert!(gap < TOL, "{:e}", gap);
    }
}

fn patch_between(a: &SplineCurve, b: &SplineCurve, config: &PatchConfig) -> NurbsPatch {
    NurbsPatch::between_data(&a.to_data(), &b.to_data(), config)
        .unwrap()
        .patch
}

/// Largest distance between the patch's `v = 0` and `v = 1` boundaries and
/// the two curves, each at the same fraction of its parameter.
fn boundary_gap(p: &NurbsPatch, a: &SplineCurve, b: &SplineCurve, b_reversed: bool) -> f64 {
    let (la, lb) = (a.param_length(), b.param_length());
    params(0.0, 1.0, 3000)
        .map(|s| {
            let sb = if b_reversed { 1.0 - s } else { s };
            dist(p.point(s, 0.0), a.point(s * la)).max(dist(p.point(s, 1.0), b.point(sb * lb)))
        })
        .fold(0.0, f64::max)
}

#[test]
fn patch_boundaries_are_the_curves_and_refinement_does_not_move_it() {
    // Different element counts and degrees, so that the knot vectors must
    // be merged and one curve elevated.
    let a = wavy(false, 3, 13.0, 0.2);
    let mut pts: Vec<[f64; 2]> = (0..=500)
        .map(|i| {
            let x = 25.0 + 0.47 * i as f64;
            [x, 160.0 + 6.0 * (x / 23.0).cos()]
        })
        .collect();
    let b = SplineCurve::fit(&pts, false, 2, 17.0).unwrap();
    for q in 1..=3 {
        let config = PatchConfig {
            degree_across: q,
            ..PatchConfig::default()
        };
        let build = NurbsPatch::between_data(&a.to_data(), &b.to_data(), &config).unwrap();
        assert!(!build.reversed_second);
        assert_eq!(build.curve_degrees, [3, 2]);
        let p = build.patch;
        assert_eq!(p.degrees(), (3, q));
        let gap = boundary_gap(&p, &a, &b, false);
        assert!(gap < TOL, "degree across {q}: boundary gap {gap:e}");
        // Across, the straight segment between matching points whatever q.
        for (u, v) in [(0.13, 0.3), (0.5, 0.5), (0.91, 0.77)] {
            let (pa, pb) = (p.point(u, 0.0), p.point(u, 1.0));
            let lin = [pa[0] + v * (pb[0] - pa[0]), pa[1] + v * (pb[1] - pa[1])];
            assert!(dist(p.point(u, v), lin) < TOL, "q {q} at ({u}, {v})");
        }
    }

    let base = patch_between(&a, &b, &PatchConfig::default());
    let (ea, eb) = base.elements();
    let mut refined = base.clone();
    refined.refine(3, 4).unwrap();
    assert_eq!(refined.elements(), (3 * ea, 4 * eb));
    let mut worst: f64 = 0.0;
    for u in params(0.0, 1.0, 400) {
        for v in params(0.0, 1.0, 20) {
            worst = worst.max(dist(base.point(u, v), refined.point(u, v)));
        }
    }
    assert!(worst < TOL, "refinement moved the patch by {worst:e}");
    // The same through the configuration, with single insertions on top.
    let config = PatchConfig {
        degree_across: 2,
        refine_along: 2,
        refine_across: 3,
        ..PatchConfig::default()
    };
    let mut r2 = patch_between(&a, &b, &config);
    r2.insert_knot(0.123456, true).unwrap();
    r2.insert_knot(0.5, false).unwrap();
    assert!(boundary_gap(&r2, &a, &b, false) < TOL);

    // The second curve the other way round is reversed back.
    pts.reverse();
    let b_rev = SplineCurve::fit(&pts, false, 2, 17.0).unwrap();
    let build =
        NurbsPatch::between_data(&a.to_data(), &b_rev.to_data(), &PatchConfig::default()).unwrap();
    assert!(build.reversed_second);
    assert!(boundary_gap(&build.patch, &a, &b_rev, true) < TOL);
}

#[test]
fn patch_data_round_trips_and_has_unit_weights() {
    let a = wavy(false, 3, 20.0, 0.0);
    let b = wavy(false, 3, 25.0, 2.0);
    // Shift b down so the patch is a band.
    let mut d = b.to_data();
    for p in d.control_points.iter_mut() {
        p[1] += 70.0;
    }
    let p = NurbsPatch::between_data(
        &a.to_data(),
        &d,
        &PatchConfig {
            refine_along: 2,
            ..PatchConfig::default()
        },
    )
    .unwrap()
    .patch;
    let data = p.to_data();
    let (nu, nv) = p.size();
    assert_eq!(data.control_points.len(), nu);
    assert_eq!(data.knots_u.len(), nu + data.degree_u + 1);
    assert_eq!(data.knots_v, vec![0.0, 0.0, 1.0, 1.0]);
    assert!(data.control_points.iter().all(|r| r.len() == nv));
    assert!(data.weights.iter().flatten().all(|&w| w == 1.0));
    let json = serde_json::to_string(&data).unwrap();
    let back: PatchData = serde_json::from_str(&json).unwrap();
    let q = NurbsPatch::from_data(&back).unwrap();
    assert_eq!(q, p);
}

#[test]
fn bad_input_gives_typed_errors() {
    let open = wavy(false, 3, 20.0, 0.0).to_data();
    let closed = wavy(true, 3, 20.0, 0.0).to_data();
    let c = PatchConfig::default();
    assert!(matches!(
        NurbsPatch::between_data(&open, &closed, &c),
        Err(Error::InvalidCurve { .. })
    ));
    assert!(matches!(
        NurbsPatch::between_data(&open, &open, &c),
        Err(Error::InvalidCurve { .. })
    ));
    let mut nan = open.clone();
    nan.control_points[3][1] = f64::NAN;
    assert!(matches!(
        NurbsPatch::between_data(&open, &nan, &c),
        Err(Error::NonFinite { .. })
    ));
    let empty = SplineCurveData {
        degree: 3,
        closed: false,
        knots: vec![],
        control_points: vec![],
    };
    assert!(NurbsPatch::between_data(&open, &empty, &c).is_err());
    let mut short = open.clone();
    short.knots.pop();
    assert!(matches!(
        BSplineCurve::from_data(&short),
        Err(Error::InvalidCurve { .. })
    ));
    let mut unsorted = open.clone();
    unsorted.knots.swap(4, 5);
    assert!(BSplineCurve::from_data(&unsorted).is_err());
    for bad in [
        PatchConfig {
            degree_across: 0,
            ..c.clone()
        },
        PatchConfig {
            degree_across: 6,
            ..c.clone()
        },
        PatchConfig {
            refine_along: 0,
            ..c.clone()
        },
        PatchConfig {
            refine_across: 100_000,
            ..c.clone()
        },
    ] {
        assert!(matches!(
            NurbsPatch::between_data(&open, &open, &bad),
            Err(Error::InvalidParameter { .. })
        ));
    }
    let p = patch_between(&wavy(false, 3, 20.0, 0.0), &wavy(false, 2, 20.0, 3.0), &c);
    assert!(patch_vtu(&p, (0, 2), "").is_err());
    let mut q = p.clone();
    assert!(q.insert_knot(1.5, true).is_err());
    assert!(q.insert_knot(f64::NAN, false).is_err());
}

/// The values of a `<DataArray>` as numbers.
fn numbers(node: roxmltree::Node) -> Vec<f64> {
    node.text()
        .unwrap_or("")
        .split_whitespace()
        .map(|t| t.parse::<f64>().expect("a number"))
        .collect()
}

fn array<'a>(doc: &'a roxmltree::Document, name: &str) -> roxmltree::Node<'a, 'a> {
    doc.descendants()
        .find(|n| n.has_tag_name("DataArray") && n.attribute("Name") == Some(name))
        .unwrap_or_else(|| panic!("no DataArray {name}"))
}

#[test]
fn vtu_is_well_formed_with_consistent_counts() {
    let a = wavy(false, 3, 20.0, 0.0);
    let mut d = wavy(false, 3, 30.0, 1.0).to_data();
    for p in d.control_points.iter_mut() {
        p[1] += 60.0;
    }
    let config = PatchConfig {
        refine_across: 2,
        ..PatchConfig::default()
    };
    let p = NurbsPatch::between_data(&a.to_data(), &d, &config)
        .unwrap()
        .patch;
    let (ea, eb) = p.elements();
    let (nx, ny) = (3, 2);
    let text = patch_vtu(&p, (nx, ny), "a -- test").unwrap();
    let doc = roxmltree::Document::parse(&text).expect("well-formed XML");
    let root = doc.root_element();
    assert_eq!(root.tag_name().name(), "VTKFile");
    assert_eq!(root.attribute("type"), Some("UnstructuredGrid"));
    let piece = doc.descendants().find(|n| n.has_tag_name("Piece")).unwrap();
    let n_points: usize = piece.attribute("NumberOfPoints").unwrap().parse().unwrap();
    let n_cells: usize = piece.attribute("NumberOfCells").unwrap().parse().unwrap();
    assert_eq!(n_points, (ea * nx + 1) * (eb * ny + 1));
    assert_eq!(n_cells, ea * nx * eb * ny);
    let xyz = numbers(array(&doc, "Points"));
    let conn = numbers(array(&doc, "connectivity"));
    let offsets = numbers(array(&doc, "offsets"));
    let types = numbers(array(&doc, "types"));
    let uv = numbers(array(&doc, "parameter"));
    let element = numbers(array(&doc, "element"));
    assert_eq!(xyz.len(), 3 * n_points);
    assert_eq!(uv.len(), 2 * n_points);
    assert_eq!(conn.len(), 4 * n_cells);
    assert_eq!(offsets.len(), n_cells);
    assert_eq!(types.len(), n_cells);
    assert_eq!(element.len(), 2 * n_cells);
    assert!(types.iter().all(|&t| t == f64::from(VTK_QUAD)));
    assert!(offsets
        .iter()
        .enumerate()
        .all(|(c, &o)| o == (4 * (c + 1)) as f64));
    assert!(conn.iter().all(|&i| i >= 0.0 && (i as usize) < n_points));
    // Every point is the surface at its parameter, z = 0; every cell has a
    // positive or negative area consistently (no folded cell).
    for (k, w) in uv.chunks(2).enumerate() {
        let s = p.point(w[0], w[1]);
        assert!(dist(s, [xyz[3 * k], xyz[3 * k + 1]]) < TOL);
        assert_eq!(xyz[3 * k + 2], 0.0);
    }
    let pt = |i: f64| [xyz[3 * i as usize], xyz[3 * i as usize + 1]];
    let signs: Vec<bool> = conn
        .chunks(4)
        .map(|q| {
            let c: Vec<[f64; 2]> = q.iter().map(|&i| pt(i)).collect();
            let area: f64 = (0..4)
                .map(|i| {
                    let (a, b) = (c[i], c[(i + 1) % 4]);
                    a[0] * b[1] - a[1] * b[0]
                })
                .sum();
            area > 0.0
        })
        .collect();
    assert!(signs.iter().all(|&s| s == signs[0]), "folded cells");
    assert!(element
        .chunks(2)
        .all(|e| (e[0] as usize) < ea && (e[1] as usize) < eb));

    let net = control_net_vtu(&p, "net");
    let doc = roxmltree::Document::parse(&net).expect("well-formed XML");
    let (nu, nv) = p.size();
    let piece = doc.descendants().find(|n| n.has_tag_name("Piece")).unwrap();
    assert_eq!(
        piece.attribute("NumberOfPoints").unwrap(),
        (nu * nv).to_string()
    );
    assert_eq!(
        piece.attribute("NumberOfCells").unwrap(),
        ((nu - 1) * (nv - 1)).to_string()
    );
    assert_eq!(numbers(array(&doc, "weight")).len(), nu * nv);
}

/// An exact-coverage image of one sinusoidal edge, blurred by 1 px, and its
/// measurement from a straight segment.
fn measured_edge(y0: f64, amplitude: f64, wavelength: f64, phase: f64) -> (Measurement, Shape) {
    let shape = Shape::Sine {
        y0,
        amplitude,
        wavelength,
        phase,
        x_min: 30.0,
        x_max: 270.0,
    };
    let spec = RenderSpec {
        width: 300,
        height: 300,
        shape: shape.clone(),
        kind: Kind::Silhouette,
        method: Method::Coverage,
        foreground: 0.8,
        background: 0.2,
        blur_sigma: 1.0,
        bits: Some(8),
        ..RenderSpec::default()
    };
    let image = render(&spec).unwrap();
    let init = InitialCurve::Segment {
        x0: 30.0,
        y0,
        x1: 270.0,
        y1: y0,
    };
    let m = measure(&image, &init, &FitConfig::default()).unwrap();
    assert_eq!(m.outcome, Outcome::Converged);
    (m, shape)
}

/// The isogeometric example from real measurements: two edges measured in
/// exact-coverage images (the two sides of a wavy bar, one image each since
/// the renderer draws one curve), the patch between them.
#[test]
fn patch_between_two_measured_edges() {
    let (top, top_shape) = measured_edge(110.3, 8.0, 180.0, 0.4);
    let (bottom, bottom_shape) = measured_edge(190.6, -5.0, 150.0, 1.3);
    for (m, shape) in [(&top, &top_shape), (&bottom, &bottom_shape)] {
        let s = evaluate(&m.points(), shape).unwrap();
        println!(
            "edge: bias {:+.2e} scatter {:.2e} max {:.2e} px",
            s.bias, s.scatter, s.max_abs
        );
        assert!(s.max_abs < 0.05, "the measurement itself is off: {s:?}");
    }
    let config = PatchConfig {
        refine_along: 2,
        refine_across: 4,
        ..PatchConfig::default()
    };
    let build = NurbsPatch::between_data(&top.curve_data(), &bottom.curve_data(), &config).unwrap();
    assert!(!build.reversed_second);
    let p = build.patch;
    let gap = boundary_gap(&p, &top.curve, &bottom.curve, false);
    println!(
        "patch {:?} elements, boundary gap {gap:.1e} px",
        p.elements()
    );
    assert!(gap < TOL, "boundary gap {gap:e}");
    // The boundaries are the measured edges, so they are as close to the
    // true edges as the measurement (the points sampled on them).
    let on = |v: f64| -> Vec<[f64; 2]> { params(0.0, 1.0, 400).map(|u| p.point(u, v)).collect() };
    for (v, shape) in [(0.0, &top_shape), (1.0, &bottom_shape)] {
        let s = evaluate(&on(v), shape).unwrap();
        assert!(s.max_abs < 0.05, "boundary v = {v}: {s:?}");
    }
    // Interior points lie between the edges.
    for u in params(0.02, 0.98, 50) {
        let (t, m, b) = (p.point(u, 0.0), p.point(u, 0.5), p.point(u, 1.0));
        assert!(t[1] < m[1] && m[1] < b[1], "at u = {u}");
    }
    let text = patch_vtu(&p, (2, 1), "measured edges").unwrap();
    roxmltree::Document::parse(&text).expect("well-formed XML");
}
