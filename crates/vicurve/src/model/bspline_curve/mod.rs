//! The free B-spline curve model (`--model bspline-curve`): the curve is
//! itself a B-spline curve `C(u) = sum_k N_k(u) P_k` whose control points
//! `P_k = (x_k, y_k)` are the unknowns, rather than a normal displacement
//! `U(s) n(s)` on a reference (the engine of [`crate::fit`]). The result is
//! a B-spline curve with sub-pixel precision, each control point with its
//! uncertainty, ready for CAD export ([`crate::export`]).
//!
//! ```no_run
//! use vicurve::{curve::InitialCurve, fit::{measure, FitConfig}, io::load_image};
//! use vicurve::model::bspline_curve::{measure_bspline_curve, BsplineCurveConfig};
//! let image = load_image("part.png".as_ref())?;
//! let init = InitialCurve::Circle { cx: 320.0, cy: 240.0, r: 100.0 };
//! let config = FitConfig::default();
//! let m = measure(&image, &init, &config)?;
//! let fit = measure_bspline_curve(&image, &m, &config, &BsplineCurveConfig::default())?;
//! for p in &fit.control_points {
//!     println!("{:.4} {:.4} +- {:.4} px along the normal", p.x, p.y, p.sigma_n);
//! }
//! # Ok::<(), vicurve::Error>(())
//! ```
//!
//! # How
//! 1. **Start.** The B-spline measurement of the same image gives the
//!    curve; a least-squares B-spline of the fit's degree on a uniform
//!    basis is fitted to its samples ([`start_curve`]) with control points
//!    [`BsplineCurveConfig::control_spacing`] px apart (default 4; finer
//!    spacing follows tighter bends but spreads the pixels, hence
//!    the noise, over more unknowns). The basis (knots, parameter range)
//!    stays fixed; only the control points move. The spacing is not
//!    chosen from the measured samples: on small shapes they wander by up
//!    to 2e-2 px (tests), and following them would ask for control points
//!    a pixel apart.
//! 2. **Residuals.** Each band pixel (centre within `R` of the curve, its
//!    closest point interior) is compared, as recorded, with
//!    `a + c gamma(d)`, `d` its signed distance to the current curve (exact
//!    projection, Newton from its previous foot). `gamma` is the profile of
//!    the parametric models ([`super::ModelProfile`]): for silhouettes the
//!    pixel-edge profile (an ideal pixel through the Gaussian blur the
//!    measurement fitted, curvature shift included), for contours the
//!    paper's profile. Not the exact pixel coverage the circle, ellipse and
//!    polygon use in sharp images: the area of a pixel inside a free
//!    B-spline curve has no closed form (it needs the curve clipped to each
//!    pixel, and its derivatives with respect to every control point); the
//!    pixel-edge profile's error on a curved edge is 2 to 3e-4 px (docs of
//!    the circle model), far below what 8-bit images resolve on a free
//!    curve.
//! 3. **Unknowns.** `2n` control coordinates and the gray levels `a, c`,
//!    by Levenberg–Marquardt on the banded normal equations bordered by
//!    `a, c` ([`system`](self) module). `dd/dP_k = -N_k(u*) n(u*)` (envelope
//!    theorem at the foot `u*`).
//! 4. **Tangential regularisation.** A move of the control points that
//!    slides the curve along itself changes no distance to first order:
//!    for a straight edge those moves are an exact null space of the
//!    normal matrix (singular), for a curved one a near null space
//!    (ill-conditioned; the tests check the straight case): without a
//!    constraint the control points drift along the curve wherever the
//!    rounding or second-order terms push them. The sum of squares gets the
//!    term `lambda sum_k (t_k . (P_k - P0_k))^2`: the control points are
//!    anchored to their start `P0_k` *along the start's tangent* `t_k` at
//!    their Greville abscissa, and free across it. `lambda` is
//!    [`BsplineCurveConfig::tangential_weight`] times the mean normal
//!    stiffness of a control point (`n_k^T H_kk n_k`, the data's) at the
//!    start. Why this choice rather than uniform speed (penalising the
//!    variance of `|C'(u)|`) or a step penalty: it is a fixed quadratic (the
//!    fit stays a least-squares problem with a monotone cost), it acts only
//!    along the curve, and the start is already a good parametrisation
//!    (chord length of the measured samples), so the data need no
//!    tangential motion to speak of; its pull on the normal position is
//!    second order (the anchors' tangents turn away from the fitted
//!    curve's by the curvature times the slide) and measured below the
//!    8-bit noise (tests: `tangential_weight` from 1e-4 to 1e-1).
//! 5. **Uncertainties.** `Cov = s^2 H^-1` at the solution, `H` the
//!    regularised normal matrix and `s^2 = sum e^2 / (N - m_eff)` with
//!    `m_eff = tr(H^-1 J^T J)`, the effective number of unknowns (about
//!    `n + 2`: the tangential components are fixed by the regularisation,
//!    not by the pixels). Each control point reports its `2 x 2`
//!    covariance and its standard deviation along the curve's normal at
//!    its Greville abscissa; each sample of the curve the standard
//!    deviation of its position along the normal,
//!    `sqrt(sum_ab N_a N_b n^T Cov_ab n)`. The tangential part of a
//!    control point's covariance is that of the regularisation, not of
//!    the image.
//!
//! Coordinates are pixels, `x` the column and `y` the row; the curve keeps
//! the measurement's orientation (closed curves counterclockwise on screen,
//! normal outward).

