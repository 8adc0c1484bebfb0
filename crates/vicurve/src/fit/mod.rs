//! The measurement: multi-scale Gauss–Newton correlation of the virtual
//! image with the physical one (method, sections 5 and 6).
//!
//! [`measure`] runs the stages of the schedule in turn. In each stage the
//! curve is `x(s) = x0(s) + U(s) n(s)` with `U` a B-spline of the stage's
//! elements on the reference `x0`; the reference is replaced by the current
//! curve (new band, new matrix, `U = 0`) when a stage ends and whenever
//! `max |U|` exceeds a fraction of `R` within a stage, so that a start far
//! from the edge (a circle crossing a star) converges.
//!
//! # The files, in the order a fit runs them
//! - [`config`](FitConfig): the configuration, the stages and their
//!   elements.
//! - `probe.rs`: a start already near the edge skips the wide stages.
//! - `schedule.rs`: the stages in turn; after the last, the edge's blur
//!   chooses a stage to append; the result and, for a tracked frame, the
//!   band kept for the next one.
//! - `stage.rs`: one stage as a small state machine: build the band and
//!   system, run, then re-reference, or (converged) test the levels,
//!   refine the elements, reweight clutter, refit the blur, settle, done.
//! - `run.rs`: Gauss–Newton iterations on one reference and the stopping
//!   rule (`crate::correlation` makes each iteration).
//! - `refine.rs`, `robust.rs`, `blur.rs`: the element refinement, the
//!   robust weights, the edge's blur and the pixel-edge stage's band.
//! - `reference.rs`: a converged curve as the next reference;
//!   `settle.rs`: a settle's reference taken to the settles' fixed point.
//! - `loops.rs`: a new reference or result that crosses itself or folds
//!   back is a divergence.
//! - `output.rs`: the measured curve and its samples with `sigma`;
//!   `misfit.rs`: its model-misfit term (residuals, oscillation);
//!   `representation.rs`: the shape error its elements leave where the
//!   edge bends faster than they follow;
//!   `correlated.rs`: the factor on its noise term for residuals
//!   correlated along the curve (textured surfaces).
//! - [`breaks`], [`grow`], `track.rs`: corners, growing a short start,
//!   the tracking schedule of a sequence's frames.
//!
//! ```no_run
//! use vicurve::{fit::{measure, FitConfig}, curve::InitialCurve, io::load_image};
//! let image = load_image("part.png".as_ref())?;
//! let init = InitialCurve::Circle { cx: 320.0, cy: 240.0, r: 100.0 };
//! let m = measure(&image, &init, &FitConfig::default())?;
//! println!("{}: length {:.4} px", m.outcome, m.length());
//! # Ok::<(), vicurve::Error>(())
//! ```

mod anisotropy;
mod blur;
mod blur_offset;
pub mod breaks;
mod config;
mod corner_check;
mod corner_round;
mod corner_search;
mod correlated;
pub mod grow;
mod loops;
mod misfit;
mod output;
mod polarity;
mod probe;
mod pyramid;
mod reference;
mod refine;
mod representation;
mod robust;
mod run;
mod schedule;
mod settle;
mod stage;
mod tone;
mod track;
mod whole;

pub use crate::correlation::levels::{self, LevelModel};
pub use crate::measurement::{
    Divergence, IterationRecord, LevelSample, Measurement, Outcome, RunKind, Sample, StageReport,
    Trim, TrimReason, TrimmedEnd,
};
pub(crate) use config::capped_stages;
pub use config::{default_stages, parse_stages, Coords, Elements, FitConfig, Polarity, Stage};
pub use track::{
    measure_tracked, measure_tracked_cached, measure_tracked_from, TrackCache, TrackSnapshot,
    TrackState,
};

pub(crate) use robust::{clutter_scale, tukey_weight};
pub(crate) use schedule::MIN_CAPPED_BAND;
pub(crate) use whole::{region_light, rendering_work};

use crate::curve::{InitialCurve, SplineCurve};
use crate::error::Result;
use crate::image::Image;
use crate::interp::Sampler;
use crate::tone::Tone;
use crate::virtual_image::pixel_edge::pixel_edge_band;
use crate::virtual_image::Kind;
use blur::BLUR_TOLERANCE;
use schedule::run_schedule;

