//! The `frames` argument of `vicurve.track`: where the frames come from,
//! each frame's name and what its result file records as its input, and
//! its pixels, read when its turn comes.
//!
//! - a 3-D array (T, H, W) or any iterable of 2-D arrays or paths: taken
//!   from the iterator one at a time (never ahead of the frame measured);
//! - a glob pattern: the files sorted by name;
//! - the path of a TIFF: its pages (`STEM_0000` the first, recorded as
//!   `PATH#K`, as `vicurve track` names them);
//! - the path of a video (by its extension): its frames, named as a
//!   stack's pages, decoded by PyAV when it is installed
//!   (`vicurve._video`), else by FFmpeg's programs as `vicurve track`
//!   decodes them ([`vicurve::io::video`]).
//!
//! Files and pages can be decoded ahead (see [`Source::peek`]), so that
//! the next frame is decoded while one is measured.

use crate::errors::{to_py_err, value_error};
use crate::image_arg::ImageArg;
use pyo3::exceptions::{PyStopIteration, PyTypeError};
use pyo3::prelude::*;
use std::path::{Path, PathBuf};
use vicurve::io::video::{is_video_name, VideoReader};
use vicurve::io::TiffStack;
use vicurve::sequence::run::frames::Pages;
use vicurve::Image;

/// Where the frames come from.
pub enum Source {
    /// A Python iterator of 2-D arrays or paths.
    Items(Py<PyAny>),
    /// Files, in order.
    Paths(Vec<PathBuf>),
    /// The pages of a multi-page TIFF or the frames of a video read by
    /// FFmpeg, and the stem naming them.
    Stack(Box<Pages>, String),
    /// The frames of a video decoded by PyAV (an iterator of arrays), the
    /// stem naming them, the path and the number of frames.
    Video(Py<PyAny>, String, PathBuf, usize),
}

/// A frame's pixels, not yet read.
pub enum Pixels {
    /// Copied from an array (or why it could not be).
    Ready(Result<Image, String>),
    /// A file to decode.
    File(PathBuf),
    /// A page of the stack.
    Page(usize),
}

/// One frame: its name, its input as result files record it, its pixels.
pub struct Item {
    /// The file stem, `STEM_KKKK` for a page, `frame_KKKK` for an array.
    pub name: String,
    /// The path, `PATH#K` for a page, a description for an array.
    pub input: String,
    /// Its pixels.
    pub pixels: Pixels,
}

impl Source {
    /// Frame `k` (the next one): `None` after the last. Arrays are copied
    /// here (with the GIL); files and pages are read by [`Source::load`].
    pub fn next_item(&self, py: Python<'_>, k: usize) -> PyResult<Option<Item>> {
        match self {
            Source::Stack(..) | Source::Paths(_) => Ok(self.peek(k)),
            Source::Video(iter, stem, path, n) => {
                let item = match iter.bind(py).call_method0("__next__") {
                    Ok(item) => item,
                    Err(e) if e.is_instance_of::<PyStopIteration>(py) => return Ok(None),
                    Err(e) => return Err(e),
                };
                let pixels = match ImageArg::from_py(&item)? {
                    ImageArg::Pixels(image, _) => Ok(image),
                    ImageArg::File(p) => Err(format!("not a frame: {}", p.display())),
                };
                Ok(Some(Item {
                    name: page_name(stem, k, *n),
                    input: format!("{}#{k}", path.display()),
                    pixels: Pixels::Ready(pixels),
                }))
            }
            Source::Items(iter) => {
                let item = match iter.bind(py).call_method0("__next__") {
                    Ok(item) => item,
                    Err(e) if e.is_instance_of::<PyStopIteration>(py) => return Ok(None),
                    Err(e) => return Err(e),
                };
                Ok(Some(match ImageArg::from_py(&item)? {
                    ImageArg::File(path) => Item {
                        name: file_stem(&path),
                        input: path.display().to_string(),
                        pixels: Pixels::File(path),
                    },
                    ImageArg::Pixels(image, text) => Item {
                        name: format!("frame_{k:04}"),
                        input: text,
                        pixels: Pixels::Ready(Ok(image)),
                    },
                }))
            }
        }
    }

