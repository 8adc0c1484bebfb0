//! Levenberg–Marquardt over the control points and the gray levels.
//!
//! The residual of band pixel `q` (value `f` as recorded) is
//! `e = f - a - c gamma(d)`, `d` the signed distance from `q` to the current
//! curve: `q` is projected onto the curve by Newton's method from its foot
//! of the previous evaluation (the curve moves by at most [`MAX_STEP`] px a
//! step, so the previous foot is a good start). By the envelope theorem
//! `dd/dP_k = -N_k(u*) n(u*)`; the dependence of the pixel-edge profile's
//! normal and curvature on `P` is left out (second order), as for the
//! parametric models.
//!
//! The sum of squares is augmented by the tangential regularisation
//! `lambda sum_k (t_k . (P_k - P0_k))^2` (module docs of
//! [`super`]); the iteration solves
//! `(H + mu diag H) dz = -g` (bordered banded Cholesky, [`super::system`]),
//! accepts the step when the regularised sum does not rise, and stops when
//! the largest control-point move is under the tolerance. The band is
//! chosen on the current curve ([`crate::band::Band`]: pixels whose foot is
//! interior, within `R`, on the near side of the centre of curvature), kept
//! while iterating, and chosen again until it no longer changes.

use super::system::{Factored, Normal};
use crate::band::Band;
use crate::curve::SplineCurve;
use crate::image::Image;
use crate::measurement::{Divergence, Outcome};
use crate::model::ModelProfile;
use crate::solver::lm::{self, LmParams, Trial};
use crate::spline::MAX_DEGREE;
use crate::virtual_image::{Kind, Profile};

/// Largest control-point move of one iteration, pixels.
pub(crate) const MAX_STEP: f64 = 0.5;
/// Band selections (passes) at most.
const MAX_PASSES: usize = 6;

/// A band pixel: centre, recorded value.
#[derive(Clone, Copy, Debug, PartialEq)]
pub(crate) struct Pixel {
    pub q: [f64; 2],
    pub f: f64,
}

use crate::model::solve::profile_at;

/// The fixed parts of the problem.
pub(crate) struct Problem<'a> {
    pub image: &'a Image,
    pub profile: ModelProfile,
    /// Control points of the start, `P0`.
    pub anchors: Vec<[f64; 2]>,
    /// Unit tangent of the start at each control point's Greville abscissa.
    pub tangents: Vec<[f64; 2]>,
    /// Weight `lambda` of the tangential regularisation (absolute).
    pub lambda: f64,
    pub half_width: f64,
}

/// Sums at one point.
pub(crate) struct Eval {
    pub eq: Normal,
    /// Data sum of squares.
    pub data: f64,
    /// Regularisation term.
    pub penalty: f64,
    /// Feet of the pixels.
    pub feet: Vec<f64>,
}

impl Eval {
    fn cost(&self) -> f64 {
        self.data + self.penalty
    }
}

