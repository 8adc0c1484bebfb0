//! The schedule (method, section 6): the stages in turn, coarse to fine,
//! each stage's result the next one's reference; after the last stage,
//! the edge's blur chooses a stage to append (the pixel edge through that
//! blur for a silhouette, the pixel line through its blur and width for a
//! line), and a tracked
//! frame's band is kept for the next frame.

use super::blur::{
    bend_element, estimate_spread, matched_band, pixel_edge_band_for, shortest_element,
    shortest_pixel_edge, BAND_MISMATCH, MIN_EDGE_FIT_QUALITY,
};
use super::loops;
use super::misfit::{PLATEAU_CONTRAST, PLATEAU_NOISE, PLATEAU_SHARE};
use super::output::{plain_samples, plateau_stretch, Final, Output};
use super::polarity::line_polarity;
use super::reference::{check_open_start, next_reference, Ends, CURVE_SPACING};
use super::run::largest_change;
use super::track::{self, TrackCache, TrackState};
use super::{
    breaks, capped_stages, default_stages, Divergence, Elements, FitConfig, LevelModel,
    Measurement, Outcome, Sample, Stage, StageReport, Trim, TrimReason, TrimmedEnd,
};
use crate::curve::SplineCurve;
use crate::error::{Error, Result};
use crate::interp::Sampler;
use crate::psf;
use crate::tone::Tone;
use crate::virtual_image::pixel_edge::optical_blur;
use crate::virtual_image::{Kind, Polarity, Profile};
use std::f64::consts::TAU;

/// The optical blur (pixels) from which a closed line's pixel-line stage
/// refines its elements, as a pixel edge's does: a Gaussian blur of `b`
/// pixels leaves `exp(-2 pi^2 b^2)` of the pixel grid's aliasing of the
/// line's sides, under 1e-4 from 0.7 px. Sharper lines keep the last
/// stage's elements, as finer ones follow that aliasing; so do open lines,
/// whose ends grow an oscillation on shorter elements (docs/benchmarks.md,
/// "A closed line's elements").
const REFINED_LINE_BLUR: f64 = 0.7;
/// The narrowest band a cap ([`FitConfig::max_half_width`]) leaves a
/// pixel edge, pixels (and a pixel line beyond each side): the transition
/// of a focused edge and half a pixel of its levels.
pub(crate) const MIN_CAPPED_BAND: f64 = 1.5;

/// Run the schedule of `config` from `reference`; with `tracked`, the
/// tracking schedule instead (the pixel-edge stage alone, see
/// [`super::track`]), on the band the cache keeps when it serves, and the
/// cache updated after it.
///
/// Runs on a thread of rayon's pool (the caller's own when it is one): a
/// fit has tens of parallel loops, each a fraction of a millisecond, and
/// called from outside the pool each would hand its work over to the pool
/// and put the caller to sleep until it is done.
pub(super) fn run_schedule(
    sampler: &Sampler,
    reference: SplineCurve,
    config: &FitConfig,
    tracked: Option<(TrackState, &mut TrackCache)>,
) -> Result<Measurement> {
    rayon::scope(|_| run_schedule_here(sampler, reference, config, tracked))
}

/// [`run_schedule`] on the calling thread.
fn run_schedule_here(
    sampler: &Sampler,
    reference: SplineCurve,
    config: &FitConfig,
    tracked: Option<(TrackState, &mut TrackCache)>,
) -> Result<Measurement> {
    let (tracked, mut cache) = match tracked {
        Some((t, c)) => (Some(t), Some(c)),
        None => (None, None),
    };
    config.validate()?;
    if sampler.kind() != config.interpolation {
        return Err(Error::invalid(
            "interpolation",
            "the sampler was prepared for another interpolation than the configuration's",
        ));
    }
    let mut schedule = Schedule::new(sampler, reference, config, tracked, cache.as_deref_mut())?;
    schedule.run()?;
    schedule.finish(cache)
}

/// How a stage ended, for the schedule.
pub(super) enum Flow {
    /// It completed: its result is the schedule's last.
    Completed,
    /// It was skipped (the reason recorded): on to the next stage.
    Skipped,
    /// The schedule ends here (a failure, or an optional stage that could
    /// not run: the previous result stands).
    Stop,
    /// The probe's start is farther from the edge than its band reaches
    /// (see [`super::probe`]): the schedule runs from its first stage.
    TooFar,
}

