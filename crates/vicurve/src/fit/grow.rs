//! Segment-by-segment start (the paper's reference 18): measure a short
//! piece of the curve, extend both ends, measure again, until the curve
//! reaches the image border, closes on itself, stops being an edge (or
//! line), or is as long as asked.
//!
//! 1. The start (a segment or an open polyline near the curve) is measured
//!    with the caller's configuration.
//! 2. Each end is extended by an arc that continues the measured curve: the
//!    heading and curvature of a quadratic fitted to the last 6 to 40 px of
//!    the samples in the end's frame. The extension is cut where its band
//!    would leave the image (`R + border_gap` px from the border).
//! 3. The end's last 60 px and its extension are measured alone, with a
//!    short schedule (bands of `max(2 R_p, 6)` and `R_p` px, `R_p` the last
//!    plain band of the first measurement; elements of 40 and 20 px; one
//!    global pair of gray levels; no blur stage): the extension is at most
//!    a few pixels off the edge, and the final measurement (step 5) brings
//!    the full precision. Each step costs the length it adds, not the
//!    curve's.
//! 4. A step is kept when the fit converges and the new end still sees the
//!    edge: its local contrast (the virtual profile of the kind fitted to
//!    the image across the curve, `c` of `a + c gamma(r / R_p)`, median over
//!    the new part) keeps the sign and at least `min_contrast` of the
//!    contrast of the 40 px of curve before it. The new measurement then
//!    replaces the old end's last 30 px (measured less well before: an open
//!    end's band is cut) and the extension, and the end's next step is 1.5
//!    times longer (up to `max_step`); otherwise the step is halved, and an
//!    end whose step falls under `min_step` is where the edge ends. The two
//!    ends take turns. When they head towards each other, each step stops
//!    short of half the gap between them; once the gap is within the
//!    growing band (`max(2 R_p, 6)` px), or the new end has run onto the
//!    other end, the points are closed into a loop and measured as a closed
//!    curve. An edge that stops short of closing (a C) ends first.
//! 5. The grown curve (open or closed) is measured with the caller's
//!    configuration.
//!
//! Edge cases: a closed start is an error (it has no ends); a start that
//! does not converge is returned as measured, not grown (its outcome says
//! why); an edge that forks follows the branch nearest the extrapolated
//! arc; a corner sharper than the band can follow (a turn of about 60 deg
//! within a step) ends the growth there, as the edge "ends" for a smooth
//! extension. Everything is in pixels.

use super::{measure_from, Elements, FitConfig, LevelModel, Measurement, Stage};
use crate::curve::{dist, SplineCurve};
use crate::error::{Error, Result};
use crate::interp::Sampler;
use crate::virtual_image::{Kind, Profile};
use serde::{Deserialize, Serialize};

/// Samples of the curve's end used for its heading and curvature, pixels.
const END_WINDOW_MAX: f64 = 40.0;
/// See [`END_WINDOW_MAX`].
const END_WINDOW_MIN: f64 = 6.0;
/// The extrapolated curvature is clipped to this, 1/px (a radius of 10 px:
/// tighter bends come from noise on a short window).
const MAX_CURVATURE: f64 = 0.1;
/// Length of old curve whose contrast a new end is compared with, pixels.
const CONTRAST_WINDOW: f64 = 40.0;
/// Length of old curve measured again with each extension, pixels; the
/// half of it nearest the old end is replaced by the new measurement
/// (open ends are measured less well: their band is cut).
const FIT_WINDOW: f64 = 60.0;
/// Spacing of the points along the curve's normal where the local contrast
/// is fitted, pixels.
const PROBE_STEP: f64 = 0.5;
/// Control-point spacing of the curves rebuilt from samples, pixels.
const REBUILD_SPACING: f64 = 2.0;
/// Two measured pieces of curve closer than this are the same edge,
/// pixels (the curve has come round onto itself).
const OVERLAP_DISTANCE: f64 = 1.0;
/// Growth factor of an end's step after a success.
const STEP_GROWTH: f64 = 1.5;

