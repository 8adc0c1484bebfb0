//! Python bindings of vicurve: the native module `vicurve._vicurve` of the
//! `vicurve` Python package (`python/vicurve/__init__.py` re-exports it;
//! `python/vicurve/_vicurve.pyi` types it).
//!
//! Nothing is measured here: arguments are converted to the library's
//! types (with the names the command-line tool uses), the library runs
//! with the GIL released, and results and errors are converted back. The
//! conversions that need no Python object are in [`args`] and unit-tested
//! by `cargo test`; the Python side is tested by `tests/*.py` (pytest, on
//! the installed wheel).
//!
//! Built by maturin (`pyproject.toml`), which sets
//! `PYO3_BUILD_EXTENSION_MODULE` so that the module does not link
//! libpython; a plain `cargo build` or `cargo test` links it.

#![deny(missing_docs)]

mod all;
pub mod args;
mod curves;
mod errors;
mod frames;
mod functions;
mod image_arg;
mod json;
mod result;
mod run;
mod track;
mod tracked;

use pyo3::prelude::*;

/// Sub-pixel measurement of curves and edges in images by Virtual Image
/// Correlation (native part of the `vicurve` package).
#[pymodule]
fn _vicurve(m: &Bound<'_, PyModule>) -> PyResult<()> {
    let py = m.py();
    m.add("__version__", env!("CARGO_PKG_VERSION"))?;
    m.add("FitError", py.get_type::<errors::FitError>())?;
    m.add_class::<curves::Circle>()?;
    m.add_class::<curves::Segment>()?;
    m.add_class::<curves::Polyline>()?;
    m.add_class::<curves::Auto>()?;
    m.add_class::<result::PyMeasurement>()?;
    m.add_function(wrap_pyfunction!(functions::measure, m)?)?;
    m.add_function(wrap_pyfunction!(all::measure_all, m)?)?;
    m.add_function(wrap_pyfunction!(functions::synth, m)?)?;
    m.add_function(wrap_pyfunction!(functions::evaluate, m)?)?;
    m.add_function(wrap_pyfunction!(functions::basis_values, m)?)?;
    m.add_function(wrap_pyfunction!(functions::interpolate, m)?)?;
    m.add_class::<track::Tracker>()?;
    m.add_class::<tracked::TrackedFrame>()?;
    m.add_function(wrap_pyfunction!(track::track, m)?)?;
    m.add_function(wrap_pyfunction!(run::run, m)?)?;
    Ok(())
}
