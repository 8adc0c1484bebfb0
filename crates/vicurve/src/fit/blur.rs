//! The edge's blur: estimated on the measured curve, it chooses the band
//! matched to the edge (the paper's optimum `R_g = R_f`) or the pixel-edge
//! profile through that blur, whose own blur is then fitted on the band.

use super::blur_offset::{self, Coupling};
use super::reference::{trim_to_band, Clip, TRIM_MARGIN};
use crate::correlation::Correlation;
use crate::curve::SplineCurve;
use crate::interp::Sampler;
use crate::psf;
use crate::virtual_image::pixel_edge::MIN_BLUR;
use crate::virtual_image::pixel_edge::{pixel_edge_band, spread_variance};
use crate::virtual_image::{Anisotropy, Kind, Profile};

/// Half-width of the first band on which the edge's blur is estimated,
/// pixels (a wider one is tried when the edge fills it).
const EDGE_SPREAD_BAND: f64 = 8.0;
/// Times [`estimate_spread`] and [`line_spread`] may widen their band.
const SPREAD_WIDENINGS: usize = 3;
/// The band half-width that matches an edge of spread `s` is about
/// `MATCHED_BAND * s` (the transition of an error-function edge spans
/// roughly +-2.5 s; R = 2 px for a sharp, focused edge).
const MATCHED_BAND: f64 = 2.5;
/// A band narrower than the matched one by more than this factor does not
/// see the whole edge.
pub(super) const BAND_MISMATCH: f64 = 1.5;
/// The blur correction needs an edge that an error function fits this well
/// (fraction of the variance explained); clutter or texture turn it off.
pub(super) const MIN_EDGE_FIT_QUALITY: f64 = 0.8;
/// Band pixels used to fit the blur of the pixel-edge profile at most.
pub(crate) const BLUR_FIT_PIXELS: usize = 8192;
/// Runs of the pixel-edge stage with an updated blur, at most.
pub(super) const MAX_BLUR_UPDATES: usize = 3;
/// ... and where the image's encoding clipped some band pixels
/// (`Correlation::censored`): the blur estimated on the coarse stages'
/// curve, which the clip moved, starts farther off (a backlight at 1.6
/// times the clip level: 1.74 px for 2.17), and each run at a fixed blur
/// brings the curve only part of the way.
pub(super) const MAX_CENSORED_BLUR_UPDATES: usize = 8;
/// A fitted blur that differs from the one in use by more than this (pixels)
/// is worth another run.
pub(crate) const BLUR_TOLERANCE: f64 = 0.01;
/// Whether a refitted blur `fitted` is worth another run of a pixel-edge
/// stage whose curve `reference` was fitted under `blur` (pixels): it
/// differs by more than [`BLUR_TOLERANCE`], or it moves the half level of
/// the curve's most curved stretch by more than `tolerance` (pixels, the
/// run's own), by the curvature shift `v kappa / 2` (`v` the spread's
/// variance, [`spread_variance`]).
///
/// Why: on a noiseless 16-bit star (mean radius 140 px, amplitude 0.1, 6
/// lobes, blur 4 px) the stage from the automatic start ended under a blur
/// of 4.0092 px whose refit, 4.0004, was within the fixed tolerance; the
/// curvature shift it left, about 1e-3 px at the lobes, put the curve
/// 5.2e-4 px RMS off where `sigma` said 1.6e-4 (taken: 6.4e-5 px).
pub(super) fn blur_change_matters(
    reference: &SplineCurve,
    (blur, fitted): (f64, f64),
    tolerance: f64,
) -> bool {
    if (fitted - blur).abs() > BLUR_TOLERANCE {
        return true;
    }
    let kappa = reference.largest_curvature(CURVATURE_STEP);
    let moved = 0.5 * kappa * (spread_variance(fitted) - spread_variance(blur)).abs();
    moved > tolerance
}

