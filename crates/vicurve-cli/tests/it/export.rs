//! `vicurve measure --dxf/--svg-curve`, `vicurve export` and `vicurve
//! mesh`, end to end: files written, consistent with the result file, and
//! bad inputs giving one line and exit 1.

use std::path::Path;

use crate::common::{assert_error, ok, p, text, vicurve};

/// A 300x200 sinusoidal edge at mean row `y0`, measured from a segment;
/// returns the result file.
fn edge(dir: &Path, name: &str, y0: &str, extra: &[&str]) -> String {
    let img = p(dir, &format!("{name}.png"));
    ok(&vicurve(&[
        "synth",
        "sine-edge",
        "--size",
        "300x200",
        "--y0",
        y0,
        "--amplitude",
        "6",
        "--wavelength",
        "140",
        "--blur",
        "1",
        "--out",
        &img,
    ]));
    let json = p(dir, &format!("{name}.json"));
    let init = format!("segment:20,{y0},280,{y0}");
    let mut args = vec![
        "measure",
        img.as_str(),
        "--init",
        init.as_str(),
        "--out",
        json.as_str(),
    ];
    args.extend_from_slice(extra);
    ok(&vicurve(&args));
    json
}

/// The values of group code `code` in the SPLINE entity of a DXF file.
fn dxf_values(text: &str, code: &str) -> Vec<String> {
    let start = text.find("\nAcDbSpline\n").expect("a SPLINE");
    let end = start + text[start..].find("\nENDSEC\n").expect("its end");
    let lines: Vec<&str> = text[start + 1..end].lines().skip(1).collect();
    lines
        .chunks(2)
        .filter(|c| c[0].trim() == code)
        .map(|c| c[1].to_string())
        .collect()
}

