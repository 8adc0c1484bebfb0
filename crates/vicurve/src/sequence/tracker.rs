//! [`CurveTracker`]: one curve through a sequence, frame after frame, as
//! `vicurve track` runs it (without its files).

use super::{
    measure_curve, rebuild, tracking_state, CurveStep, FrameSamplers, Previous, SequenceCurve,
};
use crate::curve::{InitialCurve, SplineCurve};
use crate::fit::{FitConfig, Outcome, TrackCache, TrackSnapshot};
use crate::image::Image;
use crate::interp::Interpolation;

/// One curve tracked through a sequence: the curve's start and
/// configurations, and what it carries from frame to frame.
pub struct CurveTracker {
    init: InitialCurve,
    first: FitConfig,
    tracked: FitConfig,
    tracking_schedule: bool,
    track: bool,
    last_good: Option<Previous>,
    cache: TrackCache,
}

/// One frame measured by a [`CurveTracker`].
#[derive(Clone, Debug)]
pub struct TrackedFrame {
    /// The fit, its start and configuration.
    pub step: CurveStep,
    /// The curve as written, when the fit is good to go on from (converged
    /// or at its iteration limit); the next frame starts from it.
    pub good: Option<SplineCurve>,
    /// Why the frame failed (no measurement, diverged, or an unusable
    /// curve), `None` when `good` is set.
    pub failure: Option<String>,
}

impl CurveTracker {
    /// A tracker starting from `init`: the first frame with `first`, the
    /// following ones from the previous result with `tracked` (the tracking
    /// schedule first when `tracking_schedule`), or every frame from `init`
    /// when `track` is false.
    pub fn new(
        init: InitialCurve,
        first: FitConfig,
        tracked: FitConfig,
        tracking_schedule: bool,
        track: bool,
    ) -> CurveTracker {
        CurveTracker {
            init,
            first,
            tracked,
            tracking_schedule,
            track,
            last_good: None,
            cache: TrackCache::default(),
        }
    }

    /// The last good curve and its frame, if any.
    pub fn last_good(&self) -> Option<&Previous> {
        self.last_good.as_ref()
    }

    /// Go on from a frame measured before (read back from its result file):
    /// its curve as written, its band, and what its fit left.
    pub fn resume_from(&mut self, previous: Previous) {
        self.cache = previous
            .band
            .clone()
            .map(TrackCache::from_snapshot)
            .unwrap_or_default();
        self.last_good = Some(previous);
    }

    /// Measure the curve on frame `image`, named `stem` (recorded by the
    /// next frame as where it started from).
    pub fn measure(&mut self, image: &Image, stem: &str) -> TrackedFrame {
        let samplers = FrameSamplers::new(image);
        let sampler = |k: Interpolation| samplers.get(k);
        let spec = SequenceCurve {
            init: &self.init,
            first: &self.first,
            tracked: &self.tracked,
            tracking_schedule: self.tracking_schedule,
        };
        let prev = if self.track {
            self.last_good.as_ref()
        } else {
            None
        };
        let step = measure_curve(spec, prev, &mut self.cache, &sampler);
        let (good, failure) = match &step.measured {
            Err(e) => (None, Some(e.clone())),
            Ok(m) => match m.outcome {
                Outcome::Diverged { divergence } => {
                    (None, Some(format!("the fit diverged: {divergence}")))
                }
                _ => match rebuild(&m.curve_data()) {
                    Ok(c) => {
                        self.last_good = Some(Previous {
                            curve: c.clone(),
                            stem: stem.to_string(),
                            state: tracking_state(m, &c),
                            band: step.band.clone(),
                        });
                        (Some(c), None)
                    }
                    Err(e) => (None, Some(e)),
                },
            },
        };
        if good.is_none() {
            // Go on from the last good frame, band included.
            let band: Option<TrackSnapshot> = self.last_good.as_ref().and_then(|p| p.band.clone());
            self.cache = band.map(TrackCache::from_snapshot).unwrap_or_default();
        }
        TrackedFrame {
            step,
            good,
            failure,
        }
    }
}
