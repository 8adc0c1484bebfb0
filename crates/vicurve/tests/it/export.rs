//! CAD export (`vicurve::export`): the DXF `SPLINE` and the SVG cubic
//! Bézier path, each read back with a parser and evaluated with an
//! evaluator written here (not the library's), reproduce the measured curve
//! to 1e-9 px; the DXF drawing has the structure CAD programs require.

use std::collections::{HashMap, HashSet};
use vicurve::curve::{InitialCurve, SplineCurve, SplineCurveData};
use vicurve::export::dxf::{dxf_spline, spline_dxf, ClosedForm, DxfOptions, YAxis};
use vicurve::export::read_result_curve;
use vicurve::export::source::parse_result_curve;
use vicurve::export::svg_bezier::{cubic_segments, curve_svg, SvgOptions};
use vicurve::fit::{measure, FitConfig, Outcome};
use vicurve::render::{render, Method, RenderSpec};
use vicurve::report::ResultFile;
use vicurve::truth::{Kind, Shape};
use vicurve::Error;

const TOL: f64 = 1e-9;

fn dist(a: [f64; 2], b: [f64; 2]) -> f64 {
    (a[0] - b[0]).hypot(a[1] - b[1])
}

/// Measured-like curves: least-squares B-splines of each degree through a
/// wavy open line and a star-shaped closed curve.
fn curves() -> Vec<SplineCurve> {
    let star: Vec<[f64; 2]> = (0..720)
        .map(|i| {
            let t = i as f64 / 720.0 * std::f64::consts::TAU;
            let r = 90.0 * (1.0 + 0.15 * (5.0 * t + 0.3).cos());
            [150.3 + r * t.cos(), 149.6 - r * t.sin()]
        })
        .collect();
    let wave: Vec<[f64; 2]> = (0..=600)
        .map(|i| {
            let x = 20.0 + 0.4 * i as f64;
            [x, 80.0 + 9.0 * (x / 31.0).sin()]
        })
        .collect();
    let mut out = Vec::new();
    for degree in 1..=5 {
        out.push(SplineCurve::fit(&wave, false, degree, 11.0).unwrap());
        out.push(SplineCurve::fit(&star, true, degree, 14.0).unwrap());
    }
    out
}

// ---------------------------------------------------------------- DXF

/// The (group code, value) pairs of a DXF file.
fn dxf_tags(text: &str) -> Vec<(i32, String)> {
    let lines: Vec<&str> = text.lines().collect();
    assert!(lines.len().is_multiple_of(2), "odd number of lines");
    lines
        .chunks(2)
        .map(|c| {
            let code = c[0].trim().parse::<i32>().expect("a group code");
            (code, c[1].to_string())
        })
        .collect()
}

/// A SPLINE entity as read back: flags, degree, knots, control points.
struct ReadSpline {
    flags: i64,
    degree: usize,
    knots: Vec<f64>,
    ctrl: Vec<[f64; 3]>,
}

/// The first SPLINE entity, with the counts (72, 73) checked against the
/// values read.
fn read_spline(tags: &[(i32, String)]) -> ReadSpline {
    let start = tags
        .iter()
        .position(|(c, v)| *c == 0 && v == "SPLINE")
        .expect("a SPLINE entity");
    let mut s = ReadSpline {
        flags: -1,
        degree: 0,
        knots: vec![],
        ctrl: vec![],
    };
    let (mut n_knots, mut n_ctrl) = (0, 0);
    for (code, value) in tags[start + 1..].iter().take_while(|(c, _)| *c != 0) {
        let f = || value.trim().parse::<f64>().expect("a number");
        let i = || value.trim().parse::<i64>().expect("an integer");
        match code {
            70 => s.flags = i(),
            71 => s.degree = i() as usize,
            72 => n_knots = i() as usize,
            73 => n_ctrl = i() as usize,
            40 => s.knots.push(f()),
            10 => s.ctrl.push([f(), f64::NAN, f64::NAN]),
            20 => s.ctrl.last_mut().expect("10 before 20")[1] = f(),
            30 => s.ctrl.last_mut().expect("10 before 30")[2] = f(),
            41 => panic!("weights written for a non-rational spline"),
            _ => {}
        }
    }
    assert_eq!(s.knots.len(), n_knots, "group 72");
    assert_eq!(s.ctrl.len(), n_ctrl, "group 73");
    assert_eq!(s.knots.len(), s.ctrl.len() + s.degree + 1);
    s
}

