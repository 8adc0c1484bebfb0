//! `measure_all`: every object of an image ([`vicurve::objects`]), its
//! results and its table.

use crate::errors::to_py_err;
use crate::image_arg::ImageArg;
use crate::result::PyMeasurement;
use numpy::IntoPyArray;
use pyo3::prelude::*;
use pyo3::types::PyDict;
use vicurve::model::ShapeModel;
use vicurve::objects::{measure_all as measure_every, object_table, AllConfig, AllResult};

/// Measure every object of `image` (a 2-D array or a path).
///
/// Objects are the regions of `polarity` ("auto": the minority phase,
/// "bright", "dark") whose edge is long (`min_length`, px), large
/// (`min_area`, px^2) and contrasted enough; defaults follow from the last
/// band and the image noise. `roi=(x0, y0, x1, y1)` limits the search;
/// objects cut by its border are skipped unless `include_border`; with
/// `holes`, the holes inside the objects are objects too (of the opposite
/// polarity, numbered after them, the table's `parent` giving the object
/// each is in). `kind="contour"` measures every ridge or valley line
/// instead, each line whose strength is at least `min_strength` (default
/// from the noise). `model` ("circle", "ellipse", "polygon:N") is fitted to
/// each. `corners=N`: the objects are polygons of N corners (the cells of
/// a square grid: 4), each fit breaking at its start's N sharpest turns.
///
/// Returns `(results, table)`: one entry per object, numbered row-major by
/// centroid, a `Result` (None when the object could not be measured at
/// all); the table a dict of NumPy arrays, one value per object, with
/// `outcome` ("measured" or the failure's reason) and `message`. One
/// object's failure never stops the others. The work runs with the GIL
/// released, objects in parallel.
#[pyfunction]
#[pyo3(signature = (
    image, *, polarity = "auto", model = None, min_length = None, min_area = None,
    roi = None, include_border = false, holes = false, kind = "silhouette",
    min_strength = None, corners = None
))]
#[allow(clippy::too_many_arguments)]
pub fn measure_all<'py>(
    py: Python<'py>,
    image: &Bound<'py, PyAny>,
    polarity: &str,
    model: Option<&str>,
    min_length: Option<f64>,
    min_area: Option<f64>,
    roi: Option<(f64, f64, f64, f64)>,
    include_border: bool,
    holes: bool,
    kind: &str,
    min_strength: Option<f64>,
    corners: Option<usize>,
) -> PyResult<(Vec<Option<PyMeasurement>>, Bound<'py, PyDict>)> {
    let model: Option<ShapeModel> = model.map(str::parse).transpose().map_err(to_py_err)?;
    let config = AllConfig {
        polarity: polarity.parse().map_err(to_py_err)?,
        model,
        min_length,
        min_area,
        roi: roi.map(|(a, b, c, d)| [a, b, c, d]),
        include_border,
        holes,
        min_strength,
        corners,
        fit: vicurve::fit::FitConfig {
            kind: kind.parse().map_err(to_py_err)?,
            ..vicurve::fit::FitConfig::default()
        },
        ..AllConfig::default()
    };
    config.validate().map_err(to_py_err)?;
    let image = ImageArg::from_py(image)?;
    let run = py.detach(
        move || -> vicurve::Result<(AllResult, String, (usize, usize))> {
            let (image, source) = image.load()?;
            let all = measure_every(&image, &config)?;
            Ok((all, source, (image.width(), image.height())))
        },
    );
    let (all, source, size) = run.map_err(to_py_err)?;
    let table = table_dict(py, &all)?;
    let results = all
        .objects
        .into_iter()
        .map(|o| match (o.start, o.measurement) {
            (Some(init), Some(measurement)) => Some(PyMeasurement {
                measurement,
                init,
                config: o.config,
                source: source.clone(),
                size,
                start: None,
                grow: None,
            }),
            _ => None,
        })
        .collect();
    Ok((results, table))
}

/// The table of `all` as a dict of NumPy arrays (float64; `id` int64) and
/// lists of strings (`outcome`, `message`).
fn table_dict<'py>(py: Python<'py>, all: &AllResult) -> PyResult<Bound<'py, PyDict>> {
    let t = object_table(all);
    let d = PyDict::new(py);
    for (name, values) in t.columns {
        if name == "id" {
            let ids: Vec<i64> = values.iter().map(|&v| v as i64).collect();
            d.set_item(name, ids.into_pyarray(py))?;
        } else {
            d.set_item(name, values.into_pyarray(py))?;
        }
    }
    d.set_item("outcome", t.outcome)?;
    d.set_item("message", t.message)?;
    Ok(d)
}
