//! The conformance sweep's CI set (`vicurve bench conformance --set ci`),
//! run through the binary: every case must meet the acceptance criteria of
//! issue 18, except the cases of [`KNOWN_FAILURES`], which must still fail
//! (when one passes, remove it from the list). The criteria are recomputed
//! here from the CSV's numbers, independently of the runner's own columns
//! (which must agree).

use crate::common::{ok, text, vicurve};
use std::collections::HashMap;

/// Cases of the CI set that fail today, with the failed criteria as the
/// runner reports them (docs/conformance.md groups them by cause). Entries
/// go as the fixes of issue 18 land; a new failure is a regression, not an
/// entry, unless the change that causes it is measured to improve the
/// sweep and the entry says, with figures, why this case moved the other
/// way.
const KNOWN_FAILURES: &[(&str, &str)] = &[
    // Since the pixel-edge profile models a corner's blurred wedge
    // (`virtual_image::corner`) this noiseless pentagon fails by little:
    // its largest error (1.5e-3 px, at a corner) is measured against a
    // scatter of 1.5e-4 px.
    (
        "polygon/blur2/noise0/16bit/dark/polyline-1.5px",
        "max 1.47e-3 > 8 x scatter 1.53e-4",
    ),
    // Not a worse result: since the refinement may take a last step onto
    // its shortest elements (`fit/refine.rs`) this noiseless sine edge's
    // scatter fell from 1.7e-5 to about 9e-6 px, and its largest error, at
    // an end (1.1e-4 px), did not move; its sigma (1.4e-5 px, the rounding
    // of 16-bit levels) is over 1 / 0.7 of that scatter.
    (
        "sine-edge/blur0/noise0/16bit/dark/auto",
        "max 1.12e-4 > 8 x scatter 9.16e-6; scatter/sigma 0.65",
    ),
    // The one entry added after a change: since the coarse stages run on
    // 8 x 8 and 4 x 4 blocks (`fit/pyramid.rs`) the paper's last stage
    // (R = 5 px, 100 elements of 47 px, too long for the bays' 43 px radius
    // of curvature) lands 0.31 to 0.33 px off from the R = 10 stage's
    // result instead of 0.18 to 0.29 px (eight starts, their centres up
    // to a pixel or their radii 5 px apart, measured), its largest error
    // in the bays 1.2 -> 1.35 px, its sigma following it (scatter/sigma
    // 1.02). The other eight far stars of the paper's schedule moved the
    // other way (scatter 0.052 -> 0.033, 0.154 -> 0.108, 0.128 -> 0.097
    // px, ...; docs/benchmarks.md, "Coarse stages on 8 x 8 blocks").
    // Since a curve more than a pixel off the edge along an element or
    // more in all is diverged (`fit/output.rs`, `off_edge`), it fails as
    // diverged too: its bays lie up to 1.4 px off.
    (
        "far-star-l5-a0.30/blur1.5/noise1/8bit/bright/circle-0.85r/paper-stages",
        "diverged: the curve does not follow the edge: it lies 1.4 px off it near (668.9, 1515.2), and over a pixel off along an element or more of its length (elements too long for the shape: give more, or let the default schedule choose them); covers 96.9 %",
    ),
    // Encoded images (`tone.rs`): measured as linear, these edges were
    // 0.25 and 0.5 px off with a sigma of 3e-3 (a silent failure). The tone
    // curve read from the edge brings them within 0.02 px, but the edge
    // cannot tell sRGB from the 2.2 and 2.4 power laws over these levels
    // (they would put it up to 0.04 px apart): this one took 2.4 for its
    // sRGB. The result's `sigma_shift` (2.1e-2 px, common to the whole
    // curve) says so; the samples' sigma matches their scatter
    // (docs/benchmarks.md, "Gamma-encoded images").
    (
        "disc/blur1/noise1/8bit/bright/srgb/circle-1.5px",
        "|bias| 1.92e-2 > 2e-3 + 3 x 6.4e-4 (reported shift sigma 2.1e-2)",
    ),
];

