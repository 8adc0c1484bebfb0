//! The curvature the pixel-edge profile takes: the reference's, averaged
//! along the curve over the blur.
//!
//! A blurred edge's half level lies `v kappa / 2` inside a circle of
//! curvature `kappa` (`v = blur^2 + 1/12`; [`crate::psf::curvature_shift`]).
//! For an edge whose displacement from a straight line is `a sin(k s)` the
//! blur's exact answer is `a exp(-v k^2 / 2)`; the shift with the local
//! curvature `a k^2 sin(k s)` gives `a (1 - v k^2 / 2)`, the first term
//! only, which is negative past `v k^2 = 2`: the profile then asks for an
//! oscillation the image has erased, and the settles (each re-references on
//! the measured curve) feed it back with gain `v k^2 / 2`, above 1 for the
//! shortest oscillations a pixel-edge stage can describe.
//!
//! The curvature averaged by a Gaussian of variance `v / 2` along the curve
//! gives `a (1 - (v k^2 / 2) exp(-v k^2 / 4))`, which agrees with the blur
//! to the second order in `v k^2` and keeps the loop gain under `2 / e`
//! (0.74) at every wavenumber, and on a circle, or any curve whose
//! curvature varies slowly against the blur, changes nothing.
//!
//! Edge cases: the curve's parameter is taken as its arc length (the
//! references are parametrised by it, to within a fraction of a percent);
//! an open curve's average is taken over the part of the kernel on the
//! curve (renormalised); a closed curve's wraps around; a curve with
//! corners is averaged across them like any other stretch; without blur
//! there is no table and the profile takes the local curvature.
//!
//! # The osculating circle's weight
//! Where the blur is not small against the radius of curvature, the
//! profile adds the rest of the blurred osculating circle
//! (`virtual_image/osculating.rs`), which describes the edge where its
//! curvature holds over the blur: on a small disc, not on a rounded corner
//! or in a star's bay, where the curvature changes within the blur's reach
//! and the osculating circle's higher terms are no better than the
//! expansion's (docs/benchmarks.md, "The blurred osculating circle"). The
//! table also holds, per sample, the weight of those terms: 1 where the
//! averaged curvature stays within [`STEADY`] of its own value over
//! [`STEADY_REACH`] spreads each way along the curve, 0 where it departs
//! by [`UNSTEADY`] (a smooth step between), and 0 wherever they add
//! nothing.

use crate::curve::SplineCurve;
use crate::virtual_image::osculating;
use crate::virtual_image::pixel_edge::spread_variance;

/// Spacing of the table's samples along the parameter, pixels.
const STEP: f64 = 0.25;
/// The kernel reaches this many of its standard deviations.
const REACH: f64 = 4.0;
/// The osculating circle counts in full where the curvature varies by at
/// most this fraction of itself over the blur's reach ...
const STEADY: f64 = 0.1;
/// ... and not at all from this fraction on.
const UNSTEADY: f64 = 0.3;
/// The blur's reach along the curve, in spreads each way.
const STEADY_REACH: f64 = 2.0;

/// The reference's curvature averaged over the blur, sampled along its
/// parameter (see the [module docs](self)).
pub(crate) struct BlurredCurvature {
    closed: bool,
    step: f64,
    values: Vec<f64>,
    /// The osculating circle's weight per sample (module docs); empty
    /// where it is 0 everywhere.
    osculating: Vec<f64>,
}

