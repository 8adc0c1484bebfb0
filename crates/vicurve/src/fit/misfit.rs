//! The model-misfit term of the output's `sigma`: where the image's edge
//! departs from what the model can follow, the noise-only Gauss–Newton
//! `sigma` says nothing of the error. Two checks, made once on the last
//! stage's result:
//!
//! - **Residuals.** The band pixels whose foot lies near a sample ask for
//!   an extra displacement ([`crate::correlation`]'s residual bins, 1 px
//!   long). Over the bins within a quarter element on each side of the
//!   sample, the window's request `d = sum p / sum A` (`p` a bin's
//!   projected residual, `A` its information) has variance `sigma_n^2 /
//!   sum A` under noise alone; beyond `REQUEST_SIGNIFICANCE` of its
//!   standard deviations, `|d|` is the misfit there. The window's sum
//!   averages out requests that alternate within it (a pixel grid's
//!   aliasing), which do not move the curve: a chi-square of the single
//!   bins' requests takes them for misfit.
//! - **Oscillation.** A curve that oscillates at its elements' scale (a
//!   feedback through the blur's curvature term, a spline chasing
//!   detail the image cannot resolve) leaves no residual: the model's image
//!   of the oscillating curve matches the image. A feedback grows from one
//!   settle to the next, so it is looked for in the last run's
//!   displacement `U` (the change from the previous settle), not in the
//!   curve: a star's own lobes have detail at the elements' scale too (a
//!   curve check fired on the exact outline of a 6-lobed star, 7e-3 px at
//!   9 px elements), and a settled curve that repeats itself holds none of
//!   it in `U`. The second differences of `U` at spans `a`, `2a` and `3a`
//!   (`a` the element length) combine to `D(a) - 0.4 D(2a) + D(3a) / 15`,
//!   which cancels the terms in `a^2` and `a^4` of a smooth `U` and is
//!   `2.13 A` for an oscillation of amplitude `A` and wavelength `2a`;
//!   under noise alone it is about the position's `sigma`. Beyond
//!   `OSCILLATION_SIGNIFICANCE` times that, `|.| / 2.13`, the largest
//!   within a span, is the misfit there.

use crate::correlation::{Correlation, ResidualBin};
use crate::interp::Sampler;

/// Length of a residual bin along the reference, pixels.
const BIN: f64 = 1.0;
/// The request of a window counts beyond this many of its noise standard
/// deviations.
const REQUEST_SIGNIFICANCE: f64 = 4.0;
/// The oscillation counts beyond this many times the noise `sigma`.
const OSCILLATION_SIGNIFICANCE: f64 = 4.0;
/// `D(a) - 0.4 D(2a) + D(3a) / 15` of an oscillation of wavelength `2a`,
/// per unit amplitude.
const OSCILLATION_GAIN: f64 = 2.0 + 2.0 / 15.0;

/// The residual check, prepared once for a result.
pub(super) struct ResidualMisfit {
    bins: Vec<ResidualBin>,
    /// Per-pixel noise variance, gray levels squared.
    noise: f64,
    /// Bins on each side of a sample's.
    reach: usize,
    closed: bool,
}

impl ResidualMisfit {
    /// The residuals of `corr` at `lambda` (none without a noise estimate),
    /// the noise at least the rounding to the image's gray-level steps
    /// ([`Sampler::rounding_variance`]).
    pub fn new(corr: &Correlation, lambda: &[f64], sampler: &Sampler) -> Option<Self> {
        let noise = corr
            .noise_var()
            .filter(|v| *v > 0.0)?
            .max(sampler.rounding_variance());
        let bins = corr.residual_bins(lambda, sampler, BIN);
        if bins.is_empty() {
            return None;
        }
        let reach = ((0.25 * corr.basis().element_length() / BIN).round() as usize).max(1);
        Some(ResidualMisfit {
            bins,
            noise,
            reach,
            closed: corr.basis().is_closed(),
        })
    }

    /// The factor on the noise variance for residuals correlated along
    /// the curve ([`super::correlated`]), on the displacement's `basis`.
    /// The bins where the misfit term speaks are left out.
    pub fn correlation_factor(&self, basis: &crate::spline::Basis) -> f64 {
        let misfit: Vec<bool> = (0..self.bins.len())
            .map(|k| self.at((k as f64 + 0.5) * BIN) > 0.0)
            .collect();
        super::correlated::noise_correlation_factor(&self.bins, &misfit, self.noise, basis, BIN)
    }