/// Spacing of the three blurs of [`parabolic_refit`], pixels: near its
/// minimum the residual is smooth, and the vertex of a parabola this narrow
/// is the minimum to far better than `BLUR_TOLERANCE` when it lies within
/// a probe of the middle (tested in `fit/track.rs`).
const BLUR_PROBE: f64 = 0.02;
/// On a noisy image the pixel-edge band reaches at least this many spreads
/// `sqrt(v)` (`v = blur^2 + 1/12`) each side. The displacement's profile,
/// a bell of unit area, overlaps the flat levels' constant with a squared
/// correlation of `sqrt(pi v) / R` on a band of half-width `R`: the levels
/// fitted on the band take that share of the information on the curve's
/// mean displacement (a disc's radius, a specimen's width) with them: 0.69
/// on the narrow band at a 2 px blur, which leaves the mean `1 / sqrt(1 -
/// 0.69) = 1.8` times the scatter the noise alone would give it. At `3
/// sqrt(pi) = 5.3` spreads the share is 1/3 (1.22 times), for about twice
/// the band's pixels. Only on noisy images ([`pixel_edge_band_for`]).
const NOISY_BAND_SPREADS: f64 = 5.3;
/// Noise (standard deviation, a fraction of the contrast) from which the
/// pixel-edge band widens ([`pixel_edge_band_for`]): below it the noise
/// moves the curve's mean by a few 1e-4 px at most, not worth a wider
/// band.
const NOISY: f64 = 2e-3;

/// The spread of the edge (silhouettes) or line (contours) around
/// `curve` ([`psf::edge_spread`], [`psf::line_spread`]). An edge's search is
/// bounded by a third of the band, so a result near that bound is estimated
/// again on a band four times the spread, up to `SPREAD_WIDENINGS` times:
/// an estimate at the bound is too small a blur, and its curvature shift
/// too small a correction (a disc of radius 150 px blurred by 4 px,
/// measured with explicit stages, was left 1.2e-2 px inside by the bound
/// of 3.56 px that a single widening reached). An open curve that crosses
/// the image border is taken where each band fits in the image.
pub(super) fn estimate_spread(
    sampler: &Sampler,
    curve: &SplineCurve,
    kind: Kind,
) -> Option<psf::EdgeSpread> {
    // An open curve that crosses the image border: the stretch whose band
    // fits (see `trim_to_band`).
    let within = |half_width: f64| {
        let clip = Clip {
            half_width,
            margin: TRIM_MARGIN,
            width: sampler.width(),
            height: sampler.height(),
        };
        trim_to_band(curve, clip).ok().map(|(stretch, _)| stretch)
    };
    if kind == Kind::Contour {
        return line_spread(sampler, within);
    }
    let mut band = EDGE_SPREAD_BAND;
    let mut e = psf::edge_spread(sampler, &within(band)?, band)?;
    for _ in 0..SPREAD_WIDENINGS {
        if e.sigma < 0.9 * band / 3.0 {
            break;
        }
        band = (4.0 * e.sigma).max(1.5 * band);
        match within(band).and_then(|stretch| psf::edge_spread(sampler, &stretch, band)) {
            Some(wider) => e = wider,
            None => break,
        }
    }
    Some(e)
}

/// [`psf::line_spread`] on a band wide enough for the line: its search
/// bounds the blur by a third of the band and the width by the band, so an
/// estimate near either bound (a line blurred by more than its band shows)
/// is made again on a band of [`matched_band`] plus the blur, up to
/// `SPREAD_WIDENINGS` times. An estimate at the bound would give the
/// blur's curvature shift of too small a blur: on a ring of radius 150 px,
/// 2.5 px wide and blurred by 4 px, the 8-px band's blur bound of 2.7 px
/// left a bias of -3e-2 px.
/// `within(R)`: the stretch of the curve whose band of half-width `R` fits
/// in the image.
fn line_spread(
    sampler: &Sampler,
    within: impl Fn(f64) -> Option<SplineCurve>,
) -> Option<psf::EdgeSpread> {
    let mut band = EDGE_SPREAD_BAND;
    let mut e = psf::line_spread(sampler, &within(band)?, band)?;
    for _ in 0..SPREAD_WIDENINGS {
        let width = e.line_width.unwrap_or(0.0);
        if e.sigma < 0.9 * band / 3.0 && width < 0.9 * band {
            break;
        }
        band = (matched_band(&e) + e.sigma).max(1.5 * band);
        match within(band).and_then(|stretch| psf::line_spread(sampler, &stretch, band)) {
            Some(wider) => e = wider,
            None => break,
        }
    }
    Some(e)
}