impl BlurredCurvature {
    /// The table for `curve` under the optical `blur` (pixels); `None` when
    /// there is no blur to average over.
    pub(crate) fn new(curve: &SplineCurve, blur: f64) -> Option<Self> {
        if !(blur.is_finite() && blur > 0.0) {
            return None;
        }
        let v = spread_variance(blur);
        let sd = (0.5 * v).sqrt();
        let l = curve.param_length();
        let closed = curve.is_closed();
        let n = ((l / STEP).ceil() as usize).max(1);
        let step = l / n as f64;
        let count = if closed { n } else { n + 1 };
        let local: Vec<f64> = (0..count)
            .map(|i| curve.frame(i as f64 * step).curvature)
            .collect();
        let half = (REACH * sd / step).ceil() as isize;
        let kernel: Vec<f64> = (-half..=half)
            .map(|j| {
                let t = j as f64 * step / sd;
                (-0.5 * t * t).exp()
            })
            .collect();
        let values: Vec<f64> = (0..count as isize)
            .map(|i| {
                let (mut sum, mut weight) = (0.0, 0.0);
                for (j, w) in (-half..=half).zip(&kernel) {
                    let k = i + j;
                    let at = if closed {
                        k.rem_euclid(count as isize)
                    } else if (0..count as isize).contains(&k) {
                        k
                    } else {
                        continue;
                    };
                    sum += w * local[at as usize];
                    weight += w;
                }
                sum / weight
            })
            .collect();
        let osculating = steadiness(&values, (v, step), closed);
        Some(BlurredCurvature {
            closed,
            step,
            values,
            osculating,
        })
    }

    /// The osculating circle's weight at parameter `u` (0 to 1; that of
    /// the nearest sample).
    pub(crate) fn osculating_at(&self, u: f64) -> f64 {
        if self.osculating.is_empty() {
            return 0.0;
        }
        let n = self.osculating.len() as isize;
        let k = (u / self.step).round() as isize;
        let k = if self.closed {
            k.rem_euclid(n)
        } else {
            k.clamp(0, n - 1)
        };
        self.osculating[k as usize]
    }

    /// The averaged curvature at parameter `u`, 1/px (linear between the
    /// samples).
    pub(crate) fn at(&self, u: f64) -> f64 {
        let n = self.values.len();
        let x = u / self.step;
        let i = x.floor();
        let t = x - i;
        let i = i as isize;
        let get = |k: isize| {
            if self.closed {
                self.values[k.rem_euclid(n as isize) as usize]
            } else {
                self.values[k.clamp(0, n as isize - 1) as usize]
            }
        };
        (1.0 - t) * get(i) + t * get(i + 1)
    }
}

/// The osculating circle's weights (module docs) of the samples of
/// `blurred` curvature (the table's: a spline's ripples of curvature
/// between its knots average out, a rounded corner's change does not),
/// under a spread of variance `v` (px^2), `step` pixels apart; empty when
/// no sample's curvature reaches the circle's correction.
fn steadiness(blurred: &[f64], (v, step): (f64, f64), closed: bool) -> Vec<f64> {
    if !blurred.iter().any(|&k| osculating::applies(v, k)) {
        return Vec::new();
    }
    let n = blurred.len() as isize;
    let half = (STEADY_REACH * v.sqrt() / step).ceil() as isize;
    (0..n)
        .map(|i| {
            let k = blurred[i as usize];
            if !osculating::applies(v, k) {
                return 0.0;
            }
            let mut departs: f64 = 0.0;
            for j in -half..=half {
                let at = if closed {
                    (i + j).rem_euclid(n)
                } else if (0..n).contains(&(i + j)) {
                    i + j
                } else {
                    continue;
                };
                departs = departs.max((blurred[at as usize] - k).abs());
            }
            let x = ((UNSTEADY - departs / k.abs()) / (UNSTEADY - STEADY)).clamp(0.0, 1.0);
            x * x * (3.0 - 2.0 * x)
        })
        .collect()
}

#[cfg(test)]
mod tests {
    use super::*;
    use std::f64::consts::TAU;

    fn closed_curve(r: impl Fn(f64) -> f64) -> SplineCurve {
        let n = 4000;
        let pts: Vec<[f64; 2]> = (0..n)
            .map(|i| {
                let th = TAU * i as f64 / n as f64;
                [300.0 + r(th) * th.cos(), 300.0 + r(th) * th.sin()]
            })
            .collect();
        SplineCurve::fit(&pts, true, 3, 1.0).unwrap()
    }

    #[test]
    fn a_circle_keeps_its_curvature() {
        let curve = closed_curve(|_| 50.0);
        let table = BlurredCurvature::new(&curve, 3.0).unwrap();
        for i in 0..100 {
            let u = curve.param_length() * i as f64 / 100.0;
            let (k, local) = (table.at(u), curve.frame(u).curvature);
            assert!((k - local).abs() < 1e-6, "{k} vs {local}");
            assert!((k.abs() - 0.02).abs() < 1e-4, "{k}");
        }
    }

