//! Automatic element length of the last stage: halve the elements on the
//! same reference while the finer curve differs from the coarser one by
//! more than the noise explains.

use super::blur::{settle_noise_gain, settle_shape_gain};
use super::run::{iterate_to_end, Run, RunLimits, RunLog};
use super::{breaks, FitConfig, IterationRecord, RunKind};
use crate::band::Band;
use crate::correlation::{Correlation, Step};
use crate::curve::SplineCurve;
use crate::error::Result;
use crate::interp::Sampler;
use crate::spline::{Basis, MAX_DEGREE};
use crate::virtual_image::Profile;

/// A converged fit on one reference: its system, coefficients and last step.
pub(super) struct Fitted {
    /// The system the fit ran on.
    pub corr: Correlation,
    /// Its coefficients, pixels.
    pub lambda: Vec<f64>,
    /// Its last step.
    pub step: Step,
}

/// The band a refinement builds: half-width (pixels) and profile.
#[derive(Clone, Copy, Debug)]
pub(super) struct RefineBand {
    /// Band half-width, pixels.
    pub half_width: f64,
    /// The stage's virtual profile.
    pub profile: Profile,
    /// Whether the fit's own band is that band (unthinned, no margin; see
    /// `Band::rebased` for when it is reused): it is then rebased on the
    /// finer basis instead of built again.
    pub reuse: bool,
}

