//! The module's functions: `measure`, `synth`, `eval`, `basis_values`,
//! `interpolate`. Arguments are converted with the GIL held; the work runs
//! with it released (`Python::detach`), so other Python threads run
//! meanwhile.

use crate::args::{self, ElementsArg, ShapeName, SynthArgs};
use crate::curves::{init_from_py, rows_xy, InitArg};
use crate::errors::{to_py_err, value_error, FitError};
use crate::image_arg::{type_name, ImageArg};
use crate::json::serde_to_py;
use crate::result::PyMeasurement;
use numpy::ndarray::{Array2, ArrayD};
use numpy::{AllowTypeChange, IntoPyArray, PyArrayLike1, PyArrayLike2, PyArrayLikeDyn};
use numpy::{PyArray2, PyUntypedArrayMethods};
use pyo3::exceptions::{PyRuntimeWarning, PyTypeError};
use pyo3::prelude::*;
use pyo3::types::{PyDict, PyTuple};
use vicurve::fit::grow::GrowConfig;
use vicurve::fit::{FitConfig, Outcome, Stage};
use vicurve::interp::Sampler;
use vicurve::render::Truth;
use vicurve::spline::Basis;
use vicurve::truth::Kind;

/// A non-negative integer argument as `usize`.
pub(crate) fn count(name: &str, v: i64) -> PyResult<usize> {
    usize::try_from(v).map_err(|_| value_error(format!("invalid {name}: {v} (must be >= 0)")))
}

/// The fit's keywords that `measure` and `track` share, as Python gives
/// them (documented with `measure`).
pub(crate) struct FitOptions<'a, 'py> {
    pub kind: &'a str,
    pub stages: Option<&'a Bound<'py, PyAny>>,
    pub degree: i64,
    pub polarity: &'a str,
    pub interpolation: &'a str,
    pub tolerance: f64,
    pub max_iterations: i64,
    pub blur_correction: bool,
    pub levels: &'a str,
    pub tone: &'a str,
}

impl FitOptions<'_, '_> {
    /// The configuration they give (not yet validated: callers add their
    /// own options first).
    pub fn config(&self) -> PyResult<FitConfig> {
        Ok(FitConfig {
            kind: self.kind.parse().map_err(to_py_err)?,
            polarity: self.polarity.parse().map_err(to_py_err)?,
            degree: count("degree", self.degree)?,
            stages: stages_from_py(self.stages)?,
            interpolation: self.interpolation.parse().map_err(to_py_err)?,
            tolerance: self.tolerance,
            max_iterations: count("max_iterations", self.max_iterations)?,
            blur_correction: self.blur_correction,
            levels: self.levels.parse().map_err(to_py_err)?,
            tone: self.tone.parse().map_err(to_py_err)?,
            ..FitConfig::default()
        })
    }
}

/// `stages=`: None (the default schedule), the command line's text
/// `"20:25,10:50"`, or a sequence of `(R, elements)` pairs where elements
/// is a number of elements or the text `"40px"` / `"auto"`.
pub(crate) fn stages_from_py(obj: Option<&Bound<'_, PyAny>>) -> PyResult<Option<Vec<Stage>>> {
    let Some(obj) = obj else {
        return Ok(None);
    };
    if obj.is_none() {
        return Ok(None);
    }
    if let Ok(text) = obj.extract::<String>() {
        return vicurve::fit::parse_stages(&text)
            .map(Some)
            .map_err(to_py_err);
    }
    let malformed = |index: usize, got: String| {
        value_error(format!(
            "invalid stages: stage {index} is {got}; expected a pair (R, elements) such as (10, 25), (2, \"40px\") or (2, \"auto\")"
        ))
    };
    let items = obj.try_iter().map_err(|_| {
        value_error(format!(
            "invalid stages: expected a list of (R, elements) pairs or a text like \"20:25,10:50\", got {}",
            type_name(obj)
        ))
    })?;
    let mut out = Vec::new();
    for (index, item) in items.enumerate() {
        let item = item?;
        let repr = item
            .repr()
            .map(|r| r.to_string())
            .unwrap_or_else(|_| "?".into());
        let pair: Vec<Bound<'_, PyAny>> = match item.try_iter() {
            Ok(it) if !item.is_instance_of::<pyo3::types::PyString>() => {
                it.collect::<PyResult<_>>()?
            }
            _ => return Err(malformed(index, repr)),
        };
        let [r, n] = pair.as_slice() else {
            return Err(malformed(index, repr));
        };
        if r.is_instance_of::<pyo3::types::PyBool>() || n.is_instance_of::<pyo3::types::PyBool>() {
            return Err(malformed(index, repr));
        }
        let half_width: f64 = r.extract().map_err(|_| malformed(index, repr.clone()))?;
        let elements = if let Ok(text) = n.extract::<String>() {
            ElementsArg::Text(text)
        } else if n.is_instance_of::<pyo3::types::PyInt>() {
            ElementsArg::Count(n.extract().map_err(|_| malformed(index, repr.clone()))?)
        } else {
            return Err(malformed(index, repr));
        };
        out.push(args::stage(index, half_width, &elements).map_err(value_error)?);
    }
    Ok(Some(out))
}

