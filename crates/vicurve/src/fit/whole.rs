//! The whole object: a small closed silhouette measured against the image
//! of all of it.
//!
//! The pixel-edge profile renders each band pixel from the blurred
//! osculating circle at its foot on the curve. That is the edge's image
//! while the blur is small against the object; where the curvature changes
//! within the blur, or the far side lies within its reach (a dot or an
//! ellipse a few blurs across), the profile is not the object's image and
//! the curve, the contrast and the blur trade errors against each other
//! the residuals cannot show (`docs/benchmarks.md`, "Small objects under a
//! large blur").
//!
//! Here the virtual image is the whole region `Ω` the curve bounds,
//! blurred by a Gaussian of `blur` px and integrated over each square
//! pixel, exactly. The kernel is separable, `k(u) k(v)` with `k` the unit
//! box convolved with the Gaussian, and with `K' = k` Green's theorem
//! turns the area integral into one along the curve:
//!
//! `W(p) = ∫_Ω k(px - qx) k(py - qy) dq = -∮ K(px - x) k(py - y) dy`
//!
//! (the region on the left of the curve). The curve is `x0 + U n0` on a
//! reference `x0` (outward normal `n0`), `U` a periodic cubic B-spline;
//! moving it by `dU` outward adds `k(px - x) k(py - y) dU` per unit of the
//! outward normal's length. Three Gauss–Legendre points on each piece
//! between the knots of `x0` and `U`, pieces at most a third of the
//! spread long, make both integrals exact to far below the noise (tested
//! against the library's renderer and by finite differences).
//!
//! Gauss–Newton fits `g = a + c W` over the object's pixels and a margin
//! of three spreads, in `U`, the levels `a` (outside) and `c` (inside
//! minus outside) and the blur. The reference is the band fit's curve on
//! the elements of `U`: its distance to the band fit's curve is the
//! shape error those elements leave. The elements are the band fit's
//! last stage's, made 1.5 times as many while the finer fit is
//! significantly better or the shape error exceeds the noise term, but
//! none shorter than the blur resolves. Each sample's `sigma` is the
//! fit's covariance (the object's size traded against its contrast
//! included) and the shape error, in quadrature.
//!
//! Edge cases: a fit that does not converge, moves the curve by more than
//! [`MAX_SHIFT`], finds a blur beyond [`BLUR_FACTOR`] of the band fit's,
//! or crosses itself leaves the band fit's result as it was. Pixels
//! beyond the image border are not in the window; the rendering needs
//! none of them.

use super::loops;
use super::output::output_points;
use super::reference::{chord_lengths, CURVE_SPACING};
use super::schedule::MIN_CLOSED_ELEMENTS;
use super::{Measurement, Outcome, Sample, StageReport};
use crate::curve::{polygon_contains, SplineCurve};
use crate::interp::Sampler;
use crate::measurement::{IterationRecord, RunKind};
use crate::solver::DenseCholesky;
use crate::spline::{Basis, MAX_DEGREE};
use crate::virtual_image::pixel_edge::{normal_cdf_pdf, spread_variance};
use crate::virtual_image::Profile;

/// The whole object is measured where the blur's spread times the
/// largest curvature reaches this. Below it the pixel-edge profile's
/// curved edge (to the second order) holds within the noise on the
/// independent probes (`bench/probes/free_ellipses.py`, `dots.py`), and
/// the whole-object fit on an object that sharp, under a blur near the
/// pixel's own, did no better.
const MIN_BLUR_CURVATURE: f64 = 0.4;
/// ... and where one rendering's work, the window's pixels times the
/// curve's quadrature points, is at most this (an object of a few
/// thousand pixels: a 16 x 9.6 px ellipse under a 2.5 px blur is about
/// 1e6; beyond, the fits would cost far more than the band fit).
const MAX_WORK: f64 = 5e6;
/// The window: the pixels inside the curve and within this many spreads
/// of it (beyond, the blurred edge is within 1.3e-3 of a level).
const MARGIN_SPREADS: f64 = 3.0;
/// Quadrature points along the curve at most this many spreads apart.
const STEP_SPREADS: f64 = 1.0 / 3.0;
/// ... and at most this many pixels.
const MAX_STEP: f64 = 0.5;
/// Elements of `U` at least this many spreads long (the blur averages
/// finer detail along the edge away: shorter elements only add noise)...
const MIN_ELEMENT_SPREADS: f64 = 1.5;
/// ... and at least this many pixels.
const MIN_ELEMENT: f64 = 2.0;
/// Gauss–Newton iterations at most.
const MAX_ITERATIONS: usize = 40;
/// Convergence: the largest change of `U` and of the blur, pixels.
const TOLERANCE: f64 = 1e-5;
/// The result is kept only if the curve moved by at most this many
/// pixels from its reference, the band fit's curve (farther, the band fit
/// or this one is not the object's edge).
const MAX_SHIFT: f64 = 1.5;
/// ... and the fitted blur is within this factor of the band fit's.
const BLUR_FACTOR: f64 = 2.0;
/// Elements of `U`: first the band fit's last stage's, then 1.5 times as
/// many, at most this many times (see [`refined`]).
const REFINEMENTS: usize = 3;

/// `m` measured against the image of the whole object when it is a small
/// closed silhouette under a blur large against its curvature (see the
/// module docs), and that fit converges near `m`'s curve; else `m`.
/// Its samples' `sigma` is that fit's covariance and its elements' shape
/// error; its last stage report is that fit's (`whole_object`).
pub(super) fn refined(sampler: &Sampler, m: Measurement, spacing: f64) -> Measurement {
    let started = std::time::Instant::now();
    let Some(start) = Start::of(sampler, &m) else {
        return m;
    };
    let Some(mut best) = start.model(start.elements).and_then(|model| model.fit()) else {
        return m;
    };
    let Some(mut outline) = best.outline(spacing) else {
        return m;
    };
    // Finer elements while they fit significantly better, or while the
    // elements' shape error exceeds the noise term.
    for _ in 0..REFINEMENTS {
        let n = (3 * best.model.basis.n_elements()).div_ceil(2);
        if n > start.most_elements {
            break;
        }
        let finer = start.model(n);
        let Some(fit) = finer.and_then(|model| model.fit()) else {
            break;
        };
        if !(fit.significant_over(&best) || outline.misfits()) {
            break;
        }
        let Some(o) = fit.outline(spacing) else {
            break;
        };
        (best, outline) = (fit, o);
    }
    best.measurement(m, outline, spacing, started.elapsed().as_secs_f64())
}

