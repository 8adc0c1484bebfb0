//! The command line, end to end: synthesise, measure, evaluate, and every
//! bad input giving one clear line and a non-zero exit.

use std::path::{Path, PathBuf};

use crate::common::{assert_error, p, text, vicurve};

/// A 200x200 disc of radius 60 and its truth, in `dir`.
fn disc(dir: &Path) -> (String, String) {
    let img = p(dir, "disc.png");
    let truth = p(dir, "disc.json");
    let out = vicurve(&[
        "synth", "disc", "--size", "200x200", "--radius", "60", "--blur", "0.8", "--out", &img,
        "--truth", &truth,
    ]);
    assert!(out.status.success(), "{}", text(&out.stderr));
    (img, truth)
}

#[test]
fn synth_measure_eval_round_trip() {
    let dir = tempfile::tempdir().unwrap();
    let d = dir.path();
    let (img, truth) = disc(d);
    let (json, csv, svg, png) = (
        p(d, "r.json"),
        p(d, "pts.csv"),
        p(d, "o.svg"),
        p(d, "o.png"),
    );
    let out = vicurve(&[
        "measure",
        &img,
        "--init",
        "circle:101,98,64",
        "--out",
        &json,
        "--points",
        &csv,
        "--svg",
        &svg,
        "--png",
        &png,
    ]);
    assert!(out.status.success(), "{}", text(&out.stderr));
    // The CSV header is a contract.
    let points = std::fs::read_to_string(&csv).unwrap();
    assert_eq!(
        points.lines().next(),
        Some("s,x,y,nx,ny,sigma,weight,sigma_noise,misfit")
    );
    let rows: Vec<Vec<f64>> = points
        .lines()
        .skip(1)
        .map(|l| l.split(',').map(|v| v.parse().unwrap()).collect())
        .collect();
    assert!(
        rows.len() > 370,
        "{} samples for a 377 px curve",
        rows.len()
    );
    for w in rows.windows(2) {
        let gap = (w[1][1] - w[0][1]).hypot(w[1][2] - w[0][2]);
        assert!(gap <= 1.0 + 1e-9, "samples {gap} px apart");
    }
    // The JSON records what a reader needs.
    let record: serde_json::Value =
        serde_json::from_str(&std::fs::read_to_string(&json).unwrap()).unwrap();
    for key in [
        "input",
        "coordinates",
        "config",
        "initial_curve",
        "outcome",
        "curve",
        "stages",
        "gray_levels",
    ] {
        assert!(record.get(key).is_some(), "missing {key}");
    }
    assert_eq!(record["outcome"]["status"], "converged");
    assert_eq!(record["curve"]["closed"], true);
    assert_eq!(record["polarity"], "bright inside");
    assert!(std::fs::read_to_string(&svg).unwrap().contains("<svg"));
    assert!(std::fs::metadata(&png).unwrap().len() > 1000);
    // eval reads the points back against the truth.
    let stats = p(d, "stats.json");
    let out = vicurve(&["eval", &csv, &truth, "--json", &stats]);
    assert!(out.status.success(), "{}", text(&out.stderr));
    let s: serde_json::Value =
        serde_json::from_str(&std::fs::read_to_string(&stats).unwrap()).unwrap();
    assert!(s["scatter"].as_f64().unwrap() < 5e-3, "{s}");
    assert!(s["bias"].as_f64().unwrap().abs() < 1.5e-2, "{s}");
    assert!(text(&out.stdout).contains("scatter"));
}

#[test]
fn summary_without_outputs() {
    let dir = tempfile::tempdir().unwrap();
    let (img, _) = disc(dir.path());
    let out = vicurve(&[
        "measure",
        &img,
        "--init",
        "circle:100,100,57",
        "--stages",
        "10:8,4:12",
    ]);
    assert!(out.status.success(), "{}", text(&out.stderr));
    let s = text(&out.stdout);
    for word in [
        "outcome:     converged",
        "iterations:",
        "residual:",
        "length:",
        "area:",
    ] {
        assert!(s.contains(word), "{word} missing in {s}");
    }
}

