//! What a measurement writes and prints: the result file, the points
//! CSV, overlays, diagnostics, the shape models' records, CAD exports and
//! the summary on the terminal. Shared by `measure`, `demo` and sequences.
//!
//! - [`measurement`]: every output of one measurement, and its summary;
//! - [`model`]: `measure --model`, a shape fitted after the measurement;
//! - [`overlay`]: SVG and PNG overlays of curves on the image;
//! - [`diagnostics`]: `measure --diagnostics DIR`;
//! - [`cad`]: DXF and SVG exports of the B-spline;
//! - [`objects`]: the outputs of `measure --all`;
//! - [`strain_map`]: `grid --map`, the circles coloured by their strain.

pub mod cad;
pub mod diagnostics;
pub mod measurement;
pub mod model;
pub mod objects;
pub mod overlay;
pub mod strain_map;

use serde::Serialize;
use std::path::Path;

/// The record `measure --out` writes lives in the library, so that the
/// Python package writes the same document.
pub use vicurve::report::{polarity_text, ResultFile};

/// Write any serialisable value as pretty JSON.
pub fn write_json<T: Serialize>(path: &Path, value: &T) -> Result<(), String> {
    let text = serde_json::to_string_pretty(value)
        .map_err(|e| format!("cannot encode JSON for {}: {e}", path.display()))?;
    std::fs::write(path, text + "\n").map_err(|e| format!("cannot write {}: {e}", path.display()))
}

/// The samples CSV and atomic writes live in the library, so that the
/// Python package writes the same files.
pub use vicurve::io::{sample_row, write_atomic, write_points_csv, SAMPLE_COLUMNS};

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn atomic_write_replaces_whole_files() {
        let dir = tempfile::tempdir().unwrap();
        let p = dir.path().join("a.txt");
        write_atomic(&p, b"first").unwrap();
        write_atomic(&p, b"second").unwrap();
        assert_eq!(std::fs::read(&p).unwrap(), b"second");
        // No temporary file is left behind.
        assert_eq!(std::fs::read_dir(dir.path()).unwrap().count(), 1);
    }
}