/// The whole spread (pixels) of a blur of `blur` px: the optics' and the
/// pixel's own in quadrature.
fn spread(blur: f64) -> f64 {
    spread_variance(blur).sqrt()
}

/// The quadrature's longest piece along the curve under a blur of `blur`
/// px, pixels of parameter.
fn quadrature_step(blur: f64) -> f64 {
    (STEP_SPREADS * spread(blur)).min(MAX_STEP)
}

/// The work of one rendering of a closed curve `length` px long under a
/// blur of `blur` px at `pixels` pixels: pixels times quadrature points
/// (three on each piece of [`quadrature_step`]).
pub(crate) fn rendering_work(length: f64, blur: f64, pixels: f64) -> f64 {
    pixels * 3.0 * length / quadrature_step(blur)
}

/// The share of each pixel's light that comes from the region `curve`
/// (closed) bounds, through a Gaussian blur of `blur` px (the rendering of
/// the module docs), at the centres of the `size[0] x size[1]` pixels
/// from `origin`, row after row: what a noiseless camera records of the
/// object, between 0 and 1. `None` for an open curve or one of no area.
pub(crate) fn region_light(
    curve: &SplineCurve,
    blur: f64,
    origin: [usize; 2],
    size: [usize; 2],
) -> Option<Vec<f64>> {
    if !(curve.is_closed() && blur.is_finite() && blur >= 0.0) {
        return None;
    }
    // A blur of 0 leaves the box's edges sharp; a hair of blur keeps the
    // quadrature's integrand smooth, far below a pixel's share of 1e-3.
    let blur = blur.max(0.05);
    let basis = Basis::new(3, MIN_CLOSED_ELEMENTS, curve.param_length(), true).ok()?;
    let quad = Quadrature::new(curve, &basis, quadrature_step(blur))?;
    let window = Window {
        origin,
        size,
        pixels: (0..size[0] * size[1])
            .map(|i| Pixel {
                col: i % size[0],
                row: i / size[0],
                g: 0.0,
            })
            .collect(),
    };
    let mut shape = Shape::default();
    quad.shape_into(&basis, &vec![0.0; basis.n_functions()], &mut shape);
    let mut tables = Tables::default();
    shape.tables_into(blur, &window, &mut tables);
    Some(
        window
            .pixels
            .iter()
            .map(|p| shape.render(p, &tables).w)
            .collect(),
    )
}

/// What the whole-object fits share.
struct Start {
    /// The band fit's curve, points at most [`Start::step`] apart.
    points: Vec<[f64; 2]>,
    /// The first fit's elements: the band fit's, at most
    /// [`Start::most_elements`], at least [`MIN_CLOSED_ELEMENTS`].
    elements: usize,
    /// The most elements a fit may have: none shorter than
    /// [`MIN_ELEMENT_SPREADS`] spreads or [`MIN_ELEMENT`].
    most_elements: usize,
    /// The band fit's blur, pixels.
    blur: f64,
    /// The quadrature's longest piece, pixels of parameter.
    step: f64,
    /// The window.
    window: Window,
}

/// A whole-object fit's basis and quadrature.
struct Model<'a> {
    start: &'a Start,
    /// The reference `x0`.
    reference: SplineCurve,
    /// The distance of each of the start's points to the reference,
    /// pixels: the shape error of the elements.
    shape_error: Vec<f64>,
    /// The displacement's basis on the reference's parameter.
    basis: Basis,
    /// The quadrature points along the reference.
    quad: Quadrature,
}

/// The pixels the whole-object fit compares, in a rectangle of the image.
struct Window {
    /// The rectangle's first column and row.
    origin: [usize; 2],
    /// Its columns and rows.
    size: [usize; 2],
    /// The pixels.
    pixels: Vec<Pixel>,
}

/// A window pixel: its column and row in the window's rectangle, and its
/// gray level.
#[derive(Clone, Copy)]
struct Pixel {
    col: usize,
    row: usize,
    g: f64,
}

impl Start {
    /// The start, when `m` qualifies: converged, closed, no corners, a
    /// silhouette whose last stage is an isotropic pixel edge, blur times
    /// largest curvature at least [`MIN_BLUR_CURVATURE`], a rendering of
    /// at most [`MAX_WORK`].
    fn of(sampler: &Sampler, m: &Measurement) -> Option<Start> {
        let last = m.stages.last()?;
        let blur = match last.profile {
            Profile::PixelEdge { blur, anisotropy } if anisotropy.is_none() => blur,
            _ => return None,
        };
        let curve = &m.curve;
        if m.outcome != Outcome::Converged || !curve.is_closed() || !curve.corners().is_empty() {
            return None;
        }
        let spread = spread(blur);
        if spread * curve.largest_curvature(0.25) < MIN_BLUR_CURVATURE {
            return None;
        }
        let margin = MARGIN_SPREADS * spread + MAX_SHIFT;
        let [x0, y0, x1, y1] = curve.bounding_box();
        let area = (x1 - x0 + 2.0 * margin) * (y1 - y0 + 2.0 * margin);
        let work = rendering_work(curve.arc_length(), blur, area);
        if work.is_nan() || work > MAX_WORK {
            return None;
        }
        let step = quadrature_step(blur);
        let points = dense_points(curve, step);
        let window = window(sampler, &points, margin);
        // Elements no shorter than the blur resolves along the edge.
        let shortest = (MIN_ELEMENT_SPREADS * spread).max(MIN_ELEMENT);
        let most_elements = (curve.arc_length() / shortest) as usize;
        Some(Start {
            points,
            elements: last.elements.min(most_elements).max(MIN_CLOSED_ELEMENTS),
            most_elements,
            blur,
            step,
            window,
        })
    }

