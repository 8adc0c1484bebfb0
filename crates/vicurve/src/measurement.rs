//! What a measurement returns: the curve, its samples, how each stage ended.
//!
//! Written by [`crate::fit`] and [`crate::model`], read by [`crate::derived`],
//! [`crate::report`] and [`crate::diagnostics`]; it imports none of them.

use crate::curve::{SplineCurve, SplineCurveData};
use crate::tone::{Tone, ToneEstimate};
use crate::virtual_image::Profile;
use serde::{Deserialize, Serialize};

/// Why a fit stopped without converging.
#[derive(Clone, Copy, Debug, PartialEq, Serialize, Deserialize)]
#[serde(tag = "reason", rename_all = "snake_case")]
pub enum Divergence {
    /// The displaced curve or its band left the image near this point.
    LeftImage {
        /// x (column), pixels.
        x: f64,
        /// y (row), pixels.
        y: f64,
    },
    /// The band holds no contrast: no edge or line within `R` of the curve.
    NoContrast,
    /// NaN or infinity appeared in the unknowns.
    NonFinite,
    /// The normal matrix of a new reference is singular (an element sees no
    /// image gradient), or the new reference is degenerate.
    Degenerate,
    /// The curve crosses itself near this point: no edge does, so the band
    /// lost the edge there (see `fit::loops`).
    SelfIntersecting {
        /// x (column), pixels.
        x: f64,
        /// y (row), pixels.
        y: f64,
    },
    /// The curve folded back on itself near this point: the displacement
    /// ran the reference backwards there, or a closed curve turns more (or
    /// less) than once round (it loops).
    FoldedBack {
        /// x (column), pixels.
        x: f64,
        /// y (row), pixels.
        y: f64,
    },
    /// The curve left the edge near this point: along a stretch of at
    /// least an element, the band holds no edge (no crossing of the half
    /// level within `R` of the curve; for a fit stopped by its iteration
    /// limit, an image that varies across the band no more than a
    /// plateau's, along an element or a quarter of the curve).
    LostEdge {
        /// x (column), pixels.
        x: f64,
        /// y (row), pixels.
        y: f64,
    },
    /// The curve does not follow the edge: the stretches where the image
    /// puts the edge more than a pixel off it (the level crossing, at
    /// samples flagged as misfits) add up to an element or more, between
    /// stretches where it crosses the edge. Elements too long for the
    /// shape do that: a cubic cannot follow a bay whose radius of
    /// curvature is shorter than its elements.
    OffEdge {
        /// x (column) of the sample farthest off, pixels.
        x: f64,
        /// y (row) of that sample, pixels.
        y: f64,
        /// How far the edge lies from it, pixels.
        offset: f64,
    },
}

impl std::fmt::Display for Divergence {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        match self {
            Divergence::LeftImage { x, y } => {
                write!(f, "the curve left the image near ({x:.1}, {y:.1})")
            }
            Divergence::NoContrast => {
                f.write_str("the band sees no contrast (no edge or line within R of the curve)")
            }
            Divergence::NonFinite => f.write_str("the unknowns became NaN or infinite"),
            Divergence::Degenerate => {
                f.write_str("the curve became degenerate (an element sees no gradient)")
            }
            Divergence::SelfIntersecting { x, y } => {
                write!(f, "the curve crosses itself near ({x:.1}, {y:.1})")
            }
            Divergence::FoldedBack { x, y } => {
                write!(
                    f,
                    "the curve folded back on itself (loops) near ({x:.1}, {y:.1})"
                )
            }
            Divergence::LostEdge { x, y } => {
                write!(
                    f,
                    "the curve left the edge near ({x:.1}, {y:.1}): no edge within the band there"
                )
            }
            Divergence::OffEdge { x, y, offset } => {
                write!(
                    f,
                    "the curve does not follow the edge: it lies {offset:.1} px off it near ({x:.1}, {y:.1}), and over a pixel off along an element or more of its length (elements too long for the shape: give more, or let the default schedule choose them)"
                )
            }
        }
    }
}