    /// The misfit's RMS displacement near reference parameter `u`, pixels
    /// (0 where the residuals are those of noise).
    pub fn at(&self, u: f64) -> f64 {
        let n = self.bins.len();
        let k = ((u.max(0.0) / BIN) as usize).min(n - 1);
        let (mut sum, mut info, mut count) = (0.0, 0.0, 0.0);
        for off in -(self.reach as isize)..=self.reach as isize {
            let j = k as isize + off;
            let j = if self.closed {
                j.rem_euclid(n as isize) as usize
            } else if (0..n as isize).contains(&j) {
                j as usize
            } else {
                continue;
            };
            let b = &self.bins[j];
            sum += b.projected;
            info += b.info;
            count += 1.0;
        }
        // The window's request `sum / info` has variance `noise / info`
        // under noise alone.
        if count == 0.0
            || info <= 0.0
            || sum * sum / info <= REQUEST_SIGNIFICANCE.powi(2) * self.noise
        {
            return 0.0;
        }
        (sum / info).abs()
    }
}

/// The oscillation of the displacement `u` (values at points about `step`
/// pixels apart along the reference, closed or not) at each point, at the
/// span `span` (pixels): `|D(a) - 0.4 D(2a) + D(3a) / 15|` with `D(k) =
/// u_i - (u_{i-k} + u_{i+k}) / 2` (0 where an open curve's end is nearer
/// than `3a`, and everywhere on a curve shorter than `6a`).
pub(super) fn oscillation(u: &[f64], step: f64, span: f64, closed: bool) -> Vec<f64> {
    let n = u.len();
    let m = ((span / step).round() as usize).max(1);
    let mut out = vec![0.0; n];
    if 6 * m >= n {
        return out;
    }
    let at = |i: usize, off: isize| -> Option<f64> {
        let j = i as isize + off;
        if closed {
            Some(u[j.rem_euclid(n as isize) as usize])
        } else {
            (0..n as isize).contains(&j).then(|| u[j as usize])
        }
    };
    for (i, o) in out.iter_mut().enumerate() {
        let d = |k: isize| -> Option<f64> { Some(u[i] - 0.5 * (at(i, -k)? + at(i, k)?)) };
        let mi = m as isize;
        if let (Some(d1), Some(d2), Some(d3)) = (d(mi), d(2 * mi), d(3 * mi)) {
            *o = (d1 - 0.4 * d2 + d3 / 15.0).abs();
        }
    }
    out
}

/// The oscillation misfit at point `i`: the largest oscillation within
/// `m` points of it, as an amplitude (pixels), when it exceeds
/// `OSCILLATION_SIGNIFICANCE` times the noise `sigma` there; else 0.
pub(super) fn oscillation_at(osc: &[f64], i: usize, m: usize, sigma: f64, closed: bool) -> f64 {
    let n = osc.len();
    let mut worst: f64 = 0.0;
    for off in -(m as isize)..=m as isize {
        let j = i as isize + off;
        let j = if closed {
            j.rem_euclid(n as isize) as usize
        } else if (0..n as isize).contains(&j) {
            j as usize
        } else {
            continue;
        };
        worst = worst.max(osc[j]);
    }
    if worst > OSCILLATION_SIGNIFICANCE * sigma {
        worst / OSCILLATION_GAIN
    } else {
        0.0
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// A smooth displacement (a slow wave and a quartic, 300 points 1 px
    /// apart) shows no oscillation at 9 px; an alternating one of
    /// wavelength `2a` shows `2.13` times its amplitude.
    #[test]
    fn the_oscillation_of_the_displacement_ignores_smooth_changes() {
        let n = 300;
        let smooth: Vec<f64> = (0..n)
            .map(|i| {
                let s = i as f64;
                0.3 * (s / 40.0).sin() + 1e-9 * (s - 150.0).powi(4)
            })
            .collect();
        let osc = oscillation(&smooth, 1.0, 9.0, false);
        let worst = osc.iter().fold(0.0f64, |m, v| m.max(*v));
        assert!(worst < 1e-4, "smooth: {worst}");
        assert_eq!(osc[10], 0.0, "an end nearer than 3a is left out");

        let amplitude = 1e-3;
        let wave: Vec<f64> = (0..n)
            .map(|i| amplitude * (std::f64::consts::PI * i as f64 / 9.0).cos())
            .collect();
        let osc = oscillation(&wave, 1.0, 9.0, true);
        let worst = osc.iter().fold(0.0f64, |m, v| m.max(*v));
        assert!(
            (worst / amplitude - OSCILLATION_GAIN).abs() < 0.05,
            "wave: {}",
            worst / amplitude
        );
    }
}