impl Problem<'_> {
    /// The sums at `curve` and levels `(a, c)`; pixel feet from `feet`.
    pub fn evaluate(
        &self,
        curve: &SplineCurve,
        pixels: &[Pixel],
        feet: &[f64],
        (a, c): (f64, f64),
    ) -> Eval {
        let basis = curve.basis();
        let p = basis.degree();
        let n = basis.n_functions();
        let mut eq = Normal::zeros(n, p, basis.is_closed());
        let mut data = 0.0;
        let mut out_feet = Vec::with_capacity(pixels.len());
        let mut idx = [0usize; 2 * (MAX_DEGREE + 1)];
        let mut val = [0.0f64; 2 * (MAX_DEGREE + 1)];
        let mut nv = [0.0; MAX_DEGREE + 1];
        for (px, &u0) in pixels.iter().zip(feet) {
            let pr = curve.project(px.q[0], px.q[1], u0);
            out_feet.push(pr.u);
            let (gamma, dgamma) = profile_at(self.profile, pr.r, pr.normal, (pr.curvature, 0.0));
            let e = px.f - a - c * gamma;
            let first = basis.eval(pr.u, &mut nv);
            let len = 2 * (p + 1);
            for k in 0..=p {
                let i = basis.index(first, k);
                // de/dP = -c gamma' dd/dP = c gamma' N_k n.
                let w = c * dgamma * nv[k];
                idx[2 * k] = 2 * i;
                idx[2 * k + 1] = 2 * i + 1;
                val[2 * k] = w * pr.normal[0];
                val[2 * k + 1] = w * pr.normal[1];
            }
            for x in 0..len {
                let (i, vi) = (idx[x], val[x]);
                eq.g[i] += vi * e;
                eq.c[i][0] -= vi;
                eq.c[i][1] -= vi * gamma;
                for y in x..len {
                    eq.b.add(i, idx[y], vi * val[y]);
                }
            }
            eq.d[0] += 1.0;
            eq.d[1] += gamma;
            eq.d[2] += gamma * gamma;
            eq.g_z[0] -= e;
            eq.g_z[1] -= gamma * e;
            data += e * e;
        }
        let mut penalty = 0.0;
        if self.lambda > 0.0 {
            for (k, (pt, (p0, t))) in curve
                .control_points()
                .iter()
                .zip(self.anchors.iter().zip(&self.tangents))
                .enumerate()
            {
                let slide = t[0] * (pt[0] - p0[0]) + t[1] * (pt[1] - p0[1]);
                penalty += self.lambda * slide * slide;
                let (i, j) = (2 * k, 2 * k + 1);
                eq.g[i] += self.lambda * t[0] * slide;
                eq.g[j] += self.lambda * t[1] * slide;
                eq.b.add(i, i, self.lambda * t[0] * t[0]);
                eq.b.add(i, j, self.lambda * t[0] * t[1]);
                eq.b.add(j, j, self.lambda * t[1] * t[1]);
            }
        }
        Eval {
            eq,
            data,
            penalty,
            feet: out_feet,
        }
    }

    /// The band of `curve`, with each pixel's foot; `Err` when the curve
    /// or its band leaves the image.
    pub fn select(&self, curve: &SplineCurve) -> crate::Result<(Vec<Pixel>, Vec<f64>)> {
        let band = Band::build(
            curve,
            curve.basis(),
            self.half_width,
            Profile::Paper {
                kind: Kind::Silhouette,
            },
            self.image.width(),
            self.image.height(),
        )?;
        let pixels = band
            .positions()
            .iter()
            .map(|q| Pixel {
                q: *q,
                f: self.image.get(q[0] as usize, q[1] as usize),
            })
            .collect();
        Ok((pixels, band.s().to_vec()))
    }
}

/// How one run on a fixed band ended.
pub(crate) struct BandRun {
    pub curve: SplineCurve,
    pub a: f64,
    pub c: f64,
    pub iterations: usize,
    pub outcome: Outcome,
    pub eval: Eval,
}

fn diverged(divergence: Divergence) -> Outcome {
    Outcome::Diverged { divergence }
}

/// The fit on a fixed band as a Levenberg–Marquardt problem: the point is
/// the curve and the levels `(a, c)`.
struct Fixed<'a, 'p> {
    problem: &'a Problem<'p>,
    pixels: &'a [Pixel],
    tolerance: f64,
}

impl lm::Problem for Fixed<'_, '_> {
    type Point = (SplineCurve, [f64; 2]);
    type Eval = Eval;
    type Stop = Divergence;

    fn cost(&self, eval: &Eval) -> f64 {
        eval.cost()
    }

    fn trial(
        &self,
        (curve, z): &(SplineCurve, [f64; 2]),
        cur: &Eval,
        mu: f64,
    ) -> Trial<(SplineCurve, [f64; 2]), Eval, Divergence> {
        let floor = 1e-9 * cur.eq.max_diag();
        let Some(f) = Factored::new(&cur.eq.damped(mu, floor)) else {
            return Trial::Retry;
        };
        let mut step: Vec<f64> = cur.eq.g.iter().map(|v| -v).collect();
        let dz = f.solve(&mut step, [-cur.eq.g_z[0], -cur.eq.g_z[1]]);
        let size = step
            .chunks_exact(2)
            .map(|d| d[0].hypot(d[1]))
            .fold(0.0, f64::max);
        if !size.is_finite() {
            return Trial::Stop(Divergence::NonFinite);
        }
        let scale = if size > MAX_STEP {
            MAX_STEP / size
        } else {
            1.0
        };
        let ctrl: Vec<[f64; 2]> = curve
            .control_points()
            .iter()
            .zip(step.chunks_exact(2))
            .map(|(p, d)| [p[0] + scale * d[0], p[1] + scale * d[1]])
            .collect();
        let Ok(trial) = SplineCurve::new(curve.basis().clone(), ctrl) else {
            return Trial::Stop(Divergence::NonFinite);
        };
        let tz = [z[0] + scale * dz[0], z[1] + scale * dz[1]];
        let ev = self
            .problem
            .evaluate(&trial, self.pixels, &cur.feet, (tz[0], tz[1]));
        Trial::Step {
            point: (trial, tz),
            eval: ev,
            small: scale * size < self.tolerance,
        }
    }