mod solve;
mod system;

use super::{ModelProfile, ShapeModel};
use crate::curve::{SplineCurve, SplineCurveData};
use crate::error::{Error, Result};
use crate::fit::FitConfig;
use crate::image::Image;
use crate::measurement::{Measurement, Outcome, Sample};
use crate::spline::MAX_DEGREE;
use serde::{Deserialize, Serialize};
use solve::{Pixel, Problem};
use system::Factored;

/// Settings of the B-spline curve model. `BsplineCurveConfig::default()`
/// gives the documented defaults.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
#[serde(default)]
pub struct BsplineCurveConfig {
    /// Iteration limit over all passes. Default: 100.
    pub max_iterations: usize,
    /// Stop when the largest control-point move is under this, pixels.
    /// Default: 1e-5.
    pub tolerance: f64,
    /// Spacing of the control points, pixels (of the start's chord
    /// length). Default: 4.
    pub control_spacing: f64,
    /// Weight of the tangential regularisation, relative to the mean
    /// normal stiffness of a control point (module docs); 0 turns it off
    /// (the normal matrix is then singular or nearly so). Default: 1e-3.
    pub tangential_weight: f64,
}

impl Default for BsplineCurveConfig {
    fn default() -> Self {
        BsplineCurveConfig {
            max_iterations: 100,
            tolerance: 1e-5,
            control_spacing: 4.0,
            tangential_weight: 1e-3,
        }
    }
}

impl BsplineCurveConfig {
    /// Check the fields. Errors: [`Error::InvalidParameter`].
    pub fn validate(&self) -> Result<()> {
        let positive = |name: &'static str, v: f64| {
            if v.is_finite() && v > 0.0 {
                Ok(())
            } else {
                Err(Error::invalid(
                    name,
                    format!("{v}: must be a positive number"),
                ))
            }
        };
        if self.max_iterations == 0 {
            return Err(Error::invalid("max_iterations", "must be at least 1"));
        }
        positive("tolerance", self.tolerance)?;
        positive("control_spacing", self.control_spacing)?;
        if !(self.tangential_weight.is_finite() && self.tangential_weight >= 0.0) {
            return Err(Error::invalid(
                "tangential_weight",
                format!("{}: must be 0 or more", self.tangential_weight),
            ));
        }
        Ok(())
    }
}

/// One fitted control point.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub struct ControlPoint {
    /// x (column), px.
    pub x: f64,
    /// y (row), px.
    pub y: f64,
    /// Standard deviation along `normal`, px (noise only).
    pub sigma_n: f64,
    /// Unit normal of the fitted curve at the point's Greville abscissa.
    pub normal: [f64; 2],
    /// Covariance `[xx, xy, yy]`, px^2 (its tangential part is the
    /// regularisation's, module docs).
    pub covariance: [f64; 3],
}

