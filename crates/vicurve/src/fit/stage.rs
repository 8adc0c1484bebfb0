//! One stage of the schedule: runs of Gauss–Newton on a band of one
//! half-width, each on a new reference, until the stage's result stands.
//!
//! A stage is a small state machine. Each run builds its band and system
//! (or takes the tracking cache's), then iterates ([`super::run`]). A run
//! that moves too far re-references. One that converges goes through
//! the checks made once per stage (varying levels significant? elements
//! refined, [`super::refine`]; clutter, [`super::robust`]), refits the
//! pixel edge's blur ([`super::blur`]), and settles: the last stage of the
//! default schedule re-references on its own result (with a pushed
//! profile, on the fixed point extrapolated from it, `fit/settle.rs`)
//! until the displacement vanishes, so that the result is a fixed point
//! whatever the start. Then
//! the stage is done, and its result the next stage's reference.

use super::anisotropy::{fit_anisotropy, MAX_ANISOTROPY_FITS};
use super::blur::{
    blur_change_matters, fit_blur_and_offset, sharpest_bend, BLUR_TOLERANCE, MAX_BLUR_UPDATES,
    MAX_CENSORED_BLUR_UPDATES,
};
use super::blur_offset::{few_blurs_across, Coupling};
use super::loops;
use super::output::Final;
use super::reference::{
    next_reference, reference_spacing, trim_to_band, Clip, Ends, CURVE_SPACING, TRIM_MARGIN,
};
use super::refine::{refine, Fitted, LocalShapeError, RefineBand};
use super::robust::{robust_refit, RobustFit};
use super::run::{iterate_to_end, largest_change, Run, RunLimits, RunLog};
use super::schedule::{Flow, Schedule};
use super::settle;
use super::track;
use super::{
    breaks, Divergence, Elements, IterationRecord, LevelModel, Outcome, RunKind, Stage, StageReport,
};
use crate::band::Band;
use crate::correlation::{Correlation, MeasuredTilt, Step};
use crate::curve::SplineCurve;
use crate::error::{Error, Result};
use crate::spline::Basis;
use crate::virtual_image::{Kind, Profile};
use std::time::Instant;

/// Re-references allowed within one stage before it is declared stuck.
const MAX_REREFERENCES: usize = 100;
/// Re-references in a row that did not lower the stage's residual by
/// [`STALL_GAIN`] (relative) below the lowest of its earlier ones, after
/// which a stage that chooses its elements re-references no more: it
/// cycles between references without approaching the edge (see
/// [`StageState::lowest_residual`]).
const MAX_STALLED: usize = 8;
/// See [`MAX_STALLED`].
const STALL_GAIN: f64 = 0.01;
/// The last stage of the default schedule re-references until its
/// displacement is under this, pixels (see [`StageState::settles`]). A
/// settle of a pushed profile re-references on the settles' fixed point
/// (`fit/settle.rs`), which the next settle's displacement measures the
/// distance to. On noiseless blurred curves a looser tolerance leaves a
/// part of that distance in the result that the sweep measures; on noisy
/// ones the settles mostly stop first, when they no longer contract
/// (docs/benchmarks.md gives the measurements).
const SETTLE_TOLERANCE: f64 = 0.002;
/// A settle whose displacement is not under this fraction of the previous
/// run's (with the same profile) does not contract: noise, not shape,
/// drives it, and the stage stops. Only for displacements under
/// `SETTLE_NOISE_CHECK` times `SETTLE_TOLERANCE`: larger ones are a shape
/// the elements cannot follow (a corner without a break), which settles
/// to `MAX_SETTLES`.
const SETTLE_CONTRACTION: f64 = 0.5;
/// See [`SETTLE_CONTRACTION`].
const SETTLE_NOISE_CHECK: f64 = 5.0;
/// Settling re-references of the last stage, at most.
const MAX_SETTLES: usize = 4;
/// A run of the last stage that a settle is sure to follow (its first)
/// stops after a step under this (pixels) instead of
/// [`super::FitConfig::tolerance`]: it only places the settle's reference,
/// and the settle's result moves by a few percent of the reference's error.
const PRE_SETTLE_TOLERANCE: f64 = 0.02;
/// Extra distance from the border of a trimmed band whose profile is
/// pulled (the image sampled at the pixels displaced by `U`), pixels: a
/// fine stage's `U` stays under it, so its displaced pixels stay in the
/// image; a coarse stage's may not (a pixel displaced out of the image
/// counts as fitting exactly, as long as few do), but a coarse stage only
/// brings the curve near the edge. Its trimmed ends are then within
/// `R + PULLED_MARGIN + TRIM_MARGIN` of the border.
const PULLED_MARGIN: f64 = 1.0;
/// A stage whose runs with varying levels lose the edge this many times
/// keeps the global pair of levels for its remaining runs (see
/// [`StageState::far`]): where the band of a coarse stage cannot reach the
/// edge from the global pair's converged curve (a lobe beyond the curve
/// the stage's elements can follow), varying levels lose it again from
/// every such curve, and the stage would alternate between the two until
/// its budget is spent. The next, narrower stage tries them again.
const MAX_LOST_RUNS: usize = 2;
/// The shortest levels' elements `Correlation::levels_needed` tries, a
/// fraction of the length asked: levels this short are not tested again
/// (`Schedule::levels_retest`).
const SHORTEST_LEVELS: f64 = 0.25;
/// Iteration records reserved per stage at most (see
/// [`StageReport::history`]): the loop pushes without allocating up to here.
const HISTORY_RESERVE: usize = 1024;