#[test]
fn measure_and_export_write_the_same_curve() {
    let dir = tempfile::tempdir().unwrap();
    let d = dir.path();
    let (dxf, svg) = (p(d, "m.dxf"), p(d, "m.svg"));
    let json = edge(d, "top", "60.3", &["--dxf", &dxf, "--svg-curve", &svg]);
    let (dxf2, svg2) = (p(d, "e.dxf"), p(d, "e.svg"));
    ok(&vicurve(&[
        "export",
        &json,
        "--dxf",
        &dxf2,
        "--svg-curve",
        &svg2,
    ]));
    let read = |f: &str| std::fs::read_to_string(f).unwrap();
    // The same curve, whether exported while measuring or from the file.
    assert_eq!(
        dxf_values(&read(&dxf), "10"),
        dxf_values(&read(&dxf2), "10")
    );
    assert_eq!(
        dxf_values(&read(&dxf), "40"),
        dxf_values(&read(&dxf2), "40")
    );
    let path = |t: String| {
        t.lines()
            .find(|l| l.starts_with("<path"))
            .unwrap()
            .to_string()
    };
    assert_eq!(path(read(&svg)), path(read(&svg2)));
    // An open curve: clamped, planar; y flipped unless --dxf-y down.
    let t = read(&dxf);
    assert!(t.contains("AC1015"));
    assert_eq!(dxf_values(&t, "70").last().map(String::as_str), Some("8"));
    let result: serde_json::Value = serde_json::from_str(&read(&json)).unwrap();
    let y_first = result["curve"]["control_points"][3][1].as_f64().unwrap();
    let ys: Vec<f64> = dxf_values(&t, "20")
        .iter()
        .map(|v| v.parse().unwrap())
        .collect();
    assert!(ys.iter().all(|&y| y < 0.0), "y_dxf = -y");
    let down = p(d, "down.dxf");
    ok(&vicurve(&[
        "export", &json, "--dxf", &down, "--dxf-y", "down",
    ]));
    let ys: Vec<f64> = dxf_values(&read(&down), "20")
        .iter()
        .map(|v| v.parse().unwrap())
        .collect();
    assert!(ys.iter().any(|&y| (y - y_first).abs() < 5.0) && ys.iter().all(|&y| y > 0.0));
    assert!(read(&svg).contains(r#"viewBox="0 0 300 200""#));
}

#[test]
fn mesh_between_two_measured_edges() {
    let dir = tempfile::tempdir().unwrap();
    let d = dir.path();
    let top = edge(d, "top", "60.3", &[]);
    let bottom = edge(d, "bottom", "140.7", &[]);
    let (out, vtu, net) = (p(d, "patch.json"), p(d, "patch.vtu"), p(d, "net.vtu"));
    let o = vicurve(&[
        "mesh",
        &top,
        &bottom,
        "--out",
        &out,
        "--vtu",
        &vtu,
        "--vtu-net",
        &net,
        "--refine-along",
        "2",
        "--refine-across",
        "3",
        "--degree-across",
        "2",
        "--vtu-cells",
        "2,2",
    ]);
    ok(&o);
    assert!(text(&o.stdout).contains("degree 3 along x 2 across"));
    let rec: serde_json::Value =
        serde_json::from_str(&std::fs::read_to_string(&out).unwrap()).unwrap();
    let patch = &rec["patch"];
    assert_eq!(patch["degree_u"], 3);
    assert_eq!(patch["degree_v"], 2);
    let nu = patch["control_points"].as_array().unwrap().len();
    assert_eq!(patch["knots_u"].as_array().unwrap().len(), nu + 4);
    assert_eq!(rec["elements"][1], 3);
    assert_eq!(rec["reversed_second"], false);
    assert!(patch["weights"]
        .as_array()
        .unwrap()
        .iter()
        .flat_map(|r| r.as_array().unwrap())
        .all(|w| w == 1.0));
    let first_row = &patch["control_points"][0];
    // Degree 2 on 3 elements across: 5 control points per row.
    assert_eq!(first_row.as_array().unwrap().len(), 5);
    let v = std::fs::read_to_string(&vtu).unwrap();
    assert!(v.contains(r#"type="UnstructuredGrid""#) && v.trim_end().ends_with("</VTKFile>"));
    assert!(std::fs::metadata(&net).unwrap().len() > 1000);
}

#[test]
fn bad_inputs_give_one_line() {
    let dir = tempfile::tempdir().unwrap();
    let d = dir.path();
    let top = edge(d, "top", "60.3", &[]);
    let garbage = p(d, "garbage.json");
    std::fs::write(&garbage, "{ not json").unwrap();
    assert_error(
        &vicurve(&["export", &garbage, "--dxf", &p(d, "x.dxf")]),
        1,
        "cannot parse",
    );
    assert_error(
        &vicurve(&["export", &p(d, "missing.json"), "--dxf", &p(d, "x.dxf")]),
        1,
        "not found",
    );
    assert_error(&vicurve(&["export", &top]), 1, "nothing to write");
    assert_error(&vicurve(&["mesh", &top, &garbage]), 1, "cannot parse");
    assert_error(
        &vicurve(&["mesh", &top, &top, "--refine-along", "0"]),
        1,
        "refinement along",
    );
    assert_error(
        &vicurve(&["mesh", &top, &top, "--vtu-cells", "2x2"]),
        1,
        "--vtu-cells",
    );
    assert_error(&vicurve(&["mesh", &top, &top]), 1, "same");
    // A closed curve cannot bound the patch.
    let disc = p(d, "disc.png");
    ok(&vicurve(&[
        "synth", "disc", "--size", "160x160", "--radius", "40", "--blur", "1", "--out", &disc,
    ]));
    let closed = p(d, "disc.json");
    ok(&vicurve(&[
        "measure",
        &disc,
        "--init",
        "circle:80,80,44",
        "--out",
        &closed,
    ]));
    assert_error(&vicurve(&["mesh", &top, &closed]), 1, "closed");
    // SVG cubic Béziers need degree <= 3: refused before measuring.
    assert_error(
        &vicurve(&[
            "measure",
            &disc,
            "--init",
            "circle:80,80,44",
            "--degree",
            "5",
            "--svg-curve",
            &p(d, "c.svg"),
        ]),
        1,
        "degree 5",
    );
    // A NaN in the result file (written as null) is a parse error.
    let text =
        std::fs::read_to_string(&top)
            .unwrap()
            .replacen("\"knots\": [", "\"knots\": [null, ", 1);
    let nan = p(d, "nan.json");
    std::fs::write(&nan, text).unwrap();
    assert_error(
        &vicurve(&["export", &nan, "--dxf", &p(d, "x.dxf")]),
        1,
        "cannot parse",
    );
    // An unwritable output.
    assert_error(
        &vicurve(&["export", &top, "--dxf", &p(d, "no/such/dir/x.dxf")]),
        1,
        "cannot write",
    );
}
