//! Grayscale images as real numbers.
//!
//! # Coordinate convention
//! `x` is the column and `y` the row. The pixel in row `i`, column `j` has
//! its centre at `(x, y) = (j, i)` and covers `[j - 1/2, j + 1/2] x
//! [i - 1/2, i + 1/2]`. The image therefore covers
//! `[-1/2, width - 1/2] x [-1/2, height - 1/2]`.
//!
//! Gray levels are `f64`; images read from 8-bit files are divided by 255 and
//! 16-bit ones by 65535, so they usually span `[0, 1]`, but any finite value
//! is accepted.

use crate::error::{Error, Result};
use std::sync::Arc;

/// A grayscale image, stored row after row.
///
/// The pixels are shared, not copied, with a bilinear
/// [`crate::interp::Sampler`] made from the image (and with clones of it);
/// [`Image::data_mut`] copies them first when they are shared.
#[derive(Clone, Debug, PartialEq)]
pub struct Image {
    width: usize,
    height: usize,
    data: Arc<Vec<f64>>,
}

/// The size checks of [`Image::new`]: `len` values for a `width x height`
/// image, neither side 0.
fn check_size(width: usize, height: usize, len: usize) -> Result<()> {
    if width == 0 || height == 0 {
        return Err(Error::EmptyImage { width, height });
    }
    if len != width * height {
        return Err(Error::invalid(
            "image data",
            format!(
                "{len} values for a {width}x{height} image (expected {})",
                width * height
            ),
        ));
    }
    Ok(())
}

impl Image {
    /// An image from its pixels, row after row (`data[y * width + x]`).
    ///
    /// Errors: [`Error::EmptyImage`] when a side is 0,
    /// [`Error::InvalidParameter`] when `data.len() != width * height`,
    /// [`Error::NonFinite`] when a pixel is NaN or infinite.
    pub fn new(width: usize, height: usize, data: Vec<f64>) -> Result<Self> {
        check_size(width, height, data.len())?;
        if let Some(i) = data.iter().position(|v| !v.is_finite()) {
            return Err(Error::NonFinite {
                what: format!("image pixel (x={}, y={})", i % width, i / width),
            });
        }
        Ok(Image {
            width,
            height,
            data: Arc::new(data),
        })
    }

    /// [`Image::new`] for pixels that are finite by construction (converted
    /// from integers): the sizes are checked, the values not (scanning a
    /// megapixel costs a fair share of a frame's decoding).
    pub(crate) fn new_finite(width: usize, height: usize, data: Vec<f64>) -> Result<Self> {
        check_size(width, height, data.len())?;
        debug_assert!(data.iter().all(|v| v.is_finite()));
        Ok(Image {
            width,
            height,
            data: Arc::new(data),
        })
    }

    /// An image whose pixel `(x, y)` (column, row) is `f(x, y)`.
    ///
    /// Panics if a side is 0 (a programming error, not a user input).
    pub fn from_fn(width: usize, height: usize, f: impl Fn(usize, usize) -> f64) -> Self {
        assert!(width > 0 && height > 0, "Image::from_fn: empty image");
        let mut data = Vec::with_capacity(width * height);
        for y in 0..height {
            for x in 0..width {
                data.push(f(x, y));
            }
        }
        Image {
            width,
            height,
            data: Arc::new(data),
        }
    }

    /// Width in pixels (number of columns).
    pub fn width(&self) -> usize {
        self.width
    }

    /// Height in pixels (number of rows).
    pub fn height(&self) -> usize {
        self.height
    }

    /// The pixels, row after row.
    pub fn data(&self) -> &[f64] {
        &self.data
    }

    /// The pixels, row after row, mutable. The caller keeps them finite.
    pub fn data_mut(&mut self) -> &mut [f64] {
        Arc::make_mut(&mut self.data).as_mut_slice()
    }

    /// The pixels, shared (see the type's docs).
    pub(crate) fn shared_data(&self) -> Arc<Vec<f64>> {
        Arc::clone(&self.data)
    }

    /// The gray level of the pixel at column `x`, row `y`.
    ///
    /// Panics when out of bounds (like slice indexing).
    #[inline]
    pub fn get(&self, x: usize, y: usize) -> f64 {
        assert!(x < self.width && y < self.height);
        self.data[y * self.width + x]
    }

    /// Whether the point `(x, y)` (pixels) lies at least `margin` pixels
    /// inside the image's area `[-1/2, width - 1/2] x [-1/2, height - 1/2]`.
    #[inline]
    pub fn contains(&self, x: f64, y: f64, margin: f64) -> bool {
        x >= -0.5 + margin
            && y >= -0.5 + margin
            && x <= self.width as f64 - 0.5 - margin
            && y <= self.height as f64 - 0.5 - margin
    }

    /// Smallest and largest gray level.
    pub fn min_max(&self) -> (f64, f64) {
        self.data
            .iter()
            .fold((f64::INFINITY, f64::NEG_INFINITY), |(lo, hi), &v| {
                (lo.min(v), hi.max(v))
            })
    }
}
