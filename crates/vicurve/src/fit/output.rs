//! The result of the last stage (method, section 8): the measured curve
//! `x0 + U n` refitted as a B-spline, its samples with normals, `sigma`
//! and robust weight, and the gray levels along it.

use super::blur::{settle_noise_gain, shortest_element};
use super::blur_offset::Coupling;
use super::breaks;
use super::misfit::{band_range, oscillation, oscillation_at, EdgeCheck, ResidualMisfit};
use super::reference::{chord_lengths, CURVE_SPACING};
use super::refine::{displacement, LocalShapeError};
use super::representation::Representation;
use super::{LevelSample, Sample};
use crate::correlation::Correlation;
use crate::curve::SplineCurve;
use crate::error::Result;
use crate::interp::Sampler;
use crate::measurement::Divergence;
use crate::virtual_image::corner::REACH;
use crate::virtual_image::pixel_edge::spread_variance;
use crate::virtual_image::{Kind, Profile};
use rayon::prelude::*;

/// Largest spacing of the points of `x0 + U n` the output curve is fitted
/// to (control points `CURVE_SPACING` apart: four points per interval),
/// pixels; see [`Final::samples`] for the spacing taken.
const FINE_STEP: f64 = 0.5;
/// How much the displacement may stretch the reference (`1 + U kappa`)
/// before the output samples, points of `x0 + U n`, come closer than the
/// requested spacing ([`Final::samples`], `output_points`).
const STRETCH_ALLOWANCE: f64 = 0.03;
/// Spacing of [`super::Measurement::levels`] along the curve, pixels.
const LEVEL_SAMPLE_SPACING: f64 = 8.0;

/// The last completed stage, kept to produce the output samples and their
/// uncertainty.
pub(super) struct Final {
    /// Band half-width of the stage, pixels.
    pub half_width: f64,
    /// The stage's virtual profile.
    pub profile: Profile,
    /// The stage's last reference.
    pub reference: SplineCurve,
    /// Its system.
    pub corr: Correlation,
    /// Its coefficients, pixels.
    pub lambda: Vec<f64>,
    /// The shape error of its elements, when its refinement measured one
    /// (RMS over the curve, pixels): a floor of the model term of every
    /// sample's `sigma` (not a flagged misfit: where along the curve it
    /// lies is not known).
    pub shape_error: Option<f64>,
    /// Where along the curve that error lies, when the refinement could
    /// tell: each sample's own model term, and a flagged misfit where it
    /// exceeds the noise term.
    pub local_shape: Option<LocalShapeError>,
    /// How the pixel edge's blur and the curve's offset trade off, where
    /// they do (`fit/blur_offset.rs`): the blur's uncertainty then adds to
    /// every sample's noise term.
    pub coupling: Option<Coupling>,
}

/// What [`Final::samples`] delivers.
pub(super) struct Output {
    /// The measured B-spline.
    pub curve: SplineCurve,
    /// Its largest distance to the points of `x0 + U n`, pixels.
    pub fit_error: f64,
    /// The output samples.
    pub samples: Vec<Sample>,
    /// The gray levels along the curve, when they vary.
    pub levels: Vec<LevelSample>,
    /// Where the curve left the edge ([`Divergence::LostEdge`], the middle
    /// of the longest stretch of samples whose band holds no edge, when it
    /// spans an element or more), or does not follow it
    /// ([`Divergence::OffEdge`], see [`off_edge`]).
    pub lost_edge: Option<Divergence>,
}

