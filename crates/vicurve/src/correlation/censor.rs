//! Pixels the image's encoding clipped: a censored fit.
//!
//! An 8- or 16-bit camera records light beyond its brightest level as that
//! level (a saturated backlight, a specular glint) and light below its
//! darkest as 0 ([`Sampler::clip_levels`]). Such a pixel says only that
//! its light was at least (at most) the clip level. Fitted as a value, a
//! clipped plateau holds the edge's profile down to the clip: a backlight
//! at 1.2 to 1.6 times the clip level moved a blurred edge by 0.5 to 1.3
//! px, at 50 to 110 times its `sigma`.
//!
//! The pushed fit instead compares the virtual image with what a clipped
//! pixel's light is expected to be, given that it was clipped: for the
//! virtual image `g`, image noise `s` and clip level `L` (bright), `E[g +
//! n | g + n >= L] = g + s phi(z) / Phi(-z)` with `z = (L - g) / s` (the
//! step of the EM algorithm for censored least squares, whose fixed point
//! is the censored maximum likelihood). Where the virtual image lies well
//! beyond the clip the pixel agrees with it (it is left out); where it
//! falls well short the pixel counts at the clip level, as any other.
//! Before the first levels every clipped pixel is left out. Unclipped
//! pixels are compared as they are, so an image with no pixel at a clip
//! level is fitted exactly as before.
//!
//! [`Sampler::clip_levels`]: crate::interp::Sampler::clip_levels

/// Beyond this many noise deviations past its clip level, a virtual
/// image agrees with a clipped pixel whatever its light: the pixel is
/// left out (the expectation above differs from `g` by under `1e-8 s`).
const AGREES: f64 = 6.0;

/// The clipped band pixels of a pushed fit and the image's noise.
#[derive(Clone, Debug)]
pub(crate) struct Censored {
    /// Per band pixel: `+1` at the bright clip level, `-1` at the dark
    /// one, 0 not clipped.
    flags: Vec<i8>,
    /// Standard deviation of the image's noise, gray levels (0: none).
    noise: f64,
}

impl Censored {
    /// The band pixels among `values` at a clip level of `clip` (dark,
    /// bright), with the image's `noise()` (gray levels; asked for only
    /// when some are); `None` when none is.
    pub(crate) fn find(
        values: &[f64],
        (low, high): (f64, f64),
        noise: impl FnOnce() -> f64,
    ) -> Option<Censored> {
        if !values.iter().any(|&v| v >= high || v <= low) {
            return None;
        }
        let noise = noise();
        let flags = values
            .iter()
            .map(|&v| match v {
                v if v >= high => 1,
                v if v <= low => -1,
                _ => 0,
            })
            .collect();
        let noise = if noise.is_finite() {
            noise.max(0.0)
        } else {
            0.0
        };
        Some(Censored { flags, noise })
    }

    /// How many band pixels are clipped.
    pub(crate) fn count(&self) -> usize {
        self.flags.iter().filter(|&&k| k != 0).count()
    }

    /// Whether band pixel `i` is clipped.
    pub(crate) fn is_clipped(&self, i: usize) -> bool {
        self.flags[i] != 0
    }

    /// Take the image noise `sd` (gray levels) the fit's residuals give:
    /// the image-wide estimate the search started from reads a saturated
    /// plateau as noiseless.
    pub(crate) fn set_noise(&mut self, sd: f64) {
        if sd.is_finite() && sd >= 0.0 {
            self.noise = sd;
        }
    }
}

