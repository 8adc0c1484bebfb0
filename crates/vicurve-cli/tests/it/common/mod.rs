//! Helpers shared by the command-line tests: running the binary, reading
//! its outputs, synthesising inputs.

pub mod golden;

use std::path::Path;
use std::process::{Command, Output};

/// Run `vicurve` with `args` (in the test's working directory, the
/// crate's folder; give absolute paths).
pub fn vicurve(args: &[&str]) -> Output {
    Command::new(env!("CARGO_BIN_EXE_vicurve"))
        .args(args)
        .output()
        .expect("run vicurve")
}

/// Run `vicurve` with `args` in `dir` (so that relative paths, and the
/// names the outputs record, do not depend on where the test runs).
pub fn vicurve_in(dir: &Path, args: &[&str]) -> Output {
    Command::new(env!("CARGO_BIN_EXE_vicurve"))
        .args(args)
        .current_dir(dir)
        .output()
        .expect("run vicurve")
}

/// Bytes printed by the binary as text.
pub fn text(b: &[u8]) -> String {
    String::from_utf8_lossy(b).into_owned()
}

/// `vicurve ARGS` in `dir`, which must succeed.
pub fn ok_in(dir: &Path, args: &[&str]) -> Output {
    let out = vicurve_in(dir, args);
    assert!(
        out.status.success(),
        "vicurve {}: {}",
        args.join(" "),
        text(&out.stderr)
    );
    out
}

/// Assert that `out` is a success, showing its stderr otherwise.
pub fn ok(out: &Output) {
    assert!(out.status.success(), "stderr: {}", text(&out.stderr));
}

/// `name` in `dir`, as an argument.
pub fn p(dir: &Path, name: &str) -> String {
    dir.join(name).display().to_string()
}

/// The error contract: exit code `code`, stderr one line starting with
/// `vicurve: error:` and containing `needle` in any case.
pub fn assert_error(out: &Output, code: i32, needle: &str) {
    let line = one_error_line(out, code);
    assert!(
        line.to_lowercase().contains(&needle.to_lowercase()),
        "'{needle}' not in: {line}"
    );
}

/// [`assert_error`] with `needle` matched as written (same case).
pub fn assert_error_exact(out: &Output, code: i32, needle: &str) {
    let line = one_error_line(out, code);
    assert!(line.contains(needle), "'{needle}' not in: {line}");
}

/// The one line of stderr of a run that failed with exit code `code`.
fn one_error_line(out: &Output, code: i32) -> String {
    let err = text(&out.stderr);
    assert_eq!(out.status.code(), Some(code), "stderr: {err}");
    let lines: Vec<&str> = err.lines().collect();
    assert_eq!(lines.len(), 1, "one line expected, got: {err}");
    assert!(lines[0].starts_with("vicurve: error: "), "{err}");
    err
}

/// The cells of one CSV line (quoted cells may hold commas and `""`): the
/// library's own reader of the files it writes.
pub fn split_cells(line: &str) -> Vec<String> {
    vicurve::sequence::run::summary::split_csv(line)
}