/// de Boor's algorithm on the control points (the library evaluates basis
/// functions instead): `C(u)`, `u` in `[U_p, U_n]`.
fn de_boor(p: usize, knots: &[f64], ctrl: &[[f64; 2]], u: f64) -> [f64; 2] {
    let n = ctrl.len();
    let mut k = p;
    while k + 1 < n && knots[k + 1] <= u {
        k += 1;
    }
    let mut d: Vec<[f64; 2]> = (0..=p).map(|j| ctrl[j + k - p]).collect();
    for r in 1..=p {
        for j in (r..=p).rev() {
            let i = j + k - p;
            let alpha = (u - knots[i]) / (knots[i + 1 + p - r] - knots[i]);
            d[j] = [
                (1.0 - alpha) * d[j - 1][0] + alpha * d[j][0],
                (1.0 - alpha) * d[j - 1][1] + alpha * d[j][1],
            ];
        }
    }
    d[p]
}

/// Largest distance between the DXF spline (mapped back to image
/// coordinates by `sign` on y) and the curve, over 4000 parameters of the
/// curve's domain, which the DXF knots keep.
fn dxf_gap(s: &ReadSpline, c: &SplineCurve, sign: f64) -> f64 {
    let l = c.param_length();
    let p = s.degree;
    assert_eq!(s.knots[p], 0.0);
    assert!((s.knots[s.ctrl.len()] - l).abs() < 1e-12 * l);
    let ctrl: Vec<[f64; 2]> = s.ctrl.iter().map(|q| [q[0], sign * q[1]]).collect();
    (0..=4000)
        .map(|i| {
            let u = l * i as f64 / 4000.0;
            dist(de_boor(p, &s.knots, &ctrl, u), c.point(u))
        })
        .fold(0.0, f64::max)
}

#[test]
fn dxf_spline_reproduces_the_curve() {
    for c in curves() {
        let data = c.to_data();
        let name = format!("degree {} closed {}", data.degree, data.closed);
        for form in [ClosedForm::Periodic, ClosedForm::Clamped] {
            for (y_axis, sign) in [(YAxis::Up, -1.0), (YAxis::Down, 1.0)] {
                let options = DxfOptions {
                    y_axis,
                    closed_form: form,
                    comment: "test".into(),
                };
                let text = spline_dxf(&data, &options).unwrap();
                let s = read_spline(&dxf_tags(&text));
                assert_eq!(s.degree, data.degree);
                assert!(s.ctrl.iter().all(|q| q[2] == 0.0));
                let gap = dxf_gap(&s, &c, sign);
                assert!(gap < TOL, "{name} {form:?} {y_axis:?}: {gap:e}");
                let p = s.degree;
                let n = s.ctrl.len();
                let first = [s.ctrl[0][0], s.ctrl[0][1]];
                let last = [s.ctrl[n - 1][0], s.ctrl[n - 1][1]];
                if data.closed && form == ClosedForm::Periodic {
                    // Closed + periodic + planar; p points repeated.
                    assert_eq!(s.flags, 11, "{name}");
                    for i in 0..p {
                        assert_eq!(s.ctrl[i], s.ctrl[n - p + i], "{name}");
                    }
                } else {
                    // Planar, clamped: starts and ends at control points.
                    assert_eq!(s.flags, 8, "{name} {form:?}");
                    assert!(s.knots[..=p].iter().all(|&k| k == 0.0));
                    assert!(s.knots[n..].iter().all(|&k| k == s.knots[n]));
                    let end0 = c.point(0.0);
                    assert!(dist(first, [end0[0], sign * end0[1]]) < TOL);
                    if data.closed {
                        assert!(
                            dist(first, last) < TOL,
                            "{name}: clamped closed form not closed"
                        );
                    }
                }
            }
        }
    }
}