/// The state of a fit across its stages.
pub(super) struct Schedule<'s> {
    /// The image.
    pub sampler: &'s Sampler,
    /// The configuration; its level model may become the global pair, or
    /// varying levels of shorter elements, on the way (see
    /// `Correlation::levels_needed`).
    pub config: FitConfig,
    /// The level model the configuration asked for, before the stages'
    /// tests changed it.
    pub levels_asked: LevelModel,
    /// What a tracked frame takes from the previous one.
    pub tracked: Option<TrackState>,
    /// Whether the schedule is the default (or tracking) one: stages may be
    /// skipped, settled and appended.
    pub auto: bool,
    /// The stages, with those appended after the last one.
    pub stages: Vec<Stage>,
    /// Fewest elements of a displacement basis on this curve.
    pub min_el: usize,
    /// Margin of a tracked frame's new band, pixels.
    pub track_margin: f64,
    /// The current reference curve.
    pub current: SplineCurve,
    /// When `current` is an open curve trimmed to the stretch whose band
    /// fits in the image: the whole curve it was cut from, and the parts
    /// cut off (carried to the next reference).
    pub trimmed: Option<(SplineCurve, Ends)>,
    /// The parts cut off the last completed stage's reference: where the
    /// result stops short of the curve it was measured from.
    pub final_ends: Ends,
    /// Tracking: the band the previous frame left, when it serves this one.
    pub reuse: Option<Box<track::Kept>>,
    /// Tracking: where the previous frame's curve is on the current band
    /// (its displacement).
    pub run_start: Option<Vec<f64>>,
    /// Tracking: how far the curve moved on the frame's earlier bands
    /// (pixels, the sum of their largest displacements: a bound; none when
    /// the frame measured on one band).
    pub moved_before: Option<f64>,
    /// The completed (or failed) stages' reports.
    pub reports: Vec<StageReport>,
    /// Stages skipped, with the reason.
    pub skipped: Vec<String>,
    /// The last completed stage.
    pub last: Option<Final>,
    /// How the fit ends so far.
    pub outcome: Outcome,
    /// The edge's blur, estimated after the last stage.
    pub edge_spread: Option<psf::EdgeSpread>,
    /// Whether a stage matched to the edge's blur was appended (once; a
    /// tracked schedule's one stage is that pixel-edge stage).
    pub matched_added: bool,
    /// The profile of that stage when it is a silhouette's pixel edge.
    pub pixel_edge: Option<Profile>,
    /// Whether the stage running is the probe ([`super::probe`]), which
    /// stops at its first new reference.
    pub probing: bool,
    /// Whether this schedule is a coarse stage run on a binned image
    /// ([`super::pyramid`]): its result is only the next stage's reference,
    /// and its residuals where the curve has not reached the edge yet are
    /// not clutter, so it runs no robust reweighting.
    pub coarse: bool,
    /// The image binned for coarse stages, by binning ([`super::pyramid`]),
    /// made on first use.
    pub binned: Vec<(usize, Sampler)>,
    /// Whether a binned stage completed: its result is the current curve,
    /// though `last` holds no system of it.
    pub binned_done: bool,
}

