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
//!   curve: a star's own lobes have detail at the elements' scale too,
//!   which a check of the curve takes for an oscillation, and a settled
//!   curve that repeats itself holds none of it in `U`. The second differences of `U` at spans `a`, `2a` and `3a`
//!   (`a` the element length) combine to `D(a) - 0.4 D(2a) + D(3a) / 15`,
//!   which cancels the terms in `a^2` and `a^4` of a smooth `U` and is
//!   `2.13 A` for an oscillation of amplitude `A` and wavelength `2a`;
//!   under noise alone it is about the position's `sigma`. Beyond
//!   `OSCILLATION_SIGNIFICANCE` times that, `|.| / 2.13`, the largest
//!   within a span, is the misfit there.
//!
//! Both estimate a misfit's size from a linearised request, which falls
//! short of a large one (a curve whose elements cannot follow a star's
//! lobes stays pixels off it while its requests say tenths). On
//! silhouettes the **level crossing** settles it ([`EdgeCheck`]): the image
//! is read along each sample's normal across the band, and the half level
//! `a + c / 2` crossed nearest the curve is where the image puts the edge;
//! at a flagged sample its distance is the misfit at least. A band that
//! holds no crossing (or whose levels have no contrast) sees no edge: the
//! curve left it there, which no residual shows, as the band sees only a
//! plateau. Where the levels may not be fitted yet (a fit stopped by its
//! iteration limit), the band's own range across the normal
//! ([`band_range`]) tells a plateau from an edge instead.

use crate::band::BlurredCurvature;
use crate::correlation::{Correlation, ResidualBin};
use crate::curve::SplineCurve;
use crate::interp::Sampler;
use crate::virtual_image::pixel_edge::spread_variance;
use crate::virtual_image::Profile;

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
/// Step of the level-crossing search along the normal, pixels.
const CROSSING_STEP: f64 = 0.25;
/// The crossing's offset counts beyond this many of its noise standard
/// deviations.
const CROSSING_SIGNIFICANCE: f64 = 3.0;
/// ... and beyond this many pixels: the half level of the interpolated
/// image lies up to 0.08 px from a focused edge that the model places
/// exactly (the cubic interpolant's overshoot at a step; far less under a
/// blur; tested on exact-coverage discs). Smaller misfits are the
/// requests' to measure; this check is for those they cannot.
const CROSSING_FLOOR: f64 = 0.1;

/// The residual check, prepared once for a result.
pub(super) struct ResidualMisfit {
    bins: Vec<ResidualBin>,
    /// Per-pixel noise variance, gray levels squared.
    noise: f64,
    /// The image's own noise variance (its pixel noise, at least the
    /// rounding to its gray levels), gray levels squared.
    image_noise: f64,
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
        let image_noise = sampler
            .pixel_noise()
            .powi(2)
            .max(sampler.rounding_variance());
        Some(ResidualMisfit {
            bins,
            noise,
            image_noise,
            reach,
            closed: corr.basis().is_closed(),
        })
    }

    /// The factor on the noise variance for residuals correlated along
    /// the curve ([`super::correlated`]), on the displacement's `basis`;
    /// with `lower`, also for residuals smaller than the noise estimate
    /// says, down to the image's own noise (else at least 1). The bins
    /// where the misfit term speaks are left out.
    pub fn correlation_factor(&self, basis: &crate::spline::Basis, lower: bool) -> f64 {
        let misfit: Vec<bool> = (0..self.bins.len())
            .map(|k| self.at((k as f64 + 0.5) * BIN) > 0.0)
            .collect();
        let floor = if lower {
            self.image_noise / self.noise
        } else {
            1.0
        };
        super::correlated::noise_correlation_factor(
            &self.bins,
            &misfit,
            (self.noise, floor),
            basis,
            BIN,
        )
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

/// The level-crossing check of a silhouette's samples (module docs),
/// prepared once for a result.
pub(super) struct EdgeCheck<'a> {
    sampler: &'a Sampler,
    reference: &'a SplineCurve,
    corr: &'a Correlation,
    /// Half-width of the band searched, pixels.
    half_width: f64,
    /// The spread's variance `v` of a pixel-edge profile, whose half level
    /// lies `v kappa / 2` off the edge it places (px^2; 0 for the paper's
    /// profile, whose curve is the half level), where the profile's own
    /// level at the curve is not at hand ([`Self::level_at`]).
    variance: f64,
    /// The noise's standard deviation per pixel, gray levels.
    noise: f64,
    /// A pixel-edge profile and the reference's curvature averaged over
    /// its blur, for its own level at the curve ([`Self::level_at`]).
    level: Option<(Profile, BlurredCurvature)>,
}

