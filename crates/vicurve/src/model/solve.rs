//! Levenberg–Marquardt over the shape parameters and the gray levels.
//!
//! The residual of band pixel `q` (centre, value `f` as recorded) is
//! `e = f - a - c gamma(q; theta)`, with `gamma` the virtual image's
//! profile of the pixel's signed distance `d(q; theta)` to the shape (the
//! pixel-edge profile for silhouettes, the paper's profile otherwise), or,
//! in a sharp image, the pixel's exact coverage by the shape. The virtual
//! image is
//! evaluated at the pixel centres (pushed, as the B-spline engine's last
//! stage): no interpolation of the image. The unknowns are
//! `z = (theta, a, c)`; the Jacobian is exact in `a` and `c` and uses
//! `dgamma/dd . dd/dtheta` for the shape (the dependence of the pixel-edge
//! profile's normal and curvature on `theta` is left out: second order).
//!
//! Each iteration solves `(J^T J + mu diag(J^T J)) dz = -J^T e` (dense
//! Cholesky; a few to ~200 unknowns), accepts the step when the sum of
//! squares does not rise, and lowers or raises `mu` accordingly; it stops
//! when the largest parameter step, in pixels (angles times a length), is
//! under the tolerance. Steps are capped at [`MAX_STEP`] px.
//!
//! The band is chosen at the current shape and kept fixed while the
//! iterations run (the model is defined everywhere, so the sum of squares
//! is a smooth function on a fixed set of pixels); then it is chosen again
//! on the result, and the fit repeated until the set no longer changes.
//! The first pass uses a band [`COARSE_EXTRA`] px wider, to pull in a start
//! that is off by a fraction of a pixel (a polygon's vertices from the
//! rounded corners of the measured curve). For the pixel-edge profile the
//! blur is fitted between passes (golden section on the sum of squares,
//! the shape and gray levels refitted for each blur tried; see
//! `fit_blur`).
//!
//! The covariance of `z` is `s^2 (J^T J)^-1` at the solution, `s^2` the
//! residual variance `sum e^2 / (n - m)` (`n` pixels, `m` unknowns): the
//! Gauss–Newton covariance for independent pixel noise.

use super::geometry::{Geometry, Grad, Local, PixelCtx, MAX_GRAD};
use super::pixels::{select, BandPixel};
use super::{CoverageModel, ModelConfig, ModelProfile};
use crate::measurement::{Divergence, Outcome};
use crate::solver::lm::{self, LmParams, Problem, Trial};
use crate::solver::DenseCholesky;
use crate::virtual_image::pixel_edge::spread_variance;
use crate::virtual_image::Profile;
use std::f64::consts::FRAC_1_SQRT_2;

/// Largest parameter step of one iteration, pixels.
const MAX_STEP: f64 = 1.0;
/// The first pass's band is this much wider, pixels.
const COARSE_EXTRA: f64 = 1.5;
/// Tolerance of the first pass, pixels.
const COARSE_TOLERANCE: f64 = 1e-3;
/// Band selections (passes) at most.
const MAX_PASSES: usize = 8;
/// A fitted blur that differs by more than this (px) is worth another pass.
const BLUR_TOLERANCE: f64 = 0.01;
/// Blur updates at most.
const MAX_BLUR_UPDATES: usize = 3;
/// `CoverageModel::Auto` models the pixels by their exact coverage up to
/// this blur, px.
const EXACT_BLUR: f64 = 0.1;
/// Blur deviations a pixel's footprint reaches.
const BLUR_REACH: f64 = 3.5;
/// Tolerance (px) and iterations of the refits of the blur's search.
const BLUR_FIT_TOLERANCE: f64 = 1e-5;
const BLUR_FIT_ITERATIONS: usize = 6;
/// The blur's step either side of the fitted one for [`blur_coupling`],
/// pixels: wide enough that the refits' tolerance does not show in the
/// cost's second difference, narrow enough for its curvature.
const COUPLING_STEP: f64 = 0.05;

