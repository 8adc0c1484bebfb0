//! The project's reference test images, shared by the CLI (`synth
//! paper-disc`, `demo`), the acceptance tests, the accuracy table and the
//! benchmarks, so that every figure in docs/benchmarks.md is about the same
//! image.

use super::{Method, RenderSpec};
use crate::truth::Shape;
use crate::virtual_image::Kind;

/// The paper's own test (its section 7): a 512x512 disc of radius 200 px at
/// a non-integer centre, rendered with the silhouette profile of half-width
/// `half_width` sampled at pixel centres, levels 0 and 1, 8-bit, noiseless.
pub fn paper_disc(half_width: f64) -> RenderSpec {
    RenderSpec {
        width: 512,
        height: 512,
        shape: Shape::Circle {
            cx: 256.3,
            cy: 255.6,
            r: 200.0,
        },
        kind: Kind::Silhouette,
        method: Method::Profile { half_width },
        foreground: 1.0,
        background: 0.0,
        bits: Some(8),
        ..RenderSpec::default()
    }
}

/// A 1024x1024 star `r = 300 (1 + 0.2 cos 5 theta)` by exact pixel coverage,
/// gray 0.8 on 0.2, Gaussian blur of 1 px, 1 % noise, 8-bit (the issue's
/// star and the demo's).
pub fn star_1024() -> RenderSpec {
    RenderSpec {
        width: 1024,
        height: 1024,
        shape: Shape::Star {
            cx: 512.3,
            cy: 511.6,
            r0: 300.0,
            amplitude: 0.2,
            lobes: 5,
            phase: 0.0,
        },
        kind: Kind::Silhouette,
        method: Method::Coverage,
        foreground: 0.8,
        background: 0.2,
        blur_sigma: 1.0,
        noise: 0.01,
        seed: 3,
        bits: Some(8),
        ..RenderSpec::default()
    }
}