/// The band half-width that sees the whole edge or line: `2.5 s` for an
/// edge, plus half the width for a line.
pub(super) fn matched_band(e: &psf::EdgeSpread) -> f64 {
    MATCHED_BAND * e.sigma + 0.5 * e.line_width.unwrap_or(0.0)
}

/// The optical blur (pixels) of the pixel-edge profile that best fits the
/// band of `corr` at `lambda` (least squares, gray levels refitted, on at
/// most `BLUR_FIT_PIXELS` band pixels). The position hardly depends on the
/// blur along a straight edge (the profile is symmetric), but a mismatched
/// width makes the fit depend on the edge's sub-pixel phase.
///
/// Each evaluation is a pass over the band, and a stage refits its blur
/// after every run, where it mostly confirms the blur in use or the one
/// the previous refit found: so first the vertex of the parabola through
/// the residual at `current` and `current +- BLUR_PROBE`, when it lies
/// within a probe ([`parabolic_refit`], 3 evaluations); else a
/// golden-section search within 30 % + 0.15 px of `current` (14 more).
/// When the optimum is at that bracket's end, the caller's next run
/// brackets again around it.
pub(super) fn fit_blur(corr: &Correlation, lambda: &[f64], current: f64) -> f64 {
    search_blur(&blur_residual(corr, lambda), current)
}

/// [`fit_blur`], the curve's offset profiled out where the band bends
/// enough for it to trade off with the blur (`fit/blur_offset.rs`), or
/// where the image's encoding clipped some of its pixels (the profile's
/// top or foot is missing, and what is left of it moves with the blur as
/// the offset does), with the [`Coupling`] there at the fitted blur.
pub(super) fn fit_blur_and_offset(
    corr: &Correlation,
    lambda: &[f64],
    current: f64,
) -> (f64, Option<Coupling>) {
    if !(blur_offset::coupled(corr, current) || corr.censored()) {
        return (fit_blur(corr, lambda, current), None);
    }
    let blur = search_blur(&blur_offset::profiled_residual(corr, lambda), current);
    (blur, blur_offset::coupling(corr, lambda, blur, BLUR_PROBE))
}

/// The blur (pixels) that minimises `ssr` near `current`: the parabola's
/// vertex when it serves, else the golden-section search (see
/// [`fit_blur`]).
fn search_blur(ssr: &impl Fn(f64) -> f64, current: f64) -> f64 {
    if let Some(blur) = vertex_near(ssr, current) {
        return blur;
    }
    let lo = (0.7 * current - 0.15).max(0.0);
    let hi = 1.3 * current + 0.15;
    // 12 steps: the bracket shrinks to 3e-3 of its width.
    let best = psf::golden(lo, hi, 12, ssr);
    // The bracket's ends are never evaluated: a focused edge's optimum is 0.
    if lo == 0.0 && ssr(0.0) <= ssr(best) {
        0.0
    } else {
        best
    }
}

/// The band's residual as a function of the pixel edge's blur (pixels),
/// on at most `BLUR_FIT_PIXELS` of its pixels.
pub(super) fn blur_residual<'a>(
    corr: &'a Correlation,
    lambda: &'a [f64],
) -> impl Fn(f64) -> f64 + 'a {
    let stride = corr.band().len().div_ceil(BLUR_FIT_PIXELS);
    // The blur's anisotropy stays as the band's profile has it.
    let anisotropy = match corr.band().profile() {
        Profile::PixelEdge { anisotropy, .. } => anisotropy,
        _ => Anisotropy::NONE,
    };
    move |blur: f64| {
        corr.pushed_ssr(lambda, Profile::PixelEdge { blur, anisotropy }, stride)
            .unwrap_or(f64::INFINITY)
    }
}

