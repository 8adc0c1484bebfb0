//! The whole-object fit: Gauss–Newton on the rendering of [`super::render`]
//! of the object and of the neighbours whose light reaches its window.

use super::render::{spread, Quadrature, Shape, Tables};
use super::{Start, MARGIN_SPREADS, MAX_SHIFT};
use crate::curve::SplineCurve;
use crate::fit::loops;
use crate::fit::output::output_points;
use crate::fit::reference::{chord_lengths, CURVE_SPACING};
use crate::fit::{Measurement, Outcome, Sample, StageReport};
use crate::measurement::{IterationRecord, RunKind};
use crate::solver::DenseCholesky;
use crate::spline::{Basis, MAX_DEGREE};
use crate::virtual_image::Profile;

/// Gauss–Newton iterations at most.
const MAX_ITERATIONS: usize = 40;
/// Convergence: the largest change of `U` and of the blur, pixels.
const TOLERANCE: f64 = 1e-5;
/// The largest change of a displacement or of the blur in one step,
/// pixels.
const LONGEST_STEP: f64 = 0.5;
/// The iterations may leave the bounds by this factor on their way.
const TRANSIENT: f64 = 2.0;
/// The fitted blur stays within this factor of the start's.
pub(super) const BLUR_FACTOR: f64 = 2.0;
/// A neighbour's curve stays within this many pixels of its traced start
/// (which a blur moves off its edge by up to a spread or so).
const NEIGHBOUR_SHIFT: f64 = 4.0;
/// A neighbour's displacement is held to its start by a weight of this
/// share of the squared contrast per unit of `U` squared: the parts of it
/// the window does not see stay put (its far side, beyond the window),
/// while the pixels that see a part outweigh it by far (a coefficient's
/// information is about the squared contrast times its element's length
/// over the spread).
const NEIGHBOUR_PRIOR: f64 = 1e-3;

/// One closed curve of the model: its reference `x0`, the basis of its
/// displacement `U` along it and the quadrature points on it.
pub(super) struct Part {
    pub reference: SplineCurve,
    pub basis: Basis,
    pub quad: Quadrature,
}

impl Part {
    /// The part of `reference` with `elements` elements of `U`; `None` for
    /// a curve of no area.
    pub fn new(reference: SplineCurve, elements: usize, step: f64) -> Option<Part> {
        let basis = Basis::new(3, elements, reference.param_length(), true).ok()?;
        let quad = Quadrature::new(&reference, &basis, step)?;
        Some(Part {
            reference,
            basis,
            quad,
        })
    }
}

/// A whole-object fit: the object's part and the start's neighbours.
/// Its parameters `theta` are the object's `U`, each neighbour's `U`, then
/// `a`, `c` and the blur.
pub(super) struct Model<'a> {
    pub start: &'a Start,
    /// The object.
    pub own: Part,
    /// The distance of each of the start's points to the object's
    /// reference, pixels: the shape error of its elements.
    pub shape_error: Vec<f64>,
}

impl<'a> Model<'a> {
    /// The object and the start's neighbours, with the first parameter of
    /// each.
    fn parts(&self) -> impl Iterator<Item = (&Part, usize)> {
        std::iter::once(&self.own)
            .chain(&self.start.neighbours)
            .scan(0, |first, part| {
                let at = *first;
                *first += part.basis.n_functions();
                Some((part, at))
            })
    }

    /// The displacements' coefficients, all parts': `a` is `theta[u]`.
    fn displacements(&self) -> usize {
        self.parts().map(|(p, _)| p.basis.n_functions()).sum()
    }

    /// The shape error at `count` points equally spaced on the reference:
    /// the largest of [`Model::shape_error`] within half an element (its
    /// points are about as equally spaced on the band fit's curve).
    fn shape_along(&self, count: usize) -> Vec<f64> {
        let m = self.shape_error.len();
        let reach = (m / self.own.basis.n_elements() / 2).max(1) as isize;
        (0..count)
            .map(|i| {
                let centre = (i * m / count) as isize;
                (centre - reach..=centre + reach)
                    .map(|k| self.shape_error[k.rem_euclid(m as isize) as usize])
                    .fold(0.0, f64::max)
            })
            .collect()
    }

