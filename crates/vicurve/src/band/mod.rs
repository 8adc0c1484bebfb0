//! The narrow band: the pixels around a reference curve, with their
//! curvilinear coordinates `(s, r)`.
//!
//! A pixel centre `X` belongs to the band of half-width `R` around the
//! reference curve `x0` when its exact closest point `x0(s)` is an interior
//! point of the curve (not an end of an open curve: pixels past the ends are
//! left out), its signed distance `r = (X - x0(s)) . n(s)` satisfies
//! `|r| < R`, and it is on the near side of the local centre of curvature
//! (`1 - kappa r > 0.1`; beyond, the closest point is ambiguous).
//!
//! Everything that depends only on the reference curve is computed here,
//! once per reference: `s`, `r`, the normal, the `p + 1` non-zero
//! displacement basis values at `s`, the virtual image profile
//! `gamma` with its derivative, the curvature at the foot and the pixel's
//! weight: `1 / (1 - kappa r)` for the paper's profiles (the band's
//! integral in `(s, r)`), 1 for the pushed ones, which model each pixel
//! (`build.rs`, `area_weight`).
//!
//! The steps, one a file:
//! - `build`: [`BandParams`] checked against the curve and the image
//!   ([`Band::new`]), the pixels' rows from the backend that [`Coords`]
//!   names, stored as the band's columns;
//! - `exact`: the closest-point projection of every pixel, started from
//!   the closest chord of a polyline of the curve (`raster`: the chords
//!   rasterised onto a grid of the image, in a [`BandScratch`]);
//! - `levelset_rows` with [`levelset`]: the paper's finite-element
//!   coordinates instead;
//! - `window`: the weights, and the window of a band with a margin;
//! - `bend`: the displaced curve's curvature for a kept band;
//! - `blurred_curvature`: the curvature the pixel-edge profile takes, the
//!   reference's averaged along it over the blur.
//!
//! # Why the weight
//! Pixels are uniform in the plane, so in `(s, r)` their density is
//! `1 - kappa r`: a convex edge has more band pixels outside than inside.
//! Where the physical profile differs from the virtual one (a sharp or
//! blurred step under the sine profile), the residual is antisymmetric in
//! `r` and this density tilts its balance: the curve moves by about
//! `0.1 R^2 kappa`. Weighting each pixel by the inverse density makes the
//! band uniform in `(s, r)`, as it is along a straight edge, and removes
//! that bias; it changes nothing where the profiles match.
//!
//! The closest point is found in two steps: a search over a polyline of the
//! curve (chords about `R / 2` long) gives each pixel a starting parameter,
//! then Newton's method on the exact curve refines it ([`SplineCurve::project`]).
//!
//! # Margin and window
//! A band built with a margin ([`Band::build_windowed`]) holds the pixels
//! within `R + margin` of the reference, but only those within `R` of the
//! curve displaced by the current `U` count ([`Band::recentre`]): their
//! weights are the band's [`weights`](Band::full_weights), the others' 0.
//! The pixels that count are then those around the displaced curve,
//! whatever the reference, as long as `|U|` stays within the margin: the
//! result no longer depends on the reference through the band's edges
//! (where the physical profile differs from the virtual one, a band
//! centred on the reference and not on the edge tips the balance of the
//! residuals by a fraction of `U`).
//!
//! # The displaced curve's curvature
//! The pixel-edge profile depends on the edge's curvature (a blurred
//! curved edge's half level lies `(sigma^2 + 1/12) kappa / 2` off it),
//! which it takes from the reference, averaged over the blur (see
//! `blurred_curvature`: the local curvature answers an oscillation the
//! blur has erased, and the settles grow it). A band that serves several frames of
//! a sequence (`fit::TrackCache`) has a reference a few frames old, and a
//! curve that shrinks, grows or bends in the meantime no longer has its
//! curvature: such a run takes the curvature of the curve it starts from
//! instead ([`Band::bend_to`]), as a band of its own, built on that curve,
//! would. For the curve displaced by `U` it is `kappa / (1 - kappa U) +
//! U'' / (1 - kappa U)^2` (`dt/ds = kappa n`; derivatives along the
//! reference's parameter, which is close to its arc length; terms in
//! `U'^2` and `U U'` left out): a parallel curve's plus the bending of `U`
//! itself, which cancel for a rigid motion. It stays fixed during the run:
//! the displacement's own `U''` in the iteration would also take the
//! short wiggles of the noise for curvature and amplify them (undoing the
//! blur's smoothing of a wiggly edge).
//!
//! # Levelset coordinates
//! With [`Coords::Levelset`] (the paper's way, method section 7) the pixels
//! get `s` and `r` by bilinear interpolation of the nodal values of a
//! [`LevelsetCoords`](levelset::LevelsetCoords) mesh instead: no pixel is
//! projected. The pixel's normal and curvature, which the exact backend
//! takes at its closest point, are then the curve's at the interpolated
//! `s`. A pixel belongs to the band when it lies in the meshed domain,
//! `|r| < R`, `1 - kappa r > 0.1` and, for an open curve, `0 < s < L` (the
//! exact backend's "closest point is not an end").