/// The blur (pixels) at the vertex of the parabola through the band's
/// residual at `current` and `current +- BLUR_PROBE` (`0, BLUR_PROBE, 2
/// BLUR_PROBE` near 0), as a function of the blur's variance, on which the
/// profile depends smoothly, also near 0, where the residual is flat in
/// the blur itself; `None` unless the parabola opens upwards and its
/// vertex lies within a probe of the middle blur. Below `MIN_BLUR` the
/// profile no longer depends on the blur, its residual is flat and the
/// vertex meaningless: `current` stands there.
pub(super) fn parabolic_refit(corr: &Correlation, lambda: &[f64], current: f64) -> Option<f64> {
    vertex_near(&blur_residual(corr, lambda), current)
}

/// [`parabolic_refit`] of the residual `ssr`.
fn vertex_near(ssr: &impl Fn(f64) -> f64, current: f64) -> Option<f64> {
    let mid = current.max(BLUR_PROBE);
    let blurs = [mid - BLUR_PROBE, mid, mid + BLUR_PROBE];
    let variance = parabola_vertex(blurs.map(|b| b * b), blurs.map(ssr))?;
    // A focused edge: the residual grows from variance 0 on.
    let blur = variance.max(0.0).sqrt();
    if blur < MIN_BLUR && current < MIN_BLUR {
        return Some(current);
    }
    ((blur - mid).abs() <= BLUR_PROBE).then_some(blur)
}

/// The abscissa of the vertex of the parabola through three points of
/// increasing `x`; `None` unless it opens upwards.
pub(super) fn parabola_vertex(x: [f64; 3], y: [f64; 3]) -> Option<f64> {
    let d01 = (y[1] - y[0]) / (x[1] - x[0]);
    let d12 = (y[2] - y[1]) / (x[2] - x[1]);
    let a = (d12 - d01) / (x[2] - x[0]);
    if !(a > 0.0 && a.is_finite() && d01.is_finite()) {
        return None;
    }
    Some(0.5 * (x[0] + x[1]) - d01 / (2.0 * a))
}

/// Half-width of the band of the pixel-edge stage (pixels, a quarter pixel
/// multiple) for an optical blur of `blur` pixels on an image whose noise
/// has the standard deviation `noise` (gray levels,
/// [`Sampler::pixel_noise`]), of `contrast` (gray levels; `None`: unknown)
/// and whose gray levels come in steps of `quantum` (`None`: continuous),
/// at most `limit` pixels (what the curve leaves clear) unless the narrow
/// band is wider.
///
/// Noise of at least half a gray-level step dithers the rounding of the
/// flat levels; if it also reaches [`NOISY`] of the contrast, the band
/// reaches [`NOISY_BAND_SPREADS`], so that the levels cost the curve's
/// mean position little. Otherwise (a noiseless 8-bit image, an unknown
/// contrast) the band stays narrow: a flat level rounded the same way over
/// the whole plateau would pull the curve by up to half a gray level's
/// worth, the more the wider the plateau's share (see the constants), and
/// without noise there is nothing to gain.
pub(crate) fn pixel_edge_band_for(
    blur: f64,
    noise: f64,
    contrast: Option<f64>,
    quantum: Option<f64>,
    limit: f64,
) -> f64 {
    let narrow = pixel_edge_band(blur);
    let noisy = contrast.is_some_and(|c| {
        noise >= 0.5 * quantum.unwrap_or(0.0) && noise >= NOISY * c.abs() && noise > 0.0
    });
    if !noisy {
        return narrow;
    }
    let spread = spread_variance(blur).sqrt();
    let wide = (NOISY_BAND_SPREADS * spread).min(limit);
    narrow.max((wide * 4.0).ceil() / 4.0)
}

