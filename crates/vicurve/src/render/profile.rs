//! Images sampled from an analytic gray-level profile across the curve (the
//! test images of Réthoré & François): each pixel centre gets
//! `background + (foreground - background) γ(d / R)`, `d` being the signed
//! distance to the curve and `R` the profile half-width.

use std::f64::consts::{FRAC_PI_2, PI};

use rayon::prelude::*;

use super::RenderSpec;
use crate::truth::Kind;

/// Silhouette profile `γ_s(ρ)`: 1 for `ρ <= -1` (inside / `-n` side),
/// `(1 - sin(πρ/2)) / 2` for `|ρ| < 1`, 0 for `ρ >= 1`.
pub fn silhouette_profile(rho: f64) -> f64 {
    if rho <= -1.0 {
        1.0
    } else if rho >= 1.0 {
        0.0
    } else {
        0.5 * (1.0 - (FRAC_PI_2 * rho).sin())
    }
}

/// Contour profile `γ_c(ρ)`: `(1 + cos(πρ)) / 2` for `|ρ| < 1`, else 0.
pub fn contour_profile(rho: f64) -> f64 {
    if rho.abs() < 1.0 {
        0.5 * (1.0 + (PI * rho).cos())
    } else {
        0.0
    }
}

/// Side of the square blocks in which far pixels are skipped, px.
const BLOCK: usize = 8;

/// The pixel values of `spec` with the profile of half-width `half_width`
/// px, row after row. The spec must be valid.
///
/// The signed distance is 1-Lipschitz, so a block of pixels whose centre is
/// farther than `half_width` plus the block's half-diagonal from the curve
/// lies wholly where the profile is flat: the whole block gets that exact
/// value without computing every distance.
pub fn profile_pixels(spec: &RenderSpec, half_width: f64) -> Vec<f64> {
    let (w, h) = (spec.width, spec.height);
    let (fg, bg) = (spec.foreground, spec.background);
    let gamma = match spec.kind {
        Kind::Silhouette => silhouette_profile,
        Kind::Contour => contour_profile,
    };
    let shape = &spec.shape;
    let mut data = vec![0.0; w * h];
    data.par_chunks_mut(BLOCK * w)
        .enumerate()
        .for_each(|(band, rows)| {
            let y0 = band * BLOCK;
            let nrows = rows.len() / w;
            for x0 in (0..w).step_by(BLOCK) {
                let ncols = BLOCK.min(w - x0);
                let cx = x0 as f64 + 0.5 * (ncols as f64 - 1.0);
                let cy = y0 as f64 + 0.5 * (nrows as f64 - 1.0);
                let reach = 0.5 * (ncols as f64 - 1.0).hypot(nrows as f64 - 1.0);
                let dc = shape.signed_distance(cx, cy);
                let flat = dc.abs() - reach * (1.0 + 1e-12) - 1e-9 >= half_width;
                let flat_value = bg + (fg - bg) * gamma(dc.signum() * 2.0);
                for i in 0..nrows {
                    for j in 0..ncols {
                        rows[i * w + x0 + j] = if flat {
                            flat_value
                        } else {
                            let d = shape.signed_distance((x0 + j) as f64, (y0 + i) as f64);
                            bg + (fg - bg) * gamma(d / half_width)
                        };
                    }
                }
            }
        });
    data
}