/// How to grow a curve from a short start. Every length is in pixels.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
#[serde(default)]
pub struct GrowConfig {
    /// Stop when the curve is this long. Default: `None`, grow until the
    /// border, a closed loop or the end of the edge.
    pub max_length: Option<f64>,
    /// First extension of each end. Default: 20 px.
    pub first_step: f64,
    /// Longest extension of an end in one step. Default: 160 px.
    pub max_step: f64,
    /// An end whose step has been halved under this is where the edge
    /// ends. Default: 4 px.
    pub min_step: f64,
    /// Space kept between the widest growing band and the image border.
    /// Default: 2 px.
    pub border_gap: f64,
    /// A new end must keep this fraction of the local contrast of the
    /// curve before it. Default: 0.5.
    pub min_contrast: f64,
    /// Growing steps (kept or not) at most. Default: 400.
    pub max_steps: usize,
}

impl Default for GrowConfig {
    fn default() -> Self {
        GrowConfig {
            max_length: None,
            first_step: 20.0,
            max_step: 160.0,
            min_step: 4.0,
            border_gap: 2.0,
            min_contrast: 0.5,
            max_steps: 400,
        }
    }
}

impl GrowConfig {
    /// Check every field; errors name the field and the accepted range.
    pub fn validate(&self) -> Result<()> {
        let positive = |v: f64| v.is_finite() && v > 0.0;
        if let Some(l) = self.max_length {
            if !positive(l) {
                return Err(Error::invalid(
                    "grow length",
                    format!("{l} (must be > 0 px)"),
                ));
            }
        }
        if !(positive(self.min_step)
            && self.first_step.is_finite()
            && self.max_step.is_finite()
            && self.min_step <= self.first_step
            && self.first_step <= self.max_step)
        {
            return Err(Error::invalid(
                "grow steps",
                format!(
                    "min {}, first {}, max {} px (need 0 < min <= first <= max)",
                    self.min_step, self.first_step, self.max_step
                ),
            ));
        }
        if !(self.border_gap.is_finite() && self.border_gap >= 0.0) {
            return Err(Error::invalid(
                "grow border gap",
                format!("{} (must be >= 0 px)", self.border_gap),
            ));
        }
        if !(self.min_contrast.is_finite() && (0.0..1.0).contains(&self.min_contrast)) {
            return Err(Error::invalid(
                "grow contrast",
                format!("{} (must be in [0, 1))", self.min_contrast),
            ));
        }
        if self.max_steps == 0 {
            return Err(Error::invalid("grow max_steps", "0 (must be >= 1)"));
        }
        Ok(())
    }
}

/// Why an end of the curve stopped growing.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Serialize, Deserialize)]
#[serde(rename_all = "snake_case")]
pub enum EndReason {
    /// Its band reached the image border.
    Border,
    /// The edge (or line) ends there: no extension, however short, kept its
    /// contrast or converged.
    EdgeEnds,
    /// The curve reached the length asked for.
    Length,
    /// The two ends met and the curve was closed.
    Closed,
    /// The two ends met but the closed curve did not converge; the open
    /// curve is the result.
    MetUnclosed,
    /// The step limit was reached.
    StepLimit,
    /// The start itself did not converge: nothing was grown.
    StartFailed,
}

/// One growing step: one end extended and measured.
#[derive(Clone, Copy, Debug, PartialEq, Serialize, Deserialize)]
pub struct GrowStep {
    /// Which end: 0 the start of the curve, 1 its end.
    pub end: usize,
    /// Length of the curve before the step, pixels.
    pub length: f64,
    /// Extension tried, pixels.
    pub extended: f64,
    /// Whether the step was kept.
    pub kept: bool,
}

