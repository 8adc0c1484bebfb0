//! Starts without a drawn curve, end to end: `--grow` from a segment, and
//! `--pick` on a thin line (`--kind contour`).

use std::path::Path;

use crate::common::{p, text, vicurve};

fn json(path: &str) -> serde_json::Value {
    serde_json::from_str(&std::fs::read_to_string(path).unwrap()).unwrap()
}

/// Largest error of the points against the truth, via `vicurve eval`.
fn max_error(dir: &Path, points: &str, truth: &str) -> f64 {
    let stats = p(dir, "stats.json");
    let out = vicurve(&["eval", points, truth, "--json", &stats]);
    assert!(out.status.success(), "{}", text(&out.stderr));
    json(&stats)["max_abs"].as_f64().unwrap()
}

/// `vicurve synth PRESET` (blur 1) into `dir`: the image's and the truth's
/// paths.
fn synth(dir: &Path, preset: &str, size: &str, radius: &str) -> (String, String) {
    let (img, truth) = (
        p(dir, &format!("{preset}.png")),
        p(dir, &format!("{preset}.json")),
    );
    let out = vicurve(&[
        "synth", preset, "--size", size, "--radius", radius, "--blur", "1", "--out", &img,
        "--truth", &truth,
    ]);
    assert!(out.status.success(), "{}", text(&out.stderr));
    (img, truth)
}

/// A 20 px segment on a disc's edge grows into the closed disc; the JSON
/// says how it grew. A closed start cannot grow.
#[test]
fn grow_from_a_segment() {
    let dir = tempfile::tempdir().unwrap();
    let d = dir.path();
    let (img, truth) = synth(d, "disc", "200x200", "60");
    // The disc's centre is (100.3, 99.8): its right edge is at x = 160.3.
    let (res, pts) = (p(d, "r.json"), p(d, "r.csv"));
    let out = vicurve(&[
        "measure",
        &img,
        "--init",
        "segment:158,110,158,90",
        "--grow",
        "--out",
        &res,
        "--points",
        &pts,
    ]);
    let err = text(&out.stderr);
    assert!(out.status.success(), "{err}");
    assert!(err.contains("closed curve"), "{err}");
    let doc = json(&res);
    assert_eq!(doc["grow"]["ends"], serde_json::json!(["closed", "closed"]));
    assert!(doc["area"].is_number(), "a closed curve has an area");
    let max = max_error(d, &pts, &truth);
    assert!(max < 0.02, "max {max}");

    // --grow LEN: an open piece of about that length.
    let out = vicurve(&[
        "measure",
        &img,
        "--init",
        "segment:158,110,158,90",
        "--grow",
        "100",
        "--out",
        &res,
    ]);
    assert!(out.status.success(), "{}", text(&out.stderr));
    let doc = json(&res);
    let length = doc["length"].as_f64().unwrap();
    assert!((length - 100.0).abs() < 3.0, "length {length}");
    assert_eq!(doc["grow"]["ends"], serde_json::json!(["length", "length"]));

    let out = vicurve(&["measure", &img, "--init", "circle:100,100,55", "--grow"]);
    assert_eq!(out.status.code(), Some(1));
    let err = text(&out.stderr);
    assert!(
        err.starts_with("vicurve: error: ") && err.contains("open start"),
        "{err}"
    );
    assert_eq!(err.lines().count(), 1, "{err}");
}

/// A thin bright ring: `--kind contour --pick` on it follows the line all
/// round and measures it.
#[test]
fn contour_from_a_picked_point() {
    let dir = tempfile::tempdir().unwrap();
    let d = dir.path();
    let (img, truth) = synth(d, "ring", "240x240", "80");
    // The ring's centre is (120.3, 119.8): its rightmost point is (200.3, 119.8).
    let (res, pts) = (p(d, "r.json"), p(d, "r.csv"));
    let out = vicurve(&[
        "measure", &img, "--kind", "contour", "--pick", "201,121", "--out", &res, "--points", &pts,
    ]);
    let err = text(&out.stderr);
    assert!(out.status.success(), "{err}");
    assert!(
        err.contains("line followed") && err.contains("closed"),
        "{err}"
    );
    let doc = json(&res);
    assert!(doc["initial_curve"].to_string().contains("polyline"));
    let max = max_error(d, &pts, &truth);
    assert!(max < 0.03, "max {max}");

    // A point on the blank ground finds no line.
    let out = vicurve(&["measure", &img, "--kind", "contour", "--pick", "20,20"]);
    assert_eq!(out.status.code(), Some(1));
    let err = text(&out.stderr);
    assert!(
        err.starts_with("vicurve: error: ") && err.contains("line"),
        "{err}"
    );
}
