//! Levenberg–Marquardt: the damping schedule and the stopping rule, shared
//! by every nonlinear least-squares fit of the crate.
//!
//! The loop knows nothing of what is fitted. A [`Problem`] proposes a step
//! from the current point for a given damping `mu` (it forms and solves its
//! damped normal equations, caps the step, evaluates the new point) and
//! says whether the step is under its tolerance; the loop decides, by the
//! rules of [`LmParams`]:
//!
//! - a trial is accepted when its cost does not exceed the current one (or,
//!   with [`LmParams::take_small_steps`], when its step is under the
//!   tolerance, whatever the rounding of the cost says); `mu` is then
//!   multiplied by [`LmParams::shrink`] (not below [`LmParams::min_damping`]);
//! - otherwise `mu` is multiplied by [`LmParams::grow`] and the step is
//!   tried again, while `mu < `[`LmParams::max_damping`];
//! - the iteration stops on an accepted step under the tolerance
//!   ([`End::Converged`]), when no damping gives an acceptable step
//!   ([`End::Stalled`]: a minimum, to rounding), after
//!   [`LmParams::max_iterations`] iterations, or when the problem asks it
//!   to ([`End::Stopped`], with the problem's own reason).
//!
//! `mu` carries over from one iteration to the next.

/// The damping schedule and the stopping rule.
///
/// The defaults are those of the shape models' fits ([`crate::model`]):
/// the circle and ellipse fits of [`crate::derived`] start from a heavier
/// damping, allow lighter and heavier ones, and stop on a small step that
/// would raise the cost instead of taking it.
#[derive(Clone, Copy, Debug, PartialEq)]
pub(crate) struct LmParams {
    /// Damping of the first trial (default `1e-6`).
    pub start_damping: f64,
    /// Factor applied to the damping after a rejected trial (default 10).
    pub grow: f64,
    /// Factor applied to the damping after an accepted trial (default 0.1).
    pub shrink: f64,
    /// The damping is never lowered below this (default `1e-12`).
    pub min_damping: f64,
    /// Trials are made while the damping is below this (default `1e10`):
    /// a damping this large means no step lowers the cost any more.
    pub max_damping: f64,
    /// Iterations (accepted steps) at most (default 100).
    pub max_iterations: usize,
    /// Whether a step under the tolerance is taken even when its cost is
    /// higher (default `true`: the difference is rounding); when `false`
    /// such a step is not taken and the iteration ends as converged.
    pub take_small_steps: bool,
}

impl Default for LmParams {
    fn default() -> Self {
        LmParams {
            start_damping: 1e-6,
            grow: 10.0,
            shrink: 0.1,
            min_damping: 1e-12,
            max_damping: 1e10,
            max_iterations: 100,
            take_small_steps: true,
        }
    }
}

/// What a [`Problem`] made of one trial.
pub(crate) enum Trial<P, E, S> {
    /// No usable point at this damping (the damped matrix is not positive
    /// definite, or the step leaves the problem's domain): the damping is
    /// raised and the step tried again.
    Retry,
    /// The iteration must stop, for the problem's reason (a non-finite
    /// step, say); the current point is kept.
    Stop(S),
    /// A new point and its evaluation.
    Step {
        /// The point.
        point: P,
        /// Its evaluation (cost, normal equations...).
        eval: E,
        /// Whether the step to it is under the problem's tolerance.
        small: bool,
    },
}

/// A nonlinear least-squares problem as the loop sees it.
pub(crate) trait Problem {
    /// The unknowns (and whatever goes with them, such as a curve).
    type Point;
    /// What is computed at a point: its cost and normal equations.
    type Eval;
    /// Why the problem may stop the iteration.
    type Stop;

    /// The cost of an evaluation (a sum of squares); NaN is never accepted.
    fn cost(&self, eval: &Self::Eval) -> f64;

    /// The trial from `point` (evaluated as `eval`) with damping `mu`.
    fn trial(
        &self,
        point: &Self::Point,
        eval: &Self::Eval,
        mu: f64,
    ) -> Trial<Self::Point, Self::Eval, Self::Stop>;

    /// A check at the start of every iteration, before any trial.
    fn before_iteration(&self, _point: &Self::Point, _eval: &Self::Eval) -> Option<Self::Stop> {
        None
    }

    /// A check after every accepted step, before the tolerance is looked at.
    fn after_step(&self, _point: &Self::Point, _eval: &Self::Eval) -> Option<Self::Stop> {
        None
    }
}

/// How the loop ended.
#[derive(Clone, Copy, Debug, PartialEq)]
pub(crate) enum End<S> {
    /// The last step was under the tolerance.
    Converged,
    /// No damping up to the largest gave an acceptable step: the point is
    /// a minimum, to rounding (or its cost is not a number).
    Stalled,
    /// [`LmParams::max_iterations`] steps were taken.
    IterationLimit,
    /// The problem stopped the iteration.
    Stopped(S),
}

/// The last point of the loop.
pub(crate) struct Minimum<P, E, S> {
    /// The last accepted point (the start if none was).
    pub point: P,
    /// Its evaluation.
    pub eval: E,
    /// Why the loop ended.
    pub end: End<S>,
    /// The iteration it ended in, from 1 (`max_iterations` at the limit).
    pub iterations: usize,
}

/// Levenberg–Marquardt from `point`, evaluated as `eval` (module docs).
pub(crate) fn minimise<Q: Problem>(
    problem: &Q,
    point: Q::Point,
    eval: Q::Eval,
    params: &LmParams,
) -> Minimum<Q::Point, Q::Eval, Q::Stop> {
    let (mut point, mut eval) = (point, eval);
    let mut mu = params.start_damping;
    for it in 1..=params.max_iterations {
        let done = |point, eval, end| Minimum {
            point,
            eval,
            end,
            iterations: it,
        };
        if let Some(stop) = problem.before_iteration(&point, &eval) {
            return done(point, eval, End::Stopped(stop));
        }
        let mut accepted = None;
        while mu < params.max_damping {
            match problem.trial(&point, &eval, mu) {
                Trial::Retry => mu *= params.grow,
                Trial::Stop(stop) => return done(point, eval, End::Stopped(stop)),
                Trial::Step {
                    point: p,
                    eval: e,
                    small,
                } => {
                    if problem.cost(&e) <= problem.cost(&eval) || (small && params.take_small_steps)
                    {
                        mu = (mu * params.shrink).max(params.min_damping);
                        accepted = Some((p, e, small));
                        break;
                    }
                    if small {
                        return done(point, eval, End::Converged);
                    }
                    mu *= params.grow;
                }
            }
        }
        let Some((p, e, small)) = accepted else {
            return done(point, eval, End::Stalled);
        };
        (point, eval) = (p, e);
        if let Some(stop) = problem.after_step(&point, &eval) {
            return done(point, eval, End::Stopped(stop));
        }
        if small {
            return done(point, eval, End::Converged);
        }
    }
    Minimum {
        point,
        eval,
        end: End::IterationLimit,
        iterations: params.max_iterations,
    }
}
