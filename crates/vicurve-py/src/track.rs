//! `vicurve.track`: one curve through a sequence of frames, each started
//! from the previous frame's result, by the library's sequence step
//! ([`vicurve::sequence::CurveTracker`], the one `vicurve track` runs), as
//! an iterator: one frame is read, measured (with the GIL released) and
//! yielded at a time, so that a sequence of any length never sits in
//! memory.
//!
//! Frames: a 3-D array (T, H, W), any iterable of 2-D arrays or paths
//! (read when their turn comes), a glob pattern (sorted by name), or the
//! path of a multi-page TIFF (its pages, `STEM_0000` the first, as `vicurve
//! track` names them).

use crate::curves::{init_from_py, InitArg};
use crate::errors::{to_py_err, value_error};
use crate::functions::{count, stages_from_py};
use crate::image_arg::ImageArg;
use crate::result::PyMeasurement;
use numpy::IntoPyArray;
use pyo3::exceptions::PyStopIteration;
use pyo3::prelude::*;
use pyo3::types::PyDict;
use std::path::{Path, PathBuf};
use vicurve::fit::{FitConfig, Outcome};
use vicurve::io::TiffStack;
use vicurve::sequence::{tracked_config, CurveTracker};

/// Where the frames come from.
enum Source {
    /// A Python iterator of 2-D arrays or paths.
    Items(Py<PyAny>),
    /// The pages of a multi-page TIFF, and the stem naming them.
    Stack(Box<TiffStack>, String),
}

