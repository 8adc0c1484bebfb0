//! What makes a sequence resumable: atomic writes, the job's fingerprint,
//! and reading back the frames already done.
//!
//! A frame is *done* when the summary (`summary.csv`, always rewritten
//! atomically, so a kill leaves the previous complete version) holds its
//! rows and every curve's JSON exists and carries the fingerprint of the
//! same job. Per-frame files are written to a temporary name and renamed,
//! so a file that exists is complete. A frame whose files were written but
//! whose rows had not reached the summary when the run was killed is
//! measured again (identically).
//!
//! Tracking goes on from a done frame with the curve read back from its
//! JSON. So that a resumed run gives exactly the same results as an
//! uninterrupted one, an uninterrupted run also starts each frame from the
//! previous curve *as written* ([`rebuild`] of its data): serde_json writes
//! floats in their shortest round-tripping form, so both are the same
//! numbers to the last bit.

use super::job::{CurveSpec, WidthSpec};
use crate::curve::{SplineCurve, SplineCurveData};
use crate::fit::{Outcome, TrackSnapshot, TrackState};
use crate::virtual_image::Profile;
use serde::Serialize;
use std::path::Path;

/// What defines the results of a job, and so its fingerprint: the
/// curves (start and configurations), tracking and widths; not the list of
/// images (frames can be added to a sequence and the run resumed) nor the
/// optional outputs.
#[derive(Serialize)]
pub struct Manifest<'a> {
    /// The library's version (results may change between versions).
    pub vicurve_version: &'static str,
    /// [`super::job::Job::track`].
    pub track: bool,
    /// The curves, their starts and configurations.
    pub curves: &'a [CurveSpec],
    /// The widths.
    pub widths: &'a [WidthSpec],
}

impl Manifest<'_> {
    /// The canonical JSON text.
    pub fn to_json(&self) -> String {
        serde_json::to_string_pretty(self).unwrap_or_default()
    }

    /// FNV-1a (64 bits) of [`Manifest::to_json`], in hex: stable across
    /// runs and platforms (unlike the standard library's hasher).
    pub fn fingerprint(&self) -> String {
        let mut h: u64 = 0xcbf2_9ce4_8422_2325;
        for b in self.to_json().bytes() {
            h ^= u64::from(b);
            h = h.wrapping_mul(0x0000_0100_0000_01b3);
        }
        format!("{h:016x}")
    }
}

pub use crate::sequence::{rebuild, tracking_state};

/// A done frame's curve as its JSON records it.
pub struct Recorded {
    /// Whether the fit is good enough to go on from (converged or hit its
    /// iteration limit).
    pub good: bool,
    /// The measured curve (as written).
    pub curve: SplineCurve,
    /// What the next frame's tracking schedule takes from this one
    /// ([`tracking_state`] of the recorded last band stage).
    pub state: Option<TrackState>,
    /// The band the frame left for the next one (its `sequence.track_band`).
    pub band: Option<TrackSnapshot>,
}

/// Read a curve's JSON written by this job (`fingerprint`) for the frame
/// `input` (the path as the job gives it). `None` when it is missing,
/// unreadable or from another job or frame: the frame is then measured
/// again.
pub fn read_recorded(path: &Path, fingerprint: &str, input: &str) -> Option<Recorded> {
    let text = std::fs::read_to_string(path).ok()?;
    let v: serde_json::Value = serde_json::from_str(&text).ok()?;
    if v["sequence"]["job"].as_str()? != fingerprint || v["input"]["path"].as_str()? != input {
        return None;
    }
    let status = v["outcome"]["status"].as_str()?;
    let data: SplineCurveData = serde_json::from_value(v["curve"].clone()).ok()?;
    let curve = rebuild(&data).ok()?;
    // The last band stage (a whole-object stage is redone on each frame).
    let last = v["stages"].as_array().and_then(|s| {
        s.iter()
            .rev()
            .find(|st| !st["whole_object"].as_bool().unwrap_or(false))
    });
    let state = last.and_then(|last| {
        let profile: Profile = serde_json::from_value(last["profile"].clone()).ok()?;
        let outcome: Outcome = serde_json::from_value(last["outcome"].clone()).ok()?;
        let elements = usize::try_from(last["elements"].as_u64()?).ok()?;
        let vary = v["gray_levels"]["along"]
            .as_array()
            .is_some_and(|a| !a.is_empty());
        TrackState::from_last_stage(profile, elements, outcome, curve.param_length(), vary)
    });
    // A band that cannot be read back is built anew by the next frame,
    // which then differs from an uninterrupted run in the last digits.
    let band = serde_json::from_value(v["sequence"]["track_band"].clone()).ok();
    Some(Recorded {
        good: status == "converged" || status == "iteration_limit",
        curve,
        state,
        band,
    })
}

/// Remove the temporary files of [`write_atomic`] that a killed run left
/// behind (`.NAME.tmp-PID`); files of runs still going (their process
/// alive) are not told apart, so two runs must not share an output folder.
///
/// [`write_atomic`]: crate::io::write_atomic
pub fn remove_stale_temporaries(dir: &Path) {
    let Ok(entries) = std::fs::read_dir(dir) else {
        return;
    };
    for e in entries.flatten() {
        let name = e.file_name().to_string_lossy().into_owned();
        if name.starts_with('.') && name.contains(".tmp-") && e.path().is_file() {
            let _ = std::fs::remove_file(e.path());
        }
    }
}

/// The fingerprint recorded in a manifest, if it can be read.
pub fn read_fingerprint(path: &Path) -> Option<String> {
    let text = std::fs::read_to_string(path).ok()?;
    let v: serde_json::Value = serde_json::from_str(&text).ok()?;
    v["fingerprint"].as_str().map(str::to_string)
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::curve::InitialCurve;

    #[test]
    fn curves_survive_the_json_round_trip_exactly() {
        for init in [
            InitialCurve::Circle {
                cx: 100.3,
                cy: 80.1,
                r: 37.7,
            },
            InitialCurve::Segment {
                x0: 3.1,
                y0: 7.0,
                x1: 191.3,
                y1: 40.2,
            },
        ] {
            let c = init.to_curve().unwrap();
            let text = serde_json::to_string(&c.to_data()).unwrap();
            let back: SplineCurveData = serde_json::from_str(&text).unwrap();
            let r = rebuild(&back).unwrap();
            assert_eq!(r.to_data(), c.to_data());
            assert_eq!(r, c);
        }
    }
}
