//! Reading and writing image files and polylines.
//!
//! Images: PNG, TIFF and JPEG are read as grayscale [`Image`]s whose gray
//! levels are the stored sample values scaled to `[0, 1]` (8-bit divided by
//! 255, 16-bit by 65535) or, for floating-point TIFF, kept as they are. The
//! format is recognised from the file's first bytes, not from its name.
//!
//! Polylines: CSV text, one point `x,y` (pixels, x = column, y = row, see
//! [`crate::image`]) per row; see [`parse_polyline_csv`].
//!
//! Multi-page TIFF stacks, page by page: [`stack`]; videos, by FFmpeg:
//! [`video`]. Result files written whole or not at all: [`mod@write`].

pub mod stack;
pub mod video;
pub mod write;
pub use stack::{page_count, TiffStack};
pub use write::{sample_row, write_atomic, write_points_csv, SAMPLE_COLUMNS};

use std::fs::File;
use std::io::{BufWriter, Cursor, Write};
use std::path::Path;

use image::{DynamicImage, ImageBuffer, ImageError, ImageFormat, ImageReader, Luma};

use crate::error::{Error, Result};
use crate::image::Image;

/// Told to the user whenever a file is not something we read.
const SUPPORTED: &str = "vicurve reads PNG, TIFF and JPEG images (gray, gray+alpha, RGB or RGBA; \
8 or 16 bits per sample, or 32-bit float TIFF)";

/// Rec. 709 luma weights, applied to the stored (gamma-encoded) R, G, B.
const LUMA: [f64; 3] = [0.2126, 0.7152, 0.0722];

/// Read a PNG, TIFF or JPEG file as a grayscale image.
///
/// Gray levels: 8-bit samples are divided by 255 and 16-bit ones by 65535,
/// so they span `[0, 1]`; 32- and 64-bit floating-point gray TIFF (and
/// 32-bit float RGB TIFF) are kept as they are. Colour images become
/// `Y = 0.2126 R + 0.7152 G + 0.0722 B` computed on the *stored* values,
/// without gamma decoding: the measurement only needs a gray level that
/// grows monotonically with the brightness of the scene (it correlates
/// against a profile fitted to the image itself), so linearising would add
/// nothing but an assumption about the file's colour space. Alpha is
/// ignored (a gray+alpha image gives its gray channel). TIFF: the first page
/// only ([`TiffStack`] reads the others).
///
/// The format is recognised from the content (magic bytes), so a misnamed
/// file is still read and a non-image named `.png` is rejected.
///
/// Errors: [`Error::NotFound`] when the file does not exist; [`Error::Io`]
/// when it cannot be read; [`Error::UnsupportedImage`] when it is not a PNG,
/// TIFF or JPEG file, or its pixel layout is not one of the above (or it is
/// too large for the decoder's memory limits); [`Error::Decode`] when it is
/// one of those formats but damaged or truncated (including a JPEG whose
/// data stop before its end-of-image marker, which the decoder would
/// otherwise silently fill with gray); [`Error::EmptyImage`] for a 0-pixel
/// image; [`Error::NonFinite`] when a floating-point pixel is NaN or
/// infinite.
pub fn load_image(path: &Path) -> Result<Image> {
    let bytes = read_file(path)?;
    let format = detect_format(path, &bytes)?;
    if format == ImageFormat::Jpeg {
        check_jpeg_complete(&bytes).map_err(|reason| decode_error(path, reason))?;
    }
    if format == ImageFormat::Tiff {
        if let Some(image) = load_float_gray_tiff(path, &bytes)? {
            return Ok(image);
        }
    }
    let mut reader = ImageReader::new(Cursor::new(&bytes[..]));
    reader.set_format(format);
    let decoded = reader.decode().map_err(|e| map_decode_error(path, e))?;
    to_gray(path, decoded)
}

