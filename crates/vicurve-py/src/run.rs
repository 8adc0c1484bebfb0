//! `vicurve.run("job.toml")`: a job file run as `vicurve run job.toml`
//! runs it, by the library's job runner (the same parser, frames, files,
//! summary and resume), with the GIL released; the summary returned as a
//! table.

use crate::errors::{to_py_err, value_error};
use crate::track::progress_bar;
use crate::tracked::table;
use numpy::IntoPyArray;
use pyo3::exceptions::{PyFileNotFoundError, PyRuntimeWarning};
use pyo3::prelude::*;
use pyo3::types::PyDict;
use std::ffi::CString;
use std::path::PathBuf;
use std::time::Duration;
use vicurve::sequence::run::frame::FrameOutput;
use vicurve::sequence::run::job::{load, parse_shard, shard};
use vicurve::sequence::run::summary::{split_csv, COLUMNS};
use vicurve::sequence::run::{run_job, RunObserver, RunStatus};

/// The columns of `summary.csv` that hold text; `iterations` and
/// `width_samples` hold counts (-1 when empty), the others numbers (NaN
/// when empty).
const TEXT: [&str; 5] = ["frame", "curve", "outcome", "reason", "started_from"];
const COUNTS: [&str; 2] = ["iterations", "width_samples"];

/// Advances a tqdm bar, taking the GIL for it.
struct Bar(Option<Py<PyAny>>);

impl Bar {
    fn call(&self, method: &str, args: (usize,)) {
        if let Some(bar) = &self.0 {
            Python::attach(|py| {
                let _ = bar.bind(py).call_method1(method, args);
            });
        }
    }
}

impl RunObserver for Bar {
    fn started(&mut self, to_do: usize) {
        if let Some(bar) = &self.0 {
            Python::attach(|py| {
                let _ = bar.bind(py).setattr("total", to_do);
                let _ = bar.bind(py).call_method0("refresh");
            });
        }
    }

    fn one_more(&mut self) {
        if let Some(bar) = &self.0 {
            Python::attach(|py| {
                let total: usize = bar
                    .bind(py)
                    .getattr("total")
                    .and_then(|t| t.extract())
                    .unwrap_or(0);
                let _ = bar.bind(py).setattr("total", total + 1);
            });
        }
    }

    fn measured(&mut self, _: (usize, usize), _: &str, _: &FrameOutput, _: Duration) {
        self.call("update", (1,));
    }
}

/// Run a job file (TOML: images, curves, widths, outputs; see the
/// README's "Sequences"), as `vicurve run job.toml`: the same frames,
/// files in the job's `out_dir` and `summary.csv`, the same resume (frames
/// done by an earlier run, of the command line or of this function, are
/// skipped; `force=True` measures every frame again) and `shard="K/N"`
/// (part K of N of an untracked job's frames). The overlays and the width
/// plots are the command line's: a job asking for overlays is refused
/// (set `overlay = "none"` or run `vicurve run`), plots are not drawn.
///
/// Returns the summary, one row per curve and width of every frame with
/// the columns of `summary.csv`: a pandas DataFrame when pandas is
/// installed (and `pandas=False` not given), else a dict of NumPy arrays
/// (text columns as strings, `iterations` and `width_samples` as integers,
/// -1 when empty, the others as floats, NaN when empty). Frames that
/// failed are in the table; a `RuntimeWarning` says how many. Raises
/// `FileNotFoundError` for a missing job file, `ValueError` for a job that
/// cannot run.
#[pyfunction]
#[pyo3(signature = (job, *, force = false, shard = None, progress = true, pandas = true))]
pub fn run<'py>(
    py: Python<'py>,
    job: PathBuf,
    force: bool,
    shard: Option<&str>,
    progress: bool,
    pandas: bool,
) -> PyResult<Bound<'py, PyAny>> {
    if !job.is_file() {
        return Err(PyFileNotFoundError::new_err(format!(
            "job file not found: {}",
            job.display()
        )));
    }
    let mut parsed = load(&job).map_err(to_py_err)?;
    if let Some(text) = shard {
        let (k, n) = parse_shard(text).map_err(to_py_err)?;
        self::shard(&mut parsed, k, n).map_err(to_py_err)?;
    }
    if parsed.outputs.overlay.is_some() {
        return Err(value_error(format!(
            "{}: overlays are drawn by the command-line tool; run `vicurve run {}`, or set overlay = \"none\" in [outputs]",
            job.display(),
            job.display()
        )));
    }
    let mut bar = Bar(progress_bar(py, progress, None));
    let report = py
        .detach(|| run_job(parsed, force, &mut bar, None))
        .map_err(to_py_err)?;
    if let Some(b) = bar.0.take() {
        b.bind(py).call_method0("close")?;
    }
    if let RunStatus::SomeFailed(m) | RunStatus::NoneMeasured(m) = &report.status {
        let warning = py.get_type::<PyRuntimeWarning>();
        let text = CString::new(format!("vicurve: {m}")).unwrap_or_default();
        PyErr::warn(py, &warning, &text, 1)?;
    }
    summary_table(py, &report.lines, pandas)
}

/// The summary's rows as a table of `summary.csv`'s columns.
fn summary_table<'py>(
    py: Python<'py>,
    lines: &[Vec<String>],
    pandas: bool,
) -> PyResult<Bound<'py, PyAny>> {
    let rows: Vec<Vec<String>> = lines.iter().flatten().map(|l| split_csv(l)).collect();
    let cell = |r: &Vec<String>, i: usize| r.get(i).cloned().unwrap_or_default();
    let np = py.import("numpy")?;
    let d = PyDict::new(py);
    for (i, name) in COLUMNS.iter().enumerate() {
        if TEXT.contains(name) {
            let v: Vec<String> = rows.iter().map(|r| cell(r, i)).collect();
            d.set_item(name, np.call_method1("array", (v, "str"))?)?;
        } else if COUNTS.contains(name) {
            let v: Vec<i64> = rows
                .iter()
                .map(|r| cell(r, i).parse().unwrap_or(-1))
                .collect();
            d.set_item(name, v.into_pyarray(py))?;
        } else {
            let v: Vec<f64> = rows
                .iter()
                .map(|r| cell(r, i).parse().unwrap_or(f64::NAN))
                .collect();
            d.set_item(name, v.into_pyarray(py))?;
        }
    }
    table(py, d, pandas)
}
