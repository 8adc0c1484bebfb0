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
//! **Neighbours.** Other objects whose light reaches the window (the dots
//! of a dense grid) are found around the object ([`neighbours`]) and
//! rendered with it, `g = a + c (W + sum W_k)`: each neighbour's own
//! displacement is fitted too (held to its traced start by a weak prior
//! where the window does not see it), the levels and the blur are shared.
//! The band fit takes that light for the object's edge, so with
//! neighbours the whole fit runs at any curvature, and also after the
//! paper's profile (which the schedule keeps when their light spoils the
//! blur's estimate); its blur then starts from the best of a few around
//! the estimate ([`Start::best_blur`]).
//!
//! Edge cases: a fit that does not converge, moves the curve by more than
//! [`MAX_SHIFT`], finds a blur beyond [`model::BLUR_FACTOR`] of its
//! start's, or crosses itself leaves the band fit's result as it was;
//! where neighbours' light reaches that result's band, its samples are
//! flagged and charged with the spread ([`unmodelled`]), as where the
//! object cannot be told from its neighbours. Pixels beyond the image
//! border are not in the window; the rendering needs none of them.

mod model;
mod neighbours;
mod render;

pub(crate) use render::{region_light, rendering_work};

use super::reference::chord_lengths;
use super::schedule::MIN_CLOSED_ELEMENTS;
use super::Measurement;
use super::Outcome;
use crate::curve::SplineCurve;
use crate::interp::Sampler;
use crate::virtual_image::pixel_edge::optical_blur;
use crate::virtual_image::{Kind, Profile};
use model::{Fit, Model, Outline, Part};
use render::{dense_points, near, quadrature_step, spread, window, Window};

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
/// The result is kept only if the curve moved by at most this many
/// pixels from its reference, the band fit's curve (farther, the band fit
/// or this one is not the object's edge).
const MAX_SHIFT: f64 = 1.5;
/// Elements of `U` at least this many spreads long (the blur averages
/// finer detail along the edge away: shorter elements only add noise)...
const MIN_ELEMENT_SPREADS: f64 = 1.5;
/// ... and at least this many pixels.
const MIN_ELEMENT: f64 = 2.0;
/// The least blur (px) a fit after the paper's profile starts its search
/// from ([`Start::best_blur`]).
const MIN_GUESS: f64 = 0.3;
/// A whole-object fit whose residual RMS exceeds the band fit's last
/// stage's (or the image's noise, if larger) this many times does not
/// describe the image and is not kept (one region where the image holds
/// several, nine dots merged at the threshold into one object: 2.7 times
/// the band's and 34 times the noise). A speck too faint for the
/// threshold, whose light only the whole window sees, leaves up to 3.6
/// times the band's (`bench/probes/grids.py`; an ellipse with a speck
/// nearby).
const RESIDUAL_GUARD: f64 = 5.0;
/// Elements of `U`: first the band fit's last stage's, then 1.5 times as
/// many, at most this many times (see [`fitted`]).
const REFINEMENTS: usize = 3;

/// `m` measured against the image of the whole object when it is a small
/// closed silhouette under a blur large against its curvature, or with
/// neighbours whose light reaches it (see the module docs), and that fit
/// converges near `m`'s curve. Its samples' `sigma` is that fit's
/// covariance and its elements' shape error; its last stage report is
/// that fit's (`whole_object`). Otherwise `m`, charged with the light of
/// any neighbours its last band sees ([`unmodelled`]).
pub(super) fn refined(sampler: &Sampler, m: Measurement, spacing: f64) -> Measurement {
    let started = std::time::Instant::now();
    let Some(look) = Look::of(&m) else {
        return m;
    };
    // The neighbours, looked for once: within the reach of the window
    // (of twice the guessed blur without the band fit's), which takes in
    // the band's.
    let reach = look.band_blur.map_or(2.0 * look.guess, |_| look.guess);
    let points = dense_points(&m.curve, 1.0);
    let margin = margin(reach).max(look.half_width);
    let found = neighbours::around(sampler, &points, margin, reach);
    if let Some(start) = Start::of(sampler, &m, &look, found.as_deref().unwrap_or_default()) {
        if let Some((best, outline)) = fitted(&start, spacing) {
            return best.measurement(m, outline, spacing, started.elapsed().as_secs_f64());
        }
    }
    // Where the window's search could not tell the neighbours, the
    // band's own reach may still (a large object beyond it).
    let found = found.or_else(|| neighbours::around(sampler, &points, look.half_width, look.guess));
    unmodelled(m, &look, &points, found.as_deref())
}

