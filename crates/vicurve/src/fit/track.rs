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
//! stage again). Where the full schedule's last stage settles (it
//! re-references on its own result until the displacement vanishes, so
//! that the result does not depend on the reference), the tracked stage's
//! band has a margin and counts the pixels around the displaced curve
//! ([`TRACK_MARGIN`]): one band and one run, from the previous frame's
//! curve refitted with control points one element apart (as a settle's
//! reference is). A frame that moves more than the margin re-references
//! on its way; where the band with its margin does not fit in the image,
//! the stage settles as the full schedule's does. In a sequence, a frame
//! may also measure on the band the previous frame left, when the curve
//! stays within its margin ([`TrackCache`], [`measure_tracked_cached`]): no
//! band and no system to prepare.
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

mod cache;

pub(super) use cache::Kept;
pub use cache::{TrackCache, TrackSnapshot};

use super::blur::{blur_residual, parabolic_refit};
use super::{measure_from, pixel_edge_band, run_schedule, Elements, FitConfig, Measurement, Stage};
use super::{LevelModel, Outcome, StageReport, BLUR_TOLERANCE};
use crate::correlation::Correlation;
use crate::curve::SplineCurve;
use crate::error::Result;
use crate::image::Image;
use crate::interp::{Interpolation, Sampler};
use crate::tone::Tone;
use crate::virtual_image::{Anisotropy, Kind, Profile};
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
    /// How the blur differs with direction (see [`Anisotropy`]; absent:
    /// none).
    #[serde(default, skip_serializing_if = "Anisotropy::is_none")]
    pub anisotropy: Anisotropy,
    /// The tone curve the measurement read the gray levels with (see
    /// [`Measurement::tone`]): the next frames are read with it unless the
    /// configuration gives one.
    #[serde(default = "Tone::linear")]
    pub tone: Tone,
}

impl TrackState {
    /// The state left by a measurement whose last band stage (the last
    /// but a whole-object stage, `fit/whole/`) is a converged
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
        let last = crate::measurement::last_band_stage(stages)?;
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
        let Profile::PixelEdge { blur, anisotropy } = profile else {
            return None;
        };
        let state = TrackState {
            blur,
            anisotropy,
            element_length: curve_length / elements as f64,
            global_levels: !levels_vary,
            tone: Tone::Linear,
        };
        (outcome.is_converged() && elements > 0 && state.usable()).then_some(state)
    }

    /// [`TrackState::from_stages`] of a measurement.
    pub fn from_measurement(m: &Measurement) -> Option<TrackState> {
        TrackState::from_stages(&m.stages, m.curve.param_length(), !m.levels.is_empty()).map(
            |state| TrackState {
                tone: m.tone,
                ..state
            },
        )
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
        Profile::PixelEdge {
            blur: self.blur,
            anisotropy: self.anisotropy,
        }
    }

    fn usable(&self) -> bool {
        self.blur.is_finite()
            && self.blur >= 0.0
            && self.element_length.is_finite()
            && self.element_length > 0.0
    }
}

/// Measure a frame with the tracking schedule (module docs), from `start`
/// (the previous frame's curve, as it is: the schedule refits it with
/// control points one element apart) and the previous frame's
/// `state`. `sampler` may be of any interpolation (only pixel-centre values
/// are read); `config` gives everything but the stages (its `stages` are
/// ignored).
///
/// `Ok(None)` when the tracking schedule does not apply or could not
/// measure the frame: `config` is not a silhouette's with the blur
/// correction on, the stage's band does not fit in the image, a step went
/// beyond the band's half-width (the band does not see the edge: a start
/// too far from it), or the stage did not converge. The frame then needs the full schedule
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
    measure_tracked_cached(sampler, start, state, config, &mut TrackCache::default())
}

/// [`measure_tracked_from`] for a frame of a sequence whose previous frame
/// left `cache` (see [`TrackCache`]): measured on the kept band when it
/// serves, and the cache updated for the next frame (emptied when the
/// frame is not measured by the tracking schedule: `Ok(None)`, an error).
/// `start` is not used when the kept band serves.
pub fn measure_tracked_cached(
    sampler: &Sampler,
    start: SplineCurve,
    state: &TrackState,
    config: &FitConfig,
    cache: &mut TrackCache,
) -> Result<Option<Measurement>> {
    let m = measure_tracked_inner(sampler, start, state, config, cache);
    if !matches!(m, Ok(Some(_))) {
        cache.clear();
    }
    m
}

