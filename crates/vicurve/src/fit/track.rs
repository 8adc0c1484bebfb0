//! The tracking schedule: a frame of a sequence started from the previous
//! frame's measured curve.
//!
//! The default schedule rebuilds everything from scratch: three coarse
//! stages (R = 20, 10, 5 px) bring a start that may cross the object onto
//! the edge, the R = 2 px stage chooses the elements, the edge's blur is
//! estimated, and the pixel-edge stage measures. A tracked start is already
//! within a fraction of a pixel of the edge, and the previous frame has
//! already chosen the elements and fitted the blur. The tracking schedule
//! runs the pixel-edge stage alone, from the previous frame's blur and
//! element length ([`TrackState`]): the blur is refitted on the converged
//! curve as in the full schedule (a change of more than 0.01 px runs the
//! stage again), and the stage settles as the full schedule's last stage
//! does (it re-references on its own result until the displacement
//! vanishes), so the result is the same fixed point whatever the start
//! (to about 1e-3 px: see `SETTLE_TOLERANCE`).
//! Within a frame the blur is refitted until a refit confirms it (the full
//! schedule refits it after every settling run), and on a narrower bracket
//! than the full schedule's (`refit_blur`). When the previous frame
//! found the gray levels even along the curve (varying levels not
//! significant, [`crate::fit::LevelModel`]), the tracked frame uses the
//! global pair from the start instead of fitting varying levels and
//! dropping them again; a sequence whose lighting becomes uneven later
//! needs the full schedule.
//!
//! The pixel-edge stage compares the virtual edge with the pixel values at
//! the pixel centres (the profile is pushed, the image is not
//! interpolated), so [`measure_tracked_from`] works with a sampler of any
//! interpolation: the cheapest, bilinear, has no prefilter.
//!
//! When the tracking schedule cannot measure the frame (the band leaves the
//! image, no contrast, no convergence), the caller measures it with the
//! full schedule ([`measure_tracked`] does it itself).

use super::correlation::Correlation;
use super::{measure_from, pixel_edge_band, run_schedule, Elements, FitConfig, Measurement, Stage};
use super::{LevelModel, Outcome, StageReport, BLUR_FIT_PIXELS, BLUR_TOLERANCE};
use crate::curve::SplineCurve;
use crate::error::Result;
use crate::image::Image;
use crate::interp::{Interpolation, Sampler};
use crate::virtual_image::{Kind, Profile};
use serde::{Deserialize, Serialize};

/// What a tracked frame takes from the previous frame's measurement.
#[derive(Clone, Copy, Debug, PartialEq, Serialize, Deserialize)]
pub struct TrackState {
    /// Optical blur of the pixel-edge profile, pixels (standard deviation;
    /// 0 for a focused edge).
    pub blur: f64,
    /// Length of the displacement's elements, pixels.
    pub element_length: f64,
    /// Whether the gray levels were a global pair (not varying along the
    /// curve).
    pub global_levels: bool,
}

impl TrackState {
    /// The state left by a measurement whose last stage is a converged
    /// pixel-edge stage (the default schedule of a silhouette with the blur
    /// correction on, or the tracking schedule), from its stage history and
    /// the length of its curve (pixels) and whether its gray levels vary
    /// along it (its [`Measurement::levels`] are not empty). `None`
    /// otherwise: the next frame then needs the full schedule.
    pub fn from_stages(
        stages: &[StageReport],
        curve_length: f64,
        levels_vary: bool,
    ) -> Option<TrackState> {
        let last = stages.last()?;
        TrackState::from_last_stage(
            last.profile,
            last.elements,
            last.outcome,
            curve_length,
            levels_vary,
        )
    }

    /// [`TrackState::from_stages`] from the last stage's profile, number of
    /// elements and outcome (as a result file records them).
    pub fn from_last_stage(
        profile: Profile,
        elements: usize,
        outcome: Outcome,
        curve_length: f64,
        levels_vary: bool,
    ) -> Option<TrackState> {
        let Profile::PixelEdge { blur } = profile else {
            return None;
        };
        let state = TrackState {
            blur,
            element_length: curve_length / elements as f64,
            global_levels: !levels_vary,
        };
        (outcome.is_converged() && elements > 0 && state.usable()).then_some(state)
    }

    /// [`TrackState::from_stages`] of a measurement.
    pub fn from_measurement(m: &Measurement) -> Option<TrackState> {
        TrackState::from_stages(&m.stages, m.curve.param_length(), !m.levels.is_empty())
    }

    /// The one stage of the tracking schedule.
    pub(super) fn stage(&self) -> Stage {
        Stage {
            half_width: pixel_edge_band(self.blur),
            elements: Elements::Length(self.element_length),
        }
    }

