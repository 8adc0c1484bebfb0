//! Measuring one object from its own traced start, its bands kept off its
//! neighbours, every way it can fail recorded.

use super::find::{Candidate, GAP_REACH};
use super::{AllConfig, ObjectFailure, ObjectResult, RegionInfo};
use crate::curve::InitialCurve;
use crate::derived::closed_measures;
use crate::fit::{
    breaks, capped_stages, default_stages, measure_from, FitConfig, Measurement, Outcome, Polarity,
    Stage,
};
use crate::image::Image;
use crate::interp::Sampler;
use crate::model::measure_model;
use crate::start::{free_run, smooth, MIN_BOUNDARY};
use crate::virtual_image::Profile;

/// Least gap (px) to another region for an object to be measured: the
/// model fit's first band at a blur of 1 px (4.75 px) and a pixel.
pub const MIN_GAP: f64 = 6.0;
/// A band's half-width stays this far (px) inside the gap: the neighbour's
/// edge reaches about three blur deviations into it.
const BAND_MARGIN: f64 = 3.0;
/// The work (pixels times points along the curve) of the rendering
/// [`expected_pixels`] does at most: a small object's (a dot of radius 10
/// px under a blur of 2.5 px is about 1e6), never a large one's, whose
/// thresholded edge a blur moves by a small fraction of its area.
const MAX_RENDERING: f64 = 2e7;
/// A model whose residual exceeds the free curve's (or 1 % of the
/// contrast, whichever is larger) this many times does not fit.
const MISFIT_RATIO: f64 = 2.0;

/// Measure `c` (module docs of [`super`]) in `image`, prepared once for
/// every object as `sampler` (of `config.fit.interpolation`); never fails:
/// a failure is recorded in the result.
pub(crate) fn measure_one(
    image: &Image,
    sampler: &Sampler,
    c: &Candidate,
    config: &AllConfig,
) -> ObjectResult {
    let mut out = unmeasured(c.id, &c.region, config);
    let start = match start_curve(c) {
        Ok(s) => s,
        Err(message) => {
            out.failure = Some(ObjectFailure::Start { message });
            return out;
        }
    };
    let mut base = config.fit.clone();
    if start.is_closed() && base.polarity == Polarity::Auto && !c.region.touches_border {
        base.polarity = if c.bright {
            Polarity::Positive
        } else {
            Polarity::Negative
        };
    }
    if let (
        Some(n),
        InitialCurve::Polyline {
            points,
            closed: true,
        },
    ) = (config.corners, &start)
    {
        base.breaks = super::corners::corner_breaks(points, n).unwrap_or_default();
    }
    let radius = (c.region.pixels as f64 / std::f64::consts::PI).sqrt();
    let capped = capped_config(&c.region, c.neighbour, &base, radius);
    // Too close for a band of its own: measured on the narrowest band,
    // kept only if the whole-object fit takes over with the neighbours'
    // light rendered (`fit::whole`; without them, it took their light for
    // the object's, or the object is several merged into one region).
    let (fit, close) = match capped {
        Err(failure @ ObjectFailure::TooClose { .. }) if base.stages.is_none() => {
            let narrowest = FitConfig {
                max_half_width: Some(crate::fit::MIN_CAPPED_BAND),
                ..base
            };
            (Ok(narrowest), Some(failure))
        }
        other => (other, None),
    };
    measure_from_start(image, sampler, out, start, fit, config, |m| {
        let whole = m
            .stages
            .last()
            .is_some_and(|s| s.whole_object && s.neighbours > 0);
        match &close {
            Some(failure) if !whole => Some(failure.clone()),
            _ => check_curve(c, m),
        }
    })
}

/// A result for the object `id` of `region` not measured yet.
pub(crate) fn unmeasured(id: usize, region: &RegionInfo, config: &AllConfig) -> ObjectResult {
    ObjectResult {
        id,
        region: region.clone(),
        start: None,
        config: config.fit.clone(),
        measurement: None,
        closed: None,
        model: None,
        failure: None,
    }
}

