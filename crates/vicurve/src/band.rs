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
//! weight `1 / (1 - kappa r)`.
//!
//! # Why the weight
//! Pixels are uniform in the plane, so in `(s, r)` their density is
//! `1 - kappa r`: a convex edge has more band pixels outside than inside.
//! Where the physical profile differs from the virtual one (a sharp or
//! blurred step under the sine profile), the residual is antisymmetric in
//! `r` and this density tilts its balance: the curve moves by about
//! `0.1 R^2 kappa` (0.28 px for `R = 20` on a disc of radius 150, 6e-3 px
//! for `R = 2`). Weighting each pixel by the inverse density makes the band
//! uniform in `(s, r)`, as it is along a straight edge, and removes that
//! bias; it changes nothing where the profiles match.
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
//! which it takes from the reference. A band that serves several frames of
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
//! short wiggles of the noise for curvature and amplify them (the blur's
//! smoothing of a wiggly edge undone; measured: the error of a sine edge
//! grown from a segment doubled, its elements halved). Without it, on a
//! disc of radius 25 px shrinking 0.4 px per frame at a blur of 1 px,
//! tracked on kept bands, the mean error was -1.5e-3 px against -7.5e-4
//! on bands of their own; with it, -3.5e-4 px (its start is moved on by
//! the last frame's change, a band of its own is a frame behind).
//!
//! # Levelset coordinates
//! With [`Coords::Levelset`] (the paper's way, method section 7) the pixels
//! get `s` and `r` by bilinear interpolation of the nodal values of a
//! [`LevelsetCoords`] mesh instead: no pixel is projected. The pixel's
//! normal and curvature, which the exact backend takes at its closest point,
//! are then the curve's at the interpolated `s`. A pixel belongs to the band
//! when it lies in the meshed domain, `|r| < R`, `1 - kappa r > 0.1` and,
//! for an open curve, `0 < s < L` (the exact backend's "closest point is
//! not an end").

use crate::curve::SplineCurve;
use crate::error::{Error, Result};
use crate::fit::Coords;
use crate::levelset::LevelsetCoords;
use crate::spline::{Basis, MAX_DEGREE};
use crate::virtual_image::Profile;
use rayon::prelude::*;
use std::sync::Mutex;

/// Pixels whose parallel-curve Jacobian `1 - kappa r` is below this are left
/// out: too close to (or beyond) the centre of curvature.
const MIN_JACOBIAN: f64 = 0.1;
/// Pixels per parallel task of [`Band::recentre`].
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
    /// `1 / (1 - kappa r)` (see the module docs), times any robust factor.
    pub(crate) full_weight: Vec<f64>,
    /// Signed curvature of the curve at the pixel's closest point, 1/px.
    pub(crate) curvature: Vec<f64>,
}

/// One band pixel with everything [`Band`] stores about it, as the parallel
/// part of [`Band::build`] computes it.
struct Candidate {
    pos: [f64; 2],
    normal: [f64; 2],
    s: f64,
    r: f64,
    first: u32,
    basis: [f64; MAX_DEGREE + 1],
    gamma: f64,
    dgamma: f64,
    weight: f64,
    curvature: f64,
}

impl Band {
    /// The band of half-width `half_width` (pixels) around `curve`, for the
    /// displacement basis `basis` (whose parameter is the curve's) and the
    /// virtual `profile` (a [`Profile`] or a [`crate::virtual_image::Kind`]
    /// for the paper's), in an image of `width x height` pixels.
    ///
    /// Errors: [`Error::InvalidParameter`] for a half-width under 0.5 px or
    /// a basis whose length differs from the curve's;
    /// [`Error::CurveOutsideImage`] when the curve leaves the image;
    /// [`Error::BandOutsideImage`] when the band does (interpolation needs the
    /// band inside the pixel centres' hull `[0, width-1] x [0, height-1]`).
    pub fn build(
        curve: &SplineCurve,
        basis: &Basis,
        half_width: f64,
        profile: impl Into<Profile>,
        width: usize,
        height: usize,
    ) -> Result<Band> {
        Band::build_with(
            curve,
            basis,
            half_width,
            profile,
            width,
            height,
            1,
            Coords::Exact,
        )
    }

