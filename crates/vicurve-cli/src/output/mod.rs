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
use std::io::Write;
use std::path::Path;
use vicurve::fit::{Measurement, Sample};

/// The record `measure --out` writes lives in the library, so that the
/// Python package writes the same document.
pub use vicurve::report::{polarity_text, ResultFile};

/// Write any serialisable value as pretty JSON.
pub fn write_json<T: Serialize>(path: &Path, value: &T) -> Result<(), String> {
    let text = serde_json::to_string_pretty(value)
        .map_err(|e| format!("cannot encode JSON for {}: {e}", path.display()))?;
    std::fs::write(path, text + "\n").map_err(|e| format!("cannot write {}: {e}", path.display()))
}

/// Write the samples as CSV: the header
/// `s,x,y,nx,ny,sigma,weight,sigma_noise,misfit` (a contract: other tools
/// read the columns by these names), then one row per sample (`sigma`: the
/// position's uncertainty in px, model misfit included; `weight`: the share
/// of the band kept by the robust weights there, 1 where nothing was
/// down-weighted; `sigma_noise`: the noise's share of `sigma`; `misfit`: 1
/// where the model misfits, else 0).
pub fn write_points_csv(path: &Path, m: &Measurement) -> Result<(), String> {
    let err = |e: std::io::Error| format!("cannot write {}: {e}", path.display());
    let file = std::fs::File::create(path).map_err(err)?;
    let mut w = std::io::BufWriter::new(file);
    writeln!(w, "{SAMPLE_COLUMNS}").map_err(err)?;
    for s in &m.samples {
        writeln!(w, "{}", sample_row(s)).map_err(err)?;
    }
    w.flush().map_err(err)
}

/// The columns of a sample row ([`write_points_csv`]).
pub const SAMPLE_COLUMNS: &str = "s,x,y,nx,ny,sigma,weight,sigma_noise,misfit";

/// One sample as a CSV row of [`SAMPLE_COLUMNS`].
pub fn sample_row(s: &Sample) -> String {
    format!(
        "{:.6},{:.6},{:.6},{:.6},{:.6},{:.3e},{:.3},{:.3e},{}",
        s.s,
        s.x,
        s.y,
        s.nx,
        s.ny,
        s.sigma,
        s.weight,
        s.sigma_noise,
        u8::from(s.misfit)
    )
}

/// Write `bytes` to `path` through a temporary file in the same folder and
/// a rename: readers (and a later run) see the old file or the new one,
/// never a part.
pub fn write_atomic(path: &Path, bytes: &[u8]) -> Result<(), String> {
    let name = path
        .file_name()
        .map(|n| n.to_string_lossy().into_owned())
        .unwrap_or_default();
    let tmp = path.with_file_name(format!(".{name}.tmp-{}", std::process::id()));
    let fail = |e: std::io::Error| format!("cannot write {}: {e}", path.display());
    std::fs::write(&tmp, bytes).map_err(fail)?;
    std::fs::rename(&tmp, path).map_err(|e| {
        let _ = std::fs::remove_file(&tmp);
        fail(e)
    })
}

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
