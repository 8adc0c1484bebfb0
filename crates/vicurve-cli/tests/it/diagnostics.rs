//! `vicurve measure --diagnostics DIR`: the files, their sizes and the
//! JSON record.

use crate::common::{p, text, vicurve};

#[test]
fn diagnostics_files_are_written() {
    let dir = tempfile::tempdir().unwrap();
    let d = dir.path();
    let img = p(d, "disc.png");
    let out = vicurve(&[
        "synth", "disc", "--size", "160x160", "--radius", "50", "--blur", "0.8", "--out", &img,
    ]);
    assert!(out.status.success(), "{}", text(&out.stderr));
    // A directory that does not exist yet, two levels deep.
    let diag = d.join("diag").join("run1");
    let out = vicurve(&[
        "measure",
        &img,
        "--init",
        "circle:81,78,54",
        "--diagnostics",
        diag.to_str().unwrap(),
    ]);
    assert!(out.status.success(), "{}", text(&out.stderr));

    let json: serde_json::Value =
        serde_json::from_str(&std::fs::read_to_string(diag.join("diagnostics.json")).unwrap())
            .unwrap();
    let grid = &json["grid"];
    let (columns, rows) = (
        grid["columns"].as_u64().unwrap() as u32,
        grid["rows"].as_u64().unwrap() as u32,
    );
    // About 2 pi 50 px of curve at 0.5 px, r over at least +-3 px at 0.25.
    assert!((600..=640).contains(&columns), "{columns}");
    assert!(rows >= 25 && rows % 2 == 1, "{rows}");
    assert_eq!(grid["ds"].as_f64(), Some(0.5));
    assert_eq!(grid["dr"].as_f64(), Some(0.25));
    assert!(json["coordinates"].as_str().unwrap().contains("x = column"));
    assert!(json["input"]["path"]
        .as_str()
        .unwrap()
        .ends_with("disc.png"));
    assert!(json["config"]["tolerance"].as_f64().is_some());
    let scale = json["residual_png"]["scale"].as_array().unwrap();
    let s = scale[1].as_f64().unwrap();
    assert!(s > 0.0 && scale[0].as_f64() == Some(-s), "{scale:?}");
    let stages = json["stages"].as_array().unwrap();
    assert!(!stages.is_empty());
    for stage in stages {
        let history = stage["history"].as_array().unwrap();
        assert_eq!(history.len() as u64, stage["iterations"].as_u64().unwrap());
    }

    for name in ["band.png", "residual.png", "weights.png"] {
        let png = image::open(diag.join(name)).unwrap();
        assert_eq!((png.width(), png.height()), (columns, rows), "{name}");
    }
    let plot = image::open(diag.join("convergence.png")).unwrap();
    assert!(plot.width() > 500 && plot.height() > 300);
    // The band's inside (top rows) is brighter than its outside: the disc
    // is bright on a dark ground.
    let band = image::open(diag.join("band.png")).unwrap().to_luma8();
    let row_mean = |y: u32| {
        (0..columns)
            .map(|x| band.get_pixel(x, y)[0] as f64)
            .sum::<f64>()
    };
    assert!(row_mean(0) > row_mean(rows - 1) + 100.0 * columns as f64);
}

#[test]
fn an_unwritable_directory_is_one_line() {
    let dir = tempfile::tempdir().unwrap();
    let d = dir.path();
    let img = p(d, "disc.png");
    let out = vicurve(&[
        "synth", "disc", "--size", "120x120", "--radius", "35", "--out", &img,
    ]);
    assert!(out.status.success(), "{}", text(&out.stderr));
    // A file where the directory should be.
    let blocker = p(d, "taken");
    std::fs::write(&blocker, "x").unwrap();
    let out = vicurve(&[
        "measure",
        &img,
        "--init",
        "circle:61,59,38",
        "--diagnostics",
        &blocker,
    ]);
    let err = text(&out.stderr);
    assert_eq!(out.status.code(), Some(1), "{err}");
    assert_eq!(err.lines().count(), 1, "{err}");
    assert!(err.starts_with("vicurve: error: cannot create the diagnostics directory"));
}

/// A fit that never got a step (no contrast) keeps its exit status 3; the
/// convergence plot and the JSON say why there are no maps.
#[test]
fn a_fit_without_a_band_still_gets_its_convergence() {
    let dir = tempfile::tempdir().unwrap();
    let d = dir.path();
    let img = p(d, "flat.png");
    let out = vicurve(&[
        "synth", "disc", "--size", "120x120", "--radius", "20", "--levels", "0.5,0.5", "--out",
        &img,
    ]);
    assert!(out.status.success(), "{}", text(&out.stderr));
    let diag = d.join("diag");
    let out = vicurve(&[
        "measure",
        &img,
        "--init",
        "circle:60,60,22",
        "--diagnostics",
        diag.to_str().unwrap(),
    ]);
    let err = text(&out.stderr);
    assert_eq!(out.status.code(), Some(3), "{err}");
    assert!(err.contains("warning: diagnostics:"), "{err}");
    assert!(diag.join("convergence.png").exists());
    assert!(!diag.join("band.png").exists());
    let json: serde_json::Value =
        serde_json::from_str(&std::fs::read_to_string(diag.join("diagnostics.json")).unwrap())
            .unwrap();
    assert!(json["maps_missing"]
        .as_str()
        .unwrap()
        .contains("gray levels"));
    assert!(json.get("grid").is_none());
}