/// The element length (pixels) at which the local curvature's loop gain
/// reaches 1/2 for an edge of optical blur `blur` (pixels): `pi sqrt(v)`,
/// `v = blur^2 + 1/12` the variance of the whole spread. The output's
/// oscillation check looks at curves whose elements are shorter than
/// `1 / sqrt 2` of it.
///
/// Why: with the local curvature `kappa` of the reference, the profile
/// places the edge `v kappa / 2` off its blurred half level. A settle
/// re-references on the measured curve, so an oscillation of the curve at
/// wavenumber `k` comes back in the next reference's curvature and the
/// next fit answers it with `v k^2 / 2` times its amplitude, the first
/// term of the blur's true response `exp(-v k^2 / 2)`. The shortest
/// oscillation of elements `h` long has `k = pi / h`; at `h = pi sqrt(v)`
/// its gain is 1/2, and above a gain of 1 the settles grow noise into an
/// oscillation of the curve. The profile takes the curvature averaged
/// over the blur (`band/blurred_curvature.rs`), whose gain stays under
/// `2 / e`; the stage's elements start from [`shortest_element`].
pub(super) fn resolved_element(blur: f64) -> f64 {
    std::f64::consts::PI * spread_variance(blur).sqrt()
}

/// The blur's floor on the elements of a pixel-edge stage under an optical
/// blur of `blur` pixels, where the stage starts: `1 / sqrt 2` of
/// [`resolved_element`], where the shortest oscillation's gain through the
/// blurred curvature (`band/blurred_curvature.rs`) is `exp(-1/2)` = 0.61
/// and the blur keeps 37 % of it in the image. The profile's curvature
/// averaged over the blur keeps every settle's gain under `2 / e`, so
/// shorter elements grow no oscillation; the stage refines below the floor
/// where [`shortest_pixel_edge`] allows it, and the refinement's rule
/// decides whether the image holds their detail (a blurred star's bays of
/// 14 px radius do). Lines keep it, and the output's oscillation check
/// looks at curves whose elements are shorter.
pub(super) fn shortest_element(blur: f64) -> f64 {
    resolved_element(blur) * std::f64::consts::FRAC_1_SQRT_2
}

/// The shortest elements a pixel-edge stage may refine to, under an
/// optical blur of `blur` pixels, on the curve `reference` (the last
/// stage's), where the schedule's own shortest is `shortest` pixels:
/// that one, where the reference's curvature stays within the reach of
/// the profile's curved edge (`v kappa^2` at most [`CURVED_EDGE_REACH`]
/// everywhere, `v` = [`spread_variance`]); [`shortest_element`] (or
/// `shortest`, the longer) elsewhere.
///
/// Why: with the blurred curvature (`band/blurred_curvature.rs`) no
/// settle grows an oscillation, and the refinement's rule, which counts
/// the settles' amplification of noise and of shape errors
/// (`fit/refine.rs`), decides whether the image holds shorter elements'
/// detail: a star's bays of 14 px radius under a 4 px blur do. A corner
/// that no break declares is beyond the profile's expansion in `v
/// kappa^2`: shorter elements there follow the model's error, not the
/// image, and the blur's floor keeps them long.
pub(super) fn shortest_pixel_edge(reference: &SplineCurve, blur: f64, shortest: f64) -> f64 {
    if within_curved_edge_reach(reference, blur) {
        shortest
    } else {
        shortest_element(blur).max(shortest)
    }
}

/// The elements that follow the bends of `reference` under an optical
/// blur of `blur` pixels: those along which its tangent turns by
/// [`MAX_ELEMENT_TURN`] at its largest curvature (at least
/// [`MIN_BEND_ELEMENT`] pixels), where that curvature is within the
/// profile's reach ([`within_curved_edge_reach`]) and the curve has no
/// corners nor bends as concentrated as a corner
/// ([`MAX_BEND_CONCENTRATION`]); `None` elsewhere (a corner, or curvature
/// beyond the profile).
/// The pixel-edge stage may refine down to them, below the schedule's
/// shortest, where the refinement's rule finds the image holds them.
///
/// Why: on a small ellipse the 8 elements a closed curve starts with turn
/// by more than a radian at its ends, which they cut by tenths of a pixel
/// at many times their `sigma`, and the schedule's shortest left the rule
/// a single step to try (`docs/benchmarks.md`, "Small ellipses as
/// free-form curves"). A polygon's corners, not yet declared when the
/// stage starts, look like such bends to the curvature; their curvature
/// is concentrated where an ellipse's is spread.
pub(super) fn bend_element(reference: &SplineCurve, blur: f64) -> Option<f64> {
    if !reference.corners().is_empty() || !within_curved_edge_reach(reference, blur) {
        return None;
    }
    sharpest_bend(reference).map(|largest| (MAX_ELEMENT_TURN / largest).max(MIN_BEND_ELEMENT))
}

