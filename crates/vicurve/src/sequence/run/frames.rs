//! The frames of a sequence: image files, the pages of multi-page TIFF
//! stacks, and the frames of videos.
//!
//! A `.tif`/`.tiff` file of more than one page stands for its pages, in
//! order; page `K` of `stack.tif` is the frame `stack_KKKK` (the index from
//! 0, zero-padded to at least 4 digits, so that the names sort in order)
//! and is recorded in result files as `stack.tif#K`. Pages are decoded one
//! at a time from the open file when the frame is measured. A stack whose
//! chain of pages breaks early (a truncated file) has one more frame after
//! its last readable page, which fails with the reason.
//!
//! A video (by its name's extension, [`crate::io::video`]) stands for its
//! frames, named and recorded as a stack's pages are; FFmpeg decodes them
//! in order. A video that cannot be opened (FFmpeg missing, no video
//! stream) is an error naming what to do.

use crate::error::{Error, Result};
use crate::io::video::{is_video_name, VideoReader};
use crate::io::TiffStack;
use crate::Image;
use std::path::{Path, PathBuf};
use std::sync::Arc;

/// One frame: an image file or one page of a stack.
#[derive(Debug, Clone)]
pub struct Frame {
    /// The file.
    pub path: PathBuf,
    /// Names the frame's results (the file stem, or `STEM_KKKK` for a page).
    pub stem: String,
    /// The page, and the stack or video it is read from.
    pub page: Option<(usize, Arc<Pages>)>,
}

/// A file of several frames.
#[derive(Debug)]
pub enum Pages {
    /// A multi-page TIFF.
    Tiff(Box<TiffStack>),
    /// A video.
    Video(VideoReader),
}

impl Pages {
    /// Frame `k` of the file.
    ///
    /// Errors: the stack's or the video's.
    pub fn read(&self, k: usize) -> Result<Image> {
        match self {
            Pages::Tiff(s) => s.read_page(k),
            Pages::Video(v) => v.read_frame(k),
        }
    }

    /// The number of frames (a broken stack's missing page included).
    pub fn count(&self) -> usize {
        match self {
            Pages::Tiff(s) => pages(s),
            Pages::Video(v) => v.len(),
        }
    }
}

impl Frame {
    /// The frame as result files record it: the path, `PATH#K` for page
    /// `K` of a stack.
    pub fn input(&self) -> String {
        match &self.page {
            None => self.path.display().to_string(),
            Some((k, _)) => format!("{}#{k}", self.path.display()),
        }
    }

    /// Decode the frame (the error as the one line the summary records).
    pub fn decode(&self) -> std::result::Result<Image, String> {
        match &self.page {
            None => crate::io::load_image(&self.path),
            Some((k, pages)) => pages.read(*k),
        }
        .map_err(|e| e.to_string())
    }
}

/// The frames of `paths`, in order: each multi-page TIFF and each video
/// (by its name's extension) expanded into its frames. A TIFF that cannot
/// be opened stays one frame (its decoding fails when it is measured, and
/// is recorded).
///
/// Errors: a file with no usable name; a video that cannot be opened.
pub fn frames(paths: Vec<PathBuf>) -> Result<Vec<Frame>> {
    let mut out = Vec::with_capacity(paths.len());
    for path in paths {
        let stem = file_stem(&path)?;
        let multi = if is_video_name(&path) {
            Some(Pages::Video(VideoReader::open(&path)?))
        } else {
            is_tiff_name(&path)
                .then(|| TiffStack::open(&path).ok())
                .flatten()
                .filter(|s| pages(s) > 1)
                .map(|s| Pages::Tiff(Box::new(s)))
        };
        let Some(stack) = multi.filter(|p| p.count() > 0) else {
            out.push(Frame {
                path,
                stem,
                page: None,
            });
            continue;
        };
        let n = stack.count();
        let digits = (n - 1).to_string().len().max(4);
        let stack = Arc::new(stack);
        for k in 0..n {
            out.push(Frame {
                path: path.clone(),
                stem: format!("{stem}_{k:0digits$}"),
                page: Some((k, Arc::clone(&stack))),
            });
        }
    }
    Ok(out)
}

/// The frames of a stack: its pages, and the missing one of a broken chain.
fn pages(stack: &TiffStack) -> usize {
    stack.len() + usize::from(stack.broken().is_some())
}

fn is_tiff_name(path: &Path) -> bool {
    path.extension()
        .and_then(|e| e.to_str())
        .is_some_and(|e| e.eq_ignore_ascii_case("tif") || e.eq_ignore_ascii_case("tiff"))
}

/// A file's stem, which names its results.
fn file_stem(p: &Path) -> Result<String> {
    p.file_stem()
        .and_then(|s| s.to_str())
        .map(str::to_string)
        .ok_or_else(|| Error::job(format!("frame {}: no usable file name", p.display())))
}
