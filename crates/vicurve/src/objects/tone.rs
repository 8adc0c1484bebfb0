//! The image's tone curve, agreed by its objects. With [`Tone::Auto`] each
//! object's edge is read on its own (`fit/tone.rs`), but a small object's
//! band holds too few pixels to tell an encoded image at ordinary noise
//! (docs/benchmarks.md, "Gamma-encoded images"). The tone curve is the
//! image's: the objects' readings are pooled, and when together they read
//! an encoding, the objects read as linear are measured again with it.

use super::measure::measure_one;
use super::{AllConfig, ObjectResult};
use crate::derived::closed_measures;
use crate::fit::{FitConfig, Measurement};
use crate::image::Image;
use crate::interp::Sampler;
use crate::tone::{allowed_spread, Tone, ToneEstimate, FITTED_SYSTEMATIC, LEAST_GAMMA};
use rayon::prelude::*;

use super::find::Candidate;

/// Objects with a reading needed to pool them.
const LEAST_READ: usize = 3;
/// The pooled evidence must exceed its mean for a linear image (one per
/// object: each is a chi-square of one degree of freedom) by this many
/// standard deviations (`sqrt(2 n)`).
const POOLED_SDS: f64 = 5.0;

/// `objects` (measured from `candidates` with `config`, whose tone is
/// [`Tone::Auto`]) with those read as linear measured again with the
/// image's tone curve, when the objects' readings pooled read one: their
/// evidence summed beyond [`POOLED_SDS`] standard deviations of a linear
/// image's, and their exponents, averaged with the evidence as weights,
/// above the least an encoding has (`tone.rs`). The curve is the one most
/// of the objects read as encoded took, else that averaged power law.
/// Each object measured again keeps its own reading in `tone_estimate`,
/// with that curve and, as its `position_sd` (the measurement's
/// `sigma_shift`, also in the radius and the semi-axes), the median of those of the
/// objects that took the curve, or a quarter of its own shift.
pub(super) fn agreed(
    image: &Image,
    sampler: &Sampler,
    candidates: &[Candidate],
    objects: Vec<ObjectResult>,
    config: &AllConfig,
) -> Vec<ObjectResult> {
    let read: Vec<(Tone, ToneEstimate)> = objects
        .iter()
        .filter_map(|o| o.measurement.as_ref())
        .filter_map(|m: &Measurement| m.tone_estimate.map(|e| (m.tone, e)))
        .collect();
    let n = read.len() as f64;
    let total: f64 = read.iter().map(|r| r.1.evidence).sum();
    if read.len() < LEAST_READ {
        return objects;
    }
    if total - n <= POOLED_SDS * (2.0 * n).sqrt() {
        return pooled_alternatives(objects);
    }
    let gamma = (read
        .iter()
        .map(|r| r.1.evidence * r.1.gamma.ln())
        .sum::<f64>()
        / total)
        .exp();
    // Written so that NaN (no evidence at all) does not pass.
    if gamma.is_nan() || gamma <= LEAST_GAMMA {
        return pooled_alternatives(objects);
    }
    // The curve most objects read as encoded took (the first of the most
    // taken), else the pooled power law.
    let encoded: Vec<&(Tone, ToneEstimate)> = read.iter().filter(|r| !r.0.is_identity()).collect();
    let votes = |t: Tone| encoded.iter().filter(|r| r.0 == t).count();
    let tone = encoded
        .iter()
        .map(|r| r.0)
        .max_by_key(|&t| votes(t))
        .unwrap_or(Tone::Gamma(gamma));
    let mut sds: Vec<f64> = encoded
        .iter()
        .filter(|r| r.0 == tone)
        .map(|r| r.1.position_sd)
        .collect();
    sds.sort_by(f64::total_cmp);
    let median = sds.get(sds.len() / 2).copied();
    let again = AllConfig {
        fit: FitConfig {
            tone,
            ..config.fit.clone()
        },
        ..config.clone()
    };
    candidates
        .par_iter()
        .zip(objects)
        .map(|(c, o)| match &o.measurement {
            Some(m) if m.tone.is_identity() && m.tone_estimate.is_some() => {
                let own = m.tone_estimate;
                let mut r = measure_one(image, sampler, c, &again);
                if let (Some(m), Some(e)) = (r.measurement.as_mut(), own) {
                    let sd = median.unwrap_or(FITTED_SYSTEMATIC * e.shift.abs());
                    m.tone_estimate = Some(ToneEstimate {
                        curve: tone,
                        position_sd: sd,
                        ..e
                    });
                    if m.curve.is_closed() {
                        r.closed = closed_measures(m).ok();
                    }
                }
                r
            }
            _ => o,
        })
        .collect()
}

/// `objects` whose readings kept linear light, with the uncertainty the
/// standard encodings leave ([`ToneEstimate::position_sd`]) weighed by all
/// the objects' readings at once: an encoding's excess over linear light
/// is the sum of the objects' (the tone curve is the image's), and one
/// that an object did not fit (ruled out) is ruled out. Small objects
/// each allow an encoding that all of them together rule out (test
/// `objects::scene::an_encoded_scene_is_read_by_its_objects_together`).
fn pooled_alternatives(objects: Vec<ObjectResult>) -> Vec<ObjectResult> {
    let linear = |o: &ObjectResult| {
        o.measurement
            .as_ref()
            .filter(|m| m.tone.is_identity())
            .and_then(|m| m.tone_estimate)
            .filter(|e| e.curve.is_identity())
    };
    let mut excess = [0.0f64; 3];
    let mut any = false;
    for e in objects.iter().filter_map(linear) {
        any = true;
        for (sum, a) in excess.iter_mut().zip(e.alternatives) {
            *sum += a.map_or(f64::INFINITY, |a| a.excess);
        }
    }
    if !any {
        return objects;
    }
    objects
        .into_iter()
        .map(|mut o| {
            let Some(e) = linear(&o) else {
                return o;
            };
            let pooled = excess
                .iter()
                .zip(e.alternatives)
                .filter(|(x, _)| x.is_finite())
                .filter_map(|(&x, a)| a.map(|a| (x, a.centre)));
            let sd = allowed_spread(pooled);
            if let Some(m) = o.measurement.as_mut() {
                m.tone_estimate = Some(ToneEstimate {
                    position_sd: sd,
                    ..e
                });
                if m.curve.is_closed() {
                    o.closed = closed_measures(m).ok();
                }
            }
            o
        })
        .collect()
}
