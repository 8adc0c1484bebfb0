//! Helpers shared by the library's integration tests: the scene most of
//! them render (an exact-coverage silhouette, gray 0.8 on 0.2) and the
//! distance between two measured curves.

use vicurve::fit::Measurement;
use vicurve::render::{Method, RenderSpec};
use vicurve::truth::Shape;
use vicurve::virtual_image::Kind;

/// An exact-coverage silhouette of `shape` in a `width x height` image,
/// gray 0.8 on 0.2: Gaussian blur `blur`
/// (sigma, px), noise `noise` (standard deviation as a fraction of the
/// gray range) drawn from `seed`, quantised to `bits` (`None`: kept as
/// floats).
pub fn spec(
    shape: Shape,
    (width, height): (usize, usize),
    blur: f64,
    noise: f64,
    seed: u64,
    bits: Option<u8>,
) -> RenderSpec {
    RenderSpec {
        width,
        height,
        shape,
        kind: Kind::Silhouette,
        method: Method::Coverage,
        foreground: 0.8,
        background: 0.2,
        blur_sigma: blur,
        noise,
        seed,
        bits,
        ..RenderSpec::default()
    }
}

/// [`spec`] of the disc of centre `(cx, cy)` and radius `r` (px) in a
/// `size x size` image.
pub fn disc(
    size: usize,
    (cx, cy, r): (f64, f64, f64),
    blur: f64,
    noise: f64,
    seed: u64,
    bits: Option<u8>,
) -> RenderSpec {
    spec(
        Shape::Circle { cx, cy, r },
        (size, size),
        blur,
        noise,
        seed,
        bits,
    )
}

/// Largest distance (px) from the samples of `a` to the curve of `b`: each
/// sample projected onto `b` from `b`'s nearest sample (the first of equal
/// ones). Not symmetric: take the larger of both directions for a distance
/// between two curves.
pub fn max_gap(a: &Measurement, b: &Measurement) -> f64 {
    let pts = b.points();
    let mut worst: f64 = 0.0;
    for p in a.points() {
        let d = |q: [f64; 2]| (q[0] - p[0]).hypot(q[1] - p[1]);
        let k = (0..pts.len())
            .min_by(|&i, &j| d(pts[i]).total_cmp(&d(pts[j])))
            .unwrap();
        worst = worst.max(b.curve.project(p[0], p[1], b.samples[k].s).r.abs());
    }
    worst
}

/// The median of the samples' `sigma` of `m` (px): the typical sample's
/// reported uncertainty, which a test compares an error with. NaN without
/// samples.
pub fn median_sigma(m: &Measurement) -> f64 {
    let mut sigmas: Vec<f64> = m.samples.iter().map(|s| s.sigma).collect();
    sigmas.sort_by(f64::total_cmp);
    sigmas.get(sigmas.len() / 2).copied().unwrap_or(f64::NAN)
}

/// The RMS of the samples' `sigma` of `m` (px): what the scatter of the
/// curve's errors is compared with. NaN without samples.
pub fn rms_sigma(m: &Measurement) -> f64 {
    (m.samples.iter().map(|s| s.sigma * s.sigma).sum::<f64>() / m.samples.len() as f64).sqrt()
}

/// A 3 x 3 grid of dots of radius `r` px, `pitch` px apart, in a 96 x 96
/// image, the middle one at (48.3, 47.6) off the pixel grid: gray 0.8 on
/// 0.2, blur `blur` px, 0.6 % noise, 8 bits.
pub fn dot_grid(r: f64, pitch: f64, blur: f64, seed: u64) -> vicurve::render::scene::Scene {
    use vicurve::render::scene::{Rendering, Role, Scene, SceneItem};
    let items = (0..9)
        .map(|k| SceneItem {
            shape: Shape::Circle {
                cx: 48.3 + pitch * (k % 3) as f64 - pitch,
                cy: 47.6 + pitch * (k / 3) as f64 - pitch,
                r,
            },
            role: Role::Object,
            strain: None,
        })
        .collect();
    Scene {
        width: 96,
        height: 96,
        items,
        rendering: Rendering {
            blur_sigma: blur,
            noise: 0.006,
            ..Rendering::standard(seed)
        },
        d0: None,
    }
}
