//! Synthetic images of a necking specimen ([`NeckedBar`]): the bright bar
//! painted by exact pixel coverage, then blurred, noisy and quantised as
//! [`super::render`] does for the shapes.
//!
//! The painted region is one polygon: the top edge from left to right, then
//! the bottom edge back, both beyond the image's sides. Its vertices lie on
//! the true edges, with chords whose sagitta stays below
//! [`super::shapes::SAGITTA`] px.

use serde::{Deserialize, Serialize};

use super::scene::{paint, Rendering};
use super::shapes::SAGITTA;
use crate::error::{Error, Result};
use crate::image::Image;
use crate::truth::specimen::{Edge, NeckedBar};

/// Largest chord, px, where the edges are (nearly) straight.
const MAX_CHORD: f64 = 0.5;

/// How far the polygon goes beyond the image's left and right sides and
/// the blur's reach ([`super::blur::reach`]), px.
const MARGIN: f64 = 3.0;

/// Everything that defines a synthetic specimen image; serialisable, and
/// written into the truth file of each frame.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub struct SpecimenSpec {
    /// Image width, px (1 to 20000).
    pub width: usize,
    /// Image height, px (1 to 20000).
    pub height: usize,
    /// The bar.
    pub bar: NeckedBar,
    /// Gray level of the bar, in `[0, 1]`.
    pub foreground: f64,
    /// Gray level elsewhere, in `[0, 1]`.
    pub background: f64,
    /// Standard deviation of the Gaussian blur, px (0: none).
    pub blur_sigma: f64,
    /// Standard deviation of the additive Gaussian noise, as a fraction of
    /// `|foreground - background|` (0: none).
    pub noise: f64,
    /// Seed of the noise.
    pub seed: u64,
    /// `Some(8)` or `Some(16)`: quantise like an integer image of that
    /// depth; `None`: full precision.
    pub bits: Option<u8>,
}

impl SpecimenSpec {
    /// Check every field: the sizes, levels, blur, noise and bits as for
    /// [`super::RenderSpec::validate`], and the bar.
    ///
    /// Errors: [`Error::InvalidParameter`] naming the field.
    pub fn validate(&self) -> Result<()> {
        // The shared checks, through a render spec with the same fields.
        self.common().validate()?;
        self.bar.validate()
    }

    /// A render spec with this one's size, levels, blur, noise and depth
    /// (the rest default).
    fn common(&self) -> super::RenderSpec {
        super::RenderSpec {
            width: self.width,
            height: self.height,
            foreground: self.foreground,
            background: self.background,
            blur_sigma: self.blur_sigma,
            noise: self.noise,
            seed: self.seed,
            bits: self.bits,
            ..super::RenderSpec::default()
        }
    }
}

/// The polygon of the bar of `spec`: the top edge from beyond the left side
/// to beyond the right one, then the bottom edge back. The bar must be
/// valid.
///
/// Errors: [`Error::InvalidParameter`] when it would need more than 100
/// million vertices.
pub fn bar_ring(spec: &SpecimenSpec) -> Result<Vec<[f64; 2]>> {
    let bar = &spec.bar;
    let margin = MARGIN + super::blur::reach(spec.blur_sigma) as f64;
    let xa = -0.5 - margin;
    let xb = spec.width as f64 - 0.5 + margin;
    let mut xs = vec![xa];
    let mut x = xa;
    // |y''| <= neck / neck_length², and the speed is at least 1: a chord of
    // length c over x sags by at most c² |y''| / 8.
    let bound = bar.neck / (bar.neck_length * bar.neck_length);
    let chord = if bound > 0.0 {
        (8.0 * SAGITTA / bound).sqrt().min(MAX_CHORD)
    } else {
        MAX_CHORD
    };
    let count = (xb - xa) / chord;
    if count.is_nan() || count >= 5e7 {
        return Err(Error::invalid(
            "neck_length",
            "the neck is too sharp to be drawn as a polygon",
        ));
    }
    while x + chord < xb {
        x += chord;
        xs.push(x);
    }
    xs.push(xb);
    let mut ring: Vec<[f64; 2]> = xs.iter().map(|&x| [x, bar.edge_y(Edge::Top, x)]).collect();
    ring.extend(xs.iter().rev().map(|&x| [x, bar.edge_y(Edge::Bottom, x)]));
    Ok(ring)
}

/// Render the specimen image described by `spec`: exact coverage of the bar
/// through the Gaussian blur ([`super::blur::blurred_coverage`], value
/// `background + (foreground - background) * fraction`), then the noise
/// and the quantisation, in that order, as [`super::render`].
///
/// Errors: those of [`SpecimenSpec::validate`] and [`bar_ring`].
pub fn render_specimen(spec: &SpecimenSpec) -> Result<Image> {
    spec.validate()?;
    let rendering = Rendering::of(&spec.common());
    paint(&[bar_ring(spec)?], (spec.width, spec.height), &rendering)
}

#[cfg(test)]
mod tests {
    use super::*;

    fn spec() -> SpecimenSpec {
        SpecimenSpec {
            width: 120,
            height: 80,
            bar: NeckedBar {
                axis_y: 40.3,
                width: 40.0,
                neck: 8.0,
                neck_length: 15.0,
                x_neck: 60.2,
            },
            foreground: 0.9,
            background: 0.1,
            blur_sigma: 0.0,
            noise: 0.0,
            seed: 0,
            bits: None,
        }
    }

    #[test]
    fn column_sums_are_the_width() {
        // Without blur, the bright fraction of a column integrates the width
        // over the column's one pixel span: sum of coverages = the mean of
        // w(x) over [j - 1/2, j + 1/2].
        let s = spec();
        let img = render_specimen(&s).unwrap();
        for j in [0usize, 30, 55, 60, 61, 75, 119] {
            let sum: f64 = (0..s.height).map(|i| (img.get(j, i) - 0.1) / 0.8).sum();
            let x = j as f64;
            let w = |x: f64| s.bar.width_at(x);
            // Composite Simpson over 16 sub-intervals.
            let mean = crate::psf::simpson(x - 0.5, x + 0.5, 16, w);
            assert!((sum - mean).abs() < 1e-6, "column {j}: {sum} vs {mean}");
        }
    }

    #[test]
    fn invalid_specs_are_rejected() {
        let mut s = spec();
        s.bar.neck = 50.0;
        assert!(render_specimen(&s).is_err());
        let mut s = spec();
        s.foreground = 2.0;
        assert!(render_specimen(&s).is_err());
    }
}