    /// The model of `n` elements; `None` when the window has too few
    /// pixels for it.
    fn model(&self, n: usize) -> Option<Model<'_>> {
        // The reference: the band fit's curve on `n` elements, so that
        // every detail of it is one the displacement can move (a ripple
        // finer than the elements, which the blur hides, would be a bias
        // `sigma` does not see). Its distance to the band fit's curve is
        // the shape error `n` elements leave on such a curve.
        let chords = chord_lengths(&self.points);
        let length =
            chords.last()? + crate::curve::dist(self.points[self.points.len() - 1], self.points[0]);
        let reference = SplineCurve::fit(&self.points, true, 3, length / n as f64).ok()?;
        let shape_error = self
            .points
            .iter()
            .zip(&chords)
            .map(|(p, &s)| crate::curve::dist(reference.point(s), *p))
            .collect();
        let basis = Basis::new(3, n, reference.param_length(), true).ok()?;
        let quad = Quadrature::new(&reference, &basis, self.step)?;
        (self.window.pixels.len() > 2 * (n + 3)).then_some(Model {
            start: self,
            reference,
            shape_error,
            basis,
            quad,
        })
    }
}

impl<'a> Model<'a> {
    /// The shape error at `count` points equally spaced on the reference:
    /// the largest of [`Model::shape_error`] within half an element (its
    /// points are about as equally spaced on the band fit's curve).
    fn shape_along(&self, count: usize) -> Vec<f64> {
        let m = self.shape_error.len();
        let reach = (m / self.basis.n_elements() / 2).max(1) as isize;
        (0..count)
            .map(|i| {
                let centre = (i * m / count) as isize;
                (centre - reach..=centre + reach)
                    .map(|k| self.shape_error[k.rem_euclid(m as isize) as usize])
                    .fold(0.0, f64::max)
            })
            .collect()
    }

    /// Gauss–Newton from `U = 0`, the band fit's blur and the levels that
    /// fit best there; `None` if it does not converge or leaves the
    /// bounds ([`MAX_SHIFT`], [`BLUR_FACTOR`]).
    fn fit(self) -> Option<Fit<'a>> {
        let n = self.basis.n_functions();
        let mut scratch = Scratch::new(n + 3);
        let mut theta = vec![0.0; n + 3];
        theta[n + 2] = self.start.blur;
        let (a, c) = self.levels(&theta, &mut scratch)?;
        theta[n] = a;
        theta[n + 1] = c;
        let mut normal = Normal::new(n + 3);
        let mut ssr = self.accumulate(&theta, &mut normal, &mut scratch);
        let mut delta = vec![0.0; n + 3];
        let mut chol = DenseCholesky::factor(&normal.h, n + 3).ok()?;
        let mut history = Vec::new();
        for iteration in 0..MAX_ITERATIONS {
            if iteration > 0 {
                chol.refactor(&normal.h).ok()?;
            }
            delta.copy_from_slice(&normal.g);
            chol.solve_in_place(&mut delta);
            let step = delta[..n]
                .iter()
                .chain(std::iter::once(&delta[n + 2]))
                .fold(0.0_f64, |m, d| m.max(d.abs()));
            history.push(IterationRecord {
                iteration,
                max_step: step,
                residual_rms: (ssr / self.start.window.pixels.len() as f64).sqrt(),
                run: RunKind::Reference,
                new_reference: iteration == 0,
            });
            if step < TOLERANCE {
                // Converged: the last normal equations are the covariance's.
                let dof = self.start.window.pixels.len().saturating_sub(n + 3).max(1);
                let inverse = chol.inverse();
                return Some(Fit {
                    theta,
                    ssr,
                    noise2: ssr / dof as f64,
                    inverse,
                    history,
                    model: self,
                });
            }
            ssr = self.descend((&mut theta, &mut normal), &delta, ssr, &mut scratch)?;
            if !self.within_bounds(&theta) {
                return None;
            }
        }
        None
    }

    /// `theta + t delta` into `theta` and its normal equations into
    /// `normal`, `t` the first of 1, 1/2, ... 1/32 that lowers the sum of
    /// squared residuals below `ssr`; returns that sum, `None` if no `t`
    /// does (no way down).
    fn descend(
        &self,
        (theta, normal): (&mut Vec<f64>, &mut Normal),
        delta: &[f64],
        ssr: f64,
        scratch: &mut Scratch,
    ) -> Option<f64> {
        let mut trial = std::mem::take(&mut scratch.trial);
        let mut next = std::mem::replace(&mut scratch.next, Normal::new(0));
        let mut scale = 1.0;
        let mut lowered = None;
        for _ in 0..6 {
            for ((t, th), d) in trial.iter_mut().zip(theta.iter()).zip(delta) {
                *t = th + scale * d;
            }
            next.clear();
            let s = self.accumulate(&trial, &mut next, scratch);
            if s.is_finite() && s <= ssr {
                std::mem::swap(theta, &mut trial);
                std::mem::swap(normal, &mut next);
                lowered = Some(s);
                break;
            }
            scale *= 0.5;
        }
        scratch.trial = trial;
        scratch.next = next;
        lowered
    }

    /// Whether `theta` stays within [`MAX_SHIFT`] of the reference and its
    /// blur within [`BLUR_FACTOR`] of the start's.
    fn within_bounds(&self, theta: &[f64]) -> bool {
        let n = self.basis.n_functions();
        let blur = theta[n + 2];
        let shift = theta[..n].iter().fold(0.0_f64, |m, u| m.max(u.abs()));
        shift <= MAX_SHIFT
            && blur >= self.start.blur / BLUR_FACTOR
            && blur <= self.start.blur * BLUR_FACTOR
    }

    /// The levels `(a, c)` that fit the window best under the shape and
    /// blur of `theta` (linear least squares); `None` if degenerate.
    fn levels(&self, theta: &[f64], scratch: &mut Scratch) -> Option<(f64, f64)> {
        let n = self.basis.n_functions();
        let Scratch { shape, tables, .. } = scratch;
        self.quad.shape_into(&self.basis, &theta[..n], shape);
        shape.tables_into(theta[n + 2], &self.start.window, tables);
        let (mut sw, mut sww, mut sg, mut swg) = (0.0, 0.0, 0.0, 0.0);
        for p in &self.start.window.pixels {
            let w = shape.render(p, tables).w;
            sw += w;
            sww += w * w;
            sg += p.g;
            swg += w * p.g;
        }
        let count = self.start.window.pixels.len() as f64;
        let det = count * sww - sw * sw;
        if det.is_nan() || det.abs() <= 1e-12 * count * sww {
            return None;
        }
        let c = (count * swg - sw * sg) / det;
        let a = (sg - c * sw) / count;
        Some((a, c))
    }

    /// The normal equations of `theta` into `normal`; returns the sum of
    /// squared residuals.
    fn accumulate(&self, theta: &[f64], normal: &mut Normal, scratch: &mut Scratch) -> f64 {
        let n = self.basis.n_functions();
        let (a, c, blur) = (theta[n], theta[n + 1], theta[n + 2]);
        if blur.is_nan() || blur <= 0.0 {
            return f64::INFINITY;
        }
        let Scratch {
            shape, tables, row, ..
        } = scratch;
        self.quad.shape_into(&self.basis, &theta[..n], shape);
        shape.tables_into(blur, &self.start.window, tables);
        let mut ssr = 0.0;
        for p in &self.start.window.pixels {
            row.iter_mut().for_each(|r| *r = 0.0);
            let r = shape.render_with_gradient(p, tables, &self.quad, &mut row[..n]);
            for v in &mut row[..n] {
                *v *= c;
            }
            row[n] = 1.0;
            row[n + 1] = r.w;
            row[n + 2] = c * r.dw_dblur;
            let e = p.g - a - c * r.w;
            ssr += e * e;
            normal.add(row, e);
        }
        ssr
    }
}