fn measure_tracked_inner(
    sampler: &Sampler,
    start: SplineCurve,
    state: &TrackState,
    config: &FitConfig,
    cache: &mut TrackCache,
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
    // The tone curve: the configuration's, else the previous frame's.
    let tone = if config.tone.is_identity() {
        state.tone
    } else {
        config.tone
    };
    let linear;
    let sampler = if tone.is_identity() {
        sampler
    } else {
        linear = super::tone::linear_sampler(sampler, tone)?;
        &*linear
    };
    let mut m = match run_schedule(sampler, start, &config, Some((*state, cache))) {
        Ok(m) => m,
        Err(_) => return Ok(None),
    };
    if !tone.is_identity() {
        m.tone = tone;
    }
    let done = m.outcome == Outcome::Converged
        && m.stages.len() == 1
        && matches!(m.stages[0].profile, Profile::PixelEdge { .. });
    // A small object under a large blur, as the first frame measured it
    // (`whole/`): else its frames would differ by the profile's bias.
    Ok(done.then(|| super::whole::refined(sampler, m, config.sample_spacing)))
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

/// Margin of a tracked frame's band beyond its half-width, pixels (see
/// [`Band::build_windowed`](crate::band::Band::build_windowed)).
///
/// The full schedule's last stage settles: it re-references on its own
/// result until the displacement vanishes, because a band centred on the
/// reference, not on the edge, tips the balance of the residuals by a
/// fraction of the displacement where the physical profile differs from
/// the virtual one. A tracked frame's band instead holds the pixels out to
/// this margin, and counts those within the half-width of the displaced
/// curve: the one run measures what a settle would, with one band instead
/// of two. A frame that moves further than the margin re-references on
/// its way (a new band around the curve reached so far). The margin costs
/// 15 % more band pixels at a blur of 1 px; a settle costs a second band.
/// It is as accurate as the settle, or more (docs/benchmarks.md).
pub(super) const TRACK_MARGIN: f64 = 0.5;

/// Half-width of the bracket of [`refit_blur`]'s fallback search, pixels:
/// a sequence's blur changes little from frame to frame.
const BLUR_BRACKET: f64 = 0.05;
/// Golden-section steps of that search: the bracket shrinks to 0.09 of
/// its width, and its middle is within half a [`BLUR_TOLERANCE`] of the
/// optimum.
const BLUR_STEPS: usize = 5;

/// The tracked frame's refit of the pixel edge's blur: the vertex of a
/// narrow parabola through the band's residual (with the gray levels
/// refitted) around `current` when it lies within its probes, as in the
/// full schedule ([`parabolic_refit`]; the test
/// `parabolic_refit_matches_the_search`: three evaluations). Otherwise
/// (the blur moved, or the residual is not convex there) a golden-section
/// search on `current +- BLUR_BRACKET` (7 evaluations), narrower than the
/// full schedule's: a blur that moved farther ends at the bracket's end,
/// more than `BLUR_TOLERANCE` away, and the stage runs again from there.
pub(super) fn refit_blur(corr: &Correlation, lambda: &[f64], current: f64) -> f64 {
    debug_assert!(BLUR_BRACKET * 0.618f64.powi(BLUR_STEPS as i32) < BLUR_TOLERANCE);
    if let Some(blur) = parabolic_refit(corr, lambda, current) {
        return blur;
    }
    let ssr = blur_residual(corr, lambda);
    let lo = (current - BLUR_BRACKET).max(0.0);
    let hi = current + BLUR_BRACKET;
    let best = crate::psf::golden(lo, hi, BLUR_STEPS, &ssr);
    // As `fit_blur`: a focused edge's optimum is 0, the bracket's end.
    if lo == 0.0 && ssr(0.0) <= ssr(best) {
        0.0
    } else {
        best
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::band::Band;
    use crate::curve::InitialCurve;
    use crate::render::{render, Method, RenderSpec};
    use crate::spline::Basis;
    use crate::truth::Shape;

    /// The parabola's vertex against a fine golden-section search of the
    /// same residual (60 steps on [0, 4] px), on exact-coverage discs of
    /// several blurs, with the global and the varying levels, from blurs in
    /// use 0.015 px either side of the optimum: within a quarter of
    /// `BLUR_TOLERANCE` (measured: 5e-4 px at most), or with as low a
    /// residual (the focused disc, whose residual is flat below 0.03 px);
    /// and the full schedule's `fit_blur` from 0.3 px either side within
    /// half of it where its bracket holds the optimum.
    #[test]
    fn parabolic_refit_matches_the_search() {
        for (blur, noise) in [(0.0, 0.0), (0.6, 0.005), (1.2, 0.01), (2.5, 0.0)] {
            let shape = Shape::Circle {
                cx: 100.3,
                cy: 99.6,
                r: 60.0,
            };
            let spec = RenderSpec {
                width: 200,
                height: 200,
                shape,
                kind: Kind::Silhouette,
                method: Method::Coverage,
                foreground: 0.8,
                background: 0.2,
                blur_sigma: blur,
                noise,
                seed: 3,
                bits: Some(16),
                ..RenderSpec::default()
            };
            let image = render(&spec).unwrap();
            let sampler = Sampler::new(&image, Interpolation::Bilinear);
            let curve = InitialCurve::Circle {
                cx: 100.3,
                cy: 99.6,
                r: 60.0,
            }
            .to_curve()
            .unwrap();
            let basis = Basis::new(3, 12, curve.param_length(), true).unwrap();
            let profile = Profile::pixel_edge(blur);
            let half_width = super::super::pixel_edge_band(blur);
            for levels in [LevelModel::Global, LevelModel::default()] {
                let band = Band::build(&curve, &basis, half_width, profile, 200, 200).unwrap();
                let corr =
                    Correlation::prepare(band, basis.clone(), &sampler, levels, None).unwrap();
                let lambda = vec![0.0; corr.n_unknowns()];
                let ssr = blur_residual(&corr, &lambda);
                let mut optimum = crate::psf::golden(0.0, 4.0, 60, &ssr);
                if ssr(0.0) <= ssr(optimum) {
                    optimum = 0.0;
                }
                // The full schedule's refit from farther (its golden
                // section then): within half a tolerance, or as good, when
                // its bracket holds the optimum (else the next run
                // brackets again).
                for offset in [-0.3, 0.015, 0.3] {
                    let current = (optimum + offset).max(0.0);
                    let bracket = (0.7 * current - 0.15).max(0.0)..=1.3 * current + 0.15;
                    if !bracket.contains(&optimum) {
                        continue;
                    }
                    let fitted = super::super::blur::fit_blur(&corr, &lambda, current);
                    let half = 0.5 * BLUR_TOLERANCE;
                    let bound = ssr(optimum + half).max(ssr((optimum - half).max(0.0)));
                    assert!(
                        (fitted - optimum).abs() < half || ssr(fitted) <= bound,
                        "fit_blur: blur {blur}, {levels:?}, from {current}: {fitted} vs {optimum}"
                    );
                }
                for offset in [-0.015, 0.0, 0.015] {
                    let current = (optimum + offset).max(0.0);
                    // The vertex step applies, except to the focused disc
                    // from 0.045 px (its residual is flat below 0.03 px):
                    // the search then.
                    let vertex = parabolic_refit(&corr, &lambda, current);
                    assert!(
                        vertex.is_some() || blur == 0.0,
                        "blur {blur} {levels:?} from {current}: no vertex"
                    );
                    let refit = refit_blur(&corr, &lambda, current);
                    assert!(vertex.is_none_or(|v| v == refit));
                    // Within a quarter tolerance of the optimum, or as good:
                    // below 0.03 px the profile hardly depends on the blur
                    // (`MIN_BLUR` of the pixel edge), and a focused edge's
                    // residual is flat there.
                    let quarter = 0.25 * BLUR_TOLERANCE;
                    let bound = ssr(optimum + quarter).max(ssr((optimum - quarter).max(0.0)));
                    assert!(
                        (refit - optimum).abs() < quarter || ssr(refit) <= bound,
                        "blur {blur}, {levels:?}, from {current}: {refit} vs {optimum}"
                    );
                }
            }
        }
    }
}