/// The per-frame values of the summary, in frame order.
#[derive(Default)]
struct Summary {
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

/// One frame of `vicurve.track`: `index` (from 0), `name` (the file stem,
/// `STEM_KKKK` for page K of a stack, `frame_KKKK` for an array), `input`
/// (the path, `PATH#K` for a page), `ok` (a curve to go on from: converged
/// or at its iteration limit), `outcome` ("converged", "iteration_limit",
/// "diverged" or "failed": nothing measured), `reason` (why it failed, or a
/// retry), `started_from` ("init" or the name of the frame the fit started
/// from) and `result` (a `vicurve.Result`, None when nothing was measured).
#[pyclass(module = "vicurve", name = "TrackedFrame", frozen, get_all)]
pub struct TrackedFrame {
    index: usize,
    name: String,
    input: String,
    ok: bool,
    outcome: String,
    reason: Option<String>,
    started_from: String,
    result: Option<Py<PyMeasurement>>,
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

/// The iterator `vicurve.track` returns; `summary()` gives the frames
/// yielded so far as a table.
#[pyclass(module = "vicurve", name = "Tracker")]
pub struct Tracker {
    source: Source,
    next: usize,
    total: Option<usize>,
    tracker: CurveTracker,
    summary: Summary,
    progress: Option<Py<PyAny>>,
}

impl Tracker {
    /// The next frame's image (or why it cannot be read), name and input;
    /// `None` at the end.
    #[allow(clippy::type_complexity)]
    fn read_next(
        &mut self,
        py: Python<'_>,
    ) -> PyResult<Option<(Result<vicurve::Image, String>, String, String)>> {
        let k = self.next;
        match &self.source {
            Source::Stack(stack, stem) => {
                let n = stack.len() + usize::from(stack.broken().is_some());
                if k >= n {
                    return Ok(None);
                }
                let digits = (n - 1).to_string().len().max(4);
                let image = py.detach(|| stack.read_page(k)).map_err(|e| e.to_string());
                let input = format!("{}#{k}", stack.path().display());
                Ok(Some((image, format!("{stem}_{k:0digits$}"), input)))
            }
            Source::Items(iter) => {
                let item = match iter.bind(py).call_method0("__next__") {
                    Ok(item) => item,
                    Err(e) if e.is_instance_of::<PyStopIteration>(py) => return Ok(None),
                    Err(e) => return Err(e),
                };
                match ImageArg::from_py(&item)? {
                    ImageArg::File(path) => {
                        let image = py
                            .detach(|| vicurve::io::load_image(&path))
                            .map_err(|e| e.to_string());
                        Ok(Some((image, file_stem(&path), path.display().to_string())))
                    }
                    ImageArg::Pixels(image, text) => {
                        Ok(Some((Ok(image), format!("frame_{k:04}"), text)))
                    }
                }
            }
        }
    }
}

#[pymethods]
impl Tracker {
    fn __iter__(slf: PyRef<'_, Self>) -> PyRef<'_, Self> {
        slf
    }

    fn __next__(&mut self, py: Python<'_>) -> PyResult<Option<TrackedFrame>> {
        let Some((image, name, input)) = self.read_next(py)? else {
            if let Some(bar) = self.progress.take() {
                bar.bind(py).call_method0("close")?;
            }
            return Ok(None);
        };
        let index = self.next;
        self.next += 1;
        let tracker = &mut self.tracker;
        let measured = match image {
            Ok(image) => {
                let size = (image.width(), image.height());
                Ok((py.detach(|| tracker.measure(&image, &name)), size))
            }
            Err(e) => Err(e),
        };
        let frame = match measured {
            Err(reason) => TrackedFrame {
                index,
                name,
                input,
                ok: false,
                outcome: "failed".into(),
                reason: Some(reason),
                started_from: String::new(),
                result: None,
            },
            Ok((t, size)) => {
                let step = t.step;
                let (outcome, result) = match step.measured {
                    Err(_) => ("failed".to_string(), None),
                    Ok(m) => {
                        let outcome = match m.outcome {
                            Outcome::Converged => "converged",
                            Outcome::IterationLimit => "iteration_limit",
                            Outcome::Diverged { .. } => "diverged",
                        };
                        let r = PyMeasurement {
                            measurement: m,
                            init: step.init,
                            config: step.config,
                            source: input.clone(),
                            size,
                            start: None,
                            grow: None,
                        };
                        (outcome.to_string(), Some(Py::new(py, r)?))
                    }
                };
                let reason = match (t.failure, step.note.is_empty()) {
                    (Some(f), _) => Some(f),
                    (None, false) => Some(step.note),
                    (None, true) => None,
                };
                TrackedFrame {
                    index,
                    name,
                    input,
                    ok: t.good.is_some(),
                    outcome,
                    reason,
                    started_from: step.started_from,
                    result,
                }
            }
        };
        self.record(py, &frame);
        if let Some(bar) = &self.progress {
            bar.bind(py).call_method1("update", (1,))?;
        }
        Ok(Some(frame))
    }

    /// The number of frames when known (an array, a list, a glob, a stack).
    fn __len__(&self) -> PyResult<usize> {
        self.total.ok_or_else(|| {
            pyo3::exceptions::PyTypeError::new_err("the number of frames is not known")
        })
    }

    /// The frames yielded so far, one row each: `frame`, `name`, `outcome`,
    /// `reason`, `started_from`, `iterations`, `residual` (RMS, gray
    /// levels), `length` and `area` (pixels; NaN for an open curve or a
    /// failed frame). A pandas DataFrame when pandas is installed (or
    /// `pandas=False` not given), else a dict of NumPy arrays.
    #[pyo3(signature = (pandas = true))]
    fn summary<'py>(&self, py: Python<'py>, pandas: bool) -> PyResult<Bound<'py, PyAny>> {
        let s = &self.summary;
        let d = PyDict::new(py);
        let np = py.import("numpy")?;
        let strings = |v: &Vec<String>| np.call_method1("array", (v.clone(),));
        d.set_item("frame", s.frame.clone().into_pyarray(py))?;
        d.set_item("name", strings(&s.name)?)?;
        d.set_item("outcome", strings(&s.outcome)?)?;
        d.set_item("reason", strings(&s.reason)?)?;
        d.set_item("started_from", strings(&s.started_from)?)?;
        d.set_item("iterations", s.iterations.clone().into_pyarray(py))?;
        d.set_item("residual", s.residual.clone().into_pyarray(py))?;
        d.set_item("length", s.length.clone().into_pyarray(py))?;
        d.set_item("area", s.area.clone().into_pyarray(py))?;
        if pandas {
            if let Ok(pd) = py.import("pandas") {
                return pd.call_method1("DataFrame", (d,));
            }
        }
        Ok(d.into_any())
    }
}

impl Tracker {
    fn record(&mut self, py: Python<'_>, f: &TrackedFrame) {
        let s = &mut self.summary;
        s.frame.push(f.index);
        s.name.push(f.name.clone());
        s.outcome.push(f.outcome.clone());
        s.reason.push(f.reason.clone().unwrap_or_default());
        s.started_from.push(f.started_from.clone());
        let m = f.result.as_ref().map(|r| &r.get().measurement);
        let _ = py;
        s.iterations
            .push(m.map_or(-1, |m| i64::try_from(m.iterations()).unwrap_or(i64::MAX)));
        s.residual.push(m.map_or(f64::NAN, |m| m.residual_rms()));
        s.length.push(m.map_or(f64::NAN, |m| m.length()));
        s.area.push(m.and_then(|m| m.area()).unwrap_or(f64::NAN));
    }
}

/// A file's stem, for a frame's name.
fn file_stem(path: &Path) -> String {
    path.file_stem()
        .map(|s| s.to_string_lossy().into_owned())
        .unwrap_or_default()
}

/// Whether a text is a glob pattern.
fn has_wildcard(s: &str) -> bool {
    s.contains(['*', '?', '['])
}

/// The frames argument as a source, and its length when known.
fn source_from_py(frames: &Bound<'_, PyAny>) -> PyResult<(Source, Option<usize>)> {
    let py = frames.py();
    let is_path =
        frames.is_instance_of::<pyo3::types::PyString>() || frames.hasattr("__fspath__")?;
    if is_path {
        let path: PathBuf = frames.extract()?;
        let text = path.display().to_string();
        if has_wildcard(&text) {
            let glob = py.import("glob")?;
            let list = glob.call_method1("glob", (text.clone(),))?;
            list.call_method0("sort")?;
            let n = list.len()?;
            if n == 0 {
                return Err(value_error(format!("frames: no file matches '{text}'")));
            }
            return Ok((Source::Items(list.try_iter()?.into_any().unbind()), Some(n)));
        }
        let stack = TiffStack::open(&path).map_err(to_py_err)?;
        let n = stack.len() + usize::from(stack.broken().is_some());
        return Ok((Source::Stack(Box::new(stack), file_stem(&path)), Some(n)));
    }
    let total = frames.len().ok();
    let iter = frames.try_iter().map_err(|_| {
        pyo3::exceptions::PyTypeError::new_err(
            "frames: expected a 3-D array (T, H, W), an iterable of 2-D arrays or paths, a glob pattern or a multi-page TIFF path",
        )
    })?;
    Ok((Source::Items(iter.into_any().unbind()), total))
}

/// Track a curve through a sequence of frames; returns an iterator that
/// yields one `TrackedFrame` per frame, as `vicurve track` measures them.
///
/// - `frames`: a 3-D array (T, H, W) (each frame scaled as `measure`
///   scales an array), an iterable of 2-D arrays or paths (read one at a
///   time), a glob pattern such as `"frames/*.png"` (sorted by name), or
///   the path of a TIFF file (its pages; a multi-page TIFF is read page by
///   page).
/// - `init`: the first frame's start (`Circle`, `Segment`, `Polyline` or
///   the command line's text); every other frame starts from the last good
///   result (`tracking=False`: every frame from `init`).
/// - `track_stages`: stages of the frames started from the previous result:
///   None (the first frame's; when those are the default schedule, a
///   silhouette's frames run the tracking schedule: the pixel-edge stage
///   alone from the previous frame's blur and elements), "default" or the
///   text "R:N,...".
/// - the other options as for `measure`.
/// - `progress`: a progress bar (tqdm, when it is installed).
///
/// A frame that cannot be read or measured is yielded with `ok=False` and
/// its reason, and the next frame starts from the last good one. The fits
/// run with the GIL released.
#[pyfunction]
#[pyo3(signature = (
    frames, init, *, kind = "silhouette", stages = None, track_stages = None, tracking = true,
    degree = 3, polarity = "auto", interpolation = "cubic", tolerance = 1e-4,
    max_iterations = 200, blur_correction = true, levels = "varying", progress = true
))]
#[allow(clippy::too_many_arguments)]
pub fn track(
    frames: &Bound<'_, PyAny>,
    init: &Bound<'_, PyAny>,
    kind: &str,
    stages: Option<&Bound<'_, PyAny>>,
    track_stages: Option<&str>,
    tracking: bool,
    degree: i64,
    polarity: &str,
    interpolation: &str,
    tolerance: f64,
    max_iterations: i64,
    blur_correction: bool,
    levels: &str,
    progress: bool,
) -> PyResult<Tracker> {
    let first = FitConfig {
        kind: kind.parse().map_err(to_py_err)?,
        polarity: polarity.parse().map_err(to_py_err)?,
        degree: count("degree", degree)?,
        stages: stages_from_py(stages)?,
        interpolation: interpolation.parse().map_err(to_py_err)?,
        tolerance,
        max_iterations: count("max_iterations", max_iterations)?,
        blur_correction,
        levels: levels.parse().map_err(to_py_err)?,
        ..FitConfig::default()
    };
    first.validate().map_err(to_py_err)?;
    let (tracked, schedule) = tracked_config(&first, track_stages).map_err(to_py_err)?;
    let InitArg::Curve(init) = init_from_py(Some(init))? else {
        return Err(value_error(
            "init: vicurve.track needs a starting curve (Circle, Segment, Polyline or \"circle:CX,CY,R\")",
        ));
    };
    let (source, total) = source_from_py(frames)?;
    let py = frames.py();
    let progress = if progress {
        py.import("tqdm")
            .and_then(|t| {
                let kw = PyDict::new(py);
                kw.set_item("total", total)?;
                kw.set_item("unit", "frame")?;
                t.getattr("tqdm")?.call((), Some(&kw))
            })
            .ok()
            .map(Bound::unbind)
    } else {
        None
    };
    Ok(Tracker {
        source,
        next: 0,
        total,
        tracker: CurveTracker::new(init, first, tracked, schedule, tracking),
        summary: Summary::default(),
        progress,
    })
}