/// Save an image as an 8- or 16-bit grayscale PNG (`.png`) or TIFF (`.tif`,
/// `.tiff`), chosen by the file name's extension (case-insensitive).
///
/// Gray levels are clamped to `[0, 1]` and scaled to `0..=255` or
/// `0..=65535` with rounding to the nearest integer, so an image read by
/// [`load_image`] from a file of the same depth is written back exactly.
///
/// Errors: [`Error::InvalidParameter`] when `bits` is not 8 or 16, the
/// extension is not one of the above, or the image has more than `u32::MAX`
/// rows or columns; [`Error::Io`] when the file cannot be created or
/// written.
pub fn save_image(path: &Path, image: &Image, bits: u8) -> Result<()> {
    let extension = path
        .extension()
        .and_then(|e| e.to_str())
        .map(str::to_ascii_lowercase);
    let format = match extension.as_deref() {
        Some("png") => ImageFormat::Png,
        Some("tif" | "tiff") => ImageFormat::Tiff,
        _ => {
            return Err(Error::invalid(
                "output image",
                format!(
                    "{}: the file name must end in .png, .tif or .tiff",
                    path.display()
                ),
            ))
        }
    };
    let too_large = || {
        Error::invalid(
            "output image",
            format!(
                "{}x{} pixels is too large for an image file",
                image.width(),
                image.height()
            ),
        )
    };
    let width = u32::try_from(image.width()).map_err(|_| too_large())?;
    let height = u32::try_from(image.height()).map_err(|_| too_large())?;
    let encoded = match bits {
        8 => ImageBuffer::<Luma<u8>, _>::from_raw(width, height, quantize(image, 255.0))
            .map(DynamicImage::ImageLuma8),
        16 => ImageBuffer::<Luma<u16>, _>::from_raw(width, height, quantize(image, 65535.0))
            .map(DynamicImage::ImageLuma16),
        _ => {
            return Err(Error::invalid(
                "bits",
                format!("{bits} bits per sample; use 8 or 16"),
            ))
        }
    }
    .ok_or_else(too_large)?;

    let io_error = |source| Error::Io {
        path: path.to_path_buf(),
        source,
    };
    let mut out = BufWriter::new(File::create(path).map_err(io_error)?);
    encoded.write_to(&mut out, format).map_err(|e| match e {
        ImageError::IoError(source) => io_error(source),
        other => io_error(std::io::Error::other(other.to_string())),
    })?;
    out.flush().map_err(io_error)
}

/// Parse a polyline from CSV text: one point per row, `x` then `y` in pixels.
///
/// Accepted:
/// - separators: comma, semicolon, tab or runs of spaces (chosen per row,
///   in that order of preference); the decimal separator is always `.`;
/// - blank lines and lines whose first non-blank character is `#`: ignored;
/// - an optional header: the first remaining row is a header when one of
///   its fields is a non-empty non-number. If the header names columns `x`
///   and `y` (case-insensitive, quotes allowed), those columns are read and
///   other columns ignored, so files like `s,x,y,nx,ny` work; a header of
///   two other names means x then y; a header of more columns naming neither
///   is an error.
/// - Without a header every row must hold exactly two fields (trailing empty
///   fields are dropped), because guessing which two of several numbers are
///   `x` and `y` would silently measure garbage.
///
/// `what` names the input in error messages (a file name, an option).
///
/// Errors: [`Error::Parse`] with the 1-based line number for a row that is
/// not numbers, has the wrong number of fields, a header naming only one of
/// `x`/`y`, or text without any point (line 0); [`Error::NonFinite`] for a
/// NaN or infinite coordinate.
pub fn parse_polyline_csv(text: &str, what: &str) -> Result<Vec<[f64; 2]>> {
    let text = text.strip_prefix('\u{feff}').unwrap_or(text);
    let parse_error = |line: usize, reason: String| Error::Parse {
        what: what.to_string(),
        line,
        reason,
    };
    // Column indices of x and y, and whether a header chose them (then rows
    // may have more fields).
    let mut columns: Option<(usize, usize, bool)> = None;
    let mut points = Vec::new();
    for (index, raw) in text.lines().enumerate() {
        let line = index + 1;
        let row = raw.trim();
        if row.is_empty() || row.starts_with('#') {
            continue;
        }
        let fields = split_fields(row);
        let (ix, iy, from_header) = match columns {
            Some(c) => c,
            None => {
                let c = if fields
                    .iter()
                    .any(|f| !f.is_empty() && f.parse::<f64>().is_err())
                {
                    let c = header_columns(&fields).map_err(|r| parse_error(line, r))?;
                    columns = Some(c);
                    continue;
                } else {
                    (0, 1, false)
                };
                columns = Some(c);
                c
            }
        };
        if from_header {
            if fields.len() <= ix.max(iy) {
                return Err(parse_error(
                    line,
                    format!(
                        "{} field(s), but the header puts x in column {} and y in column {}",
                        fields.len(),
                        ix + 1,
                        iy + 1
                    ),
                ));
            }
        } else if fields.len() != 2 {
            return Err(parse_error(
                line,
                format!(
                    "expected 2 fields `x,y`, found {} (for more columns, add a header line naming the x and y columns)",
                    fields.len()
                ),
            ));
        }
        let mut point = [0.0; 2];
        for (k, (column, name)) in [(ix, "x"), (iy, "y")].into_iter().enumerate() {
            let field = fields[column];
            let value: f64 = field.parse().map_err(|_| {
                parse_error(
                    line,
                    format!("{name} (column {}) is not a number: `{field}`", column + 1),
                )
            })?;
            if !value.is_finite() {
                return Err(Error::NonFinite {
                    what: format!("{what}, line {line}, {name}"),
                });
            }
            point[k] = value;
        }
        points.push(point);
    }
    if points.is_empty() {
        return Err(parse_error(0, "no point (x,y row) found".to_string()));
    }
    Ok(points)
}