    fn after_step(&self, (_, z): &(SplineCurve, [f64; 2]), _: &Eval) -> Option<Divergence> {
        (z[1].is_nan() || z[1].abs() <= 1e-9).then_some(Divergence::NoContrast)
    }
}

/// Levenberg–Marquardt ([`crate::solver::lm`], default damping) from
/// `curve` on a fixed band; a control-point move under `tolerance` pixels
/// is taken whatever the rounding of the regularised sum says.
pub(crate) fn levenberg_marquardt(
    problem: &Problem,
    curve: SplineCurve,
    pixels: &[Pixel],
    feet: &[f64],
    (a, c): (f64, f64),
    tolerance: f64,
    max_iterations: usize,
) -> BandRun {
    let cur = problem.evaluate(&curve, pixels, feet, (a, c));
    let fixed = Fixed {
        problem,
        pixels,
        tolerance,
    };
    let params = LmParams {
        max_iterations,
        ..LmParams::default()
    };
    let min = lm::minimise(&fixed, (curve, [a, c]), cur, &params);
    let outcome = match min.end {
        lm::End::Converged => Outcome::Converged,
        // No step lowers the sum: a minimum, to rounding; unless the sum
        // itself is not a number (then no step could be judged).
        lm::End::Stalled if !min.eval.cost().is_finite() => diverged(Divergence::NonFinite),
        lm::End::Stalled => Outcome::Converged,
        lm::End::IterationLimit => Outcome::IterationLimit,
        lm::End::Stopped(divergence) => diverged(divergence),
    };
    let (curve, z) = min.point;
    BandRun {
        curve,
        a: z[0],
        c: z[1],
        iterations: min.iterations,
        outcome,
        eval: min.eval,
    }
}

/// The result of [`run`].
pub(crate) struct Solved {
    pub end: BandRun,
    pub iterations: usize,
    pub passes: usize,
    pub band_pixels: usize,
}

/// Passes of [`levenberg_marquardt`] on re-selected bands until the band
/// no longer changes, from `start` with levels `(a, c)`; `pixels` and
/// `feet` are the start's band.
pub(crate) fn run(
    problem: &Problem,
    start: SplineCurve,
    (pixels, feet): (Vec<Pixel>, Vec<f64>),
    levels: (f64, f64),
    tolerance: f64,
    max_iterations: usize,
) -> Solved {
    let mut lm = levenberg_marquardt(
        problem,
        start,
        &pixels,
        &feet,
        levels,
        tolerance,
        max_iterations,
    );
    let mut iterations = lm.iterations;
    let mut passes = 1;
    let mut band_pixels = pixels.len();
    let mut previous = pixels;
    while lm.outcome == Outcome::Converged && passes < MAX_PASSES {
        let (pixels, feet) = match problem.select(&lm.curve) {
            Ok(sel) => sel,
            Err(_) => {
                let p = lm.curve.point(0.0);
                lm.outcome = diverged(Divergence::LeftImage { x: p[0], y: p[1] });
                break;
            }
        };
        if pixels == previous {
            break;
        }
        passes += 1;
        band_pixels = pixels.len();
        let budget = max_iterations.saturating_sub(iterations).max(1);
        lm = levenberg_marquardt(
            problem,
            lm.curve,
            &pixels,
            &feet,
            (lm.a, lm.c),
            tolerance,
            budget,
        );
        iterations += lm.iterations;
        previous = pixels;
    }
    Solved {
        end: lm,
        iterations,
        passes,
        band_pixels,
    }
}
