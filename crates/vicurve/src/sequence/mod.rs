//! Curves tracked through a sequence of frames: the frame-to-frame step
//! shared by the command-line tool (`vicurve track`, `vicurve run`) and the
//! Python package (`vicurve.track`), so that both give the same curves.
//!
//! Each frame's fit starts from the previous frame's good result, as it is
//! written to the result file and read back ([`rebuild`]), so that a run
//! resumed from its files goes on exactly as an uninterrupted one:
//! - the *tracking schedule* first when the curve asks for it and the
//!   previous frame left a [`TrackState`] (the pixel-edge stage alone, on
//!   the band the previous frame left in the [`crate::fit::TrackCache`]);
//! - else (or when it cannot measure) the tracked configuration from the
//!   previous curve smoothed (`step`);
//! - a tracked fit that fails is tried again with the first frame's
//!   configuration when the two differ.
//!
//! A frame whose fit fails or diverges is recorded, and the next frame
//! starts from the last good one. [`CurveTracker`] runs the whole loop for
//! one curve; [`run`] runs a job (several curves, widths), with its files
//! and its resume.

pub mod run;
mod samplers;
mod step;
mod tracker;
mod written;

pub use samplers::FrameSamplers;
pub use step::{measure_curve, CurveStep};
pub use tracker::{CurveTracker, TrackedFrame};
pub use written::{rebuild, tracking_state};

use crate::curve::{InitialCurve, SplineCurve};
use crate::fit::{FitConfig, TrackSnapshot, TrackState};

/// One curve to measure on every frame, and how.
#[derive(Clone, Copy, Debug)]
pub struct SequenceCurve<'a> {
    /// The start of the first frame (and of frames after a failure with no
    /// good curve before them).
    pub init: &'a InitialCurve,
    /// Configuration of frames started from `init`.
    pub first: &'a FitConfig,
    /// Configuration of frames started from the previous frame's result.
    pub tracked: &'a FitConfig,
    /// Whether those frames run the tracking schedule first, `tracked`
    /// being the fallback.
    pub tracking_schedule: bool,
}

/// The last good curve of one curve of a sequence, the frame it is from,
/// and what the tracking schedule takes from it.
#[derive(Clone, Debug)]
pub struct Previous {
    /// The curve as written ([`rebuild`]).
    pub curve: SplineCurve,
    /// The name of its frame (recorded as the next fit's `started_from`).
    pub stem: String,
    /// What the tracking schedule takes from its fit ([`tracking_state`]).
    pub state: Option<TrackState>,
    /// The band its frame left for the next one, written down (see
    /// [`crate::fit::TrackCache`]).
    pub band: Option<TrackSnapshot>,
}

/// The configuration of frames started from the previous result, and
/// whether they run the tracking schedule first, as `vicurve track
/// --track-stages` decides them: `None` keeps the first frame's stages
/// (and, when those are the default schedule on a silhouette with blur
/// correction, runs the tracking schedule first); `"default"` the whole
/// default schedule on every frame; `"R:N,..."` explicit stages.
///
/// Errors: [`crate::Error::Parse`] for stages that do not parse,
/// [`crate::Error::InvalidParameter`] for a configuration out of range.
pub fn tracked_config(
    first: &FitConfig,
    track_stages: Option<&str>,
) -> crate::Result<(FitConfig, bool)> {
    let mut tracked = first.clone();
    tracked.stages = match track_stages {
        Some("default") => None,
        Some(s) => Some(crate::fit::parse_stages(s)?),
        None => first.stages.clone(),
    };
    let schedule = track_stages.is_none()
        && first.stages.is_none()
        && first.kind == crate::virtual_image::Kind::Silhouette
        && first.blur_correction;
    tracked.validate()?;
    Ok((tracked, schedule))
}