/// How the curve grew.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub struct GrowReport {
    /// The growing configuration.
    pub config: GrowConfig,
    /// Why the start and the end of the curve stopped (both
    /// [`EndReason::Closed`] for a closed result).
    pub ends: [EndReason; 2],
    /// Every step, in order.
    pub steps: Vec<GrowStep>,
}

/// A grown curve's final measurement and how it grew.
#[derive(Clone, Debug)]
pub struct Grown {
    /// The measurement of the grown curve with the caller's configuration.
    pub measurement: Measurement,
    /// How it grew.
    pub report: GrowReport,
}

/// Grow the curve from the open `start` (module docs) and measure it.
///
/// Errors: an invalid configuration, a closed start, and the errors of
/// [`measure_from`] on the start and on the final curve.
pub fn grow(
    sampler: &Sampler,
    start: SplineCurve,
    config: &FitConfig,
    grow: &GrowConfig,
) -> Result<Grown> {
    check_start(&start, config, grow)?;
    let first = measure_from(sampler, start, config)?;
    let mut report = GrowReport {
        config: grow.clone(),
        ends: [EndReason::StartFailed; 2],
        steps: Vec::new(),
    };
    if !first.outcome.is_converged() {
        return Ok(Grown {
            measurement: first,
            report,
        });
    }
    let mut growth = Growth::new(sampler, config, grow, &first);
    growth.run(&mut report);
    let reference = match growth.closed {
        Some(m) => {
            report.ends = [EndReason::Closed; 2];
            m.curve
        }
        None => {
            report.ends = growth.ends.map(|e| e.unwrap_or(EndReason::StepLimit));
            SplineCurve::fit(&growth.chain.points(), false, 3, REBUILD_SPACING)?
        }
    };
    let measurement = measure_from(sampler, reference, config)?;
    Ok(Grown {
        measurement,
        report,
    })
}

/// The errors of [`grow`]'s inputs: the configurations, a closed start,
/// breaks.
fn check_start(start: &SplineCurve, config: &FitConfig, grow: &GrowConfig) -> Result<()> {
    grow.validate()?;
    config.validate()?;
    if start.is_closed() {
        return Err(Error::invalid(
            "grow",
            "the start is closed and has no ends to grow: start from a segment or an open polyline",
        ));
    }
    if !config.breaks.is_empty() {
        // Break positions are arc lengths along the initial curve, which
        // growing replaces.
        return Err(Error::invalid(
            "grow",
            "breaks (corners) cannot be combined with growing: their positions are along the initial curve; measure the grown curve again with the breaks",
        ));
    }
    Ok(())
}

/// The state of the growth (steps 2 to 4 of the module docs).
struct Growth<'a> {
    sampler: &'a Sampler,
    grow: &'a GrowConfig,
    /// The short schedule of the steps.
    step_config: FitConfig,
    /// The growing band's half-width, pixels: ends closer than this close
    /// the loop.
    reach: f64,
    /// Extensions stay this far from the image border, pixels.
    margin: f64,
    probe: Probe<'a>,
    chain: Chain,
    /// Each end's next step, pixels.
    steps: [f64; 2],
    /// Why each end stopped, once it has.
    ends: [Option<EndReason>; 2],
    /// The closed curve, when the ends met.
    closed: Option<Measurement>,
    /// Steps left.
    budget: usize,
}

impl<'a> Growth<'a> {
    fn new(
        sampler: &'a Sampler,
        config: &FitConfig,
        grow: &'a GrowConfig,
        first: &Measurement,
    ) -> Self {
        let probe_width = probe_half_width(first);
        let reach = (2.0 * probe_width).max(6.0);
        Growth {
            sampler,
            grow,
            step_config: step_config(config, probe_width),
            reach,
            margin: reach + grow.border_gap,
            probe: Probe {
                sampler,
                kind: config.kind,
                half_width: probe_width,
            },
            chain: Chain::of(first),
            steps: [grow.first_step; 2],
            ends: [None, None],
            closed: None,
            budget: grow.max_steps,
        }
    }

