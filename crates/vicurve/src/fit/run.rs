//! One run: Gauss–Newton iterations on one reference with its constant
//! matrix (method, section 5), until the step is under the tolerance, the
//! budget is spent, the displacement calls for a new reference, or a step
//! fails.

use super::{Divergence, FitConfig, IterationRecord, RunKind};
use crate::correlation::{Correlation, Step, StepFailure};
use crate::interp::Sampler;
use crate::spline::{Basis, MAX_DEGREE};

/// A run on one reference that has not converged after this many
/// iterations goes on with the reference's profile derivative in its
/// gradient (`Correlation::use_reference_gradient`): the displaced one's
/// may keep a model that does not fit the image from contracting. Runs
/// that converge take 2 to 6.
const DISPLACED_GRADIENT_ITERATIONS: usize = 12;
/// Contraction ratio of successive steps under which a run's error left
/// is estimated ([`error_left`]).
const FAST_CONTRACTION: f64 = 0.25;

/// How a run of Gauss–Newton iterations on one reference ended.
pub(super) enum Run {
    /// A step (or the error it leaves) under the tolerance.
    Converged,
    /// The budget of iterations was spent.
    IterationLimit,
    /// `max |U|` passed the re-referencing limit.
    Rereference,
    /// A step longer than [`RunLimits::lost`] (not applied): the band does
    /// not see the edge somewhere.
    Lost,
    /// A step could not be made.
    Failed(Divergence),
}

/// Where a run stops besides convergence.
#[derive(Clone, Copy, Debug)]
pub(super) struct RunLimits {
    /// Iterations allowed.
    pub budget: usize,
    /// Convergence tolerance on the step, pixels.
    pub tolerance: f64,
    /// A coefficient beyond this (pixels) ends the run for a new
    /// reference; infinite for none.
    pub rereference: f64,
    /// Band half-width, pixels: a step is capped at
    /// [`FitConfig::max_step_fraction`] of it.
    pub half_width: f64,
    /// A step (before any cap) that moves the curve by more than this
    /// ([`step_on_curve`]), pixels, ends the run without being applied
    /// ([`Run::Lost`]); infinite for none.
    pub lost: f64,
}

impl RunLimits {
    /// The whole iteration budget and tolerance of `config`, no
    /// re-referencing: a fit again on the same reference (refinement,
    /// reweighting, global levels).
    pub fn refit(config: &FitConfig, half_width: f64) -> Self {
        RunLimits {
            budget: config.max_iterations,
            tolerance: config.tolerance,
            rereference: f64::INFINITY,
            half_width,
            lost: f64::INFINITY,
        }
    }
}

/// What a run records: the stage's iteration history, under which kind.
pub(super) struct RunLog<'h> {
    /// The stage's history, appended to.
    pub history: &'h mut Vec<IterationRecord>,
    /// What this run is.
    pub kind: RunKind,
}

/// Iterate on one reference until convergence (a step under the
/// tolerance, or a step that leaves less than that: [`error_left`]), the
/// iteration budget, a displacement past the re-referencing limit or a
/// failure. Returns how it ended and the iterations used; `step` keeps the
/// last successful step.
pub(super) fn iterate_to_end(
    corr: &mut Correlation,
    lambda: &mut [f64],
    sampler: &Sampler,
    config: &FitConfig,
    limits: RunLimits,
    step: &mut Option<Step>,
    log: RunLog<'_>,
) -> (Run, usize) {
    let RunLog { history, kind } = log;
    let mut relax = Relaxation::new(lambda.len());
    let cap = config.max_step_fraction * limits.half_width;
    let mut used = 0;
    // The two raw steps before this one (pixels), and the contraction the
    // system showed on earlier runs, for `error_left`.
    let mut previous_steps = [f64::INFINITY; 2];
    let mut known = corr.contraction();
    loop {
        if used >= limits.budget {
            return (Run::IterationLimit, used);
        }
        if used == DISPLACED_GRADIENT_ITERATIONS && corr.displaced_gradient() {
            corr.use_reference_gradient();
            relax = Relaxation::new(lambda.len());
            known = None;
        }
        let s = match corr.iterate(lambda, sampler, config.polarity) {
            Ok(s) => s,
            Err(failure) => return (Run::Failed(divergence_of(failure)), used),
        };
        history.push(IterationRecord {
            iteration: history.len(),
            max_step: s.max_step,
            residual_rms: s.residual_rms,
            run: kind,
            new_reference: kind == RunKind::Reference && used == 0,
        });
        used += 1;
        // The coefficients' step bounds the curve's (partition of unity),
        // so the curve is looked at only past the limit.
        if s.max_step > limits.lost && step_on_curve(corr.basis(), corr.delta()) > limits.lost {
            return (Run::Lost, used);
        }
        *step = Some(s);
        let omega = relax.factor(corr.delta());
        let scale = omega
            * if omega * s.max_step > cap {
                cap / (omega * s.max_step)
            } else {
                1.0
            };
        relax.applied(scale);
        for (l, d) in lambda.iter_mut().zip(corr.delta()) {
            *l += scale * d;
        }
        if previous_steps[1].is_finite() {
            corr.observe_contraction(s.max_step / previous_steps[1]);
        }
        let left = error_left(s.max_step, previous_steps, known);
        if s.max_step < limits.tolerance || left < limits.tolerance {
            return (Run::Converged, used);
        }
        previous_steps = [previous_steps[1], s.max_step];
        if lambda.iter().any(|l| l.abs() > limits.rereference) {
            return (Run::Rereference, used);
        }
    }
}