mod bend;
mod blurred_curvature;
mod build;
mod coords;
mod exact;
pub mod levelset;
mod levelset_rows;
mod raster;
mod window;

pub(crate) use blurred_curvature::BlurredCurvature;
pub use build::BandParams;
pub(crate) use build::{check_inside, inside_stretch};
pub use coords::Coords;
pub use raster::BandScratch;

use crate::curve::SplineCurve;
use crate::error::Result;
use crate::spline::Basis;
use crate::virtual_image::osculating;
use crate::virtual_image::pixel_edge::spread_variance;
use crate::virtual_image::{Anisotropy, Profile};

/// Pixels (and levelset mesh nodes) whose parallel-curve Jacobian
/// `1 - kappa r` is at or below this are left out: too close to (or beyond)
/// the centre of curvature.
const MIN_JACOBIAN: f64 = 0.1;
/// Pixels per parallel task of [`Band::recentre`] and [`Band::bend_to`].
const RECENTRE_CHUNK: usize = 4096;

/// The band pixels and their precomputed data; see the [module docs](self).
#[derive(Clone, Debug)]
pub struct Band {
    half_width: f64,
    /// Pixels out to `half_width + margin` are kept; see the module docs.
    margin: f64,
    /// Pixels within `half_width` of the displaced curve at the last
    /// [`Band::recentre`] (all of them without a margin).
    inside: usize,
    /// Whether the image border cuts the band (a closed curve near it,
    /// [`Band::new`]).
    clipped: bool,
    profile: Profile,
    degree: usize,
    pub(crate) pos: Vec<[f64; 2]>,
    pub(crate) normal: Vec<[f64; 2]>,
    pub(crate) s: Vec<f64>,
    pub(crate) r: Vec<f64>,
    pub(crate) first: Vec<u32>,
    /// `p + 1` basis values per pixel, pixel after pixel.
    pub(crate) basis: Vec<f64>,
    /// Their second derivatives along the parameter, 1/px^2, laid out
    /// alike: made by the first [`Band::bend_to`], empty until then.
    basis_d2: Vec<f64>,
    /// The reference's curvature at each pixel's foot, 1/px, kept by the
    /// first [`Band::bend_to`] (`curvature` is then the displaced
    /// curve's); empty until then.
    reference_curvature: Vec<f64>,
    /// `gamma(r / R)`.
    pub(crate) gamma: Vec<f64>,
    /// `gamma'(r / R) / R`, the derivative of the profile with respect to `r`.
    pub(crate) dgamma: Vec<f64>,
    /// The weight each pixel counts with: [`Band::full_weights`], or 0 out
    /// of the window (module docs).
    pub(crate) weight: Vec<f64>,
    /// `1 / (1 - kappa r)` or 1 (see the module docs), times any robust
    /// factor.
    pub(crate) full_weight: Vec<f64>,
    /// Signed curvature of the curve at the pixel's closest point, 1/px.
    pub(crate) curvature: Vec<f64>,
    /// The weight of the pixel-edge profile's blurred osculating circle at
    /// each pixel (`blurred_curvature.rs`); empty when it is 0 at every
    /// pixel.
    osculating: Vec<f64>,
    /// The corners' wedge terms in `gamma` (pixel-edge profile, see
    /// [`crate::virtual_image::corner`]); empty when no pixel has one.
    corner: Vec<f64>,
    /// The wedges behind them, by pixel index, to evaluate them under
    /// another blur ([`Band::corner_terms`]).
    corner_wedges: Vec<(u32, crate::virtual_image::corner::CornerWedge)>,
}

