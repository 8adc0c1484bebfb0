//! `vicurve.track`: one curve through a sequence of frames, each started
//! from the previous frame's result, by the library's sequence step (the
//! one `vicurve track` runs), as an iterator: one frame is read, measured
//! (with the GIL released) and yielded at a time, so that a sequence of
//! any length never sits in memory. Files and stack pages are decoded one
//! frame ahead, while the frame before is measured.
//!
//! Without `out_dir` the curve is tracked in memory
//! ([`vicurve::sequence::CurveTracker`]); with it, by the library's job
//! runner ([`vicurve::sequence::run::SequenceRun`]), which writes the files
//! of `vicurve track --out-dir` and skips the frames an earlier run did.

use crate::curves::{init_from_py, InitArg};
use crate::errors::{to_py_err, value_error};
use crate::frames::{source_from_py, Item, Pixels, Source};
use crate::functions::FitOptions;
use crate::result::PyMeasurement;
use crate::tracked::{outcome_name, Summary, TrackedFrame};
use pyo3::prelude::*;
use pyo3::types::PyDict;
use std::path::PathBuf;
use vicurve::curve::InitialCurve;
use vicurve::fit::FitConfig;
use vicurve::sequence::run::frame::FrameOutput;
use vicurve::sequence::run::job::{CurveSpec, Job, JobOutputs};
use vicurve::sequence::run::summary::{cell, split_csv};
use vicurve::sequence::run::SequenceRun;
use vicurve::sequence::{tracked_config, CurveTracker};
use vicurve::Image;

/// How the frames are measured: in memory, or by the job runner with files.
enum Engine {
    Memory(Box<CurveTracker>),
    Files(Box<SequenceRun>),
}

/// The iterator `vicurve.track` returns; `summary()` gives the frames
/// yielded so far as a table.
#[pyclass(module = "vicurve", name = "Tracker")]
pub struct Tracker {
    source: Source,
    next: usize,
    total: Option<usize>,
    engine: Engine,
    /// The next frame, its pixels decoded ahead.
    ahead: Option<Item>,
    summary: Summary,
    progress: Option<Py<PyAny>>,
}

/// What measuring a frame gave, by engine.
enum Measured {
    Memory(Box<vicurve::sequence::TrackedFrame>, (usize, usize)),
    Files(FrameOutput, Option<(usize, usize)>),
}

impl Tracker {
    /// Decode and measure `item` (without the GIL), decoding the frame
    /// after it meanwhile when it is a file or page that will be measured.
    fn measure(&mut self, py: Python<'_>, item: Item) -> Measured {
        let k = self.next;
        let source = &self.source;
        let ahead = source.peek(k + 1).filter(|a| match &self.engine {
            Engine::Files(run) => !run.is_done(&a.name),
            Engine::Memory(_) => true,
        });
        let engine = &mut self.engine;
        let (name, input) = (item.name, item.input);
        let (measured, ahead) = py.detach(|| {
            rayon::join(
                || {
                    let image = source.load(item.pixels);
                    measure_one(engine, (&name, &input), image)
                },
                || {
                    ahead.map(|a| Item {
                        pixels: Pixels::Ready(source.load(a.pixels)),
                        ..a
                    })
                },
            )
        });
        self.ahead = ahead;
        measured
    }
}

/// Measure one decoded frame with `engine`.
fn measure_one(
    engine: &mut Engine,
    (name, input): (&str, &str),
    image: Result<Image, String>,
) -> Measured {
    match (engine, image) {
        (Engine::Memory(tracker), Ok(image)) => {
            let size = (image.width(), image.height());
            Measured::Memory(Box::new(tracker.measure(&image, name)), size)
        }
        (Engine::Memory(_), Err(e)) => Measured::Files(failed_output(e), None),
        (Engine::Files(run), image) => {
            let size = image.as_ref().ok().map(|i| (i.width(), i.height()));
            match run.measure((name, input), image, None) {
                Ok(out) => Measured::Files(out, size),
                Err(e) => Measured::Files(failed_output(e.to_string()), None),
            }
        }
    }
}

/// A frame with nothing measured, and why.
fn failed_output(reason: String) -> FrameOutput {
    FrameOutput {
        steps: Vec::new(),
        rows: Vec::new(),
        good: vec![None],
        states: vec![None],
        bands: vec![None],
        problems: vec![reason],
    }
}

