//! Sequences end to end: the synthetic necking specimen measured by `vicurve
//! run` against its exact width, a run killed midway and resumed, a corrupt
//! frame in the middle, `vicurve track`, and job files that cannot run.

use std::io::{BufRead, BufReader};
use std::path::{Path, PathBuf};
use std::process::{Command, Stdio};

use crate::common::{assert_error_exact, split_cells, text, vicurve};

fn s(p: &Path) -> String {
    p.display().to_string()
}

/// `vicurve synth necking` into `dir` with extra arguments.
fn necking(dir: &Path, extra: &[&str]) {
    let d = s(dir);
    let mut args = vec!["synth", "necking", "--out", &d];
    args.extend_from_slice(extra);
    let out = vicurve(&args);
    assert!(out.status.success(), "{}", text(&out.stderr));
}

/// The summary's rows as maps from column to cell.
fn summary(dir: &Path) -> Vec<std::collections::HashMap<String, String>> {
    let t = std::fs::read_to_string(dir.join("summary.csv")).unwrap();
    let mut lines = t.lines();
    let head: Vec<String> = lines
        .next()
        .unwrap()
        .split(',')
        .map(str::to_string)
        .collect();
    lines
        .map(|l| {
            let cells = split_cells(l);
            assert_eq!(cells.len(), head.len(), "{l}");
            head.iter().cloned().zip(cells).collect()
        })
        .collect()
}

/// The exact bar of each frame from `truth.json`.
fn truth(dir: &Path) -> Vec<vicurve::truth::specimen::NeckedBar> {
    let v: serde_json::Value =
        serde_json::from_str(&std::fs::read_to_string(dir.join("truth.json")).unwrap()).unwrap();
    v["frames"]
        .as_array()
        .unwrap()
        .iter()
        .map(|f| serde_json::from_value(f["spec"]["bar"].clone()).unwrap())
        .collect()
}

#[test]
fn necking_widths_match_the_exact_specimen() {
    let tmp = tempfile::tempdir().unwrap();
    let dir = tmp.path().join("neck");
    necking(&dir, &[]); // 8 frames, 400x200, blur 1.5, noise 0.001, 16 bits
    let out = vicurve(&["run", &s(&dir.join("job.toml"))]);
    assert!(out.status.success(), "{}", text(&out.stderr));
    let results = dir.join("results");
    let bars = truth(&dir);
    assert_eq!(bars.len(), 8);
    let rows = summary(&results);
    assert_eq!(rows.len(), 8 * 3);
    for (k, bar) in bars.iter().enumerate() {
        let stem = format!("frame_{k:03}");
        // Every section where both edges are measured, against w(x).
        let profile = std::fs::read_to_string(results.join(format!("{stem}.width.csv"))).unwrap();
        let mut worst: f64 = 0.0;
        let mut count = 0;
        for l in profile.lines().skip(1) {
            let v: Vec<f64> = l.split(',').map(|c| c.parse().unwrap()).collect();
            worst = worst.max((v[1] - bar.width_at(v[0])).abs());
            assert!(v[2] > 0.0 && v[2] < 0.01, "sigma {l}");
            count += 1;
        }
        // The edges span the image but for the band's margin.
        assert!(count > 380, "{stem}: {count} sections");
        assert!(worst <= 0.01, "{stem}: width error up to {worst:.4} px");
        let w = rows
            .iter()
            .find(|r| r["frame"] == stem && r["curve"] == "width")
            .unwrap();
        assert_eq!(w["outcome"], "measured");
        let pos: f64 = w["min_width_position"].parse().unwrap();
        let min: f64 = w["min_width"].parse().unwrap();
        // The figures of docs/benchmarks.md (`-- --nocapture`).
        println!(
            "{stem}: {count} sections, width error up to {worst:.4} px; minimum {:+.4} px from the truth, at {:+.3} px from the narrowest section",
            min - bar.min_width(),
            pos - bar.x_neck
        );
        assert!((pos - bar.x_neck).abs() <= 1.0, "{stem}: minimum at {pos}");
        assert!((min - bar.min_width()).abs() <= 0.01, "{stem}: {min}");
        for edge in ["top", "bottom"] {
            let r = rows
                .iter()
                .find(|r| r["frame"] == stem && r["curve"] == edge)
                .unwrap();
            assert_eq!(r["outcome"], "converged", "{stem} {edge}");
            let from = if k == 0 {
                "init".to_string()
            } else {
                format!("frame_{:03}", k - 1)
            };
            assert_eq!(r["started_from"], from);
        }
    }
    // The per-frame result is `measure --out`'s with the sequence record.
    let j: serde_json::Value =
        serde_json::from_str(&std::fs::read_to_string(results.join("frame_003.top.json")).unwrap())
            .unwrap();
    assert_eq!(j["sequence"]["started_from"], "frame_002");
    assert_eq!(j["outcome"]["status"], "converged");
    assert!(j["derived"].is_object());
    let pts = std::fs::read_to_string(results.join("frame_003.top.csv")).unwrap();
    assert_eq!(
        pts.lines().next(),
        Some("s,x,y,nx,ny,sigma,weight,sigma_noise,misfit")
    );
    for plot in ["width.png", "width.svg"] {
        assert!(std::fs::metadata(results.join(plot)).unwrap().len() > 1000);
    }
}