impl<'s> Schedule<'s> {
    /// The schedule of `config` (or of `tracked`) from `reference`, with the
    /// tracking cache's band when it serves.
    pub(super) fn new(
        sampler: &'s Sampler,
        reference: SplineCurve,
        config: &FitConfig,
        tracked: Option<TrackState>,
        mut cache: Option<&mut TrackCache>,
    ) -> Result<Self> {
        let mut config = config.clone();
        let closed = reference.is_closed();
        let (stages, auto) = match (&config.stages, tracked) {
            (_, Some(t)) => (vec![t.stage()], true),
            (Some(s), None) => (s.clone(), false),
            (None, None) => (
                config
                    .max_half_width
                    .map_or_else(default_stages, |cap| capped_stages(default_stages(), cap)),
                true,
            ),
        };
        let min_el = min_elements(closed, config.degree, auto);
        let mut current = breaks::prepare(reference, &config.breaks)?;
        check_open_start(&current, (sampler.width(), sampler.height()))?;
        // A line's polarity from the widest band around its start, when
        // the band says it clearly (`super::polarity`).
        let widest = stages.iter().map(|s| s.half_width).fold(0.0, f64::max);
        if tracked.is_none() && config.kind == Kind::Contour && config.polarity == Polarity::Auto {
            if let Some(p) = line_polarity(sampler, &current, widest) {
                config.polarity = p;
            }
        }
        let reuse = match (tracked, cache.as_deref_mut()) {
            (Some(t), Some(c)) => c.take_for(&t, config.levels, sampler, config.coords),
            _ => None,
        };
        let track_margin = cache
            .as_deref()
            .map_or(track::TRACK_MARGIN, TrackCache::margin);
        match (tracked, &reuse) {
            // A kept band's reference was refitted when the band was built.
            (Some(_), Some(kept)) => current = kept.reference.clone(),
            (Some(t), None) => {
                current = tracked_reference(&current, &t.stage(), &config, min_el)?;
            }
            (None, _) => {}
        }
        Ok(Schedule {
            sampler,
            tracked,
            auto,
            stages,
            min_el,
            track_margin,
            current,
            trimmed: None,
            final_ends: Ends::default(),
            reuse,
            run_start: None,
            moved_before: None,
            reports: Vec::new(),
            skipped: Vec::new(),
            last: None,
            outcome: Outcome::Converged,
            edge_spread: None,
            matched_added: tracked.is_some(),
            pixel_edge: tracked.map(|t| t.profile()),
            probing: false,
            coarse: false,
            binned: Vec::new(),
            binned_done: false,
            levels_asked: config.levels,
            config,
        })
    }

    /// Run the stages in turn, appending those the edge's blur calls for.
    pub(super) fn run(&mut self) -> Result<()> {
        let mut next = self.probe()?;
        while next < self.stages.len() {
            let k = next;
            next += 1;
            let stage = self.stages[k];
            let is_last = k + 1 == self.stages.len();
            if self.auto && !is_last && self.too_wide(&stage) {
                continue;
            }
            let flow = match self.run_binned(&stage, is_last) {
                Some(flow) => flow,
                None => {
                    // The stages narrow: the binned images are done with
                    // (a megapixel image's take a few megabytes each).
                    self.binned.clear();
                    self.run_stage(&stage, is_last)?
                }
            };
            match flow {
                Flow::Completed if is_last => self.append_matched(&stage),
                Flow::Completed | Flow::Skipped => {}
                Flow::Stop | Flow::TooFar => break,
            }
        }
        Ok(())
    }

    /// Whether a coarse stage's band is too wide for the curve (then it is
    /// skipped, the reason recorded).
    fn too_wide(&mut self, stage: &Stage) -> bool {
        let r = stage.half_width;
        if self.fits_band(r) {
            return false;
        }
        let length = self.current.arc_length();
        self.skipped.push(format!(
            "R = {r} px: too wide for a curve of length {length:.1} px"
        ));
        true
    }

    /// Whether a band of half-width `r` (pixels) suits the current curve:
    /// `r` at most half the radius of a circle of the same length (half
    /// the length of an open curve).
    pub(super) fn fits_band(&self, r: f64) -> bool {
        r <= self.band_limit()
    }

    /// The widest band half-width (pixels) that keeps the current curve's
    /// band clear of its other parts: [`Self::band_limit`], at most half
    /// the smallest radius of curvature (sampled every pixel of the
    /// parameter), and 0 for a curve with corners, where a band's plateau
    /// would take in the edge beyond the corner. An open curve's ends are
    /// trimmed where the narrow band leaves the image, the wider band's
    /// flat levels cut by the border there (`Band::new`).
    fn clear_band_limit(&self) -> f64 {
        let curve = &self.current;
        if !curve.corners().is_empty() {
            return 0.0;
        }
        self.band_limit().min(0.5 / curve.largest_curvature(1.0))
    }

    /// The widest band half-width that suits the current curve (pixels,
    /// see [`Self::fits_band`]).
    fn band_limit(&self) -> f64 {
        let length = self.current.arc_length();
        let size = if self.current.is_closed() {
            length / TAU
        } else {
            length
        };
        0.5 * size
    }

    /// The pixel edge's band for the optical `blur` (pixels) on this image,
    /// with the contrast the last stage measured ([`pixel_edge_band_for`]).
    fn pixel_edge_band(&self, blur: f64) -> f64 {
        let contrast = self.last.as_ref().and_then(|f| f.corr.levels_at(0.0));
        let band = pixel_edge_band_for(
            blur,
            self.sampler.pixel_noise(),
            contrast.map(|(_, c)| c),
            self.sampler.quantum(),
            self.clear_band_limit(),
        );
        self.capped(band)
    }