impl Final {
    /// Dense samples of `x0 + U n` (moved by the blur's curvature shift
    /// when `blur` is given, see [`crate::psf`]), the B-spline of `degree`
    /// fitted to them and its largest deviation from them, the output
    /// samples at most `spacing` pixels apart with `sigma` (its misfit
    /// term from the band's residuals on the image of `sampler`), and the
    /// gray levels along the curve when they vary. `left`: the spread
    /// (pixels) of a blurred edge whose curvature shift could not be
    /// removed (the last band too narrow for it): each sample's model term
    /// then covers that shift, the most the curve can be off by it. Never
    /// inlined: `vicurve bench speed --profile` tells this phase by its
    /// frame.
    #[inline(never)]
    pub fn samples(
        &self,
        sampler: &Sampler,
        spacing: f64,
        degree: usize,
        (blur, left): (Option<f64>, Option<f64>),
    ) -> Result<Output> {
        // The output samples are points of `x0 + U n` at most `spacing`
        // apart (`output_points`): the points are taken a little closer
        // than `spacing / per` on the reference, for the displacement's
        // stretch, so that every `per`-th one is an output sample where the
        // curve is not stretched more than that.
        let per = (spacing / FINE_STEP).ceil().max(1.0);
        let fine_step = spacing / per / (1.0 + STRETCH_ALLOWANCE);
        let closed = self.reference.is_closed();
        let (params, mut pts, corners) =
            breaks::displaced_samples(&self.reference, self.corr.basis(), &self.lambda, fine_step);
        let mut curve =
            SplineCurve::fit_with_corners(&pts, closed, degree, CURVE_SPACING, &corners)?;
        let mut s = chord_lengths(&pts);
        if let Some(sigma) = blur {
            for (q, &si) in pts.iter_mut().zip(&s) {
                let f = curve.frame(si);
                let shift = crate::psf::curvature_shift(sigma, f.curvature);
                q[0] += shift * f.normal[0];
                q[1] += shift * f.normal[1];
            }
            curve = SplineCurve::fit_with_corners(&pts, closed, degree, CURVE_SPACING, &corners)?;
            s = chord_lengths(&pts);
        }
        let weights = WeightBins::new(&self.corr, self.reference.param_length());
        let levels = self.levels(&params, &s, closed);
        // In parallel (each point's values are its own; a maximum does not
        // depend on the order).
        let fit_error = pts
            .par_iter()
            .zip(&s)
            .map(|(q, &si)| crate::curve::dist(curve.point(si), *q))
            .reduce(|| 0.0, f64::max);
        let closing = if closed {
            pts.last().map_or(0.0, |q| crate::curve::dist(*q, pts[0]))
        } else {
            f64::INFINITY
        };
        let kept = output_points(&s, spacing, closing);
        let terms = SigmaTerms::new(self, sampler, (&params, &s), blur);
        let speed = self.reference.arc_length() / self.reference.param_length();
        let at: Vec<f64> = kept.iter().map(|&i| s[i]).collect();
        let noise_terms: Vec<(f64, f64)> =
            kept.par_iter().map(|&i| terms.at(i, params[i])).collect();
        let noise: Vec<f64> = noise_terms.iter().map(|t| t.0).collect();
        let shapes = Representation::new(
            self.corr.basis().element_length() * speed,
            self.corr.basis().degree(),
            self.profile,
        )
        .map(|r| r.along(&curve, &at, &noise));
        let (samples, seen): (Vec<Sample>, Vec<(bool, f64)>) = kept
            .par_iter()
            .enumerate()
            .map(|(k, &i)| {
                let q = pts[i];
                let f = curve.frame(s[i]);
                let (sigma_noise, misfit) = noise_terms[k];
                let (misfit, seen) = terms.edge_checked(params[i], sigma_noise, misfit);
                // The shape error the elements leave where the edge bends
                // faster than they follow, here (`representation.rs`).
                let shape = shapes.as_ref().map_or(0.0, |r| r[k]);
                // A rejected refinement's measure of the elements' shape
                // error is spread over the curve: it counts in `sigma`,
                // not as a local misfit.
                let model = misfit.max(shape).max(self.shape_error.unwrap_or(0.0));
                // ... and where it lies, its share here.
                let local = self.local_shape.as_ref().map_or(0.0, |l| l.at(q));
                let (model, shape) = (model.max(local), shape.max(local));
                // The blur's curvature shift left in the curve.
                let unremoved = left.map_or(0.0, |sigma| {
                    crate::psf::curvature_shift(sigma, f.curvature).abs()
                });
                let (model, misfit) = (model.max(unremoved), misfit.max(unremoved));
                let sample = Sample {
                    s: s[i],
                    x: q[0],
                    y: q[1],
                    nx: f.normal[0],
                    ny: f.normal[1],
                    sigma: sigma_noise.hypot(model),
                    sigma_noise,
                    misfit: misfit.max(shape) > sigma_noise,
                    weight: weights.at(params[i]),
                };
                (sample, seen)
            })
            .unzip();
        let span = self.corr.basis().element_length();
        let lost: Vec<bool> = seen.iter().map(|&(lost, _)| lost).collect();
        let offsets: Vec<f64> = seen.iter().map(|&(_, offset)| offset).collect();
        let lost_edge = lost_stretch(&samples, &lost, closed, span)
            .map(|[x, y]| Divergence::LostEdge { x, y })
            .or_else(|| off_edge(&samples, &offsets, span));
        Ok(Output {
            curve,
            fit_error,
            samples,
            levels,
            lost_edge,
        })
    }