#[test]
fn dxf_drawing_has_the_structure_cad_programs_require() {
    let c = &curves()[5];
    let text = spline_dxf(&c.to_data(), &DxfOptions::default()).unwrap();
    assert!(text.starts_with("999\n"), "comment first");
    assert!(text.contains("y_dxf = -y"));
    let tags = dxf_tags(&text);
    // Sections in order, each closed, then EOF.
    let sections: Vec<&str> = tags
        .windows(2)
        .filter(|w| w[0] == (0, "SECTION".into()))
        .map(|w| w[1].1.as_str())
        .collect();
    assert_eq!(
        sections,
        ["HEADER", "CLASSES", "TABLES", "BLOCKS", "ENTITIES", "OBJECTS"]
    );
    let count = |v: &str| tags.iter().filter(|t| t.0 == 0 && t.1 == v).count();
    assert_eq!(count("ENDSEC"), 6);
    assert_eq!(tags.last().unwrap(), &(0, "EOF".to_string()));
    // Header: AC1015 (R2000, the first with this SPLINE layout) and the
    // handle seed.
    let var = |name: &str| -> String {
        let i = tags
            .iter()
            .position(|t| t.0 == 9 && t.1 == name)
            .unwrap_or_else(|| panic!("{name}"));
        tags[i + 1].1.clone()
    };
    assert_eq!(var("$ACADVER"), "AC1015");
    let seed = u64::from_str_radix(&var("$HANDSEED"), 16).unwrap();
    // Tables and their mandatory entries.
    for (table, entries) in [
        ("VPORT", vec!["*Active"]),
        ("LTYPE", vec!["ByBlock", "ByLayer", "Continuous"]),
        ("LAYER", vec!["0"]),
        ("STYLE", vec!["Standard"]),
        ("VIEW", vec![]),
        ("UCS", vec![]),
        ("APPID", vec!["ACAD"]),
        ("DIMSTYLE", vec!["Standard"]),
        ("BLOCK_RECORD", vec!["*Model_Space", "*Paper_Space"]),
    ] {
        let start = tags
            .windows(2)
            .position(|w| w[0] == (0, "TABLE".into()) && w[1] == (2, table.into()))
            .unwrap_or_else(|| panic!("table {table}"));
        let end = start
            + tags[start..]
                .iter()
                .position(|t| *t == (0, "ENDTAB".into()))
                .unwrap();
        let records = tags[start..end]
            .iter()
            .filter(|t| t.0 == 0 && t.1 == table)
            .count();
        assert_eq!(records, entries.len(), "entries of {table}");
        for e in entries {
            assert!(
                tags[start..end].iter().any(|t| t.0 == 2 && t.1 == e),
                "{table} {e}"
            );
        }
    }
    // Handles (5, or 105 for DIMSTYLE) unique and below the seed; every
    // pointer (330 owner, 340/350/390) names an object of the file.
    let handles: Vec<u64> = tags
        .iter()
        .enumerate()
        .filter(|(i, t)| (t.0 == 5 || t.0 == 105) && tags[i - 1] != (9, "$HANDSEED".into()))
        .map(|(_, t)| t)
        .map(|t| u64::from_str_radix(&t.1, 16).expect("hex handle"))
        .collect();
    let set: HashSet<u64> = handles.iter().copied().collect();
    assert_eq!(set.len(), handles.len(), "duplicate handles");
    assert!(handles.iter().all(|&h| h > 0 && h < seed));
    for t in tags.iter().filter(|t| [330, 340, 350, 390].contains(&t.0)) {
        let h = u64::from_str_radix(&t.1, 16).unwrap();
        assert!(
            h == 0 && t.0 == 330 || set.contains(&h),
            "dangling pointer {t:?}"
        );
    }
    // The spline belongs to the model space block record, on layer 0.
    let spline = tags
        .iter()
        .position(|t| *t == (0, "SPLINE".into()))
        .unwrap();
    let field = |code: i32| {
        tags[spline + 1..]
            .iter()
            .take_while(|t| t.0 != 0)
            .find(|t| t.0 == code)
            .map(|t| t.1.clone())
    };
    let owner = field(330).unwrap();
    let model: HashMap<_, _> = tags
        .windows(6)
        .filter(|w| w[0] == (0, "BLOCK_RECORD".into()))
        .filter_map(|w| {
            let name = w.iter().find(|t| t.0 == 2)?.1.clone();
            let handle = w.iter().find(|t| t.0 == 5)?.1.clone();
            Some((name, handle))
        })
        .collect();
    assert_eq!(model.get("*Model_Space"), Some(&owner));
    assert_eq!(field(8).as_deref(), Some("0"));
    assert_eq!(field(100).as_deref(), Some("AcDbEntity"));
}

// ---------------------------------------------------------------- SVG

/// The numbers of an SVG path's `d` attribute, with its commands.
fn path_tokens(d: &str) -> Vec<String> {
    d.replace(',', " ")
        .split_whitespace()
        .map(String::from)
        .collect()
}