/// Measure the curve in `image` starting from `init`; returns a `Result`.
///
/// - `image`: a 2-D array (uint8 divided by 255, uint16 by 65535, float32
///   or float64 as they are: the gray levels the same file gives the
///   command-line tool) or the path of a PNG, TIFF or JPEG file.
/// - `init`: `Circle(cx, cy, r)`, `Segment(x0, y0, x1, y1)`,
///   `Polyline(points, closed=False)`, `Auto(pick=None, roi=None)`, the
///   command line's text `"circle:CX,CY,R"` or `"segment:X0,Y0,X1,Y1"`,
///   or None: the automatic start (the main silhouette; silhouettes only).
///   It must cross or lie near the curve (within the first band).
/// - `kind`: "silhouette" (an edge) or "contour" (a thin line).
/// - `stages`: None (the default schedule: bands of 20, 10, 5 and 2 px,
///   the last choosing its element length, then a stage matched to the
///   edge's blur), a list of `(R, elements)` pairs (R the band half-width
///   in pixels; elements a count, `"40px"` for an element length or
///   `"auto"`), or the command line's text `"20:25,10:50,5:100"`.
/// - `degree`: of the B-splines, 1 to 5.
/// - `polarity`: "auto" (estimated), "positive" (bright inside, bright on
///   the left of an open curve's direction, a bright line) or "negative";
///   the command line's `bright-inside`, `dark-line`, ... are accepted.
/// - `interpolation`: "cubic" (cubic B-spline), "bilinear" or "keys".
/// - `tolerance`: convergence on the displacement update, pixels.
/// - `max_iterations`: per stage.
/// - `blur_correction`: estimate the blur and report the true boundary or
///   centre line; turn it off for images that are not blurred steps or
///   lines (such as `synth("paper-disc")`).
/// - `levels`: the virtual image's gray levels, "varying" (they follow
///   uneven light along the curve; kept only when they explain the image
///   better than noise would; elements of 128 px, or shorter where the
///   light changes faster), "varying:LEN" (elements of LEN px at most) or
///   "global" (one pair, the paper's).
/// - `tone`: how the gray levels relate to the light: "auto" (the tone
///   curve is estimated around a silhouette's edge and, when the image is
///   clearly not linear, such as an sRGB JPEG, the edge is measured again
///   in linear light; the result's `tone` and `tone_estimate`), "linear",
///   "srgb", or a gamma such as "2.2".
/// - `breaks`: arc lengths (pixels along the starting curve from its
///   start) where the curve may have a corner.
/// - `find_corners`: without `breaks`, look for corners (a polygon's
///   vertices: the curve turns sharply within a few pixels and hardly
///   beside) and measure again with breaks there; the result's
///   `corners_found` says where. False keeps the smooth measurement.
/// - `grow`: True to grow an open start (a `Segment` or open `Polyline` on
///   the curve) segment by segment until the image border, a closed loop or
///   the end of the edge; a number stops at that length (pixels). The
///   result's `grow` says why each end stopped.
///
/// With `init=None` or `vicurve.Auto(...)` and `kind="contour"`, the line
/// through `Auto(pick=(x, y))` is followed along its ridge (or valley) to
/// make the start.
///
/// Raises `FitError` (with the partial result in `.result`) when the fit
/// diverges, `ValueError` for bad arguments, images or curves,
/// `FileNotFoundError` for a missing file; warns (`RuntimeWarning`) when the
/// iteration limit is reached. The fit runs with the GIL released.
#[pyfunction]
#[pyo3(signature = (
    image, init = None, *, kind = "silhouette", stages = None, degree = 3,
    polarity = "auto", interpolation = "cubic", tolerance = 1e-4,
    max_iterations = 200, blur_correction = true, levels = "varying", breaks = None,
    grow = None, find_corners = true, tone = "auto"
))]
#[allow(clippy::too_many_arguments)]
pub fn measure(
    py: Python<'_>,
    image: &Bound<'_, PyAny>,
    init: Option<&Bound<'_, PyAny>>,
    kind: &str,
    stages: Option<&Bound<'_, PyAny>>,
    degree: i64,
    polarity: &str,
    interpolation: &str,
    tolerance: f64,
    max_iterations: i64,
    blur_correction: bool,
    levels: &str,
    breaks: Option<Vec<f64>>,
    grow: Option<&Bound<'_, PyAny>>,
    find_corners: bool,
    tone: &str,
) -> PyResult<PyMeasurement> {
    let grow = grow_from_py(grow)?;
    let mut config = FitOptions {
        kind,
        stages,
        degree,
        polarity,
        interpolation,
        tolerance,
        max_iterations,
        blur_correction,
        levels,
        tone,
    }
    .config()?;
    config.breaks = breaks.unwrap_or_default();
    config.find_corners = find_corners;
    config.validate().map_err(to_py_err)?;
    let init = init_from_py(init)?;
    let image = ImageArg::from_py(image)?;
    let run = py.detach(move || -> vicurve::Result<PyMeasurement> {
        let (image, source) = image.load()?;
        let (init, start) = match init {
            InitArg::Curve(c) => (c, None),
            InitArg::Auto(cfg) if config.kind == Kind::Contour => {
                (vicurve::start::ridge::find_line(&image, &cfg)?.curve, None)
            }
            InitArg::Auto(cfg) => {
                let found = vicurve::start::find_silhouette(&image, &cfg)?;
                (found.curve.clone(), Some(found))
            }
        };
        let (measurement, grow) = match grow {
            None => (vicurve::fit::measure(&image, &init, &config)?, None),
            Some(settings) => {
                let sampler = vicurve::interp::Sampler::new(&image, config.interpolation);
                let g = vicurve::fit::grow::grow(&sampler, init.to_curve()?, &config, &settings)?;
                (g.measurement, Some(g.report))
            }
        };
        Ok(PyMeasurement {
            measurement,
            init,
            config,
            source,
            size: (image.width(), image.height()),
            start,
            grow,
        })
    });
    let result = run.map_err(to_py_err)?;
    match result.measurement.outcome {
        Outcome::Converged => Ok(result),
        Outcome::IterationLimit => {
            let warning = py.get_type::<PyRuntimeWarning>();
            PyErr::warn(
                py,
                &warning,
                c"vicurve: the iteration limit was reached before convergence; raise max_iterations or start closer to the curve",
                1,
            )?;
            Ok(result)
        }
        Outcome::Diverged { divergence } => {
            let message = format!(
                "the fit diverged: {divergence}; start from a curve closer to the edge, or use a narrower band (stages)"
            );
            let err = FitError::new_err(message);
            err.value(py).setattr("result", Bound::new(py, result)?)?;
            Err(err)
        }
    }
}

