//! Uneven light across the field: a linear gradient and a lens's
//! vignetting, multiplying the light before it is encoded, as a lamp
//! beside the specimen or a backlight brighter at its centre does.
//!
//! The factor at pixel centre `(x, y)` of a `W x H` image (centres at
//! `0..W-1`, `0..H-1`), with `dx = x - (W-1)/2`, `dy = y - (H-1)/2`, is
//! `(1 + gx dx / (W-1) + gy dy / (H-1)) (1 - v ρ²)`, `ρ` the distance
//! from the centre over half the diagonal: the centre keeps its light, a
//! gradient `gx` changes it by `gx` (a fraction) from the first column to
//! the last, and vignetting `v` darkens the corner pixels by `v`.

use crate::error::{Error, Result};
use serde::{Deserialize, Serialize};
use std::fmt;
use std::str::FromStr;

/// Uneven light (module docs). The default is even light. Light it
/// raises above 1 clips when the image is quantised, as a saturated
/// sensor's does.
#[derive(Clone, Copy, Debug, Default, PartialEq, Serialize, Deserialize)]
#[serde(default)]
pub struct Shading {
    /// Relative change of the light across the width and across the
    /// height `[gx, gy]` (0.1: 10 % brighter at the right border than at
    /// the left one).
    pub gradient: [f64; 2],
    /// Relative loss of light in the image's corners (0 to below 1).
    pub vignetting: f64,
}

impl Shading {
    /// Even light: the factor is 1 everywhere.
    pub fn is_even(&self) -> bool {
        *self == Shading::default()
    }

    /// The factor at `(x, y)` of a `width x height` image (module docs).
    pub fn factor(&self, x: f64, y: f64, (width, height): (usize, usize)) -> f64 {
        // A single row or column has no extent to change across.
        let (w, h) = (
            (width as f64 - 1.0).max(1.0),
            (height as f64 - 1.0).max(1.0),
        );
        let (dx, dy) = (x - 0.5 * w, y - 0.5 * h);
        let linear = 1.0 + self.gradient[0] * dx / w + self.gradient[1] * dy / h;
        let rho2 = (dx * dx + dy * dy) / (0.25 * (w * w + h * h));
        linear * (1.0 - self.vignetting * rho2)
    }

    /// Multiply the light `values` (row-major, `width x height`) by the
    /// factor at each pixel centre.
    pub fn apply(&self, values: &mut [f64], (width, height): (usize, usize)) {
        if self.is_even() {
            return;
        }
        for (i, v) in values.iter_mut().enumerate() {
            let (x, y) = ((i % width) as f64, (i / width) as f64);
            *v *= self.factor(x, y, (width, height));
        }
    }

    /// The factor must stay positive over the whole image: `|gx| + |gy| <
    /// 2` and `0 <= v < 1`, all finite.
    ///
    /// Errors: [`Error::InvalidParameter`] naming `shading`.
    pub fn validate(&self) -> Result<()> {
        let [gx, gy] = self.gradient;
        let v = self.vignetting;
        if !(gx.is_finite() && gy.is_finite() && gx.abs() + gy.abs() < 2.0) {
            return Err(Error::invalid(
                "shading",
                format!(
                    "gradient {gx},{gy}: |gx| + |gy| must be below 2 (the light stays positive)"
                ),
            ));
        }
        if !(v.is_finite() && (0.0..1.0).contains(&v)) {
            return Err(Error::invalid(
                "shading",
                format!("vignetting {v}: must be at least 0 and below 1"),
            ));
        }
        Ok(())
    }
}

impl fmt::Display for Shading {
    /// `GX,GY` or `GX,GY,V` (the words [`FromStr`] reads), `even` for
    /// even light.
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        let [gx, gy] = self.gradient;
        if self.is_even() {
            write!(f, "even")
        } else if self.vignetting == 0.0 {
            write!(f, "{gx},{gy}")
        } else {
            write!(f, "{gx},{gy},{}", self.vignetting)
        }
    }
}

impl FromStr for Shading {
    type Err = Error;

    /// `even`, `GX,GY` (a gradient) or `GX,GY,V` (and vignetting), checked
    /// by [`Shading::validate`].
    fn from_str(text: &str) -> Result<Shading> {
        let text = text.trim();
        if text.eq_ignore_ascii_case("even") {
            return Ok(Shading::default());
        }
        let numbers: std::result::Result<Vec<f64>, _> =
            text.split(',').map(|t| t.trim().parse::<f64>()).collect();
        let shading = match numbers.as_deref() {
            Ok(&[gx, gy]) => Shading {
                gradient: [gx, gy],
                vignetting: 0.0,
            },
            Ok(&[gx, gy, v]) => Shading {
                gradient: [gx, gy],
                vignetting: v,
            },
            _ => {
                return Err(Error::invalid(
                    "shading",
                    format!("'{text}': expected even, GX,GY or GX,GY,V"),
                ))
            }
        };
        shading.validate()?;
        Ok(shading)
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn the_gradient_and_the_vignetting_are_what_they_say() {
        let s = Shading {
            gradient: [0.1, -0.2],
            vignetting: 0.3,
        };
        let size = (201, 101);
        // The centre keeps its light; a corner loses v and gets half of
        // each gradient.
        assert!((s.factor(100.0, 50.0, size) - 1.0).abs() < 1e-15);
        assert!((s.factor(200.0, 100.0, size) - (1.05 - 0.1) * 0.7).abs() < 1e-12);
        assert!((s.factor(0.0, 0.0, size) - (0.95 + 0.1) * 0.7).abs() < 1e-12);
        // Without vignetting, the light changes by gx across the width.
        let g = Shading {
            vignetting: 0.0,
            ..s
        };
        let across = g.factor(200.0, 50.0, size) - g.factor(0.0, 50.0, size);
        assert!((across - 0.1).abs() < 1e-12);
    }

    #[test]
    fn the_words_read_back_and_bad_ones_are_refused() {
        for text in ["even", "0.1,0", "-0.05,0.1,0.2"] {
            let s: Shading = text.parse().unwrap();
            assert_eq!(s.to_string().parse::<Shading>().unwrap(), s);
        }
        assert!("even".parse::<Shading>().unwrap().is_even());
        for bad in ["", "0.1", "1.5,0.6", "0,0,1", "0,0,-0.1", "a,b", "NaN,0"] {
            assert!(bad.parse::<Shading>().is_err(), "{bad}");
        }
    }

    #[test]
    fn even_light_changes_nothing() {
        let mut v = vec![0.25, 0.5, 0.75, 1.0];
        Shading::default().apply(&mut v, (2, 2));
        assert_eq!(v, [0.25, 0.5, 0.75, 1.0]);
    }
}
