//! One frame's prepared images, one per interpolation, each prepared when
//! a fit first asks for it: the tracking schedule needs no interpolation
//! (bilinear shares the image's pixels), and the cubic prefilter of a whole
//! frame would cost more than its fit.

use crate::image::Image;
use crate::interp::{Interpolation, Sampler};
use std::sync::OnceLock;

/// The samplers of one frame, prepared on demand (see the module docs);
/// shared by the threads that measure the frame's curves.
pub struct FrameSamplers<'a> {
    image: &'a Image,
    prepared: [OnceLock<Sampler>; Interpolation::ALL.len()],
}

impl<'a> FrameSamplers<'a> {
    /// None prepared yet, for `image`.
    pub fn new(image: &'a Image) -> Self {
        FrameSamplers {
            image,
            prepared: std::array::from_fn(|_| OnceLock::new()),
        }
    }

    /// The sampler of interpolation `kind`, prepared on the first call.
    pub fn get(&self, kind: Interpolation) -> Option<&Sampler> {
        let i = Interpolation::ALL.iter().position(|&k| k == kind)?;
        Some(self.prepared[i].get_or_init(|| Sampler::new(self.image, kind)))
    }
}
