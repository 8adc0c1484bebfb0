//! An optical blur that is not the same in every direction: astigmatism,
//! motion during the exposure, a lens tilted against the sensor.
//!
//! The blur's covariance (px²) is `blur² I + [[p, q], [q, -p]]`: along a
//! unit vector `u` its variance is `blur² + p (ux² - uy²) + 2 q ux uy`, and
//! the mean over all directions is `blur²`. A profile across an edge sees
//! the variance along the edge's normal (the width of the transition); the
//! curvature shift `v kappa / 2` sees the variance along the tangent (the
//! blur smears the curved edge along itself). With an isotropic model both
//! are the mean, and on an astigmatic image (1 px along x, 2.5 px along y)
//! the measured edge wiggled by 0.8 px on a star's flanks while reporting
//! 0.02 px (`fit/anisotropy.rs` estimates `p` and `q`).

use serde::{Deserialize, Serialize};

/// The anisotropic part `(p, q)` of a blur's covariance, px² (module
/// docs); zero for an isotropic blur.
#[derive(Clone, Copy, Debug, Default, PartialEq, Serialize, Deserialize)]
pub struct Anisotropy {
    /// `p`: half the difference of the variances along x and along y, px².
    pub p: f64,
    /// `q`: the covariance of x and y, px².
    pub q: f64,
}

impl Anisotropy {
    /// An isotropic blur.
    pub const NONE: Anisotropy = Anisotropy { p: 0.0, q: 0.0 };

    /// Whether the blur is isotropic.
    pub fn is_none(&self) -> bool {
        self.p == 0.0 && self.q == 0.0
    }

    /// The variance added along the unit vector `u` (px², negative where
    /// the blur is narrower than its mean).
    #[inline]
    pub fn along(&self, u: [f64; 2]) -> f64 {
        self.p * (u[0] * u[0] - u[1] * u[1]) + 2.0 * self.q * u[0] * u[1]
    }

    /// The covariance it adds between the coordinates along `u` and along
    /// `v` (px²; [`Anisotropy::along`] is `cross(u, u)`).
    #[inline]
    pub fn cross(&self, u: [f64; 2], v: [f64; 2]) -> f64 {
        self.p * (u[0] * v[0] - u[1] * v[1]) + self.q * (u[0] * v[1] + u[1] * v[0])
    }

    /// The largest optical blur over the directions, pixels, of an
    /// isotropic blur `blur` with this anisotropy.
    pub fn largest(&self, blur: f64) -> f64 {
        (blur * blur + self.amplitude()).sqrt()
    }

    /// Half the difference between the largest and smallest variance, px².
    pub fn amplitude(&self) -> f64 {
        self.p.hypot(self.q)
    }

    /// The direction of the largest variance, radians from the x axis
    /// (towards y, i.e. clockwise on screen), in `(-pi/2, pi/2]`.
    pub fn axis(&self) -> f64 {
        0.5 * self.q.atan2(self.p)
    }

    /// The optical blurs along the normal and along the tangent, pixels
    /// (each at least 0), and the covariance of the two (px²), of an
    /// isotropic blur `blur` with this anisotropy at a point of unit normal
    /// `n` (the tangent `(-ny, nx)`).
    #[inline]
    pub fn blurs(&self, blur: f64, n: [f64; 2]) -> (f64, f64, f64) {
        if self.is_none() {
            return (blur, blur, 0.0);
        }
        let (mean, extra) = (blur * blur, self.along(n));
        (
            (mean + extra).max(0.0).sqrt(),
            (mean - extra).max(0.0).sqrt(),
            self.cross(n, [-n[1], n[0]]),
        )
    }
}

impl std::fmt::Display for Anisotropy {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        write!(
            f,
            "{:.3} px² more along {:.1}°",
            2.0 * self.amplitude(),
            self.axis().to_degrees()
        )
    }
}

#[cfg(test)]
mod tests {
    use super::Anisotropy;

    /// A Gaussian of deviations 2.5 along y and 1 along x: blur² = 3.625,
    /// p = -2.625; the normal along y sees 2.5 px and the tangent 1 px, a
    /// diagonal normal sees the mean both ways; the axis is y.
    #[test]
    fn an_astigmatic_blur_along_its_axes_and_between() {
        let a = Anisotropy { p: -2.625, q: 0.0 };
        let blur = 3.625f64.sqrt();
        let (n, t, c) = a.blurs(blur, [0.0, 1.0]);
        assert_eq!(c, 0.0);
        assert!(
            (n - 2.5).abs() < 1e-12 && (t - 1.0).abs() < 1e-12,
            "{n} {t}"
        );
        let d = std::f64::consts::FRAC_1_SQRT_2;
        // A diagonal normal: the axes' difference is the covariance.
        let (n, t, c) = a.blurs(blur, [d, d]);
        assert!((c - 2.625).abs() < 1e-12, "{c}");
        assert!(
            (n - blur).abs() < 1e-12 && (t - blur).abs() < 1e-12,
            "{n} {t}"
        );
        assert!((a.axis().abs() - std::f64::consts::FRAC_PI_2).abs() < 1e-12);
        // A blur along the diagonal: q > 0, axis 45°.
        let m = Anisotropy { p: 0.0, q: 0.5 };
        assert!((m.axis() - std::f64::consts::FRAC_PI_4).abs() < 1e-12);
        assert!(m.blurs(1.0, [d, -d]).0 < 0.71);
    }
}