/// What one stage knows across its runs.
pub(super) struct StageState {
    /// The stage.
    stage: Stage,
    /// Whether it is the schedule's last (so far).
    is_last: bool,
    /// Whether it is the stage appended after the last one.
    appended: bool,
    /// Whether a pixel-edge stage will follow it (a silhouette's stage
    /// then leaves the settling to that one).
    followed: bool,
    /// When the stage started.
    started: Instant,
    /// Iterations so far.
    iterations: usize,
    /// New references so far.
    rereferences: usize,
    /// The lowest residual RMS (gray levels) a run ended with before a new
    /// reference, and the re-references since that have not lowered it
    /// by [`STALL_GAIN`]: elements too long for a fine shape under a narrow
    /// band (a star's bays of 10 px radius on 40 px elements at R = 2)
    /// alternate between two references 8 px apart, the residual rising,
    /// until [`MAX_REREFERENCES`] (200 iterations, most of the fit's
    /// time); after [`MAX_STALLED`] the run converges on its reference and
    /// the refinement of the elements follows, as after that limit.
    lowest_residual: f64,
    /// See [`StageState::lowest_residual`].
    stalled: usize,
    /// The last successful step.
    step: Option<Step>,
    /// Runs with a refitted blur so far.
    blur_updates: usize,
    /// Tracking: once a refit of the blur confirms the one in use, the
    /// stage's settling runs do not refit it again.
    blur_confirmed: bool,
    /// Fits of the blur's anisotropy so far.
    anisotropy_fits: usize,
    /// What the blur's uncertainty adds to the curve's, from its last
    /// refit where the blur and the curve's offset trade off.
    coupling: Option<Coupling>,
    /// Once the last stage has chosen its elements, re-runs keep them.
    fixed_elements: Option<usize>,
    /// The shape error of those elements, when the refinement measured one
    /// (`refine::kept_shape_error`), pixels RMS.
    shape_error: Option<f64>,
    /// Where along the curve that error lies (`refine::LocalShapeError`).
    local_shape: Option<LocalShapeError>,
    /// Settling re-references so far.
    settles: usize,
    /// Decided once per stage, on its first converged run (the runs after
    /// it re-reference the same image a fraction of a pixel away): whether
    /// varying levels are significant...
    levels_tested: bool,
    /// ...whether the band holds clutter (`None`: not yet probed)...
    cluttered: Option<bool>,
    /// ...and the image noise (variance, gray levels squared).
    stage_noise: Option<f64>,
    /// The light's tilt, measured on the stage's first reference.
    tilt: Option<MeasuredTilt>,
    /// The largest displacement of the run before this one, pixels.
    previous_move: f64,
    /// Whether the band lost the edge: a step of a run with varying levels
    /// was longer than the band's half-width, which happens where the band
    /// sees no edge (see [`Schedule::limits`]). The runs then fit the
    /// global pair of levels, re-referencing, until one converges.
    far: bool,
    /// Runs of the stage that lost the edge so far: from the
    /// [`MAX_LOST_RUNS`]th on, the stage keeps the global pair.
    lost_runs: usize,
    /// The stage's iterations.
    history: Vec<IterationRecord>,
}

impl StageState {
    /// The report of the stage, ending with `outcome`, on `basis` and a
    /// band of `band_pixels`; its history is moved into it.
    fn report(
        &mut self,
        profile: Profile,
        basis: &Basis,
        band_pixels: usize,
        outcome: Outcome,
    ) -> StageReport {
        StageReport {
            half_width: self.stage.half_width,
            profile,
            elements: basis.n_elements(),
            iterations: self.iterations,
            rereferences: self.rereferences,
            band_pixels,
            binning: 1,
            residual_rms: self.step.map_or(f64::NAN, |s| s.residual_rms),
            a: self.step.map_or(f64::NAN, |s| s.a),
            c: self.step.map_or(f64::NAN, |s| s.c),
            seconds: self.started.elapsed().as_secs_f64(),
            outcome,
            history: std::mem::take(&mut self.history),
            whole_object: false,
            neighbours: 0,
            clipped: 0,
        }
    }
}

/// A value, or how the stage ends instead.
type OrFlow<T> = std::result::Result<T, Flow>;

/// A run's system as it was built or taken from the tracking cache.
struct Acquired {
    corr: Correlation,
    /// The displacement basis the run starts with.
    basis: Basis,
    /// Pixels of its band.
    band_pixels: usize,
    /// A kept band's displacement and change.
    kept: Option<KeptStart>,
}

/// A run's system and coefficients after the stage's checks.
struct Checked {
    corr: Correlation,
    lambda: Vec<f64>,
}

/// A kept band's displacement and its change over the last frame (see
/// `TrackCache`).
type KeptStart = (Vec<f64>, Option<Vec<f64>>);

/// After one run: another, or the stage's end.
enum Next {
    /// Another run, on the new reference.
    Again,
    /// The stage ends.
    Exit(Flow),
}

/// One run's system and what it was made of.
struct RunSystem {
    /// The system.
    corr: Correlation,
    /// The displacement basis the run started with.
    basis: Basis,
    /// Its virtual profile.
    profile: Profile,
    /// The pushed (pixel-edge) profile, when the run has one.
    pushed: Option<Profile>,
    /// Pixels of its band.
    band_pixels: usize,
    /// Its convergence tolerance, pixels.
    tolerance: f64,
    /// Whether its band has a margin (a tracked band: no settle).
    windowed: bool,
}