/// The largest curvature of `reference` (1/px, sampled every
/// `CURVATURE_STEP` of its parameter) when it is a bend, not a corner not
/// yet declared: at most [`MAX_BEND_CONCENTRATION`] times the mean of the
/// curvature's magnitude; `None` for such a corner (or a straight curve).
pub(super) fn sharpest_bend(reference: &SplineCurve) -> Option<f64> {
    let l = reference.param_length();
    let n = (l / CURVATURE_STEP).ceil().max(1.0) as usize;
    let (largest, sum) = (0..n)
        .map(|i| reference.frame(i as f64 * l / n as f64).curvature.abs())
        .fold((0.0, 0.0), |(m, s), k| (f64::max(m, k), s + k));
    let mean = sum / n as f64;
    (largest > 0.0 && largest <= MAX_BEND_CONCENTRATION * mean).then_some(largest)
}

/// The largest turn of the tangent along one element, radians
/// ([`bend_element`]).
const MAX_ELEMENT_TURN: f64 = 0.5;
/// The largest curvature over the mean of its magnitude beyond which a
/// curve's sharpest bend is a corner not yet declared, not a bend
/// ([`bend_element`]): about 2.3 on ellipses of aspect 5:3, 4.8 at 5:2,
/// 6.7 at 3:1; about `n s / (2 pi rho)` on a polygon of `n` sides of
/// length `s` whose elements round its corners to a radius `rho`, so that
/// a large polygon is a polygon and a small one, rounded by long
/// elements, may pass.
const MAX_BEND_CONCENTRATION: f64 = 6.0;
/// The shortest elements a bend asks for, pixels ([`bend_element`]).
const MIN_BEND_ELEMENT: f64 = 1.5;

/// Whether the curvature of `reference` stays within the reach of the
/// profile's curved edge under an optical blur of `blur` pixels: `v
/// kappa^2` at most [`CURVED_EDGE_REACH`] everywhere (`v` =
/// [`spread_variance`]). Beyond it (a corner no break declares) the
/// profile's expansion, and the settles' gain that follows from it, no
/// longer describe the edge.
pub(super) fn within_curved_edge_reach(reference: &SplineCurve, blur: f64) -> bool {
    let kappa = reference.largest_curvature(CURVATURE_STEP);
    spread_variance(blur) * kappa * kappa <= CURVED_EDGE_REACH
}

/// The largest `v kappa^2` of a curve whose pixel-edge stage may refine
/// below [`shortest_element`] ([`shortest_pixel_edge`]): the curved edge's
/// second-order terms (`virtual_image/pixel_edge.rs`) then move its half
/// level by at most a tenth of the first-order shift (`5 v kappa^2 / 12`).
const CURVED_EDGE_REACH: f64 = 0.24;
/// Spacing of the curvature's samples along the reference's parameter,
/// pixels.
const CURVATURE_STEP: f64 = 0.5;

/// How much the settles of a pixel-edge stage with elements `h` pixels long
/// amplify the noise of the position, for an optical blur of `blur` pixels
/// (a factor on the Gauss–Newton `sigma`, at least 1).
///
/// Each settle answers the reference's oscillations of wavenumber `k` with
/// `g = (v k^2 / 2) exp(-v k^2 / 4)` times their amplitude (the blurred
/// curvature's gain, `band/blurred_curvature.rs`; at most `2 / e`), so the
/// settled curve holds the noise of one fit amplified by `1 / (1 - g)`. The
/// noise of `U` spreads about evenly over `k` up to `pi / h`: the factor is
/// the RMS of `1 / (1 - g)` over `k` in `[0, pi / h]`.
pub(super) fn settle_noise_gain(blur: f64, h: f64) -> f64 {
    let g = shortest_wave(blur, h);
    // Simpson's rule on 16 intervals, over x = k h / pi.
    let f = |x: f64| settle_amplification(g * x * x).powi(2);
    psf::simpson(0.0, 1.0, 16, f).sqrt()
}