/// The job of `dir` with another output folder.
fn job_into(dir: &Path, name: &str, out_dir: &str) -> PathBuf {
    let job = std::fs::read_to_string(dir.join("job.toml"))
        .unwrap()
        .replace("out_dir = \"results\"", &format!("out_dir = \"{out_dir}\""));
    let p = dir.join(name);
    std::fs::write(&p, job).unwrap();
    p
}

#[test]
fn a_killed_run_resumes_with_identical_results() {
    let tmp = tempfile::tempdir().unwrap();
    let dir = tmp.path();
    necking(dir, &["--frames", "6", "--size", "300x120"]);
    // Uninterrupted.
    let whole = job_into(dir, "whole.toml", "whole");
    let out = vicurve(&["run", &s(&whole)]);
    assert!(out.status.success(), "{}", text(&out.stderr));

    // Killed (SIGKILL) while measuring the third frame: the log line of
    // frame 2 comes after frame 1's rows reached the summary.
    let killed = job_into(dir, "killed.toml", "killed");
    let mut child = Command::new(env!("CARGO_BIN_EXE_vicurve"))
        .args(["run", &s(&killed)])
        .stderr(Stdio::piped())
        .spawn()
        .unwrap();
    let mut log = BufReader::new(child.stderr.take().unwrap());
    let mut line = String::new();
    loop {
        line.clear();
        assert!(log.read_line(&mut line).unwrap() > 0, "the run ended early");
        if line.contains("frame 2/6") {
            break;
        }
    }
    child.kill().unwrap();
    child.wait().unwrap();
    let results = dir.join("killed");
    let done: Vec<String> = summary(&results)
        .iter()
        .map(|r| r["frame"].clone())
        .collect::<std::collections::BTreeSet<_>>()
        .into_iter()
        .collect();
    assert!(
        !done.is_empty() && done.len() < 6,
        "frames done when killed: {done:?}"
    );
    let mtime = |stem: &str| {
        std::fs::metadata(results.join(format!("{stem}.top.json")))
            .unwrap()
            .modified()
            .unwrap()
    };
    let before: Vec<_> = done.iter().map(|f| mtime(f)).collect();
    std::thread::sleep(std::time::Duration::from_millis(20));

    // Resumed: the frames done are skipped, the rest measured.
    let out = vicurve(&["run", &s(&killed)]);
    let err = text(&out.stderr);
    assert!(out.status.success(), "{err}");
    assert!(
        err.contains(&format!("{} frame(s) already done, skipped", done.len())),
        "{err}"
    );
    let after: Vec<_> = done.iter().map(|f| mtime(f)).collect();
    assert_eq!(before, after, "finished frames were written again");
    // Same results as the uninterrupted run, to the last digit.
    let read = |d: &str, f: &str| std::fs::read_to_string(dir.join(d).join(f)).unwrap();
    assert_eq!(read("whole", "summary.csv"), read("killed", "summary.csv"));
    for k in 0..6 {
        let stem = format!("frame_{k:03}");
        assert_eq!(
            read("whole", &format!("{stem}.width.csv")),
            read("killed", &format!("{stem}.width.csv"))
        );
        for edge in ["top", "bottom"] {
            let f = format!("{stem}.{edge}.json");
            let a: serde_json::Value = serde_json::from_str(&read("whole", &f)).unwrap();
            let b: serde_json::Value = serde_json::from_str(&read("killed", &f)).unwrap();
            assert_eq!(a["curve"], b["curve"], "{f}");
            assert_eq!(a["sequence"], b["sequence"], "{f}");
            let p = format!("{stem}.{edge}.csv");
            assert_eq!(read("whole", &p), read("killed", &p));
        }
    }
    // No temporary file is left.
    for e in std::fs::read_dir(&results).unwrap() {
        let n = e.unwrap().file_name().to_string_lossy().into_owned();
        assert!(!n.contains(".tmp-"), "{n}");
    }
}