    #[test]
    fn a_wiggle_is_attenuated_as_a_gaussian_of_variance_v_over_2() {
        // r = 100 + 0.5 cos(20 theta): a wiggle of wavenumber 0.2 rad/px.
        let (m, r0, blur) = (20.0, 100.0, 3.0);
        let curve = closed_curve(|th| r0 + 0.5 * (m * th).cos());
        let table = BlurredCurvature::new(&curve, blur).unwrap();
        let l = curve.param_length();
        // Curvature at the lobes (theta = 2 pi j / m) minus at the bays.
        let swing = |f: &dyn Fn(f64) -> f64| {
            let (mut top, mut bottom) = (0.0, 0.0);
            for j in 0..20 {
                top += f(l * j as f64 / m);
                bottom += f(l * (j as f64 + 0.5) / m);
            }
            (top - bottom) / 20.0
        };
        let local = swing(&|u| curve.frame(u).curvature);
        let averaged = swing(&|u| table.at(u));
        let k = m / r0;
        let v = spread_variance(blur);
        let expected = (-0.25 * v * k * k).exp();
        let ratio = averaged / local;
        assert!((ratio - expected).abs() < 0.01, "{ratio} vs {expected}");
    }

    /// The osculating circle's weight: 1 all round a disc of radius 6 px
    /// under a 2.5 px blur (`q` = 0.42), none on a disc of 50 px under 3
    /// px (0.06, under the correction's start), and on a square with
    /// corners rounded on 3 px under a 2 px blur, 0 at the corners'
    /// middles (curvature from 0 to 1/3 within the blur's reach) while the
    /// sides have none to add.
    #[test]
    fn the_osculating_circle_counts_where_the_curvature_holds() {
        let small = closed_curve(|_| 6.0);
        let table = BlurredCurvature::new(&small, 2.5).unwrap();
        let l = small.param_length();
        for i in 0..50 {
            let u = l * i as f64 / 50.0;
            let w = table.osculating_at(u);
            assert!((w - 1.0).abs() < 1e-12, "{w}");
            // ... and in full there.
            assert!(osculating::in_full(spread_variance(2.5), table.at(u)));
        }
        let large = closed_curve(|_| 50.0);
        let wide = BlurredCurvature::new(&large, 3.0).unwrap();
        let l = large.param_length();
        assert!((0..200).all(|i| wide.osculating_at(l * i as f64 / 200.0) == 0.0));
        // A rounded square: half-side 40 px, corner radius 3 px.
        let (h, c) = (40.0, 3.0);
        let square = closed_curve(|th: f64| {
            // The ray at `th` to the rounded square's boundary.
            let (dx, dy) = (th.cos(), th.sin());
            let (mut lo, mut hi) = (0.0, 2.0 * h);
            for _ in 0..60 {
                let m = 0.5 * (lo + hi);
                let (x, y) = ((m * dx).abs(), (m * dy).abs());
                let (qx, qy) = ((x - (h - c)).max(0.0), (y - (h - c)).max(0.0));
                let inside = x <= h && y <= h && qx.hypot(qy) <= c;
                if inside {
                    lo = m;
                } else {
                    hi = m;
                }
            }
            lo
        });
        let table = BlurredCurvature::new(&square, 2.0).unwrap();
        let l = square.param_length();
        let corners: Vec<f64> = (0..4).map(|k| l * (0.125 + 0.25 * k as f64)).collect();
        for u in corners {
            let w = table.osculating_at(u);
            assert!(osculating::applies(spread_variance(2.0), table.at(u)));
            assert!(w == 0.0, "corner at {u}: weight {w}");
        }
        assert_eq!(table.osculating_at(0.0), 0.0);
    }

    #[test]
    fn no_blur_no_table() {
        let curve = closed_curve(|_| 50.0);
        assert!(BlurredCurvature::new(&curve, 0.0).is_none());
    }
}