impl Band {
    /// The band of half-width `half_width` (pixels) around `curve`, for the
    /// displacement basis `basis` (whose parameter is the curve's) and the
    /// virtual `profile` (a [`Profile`] or a [`crate::virtual_image::Kind`]
    /// for the paper's), in an image of `width x height` pixels; all pixels,
    /// exact coordinates, no margin ([`BandParams::new`]).
    ///
    /// Errors: those of [`Band::new`].
    pub fn build(
        curve: &SplineCurve,
        basis: &Basis,
        half_width: f64,
        profile: impl Into<Profile>,
        width: usize,
        height: usize,
    ) -> Result<Band> {
        let params = BandParams::new(half_width, profile, width, height);
        Band::new(curve, basis, &params)
    }

    /// [`Band::build`] with a margin (see the [module docs](self)) and the
    /// coordinates `coords`: [`Band::new`] with those fields of
    /// [`BandParams`] set.
    ///
    /// Errors: those of [`Band::new`].
    #[allow(clippy::too_many_arguments)] // the callers' form; see `Band::new`
    pub fn build_windowed(
        curve: &SplineCurve,
        basis: &Basis,
        half_width: f64,
        margin: f64,
        profile: impl Into<Profile>,
        width: usize,
        height: usize,
        coords: Coords,
    ) -> Result<Band> {
        let params = BandParams {
            margin,
            coords,
            ..BandParams::new(half_width, profile, width, height)
        };
        Band::new(curve, basis, &params)
    }

    /// [`Band::build`], keeping one pixel in `thin` ([`BandParams::thin`])
    /// with the coordinates `coords`: [`Band::new`] with those fields of
    /// [`BandParams`] set.
    ///
    /// Errors: those of [`Band::new`].
    #[allow(clippy::too_many_arguments)] // the callers' form; see `Band::new`
    pub fn build_with(
        curve: &SplineCurve,
        basis: &Basis,
        half_width: f64,
        profile: impl Into<Profile>,
        width: usize,
        height: usize,
        thin: usize,
        coords: Coords,
    ) -> Result<Band> {
        let params = BandParams {
            thin,
            coords,
            ..BandParams::new(half_width, profile, width, height)
        };
        Band::new(curve, basis, &params)
    }

    /// The band `params` describes around `curve`, for the displacement
    /// basis `basis` (whose parameter is the curve's), with scratch grids
    /// from a pool shared by the process (see [`BandScratch`]).
    ///
    /// Errors: [`crate::Error::InvalidParameter`] for a half-width under
    /// 0.5 px, a negative or non-finite margin, or a basis whose length
    /// differs from the curve's; [`crate::Error::CurveOutsideImage`] when
    /// the curve leaves the image (the pixel centres' hull `[0, width-1] x
    /// [0, height-1]`) farther than 6 px from one of its corners (a
    /// corner's tip cut off by the frame is measured from the sides
    /// leading to it); [`crate::Error::BandOutsideImage`] when an open
    /// curve's band (out to `half_width + margin`) does (an open curve is
    /// trimmed where its band leaves, `fit`'s reference), or for a pushed
    /// profile the band out to its transition
    /// ([`Profile::transition_half_width`] plus margin). A closed curve's
    /// band may be cut by the border (a dot or a hole near it), and so may
    /// a pushed profile's beyond its transition (a noisy image's wide
    /// band, whose flat levels there only fix the gray levels): it is then
    /// the band's pixels in the image ([`Band::clipped`]). With
    /// [`Coords::Levelset`], those of [`levelset::LevelsetCoords::build`].
    pub fn new(curve: &SplineCurve, basis: &Basis, params: &BandParams) -> Result<Band> {
        let mut scratch = BandScratch::from_pool();
        let band = Band::new_in(curve, basis, params, &mut scratch);
        scratch.return_to_pool();
        band
    }

