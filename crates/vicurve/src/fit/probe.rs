//! The first stage chosen from the start: a start already within reach of
//! the default schedule's last coarse band needs none of the wider ones.
//!
//! Wide bands exist to bring a far start near the edge (method, section
//! 6); from a start a pixel or two off they cost most of a fit's time and
//! change its result by less than the settling tolerance, since every
//! stage converges on its own reference and the last ones settle to a
//! fixed point whatever the start. So the default schedule first runs its
//! last coarse stage (the probe) from the start, and keeps it only when
//! that stage completes without needing a new reference: its first run's
//! displacement stayed under the re-referencing fraction of `R` everywhere
//! and its band saw the edge everywhere (no lost run), and it converged.
//! The stage then runs once more, from the probe's result: a stage is
//! linearised about its reference, and the probe's reference (the start)
//! was as far from the edge as the start, where the wider stages would
//! have handed that stage a reference within a fraction of a pixel; the
//! last stages choose their elements on the result, and a curve still a
//! linearisation error off makes them choose shorter ones than the edge
//! needs. Otherwise (the start is farther than the band reaches somewhere, or the
//! probe could not run at all) everything the probe did is undone and the
//! schedule runs from its first stage, as it would have without the probe;
//! the cost is the probe's one band and a few iterations. A long curve's
//! probe runs on the image binned as its stage is ([`super::pyramid`]),
//! on a quarter of the band's pixels.
//!
//! Only the default schedule probes (the stages a user gives all run), and
//! not a tracked frame (its schedule has one stage).

use super::reference::Ends;
use super::schedule::{Flow, Schedule};
use super::{LevelModel, Outcome};
use crate::curve::SplineCurve;
use crate::error::Result;

/// What the probe may change, to undo it.
struct Saved {
    current: SplineCurve,
    trimmed: Option<(SplineCurve, Ends)>,
    levels: LevelModel,
    reports: usize,
    skipped: usize,
    binned_done: bool,
}

impl Schedule<'_> {
    /// The index of the first stage to run: the probe's stage again, from
    /// the probe's result, when the probe completed (the wider stages
    /// recorded as skipped), else 0 with the probe undone.
    pub(super) fn probe(&mut self) -> Result<usize> {
        let Some(k) = self.probe_stage() else {
            return Ok(0);
        };
        let stage = self.stages[k];
        let saved = Saved {
            current: self.current.clone(),
            trimmed: self.trimmed.clone(),
            levels: self.config.levels,
            reports: self.reports.len(),
            skipped: self.skipped.len(),
            binned_done: self.binned_done,
        };
        self.probing = true;
        // A long curve's probe runs on the binned image, as its stage then
        // does (`super::pyramid`): the same reach in the image's pixels
        // for a quarter of the band's pixels. A binned probe that does
        // not complete leaves the start too far.
        let flow = if self.binning(&stage, false) > 1 {
            Ok(self.run_binned(&stage, false).unwrap_or(Flow::TooFar))
        } else {
            self.run_stage(&stage, false)
        };
        self.probing = false;
        match flow? {
            Flow::Completed if self.outcome == Outcome::Converged => {
                let r = stage.half_width;
                let wider: Vec<String> = self.stages[..k]
                    .iter()
                    .map(|s| {
                        format!(
                            "R = {} px: the start is within reach of R = {r} px",
                            s.half_width
                        )
                    })
                    .collect();
                self.skipped.splice(saved.skipped..saved.skipped, wider);
                Ok(k)
            }
            _ => {
                self.undo_probe(saved);
                Ok(0)
            }
        }
    }

    /// The stage to probe with: the default schedule's last coarse stage,
    /// when wider ones precede it and its band suits the curve; none for a
    /// tracked frame or stages the user gave.
    fn probe_stage(&self) -> Option<usize> {
        if !self.auto || self.tracked.is_some() || self.stages.len() < 3 {
            return None;
        }
        let k = self.stages.len() - 2;
        let r = self.stages[k].half_width;
        let wider = self.stages[..k].iter().any(|s| s.half_width > r);
        (wider && self.fits_band(r)).then_some(k)
    }

    /// Everything as it was before the probe.
    fn undo_probe(&mut self, saved: Saved) {
        self.current = saved.current;
        self.trimmed = saved.trimmed;
        self.config.levels = saved.levels;
        self.reports.truncate(saved.reports);
        self.skipped.truncate(saved.skipped);
        self.binned_done = saved.binned_done;
        self.last = None;
        self.final_ends = Ends::default();
        self.outcome = Outcome::Converged;
    }
}
