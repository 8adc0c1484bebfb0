//! Diagnostics of a measurement: the band unwrapped on `(s, r)`.
//!
//! [`unwrap_band`] resamples the image on a regular grid of the measured
//! curve's curvilinear coordinates, as in Funambule's figure 2 (the band
//! unrolled into a rectangle): `s` along the curve, `r` across it. On the
//! same grid it gives the fitted virtual image, the residual
//! `image - virtual` and the robust weight the fit's rule (Tukey's biweight
//! of the residual, applied only when the band holds clutter; see
//! [`crate::fit`]) gives that residual. A well-fitted edge shows as a
//! straight horizontal transition at `r = 0` in the band, and as residuals
//! at the noise level with no structure; clutter shows as down-weighted
//! columns, a wrong profile as residual stripes parallel to `r = 0`.
//!
//! # Conventions
//! Pixels; `x` = column, `y` = row, pixel (row `i`, column `j`) centred at
//! `(x, y) = (j, i)`. `s` is the measured curve's parameter, its cumulative
//! chord length over dense samples (equal to the arc length to rounding; the
//! same `s` as [`crate::measurement::Sample::s`]). `r` is the signed distance along
//! the unit normal `n = (-t_y, t_x)`: outward on closed curves (which run
//! counterclockwise on screen), on the screen-right of travel on open ones.
//! The grid point of column `j`, row `i` is `C(s_j) + r_i n(s_j)` with
//! `s_j = j ds` and `r_i = (i - k) dr`, `r = 0` on the middle row `k`: the
//! inside (`-n` side) on the first rows. The maps are row-major, `rows x
//! columns`.

use crate::curve::Frame;
use crate::error::{Error, Result};
use crate::fit::{clutter_scale, tukey_weight, FitConfig};
use crate::image::Image;
use crate::interp::Sampler;
use crate::measurement::{LevelSample, Measurement};
use crate::virtual_image::Profile;
use serde::{Deserialize, Serialize};

/// The grid's convention in words, for files that record an unwrapped band.
pub const GRID_CONVENTION: &str = "column j is s_j = j ds, the measured curve's arc length (pixels) from its start; \
row i is r_i = -half_width + i dr, the signed distance (pixels) along the unit normal n = (-t_y, t_x), r > 0 outside a closed curve, \
on the screen-right of travel for an open one; r = 0 (the measured curve) is the middle row; the grid point is C(s_j) + r_i n(s_j)";

/// The grid's half-width is at least this (pixels) by default, so that the
/// flat levels on both sides show even when the last band is narrow (the
/// pixel-edge stage's is about 1.5 px).
pub const MIN_HALF_WIDTH: f64 = 3.0;

/// Largest grid, in cells (8 bytes per cell and map).
const MAX_CELLS: usize = 50_000_000;

/// The grid of [`unwrap_band`]. Serialisable; missing fields take the
/// defaults.
#[derive(Clone, Copy, Debug, PartialEq, Serialize, Deserialize)]
#[serde(default)]
pub struct UnwrapConfig {
    /// Spacing along the curve, pixels (> 0; default 0.5).
    pub ds: f64,
    /// Spacing across the curve, pixels (> 0; default 0.25: the edge's
    /// profile is what the band is looked at for).
    pub dr: f64,
    /// Half-width of the grid, pixels (> 0); `None` (the default): the last
    /// stage's band half-width `R`, at least [`MIN_HALF_WIDTH`]. Rounded up
    /// to a whole number of `dr`.
    pub half_width: Option<f64>,
}

impl Default for UnwrapConfig {
    fn default() -> Self {
        UnwrapConfig {
            ds: 0.5,
            dr: 0.25,
            half_width: None,
        }
    }
}

/// The band of a measurement on the `(s, r)` grid; see the
/// [module docs](self) for the conventions. Cells whose point lies outside
/// the image's pixel-centre rectangle are NaN in every map.
#[derive(Clone, Debug, PartialEq)]
pub struct UnwrappedBand {
    /// Spacing along the curve, pixels.
    pub ds: f64,
    /// Spacing across the curve, pixels.
    pub dr: f64,
    /// Half-width of the grid, pixels: `r` runs over `[-half_width,
    /// half_width]`.
    pub half_width: f64,
    /// Columns (samples along `s`, from `s = 0`).
    pub columns: usize,
    /// Rows (samples along `r`, from `r = -half_width`).
    pub rows: usize,
    /// Band half-width `R` of the last stage (that of the virtual image),
    /// pixels.
    pub fit_half_width: f64,
    /// The virtual image's profile (the last stage's).
    pub profile: Profile,
    /// Whether the gray levels vary along the curve
    /// ([`Measurement::levels`]); else the last stage's pair.
    pub varying_levels: bool,
    /// The image, interpolated as the fit did ([`FitConfig::interpolation`]),
    /// gray levels.
    pub image: Vec<f64>,
    /// The fitted virtual image `a(s) + c(s) gamma(r)`, gray levels.
    pub virtual_image: Vec<f64>,
    /// `image - virtual_image`, gray levels.
    pub residual: Vec<f64>,
    /// Robust weight of the residual, in `[0, 1]`: all 1 when the band is
    /// clean (the fit does not reweight then).
    pub weight: Vec<f64>,
    /// The robust scale (gray levels) when the band holds clutter (the
    /// weights are Tukey's biweight at 4.685 scales), `None` when clean.
    /// Estimated on the cells within the fit's band `|r| <= R`.
    pub robust_scale: Option<f64>,
    /// Cells outside the image.
    pub outside: usize,
}

