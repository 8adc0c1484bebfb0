//! Reading the measured curve back from a result file (`vicurve measure
//! --out`), to export or mesh it without measuring again.

use crate::curve::SplineCurveData;
use crate::error::{Error, Result};
use serde::Deserialize;
use std::path::Path;

/// What the exporters use of a result file: the curve and the image it
/// was measured in (other fields are ignored).
#[derive(Clone, Debug, PartialEq)]
pub struct ResultCurve {
    /// The measured B-spline (`curve` of the file).
    pub curve: SplineCurveData,
    /// The input image's name, if recorded.
    pub input_path: Option<String>,
    /// The input image's `(width, height)`, pixels, if recorded.
    pub size: Option<(usize, usize)>,
}

#[derive(Deserialize)]
struct Doc {
    curve: SplineCurveData,
    #[serde(default)]
    input: Option<Input>,
}

#[derive(Deserialize)]
struct Input {
    path: Option<String>,
    width: Option<usize>,
    height: Option<usize>,
}

/// Parse the text of a result file; `what` names it in errors.
///
/// Errors: [`Error::Parse`] when the text is not JSON or has no valid
/// `curve` (degree, closed, knots, control_points; a `null` where a
/// number is expected, as written for NaN, is an error too).
pub fn parse_result_curve(text: &str, what: &str) -> Result<ResultCurve> {
    let doc: Doc = serde_json::from_str(text).map_err(|e| Error::Parse {
        what: what.to_string(),
        line: e.line(),
        reason: format!("{e} (expected a result file written by vicurve measure --out)"),
    })?;
    let input = doc.input;
    Ok(ResultCurve {
        curve: doc.curve,
        input_path: input.as_ref().and_then(|i| i.path.clone()),
        size: input.and_then(|i| Some((i.width?, i.height?))),
    })
}

/// Read and parse a result file.
///
/// Errors: [`Error::NotFound`], [`Error::Io`], and as
/// [`parse_result_curve`].
pub fn read_result_curve(path: &Path) -> Result<ResultCurve> {
    let text = std::fs::read_to_string(path).map_err(|e| {
        if e.kind() == std::io::ErrorKind::NotFound {
            Error::NotFound {
                path: path.to_path_buf(),
            }
        } else {
            Error::Io {
                path: path.to_path_buf(),
                source: e,
            }
        }
    })?;
    parse_result_curve(&text, &path.display().to_string())
}