/// What the fit's iterations reuse: the curve at the quadrature points,
/// the kernels' tables, a Jacobian row, a trial step and its normal
/// equations.
struct Scratch {
    shape: Shape,
    tables: Tables,
    row: Vec<f64>,
    trial: Vec<f64>,
    next: Normal,
}

impl Scratch {
    /// For `n` parameters.
    fn new(n: usize) -> Self {
        Scratch {
            shape: Shape::default(),
            tables: Tables::default(),
            row: vec![0.0; n],
            trial: vec![0.0; n],
            next: Normal::new(n),
        }
    }
}

/// Dense normal equations `H delta = g` of the whole-object fit.
struct Normal {
    /// `J^T J`, row-major, lower triangle filled.
    h: Vec<f64>,
    /// `J^T r`.
    g: Vec<f64>,
    n: usize,
}

impl Normal {
    fn new(n: usize) -> Self {
        Normal {
            h: vec![0.0; n * n],
            g: vec![0.0; n],
            n,
        }
    }

    /// All sums back to zero.
    fn clear(&mut self) {
        self.h.iter_mut().for_each(|v| *v = 0.0);
        self.g.iter_mut().for_each(|v| *v = 0.0);
    }

    /// One pixel's Jacobian row and residual added.
    fn add(&mut self, row: &[f64], e: f64) {
        for (i, &ri) in row.iter().enumerate() {
            if ri == 0.0 {
                continue;
            }
            self.g[i] += ri * e;
            let line = &mut self.h[i * self.n..=i * self.n + i];
            for (h, &rj) in line.iter_mut().zip(row) {
                *h += ri * rj;
            }
        }
    }
}

/// The converged whole-object fit.
struct Fit<'a> {
    /// `U`'s coefficients, then `a`, `c`, the blur.
    theta: Vec<f64>,
    /// The sum of squared residuals, gray levels².
    ssr: f64,
    /// The residuals' variance (per degree of freedom), gray levels².
    noise2: f64,
    /// `(J^T J)^-1`, row-major.
    inverse: Vec<f64>,
    history: Vec<IterationRecord>,
    model: Model<'a>,
}