impl UnwrappedBand {
    /// `s` of column `j`, pixels.
    pub fn s(&self, j: usize) -> f64 {
        j as f64 * self.ds
    }

    /// `r` of row `i`, pixels.
    pub fn r(&self, i: usize) -> f64 {
        (i as f64 - (self.rows / 2) as f64) * self.dr
    }

    /// Index of the cell of row `i`, column `j` in the maps.
    pub fn index(&self, i: usize, j: usize) -> usize {
        i * self.columns + j
    }

    /// RMS of the finite residuals, gray levels (NaN when none is).
    pub fn residual_rms(&self) -> f64 {
        let (sum, n) = self
            .residual
            .iter()
            .filter(|v| v.is_finite())
            .fold((0.0, 0usize), |(s, n), v| (s + v * v, n + 1));
        (sum / n as f64).sqrt()
    }
}

/// Unwrap the band of `m`, measured in `image` with `config`, on the grid
/// `grid`: the image, the virtual image of the last stage (its profile and
/// band half-width; the gray levels of [`Measurement::levels`] when they
/// vary, interpolated linearly in `s`, else the stage's `a` and `c`), the
/// residual and the robust weights. When the fit removed the blur's
/// curvature shift from a paper-profile result, the virtual image is
/// shifted back by it, so that it is the one the fit matched.
///
/// Errors: [`Error::InvalidParameter`] for a spacing or half-width that is
/// not finite and positive, a grid of more than 5e7 cells, or a
/// measurement with no stage or no gray levels (a fit that never ran).
pub fn unwrap_band(
    image: &Image,
    m: &Measurement,
    config: &FitConfig,
    grid: &UnwrapConfig,
) -> Result<UnwrappedBand> {
    let stage = m
        .stages
        .last()
        .ok_or_else(|| Error::invalid("measurement", "no stage ran: there is no band to unwrap"))?;
    if !(stage.a.is_finite() && stage.c.is_finite()) {
        return Err(Error::invalid(
            "measurement",
            "the last stage has no gray levels (no iteration succeeded)",
        ));
    }
    for (name, v) in [("ds", grid.ds), ("dr", grid.dr)] {
        if !(v.is_finite() && v > 0.0) {
            return Err(Error::invalid(name, format!("{v} (must be > 0 px)")));
        }
    }
    let wanted = grid
        .half_width
        .unwrap_or(stage.half_width.max(MIN_HALF_WIDTH));
    if !(wanted.is_finite() && wanted > 0.0) {
        return Err(Error::invalid(
            "half_width",
            format!("{wanted} (must be > 0 px)"),
        ));
    }
    let k = (wanted / grid.dr - 1e-9).ceil() as usize;
    let rows = 2 * k + 1;
    let length = m.curve.param_length();
    let closed = m.curve.is_closed();
    let steps = (length / grid.ds - 1e-9).floor() as usize;
    let columns = if closed { steps.max(1) } else { steps + 1 };
    if rows.saturating_mul(columns) > MAX_CELLS {
        return Err(Error::invalid(
            "grid",
            format!("{columns} x {rows} cells (at most {MAX_CELLS}): use larger ds or dr"),
        ));
    }
    let mut band = UnwrappedBand {
        ds: grid.ds,
        dr: grid.dr,
        half_width: k as f64 * grid.dr,
        columns,
        rows,
        fit_half_width: stage.half_width,
        profile: stage.profile,
        varying_levels: !m.levels.is_empty(),
        image: vec![f64::NAN; rows * columns],
        virtual_image: vec![f64::NAN; rows * columns],
        residual: vec![f64::NAN; rows * columns],
        weight: vec![f64::NAN; rows * columns],
        robust_scale: None,
        outside: 0,
    };
    // The fit's curve, of which the paper profile is a function, lies
    // `shift` inside the reported one when the curvature shift was removed.
    let shift_sigma = match (m.blur_corrected, stage.profile, m.edge_spread) {
        (true, Profile::Paper { .. }, Some(e)) => Some(e.sigma),
        _ => None,
    };
    let sampler = Sampler::new(image, config.interpolation);
    for j in 0..columns {
        let s = band.s(j);
        let f: Frame = m.curve.frame(s);
        let (a, c) = levels_at(&m.levels, s, length, closed).unwrap_or((stage.a, stage.c));
        let shift =
            shift_sigma.map_or(0.0, |sigma| crate::psf::curvature_shift(sigma, f.curvature));
        for i in 0..rows {
            let r = band.r(i);
            let (x, y) = (f.point[0] + r * f.normal[0], f.point[1] + r * f.normal[1]);
            let idx = band.index(i, j);
            let Some(value) = sampler.value(x, y) else {
                band.outside += 1;
                continue;
            };
            let (gamma, _) = stage
                .profile
                .eval(r + shift, stage.half_width, f.normal, f.curvature);
            let g = a + c * gamma;
            band.image[idx] = value;
            band.virtual_image[idx] = g;
            band.residual[idx] = value - g;
        }
    }
    // The fit's rule, on the cells of its band (all cells if none is).
    let inner: Vec<f64> = (0..rows)
        .filter(|&i| band.r(i).abs() <= stage.half_width)
        .flat_map(|i| band.residual[i * columns..(i + 1) * columns].iter())
        .copied()
        .filter(|v| v.is_finite())
        .collect();
    let probe: Vec<f64> = if inner.is_empty() {
        band.residual
            .iter()
            .copied()
            .filter(|v| v.is_finite())
            .collect()
    } else {
        inner
    };
    band.robust_scale = clutter_scale(&probe, stage.c);
    for (w, v) in band.weight.iter_mut().zip(&band.residual) {
        if v.is_finite() {
            *w = band
                .robust_scale
                .map_or(1.0, |scale| tukey_weight(*v, scale));
        }
    }
    Ok(band)
}