    /// [`Band::build`] with a margin (see the [module docs](self)): the
    /// pixels out to `half_width + margin` (pixels) are kept, those within
    /// `half_width` of the reference count until the first
    /// [`Band::recentre`]. `coords` as in [`Band::build_with`].
    ///
    /// Errors: those of [`Band::build_with`] for a half-width of
    /// `half_width + margin`, and [`Error::InvalidParameter`] for a negative
    /// or non-finite margin.
    #[allow(clippy::too_many_arguments)]
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
        if !(margin.is_finite() && margin >= 0.0) {
            return Err(Error::invalid(
                "band margin",
                format!("{margin} px (must be 0 or more)"),
            ));
        }
        Band::build_inner(
            curve, basis, half_width, margin, profile, width, height, 1, coords,
        )
    }

    /// [`Band::build`], keeping one pixel in `thin` (each with `thin` times
    /// the weight): 1 keeps all, 2 a checkerboard, 4 every other pixel of
    /// every other row (any other value is taken as the nearest of these
    /// below it).
    ///
    /// For the coarse stages of a schedule: they only need to bring the
    /// curve near the edge, and half the pixels of a wide band do that at
    /// half the cost. The last stage always uses every pixel.
    ///
    /// `coords` chooses how the pixels get their `(s, r)`: exact projection
    /// or the paper's levelsets (see the [module docs](self)); the latter
    /// may also fail as [`LevelsetCoords::build`] does.
    #[allow(clippy::too_many_arguments)]
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
        Band::build_inner(
            curve, basis, half_width, 0.0, profile, width, height, thin, coords,
        )
    }

    /// [`Band::build_with`] out to `half_width + margin` (pixels), the
    /// profile taken with `half_width`.
    #[allow(clippy::too_many_arguments)]
    fn build_inner(
        curve: &SplineCurve,
        basis: &Basis,
        half_width: f64,
        margin: f64,
        profile: impl Into<Profile>,
        width: usize,
        height: usize,
        thin: usize,
        coords: Coords,
    ) -> Result<Band> {
        let profile = profile.into();
        if !(half_width.is_finite() && half_width >= 0.5) {
            return Err(Error::invalid(
                "band half-width",
                format!("{half_width} px (must be at least 0.5 px)"),
            ));
        }
        let l = curve.param_length();
        if (basis.length() - l).abs() > 1e-9 * l.max(1.0) || basis.is_closed() != curve.is_closed()
        {
            return Err(Error::invalid(
                "displacement basis",
                "its length or closure differs from the reference curve's",
            ));
        }
        let reach = half_width + margin;
        check_inside(curve, reach, width, height)?;
        let cut = Cut {
            half_width,
            reach,
            thin,
        };
        let rows = match coords {
            Coords::Exact => Band::exact_rows(curve, basis, cut, profile, width, height),
            Coords::Levelset { mesh_size } => {
                let levelsets = LevelsetCoords::build(curve, reach, mesh_size, width, height)?;
                Band::levelset_rows(&levelsets, curve, basis, cut, profile, width, height)
            }
        };

        let total: usize = rows.iter().map(Vec::len).sum();
        let p = basis.degree();
        let mut band = Band {
            half_width,
            margin,
            inside: 0,
            profile,
            degree: p,
            pos: Vec::with_capacity(total),
            normal: Vec::with_capacity(total),
            s: Vec::with_capacity(total),
            r: Vec::with_capacity(total),
            first: Vec::with_capacity(total),
            basis: Vec::with_capacity(total * (p + 1)),
            basis_d2: Vec::new(),
            reference_curvature: Vec::new(),
            gamma: Vec::with_capacity(total),
            dgamma: Vec::with_capacity(total),
            weight: Vec::with_capacity(total),
            full_weight: Vec::with_capacity(total),
            curvature: Vec::with_capacity(total),
        };
        for c in rows.into_iter().flatten() {
            band.pos.push(c.pos);
            band.normal.push(c.normal);
            band.s.push(c.s);
            band.r.push(c.r);
            band.first.push(c.first);
            band.basis.extend_from_slice(&c.basis[..=p]);
            band.gamma.push(c.gamma);
            band.dgamma.push(c.dgamma);
            band.full_weight.push(c.weight);
            band.weight.push(c.weight);
            band.curvature.push(c.curvature);
        }
        band.inside = band.len();
        // With a margin, the pixels within `half_width` of the reference
        // count until the first `recentre`.
        band.window_at_reference();
        Ok(band)
    }

    /// The band pixels by exact projection, row by row (raster order).
    fn exact_rows(
        curve: &SplineCurve,
        basis: &Basis,
        cut: Cut,
        profile: Profile,
        width: usize,
        height: usize,
    ) -> Vec<Vec<Candidate>> {
        let Cut {
            half_width,
            reach: band_reach,
            thin,
        } = cut;
        let l = curve.param_length();
        // Polyline of the curve: chords short enough that the closest chord
        // leads Newton to the global closest point.
        let step = (0.5 * band_reach).clamp(0.5, 4.0);
        let count = ((l / step).ceil() as usize).max(4);
        let params = curve.sample_params(if curve.is_closed() { count } else { count + 1 });
        let verts: Vec<[f64; 2]> = params.iter().map(|&u| curve.point(u)).collect();
        let nseg = if curve.is_closed() {
            verts.len()
        } else {
            verts.len() - 1
        };

        let chords = Chords {
            verts: &verts,
            params: &params,
            nseg,
            closed: curve.is_closed(),
            length: l,
        };
        // The polyline is within its largest sagitta of the curve (about
        // chord * turning angle / 8; bounded by a quarter for safety): a
        // pixel within `band_reach` of the curve is within `band_reach +
        // sagitta` of its nearest chord, which the grid below reaches with
        // a pixel to spare; only such pixels need the exact projection.
        let turns = if curve.is_closed() { nseg } else { nseg - 1 };
        let sagitta = (0..turns)
            .map(|k| {
                let (t0, t1) = (chords.dir(k), chords.dir(k + 1));
                step * (t0[0] * t1[1] - t0[1] * t1[0]).abs().asin() / 4.0
            })
            .fold(0.0, f64::max);
        let reach = band_reach + sagitta + 1.0;
        // The control polygon's box contains the curve and its polyline.
        let bb = curve.bounding_box();
        let gx0 = ((bb[0] - reach).floor().max(0.0)) as usize;
        let gy0 = ((bb[1] - reach).floor().max(0.0)) as usize;
        let gx1 = ((bb[2] + reach).ceil().min(width as f64 - 1.0)).max(0.0) as usize;
        let gy1 = ((bb[3] + reach).ceil().min(height as f64 - 1.0)).max(0.0) as usize;
        let gw = gx1 + 1 - gx0;
        let gh = gy1 + 1 - gy0;
        // Per cell: one plus the squared distance to the closest chord and
        // the parameter of its foot, as f32 bits packed in a u64 (a starting
        // point for Newton); the smaller packed value wins, so the grid does
        // not depend on the order of the chords. Zero marks a cell no chord
        // reached. The cells reached are listed in `touched`, so that neither
        // clearing nor scanning costs the bounding box's area, and the grids
        // are kept zeroed in a pool between bands (a fresh one would cost a
        // page fault per row the curve crosses). The chords are rasterised
        // in `GRID_PARTS` runs in parallel, each on its own grid, merged
        // after.
        let grid = GridShape {
            gx0,
            gy0,
            gx1,
            gy1,
            gw,
            reach,
        };
        let per = nseg.div_ceil(GRID_PARTS).max(1);
        let mut parts: Vec<(Vec<u64>, Vec<u32>)> = (0..GRID_PARTS)
            .into_par_iter()
            .map(|part| {
                let mut best = take_grid(gw * gh);
                let mut touched = Vec::new();
                let range = (part * per).min(nseg)..((part + 1) * per).min(nseg);
                chords.rasterize(range, &grid, &mut best, &mut touched);
                (best, touched)
            })
            .collect();
        let (mut best, mut touched) = parts.remove(0);
        for (mut other, cells) in parts {
            for cell in cells {
                let c = cell as usize;
                let v = std::mem::take(&mut other[c]);
                if best[c] == 0 {
                    touched.push(cell);
                    best[c] = v;
                } else {
                    best[c] = best[c].min(v);
                }
            }
            keep_grid(other);
        }
        // Refine on the exact curve, row by row in parallel (raster order kept).
        let cutoff2 = (band_reach + sagitta + 1e-6).powi(2);
        let weight = thin_weight(thin);
        // Pixels that see both sides of a corner (see `curve/corners.rs`).
        let clearances = curve.corner_clearances();
        // Raster order, whatever order the chords reached the cells in.
        touched.par_sort_unstable();
        let rows = touched
            .par_chunks(TOUCHED_CHUNK)
            .map(|cells| {
                let mut out = Vec::new();
                for &cell in cells {
                    let cell = cell as usize;
                    let (i, j) = (cell % gw, cell / gw);
                    if thinned_out(thin, gx0 + i, gy0 + j) {
                        continue;
                    }
                    let (key, u0) = unpack(best[cell]);
                    if f64::from(key) - 1.0 > cutoff2 {
                        continue;
                    }
                    let x = (gx0 + i) as f64;
                    let y = (gy0 + j) as f64;
                    let pr = curve.project(x, y, f64::from(u0));
                    let jacobian = 1.0 - pr.curvature * pr.r;
                    if pr.at_end || pr.r.abs() >= band_reach || jacobian <= MIN_JACOBIAN {
                        continue;
                    }
                    if clearances
                        .iter()
                        .any(|(v, radius)| (x - v[0]).hypot(y - v[1]) < *radius)
                    {
                        continue;
                    }
                    let mut values = [0.0; MAX_DEGREE + 1];
                    let first = basis.eval(pr.u, &mut values) as u32;
                    let (gamma, dgamma) = profile.eval(pr.r, half_width, pr.normal, pr.curvature);
                    out.push(Candidate {
                        pos: [x, y],
                        normal: pr.normal,
                        s: pr.u,
                        r: pr.r,
                        first,
                        basis: values,
                        gamma,
                        dgamma,
                        weight: weight / jacobian,
                        curvature: pr.curvature,
                    });
                }
                out
            })
            .collect();
        for &cell in &touched {
            best[cell as usize] = 0;
        }
        keep_grid(best);
        rows
    }

    /// The band pixels with levelset coordinates, row by row (raster
    /// order): the pixels of the meshed domain whose interpolated `(s, r)`
    /// are in the band (see the module docs).
    fn levelset_rows(
        levelsets: &LevelsetCoords,
        curve: &SplineCurve,
        basis: &Basis,
        cut: Cut,
        profile: Profile,
        width: usize,
        height: usize,
    ) -> Vec<Vec<Candidate>> {
        let Cut {
            half_width,
            reach,
            thin,
        } = cut;
        let l = curve.param_length();
        let closed = curve.is_closed();
        let weight = thin_weight(thin);
        let b = levelsets.bounds();
        let x0 = b[0].ceil().max(0.0) as usize;
        let y0 = b[1].ceil().max(0.0) as usize;
        let x1 = b[2].floor().min(width as f64 - 1.0);
        let y1 = b[3].floor().min(height as f64 - 1.0);
        if x1 < x0 as f64 || y1 < y0 as f64 {
            return Vec::new();
        }
        let (x1, y1) = (x1 as usize, y1 as usize);
        (y0..=y1)
            .into_par_iter()
            .map(|y| {
                let mut out = Vec::new();
                let mut spans = Vec::new();
                levelsets.row_spans(y as f64, &mut spans);
                let columns = spans.iter().flat_map(|&[a, b]| {
                    let a = a.ceil().max(x0 as f64) as usize;
                    let b = b.floor().min(x1 as f64);
                    // An empty range when the span holds no pixel column.
                    a..if b >= a as f64 { b as usize + 1 } else { a }
                });
                for x in columns {
                    if thinned_out(thin, x, y) {
                        continue;
                    }
                    let (xf, yf) = (x as f64, y as f64);
                    let Some((s, r)) = levelsets.eval(xf, yf) else {
                        continue;
                    };
                    if r.abs() >= reach || (!closed && (s <= 0.0 || s >= l)) {
                        continue;
                    }
                    let f = curve.frame(s);
                    let jacobian = 1.0 - f.curvature * r;
                    if jacobian <= MIN_JACOBIAN {
                        continue;
                    }
                    let mut values = [0.0; MAX_DEGREE + 1];
                    let first = basis.eval(s, &mut values) as u32;
                    let (gamma, dgamma) = profile.eval(r, half_width, f.normal, f.curvature);
                    out.push(Candidate {
                        pos: [xf, yf],
                        normal: f.normal,
                        s,
                        r,
                        first,
                        basis: values,
                        gamma,
                        dgamma,
                        weight: weight / jacobian,
                        curvature: f.curvature,
                    });
                }
                out
            })
            .collect()
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

    /// The margin beyond the half-width, pixels (0 unless built by
    /// [`Band::build_windowed`]).
    pub fn margin(&self) -> f64 {
        self.margin
    }

    /// Pixels that count at the last [`Band::recentre`]: those within the
    /// half-width of the displaced curve ([`Band::len`] without a margin).
    pub fn inside(&self) -> usize {
        self.inside
    }

    /// Each pixel's weight before the window: `1 / (1 - kappa r)` (module
    /// docs), times any robust factor.
    pub fn full_weights(&self) -> &[f64] {
        &self.full_weight
    }

    /// Set the weights before the window (one per pixel; a robust fit's
    /// reweighting) and window them on the curve displaced by `lambda`
    /// (coefficients in `basis`, the band's), as [`Band::recentre`].
    ///
    /// Panics if `weights` does not hold one weight per pixel.
    pub(crate) fn set_full_weights(&mut self, weights: Vec<f64>, basis: &Basis, lambda: &[f64]) {
        assert_eq!(weights.len(), self.len(), "one weight per band pixel");
        self.full_weight = weights;
        if self.margin > 0.0 {
            self.recentre(basis, lambda);
        } else {
            self.weight.clone_from(&self.full_weight);
        }
    }

    /// Window a band with a margin on its reference (`U = 0`, as
    /// [`Band::recentre`] with a zero displacement, without evaluating
    /// it): the window it is built with, and the one a system's constant
    /// matrix is assembled over. Without a margin, nothing changes.
    pub(crate) fn window_at_reference(&mut self) {
        if self.margin == 0.0 {
            return;
        }
        let h = self.half_width;
        let mut inside = 0;
        for ((w, full), r) in self.weight.iter_mut().zip(&self.full_weight).zip(&self.r) {
            let counts = r.abs() < h;
            *w = if counts { *full } else { 0.0 };
            inside += usize::from(counts);
        }
        self.inside = inside;
    }

    /// Window a band with a margin on the curve displaced by `lambda`
    /// (coefficients in `basis`, the band's): a pixel counts with its
    /// weight when `|r - U| < R`, with 0 otherwise (module docs). Returns
    /// the sum of the weights. Without a margin, nothing changes.
    pub fn recentre(&mut self, basis: &Basis, lambda: &[f64]) -> f64 {
        if self.margin == 0.0 {
            return self.weight.iter().sum();
        }
        let p = self.degree;
        let h = self.half_width;
        let (r, first, values, full) = (&self.r, &self.first, &self.basis, &self.full_weight);
        let (sum, inside) = self
            .weight
            .par_chunks_mut(RECENTRE_CHUNK)
            .enumerate()
            .map(|(k, chunk)| {
                let mut sum = 0.0;
                let mut inside = 0;
                for (j, w) in chunk.iter_mut().enumerate() {
                    let i = k * RECENTRE_CHUNK + j;
                    let u = displacement(basis, first[i], &values[i * (p + 1)..], lambda);
                    *w = if (r[i] - u).abs() < h {
                        inside += 1;
                        full[i]
                    } else {
                        0.0
                    };
                    sum += *w;
                }
                (sum, inside)
            })
            .reduce(|| (0.0, 0), |a, b| (a.0 + b.0, a.1 + b.1));
        self.inside = inside;
        sum
    }

    /// `U` at pixel `i` for the displacement `lambda` (coefficients in
    /// `basis`, the band's), pixels.
    #[inline]
    pub(crate) fn displacement_at(&self, basis: &Basis, i: usize, lambda: &[f64]) -> f64 {
        let p = self.degree;
        displacement(basis, self.first[i], &self.basis[i * (p + 1)..], lambda)
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
        self.profile.eval(
            self.r[i] - u,
            self.half_width,
            self.normal[i],
            self.curvature[i],
        )
    }

    /// Take the curvature of the curve displaced by `lambda` (coefficients
    /// in `basis`, the band's) at every pixel, instead of the reference's,
    /// until the next call (module docs). The first call also evaluates the
    /// basis' second derivatives at the pixels (kept for the next). Does
    /// nothing on the bands of the paper's profiles, which do not take the
    /// curvature. Where `1 - kappa U` falls under the band's smallest
    /// Jacobian (`U` beyond the centre of curvature) the reference's stays.
    pub fn bend_to(&mut self, basis: &Basis, lambda: &[f64]) {
        if !self.profile.is_pushed() {
            return;
        }
        let p = self.degree;
        if self.basis_d2.is_empty() {
            let s = &self.s;
            self.basis_d2 = vec![0.0; s.len() * (p + 1)];
            self.basis_d2
                .par_chunks_mut(RECENTRE_CHUNK * (p + 1))
                .enumerate()
                .for_each(|(k, chunk)| {
                    let mut v = [0.0; MAX_DEGREE + 1];
                    for (j, d2) in chunk.chunks_exact_mut(p + 1).enumerate() {
                        basis.eval_d2(s[k * RECENTRE_CHUNK + j], &mut v);
                        d2.copy_from_slice(&v[..=p]);
                    }
                });
        }
        if self.reference_curvature.is_empty() {
            self.reference_curvature = self.curvature.clone();
        }
        let (first, values, d2) = (&self.first, &self.basis, &self.basis_d2);
        let kappa = &self.reference_curvature;
        self.curvature
            .par_chunks_mut(RECENTRE_CHUNK)
            .enumerate()
            .for_each(|(k, chunk)| {
                for (j, bent) in chunk.iter_mut().enumerate() {
                    let i = k * RECENTRE_CHUNK + j;
                    let u = displacement(basis, first[i], &values[i * (p + 1)..], lambda);
                    let u2 = displacement(basis, first[i], &d2[i * (p + 1)..], lambda);
                    let q = 1.0 - kappa[i] * u;
                    *bent = if q > MIN_JACOBIAN {
                        kappa[i] / q + u2 / (q * q)
                    } else {
                        kappa[i]
                    };
                }
            });
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

/// Which pixels a band keeps: those within `reach` of the curve (one in
/// `thin`), its profile taken with `half_width` (pixels).
#[derive(Clone, Copy)]
struct Cut {
    half_width: f64,
    reach: f64,
    thin: usize,
}

/// The weight of a kept pixel when one in `thin` is kept (see
/// [`Band::build_with`]).
fn thin_weight(thin: usize) -> f64 {
    match thin {
        0 | 1 => 1.0,
        2 | 3 => 2.0,
        _ => 4.0,
    }
}

/// Grids of [`Band::exact_rows`] kept for the next bands, all zero.
static GRIDS: Mutex<Vec<Vec<u64>>> = Mutex::new(Vec::new());

/// Cells of a grid kept for the next band (128 MB); a larger one is freed.
const MAX_KEPT_GRID: usize = 1 << 24;
/// Grids kept at most: two per band being built, for two curves measured
/// at once (at most 512 MB kept, for bands around curves 4000 px across).
const MAX_KEPT_GRIDS: usize = 4;
/// Parallel runs of the chords' rasterisation.
const GRID_PARTS: usize = 2;

/// A zeroed grid of at least `cells` cells, from the pool when it has one.
fn take_grid(cells: usize) -> Vec<u64> {
    let kept = GRIDS.lock().ok().and_then(|mut g| g.pop());
    match kept {
        Some(g) if g.len() >= cells => g,
        _ => vec![0; cells],
    }
}

/// Return a grid, all zero again, to the pool.
fn keep_grid(grid: Vec<u64>) {
    if grid.len() <= MAX_KEPT_GRID {
        if let Ok(mut g) = GRIDS.lock() {
            if g.len() < MAX_KEPT_GRIDS {
                g.push(grid);
            }
        }
    }
}

/// Where [`Chords::rasterize`] writes: the grid's box of pixel centres
/// `[gx0, gx1] x [gy0, gy1]`, `gw` cells per row, and how far from a chord
/// it looks, pixels.
struct GridShape {
    gx0: usize,
    gy0: usize,
    gx1: usize,
    gy1: usize,
    gw: usize,
    reach: f64,
}

/// The polyline of a curve: vertices at parameters `params`, `nseg`
/// chords (closing back to the first vertex when closed).
struct Chords<'a> {
    verts: &'a [[f64; 2]],
    params: &'a [f64],
    nseg: usize,
    closed: bool,
    length: f64,
}

impl Chords<'_> {
    /// Unit direction of chord `k` (wrapping around).
    fn dir(&self, k: usize) -> [f64; 2] {
        let n = self.verts.len();
        let a = self.verts[k % n];
        let b = self.verts[(k + 1) % n];
        let d = [b[0] - a[0], b[1] - a[1]];
        let len = (d[0] * d[0] + d[1] * d[1]).sqrt().max(1e-12);
        [d[0] / len, d[1] / len]
    }

    /// Write, for every cell near chords `range`, the smaller of its value
    /// and the packed (squared distance, foot parameter) of the chord; the
    /// cells first reached go to `touched`.
    fn rasterize(
        &self,
        range: std::ops::Range<usize>,
        grid: &GridShape,
        best: &mut [u64],
        touched: &mut Vec<u32>,
    ) {
        let (verts, params, nseg) = (self.verts, self.params, self.nseg);
        let reach = grid.reach;
        for k in range {
            let a = verts[k];
            let b = verts[(k + 1) % verts.len()];
            let ua = params[k];
            let ub = if k + 1 < params.len() {
                params[k + 1]
            } else {
                self.length
            };
            let d = [b[0] - a[0], b[1] - a[1]];
            let len = (d[0] * d[0] + d[1] * d[1]).sqrt();
            let dd = (len * len).max(1e-300);
            // Only the pixels whose foot falls on this chord (give or take
            // `ext`) can have it as their closest chord. `ext` covers the
            // wedge between this chord's rectangle and its neighbours' on the
            // convex side, which widens with the distance and the turning.
            let t = self.dir(k);
            let turn = |j: usize| {
                let o = self.dir(j);
                (t[0] * o[1] - t[1] * o[0]).abs().asin()
            };
            let prev = if self.closed {
                turn(k + nseg - 1)
            } else if k > 0 {
                turn(k - 1)
            } else {
                0.0
            };
            let next = if k + 1 < nseg || self.closed {
                turn(k + 1)
            } else {
                0.0
            };
            let ext = 1.0 + reach * prev.max(next).min(1.0) * 2.0;
            let (lo, hi) = (-ext, len + ext);
            let n = [-t[1], t[0]];
            let y_lo = ((a[1].min(b[1]) - reach - ext).floor().max(grid.gy0 as f64)) as usize;
            let y_hi = ((a[1].max(b[1]) + reach + ext).ceil().min(grid.gy1 as f64)) as usize;
            for y in y_lo..=y_hi {
                let py = y as f64 - a[1];
                // x-range where (X - a).t in [lo, hi] and |(X - a).n| <= reach.
                let mut x_min = f64::NEG_INFINITY;
                let mut x_max = f64::INFINITY;
                for (axis, (mn, mx)) in [(t, (lo, hi)), (n, (-reach, reach))] {
                    let rest = py * axis[1];
                    if axis[0].abs() < 1e-12 {
                        if rest < mn || rest > mx {
                            x_min = f64::INFINITY;
                        }
                        continue;
                    }
                    let e0 = (mn - rest) / axis[0];
                    let e1 = (mx - rest) / axis[0];
                    x_min = x_min.max(e0.min(e1));
                    x_max = x_max.min(e0.max(e1));
                }
                if x_min > x_max {
                    continue;
                }
                let x_lo = ((a[0] + x_min).floor().max(grid.gx0 as f64)) as usize;
                let x_hi = (a[0] + x_max).ceil().min(grid.gx1 as f64);
                if x_hi < x_lo as f64 {
                    continue;
                }
                let row = (y - grid.gy0) * grid.gw;
                for x in x_lo..=x_hi as usize {
                    let px = x as f64 - a[0];
                    let t = ((px * d[0] + py * d[1]) / dd).clamp(0.0, 1.0);
                    let ex = px - t * d[0];
                    let ey = py - t * d[1];
                    let d2 = ex * ex + ey * ey;
                    let cell = row + x - grid.gx0;
                    let packed = pack((1.0 + d2) as f32, (ua + t * (ub - ua)) as f32);
                    let old = best[cell];
                    if old == 0 {
                        touched.push(cell as u32);
                        best[cell] = packed;
                    } else if packed < old {
                        best[cell] = packed;
                    }
                }
            }
        }
    }
}

