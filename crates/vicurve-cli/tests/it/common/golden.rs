//! Golden outputs: whole runs whose files are compared with copies kept in
//! `tests/golden/CASE/`, numbers within [`TOLERANCE`], so that a change
//! which should move no result is shown to move none.
//!
//! `REGENERATE=1 cargo test -p vicurve-cli --test it golden` rewrites the
//! copies on purpose (review the diff before committing it).

use super::split_cells;
use std::path::{Path, PathBuf};

/// Largest difference accepted between a number and its golden copy,
/// relative to the larger of 1 and its magnitude (so pixels to 1e-12 px).
pub const TOLERANCE: f64 = 1e-12;

/// Fields and CSV columns that legitimately differ from run to run
/// (wall-clock times).
const VOLATILE: &[&str] = &["seconds"];

/// Where the golden copies of `case` are kept.
fn golden_dir(case: &str) -> PathBuf {
    Path::new(env!("CARGO_MANIFEST_DIR"))
        .join("tests/golden")
        .join(case)
}

/// Whether this run rewrites the golden copies.
fn regenerate() -> bool {
    std::env::var_os("REGENERATE").is_some_and(|v| v == "1")
}

/// Compare `files` (paths relative to `dir`) with the golden copies of
/// `case`, or rewrite those with `REGENERATE=1`. Panics with every
/// difference found (the first few of each file).
pub fn check(case: &str, dir: &Path, files: &[&str]) {
    let golden = golden_dir(case);
    let mut problems = Vec::new();
    for file in files {
        let actual_path = dir.join(file);
        let actual = std::fs::read_to_string(&actual_path)
            .unwrap_or_else(|e| panic!("{case}: {} not written: {e}", actual_path.display()));
        let kept = golden.join(file.replace('/', "__"));
        if regenerate() {
            std::fs::create_dir_all(&golden).unwrap();
            std::fs::write(&kept, &actual).unwrap();
            continue;
        }
        let expected = std::fs::read_to_string(&kept).unwrap_or_else(|e| {
            panic!(
                "{case}: no golden copy {} ({e}); run with REGENERATE=1",
                kept.display()
            )
        });
        let mut diffs = Vec::new();
        if file.ends_with(".json") {
            let a: serde_json::Value = serde_json::from_str(&actual).unwrap();
            let e: serde_json::Value = serde_json::from_str(&expected).unwrap();
            json_diff("", &e, &a, &mut diffs);
        } else if file.ends_with(".csv") {
            csv_diff(&expected, &actual, &mut diffs);
        } else if expected != actual {
            diffs.push("contents differ".to_string());
        }
        problems.extend(diffs.into_iter().take(8).map(|d| format!("{file}: {d}")));
    }
    assert!(
        problems.is_empty(),
        "{case}: outputs differ from tests/golden/{case} (REGENERATE=1 rewrites them on purpose):\n{}",
        problems.join("\n")
    );
}

/// Whether two numbers agree within [`TOLERANCE`].
fn close(e: f64, a: f64) -> bool {
    e == a || (e - a).abs() <= TOLERANCE * e.abs().max(a.abs()).max(1.0)
}

/// The differences between JSON values `e` (golden) and `a`, at `path`.
fn json_diff(path: &str, e: &serde_json::Value, a: &serde_json::Value, out: &mut Vec<String>) {
    use serde_json::Value;
    match (e, a) {
        (Value::Number(x), Value::Number(y)) => {
            let (x, y) = (x.as_f64().unwrap(), y.as_f64().unwrap());
            if !close(x, y) {
                out.push(format!("{path}: {x:e} -> {y:e}"));
            }
        }
        (Value::Object(x), Value::Object(y)) => {
            for (k, v) in x {
                if VOLATILE.contains(&k.as_str()) {
                    continue;
                }
                match y.get(k) {
                    Some(w) => json_diff(&format!("{path}.{k}"), v, w, out),
                    None => out.push(format!("{path}.{k}: missing")),
                }
            }
            for k in y.keys().filter(|k| !x.contains_key(*k)) {
                out.push(format!("{path}.{k}: new field"));
            }
        }
        (Value::Array(x), Value::Array(y)) if x.len() == y.len() => {
            for (i, (v, w)) in x.iter().zip(y).enumerate() {
                json_diff(&format!("{path}[{i}]"), v, w, out);
            }
        }
        (Value::Array(x), Value::Array(y)) => {
            out.push(format!("{path}: {} -> {} elements", x.len(), y.len()));
        }
        _ if e == a => {}
        _ => out.push(format!("{path}: {e} -> {a}")),
    }
}

/// The differences between two CSV texts: same header, same rows, numbers
/// within [`TOLERANCE`], other cells equal; [`VOLATILE`] columns skipped.
fn csv_diff(expected: &str, actual: &str, out: &mut Vec<String>) {
    let (e, a): (Vec<&str>, Vec<&str>) = (expected.lines().collect(), actual.lines().collect());
    if e.len() != a.len() {
        out.push(format!("{} -> {} lines", e.len(), a.len()));
        return;
    }
    let Some(head) = e.first() else { return };
    let columns: Vec<&str> = head.split(',').collect();
    for (row, (le, la)) in e.iter().zip(&a).enumerate() {
        let (ce, ca) = (split_cells(le), split_cells(la));
        if ce.len() != ca.len() {
            out.push(format!(
                "line {}: {} -> {} cells",
                row + 1,
                ce.len(),
                ca.len()
            ));
            continue;
        }
        for (i, (x, y)) in ce.iter().zip(&ca).enumerate() {
            let column = columns.get(i).copied().unwrap_or("");
            if row > 0 && VOLATILE.iter().any(|v| column.contains(v)) {
                continue;
            }
            let same = match (x.parse::<f64>(), y.parse::<f64>()) {
                (Ok(p), Ok(q)) => close(p, q) || (p.is_nan() && q.is_nan()),
                _ => x == y,
            };
            if !same {
                out.push(format!("line {}, {column}: {x} -> {y}", row + 1));
            }
        }
    }
}
