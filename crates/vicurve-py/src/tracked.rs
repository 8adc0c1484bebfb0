//! What `vicurve.track` yields per frame ([`TrackedFrame`]), and the
//! table of the frames yielded so far ([`Summary`]).

use crate::result::PyMeasurement;
use numpy::IntoPyArray;
use pyo3::prelude::*;
use pyo3::types::PyDict;
use vicurve::fit::{Measurement, Outcome};
use vicurve::sequence::run::summary::{cell, split_csv};

/// One frame of `vicurve.track`: `index` (from 0), `name` (the file stem,
/// `STEM_KKKK` for page K of a stack, `frame_KKKK` for an array), `input`
/// (the path, `PATH#K` for a page), `ok` (a curve to go on from: converged
/// or at its iteration limit), `outcome` ("converged", "iteration_limit",
/// "diverged" or "failed": nothing measured), `reason` (why it failed, or a
/// retry), `started_from` ("init" or the name of the frame the fit started
/// from), `result` (a `vicurve.Result`, None when nothing was measured or
/// the frame was `resumed`) and `resumed` (with `out_dir`: the frame was
/// done by an earlier run, and read back from its files instead of being
/// measured again).
#[pyclass(module = "vicurve", name = "TrackedFrame", frozen, get_all)]
pub struct TrackedFrame {
    pub(crate) index: usize,
    pub(crate) name: String,
    pub(crate) input: String,
    pub(crate) ok: bool,
    pub(crate) outcome: String,
    pub(crate) reason: Option<String>,
    pub(crate) started_from: String,
    pub(crate) result: Option<Py<PyMeasurement>>,
    pub(crate) resumed: bool,
}

#[pymethods]
impl TrackedFrame {
    fn __repr__(&self) -> String {
        format!(
            "TrackedFrame(index={}, name={:?}, outcome={:?})",
            self.index, self.name, self.outcome
        )
    }
}

/// A fit's outcome as the summary names it.
pub fn outcome_name(m: &Measurement) -> &'static str {
    match m.outcome {
        Outcome::Converged => "converged",
        Outcome::IterationLimit => "iteration_limit",
        Outcome::Diverged { .. } => "diverged",
    }
}

/// The per-frame values of the summary, in frame order.
#[derive(Default)]
pub struct Summary {
    frame: Vec<usize>,
    name: Vec<String>,
    outcome: Vec<String>,
    reason: Vec<String>,
    started_from: Vec<String>,
    iterations: Vec<i64>,
    residual: Vec<f64>,
    length: Vec<f64>,
    area: Vec<f64>,
}

impl Summary {
    /// A frame yielded, its numbers from its measurement.
    pub fn record(&mut self, f: &TrackedFrame) {
        let m = f.result.as_ref().map(|r| &r.get().measurement);
        self.push_names(f);
        self.iterations
            .push(m.map_or(-1, |m| i64::try_from(m.iterations()).unwrap_or(i64::MAX)));
        self.residual.push(m.map_or(f64::NAN, |m| m.residual_rms()));
        self.length.push(m.map_or(f64::NAN, |m| m.length()));
        self.area.push(m.and_then(|m| m.area()).unwrap_or(f64::NAN));
    }

    /// A frame read back, its numbers from its summary row (as written:
    /// six decimals, the residual to three digits).
    pub fn record_row(&mut self, f: &TrackedFrame, row: &str) {
        let cells = split_csv(row);
        let num = |name: &str| cell(&cells, name).parse::<f64>().unwrap_or(f64::NAN);
        self.push_names(f);
        self.iterations
            .push(cell(&cells, "iterations").parse::<i64>().unwrap_or(-1));
        self.residual.push(num("residual"));
        self.length.push(num("length"));
        self.area.push(num("area"));
    }

    fn push_names(&mut self, f: &TrackedFrame) {
        self.frame.push(f.index);
        self.name.push(f.name.clone());
        self.outcome.push(f.outcome.clone());
        self.reason.push(f.reason.clone().unwrap_or_default());
        self.started_from.push(f.started_from.clone());
    }

    /// The table: a dict of NumPy arrays, a DataFrame when `pandas` and
    /// pandas is installed.
    pub fn to_py<'py>(&self, py: Python<'py>, pandas: bool) -> PyResult<Bound<'py, PyAny>> {
        let d = PyDict::new(py);
        let np = py.import("numpy")?;
        let strings = |v: &Vec<String>| np.call_method1("array", (v.clone(),));
        d.set_item("frame", self.frame.clone().into_pyarray(py))?;
        d.set_item("name", strings(&self.name)?)?;
        d.set_item("outcome", strings(&self.outcome)?)?;
        d.set_item("reason", strings(&self.reason)?)?;
        d.set_item("started_from", strings(&self.started_from)?)?;
        d.set_item("iterations", self.iterations.clone().into_pyarray(py))?;
        d.set_item("residual", self.residual.clone().into_pyarray(py))?;
        d.set_item("length", self.length.clone().into_pyarray(py))?;
        d.set_item("area", self.area.clone().into_pyarray(py))?;
        table(py, d, pandas)
    }
}

/// `d` as a pandas DataFrame when `pandas` and pandas is installed, else
/// as it is.
pub fn table<'py>(
    py: Python<'py>,
    d: Bound<'py, PyDict>,
    pandas: bool,
) -> PyResult<Bound<'py, PyAny>> {
    if pandas {
        if let Ok(pd) = py.import("pandas") {
            return pd.call_method1("DataFrame", (d,));
        }
    }
    Ok(d.into_any())
}
