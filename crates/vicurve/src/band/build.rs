//! Building a band: its parameters and their checks, the pixels' rows from
//! one of the coordinate backends, and their storage as the band's columns.

use super::blurred_curvature::BlurredCurvature;
use super::levelset::LevelsetCoords;
use super::{Band, BandScratch, Coords, MIN_JACOBIAN};
use crate::curve::SplineCurve;
use crate::error::{Error, Result};
use crate::spline::{Basis, MAX_DEGREE};
use crate::virtual_image::corner::CornerWedge;
use crate::virtual_image::{Anisotropy, Profile};

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
    /// The curvature the pixel-edge profile takes (`None`: the local one).
    pub blurred_curvature: Option<&'a BlurredCurvature>,
    pub profile: Profile,
    pub half_width: f64,
    pub reach: f64,
    pub thin: usize,
    pub width: usize,
    pub height: usize,
}

impl<'a> Pixels<'a> {
    /// The pixels `params` asks for around `curve` (out to its half-width
    /// plus margin), for `basis`, the pixel-edge profile taking the
    /// curvature of `blurred_curvature` when given.
    fn asked(
        curve: &'a SplineCurve,
        basis: &'a Basis,
        params: &BandParams,
        blurred_curvature: Option<&'a BlurredCurvature>,
    ) -> Self {
        Pixels {
            curve,
            basis,
            blurred_curvature,
            profile: params.profile,
            half_width: params.half_width,
            reach: params.half_width + params.margin,
            thin: params.thin,
            width: params.width,
            height: params.height,
        }
    }
}

/// A band pixel as [`Band::distances`] gives it: its centre, its signed
/// distance `r` to the curve (pixels) and the curve's unit normal at its
/// foot.
pub(crate) type Distance = ([f64; 2], f64, [f64; 2]);

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
    /// The corners' wedges that reach the pixel (at most [`MAX_WEDGES`]),
    /// out of line: few pixels have any, and every candidate of a band is
    /// written out before the band's columns are made of them.
    wedges: Option<Box<[Option<CornerWedge>; MAX_WEDGES]>>,
    /// Their terms, summed.
    corner: f64,
    /// The weight of the profile's blurred osculating circle.
    osculating: f64,
}

/// Corners whose wedges a pixel takes at most: two, those at the ends of
/// its side; a third reaches it only on a side shorter than a few blur
/// widths, which no measurement resolves.
const MAX_WEDGES: usize = 2;

impl Candidate {
    /// Take the corners' `wedges` that reach the pixel into its profile,
    /// evaluated under the optical blur `blur` (px) with `anisotropy`.
    pub(super) fn add_wedges(
        &mut self,
        wedges: impl Iterator<Item = CornerWedge>,
        (blur, anisotropy): (f64, Anisotropy),
    ) {
        let mut wedges = wedges.peekable();
        if wedges.peek().is_none() {
            return;
        }
        let slots = self.wedges.get_or_insert_with(Box::default);
        for (slot, w) in slots.iter_mut().zip(wedges) {
            let term = w.term_for(blur, anisotropy);
            *slot = Some(w);
            self.corner += term;
            self.gamma += term;
        }
    }
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

    /// The weight of a pixel whose parallel-curve Jacobian is `jacobian`:
    /// `1 / jacobian` for the paper's profiles, whose sums stand for
    /// integrals over the band in `(s, r)` (the method's); 1 for the
    /// pushed ones (pixel edge and line), which model each pixel's value:
    /// every pixel carries the same noise, so equal weights make the
    /// least-squares estimate and its Gauss–Newton covariance those of
    /// the noise. Why: on a dot a blur or so across the Jacobian falls
    /// to 0.1 near its centre, and those few pixels' noise, weighted up to
    /// tenfold, moved its radius by several `sigma` (docs/benchmarks.md).
    fn area_weight(&self, jacobian: f64) -> f64 {
        if self.profile.is_pushed() {
            1.0
        } else {
            1.0 / jacobian
        }
    }