/// Read a polyline from a CSV file; the format is that of
/// [`parse_polyline_csv`], and errors name the file.
///
/// Errors: [`Error::NotFound`], [`Error::Io`], [`Error::Parse`] (also for a
/// file that is not UTF-8 text, with the line of the first bad byte),
/// [`Error::NonFinite`].
pub fn read_polyline_csv(path: &Path) -> Result<Vec<[f64; 2]>> {
    let bytes = read_file(path)?;
    let what = path.display().to_string();
    let text = std::str::from_utf8(&bytes).map_err(|e| {
        let line = 1 + bytes[..e.valid_up_to()]
            .iter()
            .filter(|&&b| b == b'\n')
            .count();
        Error::Parse {
            what: what.clone(),
            line,
            reason: "not UTF-8 text".to_string(),
        }
    })?;
    parse_polyline_csv(text, &what)
}

/// The whole file, with "missing" told apart from other failures.
fn read_file(path: &Path) -> Result<Vec<u8>> {
    std::fs::read(path).map_err(|source| read_file_error(path, source))
}

/// [`Error::NotFound`] or [`Error::Io`] for a file that cannot be read.
fn read_file_error(path: &Path, source: std::io::Error) -> Error {
    if source.kind() == std::io::ErrorKind::NotFound {
        Error::NotFound {
            path: path.to_path_buf(),
        }
    } else {
        Error::Io {
            path: path.to_path_buf(),
            source,
        }
    }
}

/// PNG, JPEG or TIFF (including BigTIFF) from the first bytes; anything
/// else is [`Error::UnsupportedImage`], naming the format when known.
fn detect_format(path: &Path, bytes: &[u8]) -> Result<ImageFormat> {
    const MAGIC: [(&[u8], ImageFormat); 6] = [
        (b"\x89PNG\r\n\x1a\n", ImageFormat::Png),
        (&[0xFF, 0xD8, 0xFF], ImageFormat::Jpeg),
        (b"II*\0", ImageFormat::Tiff),
        (b"MM\0*", ImageFormat::Tiff),
        (b"II+\0", ImageFormat::Tiff),
        (b"MM\0+", ImageFormat::Tiff),
    ];
    if let Some((_, format)) = MAGIC.iter().find(|(magic, _)| bytes.starts_with(magic)) {
        return Ok(*format);
    }
    let reason = if bytes.is_empty() {
        format!("the file is empty; {SUPPORTED}")
    } else if let Ok(other) = image::guess_format(bytes) {
        format!("{other:?} files are not supported; {SUPPORTED}")
    } else {
        format!("not a PNG, TIFF or JPEG file (content not recognised); {SUPPORTED}")
    };
    Err(Error::UnsupportedImage {
        path: path.to_path_buf(),
        reason,
    })
}

/// Walk the JPEG's marker segments from start-of-image to end-of-image.
///
/// The JPEG decoder is lenient: data cut short decode "successfully" with
/// the missing part filled in, which would be measured as if real. A file
/// is accepted only if its segments, and the entropy-coded data after each
/// start-of-scan, are complete up to an end-of-image marker. Segments are
/// skipped by their length, so a thumbnail inside an APP segment (with its
/// own end-of-image marker) is not mistaken for the main image's end.
fn check_jpeg_complete(bytes: &[u8]) -> std::result::Result<(), String> {
    const TRUNCATED: &str = "the JPEG data end before the end-of-image marker (truncated file?)";
    let n = bytes.len();
    if n < 2 || bytes[0] != 0xFF || bytes[1] != 0xD8 {
        return Err("no JPEG start-of-image marker".to_string());
    }
    let mut i = 2;
    loop {
        // Tolerate stray bytes between segments, as common decoders do, then
        // fill bytes (0xFF) before the marker code.
        while i < n && bytes[i] != 0xFF {
            i += 1;
        }
        while i < n && bytes[i] == 0xFF {
            i += 1;
        }
        let Some(&marker) = bytes.get(i) else {
            return Err(TRUNCATED.to_string());
        };
        i += 1;
        match marker {
            0xD9 => return Ok(()),
            // Markers without a length field.
            0x00 | 0x01 | 0xD0..=0xD8 => continue,
            _ => {}
        }
        if i + 2 > n {
            return Err(TRUNCATED.to_string());
        }
        let length = usize::from(u16::from_be_bytes([bytes[i], bytes[i + 1]]));
        if length < 2 {
            return Err(format!(
                "JPEG segment of impossible length {length} at byte {i}"
            ));
        }
        i += length;
        if i > n {
            return Err(TRUNCATED.to_string());
        }
        if marker == 0xDA {
            // Entropy-coded data: 0xFF is followed by 0x00 (stuffing), a
            // restart marker, or fill 0xFF; anything else is the next marker.
            loop {
                if i + 1 >= n {
                    return Err(TRUNCATED.to_string());
                }
                if bytes[i] == 0xFF {
                    match bytes[i + 1] {
                        0x00 | 0xD0..=0xD7 => i += 2,
                        0xFF => i += 1,
                        _ => break,
                    }
                } else {
                    i += 1;
                }
            }
        }
    }
}

