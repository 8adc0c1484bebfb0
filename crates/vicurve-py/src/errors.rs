//! The library's errors as Python exceptions.
//!
//! - [`vicurve::Error::NotFound`] becomes `FileNotFoundError`;
//! - [`vicurve::Error::Io`] becomes `OSError`;
//! - everything else (parameters, images, curves, bands, parsing): `ValueError`;
//! - a fit that diverged is not a library error (it is an outcome); the
//!   `measure` function raises [`FitError`] for it, a `RuntimeError` whose
//!   `result` attribute holds the partial result.
//!
//! The exception's message is the library's, unchanged.

use pyo3::exceptions::{PyFileNotFoundError, PyOSError, PyRuntimeError, PyValueError};
use pyo3::PyErr;

pyo3::create_exception!(
    vicurve,
    FitError,
    PyRuntimeError,
    "The fit diverged. The message says why; the attribute `result` holds the partial result (a `vicurve.Result` with the last good curve and the history)."
);

/// The Python exception for a library error.
pub fn to_py_err(e: vicurve::Error) -> PyErr {
    match e {
        vicurve::Error::NotFound { .. } => PyFileNotFoundError::new_err(e.to_string()),
        vicurve::Error::Io { .. } => PyOSError::new_err(e.to_string()),
        other => PyValueError::new_err(other.to_string()),
    }
}

/// A `ValueError` with this message.
pub fn value_error(message: impl Into<String>) -> PyErr {
    PyValueError::new_err(message.into())
}