#[test]
fn open_curve_from_a_polyline_file() {
    let dir = tempfile::tempdir().unwrap();
    let d = dir.path();
    let img = p(d, "edge.tif");
    let truth = p(d, "edge.json");
    let out = vicurve(&[
        "synth",
        "sine-edge",
        "--size",
        "240x160",
        "--amplitude",
        "6",
        "--wavelength",
        "200",
        "--bits",
        "16",
        "--blur",
        "1",
        "--out",
        &img,
        "--truth",
        &truth,
    ]);
    assert!(out.status.success(), "{}", text(&out.stderr));
    let poly = d.join("start.csv");
    std::fs::write(&poly, "x,y\n20,80\n120,82\n220,80\n").unwrap();
    let csv = p(d, "pts.csv");
    let out = vicurve(&[
        "measure",
        &img,
        "--init",
        &format!("polyline:{}", poly.display()),
        "--points",
        &csv,
    ]);
    assert!(out.status.success(), "{}", text(&out.stderr));
    let out = vicurve(&["eval", &csv, &truth]);
    let s = text(&out.stdout);
    let scatter: f64 = s
        .lines()
        .find(|l| l.starts_with("scatter"))
        .and_then(|l| l.split_whitespace().nth(1))
        .and_then(|v| v.parse().ok())
        .unwrap();
    assert!(scatter < 1e-2, "{s}");
}

#[test]
fn bad_inputs_give_one_line_and_a_nonzero_exit() {
    let dir = tempfile::tempdir().unwrap();
    let d = dir.path();
    let (img, _) = disc(d);
    let missing = p(d, "nope.png");
    assert_error(
        &vicurve(&["measure", &missing, "--init", "circle:100,100,60"]),
        1,
        "not found",
    );

    let text_file = d.join("text.png");
    std::fs::write(&text_file, "this is not an image").unwrap();
    assert_error(
        &vicurve(&[
            "measure",
            &text_file.display().to_string(),
            "--init",
            "circle:100,100,60",
        ]),
        1,
        "unsupported",
    );

    let empty = d.join("empty.png");
    std::fs::write(&empty, b"").unwrap();
    assert_error(
        &vicurve(&[
            "measure",
            &empty.display().to_string(),
            "--init",
            "circle:100,100,60",
        ]),
        1,
        "image",
    );

    let bytes = std::fs::read(&img).unwrap();
    let truncated = d.join("truncated.png");
    std::fs::write(&truncated, &bytes[..bytes.len() / 2]).unwrap();
    assert_error(
        &vicurve(&[
            "measure",
            &truncated.display().to_string(),
            "--init",
            "circle:100,100,60",
        ]),
        1,
        "decode",
    );

    assert_error(
        &vicurve(&["measure", &img, "--init", "circle:100,100"]),
        1,
        "circle needs 3 numbers",
    );
    assert_error(
        &vicurve(&["measure", &img, "--init", "square:1,2,3"]),
        1,
        "unknown curve type",
    );
    assert_error(
        &vicurve(&["measure", &img, "--init", "circle:NaN,100,60"]),
        1,
        "non-finite",
    );
    assert_error(
        &vicurve(&[
            "measure",
            &img,
            "--init",
            "circle:100,100,60",
            "--stages",
            "10",
        ]),
        1,
        "stages",
    );
    assert_error(
        &vicurve(&[
            "measure",
            &img,
            "--init",
            "circle:100,100,60",
            "--stages",
            "10:x",
        ]),
        1,
        "stages",
    );
    assert_error(
        &vicurve(&[
            "measure",
            &img,
            "--init",
            "circle:100,100,60",
            "--degree",
            "7",
        ]),
        1,
        "degree",
    );
    assert_error(
        &vicurve(&[
            "measure",
            &img,
            "--init",
            "circle:100,100,60",
            "--polarity",
            "up",
        ]),
        1,
        "polarity",
    );
    // Initial curve outside the image; an open curve along the border,
    // whose band fits nowhere (a closed curve's band may be cut by the
    // border).
    assert_error(
        &vicurve(&["measure", &img, "--init", "circle:100,100,150"]),
        1,
        "leaves the image",
    );
    assert_error(
        &vicurve(&[
            "measure",
            &img,
            "--init",
            "segment:0.5,10,0.5,190",
            "--stages",
            "5:10",
        ]),
        1,
        "band",
    );
    // NaN in a polyline file.
    let poly = d.join("nan.csv");
    std::fs::write(&poly, "10,10\n20,NaN\n30,30\n").unwrap();
    assert_error(
        &vicurve(&[
            "measure",
            &img,
            "--init",
            &format!("polyline:{}", poly.display()),
        ]),
        1,
        "non-finite",
    );
    // Eval with a malformed truth file.
    let bad_truth = d.join("bad.json");
    std::fs::write(&bad_truth, "{\"shape\": \"circle\"").unwrap();
    let pts = d.join("pts.csv");
    std::fs::write(&pts, "x,y\n1,2\n").unwrap();
    assert_error(
        &vicurve(&[
            "eval",
            &pts.display().to_string(),
            &bad_truth.display().to_string(),
        ]),
        1,
        "parse",
    );
    // Synth with a bad size.
    assert_error(
        &vicurve(&["synth", "disc", "--size", "0x10", "--out", &p(d, "x.png")]),
        1,
        "size",
    );
}

