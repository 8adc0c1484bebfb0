//! Automatic element length of the last stage: halve the elements on the
//! same reference while the finer curve differs from the coarser one by
//! more than the noise explains.

use super::blur::{
    one_settle_noise_gain, one_settle_shape_gain, settle_noise_gain, settle_shape_gain,
};
use super::loops::curve_loops;
use super::reference::{next_reference, Ends, CURVE_SPACING};
use super::run::{iterate_to_end, Run, RunLimits, RunLog};
use super::{breaks, FitConfig, IterationRecord, RunKind};
use crate::band::Band;
use crate::buckets::Buckets;
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
    /// Whether `corr`'s noise variance was estimated at `lambda`
    /// ([`Correlation::estimate_noise`]; not carried from another run):
    /// then [`refine`] does not estimate it again.
    pub noise_estimated: bool,
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
/// A last step onto the shortest elements (less than a halving, see
/// [`finer_length`]) of a pushed profile on a closed curve is judged on
/// references of its own: the finer fit and the coarse one each run on the
/// coarse curve refitted with control points their elements apart (a
/// settle of each, [`next_reference`]), and the difference is between the
/// two curves. On the coarse reference the finer fit would be blind to the
/// coarse elements' shape error: the reference holds it at the coarse
/// elements' own period, which elements less than half as long cannot
/// represent, and the profile takes its curvature from the reference. (A
/// disc of radius 10 px on its 8 elements, 4.0e-3 px off a circle, under
/// a blur of 1 px: the step to 13 lowered the residual by 1 % on the
/// coarse reference, by 56 % on its own.) Open curves keep the coarse reference (their trimmed
/// ends belong to the stage); halvings too (their elements represent the
/// coarse period).
///
/// Returns the fit kept, the iterations used, the kept elements' shape
/// error when a rejected refinement measured one ([`kept_shape_error`]),
/// and where along the curve it lies ([`LocalShapeError`]), and the kept
/// fit's reference when it is not `reference`.
pub(super) fn refine(
    reference: &SplineCurve,
    fit: Fitted,
    shortest: f64,
    sampler: &Sampler,
    config: &FitConfig,
    band: RefineBand,
    history: &mut Vec<IterationRecord>,
) -> Result<Refined> {
    let Fitted {
        mut corr,
        mut lambda,
        mut step,
        noise_estimated,
    } = fit;
    let closed = reference.is_closed();
    let min_el = super::schedule::min_elements(closed, config.degree, true);
    let length = reference.param_length();
    let params = reference.sample_params((length.ceil() as usize).max(8));
    let mut iterations = 0;
    let mut previous_diff2 = f64::INFINITY;
    let mut shape_error = None;
    let mut local_shape = None;
    let mut moved = None;
    // Halvings of the first elements reach `shortest` up to the rounding of
    // their count (`Stage::element_count`): elements `longest` long
    // halve down to `shortest` whether that count rounded up or down.
    let rounding = 0.5 / corr.basis().n_elements() as f64;
    // Pixels of curve per unit of parameter (element lengths are in the
    // latter, `shortest` in the former).
    let speed = reference.arc_length() / length;
    // The settles that follow a pushed profile amplify each fit's noise,
    // the more the shorter its elements, and the coarse curve's shape
    // error.
    let settled = match band.profile {
        Profile::PixelEdge { blur, .. } | Profile::PixelLine { blur, .. } => Some(blur),
        Profile::Paper { .. } => None,
    };
    if !noise_estimated {
        corr.estimate_noise(&lambda, sampler);
    }
    // A step on references of its own is the last one (onto `shortest`).
    while moved.is_none() {
        let coarse = corr.basis().element_length();
        let Some(h) = finer_length(coarse, shortest / speed, rounding) else {
            break;
        };
        let halving = (h - 0.5 * coarse).abs() <= 1e-9 * coarse;
        let own = settled.is_some() && closed && !halving && reference.corners().is_empty();
        // The finer fit, and the coarse one it is compared with when that
        // is not the fit given (on references of their own).
        let (fine, baseline) = if own {
            let size = (sampler.width(), sampler.height());
            let on_own = |spacing: f64, n_el: usize, history: &mut Vec<IterationRecord>| {
                own_fit(
                    (reference, corr.basis(), &lambda),
                    (spacing, n_el),
                    size,
                    sampler,
                    config,
                    band,
                    history,
                )
            };
            let n_fine = ((length / h).round() as usize).max(min_el);
            let (fine, used_fine) = on_own((h * speed).max(CURVE_SPACING), n_fine, history);
            let (baseline, used_coarse) = on_own(
                (coarse * speed).max(CURVE_SPACING),
                corr.basis().n_elements(),
                history,
            );
            iterations += used_fine + used_coarse;
            match (fine, baseline) {
                (Some(f), Some(b)) => (f, Some(b)),
                _ => break,
            }
        } else {
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
            let (f, used) = converged_fit(built, basis, sampler, config, band, history);
            iterations += used;
            let Some(f) = f else {
                break;
            };
            (f, None)
        };
        let gain = |basis: &Basis| {
            settled.map_or(1.0, |blur| {
                settle_noise_gain(blur, basis.element_length() * speed)
            })
        };
        // The noise estimate leaves out the rounding to the gray levels,
        // which the settles amplify as they do noise.
        let rounding = |c: &Correlation| settled.map_or(1.0, |_| c.rounding_gain(sampler));
        let coarse_fit = baseline
            .as_ref()
            .map_or((&corr, &lambda[..]), |b| (&b.corr, &b.lambda[..]));
        let (rf, rc) = (rounding(&fine.corr), rounding(coarse_fit.0));
        let (gf, gc) = (gain(fine.corr.basis()), gain(coarse_fit.0.basis()));
        // Fits on references of their own each come after one settle,
        // which has amplified both their noise and the coarse shape error
        // in their difference: the rule counts that settle out.
        let one = |basis: &Basis| match (settled, &baseline) {
            (Some(blur), Some(_)) => one_settle_noise_gain(blur, basis.element_length() * speed),
            _ => 1.0,
        };
        let (of, oc) = (one(fine.corr.basis()), one(coarse_fit.0.basis()));
        let (mut diff2, mut noise2, mut settled_noise2) = (0.0, 0.0, 0.0);
        // Each point's share of `diff2` and `noise2`, for where along the
        // curve a rejected refinement's difference lies.
        let mut point_diff2 = Vec::with_capacity(params.len());
        let mut point_noise2 = Vec::with_capacity(params.len());
        // The same fraction of each reference's parameter (all follow the
        // arc length of about the same curve).
        let base_reference = baseline.as_ref().and_then(|b| b.reference.as_ref());
        let scale = |r: Option<&SplineCurve>| r.map_or(1.0, |r| r.param_length() / length);
        let (kf, kc) = (scale(fine.reference.as_ref()), scale(base_reference));
        for &u in &params {
            let (uf, uc) = (u * kf, u * kc);
            let d = match (&fine.reference, base_reference) {
                (Some(fine_ref), Some(base_ref)) => {
                    let pf = displaced(fine_ref, fine.corr.basis(), &fine.lambda, uf);
                    let f = base_ref.frame(uc);
                    let dc = displacement(coarse_fit.0.basis(), coarse_fit.1, uc);
                    // The normal distance of the finer curve from the coarse.
                    (pf[0] - f.point[0]) * f.normal[0] + (pf[1] - f.point[1]) * f.normal[1] - dc
                }
                _ => {
                    displacement(fine.corr.basis(), &fine.lambda, u)
                        - displacement(coarse_fit.0.basis(), coarse_fit.1, u)
                }
            };
            diff2 += d * d;
            let (sf, sc) = (
                rf * fine.corr.position_sigma(uf),
                rc * coarse_fit.0.position_sigma(uc),
            );
            let point_noise = (of * sf).powi(2) - (oc * sc).powi(2);
            noise2 += point_noise;
            point_diff2.push(d * d);
            point_noise2.push(point_noise);
            settled_noise2 += (gf * sf).powi(2) - (gc * sc).powi(2);
        }
        // The coarse curve's shape error, as the settles will leave it.
        let shape_gain = settled.map_or(1.0, |blur| {
            let h = corr.basis().element_length() * speed;
            let settled_once = match baseline {
                Some(_) => one_settle_shape_gain(blur, h),
                None => 1.0,
            };
            settle_shape_gain(blur, h) / settled_once
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
                let extra = fine
                    .corr
                    .n_unknowns()
                    .saturating_sub(coarse_fit.0.n_unknowns())
                    .max(1);
                shape_error = kept_shape_error(diff2, noise2, extra, shape_gain, params.len());
                // Points per coarse element.
                let per_element = coarse * params.len() as f64 / length;
                let at: Vec<[f64; 2]> = params.iter().map(|&u| reference.point(u)).collect();
                local_shape = LocalShapeError::new(
                    &at,
                    (&point_diff2, &point_noise2),
                    per_element,
                    shape_gain,
                    closed,
                );
            }
            break;
        }
        previous_diff2 = diff2;
        (corr, lambda, step) = (fine.corr, fine.lambda, fine.step);
        if fine.reference.is_some() {
            moved = fine.reference;
        }
    }
    Ok(Refined {
        fit: Fitted {
            corr,
            lambda,
            step,
            noise_estimated: true,
        },
        iterations,
        shape_error,
        local_shape,
        reference: moved,
    })
}