/// Measure the curve in `image` starting from `init`.
///
/// Errors are reserved for inputs that cannot be measured at all: an
/// invalid configuration, an initial curve or first band outside the image,
/// a band with too few pixels. A fit that starts but fails later is
/// reported as [`Outcome::Diverged`] with the last good curve.
pub fn measure(image: &Image, init: &InitialCurve, config: &FitConfig) -> Result<Measurement> {
    config.validate()?;
    let sampler = Sampler::new(image, config.interpolation);
    let start = breaks::initial_curve(init, &config.breaks)?;
    measure_from(&sampler, start, config)
}

/// [`measure`] with a prepared image sampler and reference curve (for
/// sequences and benchmarks: the sampler's prefilter is done once).
///
/// The image's tone curve ([`FitConfig::tone`]): an explicit one is undone
/// on a copy of the image first; [`Tone::Auto`] measures the image as it
/// is, estimates the tone curve around a silhouette's edge, and measures
/// again on the image in linear light when it is clearly not linear
/// (`fit/tone.rs`; the result's [`Measurement::tone`] and
/// [`Measurement::tone_estimate`] say what was done).
pub fn measure_from(
    sampler: &Sampler,
    reference: SplineCurve,
    config: &FitConfig,
) -> Result<Measurement> {
    if !config.tone.is_identity() {
        let linear = tone::linear_sampler(sampler, config.tone)?;
        let mut m = measure_as_linear(&linear, reference, config)?;
        m.tone = config.tone;
        return Ok(m);
    }
    if config.tone != Tone::Auto {
        return measure_as_linear(sampler, reference, config);
    }
    let m = measure_as_linear(sampler, reference.clone(), config)?;
    Ok(tone::with_estimate(
        sampler,
        reference,
        m,
        config.kind,
        |s, r| measure_as_linear(s, r, config),
    ))
}

/// [`measure_from`] on gray levels taken as proportional to the light.
fn measure_as_linear(
    sampler: &Sampler,
    reference: SplineCurve,
    config: &FitConfig,
) -> Result<Measurement> {
    let smooth_start = config.breaks.is_empty() && reference.corners().is_empty();
    let m = run_schedule(sampler, reference, config, None)?;
    let m = if config.find_corners && smooth_start && config.coords == Coords::Exact {
        with_found_corners(sampler, m, config)
    } else {
        m
    };
    // A small object under a large blur: measured against its whole image
    // (`whole/`).
    Ok(whole::refined(sampler, m, config.sample_spacing))
}

/// `m` measured again with breaks at the corners its curve shows
/// ([`corner_search`]), when it has some and the new result converges
/// without a residual RMS much above the smooth one's; of a silhouette,
/// only at the corners the image confirms ([`corner_check`]: measured
/// once more when it confirms some but not all), the samples near a kept
/// corner the image shows rounded charged with the fillet's distance
/// ([`corner_round`]); else `m`. A smooth result at its iteration limit,
/// or diverged off the edge, is searched too: a spline ringing at a
/// polygon's corners is one reason a fit does not settle or leaves the
/// edge there.
fn with_found_corners(sampler: &Sampler, m: Measurement, config: &FitConfig) -> Measurement {
    let off_edge = matches!(
        m.outcome,
        Outcome::Diverged {
            divergence: Divergence::OffEdge { .. }
        }
    );
    if matches!(m.outcome, Outcome::Diverged { .. }) && !off_edge {
        return m;
    }
    let closed = m.curve.is_closed();
    let corners = corner_search::find_corners(&m.samples, closed);
    if corners.is_empty() {
        return m;
    }
    let with = FitConfig {
        breaks: corners,
        ..config.clone()
    };
    let init = InitialCurve::Polyline {
        points: m.points(),
        closed,
    };
    let Ok(start) = breaks::initial_curve(&init, &with.breaks) else {
        return m;
    };
    let residual = |m: &Measurement| m.stages.last().map_or(f64::INFINITY, |s| s.residual_rms);
    let c = match run_schedule(sampler, start, &with, None) {
        Ok(c)
            if matches!(c.outcome, Outcome::Converged)
                && residual(&c) < FOUND_CORNERS_GAIN * residual(&m) =>
        {
            c
        }
        _ => return m,
    };
    if config.kind != Kind::Silhouette {
        return with_corners_listed(c);
    }
    // The corners the image confirms (`corner_check.rs`); near a corner
    // kept on ambiguous evidence, `sigma` covers the smooth curve.
    let verdicts = corner_check::verdicts(sampler, &m, &c);
    let kept: Vec<[f64; 2]> = verdicts
        .iter()
        .filter(|v| v.keep)
        .map(|v| v.vertex)
        .collect();
    let rounded: Vec<corner_round::Rounded> =
        verdicts.iter().filter_map(|v| v.rounded.clone()).collect();
    if kept.len() == verdicts.len() {
        let mut c = with_corners_listed(c);
        corner_check::cover_ambiguous(&mut c, &m.curve, &judged(&verdicts, |v| v.ambiguous));
        corner_round::cover_rounded(&mut c, &rounded);
        return c;
    }
    // Measured again with the kept corners alone, unless that fits worse
    // than both (its long elements ringing where corners were dropped) or
    // moves the kept corners; else whichever of the smooth and cornered
    // measurements fits better. `sigma` near the corners judged otherwise
    // than the chosen curve shows them covers the other curve.
    let smooth = m.curve.clone();
    let sharp = c.curve.clone();
    let again = if kept.is_empty() {
        None
    } else {
        with_corners_at(sampler, &m, &kept, config)
            .filter(|r| residual(r) <= FOUND_CORNERS_GAIN * residual(&m).min(residual(&c)))
    };
    let (mut chosen, other, covered) = match again {
        Some(r) => (r, &smooth, judged(&verdicts, |v| v.ambiguous && v.keep)),
        None if !kept.is_empty() && residual(&c) < residual(&m) => (
            with_corners_listed(c),
            &smooth,
            judged(&verdicts, |v| v.ambiguous || !v.keep),
        ),
        None => (m, &sharp, judged(&verdicts, |v| v.ambiguous || v.keep)),
    };
    corner_check::cover_ambiguous(&mut chosen, other, &covered);
    if !chosen.corners_found.is_empty() {
        corner_round::cover_rounded(&mut chosen, &rounded);
    }
    chosen
}