/// Measure `out`'s object from `start` with `fit` (or record why its
/// configuration failed), `check` the measurement, then fit the model of
/// `config` if any; never fails.
pub(crate) fn measure_from_start(
    image: &Image,
    sampler: &Sampler,
    mut out: ObjectResult,
    start: InitialCurve,
    fit: Result<FitConfig, ObjectFailure>,
    config: &AllConfig,
    check: impl Fn(&Measurement) -> Option<ObjectFailure>,
) -> ObjectResult {
    out.start = Some(start.clone());
    let fit = match fit {
        Ok(f) => f,
        Err(f) => {
            out.failure = Some(f);
            return out;
        }
    };
    out.config = fit.clone();
    let m = match breaks::initial_curve(&start, &fit.breaks)
        .and_then(|reference| measure_from(sampler, reference, &fit))
    {
        Ok(m) => m,
        Err(e) => {
            out.failure = Some(ObjectFailure::Measure {
                message: e.to_string(),
            });
            return out;
        }
    };
    out.failure = diverged(&m).or_else(|| check(&m));
    if m.curve.is_closed() {
        out.closed = closed_measures(&m).ok();
    }
    if let (None, Some(model)) = (&out.failure, config.model) {
        match measure_model(image, &m, &fit, model, &config.model_config) {
            Ok(f) => {
                out.failure = check_model(&f, &m);
                out.model = Some(f);
            }
            Err(e) => {
                out.failure = Some(ObjectFailure::Model {
                    message: e.to_string(),
                })
            }
        }
    }
    out.measurement = Some(m);
    out
}

/// The smoothed traced boundary: closed for an object seen whole, its
/// longest stretch away from the border for one cut by it.
fn start_curve(c: &Candidate) -> Result<InitialCurve, String> {
    if !c.region.touches_border {
        return Ok(InitialCurve::Polyline {
            points: smooth(&c.chain, true),
            closed: true,
        });
    }
    let (x0, y0) = (c.rect.x0 as f64, c.rect.y0 as f64);
    let local: Vec<(usize, usize)> = c
        .chain
        .iter()
        .map(|p| ((p[0] - x0) as usize, (p[1] - y0) as usize))
        .collect();
    let run = free_run(&local, c.rect);
    if run.len() < MIN_BOUNDARY {
        return Err("the visible edge stays near the border".into());
    }
    let points: Vec<[f64; 2]> = run
        .iter()
        .map(|&(i, j)| [x0 + i as f64, y0 + j as f64])
        .collect();
    Ok(InitialCurve::Polyline {
        points: smooth(&points, false),
        closed: false,
    })
}

/// The fit's configuration for an object of `region` (its neighbour's id
/// `neighbour`) from `base`: when another edge lies within [`GAP_REACH`],
/// the bands kept clear of it: the default schedule capped there
/// ([`FitConfig::max_half_width`]: it still ends with the pixel edge or
/// line matched to the blur), or, for explicit stages, those whose band
/// would reach it left out (with the default schedule's rule that a coarse
/// band wider than half the object's `radius`, px, is skipped). Errors:
/// [`ObjectFailure::TooClose`].
pub(crate) fn capped_config(
    region: &RegionInfo,
    neighbour: Option<usize>,
    base: &FitConfig,
    radius: f64,
) -> Result<FitConfig, ObjectFailure> {
    let mut fit = base.clone();
    let gap = region.gap;
    let too_close = || ObjectFailure::TooClose {
        neighbour,
        gap,
        needed: MIN_GAP,
    };
    if gap < MIN_GAP {
        return Err(too_close());
    }
    if gap >= GAP_REACH as f64 - 1.0 {
        return Ok(fit);
    }
    let cap = gap - BAND_MARGIN;
    let Some(explicit) = fit.stages.take() else {
        // The default schedule, capped: it still ends with the pixel edge
        // (or line) matched to the blur, whose band the cap narrows.
        if default_stages().last().is_some_and(|s| s.half_width > cap) {
            return Err(too_close());
        }
        fit.max_half_width = Some(cap);
        return Ok(fit);
    };
    let n = explicit.len();
    if explicit.last().is_none_or(|s| s.half_width > cap) {
        return Err(too_close());
    }
    let within: Vec<Stage> = explicit
        .into_iter()
        .enumerate()
        .filter(|(k, s)| k + 1 == n || s.half_width <= 0.5 * radius)
        .map(|(_, s)| s)
        .collect();
    fit.stages = Some(capped_stages(within, cap));
    Ok(fit)
}