/// Gray (and 16-bit gray) TIFF with 32- or 64-bit samples, which the `image`
/// crate does not read; `Ok(None)` leaves any other TIFF to it (including
/// ones this quick look cannot parse, so that its error message is used).
fn load_float_gray_tiff(path: &Path, bytes: &[u8]) -> Result<Option<Image>> {
    use tiff::decoder::{Decoder, DecodingResult};
    let Ok(mut decoder) = Decoder::new(Cursor::new(bytes)) else {
        return Ok(None);
    };
    let Ok(tiff::ColorType::Gray(32 | 64)) = decoder.colortype() else {
        return Ok(None);
    };
    let tiff_error = |e: tiff::TiffError| match e {
        tiff::TiffError::UnsupportedError(u) => Error::UnsupportedImage {
            path: path.to_path_buf(),
            reason: format!("{u}; {SUPPORTED}"),
        },
        tiff::TiffError::LimitsExceeded => Error::UnsupportedImage {
            path: path.to_path_buf(),
            reason: "the image is too large to decode".to_string(),
        },
        other => decode_error(path, other.to_string()),
    };
    let (width, height) = decoder.dimensions().map_err(tiff_error)?;
    let (width, height) = (width as usize, height as usize);
    if width == 0 || height == 0 {
        return Err(Error::EmptyImage { width, height });
    }
    let data: Vec<f64> = match decoder.read_image().map_err(tiff_error)? {
        DecodingResult::F32(v) => v.into_iter().map(f64::from).collect(),
        DecodingResult::F64(v) => v,
        DecodingResult::U32(v) => v
            .into_iter()
            .map(|s| f64::from(s) / f64::from(u32::MAX))
            .collect(),
        _ => {
            return Err(Error::UnsupportedImage {
                path: path.to_path_buf(),
                reason: format!("signed or 64-bit integer gray samples; {SUPPORTED}"),
            })
        }
    };
    if data.len() != width * height {
        return Err(decode_error(
            path,
            format!("{} samples for a {width}x{height} image", data.len()),
        ));
    }
    build_image(path, width, height, data).map(Some)
}

/// Gray levels of a decoded image; see [`load_image`] for the scaling.
fn to_gray(path: &Path, decoded: DynamicImage) -> Result<Image> {
    let (width, height) = (decoded.width() as usize, decoded.height() as usize);
    if width == 0 || height == 0 {
        return Err(Error::EmptyImage { width, height });
    }
    // Divisors, not reciprocal factors, so that `v / 255` is exactly what
    // a user computing it by hand gets (and 8-bit round trips are exact).
    const U8: f64 = 255.0;
    const U16: f64 = 65535.0;
    let data = match &decoded {
        // The 256 levels divided once (the same values, bit for bit).
        DynamicImage::ImageLuma8(b) => {
            let levels: [f64; 256] = std::array::from_fn(|k| k as f64 / U8);
            let raw = b.as_raw();
            crate::pages::collect(raw.len(), raw.iter().map(|&v| levels[usize::from(v)]))
        }
        DynamicImage::ImageLumaA8(b) => gray_values(b.as_raw(), 2, U8),
        DynamicImage::ImageRgb8(b) => gray_values(b.as_raw(), 3, U8),
        DynamicImage::ImageRgba8(b) => gray_values(b.as_raw(), 4, U8),
        DynamicImage::ImageLuma16(b) => gray_values(b.as_raw(), 1, U16),
        DynamicImage::ImageLumaA16(b) => gray_values(b.as_raw(), 2, U16),
        DynamicImage::ImageRgb16(b) => gray_values(b.as_raw(), 3, U16),
        DynamicImage::ImageRgba16(b) => gray_values(b.as_raw(), 4, U16),
        DynamicImage::ImageRgb32F(b) => {
            return build_image(path, width, height, gray_values(b.as_raw(), 3, 1.0))
        }
        DynamicImage::ImageRgba32F(b) => {
            return build_image(path, width, height, gray_values(b.as_raw(), 4, 1.0))
        }
        other => {
            return Err(Error::UnsupportedImage {
                path: path.to_path_buf(),
                reason: format!("pixel layout {:?}; {SUPPORTED}", other.color()),
            })
        }
    };
    // Integer levels: finite by construction.
    Image::new_finite(width, height, data)
}