impl<'a> EdgeCheck<'a> {
    /// The check of the result of `corr` on `reference` (band half-width
    /// `half_width`, pixels) on the image of `sampler`, for a pixel-edge
    /// profile of optical blur `blur` (pixels; `None` for the paper's
    /// profile). `None` without a noise estimate.
    pub fn new(
        sampler: &'a Sampler,
        reference: &'a SplineCurve,
        corr: &'a Correlation,
        half_width: f64,
        blur: Option<f64>,
    ) -> Option<Self> {
        let noise = corr.noise_var()?.max(sampler.rounding_variance()).sqrt();
        let profile = corr.band().profile();
        let curvature = match profile {
            Profile::PixelEdge { blur, .. } => BlurredCurvature::new(reference, blur),
            Profile::PixelLine { .. } | Profile::Paper { .. } => None,
        };
        Some(EdgeCheck {
            sampler,
            reference,
            corr,
            half_width,
            variance: blur.map_or(0.0, spread_variance),
            noise,
            level: curvature.map(|table| (profile, table)),
        })
    }

    /// The profile's own level at the curve (0 to 1 of the contrast) at
    /// reference parameter `u` whose normal is `normal`: the pixel edge's
    /// through the reference's curvature averaged over the blur and its
    /// blurred osculating circle (`virtual_image::pixel_edge::curved_edge`),
    /// else 1/2 (a straight edge's half level).
    fn level_at(&self, u: f64, normal: [f64; 2]) -> f64 {
        match &self.level {
            Some((profile, table)) => {
                let curvature = (table.at(u), table.osculating_at(u));
                profile.eval_at(0.0, self.half_width, normal, curvature).0
            }
            None => 0.5,
        }
    }

    /// How far the image's edge lies from the measured point `x0(u) + U
    /// n(u)` (reference parameter `u`, displacement `displacement` px),
    /// pixels, where that is beyond the crossing's noise and
    /// `CROSSING_FLOOR`: the offset along the normal of the half level
    /// crossed nearest the point, less the profile's own offset of it; 0
    /// where the offset is within the noise or the floor. `None` where the
    /// band holds no edge: no crossing within the half-width, or levels
    /// without contrast (the varying levels of a band on a plateau have
    /// none).
    pub fn at(&self, u: f64, displacement: f64) -> Option<f64> {
        let (a, c) = self.corr.levels_at(u)?;
        if c.abs() <= CROSSING_SIGNIFICANCE * self.noise {
            return None;
        }
        let f = self.reference.frame(u);
        // The level the profile itself has at the curve: a dot a blur or
        // so across never reaches its straight edge's half level inside
        // when its contrast is low, and its level at the edge lies far
        // from that level's first-order shift `v kappa / 2`.
        let exact = self.level.is_some();
        let half = a + self.level_at(u, f.normal) * c;
        let value = |t: f64| {
            let along = displacement + t;
            self.sampler.value(
                f.point[0] + along * f.normal[0],
                f.point[1] + along * f.normal[1],
            )
        };
        let t = nearest_crossing(self.half_width, half, &value)?;
        // The gradient across one pixel at the crossing sets its noise.
        let slope = match (value(t + 0.5), value(t - 0.5)) {
            (Some(p), Some(m)) => (p - m).abs(),
            _ => return Some(0.0),
        };
        let offset = if exact {
            t
        } else {
            t - 0.5 * self.variance * f.curvature
        };
        let significant = (CROSSING_SIGNIFICANCE * self.noise / slope).max(CROSSING_FLOOR);
        Some(if slope > 0.0 && offset.abs() > significant {
            offset.abs()
        } else {
            0.0
        })
    }
}

