//! Multi-page TIFF stacks (as ImageJ, Micro-Manager and camera software
//! write them), read one page at a time.
//!
//! [`TiffStack::open`] walks the chain of image directories once (a few
//! hundred bytes per page, no pixel data) to count the pages and remember
//! where each is; [`TiffStack::read_page`] then decodes one page, so that a
//! sequence of thousands of frames never sits in memory. Gray levels are
//! those of [`super::load_image`]: 8-bit samples divided by 255, 16-bit ones
//! by 65535, floating-point ones kept as they are, colour pages as luma of
//! the stored values.
//!
//! A truncated stack (its chain of directories broken after some page)
//! opens with the pages before the break; [`TiffStack::broken`] says why
//! the chain stops, and reading the page after the last one fails with that
//! reason, so that a sequence records the loss.
//!
//! A stack whose pages have different sizes is read as it is (each page is
//! its own image). ImageJ's files of more than 4 GB keep a single directory
//! and store the other frames raw after it: they are read as one page.

use std::fs::File;
use std::io::BufReader;
use std::path::{Path, PathBuf};
use std::sync::Mutex;

use tiff::decoder::{Decoder, DecodingResult};
use tiff::TiffError;

use super::{decode_error, gray_values, read_file_error, SUPPORTED};
use crate::error::{Error, Result};
use crate::image::Image;

/// An open multi-page TIFF file. `Sync`: pages can be read from any thread
/// (one at a time; the decoder is behind a lock).
pub struct TiffStack {
    path: PathBuf,
    pages: usize,
    broken: Option<String>,
    decoder: Mutex<Decoder<BufReader<File>>>,
}

impl std::fmt::Debug for TiffStack {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        f.debug_struct("TiffStack")
            .field("path", &self.path)
            .field("pages", &self.pages)
            .finish()
    }
}

impl TiffStack {
    /// Open `path` and count its pages (those before a break in the chain
    /// of directories: see [`TiffStack::broken`]).
    ///
    /// Errors: [`Error::NotFound`], [`Error::Io`]; [`Error::UnsupportedImage`]
    /// when the file is not a TIFF; [`Error::Decode`] when its header or
    /// first directory is damaged or lies beyond the end of the file.
    pub fn open(path: &Path) -> Result<TiffStack> {
        let file = File::open(path).map_err(|e| read_file_error(path, e))?;
        let mut reader = BufReader::new(file);
        let mut magic = [0u8; 4];
        let is_tiff = std::io::Read::read_exact(&mut reader, &mut magic).is_ok()
            && matches!(&magic, b"II*\0" | b"MM\0*" | b"II+\0" | b"MM\0+");
        if !is_tiff {
            return Err(Error::UnsupportedImage {
                path: path.to_path_buf(),
                reason: "not a TIFF file (a stack of frames must be a multi-page TIFF)".into(),
            });
        }
        std::io::Seek::rewind(&mut reader).map_err(|e| read_file_error(path, e))?;
        let mut decoder = Decoder::new(reader).map_err(|e| tiff_error(path, 0, e))?;
        let mut pages = 1;
        let mut broken = None;
        while decoder.more_images() {
            if let Err(e) = decoder.next_image() {
                broken = Some(match tiff_error(path, pages, e) {
                    Error::Decode { reason, .. } | Error::UnsupportedImage { reason, .. } => reason,
                    other => other.to_string(),
                });
                break;
            }
            pages += 1;
        }
        Ok(TiffStack {
            path: path.to_path_buf(),
            pages,
            broken,
            decoder: Mutex::new(decoder),
        })
    }

    /// The file.
    pub fn path(&self) -> &Path {
        &self.path
    }

    /// Why the chain of directories stops after [`TiffStack::len`] pages
    /// when it does so early (a truncated or damaged file): page `len()`
    /// is then missing, `None` when the file ends where it should.
    pub fn broken(&self) -> Option<&str> {
        self.broken.as_deref()
    }

    /// The number of pages that can be read (at least 1).
    pub fn len(&self) -> usize {
        self.pages
    }

    /// Never: a TIFF file has at least one page. (For `len`'s sake.)
    pub fn is_empty(&self) -> bool {
        self.pages == 0
    }