/// `(gamma, dgamma/dd)` of the profile at signed distance `d` (the
/// pixel-edge profile with its curvature shift, and the weight
/// `osculating` of its blurred osculating circle: 1 on a circle, whose
/// curvature is constant, 0 elsewhere; or the paper's profile centred
/// `blur_variance kappa / 2` from the curve).
pub(crate) fn profile_at(
    profile: ModelProfile,
    d: f64,
    normal: [f64; 2],
    (curvature, osculating): (f64, f64),
) -> (f64, f64) {
    match profile {
        ModelProfile::PixelEdge { blur } => {
            Profile::pixel_edge(blur).eval_at(d, 1.0, normal, (curvature, osculating))
        }
        ModelProfile::Paper {
            kind,
            half_width,
            blur_variance,
        } => Profile::Paper { kind }.eval(
            d - 0.5 * blur_variance * curvature,
            half_width,
            normal,
            0.0,
        ),
    }
}

/// `gamma` and `dgamma/dtheta` of a pixel; `None` when it is left out.
fn pixel_model(
    geom: &Geometry,
    q: [f64; 2],
    profile: ModelProfile,
    corners: PixelCtx,
) -> Option<(f64, Grad, bool)> {
    match geom.local(q, corners) {
        Local::Edge {
            d,
            normal,
            curvature,
            grad,
        } => {
            // A small ellipse under the blur: its exact blurred level.
            if let (Geometry::Ellipse(e), ModelProfile::PixelEdge { blur }) = (geom, profile) {
                let variance = spread_variance(blur);
                if e.bends_under(variance) {
                    let (value, grad) = e.blurred(q, variance);
                    return Some((value, grad, false));
                }
            }
            let osculating = match geom {
                Geometry::Circle(_) => 1.0,
                _ => 0.0,
            };
            let (v, dv) = profile_at(profile, d, normal, (curvature, osculating));
            let mut g = Grad::new();
            for (i, gi) in grad.iter() {
                g.add(i, dv * gi);
            }
            Some((v, g, false))
        }
        Local::Coverage { value, grad, .. } => Some((value, grad, true)),
        Local::Excluded { .. } => None,
    }
}

/// The band's half-width for a profile, px: for the pixel edge, as the
/// B-spline engine's pixel-edge stage (the pixel's extent along a normal,
/// two blur deviations and half a pixel of each flat level; at least
/// 1.5 px; rounded up to a quarter pixel).
pub(crate) fn band_half_width(profile: ModelProfile) -> f64 {
    match profile {
        ModelProfile::PixelEdge { blur } => {
            let r = FRAC_1_SQRT_2 + 2.0 * blur + 0.5;
            (r.max(1.5) * 4.0).ceil() / 4.0
        }
        ModelProfile::Paper { half_width, .. } => half_width,
    }
}

/// How the pixels are modelled under `profile` and `config`.
pub(crate) fn pixel_ctx(profile: ModelProfile, config: &ModelConfig) -> PixelCtx {
    match profile {
        ModelProfile::PixelEdge { blur } => PixelCtx {
            reach: FRAC_1_SQRT_2 + BLUR_REACH * blur + 0.05,
            exact: match config.coverage {
                CoverageModel::Auto => blur <= EXACT_BLUR,
                CoverageModel::Exact => true,
                CoverageModel::PixelEdge => false,
            },
            exclude_corners: config.exclude_corners,
        },
        ModelProfile::Paper { half_width, .. } => PixelCtx {
            reach: half_width + FRAC_1_SQRT_2,
            exact: false,
            exclude_corners: true,
        },
    }
}

/// Sums over the band at one point `z`.
#[derive(Clone, Debug)]
pub(crate) struct Eval {
    /// `sum e^2`.
    pub cost: f64,
    /// `J^T J`, row-major `m x m`.
    pub h: Vec<f64>,
    /// `J^T e`.
    pub g: Vec<f64>,
    /// Pixels used.
    pub used: usize,
    /// Of which modelled by exact coverage.
    pub coverage: usize,
    /// Pixels left out.
    pub excluded: usize,
}