/// How a fit (or one stage of it) ended.
#[derive(Clone, Copy, Debug, PartialEq, Serialize, Deserialize)]
#[serde(tag = "status", rename_all = "snake_case")]
pub enum Outcome {
    /// `max |dLambda|` fell under the tolerance.
    Converged,
    /// The iteration limit was reached first; the curve is the last iterate.
    IterationLimit,
    /// The fit failed; the curve is the last good one.
    Diverged {
        /// Why.
        #[serde(flatten)]
        divergence: Divergence,
    },
}

impl Outcome {
    /// Whether the outcome is [`Outcome::Converged`].
    pub fn is_converged(&self) -> bool {
        matches!(self, Outcome::Converged)
    }
}

impl std::fmt::Display for Outcome {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        match self {
            Outcome::Converged => f.write_str("converged"),
            Outcome::IterationLimit => f.write_str("iteration limit reached"),
            Outcome::Diverged { divergence } => write!(f, "diverged: {divergence}"),
        }
    }
}

/// The history of one stage.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub struct StageReport {
    /// Band half-width `R`, pixels.
    pub half_width: f64,
    /// The virtual image's profile (with the blur it assumed, for a pixel
    /// edge).
    pub profile: Profile,
    /// Number of elements of the displacement basis.
    pub elements: usize,
    /// Gauss–Newton iterations (all references of the stage).
    pub iterations: usize,
    /// How many times the reference was moved within the stage.
    pub rereferences: usize,
    /// Band pixels of the last reference.
    pub band_pixels: usize,
    /// 1, or `k` for a coarse stage that ran on the image binned by `k`
    /// (the means of its `k x k` blocks, see `fit::pyramid`): its band
    /// pixels, residual and iterations' residuals are then the binned
    /// image's, its iterations' steps full-resolution pixels. Absent
    /// from result files when 1.
    #[serde(default = "unbinned", skip_serializing_if = "is_unbinned")]
    pub binning: usize,
    /// RMS of the residual `g - f` at the last iteration, gray levels.
    pub residual_rms: f64,
    /// Dark level `a` of the virtual image at the end of the stage.
    pub a: f64,
    /// Contrast `c` (its sign is the polarity).
    pub c: f64,
    /// Wall-clock time of the stage, seconds.
    pub seconds: f64,
    /// How the stage ended.
    pub outcome: Outcome,
    /// Every Gauss–Newton iteration of the stage, in order (empty in
    /// result files written before it was recorded).
    #[serde(default)]
    pub history: Vec<IterationRecord>,
    /// Whether the stage rendered the whole object rather than a band
    /// profile across the curve: a small closed silhouette under a blur
    /// large against its curvature, or with other objects' light within
    /// its reach, its pixel edge rendered as the whole blurred region the
    /// curve bounds; `half_width` is then the margin of its window around
    /// the curve, `band_pixels` the window's pixels. Absent from result
    /// files when false.
    #[serde(default, skip_serializing_if = "std::ops::Not::not")]
    pub whole_object: bool,
    /// The other objects a `whole_object` stage rendered and fitted with
    /// this one (the dots of a grid around it, whose light reaches its
    /// window). Absent from result files when 0.
    #[serde(default, skip_serializing_if = "is_zero")]
    pub neighbours: usize,
    /// Band pixels at the darkest or brightest level of the image's
    /// encoding (0 or 255 in 8 bits: a saturated backlight), which the
    /// pixel-edge stage fitted as clipped, their light known only to lie
    /// beyond that level (`correlation::censor`). Absent from result files
    /// when 0.
    #[serde(default, skip_serializing_if = "is_zero")]
    pub clipped: usize,
}

/// Whether `n` is 0 (serde's test for [`StageReport::neighbours`] and
/// [`StageReport::clipped`]).
fn is_zero(n: &usize) -> bool {
    *n == 0
}

/// [`StageReport::binning`] of a stage on the image itself.
fn unbinned() -> usize {
    1
}

/// Whether a stage ran on the image itself (`binning` 1).
fn is_unbinned(binning: &usize) -> bool {
    *binning == 1
}