impl Fit<'_> {
    /// Whether this fit's residuals are significantly below those of
    /// `coarser`, a fit of fewer elements: an F test on the drop per
    /// added function, at three standard deviations of its noise-only
    /// spread (the two references differ a little, so the test is an
    /// approximate one).
    fn significant_over(&self, coarser: &Fit) -> bool {
        let added = (self.theta.len() - coarser.theta.len()) as f64;
        let drop = (coarser.ssr - self.ssr) / added;
        drop > self.noise2 * (1.0 + 3.0 * (2.0 / added).sqrt())
    }

    /// The fitted curve `x0 + U n0` at points about a quarter of
    /// `spacing` apart (a quarter pixel at most), with their noise terms
    /// and shape terms, and the B-spline through them; `None` if it
    /// crosses itself.
    fn outline(&self, spacing: f64) -> Option<Outline> {
        let (reference, basis) = (&self.model.reference, &self.model.basis);
        let n = basis.n_functions();
        let l = reference.param_length();
        let count = ((l / (0.25 * spacing).min(0.25)).ceil() as usize).max(16);
        let mut values = [0.0; MAX_DEGREE + 1];
        let mut points = Vec::with_capacity(count);
        let mut noise = Vec::with_capacity(count);
        for i in 0..count {
            let t = l * i as f64 / count as f64;
            let first = basis.eval(t, &mut values);
            let (mut u, mut var) = (0.0, 0.0);
            for (k, &vk) in values.iter().enumerate().take(4) {
                let jk = basis.index(first, k);
                u += self.theta[jk] * vk;
                for (q, &vq) in values.iter().enumerate().take(4) {
                    var += vk * vq * self.inverse[jk * (n + 3) + basis.index(first, q)];
                }
            }
            let f = reference.frame(t);
            let out = self.model.quad.outward;
            points.push([
                f.point[0] + u * out * f.normal[0],
                f.point[1] + u * out * f.normal[1],
            ]);
            noise.push((self.noise2 * var.max(0.0)).sqrt());
        }
        if loops::looped(&points, true).is_some() {
            return None;
        }
        let curve = SplineCurve::fit(&points, true, 3, CURVE_SPACING).ok()?;
        let s = chord_lengths(&points);
        let shape = self.model.shape_along(count);
        Some(Outline {
            points,
            s,
            noise,
            shape,
            curve,
        })
    }

    /// `m` with this fit's curve `outline`, samples and stage report.
    fn measurement(
        self,
        mut m: Measurement,
        outline: Outline,
        spacing: f64,
        seconds: f64,
    ) -> Measurement {
        let out = self.model.quad.outward;
        let Outline {
            points,
            s,
            noise,
            shape,
            curve,
        } = outline;
        let closing = crate::curve::dist(points[points.len() - 1], points[0]);
        let samples = output_points(&s, spacing, closing)
            .into_iter()
            .map(|i| {
                let f = curve.frame(s[i]);
                Sample {
                    s: s[i],
                    x: points[i][0],
                    y: points[i][1],
                    nx: out * f.normal[0],
                    ny: out * f.normal[1],
                    sigma: noise[i].hypot(shape[i]),
                    sigma_noise: noise[i],
                    misfit: shape[i] > noise[i],
                    weight: 1.0,
                }
            })
            .collect();
        let n = self.model.basis.n_functions();
        let (a, c, blur) = (self.theta[n], self.theta[n + 1], self.theta[n + 2]);
        m.curve_fit_error = points
            .iter()
            .zip(&s)
            .map(|(q, &si)| crate::curve::dist(curve.point(si), *q))
            .fold(0.0, f64::max);
        m.curve = curve;
        m.samples = samples;
        m.levels.clear();
        m.blur_corrected = true;
        m.stages.push(StageReport {
            half_width: MARGIN_SPREADS * spread(blur),
            profile: Profile::pixel_edge(blur),
            elements: self.model.basis.n_elements(),
            iterations: self.history.len(),
            rereferences: 0,
            band_pixels: self.model.start.window.pixels.len(),
            binning: 1,
            residual_rms: self.noise2.sqrt(),
            a,
            c,
            seconds,
            outcome: Outcome::Converged,
            history: self.history,
            whole_object: true,
        });
        m
    }
}

/// A fit's curve, sampled densely.
struct Outline {
    /// Points of `x0 + U n0`.
    points: Vec<[f64; 2]>,
    /// Their arc lengths (chords).
    s: Vec<f64>,
    /// Their noise terms, pixels.
    noise: Vec<f64>,
    /// Their shape terms, pixels.
    shape: Vec<f64>,
    /// The B-spline through them.
    curve: SplineCurve,
}

impl Outline {
    /// Whether the elements' shape error exceeds the noise term somewhere.
    fn misfits(&self) -> bool {
        self.shape.iter().zip(&self.noise).any(|(s, n)| s > n)
    }
}

/// Points equally spaced on the reference's parameter, with what the
/// rendering needs of them.
struct Quadrature {
    /// The points' weights, pixels of parameter.
    weight: Vec<f64>,
    /// The reference's points.
    x0: Vec<[f64; 2]>,
    /// Its first derivatives.
    d0: Vec<[f64; 2]>,
    /// Its outward unit normals `n0`.
    n0: Vec<[f64; 2]>,
    /// The outward normal's rate of change along `x0'`: `n0' = turn x0'`.
    turn: Vec<f64>,
    /// The displacement basis: first function, values, derivatives.
    basis: Vec<(usize, [f64; 4], [f64; 4])>,
    /// `n0` in units of the reference frame's (left) normal: -1 when the
    /// region lies on the curve's left, 1 otherwise.
    outward: f64,
}

impl Quadrature {
    /// The quadrature of `curve`: three Gauss–Legendre points on each
    /// piece between the knots of `curve` and of `basis` (where the
    /// integrands are smooth), pieces at most `step` pixels of parameter
    /// long; `None` for a curve of no area.
    fn new(curve: &SplineCurve, basis: &Basis, step: f64) -> Option<Quadrature> {
        let nodes = gauss_nodes(&knots(curve, basis), step);
        let area = curve.area()?;
        // The signed area (Green's theorem), for the orientation.
        let signed: f64 = nodes
            .iter()
            .map(|&(t, w)| {
                let [p, d, _] = curve.derivatives(t);
                0.5 * (p[0] * d[1] - p[1] * d[0]) * w
            })
            .sum();
        if area.is_nan() || area <= 0.0 || signed == 0.0 {
            return None;
        }
        // Left normal `(-y', x') / |x'|`; the outward normal is `-left`
        // when the region is on the left (positive signed area).
        let outward = -signed.signum();
        let count = nodes.len();
        let mut q = Quadrature {
            weight: Vec::with_capacity(count),
            x0: Vec::with_capacity(count),
            d0: Vec::with_capacity(count),
            n0: Vec::with_capacity(count),
            turn: Vec::with_capacity(count),
            basis: Vec::with_capacity(count),
            outward,
        };
        for &(t, w) in &nodes {
            let [p, d, dd] = curve.derivatives(t);
            let f = crate::curve::frame_from(p, d, dd);
            q.weight.push(w);
            q.x0.push(p);
            q.d0.push(d);
            q.n0.push([outward * f.normal[0], outward * f.normal[1]]);
            // left' = -kappa |x'| T = -kappa x'; n0 = outward * left.
            q.turn.push(-outward * f.curvature);
            let b = basis.eval_derivs(t);
            let mut v = [0.0; 4];
            let mut d1 = [0.0; 4];
            v.copy_from_slice(&b.value[..4]);
            d1.copy_from_slice(&b.d1[..4]);
            q.basis.push((b.first, v, d1));
        }
        Some(q)
    }