    /// `half_width` within [`FitConfig::max_half_width`] (pixels, a
    /// quarter-pixel multiple when capped), not under the narrowest band a
    /// pixel edge takes.
    fn capped(&self, half_width: f64) -> f64 {
        match self.config.max_half_width {
            Some(cap) if cap < half_width => ((cap * 4.0).floor() / 4.0).max(MIN_CAPPED_BAND),
            _ => half_width,
        }
    }

    /// The elements of the stage matched to an optical `blur` (pixels)
    /// appended after `stage`, whose elements ended `chosen` long: from
    /// those, no shorter than the blur resolves ([`shortest_element`]),
    /// refined further when `refined` and `stage` could refine
    /// (below that where the curve's curvature is within the profile's
    /// reach, [`shortest_pixel_edge`], and down to elements that follow
    /// its bends, [`bend_element`]); fixed otherwise.
    fn matched_elements(&self, stage: &Stage, chosen: f64, blur: f64, refined: bool) -> Elements {
        let floor = shortest_element(blur);
        // Down to elements that follow the curve's bends, where the
        // profile does (`bend_element`), if the refinement's rule finds
        // the image holds them.
        let bends = bend_element(&self.current, blur).unwrap_or(f64::INFINITY);
        match stage.elements {
            Elements::Auto { shortest, .. } if refined => Elements::Auto {
                longest: chosen.max(floor),
                shortest: shortest_pixel_edge(&self.current, blur, shortest).min(bends),
            },
            _ => Elements::Length(chosen.max(floor)),
        }
    }

    /// After the last stage: estimate the edge's blur on the measured
    /// curve and, with the default schedule, measure once more with a
    /// profile matched to it: for a silhouette the pixel edge through that
    /// blur (exact, see `Profile::PixelEdge`); for a line the pixel line
    /// through its blur and width (`Profile::PixelLine`). Neither when the
    /// spread's fit is poor (not a blurred step or bar).
    fn append_matched(&mut self, stage: &Stage) {
        if !self.config.blur_correction || self.tracked.is_some() {
            return;
        }
        // After the pixel-edge stage (which fits the blur itself) the
        // spread is not used again: keep the one it was chosen from.
        if self.pixel_edge.is_some() {
            return;
        }
        self.edge_spread = estimate_spread(self.sampler, &self.current, self.config.kind);
        let chosen = self.last.as_ref().map(|f| f.corr.basis().element_length());
        if let (Some(e), Some(chosen), true, false) =
            (self.edge_spread, chosen, self.auto, self.matched_added)
        {
            let good = e.fit_quality >= MIN_EDGE_FIT_QUALITY;
            if good && self.config.kind == Kind::Silhouette {
                // Starting from the elements the last stage chose, no
                // shorter than the blur resolves (`shortest_element`), and
                // refining further when that stage could (its sine profile
                // may have stopped on aliasing, which the pixel edge does
                // not have), below that where the curve's curvature is
                // within the profile's reach (`shortest_pixel_edge`).
                let blur = optical_blur(e.sigma);
                let elements = self.matched_elements(stage, chosen, blur, true);
                self.min_el = self.min_el.min(resolved_min_elements(
                    &self.current,
                    self.config.degree,
                    blur,
                ));
                self.matched_added = true;
                self.pixel_edge = Some(Profile::pixel_edge(blur));
                self.stages.push(Stage {
                    half_width: self.pixel_edge_band(blur),
                    elements,
                });
            } else if let (true, Some(width)) = (good, e.line_width) {
                // A line: the pixel line through its blur and width, its
                // band the pixel edge's beyond each side. A closed line
                // blurred by `REFINED_LINE_BLUR` at least chooses its
                // elements as a pixel edge does (the last stage's sine
                // profile stops on a blurred line's profile mismatch as it
                // does on an edge's); others keep the last stage's, no
                // shorter than the blur resolves.
                let blur = optical_blur(e.sigma);
                let refined = blur >= REFINED_LINE_BLUR && self.current.is_closed();
                let elements = self.matched_elements(stage, chosen, blur, refined);
                self.matched_added = true;
                self.pixel_edge = Some(Profile::PixelLine { blur, width });
                let half_width = 0.5 * width + self.pixel_edge_band(blur);
                let half_width = self.capped((half_width * 4.0).ceil() / 4.0);
                self.stages.push(Stage {
                    half_width: half_width.max(0.5 * width + MIN_CAPPED_BAND),
                    elements,
                });
            }
        }
        // A silhouette's last stage left its settling to a pixel-edge stage
        // that is not coming (no edge spread: an edge within a few pixels of
        // the image border; or an edge that is not a blurred step: texture,
        // clutter). Run it once more, this time settling (its profile stays
        // the sine, as `pixel_edge` is unset), so that detail finer than the
        // elements, such as a traced start's staircase, does not stay in
        // the result.
        if let (Some(chosen), true, false, Kind::Silhouette) =
            (chosen, self.auto, self.matched_added, self.config.kind)
        {
            self.matched_added = true;
            self.stages.push(Stage {
                half_width: stage.half_width,
                elements: Elements::Length(chosen),
            });
        }
    }