    /// The gray levels at the points of reference parameters `params` and
    /// arc lengths `s`, about `LEVEL_SAMPLE_SPACING` apart (and at an open
    /// curve's end); none when the levels are global.
    fn levels(&self, params: &[f64], s: &[f64], closed: bool) -> Vec<LevelSample> {
        let mut levels = Vec::new();
        if !self.corr.varying_levels() {
            return levels;
        }
        let mut next_level = 0.0;
        for (i, &u) in params.iter().enumerate() {
            let last = !closed && i + 1 == params.len();
            if s[i] >= next_level || last {
                if let Some((a, c)) = self.corr.levels_at(u) {
                    levels.push(LevelSample { s: s[i], a, c });
                }
                next_level = s[i] + LEVEL_SAMPLE_SPACING;
            }
        }
        levels
    }
}

/// The two terms of a sample's `sigma` ([`super::misfit`]), prepared once.
struct SigmaTerms<'a> {
    fin: &'a Final,
    residual: Option<ResidualMisfit>,
    /// The level-crossing check of a silhouette's samples.
    edge: Option<EdgeCheck<'a>>,
    /// The oscillation of `U` at each point of `x0 + U n`, when it is
    /// checked.
    oscillation: Option<Vec<f64>>,
    /// Points of `x0 + U n` in an element.
    reach: usize,
    /// The settles' noise gain on the Gauss–Newton `sigma`.
    gain: f64,
    /// What the blur's uncertainty adds to every sample's noise term,
    /// pixels (standard deviation; 0 where the blur and the curve's offset
    /// do not trade off).
    blur_sd: f64,
    /// The rounding's floor on the noise, a factor on `sigma`.
    rounding: f64,
    /// The residuals' correlation factor on the noise variance
    /// ([`super::correlated`]), lowered where the requests are smaller
    /// than the noise estimate says.
    correlation: f64,
    /// Where a corner's wedges reach, and the factor there.
    near_corners: Option<NearCorners>,
}

/// The stretches of a curve with corners where the noise term keeps the
/// unlowered correlation factor ([`SigmaTerms::gain_at`]).
struct NearCorners {
    /// The corners' reference parameters.
    corners: Vec<f64>,
    /// How far from a corner, in reference parameter ([`corner_reach`]).
    reach: f64,
    /// The reference's parameter length.
    length: f64,
    /// Whether the reference is closed.
    closed: bool,
    /// The unlowered factor.
    correlation: f64,
}

impl NearCorners {
    /// Whether reference parameter `u` lies within the reach of a corner.
    fn holds(&self, u: f64) -> bool {
        self.corners.iter().any(|&c| {
            let d = (u - c).abs();
            let d = if self.closed {
                d.min(self.length - d)
            } else {
                d
            };
            d <= self.reach
        })
    }
}

/// How far from a corner (reference parameter, for `speed` pixels of
/// curve per unit) its wedge model's errors reach along the sides: the
/// wedge terms' [`REACH`] spreads of the pixel edge's blur (the pixel's
/// own spread for other profiles), and an element beyond, whose
/// displacement takes up what the wedge leaves at the side's end.
fn corner_reach(profile: Profile, span: f64, speed: f64) -> f64 {
    let blur = profile.blur().unwrap_or(0.0);
    let spread = spread_variance(blur).sqrt();
    REACH * spread / speed.max(1e-9) + span
}