#[test]
fn a_diverging_fit_keeps_its_outputs_and_exits_3() {
    let dir = tempfile::tempdir().unwrap();
    let d = dir.path();
    // A uniform image: no edge anywhere, the band sees no contrast.
    let img = p(d, "flat.png");
    let out = vicurve(&[
        "synth", "disc", "--size", "120x120", "--radius", "20", "--levels", "0.5,0.5", "--out",
        &img,
    ]);
    assert!(out.status.success(), "{}", text(&out.stderr));
    let json = p(d, "r.json");
    let out = vicurve(&[
        "measure",
        &img,
        "--init",
        "circle:60,60,30",
        "--stages",
        "5:10",
        "--out",
        &json,
    ]);
    assert_error(&out, 3, "diverged");
    let record: serde_json::Value =
        serde_json::from_str(&std::fs::read_to_string(&json).unwrap()).unwrap();
    assert_eq!(record["outcome"]["status"], "diverged");
}

#[test]
fn demo_runs_and_reports_accuracy() {
    let dir = tempfile::tempdir().unwrap();
    let out_dir: PathBuf = dir.path().join("demo");
    let out = vicurve(&["demo", "--out-dir", &out_dir.display().to_string()]);
    assert!(out.status.success(), "{}", text(&out.stderr));
    let s = text(&out.stdout);
    assert!(s.contains("scatter") && s.contains("converged"), "{s}");
    for f in [
        "star.png",
        "truth.json",
        "result.json",
        "points.csv",
        "overlay.svg",
        "overlay.png",
    ] {
        assert!(out_dir.join(f).exists(), "{f} missing");
    }
}