/// Refine `fit` on `reference` down to elements of `shortest` pixels.
///
/// With nested spline spaces the mean squared difference between the two
/// normal positions is about `rep^2 + (sigma_f^2 - sigma_c^2)`, where `rep`
/// is the coarse curve's shape (representation) error and `sigma` the noise
/// scatter of each fit. Refining lowers the total error `rep^2 + sigma^2`
/// when `rep^2 > sigma_f^2 - sigma_c^2` (the fine error being ~rep/16 for
/// cubics), i.e. when the difference exceeds twice the noise increase. The
/// noise variance comes from [`Correlation::estimate_noise`], which excludes
/// the systematic mismatch between the profiles. A shape error also shrinks
/// fast with the element length (16 times per halving for cubics, 4 for
/// linear elements); differences driven by noise or by the aliasing of a
/// sharp edge on the pixel grid do not, so refinement also stops when the
/// change is not at least halved (RMS) from one halving to the next.
///
/// A pushed profile (pixel edge or line) is followed by settles, which
/// amplify both terms ([`super::blur`]): each fit's noise by
/// `settle_noise_gain` of its elements, and the coarse curve's shape error,
/// left at about the coarse elements' own scale, by `settle_shape_gain`.
/// Refining then pays when the amplified `rep^2` exceeds the amplified
/// noise increase; without settles both gains are 1 and the rule is the
/// one above. (The shape error of elements too long for a blurred star's
/// bays is small in one fit, and the settles make it a wiggle.)
///
/// Returns the fit kept, the iterations used, and the kept elements' shape
/// error when a rejected refinement measured one ([`kept_shape_error`]).
pub(super) fn refine(
    reference: &SplineCurve,
    fit: Fitted,
    shortest: f64,
    sampler: &Sampler,
    config: &FitConfig,
    band: RefineBand,
    history: &mut Vec<IterationRecord>,
) -> Result<(Fitted, usize, Option<f64>)> {
    let Fitted {
        mut corr,
        mut lambda,
        mut step,
    } = fit;
    let closed = reference.is_closed();
    let min_el = super::schedule::min_elements(closed, config.degree, true);
    let length = reference.param_length();
    let params = reference.sample_params((length.ceil() as usize).max(8));
    let mut iterations = 0;
    let mut previous_diff2 = f64::INFINITY;
    let mut shape_error = None;
    // Halvings of the first elements reach `shortest` up to the rounding of
    // their count (`Stage::element_count`): elements `longest` long
    // halve down to `shortest` whether that count rounded up or down.
    let rounding = 0.5 / corr.basis().n_elements() as f64;
    // Pixels of curve per unit of parameter (element lengths are in the
    // latter, `shortest` in the former).
    let speed = reference.arc_length() / length;
    corr.estimate_noise(&lambda, sampler);
    loop {
        let coarse = corr.basis().element_length();
        let Some(h) = finer_length(coarse, shortest / speed, rounding) else {
            break;
        };
        let n_el = ((length / h).round() as usize).max(min_el);
        let basis = breaks::displacement_basis(reference, config.degree, n_el)?;
        let reusable = band.reuse
            && corr.band().margin() == 0.0
            && !corr.band().is_bent()
            && !corr.reweighted();
        let rebased = reusable.then(|| corr.band().rebased(&basis));
        let Ok(built) = rebased.map(Ok).unwrap_or_else(|| {
            Band::build_with(
                reference,
                &basis,
                band.half_width,
                band.profile,
                sampler.width(),
                sampler.height(),
                1,
                config.coords,
            )
        }) else {
            break;
        };
        let Ok(mut fine) = Correlation::prepare(built, basis, sampler, config.levels, None) else {
            break;
        };
        let mut fine_lambda = vec![0.0; fine.n_unknowns()];
        let mut fine_step = None;
        let (end, used) = iterate_to_end(
            &mut fine,
            &mut fine_lambda,
            sampler,
            config,
            RunLimits::refit(config, band.half_width),
            &mut fine_step,
            RunLog {
                history: &mut *history,
                kind: RunKind::Refine,
            },
        );
        iterations += used;
        let (Run::Converged, Some(fs)) = (end, fine_step) else {
            break;
        };
        fine.estimate_noise(&fine_lambda, sampler);
        // The settles that follow a pushed profile amplify each fit's
        // noise, the more the shorter its elements, and the coarse
        // curve's shape error.
        let settled = match band.profile {
            Profile::PixelEdge { blur } | Profile::PixelLine { blur, .. } => Some(blur),
            Profile::Paper { .. } => None,
        };
        let gain = |basis: &Basis| {
            settled.map_or(1.0, |blur| {
                settle_noise_gain(blur, basis.element_length() * speed)
            })
        };
        // The noise estimate leaves out the rounding to the gray levels,
        // which the settles amplify as they do noise.
        let rounding = |c: &Correlation| settled.map_or(1.0, |_| c.rounding_gain(sampler));
        let (rf, rc) = (rounding(&fine), rounding(&corr));
        let (gf, gc) = (gain(fine.basis()), gain(corr.basis()));
        let (mut diff2, mut noise2, mut settled_noise2) = (0.0, 0.0, 0.0);
        for &u in &params {
            let d = displacement(fine.basis(), &fine_lambda, u)
                - displacement(corr.basis(), &lambda, u);
            diff2 += d * d;
            let (sf, sc) = (rf * fine.position_sigma(u), rc * corr.position_sigma(u));
            noise2 += sf * sf - sc * sc;
            settled_noise2 += (gf * sf).powi(2) - (gc * sc).powi(2);
        }
        // The coarse curve's shape error, as the settles will leave it.
        let shape_gain = settled.map_or(1.0, |blur| {
            settle_shape_gain(blur, corr.basis().element_length() * speed)
        });
        let shape2 = shape_gain * shape_gain * (diff2 - noise2.max(0.0));
        // Significant, and still converging like a shape error (a change
        // that does not shrink is noise or aliasing being chased).
        if diff2 >= 0.25 * previous_diff2 {
            break;
        }
        if shape2 <= settled_noise2.max(0.0) {
            // On a sharp edge the finer fit may chase the pixel grid's
            // aliasing instead: the difference is then not the kept
            // elements' error. A blur of a pixel leaves no aliasing.
            if settled.is_some_and(|blur| blur >= ALIAS_FREE_BLUR) {
                let extra = fine.n_unknowns().saturating_sub(corr.n_unknowns()).max(1);
                shape_error = kept_shape_error(diff2, noise2, extra, shape_gain, params.len());
            }
            break;
        }
        previous_diff2 = diff2;
        (corr, lambda, step) = (fine, fine_lambda, fs);
    }
    Ok((Fitted { corr, lambda, step }, iterations, shape_error))
}

/// The blur (pixels) from which a rejected refinement's difference is
/// taken for the kept elements' shape error ([`kept_shape_error`]): a
/// Gaussian blur of `b` pixels leaves `exp(-2 pi^2 b^2)` of the pixel
/// grid's aliasing, nothing at 1 px.
const ALIAS_FREE_BLUR: f64 = 1.0;