impl<'a> SigmaTerms<'a> {
    /// The terms for the points of `x0 + U n` of `fin` at reference
    /// parameters `params` and arc lengths `s`, and the edge's spread
    /// `blur` (pixels, when its curvature shift was removed).
    fn new(
        fin: &'a Final,
        sampler: &'a Sampler,
        (params, s): (&[f64], &[f64]),
        blur: Option<f64>,
    ) -> Self {
        let closed = fin.reference.is_closed();
        let step = s.last().copied().unwrap_or(0.0) / (params.len().max(2) - 1) as f64;
        let span = fin.corr.basis().element_length();
        // Elements shorter than the blur resolves (`shortest_element`;
        // given ones can be) may describe an oscillation the image no
        // longer holds, unseen by the residuals; longer ones follow what
        // the image shows.
        let shortest = match fin.profile {
            Profile::PixelEdge { blur, .. } | Profile::PixelLine { blur, .. } => {
                Some(shortest_element(blur))
            }
            Profile::Paper { .. } => {
                blur.map(|b| std::f64::consts::PI * b * std::f64::consts::FRAC_1_SQRT_2)
            }
        };
        let oscillation = shortest.filter(|&r| span < r).map(|_| {
            let basis = fin.corr.basis();
            let u: Vec<f64> = params
                .iter()
                .map(|&p| displacement(basis, &fin.lambda, p))
                .collect();
            oscillation(&u, step, span, closed)
        });
        // A pixel-edge stage's settles amplify the noise of one fit.
        let gain = match fin.profile {
            Profile::PixelEdge { blur, .. } | Profile::PixelLine { blur, .. } => {
                settle_noise_gain(blur, span)
            }
            Profile::Paper { .. } => 1.0,
        };
        let residual = ResidualMisfit::new(&fin.corr, &fin.lambda, sampler);
        // Residual requests smaller than the noise estimate says lower the
        // noise term, except near a corner: its wedge model leaves errors
        // at the sides' ends that the requests do not show, and the larger
        // estimate is all that covers them (docs/benchmarks.md). Along the
        // sides beyond the wedges' reach the edge is a plain one.
        let factor = |lower: bool| {
            residual
                .as_ref()
                .map_or(1.0, |r| r.correlation_factor(fin.corr.basis(), lower))
        };
        let correlation = factor(true);
        let corners = fin.reference.corners();
        let near_corners = (!corners.is_empty()).then(|| NearCorners {
            corners: corners.to_vec(),
            reach: corner_reach(
                fin.profile,
                span,
                fin.reference.arc_length() / fin.reference.param_length(),
            ),
            length: fin.reference.param_length(),
            closed,
            correlation: factor(false),
        });
        // The noise estimate misses the rounding to the image's gray-level
        // steps (`Correlation::estimate_noise`): the Gauss–Newton `sigma`
        // scales as the root of the noise variance.
        let rounding = fin.corr.rounding_gain(sampler);
        let blur_sd = match (fin.coupling, fin.corr.noise_var()) {
            (Some(c), Some(v)) => rounding * c.position_sd(v),
            _ => 0.0,
        };
        let edge = match fin.profile {
            Profile::PixelEdge { blur, .. } => Some(Some(blur)),
            Profile::Paper {
                kind: Kind::Silhouette,
            } => Some(None),
            Profile::Paper { .. } | Profile::PixelLine { .. } => None,
        }
        .and_then(|blur| EdgeCheck::new(sampler, &fin.reference, &fin.corr, fin.half_width, blur));
        SigmaTerms {
            fin,
            residual,
            edge,
            oscillation,
            reach: ((span / step.max(1e-9)).round() as usize).max(1),
            gain,
            blur_sd,
            rounding,
            correlation,
            near_corners,
        }
    }