#[test]
fn a_corrupt_frame_is_reported_and_skipped() {
    let tmp = tempfile::tempdir().unwrap();
    let dir = tmp.path();
    necking(dir, &["--frames", "4", "--size", "300x120"]);
    // Truncate the second frame.
    let f = dir.join("frame_001.png");
    let bytes = std::fs::read(&f).unwrap();
    std::fs::write(&f, &bytes[..bytes.len() / 2]).unwrap();
    let out = vicurve(&["run", &s(&dir.join("job.toml"))]);
    let err = text(&out.stderr);
    assert_eq!(out.status.code(), Some(3), "{err}");
    let last = err.lines().last().unwrap();
    assert!(
        last.starts_with("vicurve: error: 1 of 4 frames failed (first: frame_001"),
        "{err}"
    );
    assert!(err.contains("vicurve: warning: frame_001:"), "{err}");
    let rows = summary(&dir.join("results"));
    assert_eq!(rows.len(), 12);
    for r in &rows {
        let frame = r["frame"].as_str();
        if frame == "frame_001" {
            assert_eq!(r["outcome"], "failed");
            assert!(r["reason"].contains("frame_001.png"), "{r:?}");
        } else if r["curve"] == "width" {
            assert_eq!(r["outcome"], "measured", "{r:?}");
        } else {
            assert_eq!(r["outcome"], "converged", "{r:?}");
        }
    }
    // The frame after the corrupt one starts from the last good curve.
    let r = rows
        .iter()
        .find(|r| r["frame"] == "frame_002" && r["curve"] == "top")
        .unwrap();
    assert_eq!(r["started_from"], "frame_000");
    // Re-running tries the failed frame again (and only it).
    let out = vicurve(&["run", &s(&dir.join("job.toml"))]);
    assert_eq!(out.status.code(), Some(3));
    let err = text(&out.stderr);
    assert!(err.contains("3 frame(s) already done, skipped"), "{err}");
    assert!(err.contains("; 1 measured"), "{err}");
}

#[test]
fn track_one_edge_and_rerun() {
    let tmp = tempfile::tempdir().unwrap();
    let dir = tmp.path();
    necking(dir, &["--frames", "3", "--size", "300x120"]);
    let pattern = s(&dir.join("frame_*.png"));
    let out_dir = s(&dir.join("t"));
    let args = [
        "track",
        &pattern,
        "--init",
        "segment:0,26,299,26",
        "--kind",
        "silhouette",
        "--out-dir",
        &out_dir,
        "--overlay",
        "svg",
    ];
    let out = vicurve(&args);
    assert!(out.status.success(), "{}", text(&out.stderr));
    let t = dir.join("t");
    for k in 0..3 {
        for ext in ["json", "csv", "overlay.svg"] {
            assert!(t.join(format!("frame_{k:03}.{ext}")).is_file(), "{k} {ext}");
        }
    }
    let rows = summary(&t);
    assert_eq!(rows.len(), 3);
    assert!(rows.iter().all(|r| r["outcome"] == "converged"));
    // Against the exact top edge: every sample within 0.02 px but for the
    // last 3 px at each end of the open curve, where the fit's band stops
    // (measured: 0.009 px at most; a single edge carries an offset common
    // to both edges of the bar that the width cancels, hence the width
    // test's 0.01 px).
    let bars = truth(dir);
    for (k, bar) in bars.iter().enumerate() {
        let pts = std::fs::read_to_string(t.join(format!("frame_{k:03}.csv"))).unwrap();
        let rows: Vec<Vec<f64>> = pts
            .lines()
            .skip(1)
            .map(|l| l.split(',').map(|c| c.parse().unwrap()).collect())
            .collect();
        let length = rows.last().unwrap()[0];
        assert!(length > 290.0, "frame {k}: {length} px long");
        for v in rows.iter().filter(|v| v[0] >= 3.0 && v[0] <= length - 3.0) {
            let d = bar.signed_distance(vicurve::truth::specimen::Edge::Top, v[1], v[2]);
            assert!(d.abs() < 0.02, "frame {k}: {v:?}: {d}");
        }
    }
    // Again: nothing to do. With --force: everything again.
    let out = vicurve(&args);
    assert!(text(&out.stderr).contains("3 frame(s) already done"));
    let mut forced = args.to_vec();
    forced.push("--force");
    let out = vicurve(&forced);
    assert!(out.status.success());
    assert!(!text(&out.stderr).contains("already done"));
}

#[test]
fn job_files_that_cannot_run() {
    let tmp = tempfile::tempdir().unwrap();
    let dir = tmp.path();
    necking(dir, &["--frames", "2", "--size", "200x80"]);
    let job = std::fs::read_to_string(dir.join("job.toml")).unwrap();
    let write = |name: &str, text: &str| {
        let p = dir.join(name);
        std::fs::write(&p, text).unwrap();
        s(&p)
    };
    let p = write("typo.toml", &job.replace("axis = ", "axes = "));
    assert_error_exact(&vicurve(&["run", &p]), 1, "unknown field `axes`");
    let p = write("curve.toml", &job.replace("\"bottom\"]", "\"side\"]"));
    assert_error_exact(&vicurve(&["run", &p]), 1, "no curve named 'side'");
    let p = write("glob.toml", &job.replace("frame_*.png", "shot_*.png"));
    assert_error_exact(&vicurve(&["run", &p]), 1, "no image matches");
    assert_error_exact(
        &vicurve(&["run", &s(&dir.join("none.toml"))]),
        1,
        "job file not found",
    );
    // Results of another job in the same folder are not mixed up.
    let p = write("a.toml", &job);
    assert!(vicurve(&["run", &p]).status.success());
    let p = write(
        "b.toml",
        &job.replace("axis = \"x\"", "axis = \"estimate\""),
    );
    assert_error_exact(&vicurve(&["run", &p]), 1, "another job");
    assert!(vicurve(&["run", &p, "--force"]).status.success());
}
