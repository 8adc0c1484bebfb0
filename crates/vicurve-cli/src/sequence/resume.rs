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
use serde::Serialize;
use std::path::Path;
use vicurve::curve::{SplineCurve, SplineCurveData};
use vicurve::fit::{Measurement, Outcome, TrackSnapshot, TrackState};
use vicurve::spline::Basis;
use vicurve::virtual_image::Profile;

/// What defines the results of a job, and so its fingerprint: the
/// curves (start and configurations), tracking and widths; not the list of
/// images (frames can be added to a sequence and the run resumed) nor the
/// optional outputs.
#[derive(Serialize)]
pub struct Manifest<'a> {
    pub vicurve_version: &'static str,
    pub track: bool,
    pub curves: &'a [CurveSpec],
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

/// The B-spline described by `data` (as [`SplineCurve::to_data`] writes
/// it: a closed curve's first `degree` control points repeated at the end).
pub fn rebuild(data: &SplineCurveData) -> Result<SplineCurve, String> {
    let p = data.degree;
    let bad = |why: &str| format!("the recorded curve is not usable: {why}");
    if data.knots.len() < 2 * p + 2 {
        return Err(bad("too few knots"));
    }
    let n_el = data.knots.len() - 2 * p - 1;
    // Knots are (i - p) h with h = L / n, so knot p + n is L to within an
    // ulp or two: the length whose basis gives the recorded knots exactly
    // is among its neighbours (the same L when the file was written from a
    // basis; else the nearest, within 1e-12 relative).
    let guess = data.knots[p + n_el];
    if !(guess.is_finite() && guess > 0.0) {
        return Err(bad("the knots do not span a positive length"));
    }
    let mut best: Option<(f64, Basis)> = None;
    for k in -4i64..=4 {
        let length = f64::from_bits((guess.to_bits() as i64 + k) as u64);
        let basis = Basis::new(p, n_el, length, data.closed).map_err(|e| bad(&e.to_string()))?;
        let err = basis
            .knots()
            .iter()
            .zip(&data.knots)
            .map(|(a, b)| (a - b).abs())
            .fold(0.0, f64::max);
        if best.as_ref().is_none_or(|b| err < b.0) {
            best = Some((err, basis));
        }
    }
    let (err, basis) = best.ok_or_else(|| bad("no basis"))?;
    if err > 1e-12 * guess {
        return Err(bad("non-uniform knots"));
    }
    let mut ctrl = data.control_points.clone();
    if data.closed {
        ctrl.truncate(ctrl.len().saturating_sub(p));
    }
    SplineCurve::new(basis, ctrl).map_err(|e| bad(&e.to_string()))
}

/// A done frame's curve as its JSON records it.
pub struct Recorded {
    /// Whether the fit is good enough to go on from (converged or hit its
    /// iteration limit).
    pub good: bool,
    /// The measured curve (as written).
    pub curve: SplineCurve,
    /// What the next frame's tracking schedule takes from this one
    /// ([`tracking_state`] of the recorded last stage).
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
    let last = v["stages"].as_array().and_then(|s| s.last());
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

/// What the frame after `m` takes from it for the tracking schedule, `m`'s
/// curve being `written` as read back ([`rebuild`]): computed as
/// [`read_recorded`] does from the JSON, so that a resumed run goes on
/// exactly as an uninterrupted one.
pub fn tracking_state(m: &Measurement, written: &SplineCurve) -> Option<TrackState> {
    let last = m.stages.last()?;
    TrackState::from_last_stage(
        last.profile,
        last.elements,
        last.outcome,
        written.param_length(),
        !m.levels.is_empty(),
    )
}

/// Remove the temporary files of [`write_atomic`] that a killed run left
/// behind (`.NAME.tmp-PID`); files of runs still going (their process
/// alive) are not told apart, so two runs must not share an output folder.
///
/// [`write_atomic`]: crate::output::write_atomic
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
    use vicurve::curve::InitialCurve;

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