/// A band whose image varies by less than this many noise deviations
/// sees a plateau (`Schedule::check_plateau`): the cubic interpolant of
/// white noise spans up to about 7 along a 40 px band (tested).
pub(super) const PLATEAU_NOISE: f64 = 10.0;
/// ... or by less than this fraction of the edge's contrast.
pub(super) const PLATEAU_CONTRAST: f64 = 0.25;
/// An iteration-limit result whose plateaus make up this share of its
/// samples is off the edge, however short each one.
pub(super) const PLATEAU_SHARE: f64 = 0.25;

/// The range of the image (largest less smallest interpolated value, gray
/// levels) along the normal `n` through `p` over `half_width` pixels on
/// each side, read `CROSSING_STEP` apart (0 where none of it is in the
/// image): how much a band there can see of any edge. A plateau's is a
/// few noise deviations; a band across an edge sees its contrast.
pub(super) fn band_range(sampler: &Sampler, p: [f64; 2], n: [f64; 2], half_width: f64) -> f64 {
    let steps = (half_width / CROSSING_STEP).ceil() as i64;
    let (lo, hi) = (-steps..=steps)
        .filter_map(|k| {
            let t = k as f64 * CROSSING_STEP;
            sampler.value(p[0] + t * n[0], p[1] + t * n[1])
        })
        .fold((f64::INFINITY, f64::NEG_INFINITY), |(lo, hi), v| {
            (lo.min(v), hi.max(v))
        });
    if hi >= lo {
        hi - lo
    } else {
        0.0
    }
}