/// Which run of a stage an iteration belongs to.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Serialize, Deserialize)]
#[serde(rename_all = "snake_case")]
pub enum RunKind {
    /// The fit on a reference curve (the stage's first, or one after a
    /// re-reference or a settling step).
    Reference,
    /// The refit with other gray levels after the stage's test of them:
    /// the global pair (the varying levels were not significant) or
    /// varying levels of shorter elements.
    #[serde(alias = "global_levels")]
    Levels,
    /// A refit with halved elements (automatic element length).
    Refine,
    /// A refit with robust weights.
    Robust,
}

/// One Gauss–Newton iteration, for convergence diagnostics.
#[derive(Clone, Copy, Debug, PartialEq, Serialize, Deserialize)]
pub struct IterationRecord {
    /// Index of the iteration within the stage, from 0.
    pub iteration: usize,
    /// `max |dLambda|` of the step before any step limit, pixels (the
    /// quantity compared with the tolerance).
    pub max_step: f64,
    /// RMS of the residual `g - f` over the band at this iteration, gray
    /// levels.
    pub residual_rms: f64,
    /// Which run it belongs to; a refinement or reweighting run restarts
    /// from the current curve, so its first steps jump.
    pub run: RunKind,
    /// Whether it is the first iteration on a new reference curve (the
    /// reference moved just before it).
    pub new_reference: bool,
}

/// One sample of the measured curve.
#[derive(Clone, Copy, Debug, PartialEq, Serialize, Deserialize)]
pub struct Sample {
    /// Arc length from the start of the measured curve, pixels.
    pub s: f64,
    /// x (column), pixels.
    pub x: f64,
    /// y (row), pixels.
    pub y: f64,
    /// Unit normal x component (outward for closed curves).
    pub nx: f64,
    /// Unit normal y component.
    pub ny: f64,
    /// Standard deviation of the position along the normal, pixels: the
    /// noise term [`Sample::sigma_noise`] combined in quadrature with the
    /// model-misfit term where the image's edge departs from the model
    /// (see [`Sample::misfit`]); equal to `sigma_noise` elsewhere. It does
    /// not include a bias that the residuals cannot show (a model that
    /// fits the image exactly but places the edge wrongly), nor the
    /// uncertainty common to every sample ([`Measurement::sigma_shift`]):
    /// `sigma` is what differs from sample to sample, and averages down
    /// over independent samples; one sample's whole uncertainty is
    /// `sigma` and `sigma_shift` in quadrature.
    pub sigma: f64,
    /// The noise term alone: the Gauss–Newton covariance of the last
    /// stage, pixels (method, section 8); NaN without a fit.
    #[serde(default = "nan")]
    pub sigma_noise: f64,
    /// Whether the model misfits here: the band's residuals near the
    /// sample ask for a displacement beyond what the noise explains, the
    /// curve oscillates at its elements' scale, the edge bends faster
    /// than the elements can follow, a corner found near it was dropped on
    /// evidence the noise could have made, or the blur's curvature shift
    /// could not be removed (no band matched to the blur fitted in the
    /// image), by more than the noise term; `sigma` then covers that
    /// misfit.
    #[serde(default)]
    pub misfit: bool,
    /// Mean robust weight of the last stage's band pixels within about a
    /// pixel of this sample, in `[0, 1]`: 1 where nothing was down-weighted,
    /// lower where clutter crossing the band was (see the fit's robust
    /// weights); NaN without a fit.
    pub weight: f64,
}

impl Sample {
    /// Charge a model misfit of `misfit` pixels: where it exceeds the
    /// model term `sigma` already holds, `sigma` becomes the noise term
    /// and `misfit` in quadrature, and the sample is flagged where the
    /// misfit exceeds the noise term.
    pub(crate) fn cover(&mut self, misfit: f64) {
        let model = (self.sigma.powi(2) - self.sigma_noise.powi(2))
            .max(0.0)
            .sqrt();
        if misfit > model {
            self.sigma = self.sigma_noise.hypot(misfit);
            self.misfit |= misfit > self.sigma_noise;
        }
    }
}