    /// The measurement: the last completed stage's curve and samples (the
    /// start's when no stage completed), and the tracking cache updated.
    fn finish(mut self, cache: Option<&mut TrackCache>) -> Result<Measurement> {
        let Some(fin) = self.last.take() else {
            // Not even one stage completed: report the start as the result.
            return Ok(Measurement {
                edge_spread: None,
                blur_corrected: false,
                outcome: self.outcome,
                curve_fit_error: 0.0,
                samples: plain_samples(&self.current, self.config.sample_spacing),
                curve: self.current,
                stages: self.reports,
                skipped: self.skipped,
                trim: Trim::default(),
                levels: Vec::new(),
                corners_found: Vec::new(),
                tone: Tone::Linear,
                tone_estimate: None,
            });
        };
        let ends = [0.0, fin.reference.param_length()].map(|u| fin.reference.point(u));
        // The blur's curvature shift: removed when the edge (or line) looks
        // like a blurred step (or bar) and the last band is not much
        // narrower than it (a narrow band sees only the middle of a wide
        // edge, and stays between the half-level and the boundary). A
        // pixel-edge profile models the shift already.
        let pixel_edge_result = fin.profile.is_pushed();
        let blurred = self
            .edge_spread
            .filter(|_| !pixel_edge_result)
            .filter(|e| e.fit_quality >= MIN_EDGE_FIT_QUALITY);
        let blur = blurred
            .filter(|e| matched_band(e) <= BAND_MISMATCH * fin.half_width)
            .map(|e| e.sigma);
        // A blurred edge whose shift the band could not remove (the stage
        // matched to its blur skipped, say near the border): `sigma`
        // covers the shift.
        let left = blurred.filter(|_| blur.is_none()).map(|e| e.sigma);
        let Output {
            curve,
            fit_error,
            samples,
            levels,
            lost_edge,
        } = fin.samples(
            self.sampler,
            self.config.sample_spacing,
            self.config.degree.max(3),
            (blur, left),
        )?;
        self.check_loops(&samples, curve.is_closed());
        self.check_edge(lost_edge);
        let span = fin.corr.basis().element_length();
        self.check_plateau(&samples, (fin.half_width, span), curve.is_closed());
        self.check_contrast();
        if let Some(cache) = cache {
            self.keep_band(fin, cache);
        }
        let trim = trim_report(&self.final_ends, ends, &samples);
        Ok(Measurement {
            outcome: self.outcome,
            curve,
            curve_fit_error: fit_error,
            samples,
            stages: self.reports,
            skipped: self.skipped,
            trim,
            edge_spread: self.edge_spread,
            blur_corrected: blur.is_some() || pixel_edge_result,
            levels,
            corners_found: Vec::new(),
            tone: Tone::Linear,
            tone_estimate: None,
        })
    }

    /// The output samples crossing themselves or looping (see [`loops`])
    /// make a fit that has not failed yet a divergence, its last stage's
    /// report included.
    fn check_loops(&mut self, samples: &[super::Sample], closed: bool) {
        if matches!(self.outcome, Outcome::Diverged { .. }) {
            return;
        }
        let points: Vec<[f64; 2]> = samples.iter().map(|s| [s.x, s.y]).collect();
        if let Some(divergence) = loops::looped(&points, closed) {
            self.diverge_result(divergence);
        }
    }

    /// The result diverged by `divergence`, its last stage's report too.
    fn diverge_result(&mut self, divergence: Divergence) {
        self.outcome = Outcome::Diverged { divergence };
        if let Some(last) = self.reports.last_mut() {
            last.outcome = self.outcome;
        }
    }