    /// Whether [`Band::bend_to`] gave the band another curve's curvature.
    pub(crate) fn is_bent(&self) -> bool {
        !self.reference_curvature.is_empty()
    }

    /// The same band (pixels, coordinates, profile, weights) on another
    /// displacement basis of the same reference: only the basis values are
    /// evaluated again, at the pixels' stored `s` (a refinement's finer
    /// basis, without the projection of every pixel). It is the band
    /// [`Band::build_with`] makes for `basis` when this one was made by it
    /// on the same reference, half-width, profile and coordinates,
    /// unthinned, not bent ([`Band::is_bent`]), and no robust factor
    /// entered its weights.
    pub(crate) fn rebased(&self, basis: &Basis) -> Band {
        let p = basis.degree();
        let mut b = self.clone();
        b.degree = p;
        b.first.clear();
        b.basis.clear();
        b.basis.reserve(self.s.len() * (p + 1));
        let mut values = [0.0; crate::spline::MAX_DEGREE + 1];
        for &s in &self.s {
            let first = basis.eval(s, &mut values) as u32;
            b.first.push(first);
            b.basis.extend_from_slice(&values[..=p]);
        }
        b
    }

    /// Number of pixels in the band.
    pub fn len(&self) -> usize {
        self.pos.len()
    }

    /// Whether the band holds no pixel.
    pub fn is_empty(&self) -> bool {
        self.pos.is_empty()
    }

    /// Half-width `R`, pixels (of the window, for a band with a margin).
    pub fn half_width(&self) -> f64 {
        self.half_width
    }

    /// The margin beyond the half-width, pixels (0 unless built with one,
    /// [`BandParams::margin`]).
    pub fn margin(&self) -> f64 {
        self.margin
    }

    /// The profile of the virtual image.
    pub fn profile(&self) -> Profile {
        self.profile
    }

    /// `(gamma, d gamma / d r)` of the band's profile at pixel `i` for the
    /// curve displaced by `u` pixels along its normal: at `r - u`, with the
    /// pixel's normal and curvature (the reference's, or the one
    /// [`Band::bend_to`] set; the pushed profile, see `fit::correlation`).
    /// At `u = 0` on the reference's curvature, the values the band holds
    /// (the same call, made once when the band was built).
    #[inline]
    pub fn profile_at(&self, i: usize, u: f64) -> (f64, f64) {
        if u == 0.0 && self.reference_curvature.is_empty() {
            return (self.gamma[i], self.dgamma[i]);
        }
        let (gamma, dgamma) = self.profile.eval_at(
            self.r[i] - u,
            self.half_width,
            self.normal[i],
            (self.curvature[i], self.osculating_at(i)),
        );
        (gamma + self.corner_at(i), dgamma)
    }

    /// The weight of the blurred osculating circle in pixel `i`'s profile
    /// (0 for most pixels; see [`crate::virtual_image::Profile::eval_at`]).
    #[inline]
    pub(crate) fn osculating_at(&self, i: usize) -> f64 {
        sparse_at(&self.osculating, i)
    }

    /// Whether the pixel-edge profile's blurred osculating circle counts
    /// in full, by at least half its weight, at some pixel
    /// (`blurred_curvature.rs`): where it barely starts it changes the
    /// profile's answer to the curvature by little.
    pub(crate) fn osculates(&self) -> bool {
        let Profile::PixelEdge { blur, .. } = self.profile else {
            return false;
        };
        let v = spread_variance(blur);
        (0..self.len())
            .any(|i| self.osculating_at(i) >= 0.5 && osculating::in_full(v, self.curvature[i]))
    }

