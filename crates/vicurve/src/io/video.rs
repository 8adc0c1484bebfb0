//! Video files, frame by frame, decoded by the `ffmpeg` program (FFmpeg,
//! found on `PATH`): the library links no video decoder, and FFmpeg reads
//! every common container and codec.
//!
//! [`VideoReader::open`] asks `ffprobe` for the first video stream's size
//! and its number of frames (its packets counted, which reads the file
//! without decoding it). Frames are then decoded in order by one `ffmpeg`
//! process writing raw 16-bit gray frames (`gray16le`) to a pipe: gray
//! levels are the frame's luma divided by 65535, so that an 8-bit video
//! gives the levels of the same frames as 8-bit PNG files (FFmpeg widens
//! `v` to `257 v`). Reading a frame before the last one read starts the
//! decoder again; reading ahead decodes and drops the frames between.
//! Lossy codecs change the pixels: measure from lossless ones (FFV1,
//! PNG-in-MKV, raw video) when accuracy matters.

use crate::error::{Error, Result};
use crate::image::Image;
use std::io::Read;
use std::path::{Path, PathBuf};
use std::process::{Child, ChildStdout, Command, Stdio};
use std::sync::Mutex;

/// What to do when the FFmpeg programs are missing.
const INSTALL: &str = "reading videos needs the ffmpeg and ffprobe programs on PATH (install FFmpeg: https://ffmpeg.org/download.html), or convert the video to a multi-page TIFF or image files";

/// The extensions read as videos (case-insensitive).
pub const VIDEO_EXTENSIONS: [&str; 12] = [
    "mp4", "m4v", "mov", "mkv", "webm", "avi", "mpg", "mpeg", "wmv", "flv", "ogv", "mts",
];

/// Whether `path`'s extension is a video's ([`VIDEO_EXTENSIONS`]).
pub fn is_video_name(path: &Path) -> bool {
    path.extension()
        .and_then(|e| e.to_str())
        .is_some_and(|e| VIDEO_EXTENSIONS.iter().any(|v| e.eq_ignore_ascii_case(v)))
}

/// An open video: its size and frame count, and the decoder.
pub struct VideoReader {
    path: PathBuf,
    width: usize,
    height: usize,
    frames: usize,
    decoder: Mutex<Option<Decoder>>,
}

/// An `ffmpeg` process and the index of the next frame it writes.
struct Decoder {
    child: Child,
    out: ChildStdout,
    next: usize,
}

impl Drop for Decoder {
    fn drop(&mut self) {
        let _ = self.child.kill();
        let _ = self.child.wait();
    }
}

impl std::fmt::Debug for VideoReader {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        write!(
            f,
            "VideoReader({}, {}x{}, {} frames)",
            self.path.display(),
            self.width,
            self.height,
            self.frames
        )
    }
}

impl VideoReader {
    /// Open `path`: its first video stream's size and number of frames.
    ///
    /// Errors: [`Error::NotFound`]; [`Error::UnsupportedImage`] when
    /// `ffprobe` is missing or finds no video stream in the file.
    pub fn open(path: &Path) -> Result<VideoReader> {
        if !path.is_file() {
            return Err(Error::NotFound {
                path: path.to_path_buf(),
            });
        }
        let unsupported = |reason: String| Error::UnsupportedImage {
            path: path.to_path_buf(),
            reason,
        };
        let out = Command::new("ffprobe")
            .args(["-v", "error", "-select_streams", "v:0", "-count_packets"])
            .args(["-show_entries", "stream=width,height,nb_read_packets"])
            .args(["-of", "csv=p=0"])
            .arg(path)
            .stdin(Stdio::null())
            .output()
            .map_err(|e| unsupported(format!("{INSTALL} ({e})")))?;
        let text = String::from_utf8_lossy(&out.stdout);
        let fields: Vec<usize> = text
            .trim()
            .split(',')
            .filter_map(|f| f.trim().parse().ok())
            .collect();
        let [width, height, frames] = fields[..] else {
            let why = String::from_utf8_lossy(&out.stderr);
            let why = why.split_whitespace().collect::<Vec<_>>().join(" ");
            return Err(unsupported(format!(
                "ffprobe finds no video stream ({why})"
            )));
        };
        if width == 0 || height == 0 {
            return Err(Error::EmptyImage { width, height });
        }
        Ok(VideoReader {
            path: path.to_path_buf(),
            width,
            height,
            frames,
            decoder: Mutex::new(None),
        })
    }

    /// The file.
    pub fn path(&self) -> &Path {
        &self.path
    }

    /// The number of frames.
    pub fn len(&self) -> usize {
        self.frames
    }

    /// Whether the video has no frame.
    pub fn is_empty(&self) -> bool {
        self.frames == 0
    }

    /// Frame `index` (from 0) as gray levels in `[0, 1]`.
    ///
    /// Errors: [`Error::UnsupportedImage`] when `ffmpeg` cannot be started,
    /// [`Error::Decode`] when the video ends before the frame or the
    /// decoder fails, [`Error::InvalidParameter`] for an index past the end.
    pub fn read_frame(&self, index: usize) -> Result<Image> {
        if index >= self.frames {
            return Err(Error::invalid(
                "frame",
                format!("{index} (the video has {} frames)", self.frames),
            ));
        }
        let mut slot = self.decoder.lock().unwrap_or_else(|e| e.into_inner());
        if slot.as_ref().is_none_or(|d| d.next > index) {
            *slot = None;
            *slot = Some(self.start()?);
        }
        let Some(decoder) = slot.as_mut() else {
            return Err(self.decode_error(index, "no decoder".into()));
        };
        let mut bytes = vec![0u8; self.width * self.height * 2];
        while decoder.next <= index {
            if let Err(e) = decoder.out.read_exact(&mut bytes) {
                *slot = None;
                return Err(self.decode_error(index, format!("the video ended early ({e})")));
            }
            decoder.next += 1;
        }
        let data = bytes
            .chunks_exact(2)
            .map(|b| f64::from(u16::from_le_bytes([b[0], b[1]])) / 65535.0)
            .collect();
        Image::new(self.width, self.height, data)
    }

    /// A decoder writing every frame from the first.
    fn start(&self) -> Result<Decoder> {
        let mut child = Command::new("ffmpeg")
            .args(["-v", "error", "-nostdin", "-i"])
            .arg(&self.path)
            .args([
                "-map", "0:v:0", "-f", "rawvideo", "-pix_fmt", "gray16le", "-",
            ])
            .stdin(Stdio::null())
            .stdout(Stdio::piped())
            .stderr(Stdio::null())
            .spawn()
            .map_err(|e| Error::UnsupportedImage {
                path: self.path.clone(),
                reason: format!("{INSTALL} ({e})"),
            })?;
        let out = child
            .stdout
            .take()
            .ok_or_else(|| self.decode_error(0, "no pipe from ffmpeg".into()))?;
        Ok(Decoder {
            child,
            out,
            next: 0,
        })
    }

    fn decode_error(&self, index: usize, why: String) -> Error {
        Error::Decode {
            path: self.path.clone(),
            reason: format!("frame {index}: {why}"),
        }
    }
}