    /// A converged result that left the edge along a stretch of an element
    /// or more (`lost`: [`Divergence::LostEdge`], see
    /// `output::lost_stretch`), or lies over a pixel off it along an
    /// element or more in all (`lost`: [`Divergence::OffEdge`], see
    /// `output::off_edge`), is diverged: neither the curve nor its `sigma`
    /// says where the edge is there. Only a converged one: the check reads the half
    /// level of the fitted gray levels, which a fit stopped early (a single
    /// iteration from 10 px off) may not have yet; an iteration limit has
    /// [`Self::check_plateau`].
    fn check_edge(&mut self, lost: Option<Divergence>) {
        if self.outcome != Outcome::Converged {
            return;
        }
        if let Some(divergence) = lost {
            self.diverge_result(divergence);
        }
    }

    /// An iteration-limit result with a stretch an element long or more,
    /// or stretches making up `PLATEAU_SHARE` of it, where the band sees a
    /// plateau ([`plateau_stretch`]: its image varies by less than
    /// `PLATEAU_NOISE` noise deviations and than `PLATEAU_CONTRAST` of the
    /// edge's contrast) is diverged: the curve is off the edge there, and
    /// stopping early does not make that a result to warn about. Long
    /// elements leave the lobes they cannot reach in stretches shorter
    /// than an element, between which the curve crosses the edge: hence
    /// the share. A converged result has the level-crossing test instead
    /// ([`Self::check_edge`]); an iteration limit may come before the
    /// levels are fitted, whose missing contrast is no sign of a plateau.
    /// `(half_width, span)`: the last band's half-width and element
    /// length, pixels.
    fn check_plateau(&mut self, samples: &[Sample], (half_width, span): (f64, f64), closed: bool) {
        if self.outcome != Outcome::IterationLimit {
            return;
        }
        let noise = self
            .sampler
            .pixel_noise()
            .max(self.sampler.rounding_variance().sqrt());
        let contrast = self.reports.last().map_or(0.0, |r| r.c.abs());
        let threshold = (PLATEAU_NOISE * noise).max(PLATEAU_CONTRAST * contrast);
        let stretch = plateau_stretch(
            samples,
            self.sampler,
            (half_width, threshold),
            closed,
            (span, PLATEAU_SHARE),
        );
        if let Some([x, y]) = stretch {
            self.diverge_result(Divergence::LostEdge { x, y });
        }
    }

    /// A result whose contrast is a small fraction of the image's gray-level
    /// range ([`MIN_CONTRAST_FRACTION`]) measured no edge: the curve
    /// wandered on a plateau (a start that never came within a band of the
    /// edge), chasing noise; a divergence, not a result. Not for tracked
    /// frames, which start from a measured curve.
    fn check_contrast(&mut self) {
        if matches!(self.outcome, Outcome::Diverged { .. }) || self.tracked.is_some() {
            return;
        }
        let Some(c) = self.reports.last().map(|r| r.c.abs()) else {
            return;
        };
        if c < MIN_CONTRAST_FRACTION * gray_range(self.sampler) {
            self.diverge_result(Divergence::NoContrast);
        }
    }

    /// Tracking: the frame's last band, kept for the next frame (see
    /// `TrackCache`), with how far the curve moved; not after a robust
    /// reweighting (the weights would carry over).
    fn keep_band(&self, fin: Final, cache: &mut TrackCache) {
        let motion = self.run_start.as_deref().map(|start| {
            self.moved_before.unwrap_or(0.0) + largest_change(&fin.lambda, Some(start))
        });
        // How the curve moved on its one band, if it did on one.
        let velocity = match (&self.run_start, self.moved_before) {
            (Some(start), None) => Some(fin.lambda.iter().zip(start).map(|(l, s)| l - s).collect()),
            _ => None,
        };
        let keep = self.outcome == Outcome::Converged
            && motion.is_some()
            && fin.corr.band().margin() > 0.0
            && !fin.corr.reweighted();
        let kept = keep.then(|| {
            Box::new(track::Kept {
                reference: fin.reference,
                corr: fin.corr,
                lambda: fin.lambda,
                velocity,
                levels: self.config.levels,
                size: (self.sampler.width(), self.sampler.height()),
            })
        });
        cache.update(kept, motion);
    }
}