    /// The corners' wedge term in pixel `i`'s profile (0 for most pixels;
    /// see [`crate::virtual_image::corner`]). It stays that of the
    /// reference while the curve is displaced: a stage re-references until
    /// the displacement is negligible.
    #[inline]
    pub(crate) fn corner_at(&self, i: usize) -> f64 {
        sparse_at(&self.corner, i)
    }

    /// Every pixel's wedge term under the pixel-edge profile of blur `blur`
    /// (px) with `anisotropy` instead of the band's, or `None` when no pixel
    /// has one (for comparing blurs at a fixed curve; allocates).
    pub(crate) fn corner_terms(&self, blur: f64, anisotropy: Anisotropy) -> Option<Vec<f64>> {
        if self.corner_wedges.is_empty() {
            return None;
        }
        let mut terms = vec![0.0; self.len()];
        for (i, w) in &self.corner_wedges {
            terms[*i as usize] += w.term_for(blur, anisotropy);
        }
        Some(terms)
    }

    /// Whether the image border cuts the band: a closed curve near the
    /// border keeps the band's pixels in the image ([`Band::new`]).
    pub fn clipped(&self) -> bool {
        self.clipped
    }

    /// Whether pixel `i`, displaced by `u` (pixels) out of the image,
    /// lies beyond a border that cuts the band while the curve's point
    /// it belongs to, displaced alike, stays where `inside` says the image
    /// is: not the curve leaving the image, only a pixel the border took.
    /// Always false for a band that fits in the image.
    pub(crate) fn cut_by_border(
        &self,
        i: usize,
        u: f64,
        inside: impl Fn(f64, f64) -> bool,
    ) -> bool {
        if !self.clipped {
            return false;
        }
        let ([x, y], [nx, ny]) = (self.pos[i], self.normal[i]);
        let along = u - self.r[i];
        inside(x + along * nx, y + along * ny)
    }

    /// `U` at pixel `i` for the displacement `lambda` (coefficients in
    /// `basis`, the band's), pixels.
    #[inline]
    pub(crate) fn displacement_at(&self, basis: &Basis, i: usize, lambda: &[f64]) -> f64 {
        let p = self.degree;
        displacement(basis, self.first[i], &self.basis[i * (p + 1)..], lambda)
    }

    /// Degree of the displacement basis.
    pub fn degree(&self) -> usize {
        self.degree
    }

    /// Pixel centres `[x, y]` of the band.
    pub fn positions(&self) -> &[[f64; 2]] {
        &self.pos
    }

    /// Curvilinear abscissa (reference curve parameter) of each pixel, pixels.
    pub fn s(&self) -> &[f64] {
        &self.s
    }

    /// Signed distance of each pixel to the reference curve, pixels.
    pub fn r(&self) -> &[f64] {
        &self.r
    }
}

/// `sum_k lambda[first + k] values[k]` over the `p + 1` functions of
/// `basis` from `first` (a pixel's `U` from its basis values, or `U''`
/// from their second derivatives).
#[inline]
fn displacement(basis: &Basis, first: u32, values: &[f64], lambda: &[f64]) -> f64 {
    let first = first as usize;
    values[..=basis.degree()]
        .iter()
        .enumerate()
        .map(|(k, v)| lambda[basis.index(first, k)] * v)
        .sum()
}

/// Pixel `i`'s value of a per-pixel term that most bands do not have
/// (kept empty then): 0 for an empty one.
#[inline]
fn sparse_at(values: &[f64], i: usize) -> f64 {
    values.get(i).copied().unwrap_or(0.0)
}

#[cfg(test)]
mod tests {
    use super::{Band, BandParams, Coords};
    use crate::curve::SplineCurve;
    use crate::spline::Basis;
    use crate::virtual_image::{Kind, Profile};