#[pymethods]
impl Tracker {
    fn __iter__(slf: PyRef<'_, Self>) -> PyRef<'_, Self> {
        slf
    }

    fn __next__(&mut self, py: Python<'_>) -> PyResult<Option<TrackedFrame>> {
        let k = self.next;
        let item = match self.ahead.take() {
            Some(item) => Some(item),
            None => self.source.next_item(py, k)?,
        };
        let Some(item) = item else {
            if let Some(bar) = self.progress.take() {
                bar.bind(py).call_method0("close")?;
            }
            return Ok(None);
        };
        let resumed = match &mut self.engine {
            Engine::Files(run) => run.resume(&item.name, &item.input).map_err(to_py_err)?,
            Engine::Memory(_) => None,
        };
        let frame = match resumed {
            Some(rows) => {
                let row = rows.first().cloned().unwrap_or_default();
                let frame = frame_from_row(k, item, &row);
                self.summary.record_row(&frame, &row);
                frame
            }
            None => {
                let (name, input) = (item.name.clone(), item.input.clone());
                let measured = self.measure(py, item);
                let frame = tracked_frame(py, (k, name, input), measured)?;
                self.summary.record(&frame);
                frame
            }
        };
        self.next += 1;
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
    /// failed frame; for a resumed frame as its summary row has them). A
    /// pandas DataFrame when pandas is installed (and `pandas=False` not
    /// given), else a dict of NumPy arrays.
    #[pyo3(signature = (pandas = true))]
    fn summary<'py>(&self, py: Python<'py>, pandas: bool) -> PyResult<Bound<'py, PyAny>> {
        self.summary.to_py(py, pandas)
    }
}

/// A frame done by an earlier run, from its summary row.
fn frame_from_row(index: usize, item: Item, row: &str) -> TrackedFrame {
    let cells = split_csv(row);
    let outcome = cell(&cells, "outcome").to_string();
    let reason = cell(&cells, "reason").to_string();
    TrackedFrame {
        index,
        name: item.name,
        input: item.input,
        ok: outcome == "converged" || outcome == "iteration_limit",
        outcome,
        reason: (!reason.is_empty()).then_some(reason),
        started_from: cell(&cells, "started_from").to_string(),
        result: None,
        resumed: true,
    }
}

/// The frame yielded for what measuring it gave.
fn tracked_frame(
    py: Python<'_>,
    (index, name, input): (usize, String, String),
    measured: Measured,
) -> PyResult<TrackedFrame> {
    let (step, ok, reason, size) = match measured {
        Measured::Memory(t, size) => {
            let t = *t;
            let reason = t.failure.or_else(|| Some(t.step.note.clone()));
            (Some(t.step), t.good.is_some(), reason, Some(size))
        }
        Measured::Files(mut out, size) => {
            let row = out.rows.first().map(|r| r.to_line()).unwrap_or_default();
            let reason = Some(cell(&split_csv(&row), "reason").to_string())
                .filter(|r| !r.is_empty())
                .or_else(|| out.problems.first().cloned());
            let ok = out.good.first().is_some_and(Option::is_some);
            let step = (!out.steps.is_empty()).then(|| out.steps.swap_remove(0));
            (step, ok, reason, size)
        }
    };
    let reason = reason.filter(|r| !r.is_empty());
    let Some(step) = step else {
        return Ok(failed_frame((index, name, input), reason));
    };
    let (outcome, result, reason) = match step.measured {
        Err(e) => ("failed".to_string(), None, reason.or(Some(e))),
        Ok(m) => {
            let outcome = outcome_name(&m).to_string();
            let r = PyMeasurement {
                measurement: m,
                init: step.init,
                config: step.config,
                source: input.clone(),
                size: size.unwrap_or_default(),
                start: None,
                grow: None,
            };
            (outcome, Some(Py::new(py, r)?), reason)
        }
    };
    Ok(TrackedFrame {
        index,
        name,
        input,
        ok,
        outcome,
        reason,
        started_from: step.started_from,
        result,
        resumed: false,
    })
}

/// A frame with nothing measured (unreadable, or no start).
fn failed_frame(
    (index, name, input): (usize, String, String),
    reason: Option<String>,
) -> TrackedFrame {
    TrackedFrame {
        index,
        name,
        input,
        ok: false,
        outcome: "failed".into(),
        reason,
        started_from: String::new(),
        result: None,
        resumed: false,
    }
}