/// The largest displacement (pixels) that the coefficient step `delta`
/// makes on the curve: `max |sum delta_i N_i(s)|` over the ends and the
/// middle of every element.
///
/// Why not `max |delta_i|`: an open curve's end functions barely reach
/// into the curve (a cubic's first one is at most 1/6 there), so their
/// coefficients can take long raw steps that hardly move it, at a trimmed
/// end say; a band that lost the edge moves the curve itself.
pub(super) fn step_on_curve(basis: &Basis, delta: &[f64]) -> f64 {
    let mut values = [0.0; MAX_DEGREE + 1];
    let p = basis.degree();
    let mut largest: f64 = 0.0;
    let mut at = |s: f64| {
        let first = basis.eval(s, &mut values);
        let u: f64 = (0..=p)
            .map(|k| delta[basis.index(first, k)] * values[k])
            .sum();
        largest = largest.max(u.abs());
    };
    for e in 0..basis.n_elements() {
        let (start, h) = basis.element_bounds(e);
        at(start);
        at(start + 0.5 * h);
    }
    if !basis.is_closed() {
        at(basis.length());
    }
    largest
}

/// The divergence a failed step means.
fn divergence_of(failure: StepFailure) -> Divergence {
    match failure {
        StepFailure::LeftImage([x, y]) => Divergence::LeftImage { x, y },
        StepFailure::NoContrast => Divergence::NoContrast,
        StepFailure::NonFinite => Divergence::NonFinite,
    }
}

/// The error (pixels) that remains once a step of `step` is applied, the
/// two steps before it being `previous` (older first, infinite when the run
/// has not made them) and `known` the slowest contraction the system
/// showed on earlier runs (`Correlation::contraction`).
///
/// Gauss–Newton with a constant matrix contracts linearly: with `q` the
/// larger ratio of the last three steps, the steps still to come add up to
/// about `step q / (1 - q)`; taken twice for safety, and only once three
/// steps show a good contraction (`q` under `FAST_CONTRACTION`), infinite
/// otherwise. The contraction is a property of the system, not of the run:
/// on a band that earlier runs showed to contract fast (a kept band's next
/// frames, see `TrackCache`), two steps of the run suffice, `q` then being
/// at least what those runs showed.
pub(super) fn error_left(step: f64, previous: [f64; 2], known: Option<f64>) -> f64 {
    let q = match (previous[0].is_finite(), known) {
        (true, _) => (step / previous[1]).max(previous[1] / previous[0]),
        (false, Some(k)) if previous[1].is_finite() => (step / previous[1]).max(k),
        _ => return f64::INFINITY,
    };
    if q < FAST_CONTRACTION {
        2.0 * step * q / (1.0 - q)
    } else {
        f64::INFINITY
    }
}

/// The largest change of the coefficients from `start` (from 0 without
/// one), pixels: a bound on that of the displacement (the B-splines are a
/// partition of unity).
pub(super) fn largest_change(lambda: &[f64], start: Option<&[f64]>) -> f64 {
    match start {
        Some(start) => lambda
            .iter()
            .zip(start)
            .fold(0.0, |m: f64, (l, s)| m.max((l - s).abs())),
        None => lambda.iter().fold(0.0, |m: f64, l| m.max(l.abs())),
    }
}

/// Smallest relaxation factor: steps overshooting up to 20 times are
/// damped in one step. An open curve's end coefficient barely reaches into
/// the curve, and the step can overshoot it ten times and more (a robust
/// run on a cluttered band, say); a factor `w` leaves such a mode
/// contracting by `1 - w lambda` a step, which a higher floor makes slow
/// or even growing (docs/benchmarks.md, "The relaxation's floor").
const MIN_RELAXATION: f64 = 0.05;

/// Largest relaxation factor (a creeping mode is lengthened at most this
/// much).
const MAX_RELAXATION: f64 = 3.0;