/// The result of a B-spline curve fit.
#[derive(Clone, Debug, Serialize)]
pub struct BsplineCurveFit {
    /// Always [`ShapeModel::BsplineCurve`].
    pub model: ShapeModel,
    /// How the fit ended (a diverged fit keeps its last curve).
    pub outcome: Outcome,
    /// The fitted curve: degree, closed, knots and control points (the
    /// format of the measurement's `curve`; closed curves repeat their
    /// first `degree` control points at the end).
    pub curve: SplineCurveData,
    /// The `n` distinct control points with their uncertainties, in order.
    pub control_points: Vec<ControlPoint>,
    /// Dark level `a` of the virtual image.
    pub a: f64,
    /// Contrast `c` (its sign is the polarity).
    pub c: f64,
    /// The profile.
    pub profile: ModelProfile,
    /// Band half-width, px.
    pub half_width: f64,
    /// Band pixels of the last pass.
    pub band_pixels: usize,
    /// RMS of the residual, gray levels.
    pub residual_rms: f64,
    /// Residual standard deviation per pixel, `sqrt(sum e^2 / (N -
    /// m_eff))`, gray levels.
    pub noise_sigma: f64,
    /// Effective number of unknowns `m_eff = tr(H^-1 J^T J)`.
    pub effective_unknowns: f64,
    /// Largest slide of a control point along the start's tangent, px.
    pub tangential_slide: f64,
    /// Largest normal move of the curve from its start, px (at the
    /// control points' Greville abscissae).
    pub normal_move: f64,
    /// Iterations over all passes.
    pub iterations: usize,
    /// Band selections.
    pub passes: usize,
    /// Control-point spacing (element length of the basis), px.
    pub control_spacing: f64,
    /// Largest distance from the measured samples to the start, px (NaN
    /// for a start given directly).
    pub start_fit_error: f64,
    /// The settings.
    pub config: BsplineCurveConfig,
    #[serde(skip)]
    spline: SplineCurve,
    /// Band of the control points' covariance ([`Factored::inverse_band`]
    /// times `s^2`).
    #[serde(skip)]
    cov: Vec<[f64; 4]>,
}

impl BsplineCurveFit {
    /// The fitted curve.
    pub fn spline(&self) -> &SplineCurve {
        &self.spline
    }

    /// The covariance of control points `k` and `l` (`|k - l| <= degree`,
    /// modulo `n` for a closed curve), row-major `[xx, xy, yx, yy]`; zero
    /// farther apart (not computed).
    fn block(&self, k: usize, l: usize) -> [f64; 4] {
        let basis = self.spline.basis();
        let (p, n) = (basis.degree(), basis.n_functions());
        let forward = |from: usize, to: usize| {
            if basis.is_closed() {
                (to + n - from) % n
            } else {
                to.wrapping_sub(from)
            }
        };
        let o = forward(k, l);
        if o <= p {
            return self.cov[k * (p + 1) + o];
        }
        let o = forward(l, k);
        if o <= p {
            let b = self.cov[l * (p + 1) + o];
            return [b[0], b[2], b[1], b[3]];
        }
        [0.0; 4]
    }

    /// Standard deviation of the curve's position along its normal `n` at
    /// parameter `u`, px.
    fn sigma_at(&self, u: f64, n: [f64; 2]) -> f64 {
        let basis = self.spline.basis();
        let p = basis.degree();
        let mut v = [0.0; MAX_DEGREE + 1];
        let first = basis.eval(u, &mut v);
        let mut q = 0.0;
        for a in 0..=p {
            for b in 0..=p {
                let m = self.block(basis.index(first, a), basis.index(first, b));
                let quad = n[0] * (m[0] * n[0] + m[1] * n[1]) + n[1] * (m[2] * n[0] + m[3] * n[1]);
                q += v[a] * v[b] * quad;
            }
        }
        q.max(0.0).sqrt()
    }

    /// Samples of the fitted curve at most `spacing` px apart (both ends
    /// of an open curve included), `s` the arc length from the start, with
    /// the unit normal, the standard deviation of the position along it
    /// (`sigma`, px) and `weight` 1.
    ///
    /// Errors: [`Error::InvalidParameter`] for a spacing that is not a
    /// positive number.
    pub fn samples(&self, spacing: f64) -> Result<Vec<Sample>> {
        if !(spacing.is_finite() && spacing > 0.0) {
            return Err(Error::invalid(
                "sample spacing",
                format!("{spacing}: must be a positive number of pixels"),
            ));
        }
        let curve = &self.spline;
        let length = curve.arc_length();
        let count = ((length / spacing).ceil() as usize).max(2);
        let params = curve.sample_params(if curve.is_closed() { count } else { count + 1 });
        let mut s = 0.0;
        let mut prev = 0.0;
        Ok(params
            .iter()
            .map(|&u| {
                s += curve.arc_length_between(prev, u);
                prev = u;
                let f = curve.frame(u);
                Sample {
                    s,
                    x: f.point[0],
                    y: f.point[1],
                    nx: f.normal[0],
                    ny: f.normal[1],
                    sigma: self.sigma_at(u, f.normal),
                    sigma_noise: self.sigma_at(u, f.normal),
                    misfit: false,
                    weight: 1.0,
                }
            })
            .collect())
    }
}

