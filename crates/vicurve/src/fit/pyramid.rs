//! Coarse stages on a binned image: one level of an image pyramid.
//!
//! A coarse stage (every stage of a schedule but its last) only brings the
//! curve near the edge, from where the next, narrower band takes over
//! (method, section 6). A band of `R = 20` px holds some forty pixels
//! across, every one of which the stage projects on the curve at each of
//! its re-references; a far start walks to the edge in dozens of them.
//! The stage needs the band's reach, not its resolution, so it runs on the
//! image binned by `k`: the mean of each `k x k` block of pixels, a box
//! filter, so that every pixel's light counts (keeping one pixel in 16
//! instead misses a line narrower than 4 px and aliases a sharp edge),
//! with the band's half-width `R / k`, elements and the convergence
//! tolerance `k` times shorter, and the curve mapped to the binned image's
//! pixels. Its result, mapped back, is the next stage's reference. `k` is
//! the largest of 8, 4 and 2 that leaves a band of at least
//! [`MIN_BINNED_HALF_WIDTH`] binned pixels: the default schedule's `R =
//! 20` stage runs on 8 x 8 blocks, its `R = 10` stage on 4 x 4, and its
//! `R = 5` stage, when it is a coarse one, on 2 x 2.
//!
//! Binned pixel `(i, j)` covers the image's pixels `k i .. k i + k - 1`
//! (columns) and `k j .. k j + k - 1` (rows): its centre is at `x = k i +
//! (k - 1) / 2`. Blocks cut by the right or bottom border are left out.
//!
//! Only closed curves without corners are binned: an open curve reaches
//! the border, where the binned image has no pixel centre within `(k - 1)
//! / 2` px, and a corner's repeated knots tie the curve's parameter to the
//! image's pixels. Neither are a tracked frame (one stage, the last), an
//! automatic stage or the paper's levelset coordinates (their mesh is in
//! the image's pixels), nor a band under [`MIN_BINNED_AREA`] pixels, which
//! is cheap. A binned stage that does not complete (its band leaves the
//! binned image, it diverges) runs again on the image itself, as it would
//! have without binning. The probe ([`super::probe`]) is binned as its
//! stage is: a binned probe that does not complete says that the start is
//! too far, as the probe on the image would.

use super::schedule::{Flow, Schedule};
use super::{Elements, LevelModel, Outcome, Stage};
use crate::band::Coords;
use crate::correlation::levels::MIN_LEVEL_ELEMENT;
use crate::curve::SplineCurve;
use crate::interp::Sampler;
use crate::spline::Basis;
use std::time::Instant;

/// Narrowest band of a binned stage, in binned pixels: wider than the
/// `R = 2` px the default schedule's paper profile runs on in the image's
/// own pixels, which brings a curve a pixel or two off onto the edge. A
/// binned stage's job is the same in binned pixels.
///
/// Why not wider: a stage costs its band's pixels times its runs, and a
/// far start's runs are about as many on any binning (it re-references
/// every `0.75 R` of the walk), so twice the binning leaves a quarter of
/// the band's pixels to each run, at the same accuracy on the conformance
/// sweep (docs/benchmarks.md, "Coarse stages on 8 x 8 blocks").
const MIN_BINNED_HALF_WIDTH: f64 = 2.5;

/// Binnings tried, largest first.
const BINNINGS: [usize; 3] = [8, 4, 2];

/// Smallest band (pixels of the image: twice the half-width times the
/// curve's length) that a stage bins: a smaller one is cheap to build and
/// iterate on, so binning saves little, and the image's own pixels hold
/// the most information.
const MIN_BINNED_AREA: f64 = 16384.0;

/// Smallest side of a binned image, binned pixels: a smaller image has no
/// room for a band of [`MIN_BINNED_HALF_WIDTH`] around a curve.
const MIN_BINNED_SIDE: usize = 16;

/// The image of `sampler` binned by `k` (the mean of each `k x k` block of
/// its pixels), prepared with the same interpolation; `None` when a side
/// of the binned image would be under [`MIN_BINNED_SIDE`], or `sampler` is
/// a binned level itself.
fn binned(sampler: &Sampler, k: usize) -> Option<Sampler> {
    let (w, h) = (sampler.width() / k, sampler.height() / k);
    if w < MIN_BINNED_SIDE || h < MIN_BINNED_SIDE {
        return None;
    }
    let (pixels, stride) = (sampler.image_pixels(), sampler.width());
    if pixels.len() != stride * sampler.height() {
        return None;
    }
    let scale = 1.0 / (k * k) as f64;
    Some(Sampler::binned_level(w, h, sampler.kind(), |j, row| {
        for dy in 0..k {
            let line = &pixels[(j * k + dy) * stride..][..w * k];
            for (v, block) in row.iter_mut().zip(line.chunks_exact(k)) {
                *v += block.iter().sum::<f64>();
            }
        }
        row.iter_mut().for_each(|v| *v *= scale);
    }))
}