/// `bench paper --quick` writes every file, and its numbers are those of
/// the study: the paper's disc at R_f = R_g is measured to well under the
/// paper's 5.5e-3 px of mean error, a mismatched band is worse, and the
/// figures are real images.
#[test]
fn bench_paper_quick_writes_its_report() {
    let dir = tempfile::tempdir().unwrap();
    let out = dir.path().join("paper");
    let o = vicurve(&["bench", "paper", "--quick", "--out", out.to_str().unwrap()]);
    assert!(o.status.success(), "{}", text(&o.stderr));
    for f in [
        "paper.csv",
        "coverage.csv",
        "report.md",
        "fig7.svg",
        "fig7.png",
        "fig7-levelset.svg",
        "fig7-levelset.png",
        "fig8.svg",
        "fig8.png",
        "fig9.svg",
        "fig9.png",
        "fig10.svg",
        "fig10.png",
    ] {
        assert!(out.join(f).is_file(), "{f} missing");
    }
    let png = std::fs::read(out.join("fig7.png")).unwrap();
    assert_eq!(&png[1..4], b"PNG");
    let svg = std::fs::read_to_string(out.join("fig9.svg")).unwrap();
    assert!(svg.contains("<polyline") && svg.contains("R_f / R_g"));

    let csv = std::fs::read_to_string(out.join("paper.csv")).unwrap();
    let mut lines = csv.lines();
    let header: Vec<&str> = lines.next().unwrap().split(',').collect();
    let col = |name: &str| header.iter().position(|h| *h == name).unwrap();
    let (bias, study, r_g, outcome) = (col("bias"), col("study"), col("r_g"), col("outcome"));
    let coords = col("coords");
    let rows: Vec<Vec<String>> = lines
        .map(|l| l.split(',').map(str::to_string).collect())
        .collect();
    assert!(rows.len() >= 20, "{} rows", rows.len());
    let matched: Vec<f64> = rows
        .iter()
        .filter(|r| r[study] == "\"degree\"" && r[coords] == "\"exact\"")
        .map(|r| r[bias].parse::<f64>().unwrap().abs())
        .collect();
    assert!(matched.iter().all(|b| *b < 1e-3), "{matched:?}");
    // The paper's levelsets (10 px mesh) overestimate the convex distance.
    let level: Vec<f64> = rows
        .iter()
        .filter(|r| r[coords] == "\"levelset-10px\"")
        .map(|r| r[bias].parse::<f64>().unwrap())
        .collect();
    assert!(
        !level.is_empty() && level.iter().all(|b| *b > 1e-2 && *b < 0.1),
        "{level:?}"
    );
    let wide: Vec<f64> = rows
        .iter()
        .filter(|r| r[study] == "\"ratio\"" && r[r_g] == "20.0")
        .map(|r| r[bias].parse::<f64>().unwrap().abs())
        .collect();
    assert!(
        !wide.is_empty() && wide.iter().all(|b| *b > 2e-3),
        "{wide:?}"
    );
    assert!(rows.iter().all(|r| r[outcome] == "\"converged\""));

    let report = std::fs::read_to_string(out.join("report.md")).unwrap();
    for heading in [
        "## Figure 7",
        "## Figure 8",
        "## Figures 9 and 10",
        "## Harder",
    ] {
        assert!(report.contains(heading), "{heading}");
    }
}

/// Without `--init` a silhouette is found automatically; the start goes
/// into the JSON; `--pick`/`--roi` errors are one line.
#[test]
fn automatic_start() {
    let dir = tempfile::tempdir().unwrap();
    let d = dir.path();
    let (img, truth) = disc(d);
    let (json, csv) = (p(d, "auto.json"), p(d, "auto.csv"));
    let out = vicurve(&["measure", &img, "--out", &json, "--points", &csv]);
    assert!(out.status.success(), "{}", text(&out.stderr));
    assert!(text(&out.stderr).contains("automatic start"));
    let doc: serde_json::Value =
        serde_json::from_str(&std::fs::read_to_string(&json).unwrap()).unwrap();
    assert!(
        doc["initial_curve"].to_string().contains("polyline"),
        "{}",
        doc["initial_curve"]
    );
    let stats_path = p(d, "stats.json");
    let eval = vicurve(&["eval", &csv, &truth, "--json", &stats_path]);
    assert!(eval.status.success(), "{}", text(&eval.stderr));
    let stats: serde_json::Value =
        serde_json::from_str(&std::fs::read_to_string(&stats_path).unwrap()).unwrap();
    let max = stats["max_abs"].as_f64().unwrap();
    assert!(max < 0.02, "max {max}");

    let picked = vicurve(&["measure", &img, "--pick", "100,100", "--points", &csv]);
    assert!(picked.status.success(), "{}", text(&picked.stderr));
    assert_error(
        &vicurve(&["measure", &img, "--pick", "900,5"]),
        1,
        "outside",
    );
    assert_error(
        &vicurve(&[
            "measure",
            &img,
            "--init",
            "circle:100,100,60",
            "--pick",
            "100,100",
        ]),
        1,
        "--pick",
    );
    assert_error(&vicurve(&["measure", &img, "--roi", "1,2,3"]), 1, "--roi");
    assert_error(
        &vicurve(&["measure", &img, "--kind", "contour"]),
        1,
        "--init",
    );
}

