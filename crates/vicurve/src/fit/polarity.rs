//! A line's polarity (bright or dark) from its start, when it is left to
//! the fit (`Polarity::Auto`).
//!
//! The contour profile is a bell, even about the curve: a line beside the
//! start, on the bell's flank, correlates with it as well with a bright
//! bell as with a dark one, and the contrast the fit estimates from such a
//! band can take the wrong sign. A bell of the wrong sign then moves the
//! curve away from the line, which a start with the polarity given does
//! not (docs/benchmarks.md, "A line's polarity from its start"). The
//! band's gray levels say which it is: a line covers a few percent of a
//! wide band's pixels, all on one side of the others. A dark line puts the band's lowest percentile far below its median and
//! leaves its highest within the noise; a bright line the reverse. When
//! the two tails do not differ that clearly (no line in the band yet, an
//! edge or uneven light across it), the fit estimates the sign as before.

use crate::curve::SplineCurve;
use crate::interp::Sampler;
use crate::psf::band_data;
use crate::virtual_image::Polarity;

/// Pixels read at most (a regular subsample of a larger band).
const MAX_PIXELS: usize = 100_000;

/// The tails' quantile: a line one pixel wide covers 2.5 % of a band of
/// half-width 20 px, more than this share, so the quantile lies on it.
const TAIL: f64 = 0.01;

/// One tail's excursion from the median must exceed the other's this many
/// times to decide.
const DOMINANCE: f64 = 3.0;

/// ...and this many noise deviations of a pixel.
const SIGNIFICANCE: f64 = 5.0;

/// The polarity of the line beside or under `curve`, from the pixels
/// within `half_width` (pixels) of it; `None` when the band does not say
/// clearly (see the module docs) or cannot be built (near the border).
pub(super) fn line_polarity(
    sampler: &Sampler,
    curve: &SplineCurve,
    half_width: f64,
) -> Option<Polarity> {
    let data = band_data(sampler, curve, half_width, MAX_PIXELS)?;
    let mut values: Vec<f64> = data.into_iter().map(|(_, f)| f).collect();
    if values.len() < 100 {
        return None;
    }
    values.sort_unstable_by(f64::total_cmp);
    let at = |q: f64| values[((values.len() - 1) as f64 * q).round() as usize];
    let (low, median, high) = (at(TAIL), at(0.5), at(1.0 - TAIL));
    let (dark, bright) = (median - low, high - median);
    let floor = SIGNIFICANCE * sampler.pixel_noise();
    if dark > DOMINANCE * bright && dark > floor {
        Some(Polarity::Negative)
    } else if bright > DOMINANCE * dark && bright > floor {
        Some(Polarity::Positive)
    } else {
        None
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::curve::InitialCurve;
    use crate::image::Image;
    use crate::interp::Interpolation;

    /// A deterministic pseudo-random value in `[-0.5, 0.5)` per pixel.
    fn jitter(x: usize, y: usize) -> f64 {
        let v = ((x as f64 * 12.9898 + y as f64 * 78.233).sin() * 43_758.545_3).fract();
        v.abs() - 0.5
    }

    /// The polarity read beside a vertical start at x = 58 in a 100 x 100
    /// image whose pixel `(x, y)` is `f(x, y)`, over a band of 20 px.
    fn read(f: impl Fn(usize, usize) -> f64) -> Option<Polarity> {
        let image = Image::from_fn(100, 100, f);
        let sampler = Sampler::new(&image, Interpolation::CubicBSpline);
        let start = InitialCurve::Segment {
            x0: 58.0,
            y0: 25.0,
            x1: 58.0,
            y1: 75.0,
        }
        .to_curve()
        .unwrap();
        line_polarity(&sampler, &start, 20.0)
    }

    /// A line 3 px wide 8 px beside the start gives its polarity, dark or
    /// bright; noise alone or a ramp of light across the band give none.
    #[test]
    fn a_line_beside_the_start_gives_its_polarity() {
        let line = |level: f64| {
            move |x: usize, y: usize| {
                let on = (49..=51).contains(&x);
                (if on { level } else { 0.5 }) + 0.02 * jitter(x, y)
            }
        };
        assert_eq!(read(line(0.2)), Some(Polarity::Negative));
        assert_eq!(read(line(0.8)), Some(Polarity::Positive));
        assert_eq!(read(|x, y| 0.5 + 0.02 * jitter(x, y)), None);
        assert_eq!(
            read(|x, y| 0.2 + 0.006 * x as f64 + 0.02 * jitter(x, y)),
            None
        );
    }
}
