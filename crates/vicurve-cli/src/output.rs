//! Result files: the JSON record of a measurement and the points CSV.

use serde::Serialize;
use std::io::Write;
use std::path::Path;
use vicurve::fit::Measurement;

/// The record `measure --out` writes lives in the library, so that the
/// Python package writes the same document.
pub use vicurve::report::{polarity_text, ResultFile};

/// Write any serialisable value as pretty JSON.
pub fn write_json<T: Serialize>(path: &Path, value: &T) -> Result<(), String> {
    let text = serde_json::to_string_pretty(value)
        .map_err(|e| format!("cannot encode JSON for {}: {e}", path.display()))?;
    std::fs::write(path, text + "\n").map_err(|e| format!("cannot write {}: {e}", path.display()))
}

/// Write the samples as CSV: the header `s,x,y,nx,ny,sigma,weight` (a
/// contract: other tools read the columns by these names), then one row per
/// sample (`sigma`: the position's uncertainty in px; `weight`: the share
/// of the band kept by the robust weights there, 1 where nothing was
/// down-weighted).
pub fn write_points_csv(path: &Path, m: &Measurement) -> Result<(), String> {
    let err = |e: std::io::Error| format!("cannot write {}: {e}", path.display());
    let file = std::fs::File::create(path).map_err(err)?;
    let mut w = std::io::BufWriter::new(file);
    writeln!(w, "s,x,y,nx,ny,sigma,weight").map_err(err)?;
    for s in &m.samples {
        writeln!(
            w,
            "{:.6},{:.6},{:.6},{:.6},{:.6},{:.3e},{:.3}",
            s.s, s.x, s.y, s.nx, s.ny, s.sigma, s.weight
        )
        .map_err(err)?;
    }
    w.flush().map_err(err)
}