    /// The curve `x0 + U n0` of the coefficients `lambda` at the
    /// quadrature points, into `shape` (its storage reused).
    fn shape_into(&self, basis: &Basis, lambda: &[f64], shape: &mut Shape) {
        shape.x.clear();
        shape.dy.clear();
        shape.rate.clear();
        shape.region_left = self.outward < 0.0;
        for i in 0..self.x0.len() {
            let (first, v, d1) = &self.basis[i];
            let (mut u, mut du) = (0.0, 0.0);
            for k in 0..4 {
                let c = lambda[basis.index(*first, k)];
                u += c * v[k];
                du += c * d1[k];
            }
            let (p, d, n) = (self.x0[i], self.d0[i], self.n0[i]);
            let stretch = 1.0 + self.turn[i] * u;
            let dx = [d[0] * stretch + du * n[0], d[1] * stretch + du * n[1]];
            shape.x.push([p[0] + u * n[0], p[1] + u * n[1]]);
            shape.dy.push(dx[1] * self.weight[i]);
            // The outward normal times |x'|, dotted with n0, times the
            // weight: the area swept per unit of U.
            let outward = if shape.region_left {
                [dx[1], -dx[0]]
            } else {
                [-dx[1], dx[0]]
            };
            shape
                .rate
                .push((outward[0] * n[0] + outward[1] * n[1]) * self.weight[i]);
        }
    }
}

/// The current curve at the quadrature points.
#[derive(Default)]
struct Shape {
    x: Vec<[f64; 2]>,
    /// `y'` times the point's weight.
    dy: Vec<f64>,
    /// Area swept per unit of `U`: `(outward |x'|) . n0` times the weight.
    rate: Vec<f64>,
    /// Whether the region lies on the curve's left.
    region_left: bool,
}

/// A pixel's rendering.
struct Rendered {
    /// `W(p)`, the region's share of the pixel's light.
    w: f64,
    /// `dW / dblur`.
    dw_dblur: f64,
}

impl Shape {
    /// The kernels of every quadrature point at every column and row of
    /// `window` under a blur of `blur`, into `tables` (its storage
    /// reused): the kernel is separable, so a pixel's rendering reads
    /// them instead of evaluating its own.
    fn tables_into(&self, blur: f64, window: &Window, tables: &mut Tables) {
        tables.nodes = self.x.len();
        tables.columns.clear();
        tables.rows.clear();
        let [x0, y0] = window.origin.map(|v| v as f64);
        let [width, height] = window.size;
        for col in 0..width {
            let x = x0 + col as f64;
            let kernels = self.x.iter().map(|q| Kernel::at(x - q[0], blur));
            tables.columns.extend(kernels);
        }
        // A row's kernel beyond `cut` is below 1e-15: zero, and skipped.
        let cut = 0.5 + 8.0 * blur;
        for row in 0..height {
            let y = y0 + row as f64;
            tables.rows.extend(self.x.iter().map(|q| {
                let v = y - q[1];
                if v.abs() > cut {
                    Kernel::ZERO
                } else {
                    Kernel::at(v, blur)
                }
            }));
        }
    }

    /// `W(p)` and its derivative in the blur, from `tables`.
    fn render(&self, p: &Pixel, tables: &Tables) -> Rendered {
        let (columns, rows) = tables.at(p);
        let (mut w, mut dw) = (0.0, 0.0);
        for ((ku, kv), &dy) in columns.iter().zip(rows).zip(&self.dy) {
            if kv.k == 0.0 && kv.dk == 0.0 {
                continue;
            }
            w += ku.big * kv.k * dy;
            dw += (ku.dbig * kv.k + ku.big * kv.dk) * dy;
        }
        let sign = if self.region_left { -1.0 } else { 1.0 };
        Rendered {
            w: sign * w,
            dw_dblur: sign * dw,
        }
    }

    /// [`Shape::render`], and `dW / dlambda_j` added into `grad`.
    fn render_with_gradient(
        &self,
        p: &Pixel,
        tables: &Tables,
        quad: &Quadrature,
        grad: &mut [f64],
    ) -> Rendered {
        let (columns, rows) = tables.at(p);
        let n = grad.len();
        let (mut w, mut dw) = (0.0, 0.0);
        for (i, (ku, kv)) in columns.iter().zip(rows).enumerate() {
            if kv.k == 0.0 && kv.dk == 0.0 {
                continue;
            }
            let dy = self.dy[i];
            w += ku.big * kv.k * dy;
            dw += (ku.dbig * kv.k + ku.big * kv.dk) * dy;
            let density = ku.k * kv.k * self.rate[i];
            if density != 0.0 {
                let (first, values, _) = &quad.basis[i];
                for (k, &b) in values.iter().enumerate() {
                    let j = first + k;
                    grad[if j >= n { j - n } else { j }] += density * b;
                }
            }
        }
        let sign = if self.region_left { -1.0 } else { 1.0 };
        Rendered {
            w: sign * w,
            dw_dblur: sign * dw,
        }
    }
}

/// [`Shape::tables_into`]: the kernels, node by node, of each column and
/// row.
#[derive(Default)]
struct Tables {
    nodes: usize,
    columns: Vec<Kernel>,
    rows: Vec<Kernel>,
}

impl Tables {
    /// The kernels of `p`'s column and of its row.
    fn at(&self, p: &Pixel) -> (&[Kernel], &[Kernel]) {
        let n = self.nodes;
        (
            &self.columns[p.col * n..(p.col + 1) * n],
            &self.rows[p.row * n..(p.row + 1) * n],
        )
    }
}

/// The pixel's kernel along one axis at offset `u` (pixels) under a blur
/// of `blur`: `k = box * gauss`, its integral `K` from `-inf`, and their
/// derivatives in the blur.
struct Kernel {
    k: f64,
    big: f64,
    dk: f64,
    dbig: f64,
}