/// The gray levels `(a, c)` at `s`, linear between the samples of `levels`
/// (sorted by `s`; across the seam of a closed curve of length `length`,
/// constant beyond the ends of an open one); `None` without samples.
fn levels_at(levels: &[LevelSample], s: f64, length: f64, closed: bool) -> Option<(f64, f64)> {
    let (first, last) = (levels.first()?, levels.last()?);
    let k = levels.partition_point(|l| l.s <= s);
    if k == 0 || k == levels.len() {
        if !closed || levels.len() == 1 {
            let p = if k == 0 { first } else { last };
            return Some((p.a, p.c));
        }
        // Across the seam: from the last sample to the first one, one
        // length further.
        let s_here = if k == 0 { s + length } else { s };
        return Some(lerp(last, first, first.s + length, s_here));
    }
    Some(lerp(&levels[k - 1], &levels[k], levels[k].s, s))
}

/// The levels at `s` between `p` and `q`, the latter placed at `qs`.
fn lerp(p: &LevelSample, q: &LevelSample, qs: f64, s: f64) -> (f64, f64) {
    let span = qs - p.s;
    let t = if span > 0.0 {
        ((s - p.s) / span).clamp(0.0, 1.0)
    } else {
        0.0
    };
    (p.a + t * (q.a - p.a), p.c + t * (q.c - p.c))
}

#[cfg(test)]
mod tests {
    use super::*;

    fn sample(s: f64, a: f64, c: f64) -> LevelSample {
        LevelSample { s, a, c }
    }

    #[test]
    fn levels_interpolate_and_wrap() {
        let l = [sample(1.0, 0.0, 1.0), sample(5.0, 4.0, 2.0)];
        assert_eq!(levels_at(&[], 2.0, 10.0, true), None);
        assert_eq!(levels_at(&l, 3.0, 10.0, false), Some((2.0, 1.5)));
        // Open: constant beyond the ends.
        assert_eq!(levels_at(&l, 0.0, 10.0, false), Some((0.0, 1.0)));
        assert_eq!(levels_at(&l, 9.0, 10.0, false), Some((4.0, 2.0)));
        // Closed: from s = 5 (a = 4) to s = 11 (a = 0) across the seam.
        let (a, _) = levels_at(&l, 8.0, 10.0, true).unwrap();
        assert!((a - 2.0).abs() < 1e-12, "{a}");
        let (a, _) = levels_at(&l, 0.5, 10.0, true).unwrap();
        assert!((a - 4.0 * (1.0 - 5.5 / 6.0)).abs() < 1e-12, "{a}");
    }
}