    /// Decode page `index` (from 0).
    ///
    /// Errors: [`Error::InvalidParameter`] for an index past the last page;
    /// [`Error::Decode`] for the page after the last one of a broken chain
    /// ([`TiffStack::broken`]);
    /// [`Error::Decode`] for a damaged or truncated page;
    /// [`Error::UnsupportedImage`] for a layout not read (palette, CMYK,
    /// YCbCr, signed integers, more than 4 samples per pixel, too large);
    /// [`Error::EmptyImage`]; [`Error::NonFinite`] for a NaN or infinite
    /// floating-point sample. A failed page leaves the others readable.
    pub fn read_page(&self, index: usize) -> Result<Image> {
        if let (true, Some(reason)) = (index == self.pages, &self.broken) {
            return Err(decode_error(&self.path, reason.clone()));
        }
        if index >= self.pages {
            return Err(Error::invalid(
                "page",
                format!(
                    "page {index} of {}, which has {} page(s) (numbered from 0)",
                    self.path.display(),
                    self.pages
                ),
            ));
        }
        let mut decoder = self.decoder.lock().unwrap_or_else(|e| e.into_inner());
        let error = |e| tiff_error(&self.path, index, e);
        decoder.seek_to_image(index).map_err(error)?;
        let channels = match decoder.colortype().map_err(error)? {
            tiff::ColorType::Gray(_) => 1,
            tiff::ColorType::GrayA(_) => 2,
            tiff::ColorType::RGB(_) => 3,
            tiff::ColorType::RGBA(_) => 4,
            other => {
                return Err(self.unsupported(index, format!("pixel layout {other:?}")));
            }
        };
        let (width, height) = decoder.dimensions().map_err(error)?;
        let (width, height) = (width as usize, height as usize);
        if width == 0 || height == 0 {
            return Err(Error::EmptyImage { width, height });
        }
        let (data, finite) = match decoder.read_image().map_err(error)? {
            DecodingResult::U8(v) => (gray_values(&v, channels, 255.0), true),
            DecodingResult::U16(v) => (gray_values(&v, channels, 65535.0), true),
            DecodingResult::U32(v) => (gray_values(&v, channels, f64::from(u32::MAX)), true),
            DecodingResult::F32(v) => (gray_values(&v, channels, 1.0), false),
            DecodingResult::F64(v) => (gray_values(&v, channels, 1.0), false),
            _ => {
                return Err(self.unsupported(index, "signed or 64-bit integer samples".into()));
            }
        };
        drop(decoder);
        if data.len() != width * height {
            return Err(decode_error(
                &self.path,
                format!(
                    "page {index}: {} pixels for a {width}x{height} image",
                    data.len()
                ),
            ));
        }
        if finite {
            return Image::new_finite(width, height, data);
        }
        Image::new(width, height, data).map_err(|e| match e {
            Error::NonFinite { what } => Error::NonFinite {
                what: format!("{}, page {index}: {what}", self.path.display()),
            },
            other => other,
        })
    }

    fn unsupported(&self, index: usize, what: String) -> Error {
        Error::UnsupportedImage {
            path: self.path.clone(),
            reason: format!("page {index}: {what}; {SUPPORTED}"),
        }
    }
}

/// The number of pages of a TIFF file (see [`TiffStack::open`] for the
/// errors).
pub fn page_count(path: &Path) -> Result<usize> {
    TiffStack::open(path).map(|s| s.len())
}

/// The TIFF decoder's failures for page `index`, sorted as
/// [`super::load_image`] sorts them.
fn tiff_error(path: &Path, index: usize, e: TiffError) -> Error {
    match e {
        TiffError::UnsupportedError(u) => Error::UnsupportedImage {
            path: path.to_path_buf(),
            reason: format!("page {index}: {u}; {SUPPORTED}"),
        },
        TiffError::LimitsExceeded => Error::UnsupportedImage {
            path: path.to_path_buf(),
            reason: format!("page {index} is too large to decode"),
        },
        TiffError::IoError(e) => decode_error(
            path,
            format!("page {index}: the data end too early (truncated file?): {e}"),
        ),
        other => decode_error(path, format!("page {index}: {other}")),
    }
}