/// `|bias|` bound: 2e-3 px for blur <= 2 px and noise <= 2 %, 5e-3 px
/// elsewhere (plus three times the noise's share, `bias_noise`).
fn bias_limit(blur: f64, noise_pct: f64) -> f64 {
    if blur <= 2.0 && noise_pct <= 2.0 {
        2e-3
    } else {
        5e-3
    }
}

/// Split one CSV line (fields quoted with `"`, `""` inside).
fn split_csv(line: &str) -> Vec<String> {
    let (mut out, mut cell, mut quoted) = (Vec::new(), String::new(), false);
    let mut chars = line.chars().peekable();
    while let Some(c) = chars.next() {
        match c {
            '"' if quoted && chars.peek() == Some(&'"') => {
                cell.push('"');
                chars.next();
            }
            '"' => quoted = !quoted,
            ',' if !quoted => out.push(std::mem::take(&mut cell)),
            c => cell.push(c),
        }
    }
    out.push(cell);
    out
}

/// The rows of `conformance.csv` as column -> cell maps.
fn read_rows(csv: &str) -> Vec<HashMap<String, String>> {
    let mut lines = csv.lines();
    let header = split_csv(lines.next().expect("a header line"));
    lines
        .map(|l| header.iter().cloned().zip(split_csv(l)).collect())
        .collect()
}

/// The criteria a row fails, recomputed from its numbers.
fn failed_criteria(r: &HashMap<String, String>) -> Vec<String> {
    let num = |k: &str| r[k].parse::<f64>().unwrap_or(f64::NAN);
    let mut failed = Vec::new();
    if r["outcome"] != "converged" {
        failed.push(format!("{} {}", r["outcome"], r["message"]));
    }
    // An astigmatic image is as blurred as its larger blur.
    let blur = match r["blur_y"].as_str() {
        "" => num("blur"),
        _ => num("blur").max(num("blur_y")),
    };
    let limit = bias_limit(blur, num("noise_pct"));
    // The noise's share: on a noiseless image only the rounding of the
    // levels, a small part of the bound; the runner's figure otherwise.
    let noise = num("bias_noise");
    assert!(
        noise > 0.0 && (num("noise_pct") > 0.0 || noise < limit / 4.0),
        "{}: bias_noise {noise}",
        r["id"]
    );
    // Written so that NaN (no curve) fails.
    let bias_ok = num("bias").abs() <= limit + 3.0 * noise;
    if !bias_ok {
        failed.push(format!(
            "|bias| {:.2e} > {limit:.0e} + 3 x {noise:.1e}",
            num("bias").abs()
        ));
    }
    let max_ok = num("max_abs") <= 8.0 * num("scatter");
    if !max_ok {
        failed.push(format!("max {:.2e} > 8 x scatter", num("max_abs")));
    }
    let ratio = num("scatter") / num("sigma_rms");
    if !((0.7..=1.4).contains(&ratio)) {
        failed.push(format!("scatter/sigma {ratio:.2}"));
    }
    let gap = num("border_gap");
    let covered = if gap.is_nan() {
        num("coverage") >= 0.99
    } else {
        gap <= 10.0
    };
    if !covered {
        failed.push(format!("coverage {} gap {gap}", r["coverage"]));
    }
    failed
}

/// What is wrong with one row against the list of known failures.
fn check_row(r: &HashMap<String, String>, known: &HashMap<&str, &str>) -> Option<String> {
    let id = r["id"].as_str();
    let failed = failed_criteria(r);
    let pass = failed.is_empty();
    if (r["pass"] == "true") != pass {
        return Some(format!(
            "{id}: the runner's pass column disagrees ({failed:?})"
        ));
    }
    match (pass, known.get(id)) {
        (true, Some(_)) => Some(format!("{id}: now passes - remove it from KNOWN_FAILURES")),
        (false, None) => Some(format!("{id}: fails: {}", failed.join("; "))),
        _ => None,
    }
}