/// Greville abscissa of control point `k` on the uniform basis (knots
/// `(i - p) h`): `(k - (p - 1) / 2) h`, wrapped (closed) or clamped to
/// `[0, L]` (open).
fn greville(curve: &SplineCurve, k: usize) -> f64 {
    let b = curve.basis();
    let u = (k as f64 - 0.5 * (b.degree() as f64 - 1.0)) * b.element_length();
    if b.is_closed() {
        u.rem_euclid(b.length())
    } else {
        u.clamp(0.0, b.length())
    }
}

/// The start of the fit from the samples of a measured curve (in its
/// direction; closed curves without repeating the first point): the
/// least-squares B-spline of `degree` with control points
/// `config.control_spacing` px apart. Returns the curve and its largest
/// distance to the points, px.
///
/// Errors: those of [`SplineCurve::fit`]; [`Error::InvalidParameter`] for
/// an invalid configuration.
pub fn start_curve(
    points: &[[f64; 2]],
    closed: bool,
    degree: usize,
    config: &BsplineCurveConfig,
) -> Result<(SplineCurve, f64)> {
    config.validate()?;
    let curve = SplineCurve::fit(points, closed, degree, config.control_spacing)?;
    let error = fit_error(&curve, points);
    Ok((curve, error))
}

/// Largest distance from `points` to `curve`: each point starts from
/// the nearest vertex of a polyline of the curve (chords of at most
/// 0.5 px), then Newton's projection.
fn fit_error(curve: &SplineCurve, points: &[[f64; 2]]) -> f64 {
    let count = ((curve.param_length() / 0.5).ceil() as usize).max(8);
    let params = curve.sample_params(count);
    let poly: Vec<[f64; 2]> = params.iter().map(|&u| curve.point(u)).collect();
    let len = poly.len() as i64;
    let mut worst: f64 = 0.0;
    let mut hint = 0i64;
    for p in points {
        let d2 = |i: i64| {
            let q = poly[i.rem_euclid(len) as usize];
            (q[0] - p[0]).powi(2) + (q[1] - p[1]).powi(2)
        };
        // Consecutive points are near each other: a window around the
        // previous one first, the whole polyline when that is not close.
        let mut best = (hint - 16..=hint + 16)
            .min_by(|&i, &j| d2(i).total_cmp(&d2(j)))
            .unwrap_or(0);
        if d2(best) > 4.0 {
            best = (0..len)
                .min_by(|&i, &j| d2(i).total_cmp(&d2(j)))
                .unwrap_or(0);
        }
        hint = best.rem_euclid(len);
        let pr = curve.project(p[0], p[1], params[hint as usize]);
        worst = worst.max(pr.r.abs());
    }
    worst
}

/// Fit a free B-spline curve to the curve a measurement `m` of `image`
/// found (with `fit_config`): [`start_curve`] of its samples at the fit's
/// degree, the profile [`ModelProfile::from_measurement`], then
/// [`fit_bspline_curve`].
///
/// Errors: those of [`start_curve`] and [`fit_bspline_curve`].
pub fn measure_bspline_curve(
    image: &Image,
    m: &Measurement,
    fit_config: &FitConfig,
    config: &BsplineCurveConfig,
) -> Result<BsplineCurveFit> {
    if !m.curve.corners().is_empty() {
        // The free curve's knots are uniform: it would round the corners.
        return Err(Error::ModelMismatch {
            model: ShapeModel::BsplineCurve.to_string(),
            reason: "the measured curve has corners (--break) and the free B-spline curve has uniform knots; export the measured curve itself (--dxf, --svg-curve)".into(),
        });
    }
    let (start, error) = start_curve(&m.points(), m.curve.is_closed(), fit_config.degree, config)?;
    let mut fit = fit_bspline_curve(
        image,
        &start,
        ModelProfile::from_measurement(m, fit_config),
        config,
    )?;
    fit.start_fit_error = error;
    Ok(fit)
}