/// `grow=`: None or False (no growth), True (until the border, a loop or
/// the end of the edge), or a length in pixels.
fn grow_from_py(obj: Option<&Bound<'_, PyAny>>) -> PyResult<Option<GrowConfig>> {
    let Some(obj) = obj else { return Ok(None) };
    if let Ok(flag) = obj.cast::<pyo3::types::PyBool>() {
        return Ok(flag.is_true().then(GrowConfig::default));
    }
    let length: f64 = obj
        .extract()
        .map_err(|_| value_error("grow: expected True, False, None or a length in pixels"))?;
    let settings = GrowConfig {
        max_length: Some(length),
        ..GrowConfig::default()
    };
    settings.validate().map_err(to_py_err)?;
    Ok(Some(settings))
}

/// Render a test image of exactly known geometry, as `vicurve synth`;
/// returns `(image, truth)`.
///
/// `shape` is "disc", "ellipse", "star", "sine-edge", "ring", "sine-line"
/// or "paper-disc" (the paper's 512 x 512 disc of radius 200, drawn with
/// the silhouette profile). Options (pixels, degrees; the command line's
/// defaults): `size=(width, height)`, `center=(x, y)` (image centre moved
/// by (0.3, -0.2)), `radius` (30 % of the smaller side), `axes=(a, b)`
/// (ellipse), `angle`, `amplitude` (star: relative; sine: pixels), `lobes`,
/// `phase`, `wavelength`, `y0`, `line` (full width of a line: a contour),
/// `profile` (draw with the virtual profile of this half-width instead of
/// exact pixel coverage), `blur` (Gaussian, sigma), `blur_y` (the blur
/// along the columns when it differs: `blur` is then along the rows; exact
/// coverage only), `noise` (standard
/// deviation as a fraction of the contrast), `seed`, `bits` (8: uint8, 16:
/// uint16, None: float64 without quantisation), `levels=(background,
/// foreground)` in [0, 1] (0.2, 0.8), `tone` (the tone curve that
/// encodes the light in the gray levels: "linear", "srgb" or a gamma such
/// as "2.2"; the noise is added after it), `shading` (uneven light
/// multiplying the levels before the tone curve: "GX,GY" a gradient, the
/// light changing by GX, a fraction, from the first column to the last
/// and by GY down the rows, "GX,GY,V" and vignetting, corners darker by
/// V; "even").
///
/// The image is a (height, width) array equal to the file the command line
/// writes; `truth` is the content of its truth file (the exact curve, the
/// kind, how the image was made), which `eval` takes.
#[pyfunction]
#[pyo3(signature = (
    shape, *, size = (512, 512), center = None, radius = None, axes = None,
    angle = 20.0, amplitude = None, lobes = 5, phase = 0.0, wavelength = None,
    y0 = None, line = None, profile = None, blur = 0.0, blur_y = None, noise = 0.0,
    seed = 1, bits = Some(8), levels = None, tone = "linear", shading = "even"
), text_signature = "(shape, *, size=(512, 512), center=None, radius=None, axes=None, angle=20.0, amplitude=None, lobes=5, phase=0.0, wavelength=None, y0=None, line=None, profile=None, blur=0.0, blur_y=None, noise=0.0, seed=1, bits=8, levels=None, tone='linear', shading='even')")]
#[allow(clippy::too_many_arguments)]
pub fn synth<'py>(
    py: Python<'py>,
    shape: &str,
    size: (i64, i64),
    center: Option<(f64, f64)>,
    radius: Option<f64>,
    axes: Option<(f64, f64)>,
    angle: f64,
    amplitude: Option<f64>,
    lobes: i64,
    phase: f64,
    wavelength: Option<f64>,
    y0: Option<f64>,
    line: Option<f64>,
    profile: Option<f64>,
    blur: f64,
    blur_y: Option<f64>,
    noise: f64,
    seed: i64,
    bits: Option<i64>,
    levels: Option<(f64, f64)>,
    tone: &str,
    shading: &str,
) -> PyResult<Bound<'py, PyTuple>> {
    let mut a = SynthArgs::new(ShapeName::parse(shape).map_err(value_error)?);
    a.size = size;
    a.center = center;
    a.radius = radius;
    a.axes = axes;
    a.angle = angle;
    a.amplitude = amplitude;
    a.lobes = u32::try_from(lobes)
        .map_err(|_| value_error(format!("invalid lobes: {lobes} (must be 1 to 10000)")))?;
    a.phase = phase;
    a.wavelength = wavelength;
    a.y0 = y0;
    a.line = line;
    a.profile = profile;
    a.blur = blur;
    a.blur_y = blur_y;
    a.noise = noise;
    a.levels = levels;
    a.tone = tone.parse().map_err(to_py_err)?;
    a.shading = shading.parse().map_err(to_py_err)?;
    a.seed = u64::try_from(seed)
        .map_err(|_| value_error(format!("invalid seed: {seed} (must be >= 0)")))?;
    a.bits = match bits {
        None => None,
        Some(b @ (8 | 16)) => Some(b as u8),
        Some(b) => {
            return Err(value_error(format!(
                "invalid bits: {b} (expected 8, 16 or None)"
            )))
        }
    };
    let spec = args::synth_spec(&a).map_err(to_py_err)?;
    let image = py
        .detach(|| vicurve::render::render(&spec))
        .map_err(to_py_err)?;
    let (w, h) = (image.width(), image.height());
    let data = image.data();
    let array = match spec.bits {
        Some(8) => Array2::from_shape_fn((h, w), |(i, j)| {
            args::quantised_sample(data[i * w + j], 255.0) as u8
        })
        .into_pyarray(py)
        .into_any(),
        Some(_) => Array2::from_shape_fn((h, w), |(i, j)| {
            args::quantised_sample(data[i * w + j], 65535.0) as u16
        })
        .into_pyarray(py)
        .into_any(),
        None => Array2::from_shape_fn((h, w), |(i, j)| data[i * w + j])
            .into_pyarray(py)
            .into_any(),
    };
    let truth = serde_to_py(py, &Truth::from_spec(&spec))?;
    PyTuple::new(py, [array, truth])
}