    /// Frame `k` of a list of files or a stack (which can be looked at
    /// ahead without the GIL); `None` past the end or for an iterator.
    pub fn peek(&self, k: usize) -> Option<Item> {
        match self {
            Source::Items(_) | Source::Video(..) => None,
            Source::Paths(paths) => paths.get(k).map(|path| Item {
                name: file_stem(path),
                input: path.display().to_string(),
                pixels: Pixels::File(path.clone()),
            }),
            Source::Stack(stack, stem) => {
                let n = stack.count();
                (k < n).then(|| Item {
                    name: page_name(stem, k, n),
                    input: format!("{}#{k}", stack_path(stack).display()),
                    pixels: Pixels::Page(k),
                })
            }
        }
    }

    /// Decode `pixels` (call without the GIL); the error as one line.
    pub fn load(&self, pixels: Pixels) -> Result<Image, String> {
        match (pixels, self) {
            (Pixels::Ready(image), _) => image,
            (Pixels::File(path), _) => vicurve::io::load_image(&path).map_err(|e| e.to_string()),
            (Pixels::Page(k), Source::Stack(stack, _)) => stack.read(k).map_err(|e| e.to_string()),
            (Pixels::Page(k), _) => Err(format!("page {k}: no stack")),
        }
    }
}

/// Frame `k` of `n` of a stack or video: `STEM_KKKK`, the index padded
/// to at least 4 digits and to those of the last, as `vicurve track`
/// names them.
fn page_name(stem: &str, k: usize, n: usize) -> String {
    let digits = n.saturating_sub(1).to_string().len().max(4);
    format!("{stem}_{k:0digits$}")
}

fn stack_path(pages: &Pages) -> &Path {
    match pages {
        Pages::Tiff(s) => s.path(),
        Pages::Video(v) => v.path(),
    }
}

/// A video's frames: PyAV's when it is installed, else FFmpeg's programs'.
fn video_source(py: Python<'_>, path: PathBuf) -> PyResult<(Source, Option<usize>)> {
    let stem = file_stem(&path);
    if !path.is_file() {
        return Err(to_py_err(vicurve::Error::NotFound { path }));
    }
    let opened = py
        .import("vicurve._video")?
        .call_method1("open_video", (path.clone(),))?;
    if !opened.is_none() {
        let (n, frames): (usize, Bound<'_, PyAny>) = opened.extract()?;
        return Ok((Source::Video(frames.unbind(), stem, path, n), Some(n)));
    }
    match VideoReader::open(&path) {
        Ok(v) => {
            let n = v.len();
            Ok((Source::Stack(Box::new(Pages::Video(v)), stem), Some(n)))
        }
        Err(vicurve::Error::UnsupportedImage { .. }) if which_missing() => {
            Err(pyo3::exceptions::PyImportError::new_err(format!(
                "{}: reading videos needs PyAV (pip install av), or FFmpeg's ffmpeg and ffprobe programs on PATH",
                path.display()
            )))
        }
        Err(e) => Err(to_py_err(e)),
    }
}

/// Whether `ffprobe` cannot be started (FFmpeg is not installed).
fn which_missing() -> bool {
    std::process::Command::new("ffprobe")
        .arg("-version")
        .stdout(std::process::Stdio::null())
        .stderr(std::process::Stdio::null())
        .status()
        .is_err()
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
pub fn source_from_py(frames: &Bound<'_, PyAny>) -> PyResult<(Source, Option<usize>)> {
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
            let paths: Vec<PathBuf> = list.extract()?;
            if paths.is_empty() {
                return Err(value_error(format!("frames: no file matches '{text}'")));
            }
            let n = paths.len();
            return Ok((Source::Paths(paths), Some(n)));
        }
        if is_video_name(&path) {
            return video_source(py, path);
        }
        let stack = Pages::Tiff(Box::new(TiffStack::open(&path).map_err(to_py_err)?));
        let n = stack.count();
        return Ok((Source::Stack(Box::new(stack), file_stem(&path)), Some(n)));
    }
    let total = frames.len().ok();
    let iter = frames.try_iter().map_err(|_| {
        PyTypeError::new_err(
            "frames: expected a 3-D array (T, H, W), an iterable of 2-D arrays or paths, a glob pattern or a multi-page TIFF path",
        )
    })?;
    Ok((Source::Items(iter.into_any().unbind()), total))
}