/// Fit the control points of `start` (its basis kept) to `image`, comparing
/// with the virtual image of `profile`.
///
/// Errors are for inputs that cannot be fitted at all:
/// [`Error::InvalidParameter`] for an invalid configuration or profile;
/// [`Error::CurveOutsideImage`] / [`Error::BandOutsideImage`] when the
/// start or its band leaves the image; [`Error::EmptyBand`] for too few
/// band pixels; [`Error::ModelMismatch`] when the band sees no contrast or
/// the normal matrix is singular at the start. A fit that starts but fails
/// later is reported in [`BsplineCurveFit::outcome`].
pub fn fit_bspline_curve(
    image: &Image,
    start: &SplineCurve,
    profile: ModelProfile,
    config: &BsplineCurveConfig,
) -> Result<BsplineCurveFit> {
    config.validate()?;
    profile.validate()?;
    let mismatch = |reason: &str| Error::ModelMismatch {
        model: ShapeModel::BsplineCurve.to_string(),
        reason: reason.into(),
    };
    if !start.basis().breaks().is_empty() {
        return Err(mismatch(
            "the start has repeated knots (corners); the free B-spline curve needs uniform knots",
        ));
    }
    let n = start.basis().n_functions();
    let p = start.basis().degree();
    let closed = start.is_closed();
    let anchors = start.control_points().to_vec();
    let tangents: Vec<[f64; 2]> = (0..n)
        .map(|k| start.frame(greville(start, k)).tangent)
        .collect();
    let mut problem = Problem {
        image,
        profile,
        anchors,
        tangents,
        lambda: 0.0,
        half_width: super::solve::band_half_width(profile),
    };
    let (pixels, feet) = problem.select(start)?;
    let unknowns = 2 * n + 2;
    if pixels.len() < unknowns + 2 {
        return Err(Error::EmptyBand {
            pixels: pixels.len(),
            unknowns,
        });
    }
    let (a, c) = levels(&problem, start, &pixels, &feet)
        .ok_or_else(|| mismatch("the band around the start sees no contrast"))?;
    // The regularisation's weight: relative to the data's mean normal
    // stiffness of a control point at the start.
    let ev = problem.evaluate(start, &pixels, &feet, (a, c));
    let stiffness = (0..n)
        .map(|k| {
            let nk = start.frame(greville(start, k)).normal;
            let (i, j) = (2 * k, 2 * k + 1);
            nk[0] * nk[0] * ev.eq.b.get(i, i)
                + 2.0 * nk[0] * nk[1] * ev.eq.b.get(i, j)
                + nk[1] * nk[1] * ev.eq.b.get(j, j)
        })
        .sum::<f64>()
        / n as f64;
    if !(stiffness.is_finite() && stiffness > 0.0) {
        return Err(mismatch("the band around the start sees no gradient"));
    }
    problem.lambda = config.tangential_weight * stiffness;
    let solved = solve::run(
        &problem,
        start.clone(),
        (pixels, feet),
        (a, c),
        config.tolerance,
        config.max_iterations,
    );
    let end = solved.end;
    let curve = end.curve;
    // Covariance at the solution (undamped, regularised normal matrix).
    let factored = Factored::new(&end.eval.eq);
    let (cov, m_eff) = match &factored {
        Some(f) => {
            let band = f.inverse_band(p, closed);
            // tr(H^-1 J^T J) = m - lambda sum_k t_k^T (H^-1)_kk t_k.
            let prior: f64 = problem
                .tangents
                .iter()
                .enumerate()
                .map(|(k, t)| {
                    let b = band[k * (p + 1)];
                    t[0] * (b[0] * t[0] + b[1] * t[1]) + t[1] * (b[2] * t[0] + b[3] * t[1])
                })
                .sum();
            (band, unknowns as f64 - problem.lambda * prior)
        }
        None => (vec![[f64::NAN; 4]; n * (p + 1)], unknowns as f64),
    };
    let used = solved.band_pixels as f64;
    let s2 = end.eval.data / (used - m_eff).max(1.0);
    let cov: Vec<[f64; 4]> = cov.iter().map(|b| b.map(|v| s2 * v)).collect();
    let control_points = curve
        .control_points()
        .iter()
        .enumerate()
        .map(|(k, q)| {
            let nk = curve.frame(greville(&curve, k)).normal;
            let b = cov[k * (p + 1)];
            let var_n =
                nk[0] * (b[0] * nk[0] + b[1] * nk[1]) + nk[1] * (b[2] * nk[0] + b[3] * nk[1]);
            ControlPoint {
                x: q[0],
                y: q[1],
                sigma_n: var_n.max(0.0).sqrt(),
                normal: nk,
                covariance: [b[0], b[1], b[3]],
            }
        })
        .collect();
    let (mut slide, mut normal_move) = (0.0f64, 0.0f64);
    for (k, (q, (q0, t))) in curve
        .control_points()
        .iter()
        .zip(problem.anchors.iter().zip(&problem.tangents))
        .enumerate()
    {
        slide = slide.max((t[0] * (q[0] - q0[0]) + t[1] * (q[1] - q0[1])).abs());
        let u = greville(&curve, k);
        let (f0, f1) = (start.frame(u), curve.point(u));
        normal_move = normal_move.max(
            (f0.normal[0] * (f1[0] - f0.point[0]) + f0.normal[1] * (f1[1] - f0.point[1])).abs(),
        );
    }
    Ok(BsplineCurveFit {
        model: ShapeModel::BsplineCurve,
        outcome: end.outcome,
        curve: curve.to_data(),
        control_points,
        a: end.a,
        c: end.c,
        profile,
        half_width: problem.half_width,
        band_pixels: solved.band_pixels,
        residual_rms: (end.eval.data / used.max(1.0)).sqrt(),
        noise_sigma: s2.sqrt(),
        effective_unknowns: m_eff,
        tangential_slide: slide,
        normal_move,
        iterations: solved.iterations,
        passes: solved.passes,
        control_spacing: start.basis().element_length(),
        start_fit_error: f64::NAN,
        config: config.clone(),
        spline: curve,
        cov,
    })
}