fn evaluate(
    geom: &Geometry,
    pixels: &[BandPixel],
    profile: ModelProfile,
    corners: PixelCtx,
    a: f64,
    c: f64,
) -> Eval {
    let p = geom.params().len();
    let m = p + 2;
    let mut ev = Eval {
        cost: 0.0,
        h: vec![0.0; m * m],
        g: vec![0.0; m],
        used: 0,
        coverage: 0,
        excluded: 0,
    };
    let mut idx = [0usize; MAX_GRAD + 2];
    let mut val = [0.0f64; MAX_GRAD + 2];
    for px in pixels {
        let Some((gamma, dgamma, exact)) = pixel_model(geom, px.q, profile, corners) else {
            ev.excluded += 1;
            continue;
        };
        ev.used += 1;
        ev.coverage += usize::from(exact);
        let e = px.f - a - c * gamma;
        let mut len = 0;
        for (i, v) in dgamma.iter() {
            idx[len] = i;
            val[len] = -c * v;
            len += 1;
        }
        idx[len] = p;
        val[len] = -1.0;
        idx[len + 1] = p + 1;
        val[len + 1] = -gamma;
        len += 2;
        for k in 0..len {
            ev.g[idx[k]] += val[k] * e;
            let row = idx[k] * m;
            for l in 0..len {
                ev.h[row + idx[l]] += val[k] * val[l];
            }
        }
        ev.cost += e * e;
    }
    ev
}

/// The linear least-squares gray levels `(a, c)` and the sum of squares
/// at a fixed shape; `None` without contrast.
pub(crate) fn levels(
    geom: &Geometry,
    pixels: &[BandPixel],
    profile: ModelProfile,
    corners: PixelCtx,
) -> Option<(f64, f64, f64)> {
    let (mut n, mut sg, mut sgg, mut sf, mut sfg, mut sff) = (0.0, 0.0, 0.0, 0.0, 0.0, 0.0);
    for px in pixels {
        let Some((g, ..)) = pixel_model(geom, px.q, profile, corners) else {
            continue;
        };
        n += 1.0;
        sg += g;
        sgg += g * g;
        sf += px.f;
        sfg += px.f * g;
        sff += px.f * px.f;
    }
    let det = n * sgg - sg * sg;
    if det.is_nan() || det <= 1e-12 * n * n {
        return None;
    }
    let a = (sgg * sf - sg * sfg) / det;
    let c = (n * sfg - sg * sf) / det;
    Some((a, c, (sff - a * sf - c * sfg).max(0.0)))
}

/// How one run of iterations on a fixed band ended.
pub(crate) struct BandRun {
    pub geom: Geometry,
    pub a: f64,
    pub c: f64,
    pub iterations: usize,
    pub outcome: Outcome,
    /// The sums at the final point (undamped).
    pub eval: Eval,
}

/// The fit on a fixed band as a Levenberg–Marquardt problem: the point is
/// `z = (theta, a, c)` with the geometry of `theta`.
struct Fixed<'a> {
    pixels: &'a [BandPixel],
    profile: ModelProfile,
    corners: PixelCtx,
    /// Shape parameters (`theta`'s length).
    p: usize,
    /// Pixels per unit of each shape parameter (a step's size in pixels).
    scales: Vec<f64>,
    tolerance: f64,
}

