//! Which side of the curve is bright: the sign of the virtual image's
//! contrast `c`.

use crate::error::{Error, Result};
use serde::{Deserialize, Serialize};

/// Which side of the curve is bright (silhouettes) or whether the line is
/// bright (contours), relative to the curve's normal. The default, `Auto`,
/// estimates it: it is the sign of the contrast `c` of the virtual image.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq, Serialize, Deserialize)]
#[serde(rename_all = "snake_case")]
pub enum Polarity {
    /// Estimated from the image (sign of `c`).
    #[default]
    Auto,
    /// `c > 0`: bright inside a closed curve, bright on the screen-left of
    /// an open one, or a bright line on a dark ground.
    Positive,
    /// `c < 0`: the reverse.
    Negative,
}

impl std::fmt::Display for Polarity {
    /// `auto`, `positive` or `negative`, which [`FromStr`](std::str::FromStr)
    /// reads back.
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        f.write_str(match self {
            Polarity::Auto => "auto",
            Polarity::Positive => "positive",
            Polarity::Negative => "negative",
        })
    }
}

impl std::str::FromStr for Polarity {
    type Err = Error;
    /// `auto`, `positive`, `negative`, or the words that say it on screen:
    /// `bright-inside`, `bright-left` (open curves, along their direction)
    /// and `bright-line` for positive, `dark-inside`, `bright-right` and
    /// `dark-line` for negative. Case is ignored and `_` is read as `-`.
    /// The one parser of the command line's `--polarity`, job files'
    /// `polarity` and Python's `polarity=`.
    fn from_str(s: &str) -> Result<Self> {
        match s.trim().to_ascii_lowercase().replace('_', "-").as_str() {
            "auto" => Ok(Polarity::Auto),
            "positive" | "bright-inside" | "bright-left" | "bright-line" => Ok(Polarity::Positive),
            "negative" | "dark-inside" | "bright-right" | "dark-line" => Ok(Polarity::Negative),
            _ => Err(Error::invalid(
                "polarity",
                format!(
                    "'{s}' (expected auto, bright-inside, dark-inside, bright-left, bright-right, bright-line or dark-line; or positive, negative)"
                ),
            )),
        }
    }
}