/// Linear least-squares gray levels `(a, c)` at the start; `None` without
/// contrast.
fn levels(
    problem: &Problem,
    curve: &SplineCurve,
    pixels: &[Pixel],
    feet: &[f64],
) -> Option<(f64, f64)> {
    let (mut n, mut sg, mut sgg, mut sf, mut sfg) = (0.0, 0.0, 0.0, 0.0, 0.0);
    for (px, &u) in pixels.iter().zip(feet) {
        let pr = curve.project(px.q[0], px.q[1], u);
        let (g, _) =
            crate::model::solve::profile_at(problem.profile, pr.r, pr.normal, (pr.curvature, 0.0));
        n += 1.0;
        sg += g;
        sgg += g * g;
        sf += px.f;
        sfg += px.f * g;
    }
    let det = n * sgg - sg * sg;
    if det.is_nan() || det <= 1e-12 * n * n {
        return None;
    }
    let a = (sgg * sf - sg * sfg) / det;
    let c = (n * sfg - sg * sf) / det;
    (c.is_finite() && c.abs() > 1e-9).then_some((a, c))
}

#[cfg(test)]
mod tests {
    use super::*;

    /// A straight edge (row 30.3, bright above) and the start on it: the
    /// data's normal matrix is singular (sliding the control points along
    /// the line changes nothing), the regularised one is not.
    #[test]
    fn straight_edge_is_singular_without_the_regularisation() {
        let (w, h) = (60usize, 60usize);
        let data = (0..w * h)
            .map(|i| {
                let y = (i / w) as f64;
                // Exact coverage of the pixel by y < 30.3.
                0.2 + 0.6 * (30.3 - (y - 0.5)).clamp(0.0, 1.0)
            })
            .collect();
        let image = Image::new(w, h, data).unwrap();
        let points: Vec<[f64; 2]> = (0..=80).map(|k| [10.0 + 0.5 * k as f64, 30.3]).collect();
        let (start, _) = start_curve(&points, false, 3, &BsplineCurveConfig::default()).unwrap();
        let profile = ModelProfile::PixelEdge { blur: 0.0 };
        let n = start.basis().n_functions();
        let mut problem = Problem {
            image: &image,
            profile,
            anchors: start.control_points().to_vec(),
            tangents: (0..n)
                .map(|k| start.frame(greville(&start, k)).tangent)
                .collect(),
            lambda: 0.0,
            half_width: super::super::solve::band_half_width(profile),
        };
        let (pixels, feet) = problem.select(&start).unwrap();
        let ev = problem.evaluate(&start, &pixels, &feet, (0.2, 0.6));
        assert!(Factored::new(&ev.eq).is_none());
        problem.lambda = 1e-3 * ev.eq.max_diag();
        let ev = problem.evaluate(&start, &pixels, &feet, (0.2, 0.6));
        assert!(Factored::new(&ev.eq).is_some());
        // And the fit stays on the edge.
        let f = fit_bspline_curve(&image, &start, profile, &BsplineCurveConfig::default()).unwrap();
        let worst = f
            .samples(0.5)
            .unwrap()
            .iter()
            .map(|s| (s.y - 30.3).abs())
            .fold(0.0, f64::max);
        assert!(worst < 1e-6, "{worst}");
    }
}
