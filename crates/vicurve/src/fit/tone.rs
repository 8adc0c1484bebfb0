//! The tone curve of the image ([`crate::tone`]): an explicit one undone
//! before measuring; with [`Tone::Auto`], estimated around a measured
//! silhouette and, when the image is clearly not linear, the silhouette
//! measured again on the image taken back to linear light.

use super::blur::estimate_spread;
use super::reference::{trim_to_band, Clip, TRIM_MARGIN};
use crate::curve::SplineCurve;
use crate::error::{Error, Result};
use crate::image::Image;
use crate::interp::Sampler;
use crate::measurement::{Measurement, Outcome};
use crate::psf;
use crate::tone::{self, Tone, ToneEstimate};
use crate::virtual_image::Kind;
use std::sync::Arc;

/// Band pixels the estimate reads at most (a regular subsample, see
/// `estimate`): its fit sums them by distance to the curve, so they cost
/// only the band's building.
const TONE_PIXELS: usize = 40_000;

/// `sampler`'s image taken to linear light by `tone`, prepared like it;
/// made once per sampler and tone curve ([`Sampler::linear`]).
///
/// Errors: [`Error::InvalidParameter`] when `sampler` has no pixels of its
/// own (a binned level of an image).
pub(super) fn linear_sampler(sampler: &Sampler, tone: Tone) -> Result<Arc<Sampler>> {
    sampler.linear(tone, || {
        let pixels = sampler.image_pixels();
        let light = crate::pages::collect(pixels.len(), pixels.iter().map(|&v| tone.to_linear(v)));
        let image = Image::new_finite(sampler.width(), sampler.height(), light)
            .map_err(|_| Error::invalid("tone", "the image's own pixels are not at hand"))?;
        let linear = Sampler::new(&image, sampler.kind());
        linear.set_clip_levels(sampler.clip_levels());
        Ok(linear)
    })
}

/// `m` (measured from `reference` on `sampler` by `measure`) with the tone
/// curve estimated around its edge, and measured again on the image in
/// linear light when the estimate chose a tone curve other than linear
/// ([`ToneEstimate::curve`]) and that measurement does not diverge.
/// Silhouettes that did not diverge only; `m` as it is otherwise.
pub(super) fn with_estimate(
    sampler: &Sampler,
    reference: SplineCurve,
    mut m: Measurement,
    kind: Kind,
    measure: impl Fn(&Sampler, SplineCurve) -> Result<Measurement>,
) -> Measurement {
    if kind != Kind::Silhouette || matches!(m.outcome, Outcome::Diverged { .. }) {
        return m;
    }
    let spread = m
        .edge_spread
        .or_else(|| estimate_spread(sampler, &m.curve, kind))
        .map(|e| e.sigma);
    let Some(e) = spread.and_then(|s| estimate(sampler, &m.curve, s)) else {
        return m;
    };
    m.tone_estimate = Some(e);
    if e.curve.is_identity() {
        return m;
    }
    let again = linear_sampler(sampler, e.curve).and_then(|linear| measure(&linear, reference));
    match again {
        Ok(mut linear) if !matches!(linear.outcome, Outcome::Diverged { .. }) => {
            // What the reading leaves uncertain moves the whole edge:
            // `Measurement::sigma_shift`, not the samples' own sigma.
            linear.tone = e.curve;
            linear.tone_estimate = Some(e);
            linear
        }
        _ => m,
    }
}

/// The tone estimate around `curve`, an edge of spread `spread` (pixels);
/// an open curve that crosses the image border is read where its band
/// fits in the image.
fn estimate(sampler: &Sampler, curve: &SplineCurve, spread: f64) -> Option<ToneEstimate> {
    let half_width = tone::band_half_width(spread);
    let clip = Clip {
        half_width,
        margin: TRIM_MARGIN,
        width: sampler.width(),
        height: sampler.height(),
    };
    let (stretch, _) = trim_to_band(curve, clip).ok()?;
    // Not near a corner: beyond its vertex the pixels' distance is to the
    // vertex, and their levels those of a wedge, not of the edge's
    // profile.
    let vertices: Vec<[f64; 2]> = curve.corners().iter().map(|&u| curve.point(u)).collect();
    let clear = half_width + 2.0 * spread;
    let keep = |p: [f64; 2]| vertices.iter().all(|v| crate::curve::dist(*v, p) > clear);
    // A long curve's band is read on one pixel in two or four (a
    // checkerboard, or every other pixel of every other row): reading
    // every pixel of a 1704x2272 star's band added 19 ms to its
    // measurement, the thinned band 5 ms.
    let pixels = 2.0 * half_width * stretch.param_length();
    let thin = match pixels / TONE_PIXELS as f64 {
        x if x > 4.0 => 4,
        x if x > 1.0 => 2,
        _ => 1,
    };
    let data =
        psf::oriented_band_data_where(sampler, &stretch, (half_width, thin), TONE_PIXELS, keep)?;
    let rounding = tone::Rounding {
        quantum: sampler.quantum().unwrap_or(0.0),
        noise: sampler.pixel_noise(),
    };
    tone::estimate_oriented(&data, spread, rounding)
}
