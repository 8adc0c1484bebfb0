//! The blur and the curve's offset, fitted together where they trade off.
//!
//! A curve's blurred edge lies `v kappa / 2` inside its curvature (`v` the
//! spread variance), and a small disc's image is nearly a Gaussian bump:
//! a larger disc under a smaller blur looks almost the same. Where the
//! spread is not small against the radius of curvature, the blur fitted
//! at a fixed curve ([`super::blur::fit_blur`]) and the curve fitted at a
//! fixed blur then move along that valley by a fraction of the way at each
//! turn, and the stage's turns run out far from its bottom, the dot's size
//! off by several times its `sigma` (docs/benchmarks.md, "Dots a blur or
//! so across"). Here the blur's residual is the band's at the curve's best
//! offset for that blur (the offset along the normals, the same at every
//! point, profiled out), so that one refit of the blur goes down the
//! valley; the offset's slope along it and the residual's curvature give
//! what the blur's uncertainty adds to the curve's ([`Coupling`]).
//!
//! Edge cases: only where the band's mean curvature times the spread
//! reaches [`COUPLED`] (a closed curve a few spreads across; a straight or
//! meandering edge's offset does not depend on the blur) and the edge is
//! its blurred osculating circle nearly everywhere (a dot, not a small
//! ellipse, see [`coupled`]); the offset moves the osculating circle's
//! radius with it (the pushed profile keeps the reference's curvature
//! otherwise, exact at `U = 0` only).

use crate::correlation::Correlation;
use crate::virtual_image::pixel_edge::spread_variance;
use crate::virtual_image::{Anisotropy, Profile};

/// The band's mean curvature times the edge's spread from which the blur
/// and the offset are fitted together: the blur's half-level shift
/// `v kappa / 2` then moves by a tenth of the spread per pixel of blur.
pub(super) const COUPLED: f64 = 0.1;
/// The mean weight of the blurred osculating circle over the band from
/// which the blur and the offset are fitted together (see [`coupled`]).
const OSCULATING: f64 = 0.9;
/// Half the spacing of the three offsets whose parabola finds the best
/// offset for a blur, pixels: the residual is quadratic in the offset
/// over far more than this.
const OFFSET_PROBE: f64 = 0.05;
/// Parabolas of [`profiled_at`] at most.
const OFFSET_ROUNDS: usize = 4;
/// A vertex this close to the middle of its parabola's offsets (pixels)
/// ends [`profiled_at`]'s search.
const OFFSET_SETTLED: f64 = 1e-3;
/// `1 - kappa u` below which the offset's curvature is not followed (the
/// offset would reach the centre of curvature).
const MIN_STRETCH: f64 = 0.2;

/// What the blur's uncertainty adds to the curve's: the offset's slope
/// along the valley and the blur's information.
#[derive(Clone, Copy, Debug, PartialEq)]
pub(crate) struct Coupling {
    /// How far the best offset moves per pixel of blur (pixels per pixel).
    pub slope: f64,
    /// Half the profiled residual's second derivative in the blur, per
    /// unit of noise variance: the blur's variance is the noise variance
    /// over this (1 / pixel^2).
    pub information: f64,
}

impl Coupling {
    /// The standard deviation (pixels) that the blur's uncertainty adds
    /// to every point's position on an image of noise variance `noise_var`
    /// (gray levels squared), or 0 without information.
    pub(crate) fn position_sd(&self, noise_var: f64) -> f64 {
        if self.information > 0.0 && noise_var > 0.0 {
            self.slope.abs() * (noise_var / self.information).sqrt()
        } else {
            0.0
        }
    }
}

/// Whether the band of `corr` bends enough under its pixel edge of blur
/// `blur` (pixels) for the blur and the offset to trade off ([`COUPLED`]),
/// on a curve whose edge is its blurred osculating circle nearly
/// everywhere (weight [`OSCULATING`] on average): where the curvature
/// changes within the blur's reach (a small ellipse's ends) the profile is
/// an expansion, and going down the flat valley would turn its error into
/// the curve's size.
pub(super) fn coupled(corr: &Correlation, blur: f64) -> bool {
    let band = corr.band();
    let (mut osculating, mut weight) = (0.0, 0.0);
    for (i, w) in band.weight.iter().enumerate() {
        osculating += w * band.osculating_at(i);
        weight += w;
    }
    few_blurs_across(corr, blur) && osculating >= OSCULATING * weight
}

