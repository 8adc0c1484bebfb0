//! Building a band: its parameters and their checks, the pixels' rows from
//! one of the coordinate backends, and their storage as the band's columns.

use super::levelset::LevelsetCoords;
use super::{Band, BandScratch, Coords, MIN_JACOBIAN};
use crate::curve::SplineCurve;
use crate::error::{Error, Result};
use crate::spline::{Basis, MAX_DEGREE};
use crate::virtual_image::Profile;

/// What band to build: its size, profile, image, the pixels it keeps and
/// how they get their coordinates. [`BandParams::new`] gives the plain
/// band (no margin, every pixel, exact coordinates).
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct BandParams {
    /// Half-width `R`, pixels (at least 0.5): the profile's, and the
    /// window's for a band with a margin.
    pub half_width: f64,
    /// Pixels out to `half_width + margin` (pixels, 0 or more) are kept,
    /// those within `half_width` of the reference count until the first
    /// [`Band::recentre`] (see the [module docs](super)).
    pub margin: f64,
    /// The virtual image's profile across the curve.
    pub profile: Profile,
    /// Image width, pixels.
    pub width: usize,
    /// Image height, pixels.
    pub height: usize,
    /// Keep one pixel in `thin`, each with `thin` times the weight: 1 keeps
    /// all, 2 a checkerboard, 4 every other pixel of every other row (any
    /// other value is taken as the nearest of these below it). For the
    /// coarse stages of a schedule: they only need to bring the curve near
    /// the edge, and half the pixels of a wide band do that at half the
    /// cost.
    pub thin: usize,
    /// How the pixels get their `(s, r)`: exact projection or the paper's
    /// levelsets (see the [module docs](super)).
    pub coords: Coords,
}

impl BandParams {
    /// The band of half-width `half_width` (pixels) with `profile` (a
    /// [`Profile`] or a [`crate::virtual_image::Kind`] for the paper's) in
    /// an image of `width x height` pixels: no margin, every pixel, exact
    /// coordinates.
    pub fn new(half_width: f64, profile: impl Into<Profile>, width: usize, height: usize) -> Self {
        BandParams {
            half_width,
            margin: 0.0,
            profile: profile.into(),
            width,
            height,
            thin: 1,
            coords: Coords::Exact,
        }
    }

    /// The half-width and the margin, checked.
    fn check(&self) -> Result<()> {
        let (half_width, margin) = (self.half_width, self.margin);
        if !(margin.is_finite() && margin >= 0.0) {
            return Err(Error::invalid(
                "band margin",
                format!("{margin} px (must be 0 or more)"),
            ));
        }
        if !(half_width.is_finite() && half_width >= 0.5) {
            return Err(Error::invalid(
                "band half-width",
                format!("{half_width} px (must be at least 0.5 px)"),
            ));
        }
        Ok(())
    }
}

/// The pixels a backend looks for, and what it stores for each: those
/// within `reach` of `curve` (one in `thin`), in an image of `width x
/// height`, with the values of `basis` and of `profile` (taken with
/// `half_width`, pixels).
pub(super) struct Pixels<'a> {
    pub curve: &'a SplineCurve,
    pub basis: &'a Basis,
    pub profile: Profile,
    pub half_width: f64,
    pub reach: f64,
    pub thin: usize,
    pub width: usize,
    pub height: usize,
}

/// Where a backend puts a pixel: its centre, coordinates `s` and `r`
/// (pixels), the normal and the curvature (1/px) of the curve at `s`.
pub(super) struct Foot {
    pub pos: [f64; 2],
    pub s: f64,
    pub r: f64,
    pub normal: [f64; 2],
    pub curvature: f64,
}

/// One band pixel with everything [`Band`] stores about it, as the parallel
/// part of a backend computes it.
pub(super) struct Candidate {
    foot: Foot,
    first: u32,
    basis: [f64; MAX_DEGREE + 1],
    gamma: f64,
    dgamma: f64,
    weight: f64,
}

impl Pixels<'_> {
    /// Whether pixel `(x, y)` is left out when one in `thin` is kept.
    #[inline]
    pub fn thinned_out(&self, x: usize, y: usize) -> bool {
        let (x_odd, y_odd) = (x % 2 == 1, y % 2 == 1);
        match self.thin {
            0 | 1 => false,
            2 | 3 => x_odd != y_odd,
            _ => x_odd || y_odd,
        }
    }

    /// The weight of a kept pixel when one in `thin` is kept.
    fn thin_weight(&self) -> f64 {
        match self.thin {
            0 | 1 => 1.0,
            2 | 3 => 2.0,
            _ => 4.0,
        }
    }

    /// The band pixel at `foot`, whose parallel-curve Jacobian is
    /// `jacobian` (`1 - kappa r`, above [`MIN_JACOBIAN`]).
    pub fn candidate(&self, foot: Foot, jacobian: f64) -> Candidate {
        let mut values = [0.0; MAX_DEGREE + 1];
        let first = self.basis.eval(foot.s, &mut values) as u32;
        let (gamma, dgamma) =
            self.profile
                .eval(foot.r, self.half_width, foot.normal, foot.curvature);
        Candidate {
            foot,
            first,
            basis: values,
            gamma,
            dgamma,
            weight: self.thin_weight() / jacobian,
        }
    }
}

impl Band {
    /// [`Band::new`] with the scratch grids `scratch` (the exact
    /// projection's; see [`BandScratch`]).
    ///
    /// Errors: those of [`Band::new`].
    pub fn new_in(
        curve: &SplineCurve,
        basis: &Basis,
        params: &BandParams,
        scratch: &mut BandScratch,
    ) -> Result<Band> {
        params.check()?;
        let l = curve.param_length();
        if (basis.length() - l).abs() > 1e-9 * l.max(1.0) || basis.is_closed() != curve.is_closed()
        {
            return Err(Error::invalid(
                "displacement basis",
                "its length or closure differs from the reference curve's",
            ));
        }
        let reach = params.half_width + params.margin;
        check_inside(curve, reach, params.width, params.height)?;
        let pixels = Pixels {
            curve,
            basis,
            profile: params.profile,
            half_width: params.half_width,
            reach,
            thin: params.thin,
            width: params.width,
            height: params.height,
        };
        let rows = match params.coords {
            Coords::Exact => pixels.exact_rows(scratch),
            Coords::Levelset { mesh_size } => {
                let levelsets =
                    LevelsetCoords::build(curve, reach, mesh_size, params.width, params.height)?;
                pixels.levelset_rows(&levelsets)
            }
        };
        Ok(Band::from_rows(rows, params, basis.degree()))
    }

    /// The band of the pixels `rows` (raster order) for a basis of degree
    /// `p`, windowed on its reference.
    fn from_rows(rows: Vec<Vec<Candidate>>, params: &BandParams, p: usize) -> Band {
        let total: usize = rows.iter().map(Vec::len).sum();
        let mut band = Band {
            half_width: params.half_width,
            margin: params.margin,
            inside: 0,
            profile: params.profile,
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
            band.pos.push(c.foot.pos);
            band.normal.push(c.foot.normal);
            band.s.push(c.foot.s);
            band.r.push(c.foot.r);
            band.first.push(c.first);
            band.basis.extend_from_slice(&c.basis[..=p]);
            band.gamma.push(c.gamma);
            band.dgamma.push(c.dgamma);
            band.full_weight.push(c.weight);
            band.weight.push(c.weight);
            band.curvature.push(c.foot.curvature);
        }
        band.inside = band.len();
        // With a margin, the pixels within `half_width` of the reference
        // count until the first `recentre`.
        band.window_at_reference();
        band
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