impl Problem for Fixed<'_> {
    type Point = (Vec<f64>, Geometry);
    type Eval = Eval;
    type Stop = Divergence;

    fn cost(&self, eval: &Eval) -> f64 {
        eval.cost
    }

    fn trial(
        &self,
        (z, geom): &(Vec<f64>, Geometry),
        cur: &Eval,
        mu: f64,
    ) -> Trial<(Vec<f64>, Geometry), Eval, Divergence> {
        let p = self.p;
        let m = p + 2;
        let max_diag = (0..m).map(|i| cur.h[i * m + i]).fold(0.0, f64::max);
        let mut damped = cur.h.clone();
        for i in 0..m {
            damped[i * m + i] += mu * cur.h[i * m + i].max(1e-9 * max_diag);
        }
        let Ok(chol) = DenseCholesky::factor(&damped, m) else {
            return Trial::Retry;
        };
        let mut step: Vec<f64> = cur.g.iter().map(|v| -v).collect();
        chol.solve_in_place(&mut step);
        let size = (0..p)
            .map(|k| (step[k] * self.scales[k]).abs())
            .fold(0.0, f64::max);
        if !size.is_finite() {
            return Trial::Stop(Divergence::NonFinite);
        }
        if size > MAX_STEP {
            step.iter_mut().for_each(|s| *s *= MAX_STEP / size);
        }
        let trial: Vec<f64> = z.iter().zip(&step).map(|(a, b)| a + b).collect();
        let Some(trial_geom) = geom.with_params(&trial[..p]) else {
            return Trial::Retry;
        };
        let ev = evaluate(
            &trial_geom,
            self.pixels,
            self.profile,
            self.corners,
            trial[p],
            trial[p + 1],
        );
        Trial::Step {
            point: (trial, trial_geom),
            eval: ev,
            small: size < self.tolerance,
        }
    }

    fn after_step(&self, (z, _): &(Vec<f64>, Geometry), cur: &Eval) -> Option<Divergence> {
        let p = self.p;
        if cur.used < p + 4 {
            Some(Divergence::Degenerate)
        } else if z[p + 1].is_nan() || z[p + 1].abs() <= 1e-9 {
            Some(Divergence::NoContrast)
        } else {
            None
        }
    }
}

/// Levenberg–Marquardt ([`crate::solver::lm`], default damping) from
/// `geom` and levels `(a, c)` on a fixed band; a step under `tolerance`
/// pixels is taken whatever the rounding of the sum of squares says.
#[allow(clippy::too_many_arguments)]
fn levenberg_marquardt(
    geom: Geometry,
    pixels: &[BandPixel],
    profile: ModelProfile,
    corners: PixelCtx,
    (a, c): (f64, f64),
    tolerance: f64,
    max_iterations: usize,
) -> BandRun {
    let p = geom.params().len();
    let m = p + 2;
    let problem = Fixed {
        pixels,
        profile,
        corners,
        p,
        scales: geom.scales(),
        tolerance,
    };
    let mut z = geom.params();
    z.extend([a, c]);
    let cur = evaluate(&geom, pixels, profile, corners, a, c);
    if cur.used < m + 2 {
        return BandRun {
            geom,
            a: z[p],
            c: z[p + 1],
            iterations: 0,
            outcome: diverged(Divergence::Degenerate),
            eval: cur,
        };
    }
    let params = LmParams {
        max_iterations,
        ..LmParams::default()
    };
    let min = lm::minimise(&problem, (z, geom), cur, &params);
    let ((z, geom), outcome) = (
        min.point,
        match min.end {
            // No step lowers the sum of squares: a minimum, to rounding.
            lm::End::Converged | lm::End::Stalled => Outcome::Converged,
            lm::End::IterationLimit => Outcome::IterationLimit,
            lm::End::Stopped(divergence) => diverged(divergence),
        },
    );
    BandRun {
        geom,
        a: z[p],
        c: z[p + 1],
        iterations: min.iterations,
        outcome,
        eval: min.eval,
    }
}

fn diverged(divergence: Divergence) -> Outcome {
    Outcome::Diverged { divergence }
}

/// The result of [`run`].
pub(crate) struct Solved {
    pub geom: Geometry,
    pub a: f64,
    pub c: f64,
    pub profile: ModelProfile,
    pub half_width: f64,
    pub outcome: Outcome,
    pub iterations: usize,
    pub passes: usize,
    pub eval: Eval,
    /// The blur's part in the shape's uncertainty, when the blur was
    /// fitted ([`blur_coupling`]).
    pub blur_coupling: Option<BlurCoupling>,
}

/// How the fitted blur moves the shape: the parameters' change per pixel
/// of blur (the shape refitted at each blur) and the blur's information,
/// half the profiled sum of squares' second derivative in the blur.
pub(crate) struct BlurCoupling {
    /// `d theta / d blur`, in the geometry's parameter order.
    pub slope: Vec<f64>,
    /// Half the second derivative of the cost in the blur (per unit of
    /// noise variance: the blur's variance is the noise's over this).
    pub information: f64,
}