    /// The ends take turns until both have stopped, they meet or the
    /// steps run out.
    fn run(&mut self, report: &mut GrowReport) {
        while self.budget > 0 && self.ends.iter().any(Option::is_none) {
            // The ends meet: close the loop. Only over a gap the band
            // bridges: the steps shrink towards each other (below) until
            // then, and an edge that stops short of closing (a C) ends its
            // growth first.
            let meeting = self.chain.meeting();
            if let Some(gap) = meeting {
                if gap <= self.reach && self.ends.iter().all(Option::is_none) {
                    self.close(&self.chain.points());
                    return;
                }
            }
            for e in 0..2 {
                if self.ends[e].is_some() {
                    continue;
                }
                if self.budget == 0 {
                    return;
                }
                self.budget -= 1;
                if !self.step(e, meeting, report) {
                    return;
                }
            }
        }
    }

    /// Measure `ring` as a closed curve: the grown loop, or both ends met
    /// unclosed when it does not converge.
    fn close(&mut self, ring: &[[f64; 2]]) {
        let loop_fit = SplineCurve::fit(ring, true, 3, REBUILD_SPACING)
            .and_then(|c| measure_from(self.sampler, c, &self.step_config));
        match loop_fit {
            Ok(m) if m.outcome.is_converged() => self.closed = Some(m),
            _ => self.ends = [Some(EndReason::MetUnclosed); 2],
        }
    }

    /// One step of end `e` (`meeting`: the gap when the ends head towards
    /// each other). Returns whether the growth goes on.
    fn step(&mut self, e: usize, meeting: Option<f64>, report: &mut GrowReport) -> bool {
        let length = self.chain.length();
        let remaining = self.grow.max_length.map_or(f64::INFINITY, |l| l - length);
        if remaining < 1.0 {
            self.ends.iter_mut().for_each(|e| {
                e.get_or_insert(EndReason::Length);
            });
            return false;
        }
        let active = self.ends.iter().filter(|e| e.is_none()).count() as f64;
        let mut len = self.steps[e].min(remaining / active);
        if let Some(gap) = meeting {
            // Heading towards each other: stop short of crossing.
            len = len.min(0.45 * gap);
        }
        let (margin, w, h) = (
            self.margin,
            self.sampler.width() as f64,
            self.sampler.height() as f64,
        );
        let inside = |p: [f64; 2]| {
            p[0] >= margin && p[1] >= margin && p[0] <= w - 1.0 - margin && p[1] <= h - 1.0 - margin
        };
        let ext = self.chain.extension(e, len, inside);
        if ext.is_empty() {
            self.ends[e] = Some(EndReason::Border);
            return true;
        }
        let extended = ext.len() as f64 * len / len.ceil().max(1.0);
        let kept = self.try_extension(e, &ext, extended);
        report.steps.push(GrowStep {
            end: e,
            length,
            extended,
            kept,
        });
        if kept {
            self.steps[e] = (self.steps[e] * STEP_GROWTH).min(self.grow.max_step);
            // The new end runs onto the other end: a loop.
            if let Some(ring) = self.chain.overlap(e, extended + FIT_WINDOW) {
                self.close(&ring);
                return false;
            }
        } else {
            self.steps[e] = 0.5 * self.steps[e].min(extended);
            if self.steps[e] < self.grow.min_step {
                self.ends[e] = Some(EndReason::EdgeEnds);
            }
        }
        true
    }