    /// Gauss–Newton from `U = 0`, the start's blur and the levels that fit
    /// best there; `None` if it does not converge or leaves the bounds
    /// ([`MAX_SHIFT`], [`NEIGHBOUR_SHIFT`], [`BLUR_FACTOR`]).
    pub fn fit(self) -> Option<Fit<'a>> {
        let u = self.displacements();
        let count = u + 3;
        let mut scratch = Scratch::new(count, self.start.neighbours.len() + 1);
        let mut theta = vec![0.0; count];
        theta[u + 2] = self.start.blur;
        let (a, c, _) = self.levels(&theta, &mut scratch)?;
        theta[u] = a;
        theta[u + 1] = c;
        let prior = NEIGHBOUR_PRIOR * c * c;
        let mut normal = Normal::new(count);
        let mut ssr = self.accumulate(&theta, &mut normal, &mut scratch, prior);
        let mut delta = vec![0.0; count];
        let mut chol = DenseCholesky::factor(&normal.h, count).ok()?;
        let mut history = Vec::new();
        let pixels = self.start.window.pixels.len();
        for iteration in 0..MAX_ITERATIONS {
            if iteration > 0 {
                chol.refactor(&normal.h).ok()?;
            }
            delta.copy_from_slice(&normal.g);
            chol.solve_in_place(&mut delta);
            let step = delta[..u]
                .iter()
                .chain(std::iter::once(&delta[u + 2]))
                .fold(0.0_f64, |m, d| m.max(d.abs()));
            history.push(IterationRecord {
                iteration,
                max_step: step,
                residual_rms: (ssr / pixels as f64).sqrt(),
                run: RunKind::Reference,
                new_reference: iteration == 0,
            });
            if step < TOLERANCE {
                if !self.within_bounds(&theta, 1.0) {
                    return None;
                }
                // Converged: the last normal equations are the covariance's.
                let dof = pixels.saturating_sub(count).max(1);
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
            // A step is at most `LONGEST_STEP`: far from the solution the
            // blur, the levels and the curves trade off along directions
            // the linearisation stretches.
            if step > LONGEST_STEP {
                let scale = LONGEST_STEP / step;
                delta.iter_mut().for_each(|d| *d *= scale);
            }
            ssr = self.descend((&mut theta, &mut normal), &delta, ssr, &mut scratch, prior)?;
            if !self.within_bounds(&theta, TRANSIENT) {
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
        prior: f64,
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
            let s = self.accumulate(&trial, &mut next, scratch, prior);
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

    /// Whether `theta` keeps the object within [`MAX_SHIFT`] of its
    /// reference, each neighbour within [`NEIGHBOUR_SHIFT`] of its own,
    /// and the blur within [`BLUR_FACTOR`] of the start's.
    fn within_bounds(&self, theta: &[f64], slack: f64) -> bool {
        let u = self.displacements();
        let own = self.own.basis.n_functions();
        let blur = theta[u + 2];
        let largest = |v: &[f64]| v.iter().fold(0.0_f64, |m, x| m.max(x.abs()));
        largest(&theta[..own]) <= slack * MAX_SHIFT
            && largest(&theta[own..u]) <= slack * NEIGHBOUR_SHIFT
            && blur >= self.start.blur / (slack * BLUR_FACTOR)
            && blur <= self.start.blur * slack * BLUR_FACTOR
    }

    /// Every part's curve under `theta` at its quadrature points and its
    /// kernels' tables into `scratch`.
    fn shapes_into(&self, theta: &[f64], scratch: &mut Scratch) {
        let blur = theta[self.displacements() + 2];
        for ((part, first), (shape, tables)) in self
            .parts()
            .zip(scratch.shapes.iter_mut().zip(scratch.tables.iter_mut()))
        {
            let n = part.basis.n_functions();
            part.quad
                .shape_into(&part.basis, &theta[first..first + n], shape);
            shape.tables_into(blur, &self.start.window, tables);
        }
    }

    /// The levels `(a, c)` that fit the window best under the shapes and
    /// blur of `theta` (linear least squares), and the sum of squared
    /// residuals they leave; `None` if degenerate.
    pub fn levels(&self, theta: &[f64], scratch: &mut Scratch) -> Option<(f64, f64, f64)> {
        self.shapes_into(theta, scratch);
        let (mut sw, mut sww, mut sg, mut swg, mut sgg) = (0.0, 0.0, 0.0, 0.0, 0.0);
        for p in &self.start.window.pixels {
            let w: f64 = scratch
                .shapes
                .iter()
                .zip(&scratch.tables)
                .map(|(shape, tables)| shape.render(p, tables).w)
                .sum();
            sw += w;
            sww += w * w;
            sg += p.g;
            swg += w * p.g;
            sgg += p.g * p.g;
        }
        let count = self.start.window.pixels.len() as f64;
        let det = count * sww - sw * sw;
        if det.is_nan() || det.abs() <= 1e-12 * count * sww {
            return None;
        }
        let c = (count * swg - sw * sg) / det;
        let a = (sg - c * sw) / count;
        Some((a, c, (sgg - a * sg - c * swg).max(0.0)))
    }

    /// The sum of squared residuals with every curve at its start, under
    /// a blur of `blur` px and the levels that fit best there.
    pub fn residual_at(&self, blur: f64) -> Option<f64> {
        let count = self.displacements() + 3;
        let mut scratch = Scratch::new(count, self.start.neighbours.len() + 1);
        let mut theta = vec![0.0; count];
        theta[count - 1] = blur;
        self.levels(&theta, &mut scratch).map(|(_, _, ssr)| ssr)
    }

    /// The normal equations of `theta` into `normal`, the neighbours'
    /// displacements held to their starts with the weight `prior`
    /// ([`NEIGHBOUR_PRIOR`]); returns the sum of squared residuals and the
    /// prior's term.
    fn accumulate(
        &self,
        theta: &[f64],
        normal: &mut Normal,
        scratch: &mut Scratch,
        prior: f64,
    ) -> f64 {
        let u = self.displacements();
        let (a, c, blur) = (theta[u], theta[u + 1], theta[u + 2]);
        if blur.is_nan() || blur <= 0.0 {
            return f64::INFINITY;
        }
        self.shapes_into(theta, scratch);
        let Scratch {
            shapes,
            tables,
            row,
            ..
        } = scratch;
        let mut ssr = 0.0;
        for p in &self.start.window.pixels {
            row.iter_mut().for_each(|r| *r = 0.0);
            let (mut w, mut dw) = (0.0, 0.0);
            for (((part, first), shape), tables) in
                self.parts().zip(shapes.iter()).zip(tables.iter())
            {
                let n = part.basis.n_functions();
                let r =
                    shape.render_with_gradient(p, tables, &part.quad, &mut row[first..first + n]);
                w += r.w;
                dw += r.dw_dblur;
            }
            for v in &mut row[..u] {
                *v *= c;
            }
            row[u] = 1.0;
            row[u + 1] = w;
            row[u + 2] = c * dw;
            let e = p.g - a - c * w;
            ssr += e * e;
            normal.add(row, e);
        }
        let own = self.own.basis.n_functions();
        for (i, &t) in theta.iter().enumerate().take(u).skip(own) {
            normal.h[i * normal.n + i] += prior;
            normal.g[i] -= prior * t;
            ssr += prior * t * t;
        }
        ssr
    }
}

/// What the fit's iterations reuse: each part's curve at its quadrature
/// points and its kernels' tables, a Jacobian row, a trial step and its
/// normal equations.
pub(super) struct Scratch {
    shapes: Vec<Shape>,
    tables: Vec<Tables>,
    row: Vec<f64>,
    trial: Vec<f64>,
    next: Normal,
}

impl Scratch {
    /// For `n` parameters and `parts` curves.
    pub fn new(n: usize, parts: usize) -> Self {
        Scratch {
            shapes: (0..parts).map(|_| Shape::default()).collect(),
            tables: (0..parts).map(|_| Tables::default()).collect(),
            row: vec![0.0; n],
            trial: vec![0.0; n],
            next: Normal::new(n),
        }
    }
}

/// Dense normal equations `H delta = g` of the whole-object fit.
pub(super) struct Normal {
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
pub(super) struct Fit<'a> {
    /// `U`'s coefficients, then `a`, `c`, the blur.
    theta: Vec<f64>,
    /// The sum of squared residuals, gray levels².
    ssr: f64,
    /// The residuals' variance (per degree of freedom), gray levels².
    pub noise2: f64,
    /// `(J^T J)^-1`, row-major.
    inverse: Vec<f64>,
    history: Vec<IterationRecord>,
    pub model: Model<'a>,
}

impl Fit<'_> {
    /// Whether this fit's residuals are significantly below those of
    /// `coarser`, a fit of fewer elements: an F test on the drop per
    /// added function, at three standard deviations of its noise-only
    /// spread (the two references differ a little, so the test is an
    /// approximate one).
    pub fn significant_over(&self, coarser: &Fit) -> bool {
        let added = (self.theta.len() - coarser.theta.len()) as f64;
        let drop = (coarser.ssr - self.ssr) / added;
        drop > self.noise2 * (1.0 + 3.0 * (2.0 / added).sqrt())
    }

    /// The fitted curve `x0 + U n0` at points about a quarter of
    /// `spacing` apart (a quarter pixel at most), with their noise terms
    /// and shape terms, and the B-spline through them; `None` if it
    /// crosses itself.
    pub fn outline(&self, spacing: f64) -> Option<Outline> {
        let (reference, basis) = (&self.model.own.reference, &self.model.own.basis);
        let count_all = self.theta.len();
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
                    var += vk * vq * self.inverse[jk * count_all + basis.index(first, q)];
                }
            }
            let f = reference.frame(t);
            let out = self.model.own.quad.outward;
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
    pub fn measurement(
        self,
        mut m: Measurement,
        outline: Outline,
        spacing: f64,
        seconds: f64,
    ) -> Measurement {
        let out = self.model.own.quad.outward;
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
        let u = self.model.displacements();
        let (a, c, blur) = (self.theta[u], self.theta[u + 1], self.theta[u + 2]);
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
            elements: self.model.own.basis.n_elements(),
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
            neighbours: self.model.start.neighbours.len(),
            clipped: 0,
        });
        m
    }
}

/// A fit's curve, sampled densely.
pub(super) struct Outline {
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
    pub fn misfits(&self) -> bool {
        self.shape.iter().zip(&self.noise).any(|(s, n)| s > n)
    }
}