/// What decides whether and how `m` is measured whole: a converged closed
/// silhouette whose last stage is a pixel edge or the paper's profile,
/// with a rendering of at most [`MAX_WORK`].
struct Look {
    /// The last stage's pixel-edge blur, px (`None` after the paper's
    /// profile).
    band_blur: Option<f64>,
    /// That blur, else the edge spread's estimate (1 px without one), at
    /// least [`MIN_GUESS`].
    guess: f64,
    /// The last stage's band half-width, px.
    half_width: f64,
}

impl Look {
    /// `m`'s, when it qualifies.
    fn of(m: &Measurement) -> Option<Look> {
        let last = m.stages.last()?;
        if m.outcome != Outcome::Converged || !m.curve.is_closed() {
            return None;
        }
        let band_blur = match last.profile {
            Profile::PixelEdge { blur, .. } => Some(blur),
            Profile::Paper {
                kind: Kind::Silhouette,
            } => None,
            _ => return None,
        };
        let guess = band_blur
            .or_else(|| m.edge_spread.map(|e| optical_blur(e.sigma)))
            .unwrap_or(1.0)
            .max(MIN_GUESS);
        (work_of(&m.curve, guess, 0.0) <= MAX_WORK).then_some(Look {
            band_blur,
            guess,
            half_width: last.half_width,
        })
    }
}