/// Why an open curve's measurement stops short of the curve it started
/// from.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Serialize, Deserialize)]
#[serde(rename_all = "snake_case")]
pub enum TrimReason {
    /// The last stage's band would leave the image beyond this end (an
    /// edge or line that crosses the image border): the curve is measured
    /// where its band is whole.
    BandLeavesImage,
}

/// One end of an open measured curve that was trimmed (see [`Trim`]).
#[derive(Clone, Copy, Debug, PartialEq, Serialize, Deserialize)]
pub struct TrimmedEnd {
    /// x (column) of the measured curve's end, pixels.
    pub x: f64,
    /// y (row) of the measured curve's end, pixels.
    pub y: f64,
    /// Length of the curve beyond this end that was not measured (up to
    /// the start's end, or to where that curve, carried along by the fit,
    /// leaves the image), pixels.
    pub removed: f64,
    /// Reach of the band that would leave the image: the last stage's
    /// half-width `R` (plus a tracked band's margin), pixels.
    pub half_width: f64,
    /// Why.
    pub reason: TrimReason,
}

/// Where an open measured curve was trimmed, per end: `None` (`null` in
/// the result file) where it reaches the end of the curve it was measured
/// from. Closed curves are never trimmed.
#[derive(Clone, Copy, Debug, Default, PartialEq, Serialize, Deserialize)]
pub struct Trim {
    /// The end at the curve's start (arc length 0).
    pub start: Option<TrimmedEnd>,
    /// The end at the curve's end.
    pub end: Option<TrimmedEnd>,
}

impl Trim {
    /// Whether either end was trimmed.
    pub fn is_trimmed(&self) -> bool {
        self.start.is_some() || self.end.is_some()
    }
}

/// The result of [`crate::fit::measure`].
#[derive(Clone, Debug)]
pub struct Measurement {
    /// How the fit ended (that of the last stage run).
    pub outcome: Outcome,
    /// The measured curve as a B-spline (cubic or of the fit's degree if
    /// higher), fitted to the samples.
    pub curve: SplineCurve,
    /// Largest distance between the B-spline and the samples, pixels.
    pub curve_fit_error: f64,
    /// Dense samples of the measured curve, at most the configured spacing
    /// apart.
    pub samples: Vec<Sample>,
    /// Per-stage history.
    pub stages: Vec<StageReport>,
    /// Stages of the default schedule that were skipped, with the reason.
    pub skipped: Vec<String>,
    /// Where an open curve was trimmed because its band would leave the
    /// image (none for closed curves).
    pub trim: Trim,
    /// The blur of the edge estimated on the measured curve (silhouettes
    /// with blur correction on), see [`crate::psf`].
    pub edge_spread: Option<crate::psf::EdgeSpread>,
    /// Whether the samples and curve were moved by the blur's curvature
    /// shift (the edge spread was estimated and fitted well enough).
    pub blur_corrected: bool,
    /// The virtual image's gray levels along the measured curve, every
    /// 8 px or so, when they vary ([`crate::fit::LevelModel::Varying`]);
    /// empty for the global pair (see the last stage's `a` and `c`).
    pub levels: Vec<LevelSample>,
    /// Corners found on a first, smooth measurement, where the curve was
    /// measured again with breaks ([`crate::fit::FitConfig::find_corners`]):
    /// their positions on the measured curve `[x, y]`, px; empty when none
    /// was found or the smooth result was kept.
    pub corners_found: Vec<[f64; 2]>,
    /// The tone curve the gray levels were read with: [`Tone::Linear`]
    /// unless the image was taken to linear light first (an explicit
    /// [`crate::fit::FitConfig::tone`], or the estimate of
    /// [`Tone::Auto`] when it found the image clearly not linear).
    pub tone: Tone,
    /// The tone curve estimated around the measured edge on the image as
    /// given ([`Tone::Auto`], silhouettes; see [`crate::tone::estimate`]);
    /// `None` when not estimated.
    pub tone_estimate: Option<ToneEstimate>,
}