impl Kernel {
    /// The kernel far from the pixel, where every term is zero.
    const ZERO: Kernel = Kernel {
        k: 0.0,
        big: 0.0,
        dk: 0.0,
        dbig: 0.0,
    };

    #[inline]
    fn at(u: f64, blur: f64) -> Kernel {
        let (a, b) = ((u + 0.5) / blur, (u - 0.5) / blur);
        let (pa, da) = normal_cdf_pdf(a);
        let (pb, db) = normal_cdf_pdf(b);
        // psi(x) = x Phi(x) + phi(x), psi' = Phi.
        let psi = |x: f64, p: f64, d: f64| x * p + d;
        Kernel {
            k: pa - pb,
            big: blur * (psi(a, pa, da) - psi(b, pb, db)),
            dk: -(a * da - b * db) / blur,
            dbig: da - db,
        }
    }
}

/// The knots of `curve` and of `basis` in `[0, L]`, increasing, each once
/// (both bases are periodic on the same `[0, L)`).
fn knots(curve: &SplineCurve, basis: &Basis) -> Vec<f64> {
    let l = curve.param_length();
    let reference = curve.basis();
    let mut knots: Vec<f64> = (0..reference.n_elements())
        .map(|e| reference.element_bounds(e).0)
        .chain((0..basis.n_elements()).map(|e| basis.element_bounds(e).0))
        .filter(|&t| (0.0..l).contains(&t))
        .chain([0.0, l])
        .collect();
    knots.sort_by(f64::total_cmp);
    knots.dedup_by(|a, b| (*a - *b).abs() <= 1e-9 * l);
    knots
}

/// Three-point Gauss–Legendre nodes `(t, weight)` on each piece between
/// consecutive `knots`, the pieces cut into parts at most `step` long.
fn gauss_nodes(knots: &[f64], step: f64) -> Vec<(f64, f64)> {
    const X: f64 = 0.774_596_669_241_483_4; // sqrt(3/5)
    const W: [f64; 3] = [5.0 / 9.0, 8.0 / 9.0, 5.0 / 9.0];
    let mut nodes = Vec::new();
    for k in knots.windows(2) {
        let parts = ((k[1] - k[0]) / step).ceil().max(1.0) as usize;
        let h = (k[1] - k[0]) / parts as f64;
        for i in 0..parts {
            let c = k[0] + (i as f64 + 0.5) * h;
            for (x, w) in [-X, 0.0, X].into_iter().zip(W) {
                nodes.push((c + 0.5 * h * x, 0.5 * h * w));
            }
        }
    }
    nodes
}

/// The window's pixels: inside the closed polygon `points` or within
/// `margin` pixels of it, in the image.
fn window(sampler: &Sampler, points: &[[f64; 2]], margin: f64) -> Window {
    let (w, h) = (sampler.width(), sampler.height());
    let (mut x0, mut y0, mut x1, mut y1) = (f64::MAX, f64::MAX, f64::MIN, f64::MIN);
    for p in points {
        x0 = x0.min(p[0]);
        y0 = y0.min(p[1]);
        x1 = x1.max(p[0]);
        y1 = y1.max(p[1]);
    }
    let clamp = |v: f64, hi: usize| v.max(0.0).min(hi as f64 - 1.0) as usize;
    let (i0, i1) = (
        clamp((x0 - margin).ceil(), w),
        clamp((x1 + margin).floor(), w),
    );
    let (j0, j1) = (
        clamp((y0 - margin).ceil(), h),
        clamp((y1 + margin).floor(), h),
    );
    let mut pixels = Vec::new();
    for j in j0..=j1 {
        for i in i0..=i1 {
            let (x, y) = (i as f64, j as f64);
            if !(polygon_contains(points, [x, y]) || near(points, x, y, margin)) {
                continue;
            }
            if let Some(g) = sampler.pixel(i, j) {
                pixels.push(Pixel {
                    col: i - i0,
                    row: j - j0,
                    g,
                });
            }
        }
    }
    Window {
        origin: [i0, j0],
        size: [i1 + 1 - i0, j1 + 1 - j0],
        pixels,
    }
}

/// Points of `curve` at most `step` pixels of parameter apart.
fn dense_points(curve: &SplineCurve, step: f64) -> Vec<[f64; 2]> {
    let count = ((curve.param_length() / step).ceil() as usize).max(16);
    curve
        .sample_params(count)
        .into_iter()
        .map(|u| curve.point(u))
        .collect()
}