/// The value band pixel `i` (recorded as `value`) is compared with when
/// the virtual image there is `model()` (`None`: no levels yet; called
/// for a clipped pixel only, so that the fit's loop over an unclipped
/// band evaluates no model for it): `value` for a pixel not clipped; for
/// a clipped one, its light's expectation given the clip (module docs),
/// or `None` (left out) before the first levels and where the virtual
/// image lies far beyond the clip.
#[inline]
pub(crate) fn observed(
    censored: Option<&Censored>,
    i: usize,
    value: f64,
    model: impl FnOnce() -> Option<f64>,
) -> Option<f64> {
    let Some(c) = censored else {
        return Some(value);
    };
    let sign = f64::from(c.flags[i]);
    if sign == 0.0 {
        return Some(value);
    }
    let g = model()?;
    // How far short of the clip the virtual image falls, in noise
    // deviations (negative beyond it).
    let short = sign * (value - g);
    if c.noise == 0.0 {
        return (short > 0.0).then_some(value);
    }
    let z = short / c.noise;
    if z < -AGREES {
        return None;
    }
    Some(g + sign * c.noise * mills(z))
}

/// The inverse Mills ratio `phi(z) / Phi(-z)` of the standard normal:
/// about `z` for large `z`, 0 for very negative ones.
fn mills(z: f64) -> f64 {
    if z > 30.0 {
        // Asymptotic: z + 1/z - 2/z^3 (Phi(-z) underflows).
        return z + 1.0 / z - 2.0 / (z * z * z);
    }
    let pdf = (-0.5 * z * z).exp() / (2.0 * std::f64::consts::PI).sqrt();
    let tail = 0.5 * libm::erfc(z / std::f64::consts::SQRT_2);
    pdf / tail
}

#[cfg(test)]
mod tests {
    use super::*;

    /// The inverse Mills ratio against a numerical integral of the
    /// truncated normal's mean, and its asymptote.
    #[test]
    fn mills_ratio_is_the_truncated_mean() {
        for z in [-3.0, -1.0, 0.0, 0.5, 2.0, 5.0] {
            // E[X | X >= z] for a standard normal X, by Simpson's rule.
            let (hi, n) = (z + 12.0, 20_000);
            let num = crate::psf::simpson(z, hi, n, |x| x * (-0.5 * x * x).exp());
            let den = crate::psf::simpson(z, hi, n, |x| (-0.5 * x * x).exp());
            assert!(
                (mills(z) - num / den).abs() < 1e-9,
                "z {z}: {} vs {}",
                mills(z),
                num / den
            );
        }
        assert!((mills(30.0) - mills(30.0 + 1e-12)).abs() < 1e-6);
        assert!((mills(29.999) - (29.999 + 1.0 / 29.999)).abs() < 1e-4);
    }

    /// Unclipped pixels and images without clipped pixels are compared as
    /// they are; a clipped pixel counts at its level where the virtual
    /// image falls far short of it, is left out far beyond it, and takes
    /// the truncated mean in between.
    #[test]
    fn a_clipped_pixel_is_compared_with_its_expected_light() {
        assert_eq!(observed(None, 0, 0.5, || None), Some(0.5));
        let c = Censored::find(&[0.5, 1.0, 0.0], (0.0, 1.0), || 0.01).unwrap();
        assert_eq!(observed(Some(&c), 0, 0.5, || Some(0.3)), Some(0.5));
        assert_eq!(observed(Some(&c), 1, 1.0, || None), None);
        assert!((observed(Some(&c), 1, 1.0, || Some(0.5)).unwrap() - 1.0).abs() < 1e-3);
        assert_eq!(observed(Some(&c), 1, 1.0, || Some(1.1)), None);
        let at = observed(Some(&c), 1, 1.0, || Some(1.0)).unwrap();
        assert!((at - (1.0 + 0.01 * (2.0 / std::f64::consts::PI).sqrt())).abs() < 1e-12);
        let dark = observed(Some(&c), 2, 0.0, || Some(0.0)).unwrap();
        assert!((dark + 0.01 * (2.0 / std::f64::consts::PI).sqrt()).abs() < 1e-12);
        assert!(Censored::find(&[0.5, 0.7], (0.0, 1.0), || 0.01).is_none());
        let sharp = Censored::find(&[1.0], (0.0, 1.0), || 0.0).unwrap();
        assert_eq!(observed(Some(&sharp), 0, 1.0, || Some(0.9)), Some(1.0));
        assert_eq!(observed(Some(&sharp), 0, 1.0, || Some(1.0)), None);
    }
}