/// What [`refine`] kept.
pub(super) struct Refined {
    /// The fit kept.
    pub fit: Fitted,
    /// Iterations used by the finer fits.
    pub iterations: usize,
    /// The kept elements' shape error when a rejected refinement measured
    /// one ([`kept_shape_error`]), pixels RMS.
    pub shape_error: Option<f64>,
    /// Where along the curve that error lies, where it is significant.
    pub local_shape: Option<LocalShapeError>,
    /// The kept fit's reference when it is not the one given.
    pub reference: Option<SplineCurve>,
}

/// A converged fit of [`refine`]'s, on the reference given (`reference`
/// `None`) or on one of its own.
struct Candidate {
    corr: Correlation,
    lambda: Vec<f64>,
    step: Step,
    reference: Option<SplineCurve>,
}

/// The fit, from zero, of `band` built on `basis` (`None` when it does not
/// converge), and the iterations it used.
fn converged_fit(
    built: Band,
    basis: Basis,
    sampler: &Sampler,
    config: &FitConfig,
    band: RefineBand,
    history: &mut Vec<IterationRecord>,
) -> (Option<Candidate>, usize) {
    let Ok(mut corr) = Correlation::prepare(built, basis, sampler, config.levels, None) else {
        return (None, 0);
    };
    let mut lambda = vec![0.0; corr.n_unknowns()];
    let mut step = None;
    let (end, iterations) = iterate_to_end(
        &mut corr,
        &mut lambda,
        sampler,
        config,
        RunLimits::refit(config, band.half_width),
        &mut step,
        RunLog {
            history,
            kind: RunKind::Refine,
        },
    );
    let (Run::Converged, Some(step)) = (end, step) else {
        return (None, iterations);
    };
    corr.estimate_noise(&lambda, sampler);
    let fit = Candidate {
        corr,
        lambda,
        step,
        reference: None,
    };
    (Some(fit), iterations)
}