impl BlurCoupling {
    /// Add the blur's part `v_b slope slope^T` to the row-major `p x p`
    /// covariance `cov` of the parameters, for the noise variance `s2`.
    pub fn add_to(&self, cov: &mut [f64], s2: f64) {
        let p = self.slope.len();
        if self.information <= 0.0 || cov.len() != p * p {
            return;
        }
        let var = s2 / self.information;
        for i in 0..p {
            for j in 0..p {
                cov[i * p + j] += var * self.slope[i] * self.slope[j];
            }
        }
    }
}

/// Why [`run`] could not start.
pub(crate) enum StartFailure {
    /// A band pixel of the start lies outside the image.
    Outside([f64; 2], f64),
    /// The band has too few pixels for the unknowns.
    Empty(usize, usize),
    /// No contrast at the start.
    NoContrast,
}

/// The whole fit from `start` (module docs).
pub(crate) fn run(
    image: &crate::Image,
    start: Geometry,
    profile: ModelProfile,
    config: &ModelConfig,
) -> Result<Solved, StartFailure> {
    let mut profile = profile;
    let mut half_width = band_half_width(profile);
    let mut corners = pixel_ctx(profile, config);
    let unknowns = start.params().len() + 2;
    let coarse = half_width + COARSE_EXTRA;
    let pixels =
        select(image, &start, coarse, corners).map_err(|q| StartFailure::Outside(q, coarse))?;
    if pixels.len() < unknowns + 2 {
        return Err(StartFailure::Empty(pixels.len(), unknowns));
    }
    let (a, c, _) = levels(&start, &pixels, profile, corners).ok_or(StartFailure::NoContrast)?;
    // As the B-spline engine: a contrast lost in the spread of the values.
    let n = pixels.len() as f64;
    let mean = pixels.iter().map(|p| p.f).sum::<f64>() / n;
    let spread = (pixels.iter().map(|p| (p.f - mean).powi(2)).sum::<f64>() / n).sqrt();
    if c.abs() <= 1e-9 || c.abs() < 1e-6 * spread {
        return Err(StartFailure::NoContrast);
    }
    let mut lm = levenberg_marquardt(
        start,
        &pixels,
        profile,
        corners,
        (a, c),
        COARSE_TOLERANCE.max(config.tolerance),
        config.max_iterations,
    );
    let mut iterations = lm.iterations;
    let mut passes = 1;
    let mut blur_updates = 0;
    let mut previous: Option<Vec<BandPixel>> = None;
    while !matches!(lm.outcome, Outcome::Diverged { .. }) && passes < MAX_PASSES {
        let pixels = match select(image, &lm.geom, half_width, corners) {
            Ok(p) => p,
            Err([x, y]) => {
                lm.outcome = diverged(Divergence::LeftImage { x, y });
                break;
            }
        };
        if previous.as_ref() == Some(&pixels) {
            break;
        }
        passes += 1;
        let budget = config.max_iterations.saturating_sub(iterations).max(1);
        lm = levenberg_marquardt(
            lm.geom,
            &pixels,
            profile,
            corners,
            (lm.a, lm.c),
            config.tolerance,
            budget,
        );
        iterations += lm.iterations;
        if let (ModelProfile::PixelEdge { blur }, true, Outcome::Converged) =
            (profile, config.fit_blur, lm.outcome)
        {
            if blur_updates < MAX_BLUR_UPDATES {
                let fitted = fit_blur(&lm, &pixels, blur, corners);
                if (fitted - blur).abs() > BLUR_TOLERANCE {
                    blur_updates += 1;
                    profile = ModelProfile::PixelEdge { blur: fitted };
                    half_width = band_half_width(profile);
                    corners = pixel_ctx(profile, config);
                    previous = None;
                    continue;
                }
            }
        }
        previous = Some(pixels);
    }
    // At the blur in use, also where the iterations ran out (the blur was
    // then not refitted, and is no better known).
    let blur_coupling = match (profile, config.fit_blur, &previous) {
        (ModelProfile::PixelEdge { blur }, true, Some(pixels))
            if !matches!(lm.outcome, Outcome::Diverged { .. }) =>
        {
            blur_coupling(&lm, pixels, blur, corners)
        }
        _ => None,
    };
    Ok(Solved {
        geom: lm.geom,
        a: lm.a,
        c: lm.c,
        profile,
        half_width,
        outcome: lm.outcome,
        iterations,
        passes,
        eval: lm.eval,
        blur_coupling,
    })
}