    /// The band pixel at `foot`, whose parallel-curve Jacobian is
    /// `jacobian` (`1 - kappa r`, above [`MIN_JACOBIAN`]).
    pub fn candidate(&self, mut foot: Foot, jacobian: f64) -> Candidate {
        let mut osculating = 0.0;
        if let Some(table) = self.blurred_curvature {
            foot.curvature = table.at(foot.s);
            osculating = table.osculating_at(foot.s);
        }
        let mut values = [0.0; MAX_DEGREE + 1];
        let first = self.basis.eval(foot.s, &mut values) as u32;
        let (gamma, dgamma) = self.profile.eval_at(
            foot.r,
            self.half_width,
            foot.normal,
            (foot.curvature, osculating),
        );
        Candidate {
            foot,
            first,
            basis: values,
            gamma,
            dgamma,
            weight: self.thin_weight() * self.area_weight(jacobian),
            wedges: None,
            corner: 0.0,
            osculating,
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
        // A dot or hole near the border: its band is the pixels in the
        // image (`Band::new`); so is an open curve's band beyond a pushed
        // profile's transition, when that lies in the image.
        let (width, height) = (params.width, params.height);
        let clipped = match check_inside(curve, reach, width, height) {
            Ok(()) => false,
            Err(Error::BandOutsideImage { .. }) if curve.is_closed() => true,
            Err(e @ Error::BandOutsideImage { .. }) => match params.profile.transition_half_width()
            {
                Some(core) if core + params.margin < reach => {
                    check_inside(curve, core + params.margin, width, height)?;
                    true
                }
                _ => return Err(e),
            },
            Err(e) => return Err(e),
        };
        let blurred_curvature = match params.profile {
            Profile::PixelEdge { blur, .. } | Profile::PixelLine { blur, .. } => {
                BlurredCurvature::new(curve, blur)
            }
            Profile::Paper { .. } => None,
        };
        let pixels = Pixels::asked(curve, basis, params, blurred_curvature.as_ref());
        let rows = match params.coords {
            Coords::Exact => pixels.exact_rows(scratch),
            Coords::Levelset { mesh_size } => {
                let levelsets =
                    LevelsetCoords::build(curve, reach, mesh_size, params.width, params.height)?;
                pixels.levelset_rows(&levelsets)
            }
        };
        Ok(Band::from_rows(rows, params, basis.degree(), clipped))
    }

    /// The centre and signed distance `r` (pixels) of every pixel of the
    /// band [`Band::new`] builds (raster order), without the rest of the
    /// band (the basis and profile values at each pixel, its columns): for
    /// what reads only the image across the curve, such as the edge's
    /// spread ([`crate::psf`]). Unlike [`Band::new`]'s, an open curve's
    /// band may leave the image too, and the curve with it (an object cut
    /// by the border): the band is then its pixels in the image.
    ///
    /// Errors: an invalid `params`; the level-set coordinates' errors.
    pub(crate) fn distances(
        curve: &SplineCurve,
        basis: &Basis,
        params: &BandParams,
    ) -> Result<Vec<Distance>> {
        params.check()?;
        let reach = params.half_width + params.margin;
        let pixels = Pixels::asked(curve, basis, params, None);
        let rows = match params.coords {
            Coords::Exact => {
                let mut scratch = BandScratch::from_pool();
                let rows = pixels.exact_distances(&mut scratch);
                scratch.return_to_pool();
                rows
            }
            Coords::Levelset { mesh_size } => {
                let levelsets =
                    LevelsetCoords::build(curve, reach, mesh_size, params.width, params.height)?;
                pixels
                    .levelset_rows(&levelsets)
                    .into_iter()
                    .map(|row| {
                        row.into_iter()
                            .map(|c| (c.foot.pos, c.foot.r, c.foot.normal))
                            .collect()
                    })
                    .collect()
            }
        };
        Ok(rows.into_iter().flatten().collect())
    }

    /// The band of the pixels `rows` (raster order) for a basis of degree
    /// `p`, windowed on its reference.
    fn from_rows(rows: Vec<Vec<Candidate>>, params: &BandParams, p: usize, clipped: bool) -> Band {
        let total: usize = rows.iter().map(Vec::len).sum();
        let mut band = Band {
            half_width: params.half_width,
            margin: params.margin,
            inside: 0,
            clipped,
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
            osculating: Vec::new(),
            corner: Vec::new(),
            corner_wedges: Vec::new(),
        };
        for (i, c) in rows.into_iter().flatten().enumerate() {
            if let Some(wedges) = &c.wedges {
                if band.corner.is_empty() {
                    band.corner.resize(i, 0.0);
                }
                band.corner_wedges
                    .extend(wedges.iter().flatten().map(|w| (i as u32, *w)));
            }
            if !band.corner.is_empty() {
                band.corner.push(c.corner);
            }
            if c.osculating > 0.0 && band.osculating.is_empty() {
                band.osculating.resize(i, 0.0);
            }
            if !band.osculating.is_empty() {
                band.osculating.push(c.osculating);
            }
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

/// The curve must lie inside the domain of the interpolated image, `[0,
/// width - 1] x [0, height - 1]` (but near a corner, [`CORNER_TIP`]), and
/// the two borders of its band inside that domain.
///
/// Errors: [`Error::CurveOutsideImage`] at the first point of the curve
/// outside, else [`Error::BandOutsideImage`] at the first band border
/// outside.
pub(crate) fn check_inside(
    curve: &SplineCurve,
    half_width: f64,
    width: usize,
    height: usize,
) -> Result<()> {
    check_curve_inside(curve, width, height)?;
    let domain = Domain::new(width, height, 0.0);
    for &u in &check_params(curve, 1.0) {
        if let Some(q) = band_outside(curve, u, half_width, &domain) {
            return Err(Error::BandOutsideImage {
                half_width,
                x: q[0],
                y: q[1],
            });
        }
    }
    Ok(())
}

/// Arc length (pixels) from a corner of the curve within which it may
/// pass beyond the pixel centres' hull `[0, width - 1] x [0, height - 1]`:
/// the tip of a sharp corner that the frame cuts off, up to about 4 px
/// deep at a right angle. The corner's band is then cut by the border
/// ([`Band::clipped`]) and its tip follows the two sides that lead to it
/// in the image. Held to the hull, such a corner could not be measured,
/// and the smooth curve rounding it was kept instead, a pixel off at the
/// corners with a `sigma` of hundredths. A smooth curve stays in the hull:
/// beyond it only one side of its edge is seen, and the curve of a disc
/// cut by the frame followed the border, tenths of a pixel off at tens of
/// its `sigma`.
const CORNER_TIP: f64 = 6.0;

/// The curve must lie inside the domain of the interpolated image, `[0,
/// width - 1] x [0, height - 1]`, but within [`CORNER_TIP`] of one of its
/// corners, tested about every pixel.
///
/// Errors: [`Error::CurveOutsideImage`] at the first point outside.
fn check_curve_inside(curve: &SplineCurve, width: usize, height: usize) -> Result<()> {
    let domain = Domain::new(width, height, 0.0);
    let (length, corners) = (curve.param_length(), curve.corners());
    let tip = if corners.is_empty() {
        0.0
    } else {
        CORNER_TIP * length / curve.arc_length().max(f64::MIN_POSITIVE)
    };
    let near_corner = |u: f64| {
        corners.iter().any(|&c| {
            let d = (u - c).abs();
            let d = if curve.is_closed() {
                d.min(length - d)
            } else {
                d
            };
            d <= tip
        })
    };
    for &u in &check_params(curve, 1.0) {
        let f = curve.frame(u);
        if !domain.holds(f.point) && !near_corner(u) {
            return Err(Error::CurveOutsideImage {
                x: f.point[0],
                y: f.point[1],
                width,
                height,
            });
        }
    }
    Ok(())
}

/// Spacing of the parameters at which [`inside_stretch`] tests an open
/// curve, pixels: half a pixel, so that its trim is within that of where
/// the band first leaves the image.
const STRETCH_STEP: f64 = 0.5;

/// The longest stretch `[u0, u1]` of the open `curve`'s parameter over
/// which the curve and the two borders of its band of half-width `reach`
/// (pixels) stay at least `margin` pixels inside the domain of the
/// interpolated image (`[0, width - 1] x [0, height - 1]`), tested every
/// [`STRETCH_STEP`]: where an open curve that reaches the border (an edge
/// crossing the image) can be measured with a whole band. `[0, L]` when
/// the whole curve can; a closed curve is tested as [`Band::new`] tests it.
///
/// Errors: [`Error::CurveOutsideImage`] at the first point of the curve
/// outside the domain when no point is in it, else
/// [`Error::BandOutsideImage`] at the first band border outside when no
/// band fits, as [`Band::new`] gives them.
pub(crate) fn inside_stretch(
    curve: &SplineCurve,
    reach: f64,
    margin: f64,
    width: usize,
    height: usize,
) -> Result<(f64, f64)> {
    let l = curve.param_length();
    if curve.is_closed() {
        return check_inside(curve, reach, width, height).map(|()| (0.0, l));
    }
    let domain = Domain::new(width, height, margin);
    let params = check_params(curve, STRETCH_STEP);
    let ok =
        |u: f64| domain.holds(curve.point(u)) && band_outside(curve, u, reach, &domain).is_none();
    let (mut best, mut run) = (None::<(usize, usize)>, None::<usize>);
    for (i, &u) in params.iter().enumerate() {
        match (ok(u), run) {
            (true, None) => run = Some(i),
            (false, Some(a)) => {
                if best.is_none_or(|(b0, b1)| i - 1 - a > b1 - b0) {
                    best = Some((a, i - 1));
                }
                run = None;
            }
            _ => {}
        }
    }
    if let Some(a) = run {
        let last = params.len() - 1;
        if best.is_none_or(|(b0, b1)| last - a > b1 - b0) {
            best = Some((a, last));
        }
    }
    match best {
        Some((a, b)) if b > a => Ok((params[a], params[b])),
        _ => check_inside(curve, reach, width, height).and_then(|()| {
            // Inside the domain but not within the margin of it.
            let p = curve.point(0.0);
            Err(Error::BandOutsideImage {
                half_width: reach,
                x: p[0],
                y: p[1],
            })
        }),
    }
}

/// The parameters at which the band checks test `curve`: about `step`
/// pixels apart, at least 8, both ends of an open curve included.
fn check_params(curve: &SplineCurve, step: f64) -> Vec<f64> {
    let count = ((curve.param_length() / step).ceil() as usize).max(8);
    curve.sample_params(if curve.is_closed() { count } else { count + 1 })
}

/// The domain of the interpolated image, shrunk by a margin (pixels).
struct Domain {
    lo: f64,
    x_hi: f64,
    y_hi: f64,
}

impl Domain {
    fn new(width: usize, height: usize, margin: f64) -> Self {
        Domain {
            lo: margin,
            x_hi: width as f64 - 1.0 - margin,
            y_hi: height as f64 - 1.0 - margin,
        }
    }

    fn holds(&self, p: [f64; 2]) -> bool {
        p[0] >= self.lo && p[1] >= self.lo && p[0] <= self.x_hi && p[1] <= self.y_hi
    }
}

/// The first of the two borders of the band of half-width `half_width`
/// around `curve` at `u` outside `domain`, if one is. On the concave side
/// the band stops before the centre of curvature.
fn band_outside(curve: &SplineCurve, u: f64, half_width: f64, domain: &Domain) -> Option<[f64; 2]> {
    let f = curve.frame(u);
    [-1.0, 1.0].into_iter().find_map(|side: f64| {
        let mut r = side * half_width;
        if f.curvature * r > 0.0 {
            r = r.signum() * r.abs().min((1.0 - MIN_JACOBIAN) / f.curvature.abs());
        }
        let q = [f.point[0] + r * f.normal[0], f.point[1] + r * f.normal[1]];
        (!domain.holds(q)).then_some(q)
    })
}
