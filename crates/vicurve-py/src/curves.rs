//! Starting curves: `Circle`, `Segment`, `Polyline`, and `Auto` (the
//! library's automatic start, `vicurve::start`).
//!
//! They are plain, immutable values; they are checked when a measurement
//! uses them (the library's messages say what is wrong).

use crate::errors::value_error;
use crate::image_arg::type_name;
use numpy::ndarray::Array2;
use numpy::{AllowTypeChange, IntoPyArray, PyArray2, PyArrayLike2, PyUntypedArrayMethods};
use pyo3::exceptions::PyTypeError;
use pyo3::prelude::*;
use vicurve::curve::InitialCurve;
use vicurve::start::StartConfig;

/// A circle of centre (cx, cy) and radius r, pixels (x = column, y = row):
/// a closed start.
#[pyclass(module = "vicurve", frozen, eq)]
#[derive(Clone, Debug, PartialEq)]
pub struct Circle {
    /// Centre x (column), pixels.
    #[pyo3(get)]
    pub cx: f64,
    /// Centre y (row), pixels.
    #[pyo3(get)]
    pub cy: f64,
    /// Radius, pixels (at least 2).
    #[pyo3(get)]
    pub r: f64,
}

#[pymethods]
impl Circle {
    /// A circle of centre (cx, cy) and radius r, pixels.
    #[new]
    fn new(cx: f64, cy: f64, r: f64) -> Self {
        Circle { cx, cy, r }
    }

    fn __repr__(&self) -> String {
        format!("Circle(cx={:?}, cy={:?}, r={:?})", self.cx, self.cy, self.r)
    }
}

/// The straight segment from (x0, y0) to (x1, y1), pixels: an open start,
/// whose direction sets the measured curve's (the normal points to the
/// screen-right of travel).
#[pyclass(module = "vicurve", frozen, eq)]
#[derive(Clone, Debug, PartialEq)]
pub struct Segment {
    /// Start x, pixels.
    #[pyo3(get)]
    pub x0: f64,
    /// Start y, pixels.
    #[pyo3(get)]
    pub y0: f64,
    /// End x, pixels.
    #[pyo3(get)]
    pub x1: f64,
    /// End y, pixels.
    #[pyo3(get)]
    pub y1: f64,
}

#[pymethods]
impl Segment {
    /// The segment from (x0, y0) to (x1, y1), pixels.
    #[new]
    fn new(x0: f64, y0: f64, x1: f64, y1: f64) -> Self {
        Segment { x0, y0, x1, y1 }
    }

    fn __repr__(&self) -> String {
        format!(
            "Segment(x0={:?}, y0={:?}, x1={:?}, y1={:?})",
            self.x0, self.y0, self.x1, self.y1
        )
    }
}

/// A polyline through N points (an N x 2 array-like of x, y in pixels),
/// open or closed; it is smoothed into a cubic B-spline (corners rounded
/// over about 2 px).
#[pyclass(module = "vicurve", frozen, eq)]
#[derive(Clone, Debug, PartialEq)]
pub struct Polyline {
    points: Vec<[f64; 2]>,
    /// Whether the last point joins the first.
    #[pyo3(get)]
    pub closed: bool,
}

impl Polyline {
    /// The vertices.
    pub fn vertices(&self) -> &[[f64; 2]] {
        &self.points
    }

    /// From vertices.
    pub fn from_vertices(points: Vec<[f64; 2]>, closed: bool) -> Self {
        Polyline { points, closed }
    }
}

#[pymethods]
impl Polyline {
    /// A polyline through `points` (N x 2: x, y in pixels), closed or not.
    #[new]
    #[pyo3(signature = (points, closed = false))]
    fn new(points: PyArrayLike2<'_, f64, AllowTypeChange>, closed: bool) -> PyResult<Self> {
        Ok(Polyline {
            points: rows_xy("Polyline points", &points)?,
            closed,
        })
    }

    /// The vertices as an N x 2 float64 array (a copy).
    #[getter]
    fn points<'py>(&self, py: Python<'py>) -> Bound<'py, PyArray2<f64>> {
        xy_array(py, &self.points)
    }

    fn __repr__(&self) -> String {
        format!(
            "Polyline(<{} points>, closed={})",
            self.points.len(),
            if self.closed { "True" } else { "False" }
        )
    }
}

/// The automatic start (`vicurve::start`): the image is thresholded at
/// Otsu's level and the boundary of the main region (or of the one
/// containing `pick`), smoothed, is the starting curve; a region that
/// leaves the image gives an open curve. Silhouettes only.
#[pyclass(module = "vicurve", frozen, eq)]
#[derive(Clone, Debug, PartialEq)]
pub struct Auto {
    /// A point (x, y) inside the region to measure, or None (the main
    /// region: the largest one seen whole, else the longest edge).
    #[pyo3(get)]
    pub pick: Option<(f64, f64)>,
    /// The search rectangle (x0, y0, x1, y1), pixel centres inclusive, or
    /// None (the whole image).
    #[pyo3(get)]
    pub roi: Option<(f64, f64, f64, f64)>,
}