    /// A band rebased on a finer basis of its reference (a refinement's
    /// halving) is, to the bit, the band built on that basis: the same
    /// pixels, coordinates, profile, weights and basis values.
    #[test]
    fn a_rebased_band_is_the_band_built_on_its_basis() {
        let pts: Vec<[f64; 2]> = (0..400)
            .map(|i| {
                let t = std::f64::consts::TAU * i as f64 / 400.0;
                [
                    120.3 + 70.0 * t.cos() + 6.0 * (5.0 * t).cos(),
                    110.7 + 50.0 * t.sin(),
                ]
            })
            .collect();
        let curve = SplineCurve::fit(&pts, true, 3, 4.0).unwrap();
        let basis = |n: usize| Basis::new(3, n, curve.param_length(), true).unwrap();
        let profiles = [
            Profile::Paper {
                kind: Kind::Silhouette,
            },
            Profile::pixel_edge(1.2),
        ];
        for profile in profiles {
            let build =
                |b: &Basis| Band::build_with(&curve, b, 3.0, profile, 240, 220, 1, Coords::Exact);
            let coarse = build(&basis(12)).unwrap();
            let fine = basis(24);
            let rebased = coarse.rebased(&fine);
            let built = build(&fine).unwrap();
            assert!(built.len() > 1000, "{}", built.len());
            assert_eq!(format!("{rebased:?}"), format!("{built:?}"), "{profile:?}");
        }
    }

    /// The distances-only band is the band's pixels and `r`, to the bit and
    /// in its order: on a smooth curve, with exact and levelset coordinates,
    /// and on a square with corners (whose clearances leave pixels out).
    #[test]
    fn the_distances_are_those_of_the_band() {
        let smooth: Vec<[f64; 2]> = (0..300)
            .map(|i| {
                let t = std::f64::consts::TAU * i as f64 / 300.0;
                [90.3 + 50.0 * t.cos(), 80.7 + 40.0 * t.sin()]
            })
            .collect();
        let square: Vec<[f64; 2]> = (0..160)
            .map(|i| {
                let (side, f) = (i / 40, (i % 40) as f64 / 40.0);
                let (a, b) = (40.2 + 100.0 * f, 140.2 - 100.0 * f);
                match side {
                    0 => [a, 40.4],
                    1 => [140.2, a],
                    2 => [b, 140.4],
                    _ => [40.2, b],
                }
            })
            .collect();
        let curves = [
            SplineCurve::fit(&smooth, true, 3, 4.0).unwrap(),
            SplineCurve::fit_with_corners(&square, true, 3, 4.0, &[0, 40, 80, 120]).unwrap(),
        ];
        let levelset = Coords::Levelset { mesh_size: 10.0 };
        let cases = [
            (&curves[0], Coords::Exact),
            (&curves[0], levelset),
            (&curves[1], Coords::Exact),
        ];
        for (curve, coords) in cases {
            let basis = Basis::new(1, 2, curve.param_length(), true).unwrap();
            let params = BandParams {
                coords,
                ..BandParams::new(6.0, Kind::Silhouette, 190, 180)
            };
            let band = Band::new(curve, &basis, &params).unwrap();
            let distances = Band::distances(curve, &basis, &params).unwrap();
            assert!(band.len() > 2000, "{}", band.len());
            let want: Vec<([f64; 2], f64)> = band
                .positions()
                .iter()
                .zip(band.r())
                .map(|(p, r)| (*p, *r))
                .collect();
            let got: Vec<([f64; 2], f64)> = distances.iter().map(|d| (d.0, d.1)).collect();
            assert_eq!(got, want, "{coords:?}");
            // With exact coordinates, the normal at each foot (the band's
            // `s`) is the unit vector from it to the pixel.
            if matches!(coords, Coords::Exact) {
                for ((p, r, n), &s) in distances.into_iter().zip(band.s()) {
                    assert!(((n[0] * n[0] + n[1] * n[1]) - 1.0).abs() < 1e-12);
                    let back = [p[0] - r * n[0], p[1] - r * n[1]];
                    assert!(crate::curve::dist(back, curve.point(s)) < 1e-6, "{p:?}");
                }
            }
        }
    }
}