/// `--model circle` and `--model bspline-curve`: the record gains `model`,
/// the points are the model's samples: the circle's within 0.01 px of the
/// disc, the free curve's within 0.03 px (2.0e-2 measured: 8-bit levels
/// seen by control points 4 px apart).
#[test]
fn measure_with_a_model() {
    let dir = tempfile::tempdir().unwrap();
    let d = dir.path();
    let (img, truth) = disc(d);
    for (model, bound) in [("circle", 0.01), ("bspline-curve", 0.03)] {
        let (json, csv, stats) = (p(d, "m.json"), p(d, "m.csv"), p(d, "s.json"));
        let out = vicurve(&[
            "measure",
            &img,
            "--init",
            "circle:100,100,58",
            "--model",
            model,
            "--out",
            &json,
            "--points",
            &csv,
        ]);
        assert!(out.status.success(), "{model}: {}", text(&out.stderr));
        let doc: serde_json::Value =
            serde_json::from_str(&std::fs::read_to_string(&json).unwrap()).unwrap();
        assert!(doc["model"].is_object(), "{model}: {doc}");
        assert!(text(&out.stdout).contains(&format!("model:       {model}")));
        let out = vicurve(&["eval", &csv, &truth, "--json", &stats]);
        assert!(out.status.success(), "{}", text(&out.stderr));
        let s: serde_json::Value =
            serde_json::from_str(&std::fs::read_to_string(&stats).unwrap()).unwrap();
        let max = s["max_abs"].as_f64().unwrap();
        assert!(max < bound, "{model}: max {max}");
    }
    // A circle's parameters, printed and recorded with their uncertainty.
    let doc: serde_json::Value = {
        let json = p(d, "c.json");
        let out = vicurve(&[
            "measure",
            &img,
            "--init",
            "circle:100,100,58",
            "--model",
            "circle",
            "--out",
            &json,
        ]);
        assert!(out.status.success());
        serde_json::from_str(&std::fs::read_to_string(&json).unwrap()).unwrap()
    };
    let r = doc["model"]["parameters"]
        .as_array()
        .unwrap()
        .iter()
        .find(|p| p["name"] == "r")
        .unwrap();
    assert!((r["value"].as_f64().unwrap() - 60.0).abs() < 0.01, "{r}");
    assert!(r["sigma"].as_f64().unwrap() > 0.0, "{r}");
}

/// Output piped into a reader that has stopped (`vicurve eval ... |
/// head`) ends the program quietly, with no panic on stderr.
#[test]
fn a_closed_output_pipe_is_not_a_panic() {
    use std::process::{Command, Stdio};
    let dir = tempfile::tempdir().unwrap();
    let (img, truth) = disc(dir.path());
    let points = p(dir.path(), "points.csv");
    let out = vicurve(&["measure", &img, "--points", &points]);
    assert!(out.status.success(), "{}", text(&out.stderr));
    let mut child = Command::new(env!("CARGO_BIN_EXE_vicurve"))
        .args(["eval", &points, &truth])
        .stdout(Stdio::piped())
        .stderr(Stdio::piped())
        .spawn()
        .unwrap();
    // The reader goes before the statistics are printed.
    drop(child.stdout.take());
    let out = child.wait_with_output().unwrap();
    let stderr = text(&out.stderr);
    assert!(!stderr.contains("panicked"), "{stderr}");
}