/// Whether the band of `corr` bends enough under its pixel edge of blur
/// `blur` (pixels) that the object is a few blurs across: its mean
/// curvature times the spread at least [`COUPLED`] (a dot, a small
/// ellipse). Its shape and its blur then give the same images in more
/// than one way: the blur's size trades with the curve's offset
/// ([`coupled`]), and an elongated blur with the object's own elongation.
pub(super) fn few_blurs_across(corr: &Correlation, blur: f64) -> bool {
    let band = corr.band();
    let (mut curvature, mut weight) = (0.0, 0.0);
    for (k, w) in band.curvature.iter().zip(&band.weight) {
        curvature += w * k;
        weight += w;
    }
    weight > 0.0 && spread_variance(blur).sqrt() * (curvature / weight).abs() >= COUPLED
}

/// The band's residual at `lambda` moved by `offset` (pixels, along the
/// normals) under the pixel edge `profile` (with the corners' wedge terms
/// `corner` of its blur, when the band has any), gray levels refitted,
/// every `stride`-th pixel; each pixel's osculating circle follows the
/// displacement.
fn residual_at(
    corr: &Correlation,
    lambda: &[f64],
    offset: f64,
    (profile, corner): (Profile, Option<&[f64]>),
    stride: usize,
) -> f64 {
    let band = corr.band();
    let half_width = band.half_width();
    let moved: Vec<f64> = lambda.iter().map(|l| l + offset).collect();
    corr.pushed_ssr_by(&moved, stride, |i, r| {
        let u = band.r[i] - r;
        let k = band.curvature[i];
        let stretch = 1.0 - k * u;
        let k = if stretch > MIN_STRETCH {
            k / stretch
        } else {
            k
        };
        profile
            .eval_at(r, half_width, band.normal[i], (k, band.osculating_at(i)))
            .0
            + corner.map_or(0.0, |c| c[i])
    })
    .unwrap_or(f64::INFINITY)
}

/// The lowest residual over the offset at blur `blur`, and that offset
/// (pixels), searched from 0: the vertex of the parabola through three
/// offsets around the best so far, again from each vertex that lowers the
/// residual (the first is extrapolated from a probe's reach, and falls
/// short of an offset of tenths of a pixel), until it moves by less than
/// [`OFFSET_SETTLED`] or [`OFFSET_ROUNDS`] parabolas.
fn profiled_at(corr: &Correlation, lambda: &[f64], blur: f64) -> (f64, f64) {
    let band = corr.band();
    let stride = band.len().div_ceil(super::blur::BLUR_FIT_PIXELS);
    let anisotropy = match band.profile() {
        Profile::PixelEdge { anisotropy, .. } => anisotropy,
        _ => Anisotropy::NONE,
    };
    // The corners' wedge terms depend on the blur, not on the offset.
    let corner = band.corner_terms(blur, anisotropy);
    let profile = (Profile::PixelEdge { blur, anisotropy }, corner.as_deref());
    let at = |offset: f64| residual_at(corr, lambda, offset, profile, stride);
    let mut best = (at(0.0), 0.0);
    for _ in 0..OFFSET_ROUNDS {
        let middle = best.1;
        let offsets = [middle - OFFSET_PROBE, middle, middle + OFFSET_PROBE];
        let values = [at(offsets[0]), best.0, at(offsets[2])];
        for (v, o) in values.iter().zip(offsets) {
            if *v < best.0 {
                best = (*v, o);
            }
        }
        let Some(vertex) = super::blur::parabola_vertex(offsets, values) else {
            break;
        };
        let value = at(vertex);
        if value >= best.0 {
            break;
        }
        best = (value, vertex);
        if (vertex - middle).abs() < OFFSET_SETTLED {
            break;
        }
    }
    best
}

/// The band's residual as a function of the blur (pixels) with the
/// curve's offset profiled out, for the blur's searches.
pub(super) fn profiled_residual<'a>(
    corr: &'a Correlation,
    lambda: &'a [f64],
) -> impl Fn(f64) -> f64 + 'a {
    move |blur: f64| profiled_at(corr, lambda, blur).0
}

