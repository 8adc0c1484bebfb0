//! Helpers shared by the command-line tests: running the binary, reading
//! its outputs, synthesising inputs.

pub mod golden;

use std::path::Path;
use std::process::{Command, Output};

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
