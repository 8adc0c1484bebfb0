//! # vicurve
//!
//! Sub-pixel measurement of curves (thin lines, *contours*) and edges
//! (*silhouettes*) in grayscale images by Virtual Image Correlation with
//! B-splines (Réthoré & François, 2013).
//!
//! Coordinates are in pixels: `x` is the column, `y` the row, and the centre
//! of pixel (row `i`, column `j`) is at `(x, y) = (j, i)`; see [`image`].
#![deny(missing_docs)]

pub mod band;
pub(crate) mod buckets;
pub(crate) mod correlation;
pub mod curve;
pub mod derived;
pub mod diagnostics;
pub mod error;
pub mod export;
pub mod fit;
pub mod image;
pub mod interp;
pub mod io;
pub mod measurement;
pub mod model;
pub mod nurbs;
pub mod objects;
pub(crate) mod pages;
pub mod psf;
pub mod render;
pub mod report;
pub mod sequence;
pub mod solver;
pub mod spline;
pub mod start;
pub mod tone;
pub mod truth;
pub mod virtual_image;

/// The paper's levelset coordinates, at their old path (now under [`band`]).
pub use band::levelset;
pub use error::{Error, Result};
pub use image::Image;