/// The job `vicurve track FRAMES --init ... --out-dir DIR` runs, for the
/// curve `init` with `first` and `tracked` (the job's frames come from the
/// iterator, one at a time).
fn files_engine(
    out_dir: PathBuf,
    curve: (InitialCurve, FitConfig, FitConfig, bool),
    tracking: bool,
    force: bool,
) -> PyResult<Engine> {
    let (init, first, tracked, tracking_schedule) = curve;
    let job = Job {
        images: Vec::new(),
        out_dir,
        track: tracking,
        curves: vec![CurveSpec {
            name: "curve".into(),
            init,
            first,
            tracked,
            tracking_schedule,
        }],
        widths: Vec::new(),
        outputs: JobOutputs {
            points: true,
            overlay: None,
            plots: false,
        },
        shard: None,
    };
    let run = SequenceRun::start(job, force).map_err(to_py_err)?;
    Ok(Engine::Files(Box::new(run)))
}

/// A tqdm bar of `total` frames, when tqdm is installed and `progress`.
pub fn progress_bar(py: Python<'_>, progress: bool, total: Option<usize>) -> Option<Py<PyAny>> {
    if !progress {
        return None;
    }
    py.import("tqdm")
        .and_then(|t| {
            let kw = PyDict::new(py);
            kw.set_item("total", total)?;
            kw.set_item("unit", "frame")?;
            t.getattr("tqdm")?.call((), Some(&kw))
        })
        .ok()
        .map(Bound::unbind)
}

/// Track a curve through a sequence of frames; returns an iterator that
/// yields one `TrackedFrame` per frame, as `vicurve track` measures them.
///
/// - `frames`: a 3-D array (T, H, W) (each frame scaled as `measure`
///   scales an array), an iterable of 2-D arrays or paths (read one at a
///   time), a glob pattern such as `"frames/*.png"` (sorted by name), or
///   the path of a TIFF file (its pages; a multi-page TIFF is read page by
///   page), or the path of a video (`.mp4`, `.mkv`, `.avi`, ...: its
///   frames as 16-bit luma, named as a stack's pages, decoded by PyAV when
///   it is installed, `pip install av`, else by FFmpeg's `ffmpeg` and
///   `ffprobe` on PATH as `vicurve track` decodes them; lossy codecs change
///   the pixels).
/// - `init`: the first frame's start (`Circle`, `Segment`, `Polyline` or
///   the command line's text); every other frame starts from the last good
///   result (`tracking=False`: every frame from `init`).
/// - `track_stages`: stages of the frames started from the previous result:
///   None (the first frame's; when those are the default schedule, a
///   silhouette's frames run the tracking schedule: the pixel-edge stage
///   alone from the previous frame's blur and elements), "default" or the
///   text "R:N,...".
/// - the other options as for `measure`.
/// - `out_dir`: a folder for the files of `vicurve track --out-dir` (per
///   frame `NAME.json` and `NAME.csv`, `summary.csv`, `job.json`). A
///   frame already done there by an earlier run of the same job (the
///   command line's or this function's) is not measured again: it is
///   yielded with `resumed=True` (and `result=None`), and tracking goes on
///   from its curve as written, with the results of an uninterrupted run.
///   `force=True` measures every frame again.
/// - `progress`: a progress bar (tqdm, when it is installed).
///
/// A frame that cannot be read or measured is yielded with `ok=False` and
/// its reason, and the next frame starts from the last good one. The fits
/// run with the GIL released.
#[pyfunction]
#[pyo3(signature = (
    frames, init, *, kind = "silhouette", stages = None, track_stages = None, tracking = true,
    degree = 3, polarity = "auto", interpolation = "cubic", tolerance = 1e-4,
    max_iterations = 200, blur_correction = true, levels = "varying", out_dir = None,
    force = false, progress = true, tone = "auto"
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
    out_dir: Option<PathBuf>,
    force: bool,
    progress: bool,
    tone: &str,
) -> PyResult<Tracker> {
    let first = FitOptions {
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
    first.validate().map_err(to_py_err)?;
    let (tracked, schedule) = tracked_config(&first, track_stages).map_err(to_py_err)?;
    let InitArg::Curve(init) = init_from_py(Some(init))? else {
        return Err(value_error(
            "init: vicurve.track needs a starting curve (Circle, Segment, Polyline or \"circle:CX,CY,R\")",
        ));
    };
    let (source, total) = source_from_py(frames)?;
    let engine = match out_dir {
        Some(dir) => files_engine(dir, (init, first, tracked, schedule), tracking, force)?,
        None => Engine::Memory(Box::new(CurveTracker::new(
            init, first, tracked, schedule, tracking,
        ))),
    };
    Ok(Tracker {
        source,
        next: 0,
        total,
        engine,
        ahead: None,
        summary: Summary::default(),
        progress: progress_bar(frames.py(), progress, total),
    })
}