#[pymethods]
impl Auto {
    /// An automatic start, optionally from a picked point and within a
    /// rectangle.
    #[new]
    #[pyo3(signature = (pick = None, roi = None))]
    fn new(pick: Option<(f64, f64)>, roi: Option<(f64, f64, f64, f64)>) -> Self {
        Auto { pick, roi }
    }

    fn __repr__(&self) -> String {
        let opt = |v: Option<String>| v.unwrap_or_else(|| "None".into());
        format!(
            "Auto(pick={}, roi={})",
            opt(self.pick.map(|p| format!("{p:?}"))),
            opt(self.roi.map(|r| format!("{r:?}")))
        )
    }
}

impl Auto {
    /// The library's configuration.
    pub fn config(&self) -> StartConfig {
        StartConfig {
            pick: self.pick.map(|(x, y)| [x, y]),
            roi: self.roi.map(|(a, b, c, d)| [a, b, c, d]),
        }
    }
}

/// What `init=` asks for.
pub enum InitArg {
    /// A given curve.
    Curve(InitialCurve),
    /// The automatic start.
    Auto(StartConfig),
}

/// `init=`: a `Circle`, `Segment`, `Polyline`, `Auto`, `None` (automatic),
/// or the command line's text `"circle:CX,CY,R"` / `"segment:X0,Y0,X1,Y1"`.
pub fn init_from_py(obj: Option<&Bound<'_, PyAny>>) -> PyResult<InitArg> {
    let Some(obj) = obj else {
        return Ok(InitArg::Auto(StartConfig::default()));
    };
    if let Ok(c) = obj.cast::<Circle>() {
        let c = c.get();
        return Ok(InitArg::Curve(InitialCurve::Circle {
            cx: c.cx,
            cy: c.cy,
            r: c.r,
        }));
    }
    if let Ok(s) = obj.cast::<Segment>() {
        let s = s.get();
        return Ok(InitArg::Curve(InitialCurve::Segment {
            x0: s.x0,
            y0: s.y0,
            x1: s.x1,
            y1: s.y1,
        }));
    }
    if let Ok(p) = obj.cast::<Polyline>() {
        let p = p.get();
        return Ok(InitArg::Curve(InitialCurve::Polyline {
            points: p.points.clone(),
            closed: p.closed,
        }));
    }
    if let Ok(a) = obj.cast::<Auto>() {
        return Ok(InitArg::Auto(a.get().config()));
    }
    if let Ok(text) = obj.extract::<String>() {
        return text
            .parse::<InitialCurve>()
            .map(InitArg::Curve)
            .map_err(crate::errors::to_py_err);
    }
    Err(PyTypeError::new_err(format!(
        "init: expected vicurve.Circle, vicurve.Segment, vicurve.Polyline, vicurve.Auto, None or \"circle:CX,CY,R\", got {}",
        type_name(obj)
    )))
}

/// A library starting curve as the Python object that describes it.
pub fn init_to_py<'py>(py: Python<'py>, init: &InitialCurve) -> PyResult<Bound<'py, PyAny>> {
    Ok(match init {
        InitialCurve::Circle { cx, cy, r } => Bound::new(
            py,
            Circle {
                cx: *cx,
                cy: *cy,
                r: *r,
            },
        )?
        .into_any(),
        InitialCurve::Segment { x0, y0, x1, y1 } => Bound::new(
            py,
            Segment {
                x0: *x0,
                y0: *y0,
                x1: *x1,
                y1: *y1,
            },
        )?
        .into_any(),
        InitialCurve::Polyline { points, closed } => {
            Bound::new(py, Polyline::from_vertices(points.clone(), *closed))?.into_any()
        }
    })
}

/// The rows `[x, y]` of an N x 2 array.
pub fn rows_xy(
    what: &str,
    array: &PyArrayLike2<'_, f64, AllowTypeChange>,
) -> PyResult<Vec<[f64; 2]>> {
    let shape = array.shape();
    if shape[1] != 2 {
        return Err(value_error(format!(
            "{what}: expected an N x 2 array of (x, y), got shape {shape:?}"
        )));
    }
    let view = array.as_array();
    Ok(view.rows().into_iter().map(|r| [r[0], r[1]]).collect())
}

/// Points as an N x 2 float64 array.
pub fn xy_array<'py>(py: Python<'py>, points: &[[f64; 2]]) -> Bound<'py, PyArray2<f64>> {
    let flat: Vec<f64> = points.iter().flat_map(|p| [p[0], p[1]]).collect();
    // N x 2 from N * 2 values: the shape always matches.
    Array2::from_shape_vec((points.len(), 2), flat)
        .unwrap_or_else(|_| Array2::zeros((0, 2)))
        .into_pyarray(py)
}