/// Where the measured `samples` stop short of the curve they were measured
/// from: at the ends where the last stage's reference was trimmed
/// (`ends`, the parts cut off; `joints`, the reference's end points).
fn trim_report(ends: &Ends, joints: [[f64; 2]; 2], samples: &[Sample]) -> Trim {
    let end = |start: bool, sample: Option<&Sample>| {
        let removed = ends.length(start, joints[usize::from(!start)]);
        match sample {
            Some(s) if removed > 0.0 => Some(TrimmedEnd {
                x: s.x,
                y: s.y,
                removed,
                half_width: ends.reach,
                reason: TrimReason::BandLeavesImage,
            }),
            _ => None,
        }
    };
    Trim {
        start: end(true, samples.first()),
        end: end(false, samples.last()),
    }
}

/// A tracked frame's reference: the previous frame's curve refitted with
/// control points one element of the tracking stage apart, as a settle's
/// would be (a tracked frame's run does not settle, see
/// `track::TRACK_MARGIN`). The displacement cannot remove detail finer
/// than its elements, which would otherwise stay in the result and pile up
/// from frame to frame.
fn tracked_reference(
    previous: &SplineCurve,
    stage: &Stage,
    config: &FitConfig,
    min_el: usize,
) -> Result<SplineCurve> {
    let n = stage.element_count(previous.param_length(), min_el);
    let basis = breaks::displacement_basis(previous, config.degree, n)?;
    let spacing = basis.element_length().max(CURVE_SPACING);
    let zero = vec![0.0; basis.n_functions()];
    next_reference(previous, &basis, &zero, spacing, &Ends::default(), (0, 0))
}

/// The contrast a measured edge or line must reach at least, as a fraction
/// of the image's gray-level range ([`gray_range`]). A wandering curve's
/// fitted contrast is that of the noise it chased: under 1 % of the range
/// at 1 % noise; a faint but real edge stands well above 2 %.
const MIN_CONTRAST_FRACTION: f64 = 0.02;

/// Least elements of a closed curve's displacement when the schedule
/// chooses them: a square's four corners and sides, an ellipse's two
/// axes. With the default lengths (40 px) a closed curve under 160 px got
/// the degree's minimum of 4, a shape as round as a circle, which never
/// reaches a small square's corners.
pub(super) const MIN_CLOSED_ELEMENTS: usize = 8;

/// The least element count of a curve: for a closed one the degree's
/// minimum (`degree + 1`), and [`MIN_CLOSED_ELEMENTS`] when the schedule
/// chooses the lengths (`automatic`: the default schedule, or an `auto`
/// stage; element counts the user gave are kept).
pub(super) fn min_elements(closed: bool, degree: usize, automatic: bool) -> usize {
    match (closed, automatic) {
        (false, _) => 1,
        (true, false) => degree + 1,
        (true, true) => (degree + 1).max(MIN_CLOSED_ELEMENTS),
    }
}

/// Least elements of a closed curve whose pixel-edge stage chooses them
/// when [`MIN_CLOSED_ELEMENTS`] would be shorter than the blur resolves: an
/// ellipse's (the displacement's Fourier modes 0 to 2: size, position, the
/// two axes).
const MIN_RESOLVED_CLOSED_ELEMENTS: usize = 5;

/// The least element count of the pixel-edge stage under an optical blur
/// of `blur` pixels on the closed curve `reference`, of degree `degree`:
/// [`MIN_CLOSED_ELEMENTS`], unless elements that many to the curve would
/// be shorter than the blur resolves ([`shortest_element`]); then as many
/// as it resolves, at least [`MIN_RESOLVED_CLOSED_ELEMENTS`] and the
/// degree's minimum. Why: on a dot a few blurs across (a disc of radius 3
/// px under a 2.5 px blur), eight elements 2.4 px long follow the noise in
/// waves the blur hides, and the curvature they give the profile moves
/// the edge by tenths of a pixel. Open curves: 1.
fn resolved_min_elements(reference: &SplineCurve, degree: usize, blur: f64) -> usize {
    if !reference.is_closed() {
        return 1;
    }
    let resolved = (reference.arc_length() / shortest_element(blur)).floor() as usize;
    resolved
        .clamp(MIN_RESOLVED_CLOSED_ELEMENTS, MIN_CLOSED_ELEMENTS)
        .max(degree + 1)
}

/// The image's gray-level range ([`Sampler::gray_range`], computed once
/// per image).
fn gray_range(sampler: &Sampler) -> f64 {
    sampler.gray_range()
}