/// The `d` of the first `<path>` of a document.
fn path_d(svg: &str) -> String {
    let doc = roxmltree::Document::parse(svg).expect("well-formed SVG");
    doc.descendants()
        .find(|n| n.has_tag_name("path"))
        .and_then(|n| n.attribute("d"))
        .expect("a path with d")
        .to_string()
}

/// Parse `M x y (C x1 y1 x2 y2 x3 y3)* [Z]` into cubic segments.
fn parse_cubics(d: &str) -> (Vec<[[f64; 2]; 4]>, bool) {
    let t = path_tokens(d);
    let num = |i: usize| t[i].parse::<f64>().expect("a number");
    assert_eq!(t[0], "M");
    let mut cur = [num(1), num(2)];
    let mut i = 3;
    let mut segs = Vec::new();
    while i < t.len() && t[i] == "C" {
        let q = [
            cur,
            [num(i + 1), num(i + 2)],
            [num(i + 3), num(i + 4)],
            [num(i + 5), num(i + 6)],
        ];
        cur = q[3];
        segs.push(q);
        i += 7;
    }
    let closed = i < t.len() && t[i] == "Z";
    assert_eq!(i + usize::from(closed), t.len(), "unexpected path tokens");
    (segs, closed)
}

/// Bernstein form of a cubic Bézier.
fn cubic(q: &[[f64; 2]; 4], t: f64) -> [f64; 2] {
    let s = 1.0 - t;
    let b = [s * s * s, 3.0 * s * s * t, 3.0 * s * t * t, t * t * t];
    let mut out = [0.0; 2];
    for k in 0..4 {
        out[0] += b[k] * q[k][0];
        out[1] += b[k] * q[k][1];
    }
    out
}

/// Largest distance between the segments (segment k on the k-th non-empty
/// knot span of the data's domain) and the curve.
fn svg_gap(segs: &[[[f64; 2]; 4]], data: &SplineCurveData, c: &SplineCurve) -> f64 {
    let n = data.control_points.len();
    let p = data.degree;
    let mut spans: Vec<f64> = data.knots[p..=n].to_vec();
    spans.dedup();
    assert_eq!(segs.len(), spans.len() - 1, "one segment per knot span");
    let mut worst: f64 = 0.0;
    for (k, q) in segs.iter().enumerate() {
        for i in 0..=100 {
            let t = i as f64 / 100.0;
            let u = spans[k] + t * (spans[k + 1] - spans[k]);
            worst = worst.max(dist(cubic(q, t), c.point(u)));
        }
    }
    worst
}

