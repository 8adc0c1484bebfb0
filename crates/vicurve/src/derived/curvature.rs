//! Curvature along a measured curve.

use crate::curve::SplineCurve;
use crate::measurement::Measurement;
use serde::{Deserialize, Serialize};

/// The curvature at one point of a curve.
#[derive(Clone, Copy, Debug, PartialEq, Serialize, Deserialize)]
pub struct CurvatureSample {
    /// Arc length from the start of the curve (the sample's `s`), px.
    pub s: f64,
    /// Signed curvature, 1/px, *as seen on screen*: positive where the
    /// curve turns to the left of its direction of travel on screen (towards
    /// `-n`), so a convex closed curve (run counterclockwise on screen) has
    /// `curvature = 1 / radius > 0` everywhere. In the `(x, y)` frame with
    /// `y` down this is `(y' x'' - x' y'') / |p'|^3`, the opposite of
    /// [`crate::curve::Frame::curvature`].
    pub curvature: f64,
}

/// The curvature of the measured curve's B-spline at each of its samples
/// (same `s`, same order); see [`CurvatureSample`] for the sign.
pub fn curvature_along(m: &Measurement) -> Vec<CurvatureSample> {
    let params: Vec<f64> = m.samples.iter().map(|s| s.s).collect();
    curvature_at(&m.curve, &params)
}

/// The curvature of `curve` at the parameters `params` (px; for measured
/// curves the parameter is the arc length to within the B-spline's
/// chord-length parametrisation); see [`CurvatureSample`] for the sign.
pub fn curvature_at(curve: &SplineCurve, params: &[f64]) -> Vec<CurvatureSample> {
    params
        .iter()
        .map(|&u| CurvatureSample {
            s: u,
            curvature: -curve.frame(u).curvature,
        })
        .collect()
}

/// Summary of a curvature profile, for result files (the per-sample values
/// are a column of the points table instead). 1/px and px.
#[derive(Clone, Copy, Debug, PartialEq, Serialize, Deserialize)]
pub struct CurvatureSummary {
    /// Smallest (most negative) curvature, 1/px.
    pub min: f64,
    /// Arc length where it is reached, px.
    pub min_at: f64,
    /// Largest curvature, 1/px.
    pub max: f64,
    /// Arc length where it is reached, px.
    pub max_at: f64,
    /// Mean over the samples, 1/px (for a closed curve, `2 pi / length`
    /// with samples evenly spread in `s`).
    pub mean: f64,
}

impl CurvatureSummary {
    /// The summary of `samples`, ignoring non-finite values; `None` when no
    /// value is finite.
    pub fn new(samples: &[CurvatureSample]) -> Option<Self> {
        let finite: Vec<&CurvatureSample> =
            samples.iter().filter(|c| c.curvature.is_finite()).collect();
        let lo = finite
            .iter()
            .min_by(|a, b| a.curvature.total_cmp(&b.curvature))?;
        let hi = finite
            .iter()
            .max_by(|a, b| a.curvature.total_cmp(&b.curvature))?;
        let mean = finite.iter().map(|c| c.curvature).sum::<f64>() / finite.len() as f64;
        Some(CurvatureSummary {
            min: lo.curvature,
            min_at: lo.s,
            max: hi.curvature,
            max_at: hi.s,
            mean,
        })
    }
}