#[test]
fn conformance_ci_set_meets_the_criteria() {
    let dir = tempfile::tempdir().unwrap();
    let out_dir = dir.path().display().to_string();
    let out = vicurve(&["bench", "conformance", "--out", &out_dir, "--set", "ci"]);
    ok(&out);
    let csv = std::fs::read_to_string(dir.path().join("conformance.csv")).unwrap();
    let md = std::fs::read_to_string(dir.path().join("conformance.md")).unwrap();
    assert!(md.contains("bench conformance --out"), "{md}");
    let rows = read_rows(&csv);
    assert!(
        rows.len() >= 40,
        "{} rows; stdout {}",
        rows.len(),
        text(&out.stdout)
    );
    let known: HashMap<&str, &str> = KNOWN_FAILURES.iter().copied().collect();
    let mut problems: Vec<String> = rows.iter().filter_map(|r| check_row(r, &known)).collect();
    for id in known.keys() {
        if !rows.iter().any(|r| r["id"] == *id) {
            problems.push(format!(
                "{id}: listed in KNOWN_FAILURES but not in the CI set"
            ));
        }
    }
    assert!(
        problems.is_empty(),
        "{} problem(s):\n{}",
        problems.len(),
        problems.join("\n")
    );
}

/// Mean of the columns `x` and `y` of a points CSV.
fn centroid(csv: &str) -> [f64; 2] {
    let rows = read_rows(csv);
    let mean = |k: &str| {
        rows.iter()
            .map(|r| r[k].parse::<f64>().unwrap())
            .sum::<f64>()
            / rows.len() as f64
    };
    [mean("x"), mean("y")]
}

/// Run the sweep's case `id` of `set` into `dir` (with `--samples` when
/// `samples`), and return its row of the CSV.
fn run_case(dir: &std::path::Path, set: &str, id: &str, samples: bool) -> HashMap<String, String> {
    let out_dir = dir.display().to_string();
    let mut args = vec![
        "bench",
        "conformance",
        "--out",
        &out_dir,
        "--set",
        set,
        "--filter",
        id,
    ];
    if samples {
        args.push("--samples");
    }
    ok(&vicurve(&args));
    read_rows(&std::fs::read_to_string(dir.join("conformance.csv")).unwrap())
        .into_iter()
        .find(|r| r["id"] == id)
        .unwrap()
}

/// The file of case `id` that `--samples` wrote into `dir` with extension
/// `ext` (`csv`, `png`, `start.csv`, `truth.json`), as an argument.
fn sample_file(dir: &std::path::Path, id: &str, ext: &str) -> String {
    let stem = dir.join("samples").join(id.replace('/', "_"));
    format!("{}.{ext}", stem.display())
}

/// The JSON file at `path`.
fn read_json(path: &str) -> serde_json::Value {
    serde_json::from_str(&std::fs::read_to_string(path).unwrap()).unwrap()
}

/// `--samples` writes, for each case, its samples, its image, its
/// start's points and its truth: `vicurve measure` on those measures the
/// same curve again (the start is the circle's points 1 px apart, not the
/// circle, so the two agree to a fraction of the scatter, not exactly),
/// and `vicurve eval` of the samples against the truth gives the bias and
/// scatter of the case's row.
#[test]
fn conformance_samples_measure_again_from_the_command_line() {
    let dir = tempfile::tempdir().unwrap();
    let id = "disc/blur1/noise1/8bit/dark/circle-10pct";
    let row = run_case(dir.path(), "ci", id, true);
    let file = |ext: &str| sample_file(dir.path(), id, ext);
    let samples = std::fs::read_to_string(file("csv")).unwrap();
    let points = file("points.csv");
    ok(&vicurve(&[
        "measure",
        &file("png"),
        "--init",
        &format!("polyline:{}", file("start.csv")),
        "--closed",
        "--points",
        &points,
    ]));
    let again = std::fs::read_to_string(&points).unwrap();
    let (a, b) = (centroid(&samples), centroid(&again));
    assert!(
        (a[0] - b[0]).abs() < 1e-3 && (a[1] - b[1]).abs() < 1e-3,
        "{a:?} vs {b:?}"
    );
    let stats = file("eval.json");
    ok(&vicurve(&[
        "eval",
        &file("csv"),
        &file("truth.json"),
        "--json",
        &stats,
    ]));
    let stats = read_json(&stats);
    for key in ["bias", "scatter"] {
        let (got, want) = (
            stats[key].as_f64().unwrap(),
            row[key].parse::<f64>().unwrap(),
        );
        assert!((got - want).abs() <= 1e-12, "{key}: {got} vs {want}");
    }
}