/// The truth argument of `eval`: a truth dict (as `synth` returns), a shape
/// dict (`{"shape": "circle", "cx": ..., ...}`) or the path of a truth file.
fn truth_from_py(obj: &Bound<'_, PyAny>) -> PyResult<Truth> {
    let py = obj.py();
    if obj.is_instance_of::<PyDict>() {
        let dict = obj.cast::<PyDict>()?;
        let is_shape = match dict.get_item("shape")? {
            Some(v) => v.is_instance_of::<pyo3::types::PyString>(),
            None => false,
        };
        let json = py.import("json")?;
        let text: String = if is_shape {
            let wrapped = PyDict::new(py);
            wrapped.set_item("shape", dict)?;
            wrapped.set_item("kind", "silhouette")?;
            json.call_method1("dumps", (wrapped,))?.extract()?
        } else {
            json.call_method1("dumps", (dict,))
                .map_err(|e| value_error(format!("truth: not JSON data: {e}")))?
                .extract()?
        };
        return Truth::from_json(&text, "truth").map_err(to_py_err);
    }
    if obj.is_instance_of::<pyo3::types::PyString>() || obj.hasattr("__fspath__")? {
        let path: std::path::PathBuf = obj.extract()?;
        return py.detach(|| Truth::load(&path)).map_err(to_py_err);
    }
    Err(PyTypeError::new_err(format!(
        "truth: expected a dict (as vicurve.synth returns) or the path of a truth file, got {}",
        type_name(obj)
    )))
}

