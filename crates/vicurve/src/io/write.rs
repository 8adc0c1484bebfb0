//! Files written so that a reader never sees a part of one: the samples
//! CSV of a measurement, and any file written through a temporary name.

use crate::fit::{Measurement, Sample};
use rayon::prelude::*;
use std::io::Write;
use std::path::Path;

/// Write the samples as CSV: the header
/// `s,x,y,nx,ny,sigma,weight,sigma_noise,misfit` (a contract: other tools
/// read the columns by these names), then one row per sample (`sigma`: the
/// position's uncertainty in px, model misfit included, a shift common to
/// the whole curve not ([`Measurement::sigma_shift`], in the JSON);
/// `weight`: the share
/// of the band kept by the robust weights there, 1 where nothing was
/// down-weighted; `sigma_noise`: the noise's share of `sigma`; `misfit`: 1
/// where the model misfits, else 0).
///
/// Errors: one line naming the file and the operating system's reason.
pub fn write_points_csv(path: &Path, m: &Measurement) -> Result<(), String> {
    let err = |e: std::io::Error| format!("cannot write {}: {e}", path.display());
    // The rows formatted in parallel, in blocks written in order: the
    // same bytes, on every core.
    let blocks: Vec<String> = m
        .samples
        .par_chunks(ROWS_PER_BLOCK)
        .map(|chunk| {
            let mut block = String::with_capacity(chunk.len() * 96);
            for s in chunk {
                block.push_str(&sample_row(s));
                block.push('\n');
            }
            block
        })
        .collect();
    let file = std::fs::File::create(path).map_err(err)?;
    let mut w = std::io::BufWriter::new(file);
    writeln!(w, "{SAMPLE_COLUMNS}").map_err(err)?;
    for block in &blocks {
        w.write_all(block.as_bytes()).map_err(err)?;
    }
    w.flush().map_err(err)
}

/// Rows of [`write_points_csv`] formatted per parallel task.
const ROWS_PER_BLOCK: usize = 512;

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

/// The temporary name [`write_atomic`] writes `path` to first:
/// `.NAME.tmp-PID` in the same folder (so that the rename stays on one
/// file system, and a killed run's leftovers can be recognised).
pub fn temporary_name(path: &Path) -> std::path::PathBuf {
    let name = path
        .file_name()
        .map(|n| n.to_string_lossy().into_owned())
        .unwrap_or_default();
    path.with_file_name(format!(".{name}.tmp-{}", std::process::id()))
}

/// Write `bytes` to `path` through a temporary file in the same folder and
/// a rename: readers (and a later run) see the old file or the new one,
/// never a part.
///
/// Errors: one line naming the file and the operating system's reason.
pub fn write_atomic(path: &Path, bytes: &[u8]) -> Result<(), String> {
    let tmp = temporary_name(path);
    let fail = |e: std::io::Error| format!("cannot write {}: {e}", path.display());
    std::fs::write(&tmp, bytes).map_err(fail)?;
    std::fs::rename(&tmp, path).map_err(|e| {
        let _ = std::fs::remove_file(&tmp);
        fail(e)
    })
}