/// How much the settles of a pixel-edge stage with elements `h` pixels long
/// amplify an error of the shortest oscillation those elements describe
/// (wavelength `2 h`), for an optical blur of `blur` pixels: `1 / (1 - g)`
/// with the gain `g` of [`settle_noise_gain`] at `k = pi / h`. A shape
/// the elements cannot follow leaves its error at about that scale.
pub(super) fn settle_shape_gain(blur: f64, h: f64) -> f64 {
    settle_amplification(shortest_wave(blur, h))
}

/// How much one settle amplifies the noise of the position (the factor of
/// [`settle_noise_gain`] after the first settle only): the RMS of `1 + g`
/// over `k` in `[0, pi / h]`. A fit on a reference of its own (a settle of
/// the fit before it, `fit/refine.rs`) holds its noise amplified so.
pub(super) fn one_settle_noise_gain(blur: f64, h: f64) -> f64 {
    let g = shortest_wave(blur, h);
    let f = |x: f64| (1.0 + gain_of(g * x * x)).powi(2);
    psf::simpson(0.0, 1.0, 16, f).sqrt()
}

/// How much one settle amplifies an error of the shortest oscillation of
/// elements `h` pixels long: `1 + g` (see [`settle_shape_gain`]).
pub(super) fn one_settle_shape_gain(blur: f64, h: f64) -> f64 {
    1.0 + gain_of(shortest_wave(blur, h))
}

/// The settle's gain `g = x exp(-x / 2)` at `x = v k^2 / 2`.
pub(super) fn gain_of(x: f64) -> f64 {
    x * (-0.5 * x).exp()
}

/// `v k^2 / 2` at `k = pi / h`.
fn shortest_wave(blur: f64, h: f64) -> f64 {
    spread_variance(blur) * std::f64::consts::PI.powi(2) / (2.0 * h * h)
}