/// Two successive measures of a creeping mode's `lambda` agree within this
/// fraction (see [`Relaxation::creep_jump`]).
const CREEP_AGREEMENT: f64 = 0.05;
/// Successive steps are parallel (one mode left) above this cosine.
const CREEP_PARALLEL: f64 = 0.999;
/// Largest factor of a creeping mode's jump: it bounds what the jump does
/// to whatever else the step holds (at most 4.5 % of it, by
/// [`CREEP_PARALLEL`]); a mode contracting by less than 5 % a step loses
/// `20 lambda` of itself at each jump instead of all of it.
const MAX_CREEP_JUMP: f64 = 20.0;

/// Scalar secant relaxation of the Gauss–Newton steps.
///
/// The step replaces the gradient of the physical image by the virtual
/// one's, and models how the refitted gray levels follow a shift of the
/// curve as if the physical edge had the virtual profile. When it has not (a
/// sharp or blurred edge under a sine profile), the iteration is a linear
/// contraction `d_(k+1) = (1 - w_k lambda) d_k` along its dominant mode, with
/// `lambda` up to ~2 (oscillation) or under 1 (slow creep). The ratio of two
/// successive steps measures `lambda`; the next factor is `w = 1 / lambda`
/// (clamped to [`MIN_RELAXATION`] and [`MAX_RELAXATION`]), which removes
/// that mode in one more step. With a matched profile `lambda = 1` and `w`
/// stays 1.
struct Relaxation {
    previous: Vec<f64>,
    have_previous: bool,
    omega: f64,
    last_applied: f64,
    /// The creeping mode's `lambda` measured at the step before (NaN: none).
    creep: f64,
}

impl Relaxation {
    fn new(n: usize) -> Self {
        Relaxation {
            previous: vec![0.0; n],
            have_previous: false,
            omega: 1.0,
            last_applied: 1.0,
            creep: f64::NAN,
        }
    }

    /// The factor for the raw step `delta` (before the step-length cap).
    fn factor(&mut self, delta: &[f64]) -> f64 {
        let mut factor = self.omega;
        if self.have_previous {
            let (mut dot, mut norm, mut own) = (0.0, 0.0, 0.0);
            for (d, p) in delta.iter().zip(&self.previous) {
                dot += d * p;
                norm += p * p;
                own += d * d;
            }
            if norm > 0.0 {
                let rho = dot / norm;
                let lambda = (1.0 - rho) / self.last_applied;
                if lambda.is_finite() && lambda > 1.0 / 3.0 {
                    self.omega = (1.0 / lambda).clamp(MIN_RELAXATION, MAX_RELAXATION);
                    factor = self.omega;
                    self.creep = f64::NAN;
                } else if lambda.is_finite() && lambda > 0.0 {
                    factor = self.creep_jump(lambda, dot / (norm * own).sqrt());
                }
            }
        }
        self.previous.copy_from_slice(delta);
        self.have_previous = true;
        factor
    }

    /// The factor for a step along a creeping mode (`lambda` under 1/3,
    /// where the relaxation keeps its factor: `1 / lambda` would make the
    /// other modes grow), `cosine` the angle's between this step and the
    /// previous one. When two successive measures agree (within
    /// [`CREEP_AGREEMENT`]) and the steps are parallel (cosine over
    /// [`CREEP_PARALLEL`]: the other modes have died out), the step is
    /// taken `1 / lambda` times (at most [`MAX_CREEP_JUMP`]) once, which
    /// removes the mode (Aitken's extrapolation of a linear contraction);
    /// the steps after it measure afresh. Otherwise the relaxation's factor.
    fn creep_jump(&mut self, lambda: f64, cosine: f64) -> f64 {
        let agrees = (lambda - self.creep).abs() <= CREEP_AGREEMENT * lambda;
        if agrees && cosine > CREEP_PARALLEL {
            self.creep = f64::NAN;
            return (1.0 / lambda).min(MAX_CREEP_JUMP);
        }
        self.creep = lambda;
        self.omega
    }