/// The paper's showcase as the sweep renders it (the 6-lobed star of
/// amplitude 0.2, 1704x2272, `--samples` of its case) and as `vicurve
/// bench speed` measures it: from the circle of radius 500 px at its
/// centre with the paper's stages. Where the coarse curve has not reached
/// the lobes yet its residuals are far beyond the others; taken for
/// clutter, they had the binned R = 20 px stage reweight its band and
/// walk the curve by steps of up to 47 px for 73 more iterations
/// (measured before). A coarse stage on a binned image (`fit/pyramid.rs`)
/// runs no robust reweighting.
#[test]
fn a_binned_stage_takes_no_lobe_for_clutter() {
    let dir = tempfile::tempdir().unwrap();
    let id = "far-star-l6-a0.20/blur1.5/noise1/8bit/bright/circle-0.85r/paper-stages";
    run_case(dir.path(), "full", id, true);
    let file = |ext: &str| sample_file(dir.path(), id, ext);
    let truth = read_json(&file("truth.json"));
    let (cx, cy) = (
        truth["shape"]["cx"].as_f64().unwrap(),
        truth["shape"]["cy"].as_f64().unwrap(),
    );
    let result = file("r.json");
    ok(&vicurve(&[
        "measure",
        &file("png"),
        "--init",
        &format!("circle:{cx},{cy},500"),
        "--stages",
        "20:25,10:50,5:100",
        "--out",
        &result,
    ]));
    let r = read_json(&result);
    assert_eq!(r["outcome"]["status"], "converged");
    let stages = r["stages"].as_array().unwrap();
    let binnings: Vec<u64> = stages
        .iter()
        .map(|s| s["binning"].as_u64().unwrap_or(1))
        .collect();
    assert_eq!(binnings, [8, 4, 1]);
    for s in &stages[..2] {
        let runs = s["history"].as_array().unwrap();
        assert!(
            runs.iter().all(|h| h["run"] != "robust"),
            "R = {}: a robust run in a binned stage",
            s["half_width"]
        );
    }
}

/// Elements that a refinement kept because shorter ones would cost more
/// noise than the shape error they remove leave that error in the
/// result: `sigma` counts it (`fit/refine.rs`, `kept_shape_error`). Two
/// cases of the full sweep whose noise-only `sigma` fell short by about
/// 1.5 (measured before): a blurred sine edge on elements of 40 px, and a
/// blurred star whose bays its 9 px elements cannot follow.
#[test]
fn sigma_counts_the_shape_error_of_kept_elements() {
    assert_sigma_fits_the_scatter(&[
        "sine-edge/blur4/noise1/16bit/dark/segment",
        "star-a0.2/blur4/noise1/8bit/dark/circle-10pct",
    ]);
}

/// Each full-sweep case of `ids` scatters within [0.7, 1.4] of its
/// `sigma`.
fn assert_sigma_fits_the_scatter(ids: &[&str]) {
    for &id in ids {
        let dir = tempfile::tempdir().unwrap();
        let row = run_case(dir.path(), "full", id, false);
        let ratio: f64 = row["scatter_over_sigma"].parse().unwrap();
        println!("{id}: scatter / sigma {ratio:.2}");
        assert!(
            (0.7..=1.4).contains(&ratio),
            "{id}: scatter / sigma {ratio}"
        );
    }
}

