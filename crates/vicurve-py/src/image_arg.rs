//! The `image` argument: a 2-D NumPy array or a path to an image file.
//!
//! Arrays are copied into a [`vicurve::Image`] with the scaling
//! `vicurve::io::load_image` applies to files, so that an array and the
//! file it came from give the same gray levels, bit for bit:
//! `uint8` divided by 255, `uint16` by 65535, `float32` and `float64` kept
//! as they are. Other types of arrays are refused rather than guessed at
//! (a signed or 32-bit integer image has no agreed full scale).
//!
//! Paths (`str` or `os.PathLike`) are read by `vicurve::io::load_image`
//! after the GIL is released.

use crate::errors::{to_py_err, value_error};
use numpy::ndarray::ArrayView2;
use numpy::{PyArray2, PyArrayDescrMethods, PyArrayMethods, PyUntypedArray, PyUntypedArrayMethods};
use pyo3::exceptions::PyTypeError;
use pyo3::prelude::*;
use std::path::PathBuf;
use vicurve::Image;

/// An image argument, ready to be turned into an [`Image`] without the GIL.
pub enum ImageArg {
    /// Pixels copied from an array, and the array's description.
    Pixels(Image, String),
    /// A file to read.
    File(PathBuf),
}

impl ImageArg {
    /// Read the Python argument (arrays are copied now, files read later
    /// by [`ImageArg::load`]).
    pub fn from_py(obj: &Bound<'_, PyAny>) -> PyResult<Self> {
        if let Ok(array) = obj.cast::<PyUntypedArray>() {
            return from_array(array);
        }
        if obj.is_instance_of::<pyo3::types::PyString>() || is_path_like(obj)? {
            let path: PathBuf = obj.extract()?;
            return Ok(ImageArg::File(path));
        }
        // Nested lists and other array-likes: as NumPy sees them.
        let numpy = obj.py().import("numpy")?;
        let converted = numpy.call_method1("asarray", (obj,)).map_err(|_| {
            PyTypeError::new_err(format!(
                "image: expected a 2-D NumPy array or a path (str or os.PathLike), got {}",
                type_name(obj)
            ))
        })?;
        match converted.cast::<PyUntypedArray>() {
            Ok(array) => from_array(array),
            Err(_) => Err(PyTypeError::new_err(format!(
                "image: expected a 2-D NumPy array or a path (str or os.PathLike), got {}",
                type_name(obj)
            ))),
        }
    }

    /// The image and the name a result file records for it (the path as
    /// given, or a description of the array). Call without the GIL.
    pub fn load(self) -> vicurve::Result<(Image, String)> {
        match self {
            ImageArg::Pixels(image, name) => Ok((image, name)),
            ImageArg::File(path) => {
                let image = vicurve::io::load_image(&path)?;
                Ok((image, path.display().to_string()))
            }
        }
    }
}

/// Whether `obj` implements `os.PathLike` (has `__fspath__`).
fn is_path_like(obj: &Bound<'_, PyAny>) -> PyResult<bool> {
    obj.hasattr("__fspath__")
}

/// The Python type's name of `obj`, for messages.
pub fn type_name(obj: &Bound<'_, PyAny>) -> String {
    obj.get_type()
        .name()
        .map(|n| n.to_string())
        .unwrap_or_else(|_| "?".into())
}

/// An array's pixels, scaled like image files.
fn from_array(array: &Bound<'_, PyUntypedArray>) -> PyResult<ImageArg> {
    let ndim = array.ndim();
    if ndim != 2 {
        return Err(value_error(format!(
            "image: expected a 2-D array (rows x columns of gray levels), got a {ndim}-D array of shape {:?}; convert colour images to gray first",
            array.shape()
        )));
    }
    let dtype = array.dtype();
    let dtype_text = dtype.str().map(|s| s.to_string()).unwrap_or_default();
    // Non-native byte order (e.g. '>f8' from a FITS file): native copy.
    if dtype.is_native_byteorder() == Some(false) {
        let native = dtype.call_method1("newbyteorder", ("=",))?;
        let copy = array.call_method1("astype", (native,))?;
        return from_array(copy.cast::<PyUntypedArray>()?);
    }
    let description = format!("<numpy array, {dtype_text}>");
    let (height, width) = (array.shape()[0], array.shape()[1]);
    let data = if let Ok(a) = array.cast::<PyArray2<u8>>() {
        scaled(a, |v| f64::from(v) / 255.0)?
    } else if let Ok(a) = array.cast::<PyArray2<u16>>() {
        scaled(a, |v| f64::from(v) / 65535.0)?
    } else if let Ok(a) = array.cast::<PyArray2<f32>>() {
        scaled(a, f64::from)?
    } else if let Ok(a) = array.cast::<PyArray2<f64>>() {
        scaled(a, |v| v)?
    } else {
        return Err(value_error(format!(
            "image: unsupported dtype {dtype_text} (expected uint8, uint16, float32 or float64; convert other types with astype and scale them to gray levels)"
        )));
    };
    let image = Image::new(width, height, data).map_err(to_py_err)?;
    Ok(ImageArg::Pixels(image, description))
}

/// The array's values, row after row, through `f`.
fn scaled<T: numpy::Element + Copy>(
    array: &Bound<'_, PyArray2<T>>,
    f: impl Fn(T) -> f64,
) -> PyResult<Vec<f64>> {
    let guard = array
        .try_readonly()
        .map_err(|e| value_error(format!("image: the array cannot be read: {e}")))?;
    let view: ArrayView2<'_, T> = guard.as_array();
    Ok(view.iter().map(|&v| f(v)).collect())
}