/// The whole-object fit of `start` and its curve: from the band fit's
/// elements, finer while they fit significantly better or while the
/// elements' shape error exceeds the noise term; `None` if the first
/// does not converge or leaves residuals far above the band fit's
/// ([`RESIDUAL_GUARD`]).
fn fitted(start: &Start, spacing: f64) -> Option<(Fit<'_>, Outline)> {
    let mut best = start.model(start.elements)?.fit()?;
    if best.noise2.sqrt() > RESIDUAL_GUARD * start.band_rms {
        return None;
    }
    let mut outline = best.outline(spacing)?;
    for _ in 0..REFINEMENTS {
        let n = (3 * best.model.own.basis.n_elements()).div_ceil(2);
        if n > start.most_elements {
            break;
        }
        let Some(fit) = start.model(n).and_then(|model| model.fit()) else {
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
    Some((best, outline))
}

/// `m` with every sample flagged as a misfit and its `sigma` charged with
/// the edge's spread, where another object's light reaches its last band
/// (one of the neighbours `found` lies within three spreads of the band
/// around `points`, the curve) and the whole-object fit did not take it
/// in: the band's profile takes that light for the edge's, which moves
/// the curve by up to about a spread, and its residuals do not show it
/// (a dot of a dense grid under a blur as large as the gaps). Also where
/// the object cannot be told from its neighbours (`found` is `None`,
/// [`neighbours::around`]). Else `m`.
fn unmodelled(
    mut m: Measurement,
    look: &Look,
    points: &[[f64; 2]],
    found: Option<&[SplineCurve]>,
) -> Measurement {
    let spread = spread(look.guess);
    let reach = look.half_width + 3.0 * spread;
    let seen = |c: &SplineCurve| dense_points(c, 1.0).iter().any(|&p| near(points, p, reach));
    if found.is_some_and(|f| !f.iter().any(seen)) {
        return m;
    }
    for s in &mut m.samples {
        s.sigma = s.sigma.hypot(spread);
        s.misfit = true;
    }
    m
}

/// What the whole-object fits share.
pub(super) struct Start {
    /// The band fit's curve, points at most [`Start::step`] apart.
    points: Vec<[f64; 2]>,
    /// The first fit's elements: the band fit's, at most
    /// [`Start::most_elements`], at least [`MIN_CLOSED_ELEMENTS`].
    elements: usize,
    /// The most elements a fit may have: none shorter than
    /// [`MIN_ELEMENT_SPREADS`] spreads or [`MIN_ELEMENT`].
    most_elements: usize,
    /// The blur the fits start from, pixels.
    blur: f64,
    /// The quadrature's longest piece, pixels of parameter.
    step: f64,
    /// The window.
    window: Window,
    /// The band fit's last residual RMS, or the image's noise if larger,
    /// gray levels.
    band_rms: f64,
    /// The neighbours whose light reaches the window, rendered and fitted
    /// with the object ([`neighbours`]).
    neighbours: Vec<Part>,
}

impl Start {
    /// The start of `m` (which qualifies as `look` says) with the
    /// neighbours `found`: without corners, its last stage an isotropic
    /// pixel edge (or the paper's profile, where neighbours are found:
    /// their light is one reason the edge's blur could not be estimated),
    /// with neighbours or a blur times largest curvature of at least
    /// [`MIN_BLUR_CURVATURE`], and a rendering of at most [`MAX_WORK`].
    fn of(sampler: &Sampler, m: &Measurement, look: &Look, found: &[SplineCurve]) -> Option<Start> {
        let curve = &m.curve;
        let isotropic = matches!(
            m.stages.last()?.profile,
            Profile::PixelEdge { anisotropy, .. } if anisotropy.is_none()
        );
        if !curve.corners().is_empty() || (look.band_blur.is_some() && !isotropic) {
            return None;
        }
        let curved = spread(look.guess) * curve.largest_curvature(0.25) >= MIN_BLUR_CURVATURE;
        if found.is_empty() && !(curved && look.band_blur.is_some()) {
            return None;
        }
        let blur = match look.band_blur {
            Some(b) => b,
            None => Start::build(sampler, m, look.guess, found)?.best_blur()?,
        };
        Start::build(sampler, m, blur, found)
    }

    /// The start of `m` under `blur` with the neighbours `found`; `None`
    /// beyond [`MAX_WORK`].
    fn build(
        sampler: &Sampler,
        m: &Measurement,
        blur: f64,
        found: &[SplineCurve],
    ) -> Option<Start> {
        let curve = &m.curve;
        let extra: f64 = found.iter().map(SplineCurve::arc_length).sum();
        if work_of(curve, blur, extra) > MAX_WORK {
            return None;
        }
        let spread = spread(blur);
        let step = quadrature_step(blur);
        let points = dense_points(curve, step);
        let window = window(sampler, &points, margin(blur));
        // Elements no shorter than the blur resolves along the edge.
        let shortest = (MIN_ELEMENT_SPREADS * spread).max(MIN_ELEMENT);
        let length = curve.arc_length();
        let most_elements = (length / shortest) as usize;
        let last = m.stages.last()?;
        let elements = last.elements.min(most_elements).max(MIN_CLOSED_ELEMENTS);
        // The neighbours' elements as long as the object's first ones.
        let element = length / elements as f64;
        let neighbours = found
            .iter()
            .map(|c| {
                let most = ((c.arc_length() / shortest) as usize).max(MIN_CLOSED_ELEMENTS);
                let n =
                    ((c.arc_length() / element).round() as usize).clamp(MIN_CLOSED_ELEMENTS, most);
                Part::new(c.clone(), n, step)
            })
            .collect::<Option<Vec<Part>>>()?;
        let band_rms = last.residual_rms.max(sampler.pixel_noise());
        Some(Start {
            points,
            elements,
            most_elements,
            blur,
            step,
            window,
            band_rms,
            neighbours,
        })
    }

    /// The blur, among the start's times 2^(k/2) for k from -2 to 3, under
    /// which the curves as they start and the levels that fit best there
    /// leave the least squared residual: a start for the fit's own, where
    /// the edge's blur could not be estimated.
    fn best_blur(&self) -> Option<f64> {
        let model = self.model(self.elements)?;
        let mut best: Option<(f64, f64)> = None;
        for k in -2..=3 {
            let blur = self.blur * 2f64.powf(0.5 * k as f64);
            if let Some(ssr) = model.residual_at(blur) {
                if best.is_none_or(|(s, _)| ssr < s) {
                    best = Some((ssr, blur));
                }
            }
        }
        best.map(|(_, b)| b)
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
        let own = Part::new(reference, n, self.step)?;
        let parameters: usize = self.neighbours.iter().map(|p| p.basis.n_functions()).sum();
        (self.window.pixels.len() > 2 * (n + 3 + parameters)).then_some(Model {
            start: self,
            own,
            shape_error,
        })
    }
}

/// The window's margin beyond the curve under a blur of `blur` px.
fn margin(blur: f64) -> f64 {
    MARGIN_SPREADS * spread(blur) + MAX_SHIFT
}

/// The work of one rendering of `curve` and of neighbours `extra` px long
/// under a blur of `blur` px, on the curve's window.
fn work_of(curve: &SplineCurve, blur: f64, extra: f64) -> f64 {
    let margin = margin(blur);
    let [x0, y0, x1, y1] = curve.bounding_box();
    let area = (x1 - x0 + 2.0 * margin) * (y1 - y0 + 2.0 * margin);
    let work = rendering_work(curve.arc_length() + extra, blur, area);
    if work.is_nan() {
        f64::INFINITY
    } else {
        work
    }
}