/// One gray level per pixel of interleaved samples, divided by `divisor`:
/// the first channel of gray or gray+alpha pixels, the luma of the first
/// three of RGB(A) ones.
fn gray_values<T: Copy + Into<f64>>(samples: &[T], channels: usize, divisor: f64) -> Vec<f64> {
    let pixels = samples.chunks_exact(channels);
    crate::pages::collect(
        pixels.len(),
        pixels.map(|p| {
            let gray = if channels >= 3 {
                LUMA[0] * p[0].into() + LUMA[1] * p[1].into() + LUMA[2] * p[2].into()
            } else {
                p[0].into()
            };
            gray / divisor
        }),
    )
}

/// [`Image::new`], with the file named in a non-finite pixel's message.
fn build_image(path: &Path, width: usize, height: usize, data: Vec<f64>) -> Result<Image> {
    Image::new(width, height, data).map_err(|e| match e {
        Error::NonFinite { what } => Error::NonFinite {
            what: format!("{}: {what}", path.display()),
        },
        other => other,
    })
}

/// The decoder's failures, sorted into damaged vs. not supported. The file
/// is already in memory, so an I/O error here means the data ran out.
fn map_decode_error(path: &Path, error: ImageError) -> Error {
    match error {
        ImageError::Unsupported(e) => Error::UnsupportedImage {
            path: path.to_path_buf(),
            reason: format!("{e}; {SUPPORTED}"),
        },
        ImageError::Limits(e) => Error::UnsupportedImage {
            path: path.to_path_buf(),
            reason: format!("too large to decode: {e}"),
        },
        ImageError::IoError(e) => decode_error(
            path,
            format!("the data end too early (truncated file?): {e}"),
        ),
        other => decode_error(path, other.to_string()),
    }
}

fn decode_error(path: &Path, reason: impl Into<String>) -> Error {
    Error::Decode {
        path: path.to_path_buf(),
        reason: reason.into(),
    }
}

/// Gray levels clamped to `[0, 1]`, scaled to `0..=max` and rounded.
fn quantize<T: TryFrom<u32>>(image: &Image, max: f64) -> Vec<T> {
    image
        .data()
        .iter()
        .filter_map(|&v| {
            // NaN (only reachable through `data_mut`) becomes 0.
            let level = if v.is_nan() {
                0.0
            } else {
                v.clamp(0.0, 1.0) * max
            };
            T::try_from(level.round() as u32).ok()
        })
        .collect()
}

/// Split one CSV row into trimmed fields; see [`parse_polyline_csv`].
fn split_fields(row: &str) -> Vec<&str> {
    let mut fields: Vec<&str> =
        if let Some(sep) = [',', ';', '\t'].into_iter().find(|&c| row.contains(c)) {
            row.split(sep).map(str::trim).collect()
        } else {
            row.split_whitespace().collect()
        };
    while fields.len() > 1 && fields.last().is_some_and(|f| f.is_empty()) {
        fields.pop();
    }
    fields
}

/// Columns of x and y named by a header row, or the first two when it names
/// neither. The bool says the header chose them.
fn header_columns(fields: &[&str]) -> std::result::Result<(usize, usize, bool), String> {
    let find = |name: &str| {
        fields.iter().position(|f| {
            f.trim_matches(|c| c == '"' || c == '\'')
                .trim()
                .eq_ignore_ascii_case(name)
        })
    };
    match (find("x"), find("y")) {
        (Some(x), Some(y)) => Ok((x, y, true)),
        // Two unnamed columns can only be x then y; with more, guessing
        // would risk measuring the wrong numbers.
        (None, None) if fields.len() == 2 => Ok((0, 1, true)),
        (None, None) => Err(format!(
            "the header has {} columns but none is named `x` and `y`",
            fields.len()
        )),
        (Some(_), None) => Err("the header names a column `x` but no column `y`".to_string()),
        (None, Some(_)) => Err("the header names a column `y` but no column `x`".to_string()),
    }
}