    /// The factor on the Gauss–Newton `sigma` at reference parameter `u`:
    /// the settles' gain, the rounding's floor, and the root of the
    /// residuals' correlation factor (its unlowered value near a corner).
    fn gain_at(&self, u: f64) -> f64 {
        let correlation = match &self.near_corners {
            Some(near) if near.holds(u) => near.correlation,
            _ => self.correlation,
        };
        self.gain * correlation.sqrt() * self.rounding
    }

    /// The noise term and the misfit term (pixels) at point `i`, of
    /// reference parameter `u`.
    fn at(&self, i: usize, u: f64) -> (f64, f64) {
        let closed = self.fin.reference.is_closed();
        let noise = (self.gain_at(u) * self.fin.corr.position_sigma(u)).hypot(self.blur_sd);
        let residual = self.residual.as_ref().map_or(0.0, |r| r.at(u));
        let oscillation = self
            .oscillation
            .as_ref()
            .map_or(0.0, |o| oscillation_at(o, i, self.reach, noise, closed));
        (noise, residual.max(oscillation))
    }

    /// The misfit term of a sample at reference parameter `u` with the
    /// terms `noise` and `misfit` of [`Self::at`]: where it is flagged
    /// (`misfit > noise`), at least the image's edge's distance from it
    /// ([`EdgeCheck`]), which a linearised request underestimates when it
    /// is large, or the band's half-width where the band holds no edge.
    /// With it: whether the band holds none (the curve left the edge
    /// there), flagged or not: where the band sees only a plateau the
    /// residuals are the noise's, and nothing is flagged; and the edge's
    /// distance at a flagged sample (0 elsewhere), pixels.
    fn edge_checked(&self, u: f64, noise: f64, misfit: f64) -> (f64, (bool, f64)) {
        let Some(edge) = &self.edge else {
            return (misfit, (false, 0.0));
        };
        let fin = self.fin;
        let offset = edge.at(u, displacement(fin.corr.basis(), &fin.lambda, u));
        let flagged = misfit > noise;
        match offset {
            Some(offset) if flagged => (misfit.max(offset), (false, offset)),
            Some(_) => (misfit, (false, 0.0)),
            None if flagged => (misfit.max(fin.half_width), (true, 0.0)),
            None => (misfit, (true, 0.0)),
        }
    }
}

/// The middle of the longest stretch of `samples` (of a closed curve or
/// not) whose bands, `half_width` pixels on each side along their normals
/// on the image of `sampler`, each vary by less than `threshold` gray
/// levels ([`band_range`]): plateaus, where the curve is off any edge its
/// band could see; when that stretch is at least `span` pixels long, or
/// such samples make up `share` of them. For results whose levels may not
/// be fitted yet (an iteration limit), where the level crossing's test
/// cannot tell a plateau from levels without contrast.
pub(super) fn plateau_stretch(
    samples: &[Sample],
    sampler: &Sampler,
    (half_width, threshold): (f64, f64),
    closed: bool,
    (span, share): (f64, f64),
) -> Option<[f64; 2]> {
    let lost: Vec<bool> = samples
        .par_iter()
        .map(|s| band_range(sampler, [s.x, s.y], [s.nx, s.ny], half_width) < threshold)
        .collect();
    let plateaus = lost.iter().filter(|&&l| l).count() as f64;
    let span = if plateaus >= share * samples.len() as f64 {
        0.0
    } else {
        span
    };
    lost_stretch(samples, &lost, closed, span)
}