/// The vertices of the corners whose verdict satisfies `which`.
fn judged(
    verdicts: &[corner_check::Verdict],
    which: impl Fn(&corner_check::Verdict) -> bool,
) -> Vec<[f64; 2]> {
    verdicts
        .iter()
        .filter(|v| which(v))
        .map(|v| v.vertex)
        .collect()
}

/// `m` measured again with breaks at the vertices `kept` alone, if that
/// converges with a corner within [`KEPT_CORNER_SHIFT`] of each of them:
/// a break can slide along a side towards the rounding left where a
/// corner was dropped.
fn with_corners_at(
    sampler: &Sampler,
    m: &Measurement,
    kept: &[[f64; 2]],
    config: &FitConfig,
) -> Option<Measurement> {
    let points = m.points();
    let with = FitConfig {
        breaks: kept
            .iter()
            .map(|&v| polyline_arc_length(&points, v))
            .collect(),
        ..config.clone()
    };
    let closed = m.curve.is_closed();
    let init = InitialCurve::Polyline { points, closed };
    let r = breaks::initial_curve(&init, &with.breaks)
        .and_then(|start| run_schedule(sampler, start, &with, None))
        .ok()?;
    let r = with_corners_listed(r);
    let stays = kept.iter().all(|&v| {
        r.corners_found
            .iter()
            .any(|&w| crate::curve::dist(v, w) <= KEPT_CORNER_SHIFT)
    });
    (matches!(r.outcome, Outcome::Converged) && stays).then_some(r)
}

/// How far (pixels) a kept corner may move when measured again without
/// the dropped ones.
const KEPT_CORNER_SHIFT: f64 = 1.0;

/// `c` with its curve's corners listed as found.
fn with_corners_listed(mut c: Measurement) -> Measurement {
    c.corners_found = c
        .curve
        .corners()
        .iter()
        .map(|&u| c.curve.point(u))
        .collect();
    c
}

/// The arc length (pixels, from the first point) along the polyline
/// `points` of its point nearest to `v`.
fn polyline_arc_length(points: &[[f64; 2]], v: [f64; 2]) -> f64 {
    let s = reference::chord_lengths(points);
    points
        .iter()
        .zip(&s)
        .min_by(|a, b| crate::curve::dist(*a.0, v).total_cmp(&crate::curve::dist(*b.0, v)))
        .map_or(0.0, |(_, &s)| s)
}

/// A measurement with found corners is kept unless its residual RMS
/// exceeds the smooth one's this many times (a refit gone wrong). Not a
/// test of which fits better: the two last stages' bands differ (the
/// breaks leave the wedges beyond the corners out, the pixel-edge stage
/// follows the blur each finds), and on a noisy image the residuals are
/// the noise's either way (docs/breaks.md).
const FOUND_CORNERS_GAIN: f64 = 1.25;
