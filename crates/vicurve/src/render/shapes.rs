//! The region to paint, as dense polygons that follow the true curves.
//!
//! Vertices lie exactly on the curve (or on its exact normal-offset curve
//! `p + h n` for a line of half-width `h`). Their spacing adapts to the local
//! radius of curvature `ρ` so that the chord's sagitta `L² / (8ρ)` stays below
//! [`SAGITTA`]: the polygon differs from the true region by less than that
//! everywhere, far below the 1e-3 px the library aims at.

use super::RenderSpec;
use crate::error::{Error, Result};
use crate::truth::{Kind, Shape};

/// Largest distance between a chord of the polygon and the true curve, px.
pub const SAGITTA: f64 = 1e-7;

/// Largest chord, px, where the curve is (nearly) straight.
const MAX_CHORD: f64 = 0.5;

/// How far the polygons of the infinite sine go beyond the image and the
/// blur's reach ([`super::blur::reach`]), px.
const MARGIN: f64 = 3.0;

/// Upper bound on the number of vertices (memory guard).
const MAX_VERTICES: usize = 100_000_000;

/// The polygon rings of the painted region of `spec` (foreground), in pixel
/// coordinates; see [`super::coverage::polygon_coverage`]. The spec must be
/// valid.
///
/// - Silhouette of a closed shape: its boundary (a polygon's own vertices).
/// - Silhouette of a sine: the part above the curve (smaller `y`), closed
///   outside the image.
/// - Contour of a closed shape: the outer offset curve (`+h n`) and the inner
///   one (`-h n`) reversed, i.e. an annulus.
/// - Contour of a sine: the band between the two offset curves, closed
///   outside the image.
///
/// Errors: [`Error::InvalidParameter`] when the polygon would need more than
/// 100 million vertices.
pub fn region_rings(spec: &RenderSpec) -> Result<Vec<Vec<[f64; 2]>>> {
    let shape = &spec.shape;
    let h = 0.5 * spec.line_width;
    match (shape, spec.kind) {
        (Shape::Sine { amplitude, y0, .. }, kind) => {
            let extra = if kind == Kind::Contour { h } else { 0.0 };
            let margin = MARGIN + super::blur::reach(spec.blur_sigma) as f64;
            let xa = -0.5 - margin - extra;
            let xb = spec.width as f64 - 0.5 + margin + extra;
            match kind {
                Kind::Silhouette => {
                    let mut ring = Vec::new();
                    offset_curve(shape, 0.0, xa, xb, true, &mut ring)?;
                    let top = (-0.5 - margin).min(y0 - amplitude.abs() - margin);
                    ring.push([xb, top]);
                    ring.push([xa, top]);
                    Ok(vec![ring])
                }
                Kind::Contour => {
                    let mut ring = Vec::new();
                    offset_curve(shape, -h, xa, xb, true, &mut ring)?;
                    let mut lower = Vec::new();
                    offset_curve(shape, h, xa, xb, true, &mut lower)?;
                    ring.extend(lower.iter().rev());
                    Ok(vec![ring])
                }
            }
        }
        (Shape::Polygon { .. }, Kind::Silhouette) => Ok(vec![shape.corners()]),
        (_, Kind::Silhouette) => {
            let mut ring = Vec::new();
            offset_curve(shape, 0.0, 0.0, std::f64::consts::TAU, false, &mut ring)?;
            Ok(vec![ring])
        }
        (_, Kind::Contour) => {
            let tau = std::f64::consts::TAU;
            let mut outer = Vec::new();
            offset_curve(shape, h, 0.0, tau, false, &mut outer)?;
            let mut inner = Vec::new();
            offset_curve(shape, -h, 0.0, tau, false, &mut inner)?;
            inner.reverse();
            Ok(vec![outer, inner])
        }
    }
}

/// Append to `out` points of the offset curve `p(s) + h n(s)` for `s` from
/// `s0` towards `s1` (`s1` itself included when `include_end`), with chords
/// whose sagitta is below [`SAGITTA`].
///
/// The offset curve's speed is `|p'| |1 - h k|` and its radius of curvature
/// `|1/k - h|` (`k`: signed curvature of the curve); the step is the smaller
/// of those allowed at both ends of the step.
fn offset_curve(
    shape: &Shape,
    h: f64,
    s0: f64,
    s1: f64,
    include_end: bool,
    out: &mut Vec<[f64; 2]>,
) -> Result<()> {
    let point = |s: f64| {
        let e = shape.eval(s);
        let n = e.normal();
        [e.p[0] + h * n[0], e.p[1] + h * n[1]]
    };
    let step = |s: f64| {
        let e = shape.eval(s);
        let k = e.curvature();
        let rho = if k == 0.0 {
            f64::INFINITY
        } else {
            (1.0 / k - h).abs()
        };
        let chord = (8.0 * SAGITTA * rho).sqrt().min(MAX_CHORD);
        chord / (e.speed() * (1.0 - h * k).abs())
    };
    // Guards against an endless loop on a degenerate offset (cusp); the
    // spec validation rejects those beforehand.
    let min_step = (s1 - s0) / MAX_VERTICES as f64;
    let start = out.len();
    let mut s = s0;
    while s < s1 {
        out.push(point(s));
        let ds = step(s);
        let ds = ds.min(step(s + ds));
        if ds.is_nan() || ds < min_step || out.len() - start > MAX_VERTICES {
            return Err(Error::invalid(
                "shape",
                "the curve is too large or too sharply bent to be drawn as a polygon",
            ));
        }
        s += ds;
    }
    if include_end {
        out.push(point(s1));
    }
    Ok(())
}