/// The shape error of the elements a refinement kept (RMS over the curve,
/// pixels, amplified by the settles' `shape_gain`), from the difference
/// `diff2` to the finer fit it rejected (a sum over `n` points) and the
/// noise's share of it `noise2`; `None` where the difference is within
/// what `extra` more unknowns' noise makes of it (two standard deviations
/// of a chi-square of `extra` degrees of freedom, `noise2 sqrt(2 /
/// extra)`), which is what a curve the elements follow gives.
///
/// Why: a refinement is rejected when the shape error it would remove
/// costs less than the noise it would add, but that error stays in the
/// result, where the noise-only `sigma` does not count it (a blurred sine
/// edge on elements of 40 px: its scatter 1.5 times its `sigma`).
fn kept_shape_error(
    diff2: f64,
    noise2: f64,
    extra: usize,
    shape_gain: f64,
    n: usize,
) -> Option<f64> {
    let noise2 = noise2.max(0.0);
    let excess = diff2 - noise2;
    (excess > 2.0 * noise2 * (2.0 / extra as f64).sqrt() && n > 0)
        .then(|| shape_gain * (excess / n as f64).sqrt())
}

/// The next element length (parameter units) after `coarse`, down to
/// `shortest`: half of it, or `shortest` itself where half would fall
/// under it (by more than the `rounding` of element counts) and
/// `shortest` is still at most [`LAST_STEP`] of `coarse`; `None` when no
/// finer elements are left to try.
///
/// Why the last step: a stage whose first elements are not a power of two
/// above its shortest (the pixel-edge stage starts from the blur's
/// `shortest_element`, 8.9 px under a 4 px blur, and may go down to 5 px)
/// would otherwise stop a halving short of what it may try.
fn finer_length(coarse: f64, shortest: f64, rounding: f64) -> Option<f64> {
    let half = 0.5 * coarse;
    if half >= shortest * (1.0 - rounding) {
        Some(half)
    } else if shortest <= LAST_STEP * coarse {
        Some(shortest)
    } else {
        None
    }
}

/// The largest ratio of a last, shorter than halving, refinement step
/// ([`finer_length`]): closer lengths differ by little more than the
/// rounding of their element counts.
const LAST_STEP: f64 = 0.75;

/// `U(u)` of a displacement basis and coefficients, pixels.
pub(super) fn displacement(basis: &Basis, lambda: &[f64], u: f64) -> f64 {
    let mut v = [0.0; MAX_DEGREE + 1];
    let first = basis.eval(u, &mut v);
    (0..=basis.degree())
        .map(|k| lambda[basis.index(first, k)] * v[k])
        .sum()
}

#[cfg(test)]
mod tests {
    use super::{finer_length, kept_shape_error};

    /// A difference within two standard deviations of what the extra
    /// unknowns' noise makes is no shape error; beyond, its excess over
    /// the noise, RMS over the points, amplified by the settles' gain.
    #[test]
    fn kept_shape_error_is_the_excess_over_the_noise() {
        let (noise2, extra, n) = (0.2, 32, 1000);
        let bound = noise2 * (1.0 + 2.0 * (2.0 / extra as f64).sqrt());
        assert_eq!(kept_shape_error(0.99 * bound, noise2, extra, 1.0, n), None);
        assert_eq!(kept_shape_error(0.1, noise2, extra, 2.0, n), None);
        let e = kept_shape_error(noise2 + 0.4, noise2, extra, 2.0, n).unwrap();
        assert!((e - 2.0 * (0.4f64 / 1000.0).sqrt()).abs() < 1e-12, "{e}");
        // A negative noise term (a coarser fit noisier than the finer) is
        // no noise.
        let e = kept_shape_error(0.4, -0.1, extra, 1.0, n).unwrap();
        assert!((e - (0.4f64 / 1000.0).sqrt()).abs() < 1e-12, "{e}");
    }

    /// Halving while half stays above the shortest (to the rounding),
    /// then one last step onto the shortest when it is at most
    /// `LAST_STEP` of the current length, then nothing.
    #[test]
    fn finer_lengths_halve_then_land_on_the_shortest() {
        let steps = |mut h: f64, shortest: f64| {
            let mut out = vec![h];
            while let Some(next) = finer_length(h, shortest, 0.002) {
                out.push(next);
                h = next;
            }
            out
        };
        assert_eq!(steps(40.0, 5.0), [40.0, 20.0, 10.0, 5.0]);
        // Half of 10.04 is within the rounding of 5.
        assert_eq!(steps(10.04, 5.0), [10.04, 5.02]);
        assert_eq!(steps(8.9, 5.0), [8.9, 5.0]);
        assert_eq!(steps(9.94, 5.0), [9.94, 5.0]);
        // 5 is more than 0.75 of 6.5: no step worth its fit.
        assert_eq!(steps(6.5, 5.0), [6.5]);
        assert_eq!(steps(5.0, 5.0), [5.0]);
    }
}