/// Accuracy of measured points against the exact curve: a dict with
/// `points` (how many), `bias` (mean signed distance along the true
/// normal, positive outside), `scatter` (RMS about the mean), `rms`,
/// `max_abs` and `distances` (each point's signed distance), pixels.
#[pyfunction]
#[pyo3(name = "eval")]
pub fn evaluate<'py>(
    py: Python<'py>,
    points: PyArrayLike2<'py, f64, AllowTypeChange>,
    truth: &Bound<'py, PyAny>,
) -> PyResult<Bound<'py, PyDict>> {
    let pts = rows_xy("points", &points)?;
    let truth = truth_from_py(truth)?;
    let shape = truth.shape;
    let (stats, distances) = py
        .detach(|| {
            let stats = vicurve::truth::evaluate(&pts, &shape)?;
            let d: Vec<f64> = pts
                .iter()
                .map(|p| shape.signed_distance(p[0], p[1]))
                .collect();
            Ok::<_, vicurve::Error>((stats, d))
        })
        .map_err(to_py_err)?;
    let out = PyDict::new(py);
    out.set_item("points", stats.count)?;
    out.set_item("bias", stats.bias)?;
    out.set_item("scatter", stats.scatter)?;
    out.set_item("rms", stats.rms)?;
    out.set_item("max_abs", stats.max_abs)?;
    out.set_item("distances", distances.into_pyarray(py))?;
    Ok(out)
}