/// `curve` mapped by `x -> scale x + offset` (both coordinates), its
/// parameter scaled with it (so that it stays about the arc length);
/// `None` for a curve with corners or breaks (see the module docs).
fn mapped(curve: &SplineCurve, scale: f64, offset: f64) -> Option<SplineCurve> {
    let b = curve.basis();
    if !b.breaks().is_empty() {
        return None;
    }
    let basis = Basis::new(
        b.degree(),
        b.n_elements(),
        b.length() * scale,
        b.is_closed(),
    )
    .ok()?;
    let ctrl = curve
        .control_points()
        .iter()
        .map(|p| [scale * p[0] + offset, scale * p[1] + offset])
        .collect();
    SplineCurve::new(basis, ctrl).ok()
}

/// `curve` in the pixels of the image binned by `k`.
fn to_binned(curve: &SplineCurve, k: usize) -> Option<SplineCurve> {
    let k = k as f64;
    mapped(curve, 1.0 / k, -(k - 1.0) / (2.0 * k))
}

/// `curve` from the pixels of the image binned by `k` back to the image's.
fn from_binned(curve: &SplineCurve, k: usize) -> Option<SplineCurve> {
    let k = k as f64;
    mapped(curve, k, (k - 1.0) / 2.0)
}

/// `stage` on the image binned by `k`: half-width and element length
/// divided by `k` (an element count stays).
fn binned_stage(stage: &Stage, k: usize) -> Stage {
    let k = k as f64;
    Stage {
        half_width: stage.half_width / k,
        elements: match stage.elements {
            Elements::Length(h) => Elements::Length(h / k),
            other => other,
        },
    }
}

/// What a binned stage's schedule hands back.
struct BinnedRun {
    /// Its result, in the image's pixels.
    current: SplineCurve,
    /// Its reports.
    reports: Vec<super::StageReport>,
    /// Its outcome (converged or at its iteration limit).
    outcome: Outcome,
    /// Whether it dropped the varying gray levels.
    global_levels: bool,
}