/// The shape and gray levels refitted from `end` on `pixels` under the
/// pixel edge of blur `blur` (px), a few iterations: every pixel by the
/// pixel-edge profile and corners left out, so that the sums of the blurs
/// tried compare the same pixels ([`fit_blur`], [`blur_coupling`]).
fn refit_at_blur(end: &BandRun, pixels: &[BandPixel], blur: f64, ctx: PixelCtx) -> BandRun {
    let ctx = PixelCtx {
        exact: false,
        exclude_corners: true,
        ..ctx
    };
    levenberg_marquardt(
        end.geom.clone(),
        pixels,
        ModelProfile::PixelEdge { blur },
        ctx,
        (end.a, end.c),
        BLUR_FIT_TOLERANCE,
        BLUR_FIT_ITERATIONS,
    )
}

/// The [`BlurCoupling`] at the fitted `blur` (px): the shape and gray
/// levels refitted (as [`fit_blur`] does) at `blur` and `blur +-
/// COUPLING_STEP`; `None` for a blur under two steps (a focused edge,
/// whose position hardly depends on it) or a cost that does not curve
/// upwards. Why: a dot a blur or so across looks almost the same as a
/// larger dot under a smaller blur, so the blur's uncertainty moves its
/// radius by several times the Gauss–Newton `sigma` at a fixed blur
/// (docs/benchmarks.md, "Dots a blur or so across").
fn blur_coupling(
    end: &BandRun,
    pixels: &[BandPixel],
    blur: f64,
    ctx: PixelCtx,
) -> Option<BlurCoupling> {
    if blur < 2.0 * COUPLING_STEP {
        return None;
    }
    let refit = |b: f64| {
        let run = refit_at_blur(end, pixels, b, ctx);
        (run.eval.cost, run.geom.params())
    };
    let (lo, mid, hi) = (
        refit(blur - COUPLING_STEP),
        refit(blur),
        refit(blur + COUPLING_STEP),
    );
    let second = (lo.0 - 2.0 * mid.0 + hi.0) / (COUPLING_STEP * COUPLING_STEP);
    if !(second > 0.0 && second.is_finite()) {
        return None;
    }
    let slope =
        lo.1.iter()
            .zip(&hi.1)
            .map(|(l, h)| (h - l) / (2.0 * COUPLING_STEP))
            .collect();
    Some(BlurCoupling {
        slope,
        information: 0.5 * second,
    })
}

/// The optical blur (px) of the pixel-edge profile that best fits the band
/// (golden section within 30 % + 0.15 px of `current`, and 0 when that is
/// as good, as the B-spline engine's `fit_blur`), by profile likelihood:
/// for each blur tried, the shape and gray levels are refitted (a few
/// iterations from `end`). At a fixed shape the blur would stay wherever
/// the start put it when the band cannot tell the blur from a shift (an
/// axis-aligned edge in an unblurred image shows a single row of partial
/// pixels: three gray levels, as many unknowns); refitted, every blur fits
/// equally well there and the smallest, 0, is taken.
fn fit_blur(end: &BandRun, pixels: &[BandPixel], current: f64, ctx: PixelCtx) -> f64 {
    let ssr = |blur: f64| refit_at_blur(end, pixels, blur, ctx).eval.cost;
    let lo = (0.7 * current - 0.15).max(0.0);
    let hi = 1.3 * current + 0.15;
    let best = crate::psf::golden(lo, hi, 12, ssr);
    if lo == 0.0 && ssr(0.0) <= ssr(best) * (1.0 + 1e-9) + 1e-20 {
        0.0
    } else {
        best
    }
}