/// `1 / (1 - g)` for `g = x exp(-x / 2)`, `x = v k^2 / 2`.
fn settle_amplification(x: f64) -> f64 {
    1.0 / (1.0 - gain_of(x))
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn parabola_vertex_of_a_parabola() {
        let f = |x: f64| 3.0 * (x - 0.7).powi(2) + 1.0;
        for x in [[0.5, 0.6, 0.7], [0.0, 0.01, 0.5], [0.6, 0.9, 2.0]] {
            let v = parabola_vertex(x, x.map(f)).unwrap();
            assert!((v - 0.7).abs() < 1e-12, "{x:?}: {v}");
            // Concave, flat or not finite: no vertex.
            assert_eq!(parabola_vertex(x, x.map(|x| -f(x))), None);
            assert_eq!(parabola_vertex(x, [1.0; 3]), None);
            assert_eq!(parabola_vertex(x, [1.0, f64::NAN, 1.0]), None);
        }
    }

    /// The shape gain is the settles' `1 / (1 - g)` at the elements'
    /// shortest wave: 1 for long elements, `1 / (1 - exp(-1/2))` at
    /// `shortest_element`, and at most `1 / (1 - 2 / e)` anywhere; so is
    /// the noise gain, its RMS over the longer waves.
    #[test]
    fn settle_gains() {
        for blur in [0.5, 1.0, 2.0, 4.0] {
            let floor = shortest_element(blur);
            let at_floor = settle_shape_gain(blur, floor);
            assert!(
                (at_floor - 1.0 / (1.0 - (-0.5f64).exp())).abs() < 1e-12,
                "{at_floor}"
            );
            assert!((settle_shape_gain(blur, 1e4) - 1.0).abs() < 1e-6);
            let cap = 1.0 / (1.0 - 2.0 / std::f64::consts::E);
            for h in [0.3, 0.5, 0.7, 1.0, 1.5, 3.0].map(|f| f * floor) {
                let (shape, noise) = (settle_shape_gain(blur, h), settle_noise_gain(blur, h));
                assert!(shape >= 1.0 && shape <= cap + 1e-12, "{blur} {h}: {shape}");
                assert!(noise >= 1.0 && noise <= cap + 1e-12, "{blur} {h}: {noise}");
                // One settle amplifies by at least 1 (long elements) and
                // by no more than all of them.
                let (one_shape, one_noise) = (
                    one_settle_shape_gain(blur, h),
                    one_settle_noise_gain(blur, h),
                );
                assert!(
                    one_shape >= 1.0 && one_shape <= shape + 1e-12,
                    "{blur} {h}: {one_shape}"
                );
                assert!(
                    one_noise >= 1.0 && one_noise <= noise + 1e-12,
                    "{blur} {h}: {one_noise}"
                );
            }
        }
    }

    /// Points of a closed curve: the polar `r(theta)` about the origin.
    fn polar(r: impl Fn(f64) -> f64) -> SplineCurve {
        let n = 720;
        let pts: Vec<[f64; 2]> = (0..n)
            .map(|i| {
                let t = std::f64::consts::TAU * i as f64 / n as f64;
                [r(t) * t.cos(), r(t) * t.sin()]
            })
            .collect();
        SplineCurve::fit(&pts, true, 3, 2.0).unwrap()
    }

    /// A curve whose curvature stays within the curved edge's reach may
    /// refine to the schedule's shortest elements; one with a corner the
    /// blur rounds (a square whose corners have a radius of a few pixels)
    /// keeps the blur's floor; without blur every curve may.
    #[test]
    fn shortest_pixel_edge_follows_the_curvature() {
        // A star whose bays have a radius of curvature of about 14 px.
        let star = polar(|t| 140.0 * (1.0 + 0.2 * (6.0 * t).cos()));
        assert_eq!(shortest_pixel_edge(&star, 4.0, 5.0), 5.0);
        // A square of side 200 px, its corners rounded over a few pixels
        // (a superellipse of high order).
        let square = polar(|t| {
            let (c, s) = (t.cos().abs(), t.sin().abs());
            100.0 / (c.powi(40) + s.powi(40)).powf(1.0 / 40.0)
        });
        assert_eq!(
            shortest_pixel_edge(&square, 4.0, 5.0),
            shortest_element(4.0)
        );
        assert_eq!(shortest_pixel_edge(&square, 4.0, 10.0), 10.0);
        assert_eq!(shortest_pixel_edge(&square, 0.0, 5.0), 5.0);
    }

    /// Elements that turn half a radian at the largest curvature: 1.8 px
    /// on an ellipse of 10 x 6 px (radius of curvature `b^2 / a` at its
    /// ends; its spline on elements of 2 px bends 7 % more there); none
    /// where the blur reaches beyond the profile's curved edge, nor on a
    /// curve with corners, declared or not.
    #[test]
    fn bend_elements_follow_the_largest_curvature() {
        let (a, b) = (10.0, 6.0);
        let ellipse = polar(|t: f64| a * b / (b * t.cos()).hypot(a * t.sin()));
        let h = bend_element(&ellipse, 0.7).unwrap();
        assert!((h - 0.5 * b * b / a).abs() < 0.15, "{h}");
        assert_eq!(bend_element(&ellipse, 2.5), None);
        let star = polar(|t| 140.0 * (1.0 + 0.2 * (6.0 * t).cos()));
        assert!(bend_element(&star, 1.0).unwrap() > 5.0);
        // A square whose corners are rounded over a few pixels: its bends
        // are corners.
        let square = polar(|t| {
            let (c, s) = (t.cos().abs(), t.sin().abs());
            100.0 / (c.powi(40) + s.powi(40)).powf(1.0 / 40.0)
        });
        assert_eq!(bend_element(&square, 0.0), None);
        let points: Vec<[f64; 2]> = (0..40)
            .map(|k| {
                let t = k as f64 * std::f64::consts::TAU / 40.0;
                [50.0 + 20.0 * t.cos(), 50.0 + 20.0 * t.sin()]
            })
            .collect();
        let cornered = SplineCurve::fit_with_corners(&points, true, 3, 4.0, &[0, 20]).unwrap();
        assert_eq!(bend_element(&cornered, 0.7), None);
    }
}