/// The middle of the longest run of consecutive `samples` marked `lost`
/// (wrapping round a closed curve), when its arc length reaches `span`
/// pixels (an element: a sample or two without an edge in the band are
/// clutter or a corner, a stretch that long is a curve off the edge).
fn lost_stretch(samples: &[Sample], lost: &[bool], closed: bool, span: f64) -> Option<[f64; 2]> {
    let n = samples.len();
    if n == 0 || !lost.iter().any(|&l| l) {
        return None;
    }
    // Runs start after a sample that is not lost; a closed curve lost all
    // round is one run from sample 0.
    let start = if closed {
        (0..n).find(|&i| !lost[i]).map_or(0, |i| i + 1)
    } else {
        0
    };
    let length = samples.last().map_or(0.0, |l| l.s);
    let mut best: Option<(f64, usize, usize)> = None;
    let mut run: Option<usize> = None;
    for k in 0..=n {
        let i = (start + k) % n;
        let on = k < n && lost[i];
        match (on, run) {
            (true, None) => run = Some(k),
            (false, Some(first)) => {
                let (a, b) = ((start + first) % n, (start + k - 1) % n);
                let arc = if b >= a {
                    samples[b].s - samples[a].s
                } else {
                    length - samples[a].s + samples[b].s
                };
                if best.is_none_or(|(l, _, _)| arc > l) {
                    best = Some((arc, first, k - 1));
                }
                run = None;
            }
            _ => {}
        }
    }
    let (arc, first, last) = best?;
    let mid = &samples[(start + (first + last) / 2) % n];
    (arc >= span).then_some([mid.x, mid.y])
}

/// A sample counts as off the edge ([`off_edge`]) when the image puts the
/// edge more than this far from it, pixels: a pixel off is no measurement
/// for a tool whose results are read to the thousandth (docs/benchmarks.md,
/// "Off the edge between crossings", for what the conformance sweep's
/// results hold).
const OFF_EDGE: f64 = 1.0;

/// Where a curve does not follow the edge: when `samples` whose `offsets`
/// (the edge's distance from each, pixels; 0 where it is within the
/// noise) exceed [`OFF_EDGE`] add up to `span` pixels of arc (an element)
/// or more, [`Divergence::OffEdge`] at the one farthest off. Added up,
/// not in one stretch: elements too long for a star's bays leave each
/// bay in stretches shorter than an element, between which the curve
/// crosses the edge (the level crossing sees the edge there, so
/// [`lost_stretch`] does not). A sample's arc is half the way to each
/// neighbour (the first and last samples', half the way to their one).
fn off_edge(samples: &[Sample], offsets: &[f64], span: f64) -> Option<Divergence> {
    let n = samples.len();
    let arc = |i: usize| 0.5 * (samples[(i + 1).min(n - 1)].s - samples[i.saturating_sub(1)].s);
    let off: f64 = (0..n).filter(|&i| offsets[i] > OFF_EDGE).map(arc).sum();
    if off < span {
        return None;
    }
    let far = (0..n).max_by(|&a, &b| offsets[a].total_cmp(&offsets[b]))?;
    Some(Divergence::OffEdge {
        x: samples[far].x,
        y: samples[far].y,
        offset: offsets[far],
    })
}

/// The indices of the output samples among points at arc lengths `s`
/// (increasing, from 0): the first, then each point after which the next
/// would lie more than `spacing` (px) from the last one kept, and an open
/// curve's last point (`closing` infinite; for a closed curve, the chord
/// from the last point back to the first). Samples are then at most
/// `spacing` apart wherever the points' chords are, and as close to it as
/// the points allow, even where the curve is locally stretched (where a
/// rule by index, every `k`-th point with `k` from the longest chord,
/// kept every point of the whole curve).
pub(super) fn output_points(s: &[f64], spacing: f64, closing: f64) -> Vec<usize> {
    let n = s.len();
    let mut kept = Vec::with_capacity(n);
    if n == 0 {
        return kept;
    }
    kept.push(0);
    // A hair over `spacing`: points exactly `spacing` apart on the
    // reference keep their regular rhythm despite rounding.
    let reach = spacing * (1.0 + 1e-9);
    let mut last = 0;
    for i in 1..n {
        let next = if i + 1 < n { s[i + 1] } else { s[i] + closing };
        if next - s[last] > reach {
            kept.push(i);
            last = i;
        }
    }
    kept
}

/// Robust weights binned by the reference parameter, 1 px bins (none when
/// no pixel was reweighted: the weight is 1 everywhere).
struct WeightBins {
    /// Sum of the weights and count of the pixels of each bin.
    bins: Vec<(f64, f64)>,
}