    /// The profile of that stage.
    pub(super) fn profile(&self) -> Profile {
        Profile::PixelEdge { blur: self.blur }
    }

    fn usable(&self) -> bool {
        self.blur.is_finite()
            && self.blur >= 0.0
            && self.element_length.is_finite()
            && self.element_length > 0.0
    }
}

/// Measure a frame with the tracking schedule (module docs), from `start`
/// (the previous frame's curve, usually smoothed) and the previous frame's
/// `state`. `sampler` may be of any interpolation (only pixel-centre values
/// are read); `config` gives everything but the stages (its `stages` are
/// ignored).
///
/// `Ok(None)` when the tracking schedule does not apply or could not
/// measure the frame: `config` is not a silhouette's with the blur
/// correction on, the stage's band does not fit in the image, or the stage
/// did not converge. The frame then needs the full schedule
/// ([`measure_from`]). Errors: an invalid configuration.
///
/// The result's [`Measurement::edge_spread`] is `None` (the edge's spread
/// is not estimated again; the fitted blur is in the stage's profile).
pub fn measure_tracked_from(
    sampler: &Sampler,
    start: SplineCurve,
    state: &TrackState,
    config: &FitConfig,
) -> Result<Option<Measurement>> {
    config.validate()?;
    if config.kind != Kind::Silhouette || !config.blur_correction || !state.usable() {
        return Ok(None);
    }
    // The pushed profile never interpolates: the sampler's kind is free.
    let mut config = FitConfig {
        interpolation: sampler.kind(),
        stages: None,
        ..config.clone()
    };
    if state.global_levels {
        config.levels = LevelModel::Global;
    }
    let m = match run_schedule(sampler, start, &config, Some(*state)) {
        Ok(m) => m,
        Err(_) => return Ok(None),
    };
    let done = m.outcome == Outcome::Converged
        && m.stages.len() == 1
        && matches!(m.stages[0].profile, Profile::PixelEdge { .. });
    Ok(done.then_some(m))
}

/// Measure a frame of a sequence: with the tracking schedule when `state`
/// (the previous frame's, [`TrackState::from_measurement`]) is given and
/// it can, else with `config`'s schedule from `start`. Prepares the image
/// as each needs it: no interpolation for the tracking schedule (a bilinear
/// sampler, which shares the image's pixels), `config`'s interpolation for
/// the other.
///
/// Errors: those of [`measure_from`].
pub fn measure_tracked(
    image: &Image,
    start: SplineCurve,
    state: Option<&TrackState>,
    config: &FitConfig,
) -> Result<Measurement> {
    if let Some(state) = state {
        let plain = Sampler::new(image, Interpolation::Bilinear);
        if let Some(m) = measure_tracked_from(&plain, start.clone(), state, config)? {
            return Ok(m);
        }
    }
    config.validate()?;
    let sampler = Sampler::new(image, config.interpolation);
    measure_from(&sampler, start, config)
}

/// Half-width of the bracket of [`refit_blur`], pixels: a sequence's blur
/// changes little from frame to frame.
const BLUR_BRACKET: f64 = 0.05;
/// Golden-section steps of [`refit_blur`]: the bracket shrinks to 0.09 of
/// its width, and its middle is within half a [`BLUR_TOLERANCE`] of the
/// optimum.
const BLUR_STEPS: usize = 5;

/// The tracked frame's refit of the pixel edge's blur (the full schedule's
/// `fit_blur` on a bracket of `current +- BLUR_BRACKET` instead of 30 % +
/// 0.15 px: 7 evaluations of the band's residual instead of 14). A blur
/// that moved farther ends at the bracket's end, more than
/// `BLUR_TOLERANCE` away, and the stage runs again from there.
pub(super) fn refit_blur(corr: &Correlation, lambda: &[f64], current: f64) -> f64 {
    debug_assert!(BLUR_BRACKET * 0.618f64.powi(BLUR_STEPS as i32) < BLUR_TOLERANCE);
    let stride = corr.band.len().div_ceil(BLUR_FIT_PIXELS);
    let ssr = |blur: f64| {
        corr.pushed_ssr(lambda, Profile::PixelEdge { blur }, stride)
            .unwrap_or(f64::INFINITY)
    };
    let lo = (current - BLUR_BRACKET).max(0.0);
    let hi = current + BLUR_BRACKET;
    let best = crate::psf::golden(lo, hi, BLUR_STEPS, ssr);
    // As `fit_blur`: a focused edge's optimum is 0, the bracket's end.
    if lo == 0.0 && ssr(0.0) <= ssr(best) {
        0.0
    } else {
        best
    }
}