impl Schedule<'_> {
    /// Run `stage` (not the last: `is_last` false) on a binned image when
    /// it may ([`Self::binning`]): `Some` of how it ended when it completed,
    /// the result the new reference; `None` when it may not or did not
    /// complete (then nothing changed, and the caller runs it on the
    /// image itself).
    pub(super) fn run_binned(&mut self, stage: &Stage, is_last: bool) -> Option<Flow> {
        let k = self.binning(stage, is_last);
        if k == 1 {
            return None;
        }
        let started = Instant::now();
        let level = self.level(k)?;
        let preparation = started.elapsed().as_secs_f64();
        let run = self.binned_run(stage, k, level)?;
        self.current = run.current;
        // The binned stage's system is not the image's: the next stage's
        // first band is built afresh, and should a later stage fail, the
        // binned result stands as the curve reached (`Schedule::finish`).
        self.last = None;
        self.binned_done = true;
        self.outcome = run.outcome;
        if run.global_levels {
            self.config.levels = LevelModel::Global;
        }
        let kf = k as f64;
        for (i, mut report) in run.reports.into_iter().enumerate() {
            report.half_width = stage.half_width;
            report.binning = k;
            if i == 0 {
                report.seconds += preparation;
            }
            for h in &mut report.history {
                h.max_step *= kf;
            }
            self.reports.push(report);
        }
        Some(Flow::Completed)
    }

    /// The binning of `stage`: the largest of [`BINNINGS`] that leaves a
    /// band of [`MIN_BINNED_HALF_WIDTH`], when the stage and the current
    /// curve may be binned (see the module docs) and its band covers
    /// [`MIN_BINNED_AREA`]; else 1.
    pub(super) fn binning(&self, stage: &Stage, is_last: bool) -> usize {
        let curve = &self.current;
        let eligible = !is_last
            && self.tracked.is_none()
            && curve.is_closed()
            && curve.corners().is_empty()
            && curve.basis().breaks().is_empty()
            && self.config.coords == Coords::Exact
            && !matches!(stage.elements, Elements::Auto { .. });
        let area = 2.0 * stage.half_width * curve.arc_length();
        if !eligible || area < MIN_BINNED_AREA {
            return 1;
        }
        BINNINGS
            .into_iter()
            .find(|&k| stage.half_width / k as f64 >= MIN_BINNED_HALF_WIDTH)
            .unwrap_or(1)
    }

    /// The index in `self.binned` of the image binned by `k`, made on
    /// first use; `None` when the image is too small to bin.
    fn level(&mut self, k: usize) -> Option<usize> {
        if let Some(i) = self.binned.iter().position(|(b, _)| *b == k) {
            return Some(i);
        }
        let sampler = binned(self.sampler, k)?;
        self.binned.push((k, sampler));
        Some(self.binned.len() - 1)
    }

    /// `stage` run as the one stage of a schedule on the image binned by
    /// `k` (`self.binned[level]`), from the current curve; `None` unless it
    /// completed without diverging.
    fn binned_run(&self, stage: &Stage, k: usize, level: usize) -> Option<BinnedRun> {
        let start = to_binned(&self.current, k)?;
        let mut config = self.config.clone();
        config.stages = Some(vec![binned_stage(stage, k)]);
        // Its result is only the next stage's reference.
        config.blur_correction = false;
        // Converged as the stage on the image would be, in its pixels.
        config.tolerance /= k as f64;
        if let LevelModel::Varying { element_length } = config.levels {
            config.levels = LevelModel::Varying {
                element_length: (element_length / k as f64).max(MIN_LEVEL_ELEMENT),
            };
        }
        let mut sub = Schedule::new(&self.binned[level].1, start, &config, None, None).ok()?;
        // The element floor of the schedule it stands in.
        sub.min_el = self.min_el;
        sub.coarse = true;
        // A probe stops at its first new reference, binned or not.
        sub.probing = self.probing;
        sub.run().ok()?;
        if sub.last.is_none() || matches!(sub.outcome, Outcome::Diverged { .. }) {
            return None;
        }
        let global_levels =
            sub.config.levels == LevelModel::Global && self.config.levels != LevelModel::Global;
        Some(BinnedRun {
            current: from_binned(&sub.current, k)?,
            reports: sub.reports,
            outcome: sub.outcome,
            global_levels,
        })
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::image::Image;
    use crate::interp::Interpolation;

    /// A binned pixel is the mean of its block; blocks cut by the border
    /// are left out.
    #[test]
    fn a_binned_pixel_is_its_block_s_mean() {
        let image = Image::from_fn(10, 9, |x, y| (x + 10 * y) as f64);
        let sampler = Sampler::new(&image, Interpolation::Bilinear);
        assert!(binned(&sampler, 2).is_none(), "under the smallest side");
        let big = Image::from_fn(66, 35, |x, y| (x * x + 7 * y) as f64);
        let sampler = Sampler::new(&big, Interpolation::Bilinear);
        let b = binned(&sampler, 2).unwrap();
        assert_eq!((b.width(), b.height()), (33, 17));
        assert!(
            binned(&b, 2).is_none(),
            "a binned level is not binned again"
        );
        for (i, j) in [(0, 0), (5, 3), (32, 16)] {
            let (x, y) = (2 * i, 2 * j);
            let mean = [(x, y), (x + 1, y), (x, y + 1), (x + 1, y + 1)]
                .iter()
                .map(|&(x, y)| (x * x + 7 * y) as f64)
                .sum::<f64>()
                / 4.0;
            assert_eq!(b.pixel(i, j), Some(mean));
        }
    }

    /// Mapped to a binned image and back, a curve is the same curve; in
    /// between, a block's centre is where its pixels' centres average.
    #[test]
    fn a_curve_maps_to_the_binned_pixels_and_back() {
        let circle = crate::curve::InitialCurve::Circle {
            cx: 200.0,
            cy: 150.0,
            r: 80.0,
        }
        .to_curve()
        .unwrap();
        for k in [2, 4] {
            let coarse = to_binned(&circle, k).unwrap();
            let kf = k as f64;
            let centre = (kf - 1.0) / 2.0;
            for u in [0.0, 0.3, 0.77] {
                let p = circle.point(u * circle.param_length());
                let q = coarse.point(u * coarse.param_length());
                assert!((kf * q[0] + centre - p[0]).abs() < 1e-9);
                assert!((kf * q[1] + centre - p[1]).abs() < 1e-9);
            }
            assert!((coarse.arc_length() * kf - circle.arc_length()).abs() < 1e-6);
            let back = from_binned(&coarse, k).unwrap();
            for (a, b) in back.control_points().iter().zip(circle.control_points()) {
                assert!((a[0] - b[0]).abs() < 1e-9 && (a[1] - b[1]).abs() < 1e-9);
            }
        }
    }
}
