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

use crate::curve::SplineCurve;
use crate::virtual_image::pixel_edge::spread_variance;

/// Spacing of the table's samples along the parameter, pixels.
const STEP: f64 = 0.25;
/// The kernel reaches this many of its standard deviations.
const REACH: f64 = 4.0;

/// The reference's curvature averaged over the blur, sampled along its
/// parameter (see the [module docs](self)).
pub(super) struct BlurredCurvature {
    closed: bool,
    step: f64,
    values: Vec<f64>,
}

impl BlurredCurvature {
    /// The table for `curve` under the optical `blur` (pixels); `None` when
    /// there is no blur to average over.
    pub(super) fn new(curve: &SplineCurve, blur: f64) -> Option<Self> {
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
        let values = (0..count as isize)
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
        Some(BlurredCurvature {
            closed,
            step,
            values,
        })
    }

    /// The averaged curvature at parameter `u`, 1/px (linear between the
    /// samples).
    pub(super) fn at(&self, u: f64) -> f64 {
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

    #[test]
    fn no_blur_no_table() {
        let curve = closed_curve(|_| 50.0);
        assert!(BlurredCurvature::new(&curve, 0.0).is_none());
    }
}