/// The fit with `n_el` elements on a reference of its own: `x0 + U n` of
/// the coarse fit (`x0` its reference, `U` its displacement on `basis`),
/// refitted with control points `spacing` pixels apart (`None` when that
/// curve loops, its band leaves the image or the fit fails: the refinement
/// is optional), and the iterations it used.
fn own_fit(
    (x0, basis, lambda): (&SplineCurve, &Basis, &[f64]),
    (spacing, n_el): (f64, usize),
    size: (usize, usize),
    sampler: &Sampler,
    config: &FitConfig,
    band: RefineBand,
    history: &mut Vec<IterationRecord>,
) -> (Option<Candidate>, usize) {
    let Ok(own) = next_reference(x0, basis, lambda, spacing, &Ends::default(), size) else {
        return (None, 0);
    };
    if curve_loops(&own).is_some() {
        return (None, 0);
    }
    let Ok(own_basis) = breaks::displacement_basis(&own, config.degree, n_el) else {
        return (None, 0);
    };
    let Ok(built) = Band::build_with(
        &own,
        &own_basis,
        band.half_width,
        band.profile,
        size.0,
        size.1,
        1,
        config.coords,
    ) else {
        return (None, 0);
    };
    let (fit, iterations) = converged_fit(built, own_basis, sampler, config, band, history);
    let fit = fit.map(|c| Candidate {
        reference: Some(own),
        ..c
    });
    (fit, iterations)
}

