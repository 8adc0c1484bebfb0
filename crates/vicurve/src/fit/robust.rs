//! Robust weights: clutter crossing the band (a wire, a scratch, a speck)
//! is found from the residuals of the converged fit and weighted down by
//! Tukey's biweight, and the fit runs again (iteratively reweighted least
//! squares).

use super::run::{iterate_to_end, Run, RunLimits, RunLog};
use super::{FitConfig, IterationRecord, RunKind};
use crate::correlation::{Correlation, Step};
use crate::interp::Sampler;
use rayon::prelude::*;

/// Residuals beyond this many robust deviations mark a band as cluttered
/// (below, the fit is left as it is: a clean image is not reweighted).
const OUTLIER: f64 = 5.0;
/// Tukey's biweight constant, in robust deviations (95 % efficiency on
/// Gaussian noise).
const TUKEY: f64 = 4.685;
/// The robust scale is at least this fraction of the contrast `|c|`.
const MIN_ROBUST_SCALE: f64 = 0.02;
/// Band pixels whose residuals decide whether to reweight, at most.
const ROBUST_PROBE_PIXELS: usize = 8192;
/// Reweighting rounds at most.
const ROBUST_ROUNDS: usize = 3;

/// The robust scale of `residuals` (gray levels; `c` the contrast) when
/// some of them are clutter, `None` when the band is clean (then nothing is
/// reweighted). The scale is 1.4826 times the median absolute residual, at
/// least `MIN_ROBUST_SCALE |c|`: on a noiseless image most residuals are
/// (nearly) zero, and the floor keeps quantisation and small profile
/// mismatch from passing for clutter. Clutter: a residual beyond `OUTLIER`
/// scales.
pub(crate) fn clutter_scale(residuals: &[f64], c: f64) -> Option<f64> {
    let mut abs: Vec<f64> = residuals.iter().map(|v| v.abs()).collect();
    if abs.is_empty() {
        return None;
    }
    let mid = abs.len() / 2;
    let mad = 1.4826 * *abs.select_nth_unstable_by(mid, f64::total_cmp).1;
    let scale = mad.max(MIN_ROBUST_SCALE * c.abs());
    if scale.is_nan() || scale <= 0.0 || residuals.iter().all(|v| v.abs() < OUTLIER * scale) {
        return None;
    }
    Some(scale)
}

/// Tukey's biweight of residual `v` for the robust `scale` (see
/// [`clutter_scale`]): 1 at 0, falling to 0 at `TUKEY` scales and beyond.
pub(crate) fn tukey_weight(v: f64, scale: f64) -> f64 {
    let t = v / (TUKEY * scale);
    if t.abs() < 1.0 {
        (1.0 - t * t).powi(2)
    } else {
        0.0
    }
}

/// A fit the robust check may replace: its system, coefficients and last
/// step, updated in place.
pub(super) struct RobustFit<'f> {
    /// The system.
    pub corr: &'f mut Correlation,
    /// Its coefficients, pixels.
    pub lambda: &'f mut Vec<f64>,
    /// Its last step (`None`: nothing to check).
    pub step: &'f mut Option<Step>,
}

/// Robust weights: when some residuals of the converged fit are far beyond
/// the others (the scale is 1.4826 times the median absolute residual, and
/// at least `MIN_ROBUST_SCALE` of the contrast), weight each pixel by
/// Tukey's biweight of its residual and fit again on the same reference, a
/// few rounds. Rejected pixels no longer drag the curve; their share is
/// reported per sample ([`super::Sample::weight`]). The matrix is
/// re-assembled each round. Returns the iterations used and whether the
/// band holds clutter; on any failure the fit before it stands.
pub(super) fn robust_refit(
    fit: RobustFit<'_>,
    sampler: &Sampler,
    config: &FitConfig,
    half_width: f64,
    history: &mut Vec<IterationRecord>,
) -> (usize, bool) {
    let RobustFit { corr, lambda, step } = fit;
    let base: Vec<f64> = corr
        .band()
        .full_weights()
        .iter()
        .zip(corr.robust())
        .map(|(w, k)| if *k > 0.0 { w / k } else { *w })
        .collect();
    let mut used = 0;
    let mut found = false;
    for _ in 0..ROBUST_ROUNDS {
        let Some(s) = *step else { break };
        // A pixel displaced out of the image counts as fitting exactly.
        let residual = |i: usize| corr.residual(i, lambda, sampler).unwrap_or(0.0);
        // Detection on a regular subsample (a crossing wire still leaves
        // several of its pixels in it); all residuals only when needed.
        let stride = corr.band().len().div_ceil(ROBUST_PROBE_PIXELS).max(1);
        let probe: Vec<f64> = (0..corr.band().len().div_ceil(stride))
            .into_par_iter()
            .map(|k| residual(k * stride))
            .collect();
        let Some(scale) = clutter_scale(&probe, s.c) else {
            break;
        };
        found = true;
        let res: Vec<f64> = (0..corr.band().len())
            .into_par_iter()
            .map(residual)
            .collect();
        let robust: Vec<f64> = res.iter().map(|v| tukey_weight(*v, scale)).collect();
        let mut band = corr.band().clone();
        let weights = base.iter().zip(&robust).map(|(b, k)| b * k).collect();
        band.set_full_weights(weights, corr.basis(), lambda);
        let Ok(mut next) =
            Correlation::prepare(band, corr.basis().clone(), sampler, config.levels, None)
        else {
            break;
        };
        next.set_robust(robust);
        // As the stage's later runs (see `StageState::cluttered`).
        next.use_reference_gradient();
        let mut next_lambda = lambda.clone();
        let mut next_step = None;
        let (end, it) = iterate_to_end(
            &mut next,
            &mut next_lambda,
            sampler,
            config,
            RunLimits::refit(config, half_width),
            &mut next_step,
            RunLog {
                history: &mut *history,
                kind: RunKind::Robust,
            },
        );
        used += it;
        let (Run::Converged, Some(_)) = (end, next_step) else {
            break;
        };
        let moved = next_lambda
            .iter()
            .zip(lambda.iter())
            .fold(0.0f64, |m, (a, b)| m.max((a - b).abs()));
        (*corr, *lambda, *step) = (next, next_lambda, next_step);
        if moved < config.tolerance {
            break;
        }
    }
    (used, found)
}