/// The [`Coupling`] at blur `blur` (pixels) from the profiled residual
/// and offsets at `blur` and `blur +- probe`; `None` where the residual
/// does not curve upwards there.
pub(super) fn coupling(
    corr: &Correlation,
    lambda: &[f64],
    blur: f64,
    probe: f64,
) -> Option<Coupling> {
    let stride = corr.band().len().div_ceil(super::blur::BLUR_FIT_PIXELS) as f64;
    let mid = blur.max(probe);
    let [lo, at, hi] = [mid - probe, mid, mid + probe].map(|b| profiled_at(corr, lambda, b));
    let second = (lo.0 - 2.0 * at.0 + hi.0) / (probe * probe);
    (second > 0.0 && second.is_finite()).then(|| Coupling {
        slope: (hi.1 - lo.1) / (2.0 * probe),
        information: 0.5 * second * stride,
    })
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::band::Band;
    use crate::correlation::levels::LevelModel;
    use crate::curve::InitialCurve;
    use crate::interp::{Interpolation, Sampler};
    use crate::render::{render, Method, RenderSpec};
    use crate::spline::Basis;
    use crate::truth::Shape;
    use crate::virtual_image::Kind;

    /// The pixel-edge band of blur `blur` (px) on a circle of radius
    /// `r_ref` around the centre of an exact-coverage disc of radius `r`
    /// under that blur (16-bit, noiseless), and its sampler.
    fn dot(r: f64, r_ref: f64, blur: f64) -> (Correlation, Vec<f64>) {
        let size = (2.0 * r + 40.0) as usize;
        let (cx, cy) = (size as f64 / 2.0 + 0.3, size as f64 / 2.0 - 0.4);
        let spec = RenderSpec {
            width: size,
            height: size,
            shape: Shape::Circle { cx, cy, r },
            kind: Kind::Silhouette,
            method: Method::Coverage,
            foreground: 0.8,
            background: 0.2,
            blur_sigma: blur,
            bits: Some(16),
            ..RenderSpec::default()
        };
        let image = render(&spec).unwrap();
        let sampler = Sampler::new(&image, Interpolation::default());
        let curve = InitialCurve::Circle { cx, cy, r: r_ref }
            .to_curve()
            .unwrap();
        let n = ((curve.param_length() / 5.0).round() as usize).max(5);
        let basis = Basis::new(3, n, curve.param_length(), true).unwrap();
        let half_width = super::super::pixel_edge_band(blur);
        let profile = Profile::pixel_edge(blur);
        let band = Band::build(&curve, &basis, half_width, profile, size, size).unwrap();
        let corr = Correlation::prepare(band, basis, &sampler, LevelModel::Global, None).unwrap();
        let lambda = vec![0.0; corr.n_unknowns()];
        (corr, lambda)
    }

    /// The blur (px) that minimises `ssr` on `[1.5, 3.5]`.
    fn best(ssr: impl Fn(f64) -> f64) -> f64 {
        crate::psf::golden(1.5, 3.5, 40, &ssr)
    }

    /// A dot of radius 4 px under a 2.5 px blur, its curve 0.3 px too
    /// large: at the curve held fixed the blur that fits best is far off
    /// (the larger dot under a smaller blur looks alike), with the offset
    /// profiled out it is the dot's own, and the offset brings the curve
    /// onto the edge. The coupling's slope is that trade (negative: a
    /// larger blur, a smaller dot) and its position term grows as the
    /// noise's deviation.
    #[test]
    fn a_dot_trades_its_blur_for_its_offset() {
        let (corr, lambda) = dot(4.0, 4.3, 2.5);
        assert!(coupled(&corr, 2.5));
        let fixed = best(super::super::blur::blur_residual(&corr, &lambda));
        let profiled = best(profiled_residual(&corr, &lambda));
        let (_, offset) = profiled_at(&corr, &lambda, profiled);
        println!("fixed {fixed:.4}, profiled {profiled:.4}, offset {offset:+.4}");
        assert!((fixed - 2.5).abs() > 0.2, "fixed {fixed}");
        assert!((profiled - 2.5).abs() < 2e-3, "profiled {profiled}");
        assert!((offset + 0.3).abs() < 2e-3, "offset {offset}");
        let c = coupling(&corr, &lambda, profiled, 0.02).unwrap();
        println!("{c:?}");
        assert!(c.slope < -0.5 && c.information > 0.0, "{c:?}");
        let (one, four) = (c.position_sd(1e-6), c.position_sd(4e-6));
        assert!((four / one - 2.0).abs() < 1e-12 && one > 0.0);
        assert_eq!(c.position_sd(0.0), 0.0);
    }

    /// A disc many blurs across does not trade: its blur is fitted at the
    /// curve as before.
    #[test]
    fn a_large_disc_does_not_couple() {
        let (corr, _) = dot(60.0, 60.0, 2.5);
        assert!(!coupled(&corr, 2.5));
    }
}