/// Detail about as fine as the elements is charged what least squares
/// leaves on it (`fit/representation.rs`, `NARROW`): stars whose bays
/// the smooth asymptote undercharged, noiseless and at blur 4 and 1 %
/// noise (scatter / sigma 1.56 and 1.46, measured before; now 1.36 and
/// 1.36).
#[test]
fn sigma_counts_detail_about_as_fine_as_the_elements() {
    assert_sigma_fits_the_scatter(&[
        "star-a0.2/blur1/noise0/16bit/dark/circle-10pct",
        "star-a0.2/blur4/noise1/16bit/bright/polyline-1.5px",
    ]);
}

/// Smooth open edges are not charged as fine detail at their ends, where
/// the stencils are moved inward and the reads at two steps are about
/// different places: a blurred sine edge at 2 % noise and one under
/// uneven light reported `sigma` 1.7 times their scatter (0.60 and 0.57,
/// measured before; now 0.95 and 1.08).
#[test]
fn sigma_at_an_open_edges_ends_is_not_charged_as_fine_detail() {
    assert_sigma_fits_the_scatter(&[
        "sine-edge/blur1/noise2/16bit/dark/auto",
        "sine-edge/blur2/noise1/8bit/bright/shaded0.12,-0.06/auto",
    ]);
}

/// A corner that the turning found but the image near it could hardly
/// tell from the smooth curve (`fit/corner_check.rs`) is judged with the
/// curve's other corners, and `sigma` near it covers the curve not
/// chosen. A pentagon under a 2 px blur and 5 % noise: that corner was
/// dropped, and without the cover its vertex was 0.81 px off at 14 of its
/// `sigma` (measured); with the cover, 0.81 px at 1.4. Its other corners
/// being clearly sharp, it is now kept: the largest error 0.21 px, no
/// sample beyond 4 of its `sigma` (measured: 2.3).
#[test]
fn a_corner_judged_on_ambiguous_evidence_is_covered_by_sigma() {
    let id = "polygon/blur2/noise5/16bit/bright/circle-10pct";
    let dir = tempfile::tempdir().unwrap();
    let row = run_case(dir.path(), "full", id, true);
    let bias: f64 = row["bias"].parse().unwrap();
    let samples = read_rows(&std::fs::read_to_string(sample_file(dir.path(), id, "csv")).unwrap());
    let worst = samples
        .iter()
        .map(|s| {
            let e: f64 = s["error"].parse().unwrap();
            let sigma: f64 = s["sigma"].parse().unwrap();
            (e - bias).abs() / sigma
        })
        .fold(0.0f64, f64::max);
    println!("{id}: worst sample {worst:.1} of its sigma");
    assert!(worst <= 4.0, "{id}: a sample {worst} of its sigma off");
}

/// A blur refit that would move the curve's most curved stretch by more
/// than the fit's tolerance is taken, however small (`fit/blur.rs`,
/// `blur_change_matters`): on the noiseless 16-bit star under a 4 px blur
/// the pixel-edge stage ended under a blur of 4.0092 px (the refit's
/// 4.0004 within the fixed 0.01 px), and the curvature shift it left put
/// the curve 5.2e-4 px off (scatter, measured before); now 6.4e-5 px,
/// the blur 4.0004 px.
#[test]
fn a_small_blur_change_that_moves_a_curved_edge_is_taken() {
    let id = "star-a0.1/blur4/noise0/16bit/dark/auto";
    let dir = tempfile::tempdir().unwrap();
    let row = run_case(dir.path(), "full", id, false);
    let scatter: f64 = row["scatter"].parse().unwrap();
    println!("{id}: scatter {scatter:.2e} px");
    assert!(scatter <= 1.5e-4, "{id}: scatter {scatter:e} px");
}
