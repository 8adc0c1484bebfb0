//! `vicurve bench speed`: on its small images (`--quick`), one repeat, the
//! peers asked for with a Python that does not exist. Its outputs exist
//! and parse; no timing is checked.

use crate::common::{ok, text, vicurve};

#[test]
fn speed_bench_writes_its_report() {
    let dir = tempfile::tempdir().expect("temp dir");
    let out = dir.path().join("speed");
    let out_text = out.display().to_string();
    let work = dir.path().join("work");
    let work_text = work.display().to_string();
    let run = vicurve(&[
        "bench",
        "speed",
        "--quick",
        "--repeats",
        "1",
        "--peers",
        "--python",
        "/nonexistent/python3",
        "--out",
        &out_text,
        "--work",
        &work_text,
    ]);
    ok(&run);
    let printed = text(&run.stdout);
    let cases = ["disc-512", "star-1024", "far-star-1704x2272"];
    for case in cases {
        assert!(printed.contains(case), "{case} not in: {printed}");
        assert!(work.join("images").join(format!("{case}.png")).is_file());
        assert!(work.join("runs").join(format!("{case}.json")).is_file());
        assert!(work.join("runs").join(format!("{case}.csv")).is_file());
    }
    // The peers could not run: said in one line, vicurve's table printed.
    let not_run: Vec<&str> = printed
        .lines()
        .filter(|l| l.starts_with("peers: not run"))
        .collect();
    assert_eq!(not_run.len(), 1, "{printed}");

    let md = std::fs::read_to_string(out.join("speed.md")).expect("speed.md");
    for section in [
        "## Whole process",
        "## Parts, in-process",
        "## Stages",
        "## Peers",
    ] {
        assert!(md.contains(section), "{section} not in speed.md");
    }
    assert!(md.contains("logical CPUs"));

    let csv = std::fs::read_to_string(out.join("speed.csv")).expect("speed.csv");
    let mut lines = csv.lines();
    assert_eq!(lines.next(), Some("case,quantity,median,min,max"));
    let mut process = Vec::new();
    for line in lines {
        let cells: Vec<&str> = line.split(',').collect();
        assert_eq!(cells.len(), 5, "{line}");
        let v: Vec<f64> = cells[2..]
            .iter()
            .map(|c| c.parse::<f64>().expect("a number"))
            .collect();
        if !v[0].is_nan() {
            assert!(v[1] <= v[0] && v[0] <= v[2], "{line}");
        }
        if cells[1] == "process_s" {
            assert!(v[0] > 0.0 && v[0].is_finite(), "{line}");
            process.push(cells[0].to_string());
        }
    }
    assert_eq!(process, cases);
}

/// `vicurve bench objects` on its small image (`--quick`), one repeat: the
/// report and the CSV exist and say what they measured; every circle was
/// found and measured. No timing is checked.
#[test]
fn objects_bench_writes_its_report() {
    let dir = tempfile::tempdir().expect("temp dir");
    let out = dir.path().join("objects");
    let work = dir.path().join("work");
    let (out_text, work_text) = (out.display().to_string(), work.display().to_string());
    let run = vicurve(&[
        "bench",
        "objects",
        "--quick",
        "--repeats",
        "1",
        "--out",
        &out_text,
        "--work",
        &work_text,
    ]);
    ok(&run);
    assert!(text(&run.stdout).contains("16 of 16 circles found and measured"));
    assert!(work.join("circles.png").is_file());
    let md = std::fs::read_to_string(out.join("objects-speed.md")).expect("objects-speed.md");
    for part in [
        "## Times",
        "## Where the time goes",
        "pixel edge",
        "16 of 16 circles",
    ] {
        assert!(md.contains(part), "{part} not in objects-speed.md");
    }
    let csv = std::fs::read_to_string(out.join("objects-speed.csv")).expect("csv");
    assert!(csv.starts_with("quantity,median_s,min_s,max_s\n\"whole process\","));
    assert!(csv.contains("stage,objects,iterations,rereferences,seconds"));
}