    /// Measure end `e`'s last `FIT_WINDOW` px with the extension `ext`
    /// (`extended` px long), in the curve's direction, and splice it in
    /// when it converges and still sees the edge (step 4). Returns whether
    /// it was kept.
    fn try_extension(&mut self, e: usize, ext: &[[f64; 2]], extended: f64) -> bool {
        let old = self.chain.end_part(e, FIT_WINDOW);
        let mut points: Vec<[f64; 2]> = Vec::with_capacity(old.len() + ext.len());
        if e == 0 {
            points.extend(ext.iter().rev());
            points.extend(old.iter().map(|q| q.p));
        } else {
            points.extend(old.iter().rev().map(|q| q.p));
            points.extend(ext.iter());
        }
        let trial = SplineCurve::fit(&points, false, 3, REBUILD_SPACING)
            .and_then(|c| measure_from(self.sampler, c, &self.step_config));
        let Ok(m) = &trial else { return false };
        if !m.outcome.is_converged() {
            return false;
        }
        let new = Chain::of(m);
        let before = self.probe.median(&self.chain.end_part(e, CONTRAST_WINDOW));
        // The measured end sits where the extension ended, give or take a
        // pixel: judge the extension at least 1 px in.
        let after = self
            .probe
            .median(&new.end_part(e, (extended - 1.0).max(1.0)));
        let ok = match (before, after) {
            (Some(b), Some(a)) => b != 0.0 && a * b.signum() >= self.grow.min_contrast * b.abs(),
            _ => false,
        };
        if ok {
            self.chain.splice(e, &new, extended + 0.5 * FIT_WINDOW);
        }
        ok
    }
}

/// The last band of the first measurement with the kind's own profile or
/// the pixel line (a line's width and blur; 2 px for a sharp edge), at
/// least 2 px.
fn probe_half_width(m: &Measurement) -> f64 {
    m.stages
        .iter()
        .rev()
        .find(|s| matches!(s.profile, Profile::Paper { .. } | Profile::PixelLine { .. }))
        .map_or(2.0, |s| s.half_width)
        .max(2.0)
}

/// The short schedule of the growing steps (module docs).
fn step_config(config: &FitConfig, probe: f64) -> FitConfig {
    let stage = |half_width: f64, h: f64| Stage {
        half_width,
        elements: Elements::Length(h),
    };
    FitConfig {
        stages: Some(vec![
            stage((2.0 * probe).max(6.0), 40.0),
            stage(probe, 20.0),
        ]),
        blur_correction: false,
        levels: LevelModel::Global,
        ..config.clone()
    }
}

/// A point of the growing curve and its unit normal.
#[derive(Clone, Copy, Debug)]
struct Point {
    p: [f64; 2],
    n: [f64; 2],
}

/// The growing curve: measured points about 1 px apart, in the curve's
/// direction, the new ends spliced onto the old middle.
struct Chain {
    points: Vec<Point>,
}

impl Chain {
    fn of(m: &Measurement) -> Chain {
        Chain {
            points: m
                .samples
                .iter()
                .map(|s| Point {
                    p: [s.x, s.y],
                    n: [s.nx, s.ny],
                })
                .collect(),
        }
    }

    fn points(&self) -> Vec<[f64; 2]> {
        self.points.iter().map(|q| q.p).collect()
    }

    fn length(&self) -> f64 {
        self.points.windows(2).map(|w| dist(w[0].p, w[1].p)).sum()
    }

    /// The points within `reach` px (along the chain) of end `e` (0: start,
    /// 1: end), ordered from that end inwards.
    fn end_part(&self, e: usize, reach: f64) -> Vec<Point> {
        let mut out = Vec::new();
        let mut travelled = 0.0;
        let mut previous: Option<[f64; 2]> = None;
        let ordered: Box<dyn Iterator<Item = &Point>> = if e == 0 {
            Box::new(self.points.iter())
        } else {
            Box::new(self.points.iter().rev())
        };
        for q in ordered {
            if let Some(p) = previous {
                travelled += dist(p, q.p);
            }
            if travelled > reach {
                break;
            }
            out.push(*q);
            previous = Some(q.p);
        }
        out
    }