/// `x0(u) + U(u) n(u)` of a reference `x0` and a displacement on `basis`.
fn displaced(x0: &SplineCurve, basis: &Basis, lambda: &[f64], u: f64) -> [f64; 2] {
    let f = x0.frame(u);
    let d = displacement(basis, lambda, u);
    [f.point[0] + d * f.normal[0], f.point[1] + d * f.normal[1]]
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

/// How many times the noise's share of a window's mean squared difference
/// the rest of it must be for the kept elements' shape error to count
/// there ([`LocalShapeError`]). The difference of two splines varies
/// little within a window of one coarse element: its noise there is about
/// one degree of freedom, and a curve holds a hundred windows or more. A
/// chi-square of one degree of freedom exceeds 16 times its mean with a
/// probability of 6e-5, in under 1 % of such curves. (At 7 times, the
/// conformance sweep's `sigma` rose in 163 of its 2104 cases, by 13 % in
/// the median, and over-reported in 14 more; at 16, in 8 of them and 2.)
const LOCAL_SIGNIFICANCE: f64 = 15.0;

/// The kept elements' shape error where along the curve it lies, from the
/// difference to the finer fit a refinement rejected: pixels RMS at the
/// points of the reference where it counts (0 elsewhere), looked up by
/// position (a settle's new reference starts its parameter elsewhere).
///
/// Why: a rejected refinement's RMS shape error ([`kept_shape_error`]) is
/// spread over the whole curve, and a whole curve's noise can outweigh
/// one bay the elements cannot follow: a bay of 4.4 px radius on elements
/// of 4.8 px under a 1.3 px blur, noiseless 8-bit, lay up to 0.044 px
/// off, 4.2 sigma, where the finer fit differed from the kept one by 0.028
/// px against a noise of 0.005 px. The difference is each window's (one
/// coarse element), beyond [`LOCAL_SIGNIFICANCE`] times its noise share,
/// times the settles' shape gain; a bend's least-squares error reaches
/// half an element beyond the bend, so each point takes the largest
/// within half an element.
pub(super) struct LocalShapeError {
    /// The points where the error counts...
    points: Vec<[f64; 2]>,
    /// ... the error at each...
    values: Vec<f64>,
    /// ... and the points in buckets of [`LOOKUP_REACH`].
    buckets: Buckets,
}

/// A sample takes the largest error of the points within this many
/// pixels (the output curve lies within the last displacement of the
/// reference the refinement ran on, a fraction of a pixel, and its points
/// are a pixel apart).
const LOOKUP_REACH: f64 = 1.5;

impl LocalShapeError {
    /// From the reference's points `at` (those of
    /// `SplineCurve::sample_params`, in order), each one's squared
    /// difference and noise share `(diff2, noise2)`, `per_element` points
    /// per coarse element, the settles' `shape_gain`; `None` where no
    /// window's difference is significant.
    fn new(
        at: &[[f64; 2]],
        (diff2, noise2): (&[f64], &[f64]),
        per_element: f64,
        shape_gain: f64,
        closed: bool,
    ) -> Option<Self> {
        let n = diff2.len();
        if n == 0 || n != noise2.len() || n != at.len() {
            return None;
        }
        let half = ((0.5 * per_element).round() as isize).max(1);
        let window = |k: usize| {
            let k = k as isize;
            (k - half..=k + half).filter_map(move |j| {
                if closed {
                    Some(j.rem_euclid(n as isize) as usize)
                } else {
                    (0..n as isize).contains(&j).then_some(j as usize)
                }
            })
        };
        let excess: Vec<f64> = (0..n)
            .map(|k| {
                let (mut d, mut e, mut m) = (0.0, 0.0, 0.0);
                for j in window(k) {
                    d += diff2[j];
                    e += noise2[j].max(0.0);
                    m += 1.0;
                }
                let (d, e) = (d / m, e / m);
                if d - e > LOCAL_SIGNIFICANCE * e {
                    shape_gain * (d - e).sqrt()
                } else {
                    0.0
                }
            })
            .collect();
        let (points, values): (Vec<[f64; 2]>, Vec<f64>) = (0..n)
            .map(|k| (at[k], window(k).map(|j| excess[j]).fold(0.0, f64::max)))
            .filter(|&(_, v)| v > 0.0)
            .unzip();
        if points.is_empty() {
            return None;
        }
        let buckets = Buckets::new(points.iter().copied(), LOOKUP_REACH);
        Some(LocalShapeError {
            points,
            values,
            buckets,
        })
    }

    /// The error (pixels RMS) at the point `p`: the largest within
    /// [`LOOKUP_REACH`], else 0.
    pub fn at(&self, p: [f64; 2]) -> f64 {
        self.buckets
            .within(|k| self.points[k], p, LOOKUP_REACH)
            .map(|k| self.values[k])
            .fold(0.0, f64::max)
    }
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
    use super::{finer_length, kept_shape_error, LocalShapeError};

    /// Points a pixel apart along a circle of radius 100 px.
    fn circle(n: usize) -> Vec<[f64; 2]> {
        (0..n)
            .map(|k| {
                let t = std::f64::consts::TAU * k as f64 / n as f64;
                [200.0 + 100.0 * t.cos(), 200.0 + 100.0 * t.sin()]
            })
            .collect()
    }

    /// A difference the noise explains is no local shape error; a bump
    /// of it is, where it lies (and half an element beyond), as its
    /// excess over the noise times the settles' gain; nowhere else.
    #[test]
    fn local_shape_error_is_where_the_difference_exceeds_the_noise() {
        let at = circle(628);
        let n = at.len();
        let noise2 = vec![1e-4; n];
        // Noise alone: each point's squared difference scattering about
        // the noise's share, as a chi-square of one degree of freedom.
        let mut rng = crate::render::noise::Rng::new(7);
        let noisy: Vec<f64> = (0..n).map(|_| 1e-4 * rng.normal().powi(2)).collect();
        assert!(LocalShapeError::new(&at, (&noisy, &noise2), 5.0, 1.0, true).is_none());
        // A bump of three noise deviations is not significant.
        let mut small = noise2.clone();
        for d in &mut small[100..105] {
            *d = 0.03 * 0.03;
        }
        assert!(LocalShapeError::new(&at, (&small, &noise2), 5.0, 1.0, true).is_none());
        // A bump of 0.1 px (ten noise deviations) over 5 points.
        let mut bump = noise2.clone();
        for d in &mut bump[100..105] {
            *d = 0.1 * 0.1;
        }
        let local = LocalShapeError::new(&at, (&bump, &noise2), 5.0, 2.0, true).expect("bump");
        let peak = local.at(at[102]);
        assert!(peak > 2.0 * 0.06 && peak < 2.0 * 0.1, "{peak}");
        assert!(local.at(at[96]) > 0.0, "half an element before the bump");
        assert_eq!(local.at(at[300]), 0.0);
        // Within the lookup's reach of a point, off the curve.
        let off = [at[102][0] + 1.0, at[102][1]];
        assert_eq!(local.at(off), peak);
    }

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