/// A diverged fit.
fn diverged(m: &Measurement) -> Option<ObjectFailure> {
    match m.outcome {
        Outcome::Diverged { divergence } => Some(ObjectFailure::Diverged { divergence }),
        _ => None,
    }
}

/// A closed curve whose area is far from its region's with its holes
/// (more than one pixel all round: it ran to another edge). The region is
/// the image thresholded, whose edge a blur moves off the object's (out
/// of a small bright dot under a blur of a few pixels, by several pixels
/// all round): the curve is compared with the region its own image,
/// rendered through the measured blur and levels ([`expected_pixels`]),
/// would give at the same threshold.
fn check_curve(c: &Candidate, m: &Measurement) -> Option<ObjectFailure> {
    let region = (c.region.pixels + c.enclosed) as f64;
    let area = m.area()?.abs();
    let off = |expected: f64| (expected - region).abs() > c.region.boundary as f64;
    // The rendering only where the area alone disagrees.
    (off(area) && expected_pixels(c, m).is_none_or(off)).then_some(ObjectFailure::Wandered {
        measured: area,
        region,
    })
}

/// The pixels the measured object's own image (its closed curve rendered
/// through the blur and gray levels of `m`'s last pixel-edge stage,
/// `fit::region_light`) puts beyond the threshold `c` was found at, on
/// the object's side, within its region's box widened by the blur's
/// reach; `None` without such a stage, or when that rendering would cost
/// more than [`MAX_RENDERING`].
fn expected_pixels(c: &Candidate, m: &Measurement) -> Option<f64> {
    let last = m.stages.last()?;
    let Profile::PixelEdge { blur, .. } = last.profile else {
        return None;
    };
    let threshold = m.tone.to_linear(c.threshold);
    let reach = (4.0 * blur).ceil() as usize + 2;
    let [x0, y0, x1, y1] = c.region.bbox;
    let origin = [x0.saturating_sub(reach), y0.saturating_sub(reach)];
    let size = [x1 + reach + 1 - origin[0], y1 + reach + 1 - origin[1]];
    let pixels = (size[0] * size[1]) as f64;
    if crate::fit::rendering_work(m.length(), blur, pixels) > MAX_RENDERING {
        return None;
    }
    let light = crate::fit::region_light(&m.curve, blur, origin, size)?;
    let inside = |w: &f64| {
        let g = last.a + last.c * w;
        if c.bright {
            g > threshold
        } else {
            g < threshold
        }
    };
    Some(light.iter().filter(|w| inside(w)).count() as f64)
}

/// A diverged model fit, or one whose residual is far above the free
/// curve's ([`MISFIT_RATIO`]) measured with the same profile: a line's
/// model takes the paper's profile, so its curve's residual is the last
/// stage's with that profile, not the pixel line's, which fits a line's
/// pixels far closer than any bell.
fn check_model(f: &crate::model::ModelFit, m: &Measurement) -> Option<ObjectFailure> {
    if let Outcome::Diverged { divergence } = f.outcome {
        return Some(ObjectFailure::Model {
            message: divergence.to_string(),
        });
    }
    let curve_rms = match m.stages.last().map(|s| s.profile) {
        Some(Profile::PixelLine { .. }) => m
            .last_paper_stage()
            .map_or(m.residual_rms(), |s| s.residual_rms),
        _ => m.residual_rms(),
    };
    let floor = curve_rms.max(0.01 * f.c.abs());
    if f.residual_rms.is_nan() || f.residual_rms > MISFIT_RATIO * floor {
        return Some(ObjectFailure::ModelMisfit {
            model_rms: f.residual_rms,
            curve_rms,
        });
    }
    None
}