/// An sRGB-encoded disc: `measure` finds the encoding (the JSON's `tone`
/// and `tone_estimate`, a summary line), `--tone srgb` undoes it as told,
/// and a tone that is not one gets one line and exit 1.
#[test]
fn an_encoded_image_is_measured_in_linear_light() {
    let dir = tempfile::tempdir().unwrap();
    let d = dir.path();
    let img = p(d, "srgb.png");
    let out = vicurve(&[
        "synth", "disc", "--size", "200x200", "--radius", "60", "--blur", "1", "--noise", "0.01",
        "--tone", "srgb", "--out", &img,
    ]);
    assert!(out.status.success(), "{}", text(&out.stderr));
    let json = p(d, "r.json");
    let record = |args: &[&str]| -> serde_json::Value {
        let mut all = vec![
            "measure",
            &img,
            "--init",
            "circle:100,99,60",
            "--out",
            &json,
        ];
        all.extend_from_slice(args);
        let out = vicurve(&all);
        assert!(out.status.success(), "{}", text(&out.stderr));
        serde_json::from_str(&std::fs::read_to_string(&json).unwrap()).unwrap()
    };
    // The summary says what was read and how sure it is.
    let out = vicurve(&["measure", &img, "--init", "circle:100,99,60"]);
    assert!(
        text(&out.stdout).contains("tone:        read from the edge"),
        "{}",
        text(&out.stdout)
    );
    let auto = record(&[]);
    assert_ne!(auto["tone"], "linear", "{}", auto["tone"]);
    assert!(auto["tone_estimate"]["evidence"].as_f64().unwrap() > 25.0);
    assert_eq!(auto["config"]["tone"], "auto");
    let told = record(&["--tone", "srgb"]);
    assert_eq!(told["tone"], "srgb");
    assert!(told["tone_estimate"].is_null());
    assert_error(
        &vicurve(&["measure", &img, "--init", "circle:100,99,60", "--tone", "9"]),
        1,
        "--tone",
    );
}

/// An astigmatic disc (`synth --blur-y`): its truth file records both
/// blurs, `measure` fits the blur's anisotropy (the last stage's profile
/// in the JSON, a summary line with the blurs along and across its axis),
/// and `--blur-y` with the virtual profile's rendering is refused in one
/// line.
#[test]
fn an_astigmatic_blur_is_synthesised_and_measured() {
    let dir = tempfile::tempdir().unwrap();
    let d = dir.path();
    let (img, truth) = (p(d, "astig.png"), p(d, "astig.json"));
    let out = vicurve(&[
        "synth", "disc", "--size", "240x240", "--radius", "80", "--blur", "1", "--blur-y", "2.5",
        "--noise", "0.01", "--out", &img, "--truth", &truth,
    ]);
    assert!(out.status.success(), "{}", text(&out.stderr));
    let t: serde_json::Value =
        serde_json::from_str(&std::fs::read_to_string(&truth).unwrap()).unwrap();
    assert_eq!(t["image"]["blur_sigma_y"], 2.5, "{t}");
    let json = p(d, "r.json");
    let out = vicurve(&[
        "measure",
        &img,
        "--init",
        "circle:120,119,80",
        "--out",
        &json,
    ]);
    assert!(out.status.success(), "{}", text(&out.stderr));
    let out = vicurve(&["measure", &img, "--init", "circle:120,119,80"]);
    let summary = text(&out.stdout);
    assert!(summary.contains("px perpendicular to it"), "{summary}");
    let m: serde_json::Value =
        serde_json::from_str(&std::fs::read_to_string(&json).unwrap()).unwrap();
    let last = &m["stages"][m["stages"].as_array().unwrap().len() - 1]["profile"];
    let p_ = last["anisotropy"]["p"].as_f64().unwrap();
    // Variance 1 along x, 6.25 along y: p = (1 - 6.25) / 2.
    assert!((p_ + 2.625).abs() < 0.5, "{last}");
    assert_error(
        &vicurve(&[
            "synth",
            "disc",
            "--profile",
            "5",
            "--blur-y",
            "2",
            "--out",
            &p(d, "x.png"),
        ]),
        1,
        "blur_sigma_y",
    );
}