impl Schedule<'_> {
    /// Run `stage` (`is_last`: the schedule's last so far) until it
    /// completes, is skipped or fails.
    pub(super) fn run_stage(&mut self, stage: &Stage, is_last: bool) -> Result<Flow> {
        let config = &self.config;
        let mut st = StageState {
            stage: *stage,
            is_last,
            appended: self.matched_added && is_last,
            followed: config.kind == Kind::Silhouette
                && config.blur_correction
                && !self.matched_added,
            started: Instant::now(),
            iterations: 0,
            rereferences: 0,
            lowest_residual: f64::INFINITY,
            stalled: 0,
            step: None,
            blur_updates: 0,
            blur_confirmed: false,
            anisotropy_fits: 0,
            coupling: None,
            fixed_elements: None,
            shape_error: None,
            local_shape: None,
            settles: 0,
            levels_tested: false,
            cluttered: None,
            stage_noise: None,
            tilt: None,
            previous_move: f64::INFINITY,
            far: false,
            lost_runs: 0,
            history: Vec::with_capacity(config.max_iterations.min(HISTORY_RESERVE)),
        };
        loop {
            if let Next::Exit(flow) = self.one_run(&mut st)? {
                return Ok(flow);
            }
        }
    }

    /// One run of the stage: its system, its iterations, and what follows.
    fn one_run(&mut self, st: &mut StageState) -> Result<Next> {
        let r = st.stage.half_width;
        // The pushed pixel-edge profile is only ever the appended stage's.
        let pushed = if st.appended { self.pixel_edge } else { None };
        let profile = pushed.unwrap_or(Profile::Paper {
            kind: self.config.kind,
        });
        let Acquired {
            mut corr,
            basis,
            band_pixels,
            kept,
        } = match self.run_system(st, profile, pushed)? {
            Ok(system) => system,
            Err(flow) => return Ok(Next::Exit(flow)),
        };
        let mut lambda = self.start_run(st, &mut corr, kept);
        let (limits, windowed) = self.limits(st, &corr);
        let before = st.history.len();
        let (end, used) = iterate_to_end(
            &mut corr,
            &mut lambda,
            self.sampler,
            &self.config,
            limits,
            &mut st.step,
            RunLog {
                history: &mut st.history,
                kind: RunKind::Reference,
            },
        );
        st.iterations += used;
        // Tracking: a step beyond the band's half-width means that the band
        // does not see the edge (the start is too far from it, or the
        // iteration went astray); the frame is for the full schedule, whose
        // wide bands do, rather than for a chase that ends wherever the
        // steps happen to land.
        let lost = self.tracked.is_some() && st.history[before..].iter().any(|h| h.max_step > r);
        let end = if lost {
            Run::Failed(Divergence::NoContrast)
        } else {
            end
        };
        let system = RunSystem {
            corr,
            basis,
            profile,
            pushed,
            band_pixels,
            tolerance: limits.tolerance,
            windowed,
        };
        self.after_run(st, end, system, lambda)
    }

    /// The system of a run: the kept band's for a tracked frame's first
    /// run when the cache serves (with the displacement it keeps and its
    /// last change), else a band and system built on the current
    /// reference; or how the stage ends when none can be built.
    fn run_system(
        &mut self,
        st: &mut StageState,
        profile: Profile,
        pushed: Option<Profile>,
    ) -> Result<OrFlow<Acquired>> {
        // A kept band serves the frame's first run.
        let reused = match (st.iterations, st.rereferences) {
            (0, 0) => self.reuse.take(),
            _ => None,
        };
        if let Some(kept) = reused {
            let track::Kept {
                mut corr,
                lambda,
                velocity,
                ..
            } = *kept;
            let basis = corr.basis().clone();
            corr.reload(self.sampler)?;
            let pixels = corr.band().len();
            return Ok(Ok(Acquired {
                corr,
                basis,
                band_pixels: pixels,
                kept: Some((lambda, velocity)),
            }));
        }
        // An open curve measures the stretch whose band fits in the image.
        let trimmed = self.trim_reference(st.stage.half_width, pushed);
        // Elements counted on the curve's length: a reference fitted to a
        // traced start's samples has a parameter longer than the curve by
        // the staircase it smoothed away.
        let length = self.current.arc_length();
        let n_elements = st
            .fixed_elements
            .unwrap_or_else(|| st.stage.element_count(length, self.min_el));
        let basis = breaks::displacement_basis(&self.current, self.config.degree, n_elements)?;
        if let Err(e) = trimmed {
            let first_band = self.first_band(st);
            return self
                .band_outside(st, e, (profile, &basis), first_band)
                .map(Err);
        }
        Ok(self
            .build_system(st, &basis, profile, pushed)?
            .map(|(corr, band_pixels)| Acquired {
                corr,
                basis,
                band_pixels,
                kept: None,
            }))
    }

    /// Where a run on `corr` stops, and whether its band is windowed (a
    /// tracked band, which needs no settle: see `track::TRACK_MARGIN`).
    fn limits(&self, st: &StageState, corr: &Correlation) -> (RunLimits, bool) {
        let r = st.stage.half_width;
        let windowed = corr.band().margin() > 0.0;
        // A run that a settle is sure to follow only places its reference.
        let pre_settle = self.auto && st.is_last && !st.followed && st.settles == 0 && !windowed;
        let tolerance = if pre_settle {
            self.config.tolerance.max(PRE_SETTLE_TOLERANCE)
        } else {
            self.config.tolerance
        };
        // A stage that chooses its elements stops cycling: its refinement
        // follows. A coarse stage's walk towards a far edge keeps going
        // (its residual rises and falls as the band finds the edge).
        let stalled =
            st.stalled >= MAX_STALLED && matches!(st.stage.elements, Elements::Auto { .. });
        // A windowed band serves displacements within its margin.
        let rereference = if st.rereferences >= MAX_REREFERENCES || stalled {
            f64::INFINITY
        } else if windowed {
            corr.band().margin()
        } else {
            self.config.rereference_fraction * r
        };
        // Where the band sees no edge (the start is farther than `R` from
        // it there), the varying levels' contrast there is noise, and so is
        // the displacement they give: steps of hundreds of pixels in either
        // direction. Capped, they steer the whole curve by them (the cap
        // scales the step), and the curve walks at random and loops
        // (issue 18). Such a step is not applied: the runs fit the global
        // pair instead, the edge's levels where the band sees it, which
        // moves the rest of the curve towards the edge ([`StageState::far`]).
        // Open curves too: a straight start across a wavy line sees it only
        // in places, and the varying contrast elsewhere changes sign and
        // pushes the curve away from the line. The step is the curve's
        // (`run::step_on_curve`), not the coefficients': an open curve's
        // end coefficients take long raw steps at a trimmed end while the
        // curve hardly moves there.
        let lost = if self.tracked.is_none() && !st.far && corr.varying_levels() {
            r
        } else {
            f64::INFINITY
        };
        let limits = RunLimits {
            // At least one iteration: a run on a new reference with the
            // stage's budget spent must still fit its gray levels, or the
            // result (its outcome the iteration limit) has no `sigma`; past
            // the budget, `after_run` ends the stage after that run.
            budget: self
                .config
                .max_iterations
                .saturating_sub(st.iterations)
                .max(1),
            tolerance,
            rereference,
            half_width: r,
            lost,
        };
        (limits, windowed)
    }

    /// What follows a run that ended as `end`: a new reference, the
    /// stage's failure, or the converged run's checks ([`Self::end_run`]).
    fn after_run(
        &mut self,
        st: &mut StageState,
        end: Run,
        system: RunSystem,
        lambda: Vec<f64>,
    ) -> Result<Next> {
        let r = st.stage.half_width;
        if self.probing && matches!(end, Run::Rereference | Run::Lost) {
            return Ok(Next::Exit(Flow::TooFar));
        }
        match end {
            // Past the budget (its runs get one iteration each, see
            // `limits`), a run that asks for a new reference or lost the edge
            // ends the stage on its own fit, which has its levels and sigma.
            Run::Rereference | Run::Lost if st.iterations > self.config.max_iterations => {
                self.end_run(st, Outcome::IterationLimit, system, lambda)
            }
            Run::Rereference => self.rereference(st, &system, &lambda),
            Run::Lost => {
                st.far = true;
                st.lost_runs += 1;
                Ok(Next::Again)
            }
            // The edge found everywhere: on from there with the levels of
            // the configuration, unless they lost it again from where the
            // global pair had found it.
            Run::Converged if st.far && st.lost_runs < MAX_LOST_RUNS => {
                st.far = false;
                self.rereference(st, &system, &lambda)
            }
            Run::Failed(divergence) if st.appended => {
                self.skipped
                    .push(format!("R = {r} px (matched to the blur): {divergence}"));
                Ok(Next::Exit(Flow::Stop))
            }
            Run::Failed(divergence) => {
                let RunSystem {
                    corr,
                    profile,
                    band_pixels,
                    ..
                } = system;
                self.fail(st, divergence, (profile, corr.basis(), band_pixels));
                Ok(Next::Exit(Flow::Stop))
            }
            Run::Converged => self.end_run(st, Outcome::Converged, system, lambda),
            Run::IterationLimit => self.end_run(st, Outcome::IterationLimit, system, lambda),
        }
    }

    /// The band and system of a new run on the current reference, or how
    /// the stage ends when it cannot be built.
    fn build_system(
        &mut self,
        st: &mut StageState,
        basis: &Basis,
        profile: Profile,
        pushed: Option<Profile>,
    ) -> Result<OrFlow<(Correlation, usize)>> {
        let r = st.stage.half_width;
        let first_band = self.first_band(st);
        // Coarse stages (all but the last) only bring the curve near the
        // edge: half the pixels do that, a quarter in bands of 16 px or
        // more (at least 8 pixels across per unit of length). Those of a
        // closed curve run on a binned image instead (`super::pyramid`),
        // where they are their schedule's last and keep every pixel.
        let thin = match (st.is_last, r >= 16.0) {
            (true, _) => 1,
            (false, false) => 2,
            (false, true) => 4,
        };
        // A tracked frame's band has a margin, so that its one run counts
        // the pixels around the edge whatever the reference (see
        // `track::TRACK_MARGIN`); where that band does not fit in the
        // image, the plain one settles as the full schedule does.
        let margin = self.band_margin(pushed);
        let (width, height) = (self.sampler.width(), self.sampler.height());
        let coords = self.config.coords;
        let current = &self.current;
        let plain = || Band::build_with(current, basis, r, profile, width, height, thin, coords);
        let built = if margin > 0.0 {
            Band::build_windowed(current, basis, r, margin, profile, width, height, coords)
                .or_else(|_| plain())
        } else {
            plain()
        };
        let band = match built {
            Ok(b) => b,
            Err(e @ (Error::BandOutsideImage { .. } | Error::CurveOutsideImage { .. })) => {
                return self
                    .band_outside(st, e, (profile, basis), first_band)
                    .map(Err);
            }
            Err(e) => return Err(e),
        };
        let band_pixels = band.len();
        let levels = if st.far {
            LevelModel::Global
        } else {
            self.config.levels
        };
        let prepared =
            Correlation::prepare(band, basis.clone(), self.sampler, levels, st.tilt.as_ref());
        match prepared {
            Ok(c) => Ok(Ok((c, band_pixels))),
            Err(e) if first_band => Err(e),
            Err(e) if st.appended => {
                self.skipped
                    .push(format!("R = {r} px (matched to the blur): {e}"));
                Ok(Err(Flow::Stop))
            }
            Err(_) => {
                self.fail(st, Divergence::Degenerate, (profile, basis, band_pixels));
                Ok(Err(Flow::Stop))
            }
        }
    }

    /// Whether a run builds the schedule's first band: no stage completed
    /// before it (on the image or binned, [`super::pyramid`]) and its stage
    /// has not iterated yet. A first band that cannot be built is the
    /// start's fault (an error), a later one the fit's (a divergence).
    fn first_band(&self, st: &StageState) -> bool {
        self.last.is_none() && !self.binned_done && st.iterations == 0
    }

    /// The margin of a run's band beyond its half-width, pixels: a tracked
    /// frame's pixel-edge band has one, so that its one run counts the
    /// pixels around the edge whatever the reference (see
    /// `track::TRACK_MARGIN`).
    fn band_margin(&self, pushed: Option<Profile>) -> f64 {
        match (self.tracked, pushed) {
            (Some(_), Some(_)) => self.track_margin,
            _ => 0.0,
        }
    }

    /// An open reference trimmed to the stretch whose band of half-width
    /// `r` (for a `pushed` profile, out to its transition if narrower; and
    /// margin, for a tracked frame) fits in the image (from the whole curve
    /// it was cut from, if it was already trimmed: a trim is for one run);
    /// the parts cut off are kept for its next reference
    /// ([`next_reference`]). A closed curve, or one whose band fits whole,
    /// stays as it is.
    ///
    /// A pulled profile samples the image at the band's pixels displaced
    /// by `U`: its band keeps up to [`PULLED_MARGIN`] further from the
    /// border (a pushed profile reads the pixels themselves).
    ///
    /// Errors: those of [`trim_to_band`] (the reference is then unchanged).
    fn trim_reference(&mut self, r: f64, pushed: Option<Profile>) -> Result<()> {
        let pulled = if pushed.is_some() {
            0.0
        } else {
            (self.config.rereference_fraction * r).min(PULLED_MARGIN)
        };
        // A pushed profile's band may lose the flat levels beyond its
        // transition to the border (`Band::new`): the ends are trimmed
        // where the transition leaves the image.
        let core = pushed.and_then(Profile::transition_half_width);
        let clip = Clip {
            half_width: core.map_or(r, |c| c.min(r)) + self.band_margin(pushed),
            margin: TRIM_MARGIN + pulled,
            width: self.sampler.width(),
            height: self.sampler.height(),
        };
        let full = self.trimmed.as_ref().map_or(&self.current, |t| &t.0);
        let (stretch, ends) = trim_to_band(full, clip)?;
        let previous = self.trimmed.take().map(|t| t.0);
        if ends.is_empty() {
            if let Some(full) = previous {
                self.current = full;
            }
        } else {
            let full = std::mem::replace(&mut self.current, stretch);
            self.trimmed = Some((previous.unwrap_or(full), ends));
        }
        Ok(())
    }

    /// The reference after a run that moved the current one by `lambda` on
    /// `basis` (control points `spacing` apart): with the parts a trim cut
    /// off carried along ([`next_reference`]); and those parts, which the
    /// run's result lacks.
    fn new_reference(
        &mut self,
        basis: &Basis,
        lambda: &[f64],
        spacing: f64,
    ) -> Result<std::result::Result<(SplineCurve, Ends), Divergence>> {
        let ends = self.trimmed.take().map(|t| t.1).unwrap_or_default();
        let size = (self.sampler.width(), self.sampler.height());
        let next = next_reference(&self.current, basis, lambda, spacing, &ends, size)?;
        Ok(match loops::curve_loops(&next) {
            Some(looped) => Err(looped),
            None => Ok((next, ends)),
        })
    }

    /// How the stage ends when its band leaves the image (`e`): an error on
    /// the fit's first band; a skip for an optional or coarse stage; a
    /// divergence otherwise.
    fn band_outside(
        &mut self,
        st: &mut StageState,
        e: Error,
        (profile, basis): (Profile, &Basis),
        first_band: bool,
    ) -> Result<Flow> {
        let r = st.stage.half_width;
        if st.appended && st.iterations == 0 {
            // The matched band does not fit: keep the result.
            self.skipped
                .push(format!("R = {r} px (matched to the edge's blur): {e}"));
            return Ok(Flow::Skipped);
        }
        if first_band && self.auto && !st.is_last {
            self.skipped.push(format!("R = {r} px: {e}"));
            return Ok(Flow::Skipped);
        }
        if first_band {
            return Err(e);
        }
        if st.appended {
            // An optional refinement: the previous result stands.
            self.skipped
                .push(format!("R = {r} px (matched to the blur): {e}"));
            return Ok(Flow::Stop);
        }
        let (x, y) = match e {
            Error::BandOutsideImage { x, y, .. } | Error::CurveOutsideImage { x, y, .. } => (x, y),
            _ => (f64::NAN, f64::NAN),
        };
        self.fail(st, Divergence::LeftImage { x, y }, (profile, basis, 0));
        Ok(Flow::Stop)
    }

    /// The fit diverged: the outcome and the stage's report say how.
    fn fail(
        &mut self,
        st: &mut StageState,
        divergence: Divergence,
        (profile, basis, band_pixels): (Profile, &Basis, usize),
    ) {
        self.outcome = Outcome::Diverged { divergence };
        let report = st.report(profile, basis, band_pixels, self.outcome);
        self.reports.push(report);
    }

    /// The coefficients a run starts from (zero, or a kept band's
    /// displacement moved on as it moved last), with the stage's noise,
    /// clutter and tilt carried into the system.
    fn start_run(
        &mut self,
        st: &mut StageState,
        corr: &mut Correlation,
        kept: Option<KeptStart>,
    ) -> Vec<f64> {
        if corr.noise_var().is_none() {
            corr.set_noise_var(st.stage_noise);
        }
        // A cluttered band's fits (its reweighted ones, and the stage's
        // later runs) keep the reference's profile derivative in their
        // gradient (`Correlation::use_reference_gradient`): with the
        // displaced one the weights follow the clutter's residuals, which
        // are far beyond the noise (docs/benchmarks.md).
        if st.cluttered == Some(true) {
            corr.use_reference_gradient();
        }
        st.tilt = corr.measured_tilt().cloned();
        let mut lambda = vec![0.0; corr.n_unknowns()];
        if let Some((kept, velocity)) = kept {
            // The previous frame's curve, moved on as it moved last (see
            // `TrackCache`). The blur stands as the band's first frame
            // fitted it: a sequence's blur changes slowly, and the next band
            // (a few frames on) fits it again.
            st.blur_confirmed = true;
            lambda.clone_from(&kept);
            for (l, v) in lambda.iter_mut().zip(velocity.iter().flatten()) {
                *l += v;
            }
            // The profile on the curvature of that curve, as a band built
            // on it would have (see `band`).
            corr.bend_to(&lambda);
            self.run_start = Some(kept);
        } else if self.tracked.is_some() {
            self.run_start = Some(lambda.clone());
        }
        lambda
    }

    /// The next run from a new reference (`x0 + U n` of the run `system`
    /// ended with), or the stage's divergence when that curve loops.
    fn rereference(
        &mut self,
        st: &mut StageState,
        system: &RunSystem,
        lambda: &[f64],
    ) -> Result<Next> {
        let basis = system.corr.basis();
        if let Some(last) = st.history.last() {
            if last.residual_rms < st.lowest_residual * (1.0 - STALL_GAIN) {
                st.lowest_residual = last.residual_rms;
                st.stalled = 0;
            } else {
                st.stalled += 1;
            }
        }
        match self.move_reference(st, basis, lambda, reference_spacing(basis))? {
            None => Ok(Next::Again),
            Some(looped) => {
                Ok(self.diverge(st, looped, (system.profile, basis, system.band_pixels)))
            }
        }
    }

    /// A new reference `x0 + U n`, control points `spacing` apart, for the
    /// stage's next run; tracking records how far the curve moved. A curve
    /// that folds back or loops is not taken: how it does is returned.
    fn move_reference(
        &mut self,
        st: &mut StageState,
        basis: &Basis,
        lambda: &[f64],
        spacing: f64,
    ) -> Result<Option<Divergence>> {
        let (next, _) = match self.new_reference(basis, lambda, spacing)? {
            Ok(next) => next,
            Err(looped) => return Ok(Some(looped)),
        };
        self.current = next;
        st.rereferences += 1;
        let moved = largest_change(lambda, self.run_start.as_deref());
        self.moved_before = Some(self.moved_before.unwrap_or(0.0) + moved);
        Ok(None)
    }

    /// A run that converged (or reached its iteration limit, `o`): the
    /// once-per-stage checks, the blur refit and the settle, then another
    /// run or the stage's result.
    fn end_run(
        &mut self,
        st: &mut StageState,
        o: Outcome,
        system: RunSystem,
        mut lambda: Vec<f64>,
    ) -> Result<Next> {
        let RunSystem {
            mut corr,
            basis,
            profile,
            pushed,
            band_pixels,
            tolerance,
            windowed,
        } = system;
        self.outcome = o;
        let checked = self.stage_checks(st, o, (corr, lambda), (&basis, profile, tolerance))?;
        (corr, lambda) = (checked.corr, checked.lambda);
        let again = self.refit_blur(st, &corr, &lambda, (pushed, o), tolerance);
        let settle = self.settles(st, &lambda, o, windowed, again);
        if again || settle {
            let spacing = corr.basis().element_length().max(CURVE_SPACING);
            // A settle's new reference: the settles' fixed point. A blur
            // refit starts from the result (its profile changed).
            let extrapolated = match pushed {
                Some(Profile::PixelEdge { blur, .. } | Profile::PixelLine { blur, .. })
                    if !again =>
                {
                    let osculates = corr.band().osculates();
                    settle::extrapolated(&lambda, corr.basis(), &self.current, (blur, osculates))
                }
                _ => None,
            };
            let lambda = extrapolated.as_deref().unwrap_or(&lambda);
            if let Some(looped) = self.move_reference(st, corr.basis(), lambda, spacing)? {
                return Ok(self.diverge(st, looped, (profile, corr.basis(), band_pixels)));
            }
            st.settles += 1;
            return Ok(Next::Again);
        }
        if let (None, Some(_)) = (corr.noise_var(), st.step) {
            corr.estimate_noise(&lambda, self.sampler);
        }
        self.complete(st, (corr, lambda), (profile, band_pixels), o)
    }

    /// The stage's run ended on a curve that loops (`looped`): the fit
    /// diverged, even in an appended stage (whose other failures leave the
    /// previous result standing): a curve that wants to cross itself is no
    /// measurement of a simple edge, and the previous result lies next to it.
    fn diverge(
        &mut self,
        st: &mut StageState,
        looped: Divergence,
        system: (Profile, &Basis, usize),
    ) -> Next {
        self.fail(st, looped, system);
        Next::Exit(Flow::Stop)
    }

    /// The checks a stage makes on its converged runs: varying levels
    /// dropped when they explain no more than noise would (once per
    /// stage), the elements refined (once), the band probed for clutter
    /// and reweighted, the stage's noise estimate kept.
    fn stage_checks(
        &mut self,
        st: &mut StageState,
        o: Outcome,
        (mut corr, mut lambda): (Correlation, Vec<f64>),
        (basis, profile, tolerance): (&Basis, Profile, f64),
    ) -> Result<Checked> {
        let r = st.stage.half_width;
        // Varying levels that explain no more than noise would are dropped
        // (they cost precision), and elements too long for the light are
        // shortened (`Correlation::levels_needed`): this stage runs once
        // more with the levels chosen, and so do the next.
        let test_levels = o == Outcome::Converged && !st.levels_tested;
        // The stage's later converged runs test shorter levels again
        // (`Self::levels_retest`).
        let retest = o == Outcome::Converged && st.levels_tested;
        st.levels_tested |= test_levels;
        // The levels' test estimates the noise on this fit when no stage
        // noise was carried into it: the refinement below reuses it.
        let mut noise_estimated = false;
        let plan = match (test_levels, retest) {
            (true, _) => self.levels_test(&corr, profile),
            (false, true) => self.levels_retest(&corr, profile),
            (false, false) => None,
        };
        if let Some((now, shorter)) = plan {
            let carried = corr.noise_var().is_some();
            let needed = corr.levels_needed(&lambda, self.sampler, now, shorter);
            // A retest only shortens the levels.
            let needed = match (retest, self.config.levels) {
                (true, LevelModel::Varying { element_length }) => {
                    Some(needed.map_or(element_length, |len| len.min(element_length)))
                }
                _ => needed,
            };
            let model = needed.map_or(LevelModel::Global, |len| LevelModel::Varying {
                element_length: len,
            });
            // What the system has: the global pair also where the curve
            // was too short for the configuration's varying levels.
            let current = match corr.varying_levels() {
                true => self.config.levels,
                false => LevelModel::Global,
            };
            if model == current {
                noise_estimated = !carried && corr.noise_var().is_some();
            } else {
                self.config.levels = model;
                self.refit_levels(st, (&mut corr, &mut lambda), basis, tolerance);
            }
        }
        let auto_elements = matches!(st.stage.elements, Elements::Auto { .. });
        if let (Elements::Auto { shortest, .. }, Some(step), None) =
            (st.stage.elements, st.step, st.fixed_elements)
        {
            let refined = refine(
                &self.current,
                Fitted {
                    corr,
                    lambda,
                    step,
                    noise_estimated,
                },
                shortest,
                self.sampler,
                &self.config,
                RefineBand {
                    half_width: r,
                    profile,
                    reuse: st.is_last,
                },
                &mut st.history,
            )?;
            let fit = refined.fit;
            (corr, lambda, st.step) = (fit.corr, fit.lambda, Some(fit.step));
            st.iterations += refined.iterations;
            st.shape_error = refined.shape_error;
            st.local_shape = refined.local_shape;
            if let Some(reference) = refined.reference {
                self.current = reference;
            }
        }
        if auto_elements {
            st.fixed_elements = Some(corr.basis().n_elements());
        }
        if o == Outcome::Converged && st.cluttered != Some(false) && !self.coarse {
            let fit = RobustFit {
                corr: &mut corr,
                lambda: &mut lambda,
                step: &mut st.step,
            };
            let (used, found) = robust_refit(fit, self.sampler, &self.config, r, &mut st.history);
            st.iterations += used;
            st.cluttered = Some(found);
        }
        // The noise of a clean band serves the stage's next runs (a
        // cluttered one's estimate is made without the rejected pixels, on
        // each run's own weights).
        if st.cluttered == Some(false) && st.stage_noise.is_none() {
            st.stage_noise = corr.noise_var();
        }
        Ok(Checked { corr, lambda })
    }

    /// The stage is done: its report, and its result as the schedule's
    /// last, the converged curve becoming the next stage's reference (or
    /// the curve the edge's spread is measured on after the last stage;
    /// the tracking schedule's one stage needs neither). A result that
    /// folds back or loops is a divergence instead.
    fn complete(
        &mut self,
        st: &mut StageState,
        (corr, lambda): (Correlation, Vec<f64>),
        (profile, band_pixels): (Profile, usize),
        o: Outcome,
    ) -> Result<Next> {
        let next = if self.tracked.is_some() && st.is_last {
            self.final_ends = self
                .trimmed
                .as_ref()
                .map(|t| t.1.clone())
                .unwrap_or_default();
            None
        } else {
            let spacing = reference_spacing(corr.basis());
            match self.new_reference(corr.basis(), &lambda, spacing)? {
                Ok((next, ends)) => {
                    self.final_ends = ends;
                    Some(next)
                }
                Err(looped) => {
                    return Ok(self.diverge(st, looped, (profile, corr.basis(), band_pixels)))
                }
            }
        };
        let report = StageReport {
            clipped: corr.clipped(),
            ..st.report(profile, corr.basis(), band_pixels, o)
        };
        self.reports.push(report);
        self.last = Some(Final {
            half_width: st.stage.half_width,
            profile,
            reference: match next {
                Some(next) => std::mem::replace(&mut self.current, next),
                None => self.current.clone(),
            },
            corr,
            lambda,
            shape_error: st.shape_error,
            local_shape: st.local_shape.take(),
            coupling: st.coupling,
        });
        Ok(Next::Exit(Flow::Completed))
    }

    /// Whether a converged stage, not yet tested, tests its gray levels,
    /// and how (`Correlation::levels_needed`): the element length of the
    /// varying levels it fits (or, with the global pair, of those asked
    /// for), and whether elements shorter than that are tried. Varying levels are
    /// tested once per stage; shorter elements only on the pixel edge,
    /// whose profile fits: on a coarse stage's, the misfit near a
    /// polygon's corners passed for light that changes along the curve,
    /// and shorter levels there took the corners' fit apart (the test
    /// leaves the pixels near corners out). The pixel edge also tests the
    /// global pair that an earlier stage chose, or that a closed curve
    /// shorter than the fewest elements asked for had, when varying levels
    /// were asked for: the elements may have been too long for the light,
    /// and uneven light across a small object moves its whole edge (an 8 %
    /// gradient across an object of 60 px radius, 0.2 px).
    fn levels_test(&self, corr: &Correlation, profile: Profile) -> Option<(f64, bool)> {
        let pixel_edge = matches!(profile, Profile::PixelEdge { .. });
        match (self.config.levels, self.levels_asked) {
            (LevelModel::Varying { element_length }, _) if corr.varying_levels() => {
                Some((element_length, pixel_edge))
            }
            (LevelModel::Global, LevelModel::Varying { element_length }) if pixel_edge => {
                Some((element_length, true))
            }
            // A closed curve too short for the elements asked for.
            (LevelModel::Varying { element_length }, _)
                if pixel_edge && corr.basis().is_closed() =>
            {
                Some((element_length, true))
            }
            _ => None,
        }
    }

    /// The test of a later converged run of a pixel-edge stage whose levels
    /// vary, while they may still be shortened: `(length asked, true)`,
    /// its answer taken only where shorter than the levels in use;
    /// `None` otherwise (another profile, the global pair, the shortest
    /// levels already).
    ///
    /// Why: the stage's first test runs on its first converged fit, whose
    /// curve is still off where the edge bends tightly (its elements not
    /// refined yet), and the residual that leaves hides light that
    /// changes faster along the curve: a seven-lobed shape of 95 px
    /// radius under a 10 % gradient, blur 2.5 px, 0.5 % noise, kept
    /// levels of 128 px elements and came out 0.034 px RMS off the true
    /// curve at a `sigma` of 0.012 px; tested again once the curve fits,
    /// 32 px elements, 0.013 px.
    fn levels_retest(&self, corr: &Correlation, profile: Profile) -> Option<(f64, bool)> {
        let (
            LevelModel::Varying {
                element_length: asked,
            },
            LevelModel::Varying { element_length },
        ) = (self.levels_asked, self.config.levels)
        else {
            return None;
        };
        let pixel_edge = matches!(profile, Profile::PixelEdge { .. });
        // Not on a curve with corners, declared or not yet: shorter levels
        // would take up their misfit, which is not the light's (a
        // vignetted pentagon's smooth fit took shorter levels, one corner
        // was then missed, and the edge came out 0.031 px RMS off instead
        // of 0.014).
        let smooth = self.current.corners().is_empty() && sharpest_bend(&self.current).is_some();
        (pixel_edge && smooth && corr.varying_levels() && element_length > SHORTEST_LEVELS * asked)
            .then_some((asked, true))
    }

    /// The run again with the levels the stage's test chose (already set
    /// in the configuration: the global pair, or varying levels of shorter
    /// elements), from where it converged; kept when it converges.
    fn refit_levels(
        &mut self,
        st: &mut StageState,
        (corr, lambda): (&mut Correlation, &mut Vec<f64>),
        basis: &Basis,
        tolerance: f64,
    ) {
        let band = corr.band().clone();
        let Ok(mut refit) =
            Correlation::prepare(band, basis.clone(), self.sampler, self.config.levels, None)
        else {
            return;
        };
        let mut refit_lambda = lambda.clone();
        let mut refit_step = None;
        let limits = RunLimits {
            budget: self.config.max_iterations,
            tolerance,
            rereference: f64::INFINITY,
            half_width: st.stage.half_width,
            lost: f64::INFINITY,
        };
        let (end, used) = iterate_to_end(
            &mut refit,
            &mut refit_lambda,
            self.sampler,
            &self.config,
            limits,
            &mut refit_step,
            RunLog {
                history: &mut st.history,
                kind: RunKind::Levels,
            },
        );
        st.iterations += used;
        if let (Run::Converged, Some(_)) = (end, refit_step) {
            (*corr, *lambda, st.step) = (refit, refit_lambda, refit_step);
        }
    }

    /// The pixel edge's blur, fitted on the converged curve: whether it
    /// changed enough for one more run with it (then the profile is
    /// updated). Once the isotropic blur has settled (no change, or its
    /// runs spent), its anisotropy is fitted ([`fit_anisotropy`], at most
    /// `MAX_ANISOTROPY_FITS` times; not on tracked frames, which keep the
    /// first frame's).
    fn refit_blur(
        &mut self,
        st: &mut StageState,
        corr: &Correlation,
        lambda: &[f64],
        (pushed, o): (Option<Profile>, Outcome),
        tolerance: f64,
    ) -> bool {
        let (Some(Profile::PixelEdge { blur, anisotropy }), Outcome::Converged) = (pushed, o)
        else {
            return false;
        };
        if st.blur_confirmed {
            return false;
        }
        let updates = match corr.censored() {
            true => MAX_CENSORED_BLUR_UPDATES,
            false => MAX_BLUR_UPDATES,
        };
        if st.blur_updates < updates {
            let fitted = match self.tracked {
                Some(_) => track::refit_blur(corr, lambda, blur),
                None => {
                    let (fitted, coupling) = fit_blur_and_offset(corr, lambda, blur);
                    st.coupling = coupling;
                    fitted
                }
            };
            // Where the encoding clipped band pixels the blur trades off
            // with the curve's offset and each run brings the curve only
            // part of the way: the fixed tolerance alone (a backlight at
            // 1.2 times the clip level came out 0.013 px small with the
            // curvature's, against 1.9e-3).
            let matters = if corr.censored() {
                (fitted - blur).abs() > BLUR_TOLERANCE
            } else {
                blur_change_matters(&self.current, (blur, fitted), tolerance)
            };
            if matters {
                self.pixel_edge = Some(Profile::PixelEdge {
                    blur: fitted,
                    anisotropy,
                });
                st.blur_updates += 1;
                return true;
            }
        }
        if self.tracked.is_some() {
            st.blur_confirmed = true;
            return false;
        }
        // An object a few blurs across (a dot, a small ellipse): its own
        // elongation and an elongated blur give it the same image, and the
        // curve, held fixed while the blur's shape is fitted, makes any
        // elongation look like the blur's.
        if st.anisotropy_fits >= MAX_ANISOTROPY_FITS || few_blurs_across(corr, blur) {
            return false;
        }
        st.anisotropy_fits += 1;
        let Some((fitted, shape)) = fit_anisotropy(corr, lambda, blur, anisotropy) else {
            // Settled, or isotropic: no more fits.
            st.anisotropy_fits = MAX_ANISOTROPY_FITS;
            return false;
        };
        self.pixel_edge = Some(Profile::PixelEdge {
            blur: fitted,
            anisotropy: shape,
        });
        true
    }

    /// Settle (default schedule, last stage): whether to re-reference on
    /// the measured curve (with a pushed profile, on the settles' fixed
    /// point extrapolated from it, `fit/settle.rs`), refitted with control
    /// points one element apart, because the displacement has not vanished
    /// yet. The result is then a
    /// fixed point of the stage (to about `SETTLE_TOLERANCE`), whatever the
    /// path that led there: two different starts give the same curve, and
    /// detail finer than the elements that the start (a traced boundary, a
    /// hand-drawn polyline) put in the reference, which the displacement
    /// cannot remove, is gone. A pushed profile is also exact only at
    /// `U = 0`. At least once: a wiggle finer than the elements leaves `U`
    /// near 0. A silhouette's R = 2 px stage leaves this to the pixel-edge
    /// stage that follows it. "Vanished": under `SETTLE_TOLERANCE`, or no
    /// longer contracting. `again`: a run with a new blur follows anyway
    /// (it starts a new comparison: its displacement comes from the
    /// profile's change).
    fn settles(
        &self,
        st: &mut StageState,
        lambda: &[f64],
        o: Outcome,
        windowed: bool,
        again: bool,
    ) -> bool {
        let moved = lambda.iter().fold(0.0, |m: f64, l| m.max(l.abs()));
        let contracting = moved < SETTLE_CONTRACTION * st.previous_move
            || moved >= SETTLE_NOISE_CHECK * SETTLE_TOLERANCE;
        let settle = self.auto
            && st.is_last
            && !st.followed
            && !windowed
            && o == Outcome::Converged
            && st.settles < MAX_SETTLES
            && (st.settles == 0 || (moved > SETTLE_TOLERANCE && contracting));
        st.previous_move = if again { f64::INFINITY } else { moved };
        settle
    }
}