/// Values (or derivatives) of every function of a uniform B-spline basis
/// (`vicurve::spline::Basis`) at the parameters `s`: a len(s) x n_functions
/// float64 array (`n_elements + degree` functions for an open basis,
/// `n_elements` for a periodic one).
#[pyfunction]
#[pyo3(signature = (degree, n_elements, length, closed, s, derivative = 0))]
pub fn basis_values<'py>(
    py: Python<'py>,
    degree: i64,
    n_elements: i64,
    length: f64,
    closed: bool,
    s: PyArrayLike1<'py, f64, AllowTypeChange>,
    derivative: i64,
) -> PyResult<Bound<'py, PyArray2<f64>>> {
    let basis = Basis::new(
        count("degree", degree)?,
        count("n_elements", n_elements)?,
        length,
        closed,
    )
    .map_err(to_py_err)?;
    if !(0..=2).contains(&derivative) {
        return Err(value_error(format!(
            "invalid derivative: {derivative} (0, 1 or 2)"
        )));
    }
    let s: Vec<f64> = s.as_array().iter().copied().collect();
    let n = basis.n_functions();
    let p = basis.degree();
    let mut out = Array2::<f64>::zeros((s.len(), n));
    for (row, &u) in s.iter().enumerate() {
        let v = basis.eval_derivs(u);
        let values = match derivative {
            0 => &v.value,
            1 => &v.d1,
            _ => &v.d2,
        };
        for (k, val) in values.iter().enumerate().take(p + 1) {
            // Periodic bases with n_el = p + 1 reach the same function
            // twice on no element; still, accumulate.
            out[[row, basis.index(v.first, k)]] += val;
        }
    }
    Ok(out.into_pyarray(py))
}

/// Interpolate an image at points `(xs, ys)` (pixels, pixel centres at
/// integers) with the library's `Sampler`: values, and gradients when
/// asked, with the shape of `xs`; NaN outside `[0, width - 1] x [0, height
/// - 1]`.
#[pyfunction]
#[pyo3(signature = (image, xs, ys, kind = "cubic", gradient = false))]
pub fn interpolate<'py>(
    py: Python<'py>,
    image: &Bound<'py, PyAny>,
    xs: PyArrayLikeDyn<'py, f64, AllowTypeChange>,
    ys: PyArrayLikeDyn<'py, f64, AllowTypeChange>,
    kind: &str,
    gradient: bool,
) -> PyResult<Bound<'py, PyAny>> {
    let kind: vicurve::interp::Interpolation = kind.parse().map_err(to_py_err)?;
    if xs.shape() != ys.shape() {
        return Err(value_error(format!(
            "xs and ys must have the same shape, got {:?} and {:?}",
            xs.shape(),
            ys.shape()
        )));
    }
    let shape = xs.shape().to_vec();
    let x: Vec<f64> = xs.as_array().iter().copied().collect();
    let y: Vec<f64> = ys.as_array().iter().copied().collect();
    let image = ImageArg::from_py(image)?;
    let (v, gx, gy) = py
        .detach(move || -> vicurve::Result<_> {
            let (image, _) = image.load()?;
            let sampler = Sampler::new(&image, kind);
            let nan = (f64::NAN, [f64::NAN; 2]);
            let mut v = Vec::with_capacity(x.len());
            let (mut gx, mut gy) = (Vec::new(), Vec::new());
            for (&xi, &yi) in x.iter().zip(&y) {
                if gradient {
                    let (val, g) = sampler.value_gradient(xi, yi).unwrap_or(nan);
                    v.push(val);
                    gx.push(g[0]);
                    gy.push(g[1]);
                } else {
                    v.push(sampler.value(xi, yi).unwrap_or(f64::NAN));
                }
            }
            Ok((v, gx, gy))
        })
        .map_err(to_py_err)?;
    let shaped = |data: Vec<f64>| -> PyResult<Bound<'py, PyAny>> {
        let a = ArrayD::from_shape_vec(shape.clone(), data)
            .map_err(|e| value_error(format!("cannot shape the result: {e}")))?;
        Ok(a.into_pyarray(py).into_any())
    };
    if gradient {
        Ok(PyTuple::new(py, [shaped(v)?, shaped(gx)?, shaped(gy)?])?.into_any())
    } else {
        shaped(v)
    }
}