    /// Record the factor actually applied (after the cap).
    fn applied(&mut self, factor: f64) {
        self.last_applied = factor;
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    const INF: f64 = f64::INFINITY;

    /// The steps of a linear contraction by `q` from a first step `first`.
    fn steps(first: f64, q: f64, n: usize) -> Vec<f64> {
        (0..n).map(|k| first * q.powi(k as i32)).collect()
    }

    /// The steps of a linear iteration `e -> e + w d`, `d = -overshoot e`,
    /// relaxed by [`Relaxation`]: the errors after each step.
    fn relaxed(overshoot: f64, n: usize) -> Vec<f64> {
        let mut relax = Relaxation::new(1);
        let mut e = 1.0;
        (0..n)
            .map(|_| {
                let d = -overshoot * e;
                let w = relax.factor(&[d]);
                relax.applied(w);
                e += w * d;
                e.abs()
            })
            .collect()
    }

    /// A mode that the raw step overshoots 2, 10 or 19 times is removed by
    /// the second step (the first measures it); a matched one by the first.
    #[test]
    fn an_overshooting_mode_is_damped_in_one_step() {
        assert!(relaxed(1.0, 1)[0] < 1e-12);
        for overshoot in [2.0, 9.77, 19.0] {
            let e = relaxed(overshoot, 3);
            assert!(e[1] < 1e-9 * e[0], "{overshoot}: {e:?}");
        }
    }

    /// The errors of a linear iteration `e -> e + w d`, `d_i = -lambda_i
    /// e_i` (independent modes), relaxed by [`Relaxation`], after each step.
    fn relaxed_modes(lambdas: &[f64], n: usize) -> Vec<Vec<f64>> {
        let mut relax = Relaxation::new(lambdas.len());
        let mut e = vec![1.0; lambdas.len()];
        (0..n)
            .map(|_| {
                let d: Vec<f64> = e.iter().zip(lambdas).map(|(e, l)| -l * e).collect();
                let w = relax.factor(&d);
                relax.applied(w);
                for (e, d) in e.iter_mut().zip(&d) {
                    *e += w * d;
                }
                e.clone()
            })
            .collect()
    }

    /// A creeping mode (the steps shrink by 10 % each) beside a fast one is
    /// removed once the fast one has died out: Aitken's jump along the
    /// steps, where the relaxation alone leaves 0.9^20 = 12 % of it after
    /// 20 steps. A mode shrinking by 3 % a step (beyond the jump's full
    /// reach) loses 60 % at each jump instead, and an oscillating one (the
    /// steps alternate) neither grows nor makes the others grow.
    #[test]
    fn a_creeping_mode_is_removed_by_one_jump() {
        let e = relaxed_modes(&[0.1, 1.0], 20);
        let last = &e[19];
        assert!(last[0].abs() < 1e-9 && last[1].abs() < 1e-9, "{e:?}");
        let slow = relaxed_modes(&[0.03], 20);
        assert!(slow[19][0].abs() < 1e-3 * 0.97f64.powi(20), "{slow:?}");
        let mixed = relaxed_modes(&[0.1, 1.0, 1.9], 80);
        assert!(mixed.iter().flatten().all(|e| e.abs() <= 1.0), "{mixed:?}");
        assert!(mixed[79].iter().all(|e| e.abs() < 1e-6), "{:?}", mixed[79]);
    }

    #[test]
    fn two_steps_need_a_known_contraction() {
        let s = steps(5e-2, 0.01, 2);
        // Nothing known: two steps say nothing yet.
        assert_eq!(error_left(s[1], [INF, s[0]], None), INF);
        // A known fast contraction: twice `step q / (1 - q)`, with `q` the
        // slower of the known one and the run's own ratio.
        let left = error_left(s[1], [INF, s[0]], Some(0.03));
        assert!((left - 2.0 * s[1] * 0.03 / 0.97).abs() < 1e-18, "{left}");
        let left = error_left(s[1], [INF, s[0]], Some(0.001));
        assert!((left - 2.0 * s[1] * 0.01 / 0.99).abs() < 1e-18, "{left}");
        // A known slow one, or a run slower than `FAST_CONTRACTION`: none.
        assert_eq!(error_left(s[1], [INF, s[0]], Some(0.3)), INF);
        assert_eq!(error_left(0.3 * s[0], [INF, s[0]], Some(0.01)), INF);
        // A first step: nothing to compare it with.
        assert_eq!(error_left(s[0], [INF, INF], Some(0.01)), INF);
    }

    #[test]
    fn three_steps_go_by_the_run_alone() {
        let s = steps(0.37, 0.03, 3);
        let own = error_left(s[2], [s[0], s[1]], None);
        assert!((own - 2.0 * s[2] * 0.03 / 0.97).abs() < 1e-15, "{own}");
        for known in [Some(0.001), Some(0.2), Some(0.9)] {
            assert_eq!(error_left(s[2], [s[0], s[1]], known), own);
        }
    }

    /// Whenever the contraction is as fast as the estimate assumes (every
    /// ratio at most the larger of the known one and the run's), the error
    /// left (the sum of the steps still to come) is under the estimate.
    #[test]
    fn the_estimate_bounds_a_linear_contraction() {
        for q in [0.001, 0.01, 0.05, 0.1, 0.2, 0.24] {
            for known in [q, 1.5 * q, 0.24] {
                let s = steps(0.1, q, 40);
                let left: f64 = s[2..].iter().sum();
                let estimate = error_left(s[1], [INF, s[0]], Some(known));
                assert!(
                    left <= estimate,
                    "q {q}, known {known}: {left} > {estimate}"
                );
                let left: f64 = s[3..].iter().sum();
                assert!(left <= error_left(s[2], [s[0], s[1]], None), "q {q}");
            }
        }
    }
}