/// The offset `t` (pixels, within `half_width` of 0) nearest 0 at which
/// `value(t)` crosses `half`, by linear interpolation between samples
/// `CROSSING_STEP` apart; `None` if it does not within the band (or only
/// where `value` is `None`, outside the image).
fn nearest_crossing(
    half_width: f64,
    half: f64,
    value: &impl Fn(f64) -> Option<f64>,
) -> Option<f64> {
    let steps = (half_width / CROSSING_STEP).ceil() as i64;
    let at = |k: i64| value(k as f64 * CROSSING_STEP).map(|v| v - half);
    let crossing = |k0: i64, k1: i64| -> Option<f64> {
        let (d0, d1) = (at(k0)?, at(k1)?);
        if d0 == 0.0 {
            return Some(k0 as f64 * CROSSING_STEP);
        }
        ((d0 < 0.0) != (d1 < 0.0)).then(|| {
            let w = d0 / (d0 - d1);
            (k0 as f64 + w * (k1 - k0) as f64) * CROSSING_STEP
        })
    };
    // Outwards from 0, one step each side in turn.
    (0..steps).find_map(|k| crossing(k, k + 1).or_else(|| crossing(-k, -k - 1)))
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
    use crate::interp::Interpolation;
    use crate::render::{render, Method, RenderSpec};
    use crate::truth::Shape;
    use crate::virtual_image::Kind;

    /// The basis of `CROSSING_FLOOR`: on exact-coverage discs (r = 150, 16
    /// bits), whose edge the pixel-edge profile places exactly, the cubic
    /// interpolant's half level, less the profile's curvature offset of
    /// it, lies within the floor of the edge when focused (the
    /// interpolant's overshoot at a step), within a twentieth of it at a
    /// blur of 1 px and a two-hundredth at 4 px, all round.
    #[test]
    fn the_half_level_lies_within_the_floor_of_an_exact_edge() {
        let (cx, cy, r) = (200.3, 199.6, 150.0);
        for (blur, bound) in [
            (0.0, CROSSING_FLOOR),
            (1.0, 0.05 * CROSSING_FLOOR),
            (4.0, 0.005 * CROSSING_FLOOR),
        ] {
            let spec = RenderSpec {
                width: 400,
                height: 400,
                shape: Shape::Circle { cx, cy, r },
                kind: Kind::Silhouette,
                method: Method::Coverage,
                foreground: 0.8,
                background: 0.2,
                blur_sigma: blur,
                noise: 0.0,
                seed: 1,
                bits: Some(16),
                ..RenderSpec::default()
            };
            let sampler = Sampler::new(&render(&spec).unwrap(), Interpolation::CubicBSpline);
            let worst = (0..720)
                .map(|k| {
                    let a = k as f64 * std::f64::consts::TAU / 720.0;
                    let n = [a.cos(), a.sin()];
                    let p = [cx + r * n[0], cy + r * n[1]];
                    let value = |t: f64| sampler.value(p[0] + t * n[0], p[1] + t * n[1]);
                    let t = nearest_crossing(3.0, 0.5, &value).unwrap();
                    // The outward normal: the half level lies `v / (2 r)` in.
                    (t + 0.5 * spread_variance(blur) / r).abs()
                })
                .fold(0.0, f64::max);
            println!("blur {blur}: half level within {worst:.2e} px of the edge");
            assert!(worst < bound, "blur {blur}: {worst}");
        }
    }

    /// A band's range on white noise stays under `PLATEAU_NOISE`
    /// deviations (the largest of 400 bands 40 px long: 6.6), and across
    /// an edge it is the contrast.
    #[test]
    fn a_plateau_s_band_range_is_a_few_noise_deviations() {
        let sigma = 0.01;
        let spec = RenderSpec {
            width: 200,
            height: 200,
            shape: Shape::Circle {
                cx: 100.3,
                cy: 99.6,
                r: 40.0,
            },
            kind: Kind::Silhouette,
            method: Method::Coverage,
            foreground: 0.8,
            background: 0.2,
            blur_sigma: 1.0,
            noise: sigma / 0.6,
            seed: 5,
            bits: None,
            ..RenderSpec::default()
        };
        let sampler = Sampler::new(&render(&spec).unwrap(), Interpolation::CubicBSpline);
        let noise = sampler.pixel_noise();
        let worst = (0..400)
            .map(|k| {
                let a = k as f64 * 0.37;
                let p = [30.0 + (k % 20) as f64 * 7.0, 160.0 + (k / 20) as f64];
                band_range(&sampler, p, [a.cos(), a.sin()], 20.0) / noise
            })
            .fold(0.0, f64::max);
        println!("noise {noise:.4}: a plateau's band range up to {worst:.2} deviations");
        assert!(worst < 0.8 * PLATEAU_NOISE, "{worst}");
        let across = band_range(&sampler, [140.3, 99.6], [1.0, 0.0], 5.0);
        assert!((across - 0.6).abs() < 0.05, "{across}");
    }

    /// The crossing nearest 0, interpolated; none beyond the band.
    #[test]
    fn the_nearest_crossing_of_the_half_level() {
        let step = |t: f64| Some((t - 0.3).tanh());
        let t = nearest_crossing(5.0, 0.0, &step).unwrap();
        assert!((t - 0.3).abs() < 2e-3, "{t}");
        // Two crossings: the nearer one, on either side.
        let two = |t: f64| Some((t + 1.2) * (t - 2.0));
        let t = nearest_crossing(5.0, 0.0, &two).unwrap();
        assert!((t + 1.2).abs() < 0.05, "{t}");
        assert_eq!(nearest_crossing(1.0, 0.0, &two), None);
        assert_eq!(nearest_crossing(5.0, 0.0, &|_| None), None);
    }

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