#[test]
fn svg_cubic_beziers_reproduce_the_curve() {
    for c in curves() {
        let data = c.to_data();
        let name = format!("degree {} closed {}", data.degree, data.closed);
        if data.degree > 3 {
            let e = curve_svg(&data, &SvgOptions::default()).unwrap_err();
            assert!(
                matches!(e, Error::InvalidParameter { name: "degree", .. }),
                "{name}"
            );
            assert!(cubic_segments(&data).is_err());
            continue;
        }
        let svg = curve_svg(
            &data,
            &SvgOptions {
                canvas: Some((300, 200)),
                ..SvgOptions::default()
            },
        )
        .unwrap();
        assert!(svg.contains(r#"viewBox="0 0 300 200""#));
        let (segs, closed) = parse_cubics(&path_d(&svg));
        assert_eq!(closed, data.closed, "{name}");
        let gap = svg_gap(&segs, &data, &c);
        assert!(gap < TOL, "{name}: {gap:e}");
        if closed {
            let (first, last) = (segs[0][0], segs[segs.len() - 1][3]);
            assert!(dist(first, last) < TOL, "{name}: not closed");
        }
        // Without a canvas: a view box around the curve.
        let svg = curve_svg(&data, &SvgOptions::default()).unwrap();
        assert!(roxmltree::Document::parse(&svg).is_ok());
    }
}

// ------------------------------------------------- from real measurements

/// Measured curves (an open edge and a closed one, exact-coverage images
/// blurred by 1 px), written as the result file `vicurve measure --out`
/// writes, read back, exported: both exports reproduce the measured curve.
#[test]
fn measured_curves_export_exactly_through_the_result_file() {
    let cases = [
        (
            Shape::Sine {
                y0: 150.2,
                amplitude: 12.0,
                wavelength: 150.0,
                phase: 0.3,
                x_min: 30.0,
                x_max: 270.0,
            },
            InitialCurve::Segment {
                x0: 30.0,
                y0: 150.0,
                x1: 270.0,
                y1: 150.0,
            },
        ),
        (
            Shape::Circle {
                cx: 150.3,
                cy: 149.8,
                r: 80.0,
            },
            InitialCurve::Circle {
                cx: 148.0,
                cy: 151.0,
                r: 84.0,
            },
        ),
    ];
    for (shape, init) in cases {
        let spec = RenderSpec {
            width: 300,
            height: 300,
            shape,
            kind: Kind::Silhouette,
            method: Method::Coverage,
            foreground: 0.8,
            background: 0.2,
            blur_sigma: 1.0,
            bits: Some(8),
            ..RenderSpec::default()
        };
        let image = render(&spec).unwrap();
        let config = FitConfig::default();
        let m = measure(&image, &init, &config).unwrap();
        assert_eq!(m.outcome, Outcome::Converged);
        let json = ResultFile::new("test.png", (300, 300), &init, &config, &m).to_json();
        let back = parse_result_curve(&json, "test").unwrap();
        assert_eq!(back.curve, m.curve_data(), "JSON round trip");
        assert_eq!(back.size, Some((300, 300)));
        let data = back.curve;

        let text = spline_dxf(&data, &DxfOptions::default()).unwrap();
        let s = read_spline(&dxf_tags(&text));
        assert_eq!(s.flags, if data.closed { 11 } else { 8 });
        let gap = dxf_gap(&s, &m.curve, -1.0);
        println!("closed {}: DXF gap {gap:.1e} px", data.closed);
        assert!(gap < TOL);
        let direct = dxf_spline(&data, &DxfOptions::default()).unwrap();
        assert_eq!(direct.knots, s.knots, "knots written exactly");

        let svg = curve_svg(
            &data,
            &SvgOptions {
                canvas: back.size,
                ..SvgOptions::default()
            },
        )
        .unwrap();
        let (segs, closed) = parse_cubics(&path_d(&svg));
        assert_eq!(closed, data.closed);
        let gap = svg_gap(&segs, &data, &m.curve);
        println!("closed {}: SVG gap {gap:.1e} px", data.closed);
        assert!(gap < TOL);
    }
}

#[test]
fn bad_input_gives_typed_errors() {
    let c = &curves()[4];
    let mut nan = c.to_data();
    nan.control_points[2][0] = f64::NAN;
    assert!(matches!(
        spline_dxf(&nan, &DxfOptions::default()),
        Err(Error::NonFinite { .. })
    ));
    assert!(matches!(
        curve_svg(&nan, &SvgOptions::default()),
        Err(Error::NonFinite { .. })
    ));
    let mut empty = c.to_data();
    empty.control_points.clear();
    empty.knots.clear();
    assert!(spline_dxf(&empty, &DxfOptions::default()).is_err());
    let mut broken = c.to_data();
    broken.control_points.pop();
    assert!(matches!(
        spline_dxf(&broken, &DxfOptions::default()),
        Err(Error::InvalidCurve { .. })
    ));
    // A closed curve whose wrap-around points do not repeat.
    let mut unwrapped = curves()[5].to_data();
    unwrapped.control_points.last_mut().unwrap()[0] += 1.0;
    assert!(matches!(
        spline_dxf(&unwrapped, &DxfOptions::default()),
        Err(Error::InvalidCurve { .. })
    ));
    let svg = SvgOptions {
        stroke_width: -1.0,
        ..SvgOptions::default()
    };
    assert!(curve_svg(&c.to_data(), &svg).is_err());
    let svg = SvgOptions {
        stroke: "\"><script".into(),
        ..SvgOptions::default()
    };
    assert!(curve_svg(&c.to_data(), &svg).is_err());

    assert!(matches!(
        parse_result_curve("{not json", "x.json"),
        Err(Error::Parse { .. })
    ));
    assert!(matches!(
        parse_result_curve("{\"curve\": 3}", "x.json"),
        Err(Error::Parse { .. })
    ));
    let with_null =
        r#"{"curve": {"degree": 1, "closed": false, "knots": [null], "control_points": []}}"#;
    assert!(matches!(
        parse_result_curve(with_null, "x.json"),
        Err(Error::Parse { .. })
    ));
    assert!(matches!(
        read_result_curve("/nonexistent/result.json".as_ref()),
        Err(Error::NotFound { .. })
    ));
}