/// Cells of the band's grid per parallel task of the exact projection.
const TOUCHED_CHUNK: usize = 2048;

/// Two `f32` in one `u64` (the first in the high half).
#[inline]
fn pack(a: f32, b: f32) -> u64 {
    (u64::from(a.to_bits()) << 32) | u64::from(b.to_bits())
}

/// The two `f32` of [`pack`].
#[inline]
fn unpack(v: u64) -> (f32, f32) {
    (f32::from_bits((v >> 32) as u32), f32::from_bits(v as u32))
}

/// Whether pixel `(x, y)` is left out when one in `thin` is kept.
#[inline]
fn thinned_out(thin: usize, x: usize, y: usize) -> bool {
    let (x_odd, y_odd) = (x % 2 == 1, y % 2 == 1);
    match thin {
        0 | 1 => false,
        2 | 3 => x_odd != y_odd,
        _ => x_odd || y_odd,
    }
}

/// The curve and the two borders of its band must lie inside the domain of
/// the interpolated image, `[0, width - 1] x [0, height - 1]`.
fn check_inside(curve: &SplineCurve, half_width: f64, width: usize, height: usize) -> Result<()> {
    let (w, h) = (width as f64 - 1.0, height as f64 - 1.0);
    let inside = |p: [f64; 2]| p[0] >= 0.0 && p[1] >= 0.0 && p[0] <= w && p[1] <= h;
    let count = (curve.param_length().ceil() as usize).max(8);
    let params = curve.sample_params(if curve.is_closed() { count } else { count + 1 });
    for &u in &params {
        let f = curve.frame(u);
        if !inside(f.point) {
            return Err(Error::CurveOutsideImage {
                x: f.point[0],
                y: f.point[1],
                width,
                height,
            });
        }
    }
    for &u in &params {
        let f = curve.frame(u);
        for side in [-1.0, 1.0] {
            // On the concave side the band stops before the centre of curvature.
            let mut r = side * half_width;
            if f.curvature * r > 0.0 {
                r = r.signum() * r.abs().min((1.0 - MIN_JACOBIAN) / f.curvature.abs());
            }
            let q = [f.point[0] + r * f.normal[0], f.point[1] + r * f.normal[1]];
            if !inside(q) {
                return Err(Error::BandOutsideImage {
                    half_width,
                    x: q[0],
                    y: q[1],
                });
            }
        }
    }
    Ok(())
}