/// Whether `(x, y)` lies within `margin` of one of `points`.
fn near(points: &[[f64; 2]], x: f64, y: f64, margin: f64) -> bool {
    let m2 = margin * margin;
    points
        .iter()
        .any(|p| (p[0] - x) * (p[0] - x) + (p[1] - y) * (p[1] - y) <= m2)
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::render::blur::blurred_coverage;

    /// An ellipse of semi-axes 9 x 5 at (20.3, 18.6), 0.4 rad, as dense
    /// points (counterclockwise on screen when `reversed`).
    fn ellipse(reversed: bool) -> Vec<[f64; 2]> {
        let (c, s) = (0.4_f64.cos(), 0.4_f64.sin());
        let mut pts: Vec<[f64; 2]> = (0..2000)
            .map(|i| {
                let t = i as f64 / 2000.0 * std::f64::consts::TAU;
                let (u, w) = (9.0 * t.cos(), 5.0 * t.sin());
                [20.3 + c * u - s * w, 18.6 + s * u + c * w]
            })
            .collect();
        if reversed {
            pts.reverse();
        }
        pts
    }

    impl Quadrature {
        fn shape(&self, basis: &Basis, lambda: &[f64]) -> Shape {
            let mut shape = Shape::default();
            self.shape_into(basis, lambda, &mut shape);
            shape
        }
    }

    impl Shape {
        fn tables(&self, blur: f64, window: &Window) -> Tables {
            let mut tables = Tables::default();
            self.tables_into(blur, window, &mut tables);
            tables
        }
    }

    /// Every pixel of the `size x size` square from the image's corner,
    /// row after row.
    fn square(size: usize) -> Window {
        Window {
            origin: [0, 0],
            size: [size, size],
            pixels: (0..size * size)
                .map(|i| Pixel {
                    col: i % size,
                    row: i / size,
                    g: 0.0,
                })
                .collect(),
        }
    }

    /// The quadrature of the ellipse's spline and a basis of 10 elements.
    fn quadrature(reversed: bool, blur: f64) -> (Basis, Quadrature) {
        let curve = SplineCurve::fit(&ellipse(reversed), true, 3, 0.5).unwrap();
        let basis = Basis::new(3, 10, curve.param_length(), true).unwrap();
        let step = quadrature_step(blur);
        let quad = Quadrature::new(&curve, &basis, step).unwrap();
        (basis, quad)
    }

    /// `W` is the region's blurred coverage as the library's renderer
    /// makes it (to its own accuracy), either way round the curve.
    #[test]
    fn the_rendering_is_the_blurred_region() {
        for blur in [0.8, 1.5, 2.5] {
            let rendered = blurred_coverage(40, 40, &[ellipse(false)], blur).unwrap();
            for reversed in [false, true] {
                let (basis, quad) = quadrature(reversed, blur);
                let shape = quad.shape(&basis, &vec![0.0; basis.n_functions()]);
                let window = square(40);
                let tables = shape.tables(blur, &window);
                let worst = window
                    .pixels
                    .iter()
                    .zip(&rendered)
                    .map(|(p, r)| (shape.render(p, &tables).w - r).abs())
                    .fold(0.0, f64::max);
                assert!(worst < 1e-3, "blur {blur} reversed {reversed}: {worst:e}");
            }
        }
    }

    /// The quadrature's pieces (a third of the spread, half a pixel at
    /// most) give `W` as a quadrature ten times finer does, to 1e-8 of
    /// the contrast: far below any image's noise.
    #[test]
    fn the_quadrature_is_converged() {
        for blur in [0.8_f64, 1.5, 2.5] {
            let curve = SplineCurve::fit(&ellipse(false), true, 3, 0.5).unwrap();
            let basis = Basis::new(3, 10, curve.param_length(), true).unwrap();
            let lambda: Vec<f64> = (0..10).map(|j| 0.3 * (j as f64 * 0.7).cos()).collect();
            let step = quadrature_step(blur);
            let coarse = Quadrature::new(&curve, &basis, step).unwrap();
            let fine = Quadrature::new(&curve, &basis, 0.1 * step).unwrap();
            let window = square(40);
            let (a, b) = (coarse.shape(&basis, &lambda), fine.shape(&basis, &lambda));
            let (ta, tb) = (a.tables(blur, &window), b.tables(blur, &window));
            let worst = window
                .pixels
                .iter()
                .map(|p| (a.render(p, &ta).w - b.render(p, &tb).w).abs())
                .fold(0.0, f64::max);
            assert!(worst < 1e-8, "blur {blur}: {worst:e}");
        }
    }

    /// The derivatives in `U`'s coefficients and in the blur are those of
    /// `W`.
    #[test]
    fn the_gradient_is_the_rendering_s() {
        let blur = 1.7;
        for reversed in [false, true] {
            let (basis, quad) = quadrature(reversed, blur);
            let n = basis.n_functions();
            let lambda: Vec<f64> = (0..n).map(|j| 0.4 * (j as f64 * 1.3).sin()).collect();
            let shape = quad.shape(&basis, &lambda);
            let window = square(40);
            let tables = shape.tables(blur, &window);
            let e = 1e-6;
            let render = |shape: &Shape, blur: f64, p: &Pixel| {
                shape.render(p, &shape.tables(blur, &window)).w
            };
            for [col, row] in [[20, 18], [28, 22], [13, 15], [21, 24]] {
                let p = Pixel { col, row, g: 0.0 };
                let mut grad = vec![0.0; n];
                let r = shape.render_with_gradient(&p, &tables, &quad, &mut grad);
                let db = (render(&shape, blur + e, &p) - render(&shape, blur - e, &p)) / (2.0 * e);
                assert!((db - r.dw_dblur).abs() < 1e-7, "{db} {}", r.dw_dblur);
                for (j, &gj) in grad.iter().enumerate() {
                    let mut l = lambda.clone();
                    l[j] += e;
                    let up = render(&quad.shape(&basis, &l), blur, &p);
                    l[j] -= 2.0 * e;
                    let down = render(&quad.shape(&basis, &l), blur, &p);
                    let fd = (up - down) / (2.0 * e);
                    assert!(
                        (fd - gj).abs() < 1e-6,
                        "reversed {reversed} j {j}: {fd} {gj}"
                    );
                }
            }
        }
    }

    /// The kernel integrates to 1 and `K` is its integral.
    #[test]
    fn the_kernel_is_a_unit_box_blurred() {
        for blur in [0.4, 1.0, 2.5] {
            let h = 1e-3;
            let mut total = 0.0;
            let mut u = -20.0;
            while u < 20.0 {
                let k = Kernel::at(u + 0.5 * h, blur);
                total += k.k * h;
                let kk = Kernel::at(u + h, blur);
                let k0 = Kernel::at(u, blur);
                assert!(((kk.big - k0.big) / h - k.k).abs() < 1e-5);
                let e = 1e-6;
                let (p, m) = (Kernel::at(u, blur + e), Kernel::at(u, blur - e));
                assert!(((p.k - m.k) / (2.0 * e) - k0.dk).abs() < 1e-6);
                assert!(((p.big - m.big) / (2.0 * e) - k0.dbig).abs() < 1e-6);
                u += h;
            }
            assert!((total - 1.0).abs() < 1e-9, "{total}");
            assert!((Kernel::at(30.0, blur).big - 1.0).abs() < 1e-12);
        }
    }
}