/// The virtual image's gray levels at one place of the measured curve.
#[derive(Clone, Copy, Debug, PartialEq, Serialize, Deserialize)]
pub struct LevelSample {
    /// Arc length on the measured curve (as [`Sample::s`]), pixels.
    pub s: f64,
    /// Dark level `a` (outside, or the line's ground), gray levels.
    pub a: f64,
    /// Contrast `c`: the level at `gamma = 1` is `a + c`.
    pub c: f64,
}

/// The samples where the model misfits ([`Sample::misfit`]), in brief.
#[derive(Clone, Copy, Debug, PartialEq, Serialize, Deserialize)]
pub struct MisfitSummary {
    /// Samples flagged.
    pub flagged: usize,
    /// Their fraction of all samples, in `[0, 1]` (0 without samples).
    pub fraction: f64,
    /// The largest `sigma / sigma_noise` over the samples (1 where nothing
    /// misfits; NaN without a fit).
    pub worst_inflation: f64,
}

/// The last of `stages` run on a band, before any whole-object stage
/// ([`StageReport::whole_object`]): the one a tracked frame continues
/// from (a whole-object stage is run again on each frame).
pub(crate) fn last_band_stage(stages: &[StageReport]) -> Option<&StageReport> {
    stages.iter().rev().find(|s| !s.whole_object)
}

/// NaN, the serde default of [`Sample::sigma_noise`].
fn nan() -> f64 {
    f64::NAN
}

impl Measurement {
    /// The samples where the model misfits, in brief.
    pub fn misfit_summary(&self) -> MisfitSummary {
        let flagged = self.samples.iter().filter(|s| s.misfit).count();
        let worst = self
            .samples
            .iter()
            .map(|s| s.sigma / s.sigma_noise)
            .filter(|r| r.is_finite())
            .fold(f64::NAN, f64::max);
        MisfitSummary {
            flagged,
            fraction: flagged as f64 / self.samples.len().max(1) as f64,
            worst_inflation: worst,
        }
    }

    /// Total Gauss–Newton iterations over all stages.
    pub fn iterations(&self) -> usize {
        self.stages.iter().map(|s| s.iterations).sum()
    }

    /// The standard deviation of a shift of the whole curve along its
    /// normals, common to every sample, pixels: what reading the tone
    /// curve from the edge leaves uncertain
    /// ([`ToneEstimate::position_sd`]: when the curve was measured in the
    /// linear light of that reading, and when the reading kept the image
    /// linear for want of evidence against an encoding); 0 otherwise (a
    /// linear image, or a tone curve given). Not in [`Sample::sigma`]: a term every sample
    /// shares does not average down, so a fit to the samples (a circle, a
    /// width) adds it to its own deviation, as
    /// [`crate::derived::closed_measures`] does for the radius.
    pub fn sigma_shift(&self) -> f64 {
        self.tone_estimate.map_or(0.0, |e| e.position_sd)
    }

    /// Residual RMS of the last stage, gray levels.
    pub fn residual_rms(&self) -> f64 {
        self.stages.last().map_or(f64::NAN, |s| s.residual_rms)
    }

    /// The last stage measured with the paper's profile (a line's
    /// pixel-line stage and a silhouette's pixel-edge stage come after
    /// it): the one a model with the paper's profile compares with.
    pub fn last_paper_stage(&self) -> Option<&StageReport> {
        self.stages
            .iter()
            .rev()
            .find(|s| matches!(s.profile, Profile::Paper { .. }))
    }

    /// Arc length of the measured curve, pixels.
    pub fn length(&self) -> f64 {
        self.curve.arc_length()
    }

    /// Area enclosed by a closed measured curve, square pixels.
    pub fn area(&self) -> Option<f64> {
        self.curve.area()
    }

    /// `[x, y]` of the samples.
    pub fn points(&self) -> Vec<[f64; 2]> {
        self.samples.iter().map(|s| [s.x, s.y]).collect()
    }

    /// The B-spline as serialisable data.
    pub fn curve_data(&self) -> SplineCurveData {
        self.curve.to_data()
    }
}