impl WeightBins {
    /// The bins of `corr`'s band, on a reference of parameter length `l`.
    fn new(corr: &Correlation, l: f64) -> Self {
        if !corr.reweighted() {
            return WeightBins { bins: Vec::new() };
        }
        let nbins = l.ceil() as usize + 1;
        let mut bins = vec![(0.0, 0.0); nbins];
        for (i, &u) in corr.band().s.iter().enumerate() {
            let b = &mut bins[(u.max(0.0) as usize).min(nbins - 1)];
            b.0 += corr.robust()[i];
            b.1 += 1.0;
        }
        WeightBins { bins }
    }

    /// The mean weight of the bins around reference parameter `u`.
    fn at(&self, u: f64) -> f64 {
        let nbins = self.bins.len();
        if nbins == 0 {
            return 1.0;
        }
        let k = (u.max(0.0) as usize).min(nbins - 1);
        let (mut sum, mut n) = (0.0, 0.0);
        for b in &self.bins[k.saturating_sub(1)..=(k + 1).min(nbins - 1)] {
            sum += b.0;
            n += b.1;
        }
        if n > 0.0 {
            sum / n
        } else {
            1.0
        }
    }
}

/// Samples of a curve without a fit behind them (sigma unknown: NaN).
pub(super) fn plain_samples(curve: &SplineCurve, spacing: f64) -> Vec<Sample> {
    let l = curve.param_length();
    let count = (l / spacing).ceil() as usize;
    let params = curve.sample_params(if curve.is_closed() { count } else { count + 1 });
    params
        .iter()
        .map(|&u| {
            let f = curve.frame(u);
            Sample {
                s: u,
                x: f.point[0],
                y: f.point[1],
                nx: f.normal[0],
                ny: f.normal[1],
                sigma: f64::NAN,
                sigma_noise: f64::NAN,
                misfit: false,
                weight: f64::NAN,
            }
        })
        .collect()
}

#[cfg(test)]
mod tests {
    use super::output_points;

    /// Arc lengths of points with the given chords.
    fn arcs(chords: &[f64]) -> Vec<f64> {
        let mut s = vec![0.0];
        for c in chords {
            s.push(s.last().unwrap() + c);
        }
        s
    }

    /// The largest gap between kept samples (and, closed, back to the
    /// first across `closing`).
    fn largest_gap(s: &[f64], kept: &[usize], closing: f64) -> f64 {
        let mut gap = kept
            .windows(2)
            .map(|w| s[w[1]] - s[w[0]])
            .fold(0.0, f64::max);
        if closing.is_finite() {
            gap = gap.max(s[s.len() - 1] + closing - s[*kept.last().unwrap()]);
        }
        gap
    }

    /// Regular chords: every `per`-th point, and an open curve's end.
    #[test]
    fn regular_points_keep_their_rhythm() {
        let s = arcs(&[0.485; 40]);
        let kept = output_points(&s, 1.0, f64::INFINITY);
        assert_eq!(&kept[..4], &[0, 2, 4, 6]);
        assert_eq!(*kept.last().unwrap(), 40);
        assert!(largest_gap(&s, &kept, f64::INFINITY) <= 1.0);
    }

    /// A few stretched chords (a corner's fill, a displacement's stretch)
    /// change the rhythm only where they are: the rest keeps half the
    /// points, not all of them.
    #[test]
    fn a_local_stretch_does_not_double_the_samples() {
        let mut chords = vec![0.485; 100];
        chords[50] = 0.9;
        chords[51] = 0.8;
        let s = arcs(&chords);
        let closing = 0.485;
        let kept = output_points(&s, 1.0, closing);
        assert!(kept.len() <= 55, "{} samples", kept.len());
        assert!(largest_gap(&s, &kept, closing) <= 1.0);
    }

    /// Closed: the gap across the closing chord stays within the spacing.
    #[test]
    fn a_closed_curve_closes_within_the_spacing() {
        for n in [7, 8, 9, 10] {
            let s = arcs(&vec![0.45; n]);
            let kept = output_points(&s, 1.0, 0.45);
            assert!(largest_gap(&s, &kept, 0.45) <= 1.0, "{n}: {kept:?}");
        }
    }
}