    /// Replace end `e` by the part of `new` within `reach` px of its end
    /// `e`, joined where the old chain passes nearest to it.
    fn splice(&mut self, e: usize, new: &Chain, reach: f64) {
        let piece = new.end_part(e, reach);
        let Some(joint) = piece.last() else { return };
        let nearest = |range: &mut dyn Iterator<Item = usize>| {
            range.min_by(|&a, &b| {
                dist(self.points[a].p, joint.p).total_cmp(&dist(self.points[b].p, joint.p))
            })
        };
        let n = self.points.len();
        // Only the old end's points (the other end may be near on a loop).
        let m = self.end_part(e, reach + 10.0).len();
        if e == 0 {
            let k = nearest(&mut (0..m)).unwrap_or(0);
            // From the start inwards is the curve's direction already.
            let mut out = piece.clone();
            out.extend_from_slice(&self.points[(k + 1).min(n)..]);
            self.points = out;
        } else {
            let k = nearest(&mut (n - m..n)).unwrap_or(n);
            self.points.truncate(k);
            self.points.extend(piece.iter().rev());
        }
    }

    /// When end `e`'s last `reach` px run within `OVERLAP_DISTANCE` of the
    /// other end's last `reach` px (the curve has come round onto itself),
    /// the loop between the closest pair: the points from one to the other,
    /// to be closed.
    fn overlap(&self, e: usize, reach: f64) -> Option<Vec<[f64; 2]>> {
        let n = self.points.len();
        let m = self.end_part(e, reach).len().min(n / 3);
        let (near_e, near_other): (Vec<usize>, Vec<usize>) = if e == 0 {
            ((0..m).collect(), (n - m..n).collect())
        } else {
            ((n - m..n).collect(), (0..m).collect())
        };
        let mut best: Option<(f64, usize, usize)> = None;
        for &i in &near_e {
            for &j in &near_other {
                let d = dist(self.points[i].p, self.points[j].p);
                if d < OVERLAP_DISTANCE && best.is_none_or(|b| d < b.0) {
                    best = Some((d, i, j));
                }
            }
        }
        let (_, i, j) = best?;
        let (a, b) = (i.min(j), i.max(j));
        Some(self.points[a..=b].iter().map(|q| q.p).collect())
    }

    /// When the two ends head towards each other, their distance.
    fn meeting(&self) -> Option<f64> {
        let (a, b) = (self.points.first()?, self.points.last()?);
        let d = [b.p[0] - a.p[0], b.p[1] - a.p[1]];
        let gap = d[0].hypot(d[1]);
        if gap < 1.0 {
            return Some(gap);
        }
        // Outward tangents: -t at the start, t at the end; t = (n_y, -n_x).
        let heads_to_end = -(a.n[1] * d[0] - a.n[0] * d[1]) / gap;
        let heads_to_start = -(b.n[1] * d[0] - b.n[0] * d[1]) / gap;
        (heads_to_end > 0.3 && heads_to_start > 0.3 && self.length() > 3.0 * gap).then_some(gap)
    }

