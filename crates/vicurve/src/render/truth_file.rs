//! The truth file written next to a synthetic image: the exact curve, its
//! kind and how the image was rendered (read back by `vicurve eval`).

use super::{Method, RenderSpec};
use crate::error::{Error, Result};
use crate::truth::{Kind, Shape};
use serde::{Deserialize, Serialize};
use std::path::Path;

/// The ground truth of an image: the curve, its kind and, for synthetic
/// images, how the image was rendered. Written as JSON next to the image.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub struct Truth {
    /// The true curve, px.
    pub shape: Shape,
    /// Silhouette (edge) or contour (thin line).
    pub kind: Kind,
    /// Full width of the line of a contour painted with exact coverage, px;
    /// `None` otherwise (silhouettes, profile images whose width is set by
    /// the profile half-width).
    pub line_width: Option<f64>,
    /// How the image was rendered, when it is synthetic.
    pub image: Option<RenderSpec>,
}

impl Truth {
    /// The truth of an image rendered from `spec`.
    pub fn from_spec(spec: &RenderSpec) -> Truth {
        Truth {
            shape: spec.shape.clone(),
            kind: spec.kind,
            line_width: match (spec.kind, spec.method) {
                (Kind::Contour, Method::Coverage) => Some(spec.line_width),
                _ => None,
            },
            image: Some(spec.clone()),
        }
    }

    /// Pretty-printed JSON.
    pub fn to_json(&self) -> String {
        // Serialising plain data with finite or non-finite floats cannot fail
        // (serde_json writes non-finite floats as null).
        serde_json::to_string_pretty(self).unwrap_or_default()
    }

    /// Parse the JSON written by [`Truth::to_json`] and validate the shape.
    /// `what` names the source in error messages.
    ///
    /// Errors: [`Error::Parse`] for malformed JSON, [`Error::InvalidParameter`]
    /// for an invalid shape.
    pub fn from_json(text: &str, what: &str) -> Result<Truth> {
        let t: Truth = serde_json::from_str(text).map_err(|e| Error::Parse {
            what: what.to_string(),
            line: e.line(),
            reason: e.to_string(),
        })?;
        t.shape.validate()?;
        Ok(t)
    }

    /// Write [`Truth::to_json`] to `path`.
    ///
    /// Errors: [`Error::Io`].
    pub fn save(&self, path: &Path) -> Result<()> {
        std::fs::write(path, self.to_json()).map_err(|source| Error::Io {
            path: path.to_path_buf(),
            source,
        })
    }

    /// Read a truth file written by [`Truth::save`].
    ///
    /// Errors: [`Error::NotFound`], [`Error::Io`], and those of
    /// [`Truth::from_json`].
    pub fn load(path: &Path) -> Result<Truth> {
        let text = std::fs::read_to_string(path).map_err(|source| {
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
        })?;
        Truth::from_json(&text, &path.display().to_string())
    }
}
