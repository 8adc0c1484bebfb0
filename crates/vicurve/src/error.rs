//! The library's error type.
//!
//! Every fallible public function returns [`Result<T>`](Result). Errors say
//! what is wrong in one sentence that a command-line tool can print as it is;
//! a fit that runs but does not converge is *not* an error: see
//! [`crate::measurement::Outcome`].

use crate::solver::SolverError;
use std::path::PathBuf;

/// Everything that can go wrong in vicurve.
#[derive(Debug, thiserror::Error)]
#[non_exhaustive]
pub enum Error {
    /// The file does not exist.
    #[error("file not found: {}", path.display())]
    NotFound {
        /// The path that was asked for.
        path: PathBuf,
    },
    /// The file exists but could not be read or written.
    #[error("cannot access {}: {source}", path.display())]
    Io {
        /// The path involved.
        path: PathBuf,
        /// The operating system's error.
        #[source]
        source: std::io::Error,
    },
    /// The file is an image of a known format but its content is damaged or
    /// truncated.
    #[error("cannot decode image {}: {reason}", path.display())]
    Decode {
        /// The image file.
        path: PathBuf,
        /// What the decoder said.
        reason: String,
    },
    /// The file is not an image format or pixel layout vicurve reads.
    #[error("unsupported image {}: {reason}", path.display())]
    UnsupportedImage {
        /// The image file.
        path: PathBuf,
        /// Why it is not supported.
        reason: String,
    },
    /// No silhouette could be found for an automatic start
    /// ([`crate::start`]).
    #[error("no silhouette found: {reason}")]
    NoSilhouette {
        /// Why, and what to try.
        reason: String,
    },
    /// No line could be followed from the picked point for a contour's
    /// automatic start ([`crate::start::ridge`]).
    #[error("no line found: {reason}")]
    NoLine {
        /// Why, and what to try.
        reason: String,
    },
    /// An image with no pixel.
    #[error("the image is empty ({width}x{height} pixels)")]
    EmptyImage {
        /// Width in pixels.
        width: usize,
        /// Height in pixels.
        height: usize,
    },
    /// A parameter is out of its documented range.
    #[error("invalid {name}: {reason}")]
    InvalidParameter {
        /// The parameter's name, as the user knows it.
        name: &'static str,
        /// What is wrong and what is accepted.
        reason: String,
    },
    /// A NaN or infinite value where a finite number is required.
    #[error("non-finite value (NaN or infinity) in {what}")]
    NonFinite {
        /// Where it was found.
        what: String,
    },
    /// A text input (CSV, curve specification, ...) could not be parsed.
    #[error("cannot parse {what} (line {line}): {reason}")]
    Parse {
        /// What was being parsed (a file name or an option).
        what: String,
        /// 1-based line number, 0 when not applicable.
        line: usize,
        /// What is wrong.
        reason: String,
    },
    /// A curve that cannot be used (too few points, zero length,
    /// self-overlapping points...).
    #[error("invalid curve: {reason}")]
    InvalidCurve {
        /// What is wrong with it.
        reason: String,
    },
    /// The initial or reference curve is (partly) outside the image.
    #[error("the curve leaves the image near ({x:.1}, {y:.1}) (image is {width}x{height}); move or shrink the initial curve")]
    CurveOutsideImage {
        /// x (column) of a point outside, pixels.
        x: f64,
        /// y (row) of a point outside, pixels.
        y: f64,
        /// Image width in pixels.
        width: usize,
        /// Image height in pixels.
        height: usize,
    },
    /// The narrow band around the curve reaches beyond the image.
    #[error("the band of half-width {half_width} px leaves the image near ({x:.1}, {y:.1}); move the curve away from the border or use a smaller band half-width")]
    BandOutsideImage {
        /// Band half-width R in pixels.
        half_width: f64,
        /// x (column) of a band pixel outside, pixels.
        x: f64,
        /// y (row) of a band pixel outside, pixels.
        y: f64,
    },
    /// The band holds too few pixels to determine the unknowns.
    #[error("the band holds too few usable pixels ({pixels}) for {unknowns} unknowns; use fewer elements or a wider band")]
    EmptyBand {
        /// Pixels in the band.
        pixels: usize,
        /// Unknowns of the fit.
        unknowns: usize,
    },
    /// A symmetric matrix that should be positive definite is not (an element
    /// of the curve sees no image gradient); the fit's reading of
    /// [`SolverError::NotPositiveDefinite`].
    #[error("the normal matrix is singular at unknown {index}; some element of the curve sees no band pixel: use fewer elements")]
    NotPositiveDefinite {
        /// Index of the failing pivot.
        index: usize,
    },
    /// A shape model ([`crate::model`]) does not suit the measured curve
    /// (a line for a closed curve, a polygon with more sides than corners).
    #[error("the {model} model does not fit the measured curve: {reason}")]
    ModelMismatch {
        /// The model, as the user wrote it (`circle`, `polygon:5`, ...).
        model: String,
        /// Why, and what to try.
        reason: String,
    },
    /// A sequence that cannot run: a job file that cannot be read or
    /// checked, an output folder holding another job's results, frames
    /// whose names collide. The reason is the whole message (one line,
    /// saying what to do).
    #[error("{reason}")]
    Job {
        /// What is wrong and what to do.
        reason: String,
    },
}

/// The fit's reading of a solver error: a matrix that is not positive
/// definite means an element of the curve sees no band pixel; the other two
/// are a caller's mistake, reported as an invalid matrix.
impl From<SolverError> for Error {
    fn from(e: SolverError) -> Self {
        match e {
            SolverError::NotPositiveDefinite { index } => Error::NotPositiveDefinite { index },
            SolverError::Empty => {
                Error::invalid("matrix size", "a banded matrix needs at least one row")
            }
            SolverError::DimensionMismatch { .. } => Error::invalid("matrix", e.to_string()),
        }
    }
}

/// Shorthand for results of this crate.
pub type Result<T> = std::result::Result<T, Error>;

impl Error {
    /// Build an [`Error::Job`].
    pub fn job(reason: impl Into<String>) -> Self {
        Error::Job {
            reason: reason.into(),
        }
    }

    /// Build an [`Error::InvalidParameter`].
    pub fn invalid(name: &'static str, reason: impl Into<String>) -> Self {
        Error::InvalidParameter {
            name,
            reason: reason.into(),
        }
    }
}