    /// Points about 1 px apart continuing end `e` (0: start, 1: end) by an
    /// arc of up to `len` px, ordered away from the end; cut before the
    /// first point not `inside`.
    fn extension(&self, e: usize, len: f64, inside: impl Fn([f64; 2]) -> bool) -> Vec<[f64; 2]> {
        let total = self.length();
        let window = (total / 3.0).clamp(END_WINDOW_MIN, END_WINDOW_MAX);
        let part = self.end_part(e, window);
        let Some(end) = part.first() else {
            return Vec::new();
        };
        let sign = if e == 0 { -1.0 } else { 1.0 };
        let t = [sign * end.n[1], -sign * end.n[0]];
        let n = [-t[1], t[0]];
        let p = end.p;
        // y' = a + b x' + c x'^2 on the end's window, in the frame (t, n).
        let mut normal = [[0.0; 3]; 3];
        let mut rhs = [0.0; 3];
        for q in &part {
            let d = [q.p[0] - p[0], q.p[1] - p[1]];
            let x = d[0] * t[0] + d[1] * t[1];
            let y = d[0] * n[0] + d[1] * n[1];
            let f = [1.0, x, x * x];
            for i in 0..3 {
                for j in 0..3 {
                    normal[i][j] += f[i] * f[j];
                }
                rhs[i] += f[i] * y;
            }
        }
        let fitted = (part.len() >= 5).then(|| solve3(normal, rhs)).flatten();
        let (slope, curvature) = match fitted {
            Some([_, b, c]) => (
                b,
                (2.0 * c / (1.0 + b * b).powf(1.5)).clamp(-MAX_CURVATURE, MAX_CURVATURE),
            ),
            None => (0.0, 0.0),
        };
        let steps = len.ceil().max(1.0) as usize;
        let dt = len / steps as f64;
        let mut phi = slope.atan();
        let mut q = p;
        let mut out = Vec::with_capacity(steps);
        for _ in 0..steps {
            let mid = phi + 0.5 * curvature * dt;
            let (s, c) = mid.sin_cos();
            q = [
                q[0] + dt * (c * t[0] + s * n[0]),
                q[1] + dt * (c * t[1] + s * n[1]),
            ];
            phi += curvature * dt;
            if !inside(q) {
                break;
            }
            out.push(q);
        }
        out
    }
}

/// Solve the symmetric 3x3 system by Cramer's rule; `None` when singular.
fn solve3(m: [[f64; 3]; 3], r: [f64; 3]) -> Option<[f64; 3]> {
    let det = |a: [[f64; 3]; 3]| {
        a[0][0] * (a[1][1] * a[2][2] - a[1][2] * a[2][1])
            - a[0][1] * (a[1][0] * a[2][2] - a[1][2] * a[2][0])
            + a[0][2] * (a[1][0] * a[2][1] - a[1][1] * a[2][0])
    };
    let d = det(m);
    let scale = m[0][0] * m[1][1] * m[2][2];
    if !(d.is_finite() && d.abs() > 1e-12 * scale.abs()) {
        return None;
    }
    let mut out = [0.0; 3];
    for (k, o) in out.iter_mut().enumerate() {
        let mut a = m;
        for i in 0..3 {
            a[i][k] = r[i];
        }
        *o = det(a) / d;
    }
    Some(out)
}

/// The local contrast test of step 4 (module docs).
struct Probe<'a> {
    sampler: &'a Sampler,
    kind: Kind,
    half_width: f64,
}

impl Probe<'_> {
    /// `c` of `a + c gamma(r / R)` fitted across the curve at a sample;
    /// `None` when the profile leaves the image.
    fn contrast(&self, x: f64, y: f64, nx: f64, ny: f64) -> Option<f64> {
        let r_max = self.half_width;
        let k = (r_max / PROBE_STEP).round() as i64;
        let (mut n, mut sg, mut sgg, mut sv, mut sgv) = (0.0, 0.0, 0.0, 0.0, 0.0);
        for i in -k..=k {
            let r = i as f64 * PROBE_STEP;
            let v = self.sampler.value(x + r * nx, y + r * ny)?;
            let g = self.kind.gamma(r / r_max);
            n += 1.0;
            sg += g;
            sgg += g * g;
            sv += v;
            sgv += g * v;
        }
        let det = n * sgg - sg * sg;
        (det > 0.0).then(|| (n * sgv - sg * sv) / det)
    }

    /// Median contrast over `points`; `None` for none.
    fn median(&self, points: &[Point]) -> Option<f64> {
        let mut c: Vec<f64> = points
            .iter()
            .map(|q| self.contrast(q.p[0], q.p[1], q.n[0], q.n[1]).unwrap_or(0.0))
            .collect();
        if c.is_empty() {
            return None;
        }
        c.sort_by(f64::total_cmp);
        Some(c[c.len() / 2])
    }
}
