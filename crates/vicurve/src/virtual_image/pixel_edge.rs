//! The edge profile an ideal pixel records across a blurred straight step.
//!
//! A square pixel of side 1 whose centre is at signed distance `t` from a
//! straight step with unit normal `(nx, ny)` integrates the image over its
//! area. Projected on the normal, the pixel's area is distributed as the sum
//! of two independent uniform variables of widths `|nx|` and `|ny|` (a
//! trapezoid); a Gaussian blur of standard deviation `sigma_b` adds a normal
//! variable. The recorded level is the probability that this sum `T` stays
//! on the bright side: `P(T < -t)`, i.e. one minus the distribution function
//! of `T` at `t`.
//!
//! With `Phi` the standard normal distribution, its antiderivatives
//! `Psi1(x) = x Phi(x) + phi(x)` and `Psi2(x) = ((x^2 + 1) Phi(x) + x phi(x))
//! / 2` give that distribution in closed form as a second difference of
//! `Psi2` over the trapezoid's four corners, and its density as the same
//! difference of `Psi1`.
//!
//! The profile is evaluated at every band pixel in every iteration of the
//! pixel-edge stage, so `Psi1` and `Psi2` come from a table
//! (`virtual_image/psi.rs`); the direct formula, where `Phi` and `phi` share one
//! exponential (`normal_cdf_pdf`; `erfc` from `libm` would spend two more),
//! builds that table and is the tests' reference.
//!
//! Edge cases: an axis-aligned edge (`nx` or `ny` zero) or a focused one
//! (no blur) is a limit of the formula (0/0); widths and the blur are raised
//! to 1e-3 px (widths to 5 % of a larger blur, at most 0.02 px: see
//! `MIN_WIDTH`), which moves a focused edge's profile by at most 4e-4 of
//! the contrast at a pixel whose centre lies within 1e-3 px of a corner of
//! the trapezoid (about 1e-5 RMS over the band; 1e-6 for a diagonal edge).
//! The floors
//! must stay that small: the profile is exact coverage, and at 0.03 px of
//! blur it differed from the coverage of a focused edge by up to 1.2 % of
//! the contrast, 0.5 px from the edge (1e-3 RMS over the band): on a
//! noiseless 16-bit disc that misfit, not the image, limited the scatter
//! of a free-form curve (docs/benchmarks.md).

use std::f64::consts::{FRAC_1_SQRT_2, PI};

/// Smallest trapezoid width used, pixels (see the module docs): the larger
/// of this and `WIDTH_PER_BLUR` times the blur, up to `MAX_WIDTH_FLOOR`.
const MIN_WIDTH: f64 = 1e-3;
/// See [`MIN_WIDTH`]. The profile is a second difference of `Psi2` over the
/// widths, scaled by `blur^2 / (a b)`: a floor that follows the blur keeps
/// that factor, and so the table's error, bounded (at most 8 up to 0.4 px of
/// blur, `50 blur^2` beyond), while a width that small against the blur
/// changes the profile by under 1e-4 of its variance.
const WIDTH_PER_BLUR: f64 = 0.05;
/// See [`MIN_WIDTH`], pixels.
const MAX_WIDTH_FLOOR: f64 = 0.02;

/// The trapezoid's widths `(a, b)` for the normal `(nx, ny)` under the blur
/// `s` (at least `MIN_BLUR`), raised to the floor of [`MIN_WIDTH`].
#[inline]
fn widths(nx: f64, ny: f64, s: f64) -> (f64, f64) {
    let floor = (WIDTH_PER_BLUR * s).clamp(MIN_WIDTH, MAX_WIDTH_FLOOR);
    (nx.abs().max(floor), ny.abs().max(floor))
}
/// Smallest blur used, pixels: a smaller one gives the same profile.
pub(crate) const MIN_BLUR: f64 = 1e-3;
/// The variance of a square pixel's own spread across an edge, px^2.
const PIXEL_VARIANCE: f64 = 1.0 / 12.0;

/// The pixel-edge stage's band covers the pixel's largest extent along a
/// normal (`sqrt(2) / 2` px), this many blur deviations and
/// `PIXEL_EDGE_PLATEAU` px of the flat levels on each side, and is at least
/// `PIXEL_EDGE_MIN_BAND` px wide. Narrow on purpose: the flat levels fix
/// `a` and `c`, and on a noiseless 8-bit image a flat level rounded by up to
/// half a gray level no longer lies on the line through the transition's
/// levels; the wider its share of the band, the more the curve follows it
/// (see docs/benchmarks.md).
const PIXEL_EDGE_REACH: f64 = 2.0;
/// See [`PIXEL_EDGE_REACH`], pixels.
const PIXEL_EDGE_PLATEAU: f64 = 0.5;
/// See [`PIXEL_EDGE_REACH`], pixels.
const PIXEL_EDGE_MIN_BAND: f64 = 1.5;

/// Half-width of the band of the pixel-edge stage for an optical blur of
/// `blur` pixels (see the constants), rounded up to a quarter pixel: narrow,
/// for noiseless images whose flat levels may sit between two gray levels.
pub(crate) fn pixel_edge_band(blur: f64) -> f64 {
    let r = FRAC_1_SQRT_2 + PIXEL_EDGE_REACH * blur + PIXEL_EDGE_PLATEAU;
    (r.max(PIXEL_EDGE_MIN_BAND) * 4.0).ceil() / 4.0
}

/// The variance `v` of the whole spread across an edge under an optical
/// blur of standard deviation `blur` (pixels): the blur's and the square
/// pixel's own, px^2.
#[inline]
pub(crate) fn spread_variance(blur: f64) -> f64 {
    blur * blur + PIXEL_VARIANCE
}

/// The optical blur (pixels) whose whole spread has the standard
/// deviation `spread` (pixels, an edge-spread estimate): the inverse of
/// [`spread_variance`], 0 for a spread under the pixel's own.
#[inline]
pub(crate) fn optical_blur(spread: f64) -> f64 {
    (spread * spread - PIXEL_VARIANCE).max(0.0).sqrt()
}

/// `(gamma, d gamma / d r)` of a blurred curved edge at signed distance
/// `r` (pixels) from it, for a pixel whose foot on the edge has the unit
/// normal `(nx, ny)` and the signed curvature `curvature` (1/px, of the
/// convention of [`super::Profile::eval`]), under the optical blurs
/// `(across, along, cross)` (deviations along the normal and along the
/// tangent, pixels, and the covariance of the two, px²; equal deviations
/// and no covariance for an isotropic blur, see [`super::Anisotropy`]):
/// the pixel edge
/// ([`pixel_edge_cdf`]) moved by the curvature's shift and widened by its
/// spread, plus the spread's skew, all to the second order in `v kappa`
/// (`v` = [`spread_variance`] of the blur along the tangent); plus,
/// weighted by `osculating` (0 to 1: how constant the curvature is over
/// the blur, see `band/blurred_curvature.rs`), the rest of the blurred
/// osculating circle where the blur is not small against the radius of
/// curvature (`osculating.rs`).
///
/// Why: near a point of the edge, with `x` its arc length, the edge is
/// `y = f(x)`, `f(x) = kappa x^2 / 2 + kappa' x^3 / 6 + (kappa'' + 3
/// kappa^3) x^4 / 24`. Along the normal there a Gaussian of variances
/// `v_n` across and `v` along sees the level `E[Phi((y - f(X)) / sqrt
/// v_n)]` with `X ~ N(0, v)`: the straight edge's profile averaged over the
/// random offset `f(X)`. A covariance `c` of the blur's normal and
/// tangent parts adds `b X` (`b = c / v`) to the offset and takes `b² v`
/// from the normal variance: the sum's variance is unchanged, its third
/// cumulant gains `3 c² kappa` (from `Cov(f(X), X²)`). The
/// offset's mean `v kappa / 2 + v^2 (kappa'' + 3 kappa^3) / 8` moves the
/// profile (the term in `kappa''` is the blurred curvature's,
/// `band/blurred_curvature.rs`); its variance `v^2 kappa^2 / 2` widens
/// it; its third cumulant `k3 = v^3 kappa^3` skews it by `k3 / 6` times
/// the third derivative of `Phi`. The half level then lies `v kappa / 2 +
/// v^2 kappa'' / 8 + 5 v^2 kappa^3 / 24` in. With the first order alone a
/// disc of radius 20 px under a 4 px blur looks 1 % blurrier than it is:
/// the blur's fit takes that for blur, and the first-order shift with
/// that larger `v` puts the edge out by `v^2 kappa^3 / 2` (tested against
/// the blurred disc's exact integral, and measured in
/// `fit::bias::a_small_disc_under_a_heavy_blur_keeps_its_radius`). The
/// pixel's square spread is not Gaussian; its share `1/12` of `v` matters
/// little where these terms do.
#[inline]
pub(crate) fn curved_edge(
    r: f64,
    nx: f64,
    ny: f64,
    (across, along, cross): (f64, f64, f64),
    curvature: f64,
    osculating: f64,
) -> (f64, f64) {
    let v = spread_variance(along);
    let vk = v * curvature;
    let t = r - 0.5 * vk * (1.0 + 0.75 * vk * curvature);
    // The curve's own spread along the normal, added to the blur's.
    let widened = (across * across + 0.5 * vk * vk).sqrt();
    let (cdf, pdf) = pixel_edge_cdf(t, nx, ny, widened);
    let (mut gamma, mut slope) = (1.0 - cdf, -pdf);
    // The skew `(k3 / 6) (x^2 - 1) phi(x) / sd^3`, `x = t / sd` with `sd`
    // the spread across, where it can move the edge by more than 1e-7 px.
    let v_n = spread_variance(across);
    let sd = v_n.sqrt();
    let k3 = vk * vk * vk + 3.0 * cross * cross * curvature;
    let skew = k3 / (6.0 * v_n * sd);
    if skew.abs() * sd > SKEW_FLOOR {
        let x = t / sd;
        let phi = (-0.5 * x * x).exp() * (0.5 / PI).sqrt();
        gamma += skew * (x * x - 1.0) * phi;
        slope += skew / sd * x * (3.0 - x * x) * phi;
    }
    // Where the blur is not small against the radius of curvature, the
    // rest of the blurred osculating circle (`osculating.rs`).
    if osculating > 0.0 {
        let (dgamma, dslope) = super::osculating::correction(r, v, curvature);
        gamma += osculating * dgamma;
        slope += osculating * dslope;
    }
    (gamma, slope)
}

/// The curved edge's skew is left out where it moves the edge by less
/// than this, pixels.
const SKEW_FLOOR: f64 = 1e-7;

/// Standard normal distribution function (the reference for
/// [`normal_cdf_pdf`]).
#[cfg(test)]
fn normal_cdf(x: f64) -> f64 {
    0.5 * libm::erfc(-x * FRAC_1_SQRT_2)
}

/// Standard normal density.
#[cfg(test)]
#[inline]
fn normal_pdf(x: f64) -> f64 {
    (-0.5 * x * x).exp() * (0.5 / PI).sqrt()
}

/// `(Phi(x), phi(x))`, the standard normal distribution and density, with
/// one exponential: `Phi(x) = erfc(-x / sqrt 2) / 2` and, for `|y| >=
/// 0.46875` (`y = x / sqrt 2`), `erfc(|y|) = exp(-y^2) R(|y|)` with W. J.
/// Cody's rational approximations (Math. Comp. 23, 1969; as in Netlib's
/// `calerf`), where `exp(-y^2) = exp(-x^2 / 2)` is the density's own
/// exponential; below, `erf(y)` is Cody's rational function of `y^2`.
/// Agrees with `erfc` of `libm` to a relative `(1 + x^2 / 2) 1e-15` (the
/// rounding of the exponential's argument; tested).
// Cody's coefficients as published (more digits than a double holds: each
// rounds to the nearest one).
#[allow(clippy::excessive_precision)]
#[inline]
pub(crate) fn normal_cdf_pdf(x: f64) -> (f64, f64) {
    let e = (-0.5 * x * x).exp();
    let pdf = e * (0.5 / PI).sqrt();
    let y = x.abs() * FRAC_1_SQRT_2;
    if y < 0.46875 {
        let z = y * y;
        let num = (((0.185_777_706_184_603_153 * z + 3.161_123_743_870_565_6) * z
            + 113.864_154_151_050_156)
            * z
            + 377.485_237_685_302_021)
            * z
            + 3_209.377_589_138_469_47;
        let den = (((z + 23.601_290_952_344_120_9) * z + 244.024_637_934_444_173) * z
            + 1_282.616_526_077_372_28)
            * z
            + 2_844.236_833_439_170_62;
        let erf = x * FRAC_1_SQRT_2 * num / den;
        return (0.5 + 0.5 * erf, pdf);
    }
    let erfc = if y <= 4.0 {
        let num = (((((((2.153_115_354_744_038_46e-8 * y + 0.564_188_496_988_670_089) * y
            + 8.883_149_794_388_375_94)
            * y
            + 66.119_190_637_141_629_5)
            * y
            + 298.635_138_197_400_131)
            * y
            + 881.952_221_241_769_090)
            * y
            + 1_712.047_612_634_070_58)
            * y
            + 2_051.078_377_826_071_47)
            * y
            + 1_230.339_354_797_997_25;
        let den = (((((((y + 15.744_926_110_709_834_7) * y + 117.693_950_891_312_499) * y
            + 537.181_101_862_009_858)
            * y
            + 1_621.389_574_566_690_19)
            * y
            + 3_290.799_235_733_459_63)
            * y
            + 4_362.619_090_143_247_16)
            * y
            + 3_439.367_674_143_721_64)
            * y
            + 1_230.339_354_803_749_42;
        e * num / den
    } else {
        let t = 1.0 / (y * y);
        let num = ((((0.016_315_387_137_302_097_8 * t + 0.305_326_634_961_232_344) * t
            + 0.360_344_899_949_804_439)
            * t
            + 0.125_781_726_111_229_246)
            * t
            + 0.016_083_785_148_742_276_6)
            * t
            + 6.587_491_615_298_378_03e-4;
        let den = ((((t + 2.568_520_192_289_822_42) * t + 1.872_952_849_923_467_25) * t
            + 0.527_905_102_951_428_412)
            * t
            + 0.060_518_341_312_441_319_1)
            * t
            + 2.335_204_976_268_691_85e-3;
        e / y * (FRAC_1_SQRT_PI - t * num / den)
    };
    let cdf = if x > 0.0 {
        1.0 - 0.5 * erfc
    } else {
        0.5 * erfc
    };
    (cdf, pdf)
}

/// `1 / sqrt(pi)`.
const FRAC_1_SQRT_PI: f64 = 0.564_189_583_547_756_3;

/// `(P(T <= t), density of T at t)` for `T` the pixel's extent along the
/// normal `(nx, ny)` plus a Gaussian blur of `sigma_b` pixels (module docs).
/// `Psi2` and `Psi1` come from their table (`virtual_image/psi.rs`): within
/// `1e-9 (1 + sigma_b^2)` of the direct formula (tested).
#[inline]
pub fn pixel_edge_cdf(t: f64, nx: f64, ny: f64, sigma_b: f64) -> (f64, f64) {
    let (x, s, area) = match corners(t, nx, ny, sigma_b) {
        Ok(c) => c,
        Err(level) => return (level, 0.0),
    };
    let psi = super::psi::Psi::get();
    let (p2a, p1a) = psi.at(x[0]);
    let (p2b, p1b) = psi.at(x[1]);
    let (p2c, p1c) = psi.at(x[2]);
    let (p2d, p1d) = psi.at(x[3]);
    let cdf = ((p2a - p2b) - (p2c - p2d)) * s * s * area;
    let pdf = ((p1a - p1b) - (p1c - p1d)) * s * area;
    (cdf.clamp(0.0, 1.0), pdf.max(0.0))
}

/// [`pixel_edge_cdf`] and the derivative of its distribution in
/// `sigma_b` (from the same table values: the distribution is `s^2` times
/// a sum of `Psi2((t + o) / s)`, whose derivative in `x` is `Psi1`); the
/// floor the pixel's widths take from the blur is held fixed. For fits of
/// the blur ([`crate::tone`]'s alternatives).
#[inline]
pub(crate) fn pixel_edge_cdf_ds(t: f64, nx: f64, ny: f64, sigma_b: f64) -> (f64, f64, f64) {
    let (x, s, area) = match corners(t, nx, ny, sigma_b) {
        Ok(c) => c,
        Err(level) => return (level, 0.0, 0.0),
    };
    let psi = super::psi::Psi::get();
    let (mut p2, mut p1, mut moment) = (0.0, 0.0, 0.0);
    for (x, sign) in x.into_iter().zip([1.0, -1.0, -1.0, 1.0]) {
        let (q2, q1) = psi.at(x);
        p2 += sign * q2;
        p1 += sign * q1;
        moment += sign * x * q1;
    }
    let cdf = p2 * s * s * area;
    let pdf = p1 * s * area;
    let ds = if sigma_b > MIN_BLUR && (0.0..=1.0).contains(&cdf) {
        (2.0 * p2 - moment) * s * area
    } else {
        0.0
    };
    (cdf.clamp(0.0, 1.0), pdf.max(0.0), ds)
}

/// The arguments `(t + o) / s` of the four corners of [`pixel_edge_cdf`]'s
/// trapezoid (offsets `o` = outer, -inner, inner, -outer), its blur `s`
/// (at least [`MIN_BLUR`]) and the pixel's inverse area; `Err` with the
/// distribution (0 or 1) beyond the trapezoid's reach.
#[inline]
fn corners(t: f64, nx: f64, ny: f64, sigma_b: f64) -> Result<([f64; 4], f64, f64), f64> {
    let s = sigma_b.max(MIN_BLUR);
    let (a, b) = widths(nx, ny, s);
    let reach = 0.5 * (a + b) + 9.0 * s;
    if t >= reach {
        return Err(1.0);
    }
    if t <= -reach {
        return Err(0.0);
    }
    let inv = 1.0 / s;
    let (outer, inner) = (0.5 * (a + b), 0.5 * (a - b));
    let x = [
        (t + outer) * inv,
        (t - inner) * inv,
        (t + inner) * inv,
        (t - outer) * inv,
    ];
    Ok((x, s, 1.0 / (a * b)))
}

/// [`pixel_edge_cdf`] computed directly, `Phi` and `phi` at each corner:
/// the reference for the tabulated one.
#[cfg(test)]
fn pixel_edge_cdf_direct(t: f64, nx: f64, ny: f64, sigma_b: f64) -> (f64, f64) {
    let s = sigma_b.max(MIN_BLUR);
    let (a, b) = widths(nx, ny, s);
    let reach = 0.5 * (a + b) + 9.0 * s;
    if t >= reach {
        return (1.0, 0.0);
    }
    if t <= -reach {
        return (0.0, 0.0);
    }
    let corners = [
        (0.5 * (a + b), 1.0),
        (0.5 * (b - a), -1.0),
        (0.5 * (a - b), -1.0),
        (-0.5 * (a + b), 1.0),
    ];
    let (mut cdf, mut pdf) = (0.0, 0.0);
    for (offset, sign) in corners {
        let x = (t + offset) / s;
        let (big_phi, small_phi) = normal_cdf_pdf(x);
        cdf += sign * 0.5 * ((x * x + 1.0) * big_phi + x * small_phi);
        pdf += sign * (x * big_phi + small_phi);
    }
    let cdf = (cdf * s * s / (a * b)).clamp(0.0, 1.0);
    let pdf = (pdf * s / (a * b)).max(0.0);
    (cdf, pdf)
}

#[cfg(test)]
mod tests {
    /// [`super::pixel_edge_cdf_ds`]: the distribution and density of
    /// [`super::pixel_edge_cdf`], and the derivative in the blur that
    /// central differences of it give.
    #[test]
    fn the_blurs_derivative_is_the_distributions_slope() {
        for &(nx, ny) in &[(1.0, 0.0), (0.8, 0.6), (0.3f64, 0.9539392014169457)] {
            for &blur in &[0.05, 0.3, 1.0, 2.5] {
                for k in -40..=40 {
                    let t = k as f64 * 0.1 * (blur + 0.5);
                    let (cdf, pdf, ds) = super::pixel_edge_cdf_ds(t, nx, ny, blur);
                    let (c0, p0) = super::pixel_edge_cdf(t, nx, ny, blur);
                    assert!((cdf - c0).abs() < 1e-12 && (pdf - p0).abs() < 1e-12);
                    let h = 1e-5 * blur;
                    let numeric = (super::pixel_edge_cdf(t, nx, ny, blur + h).0
                        - super::pixel_edge_cdf(t, nx, ny, blur - h).0)
                        / (2.0 * h);
                    assert!(
                        (ds - numeric).abs() < 1e-4 * (1.0 + numeric.abs()),
                        "({nx}, {ny}) blur {blur} t {t}: {ds} {numeric}"
                    );
                }
            }
        }
    }

    /// The level of a disc blurred by a Gaussian, from its exact integral
    /// (Simpson, radially and for the Bessel function), against
    /// `curved_edge` with the same spread variance (a diagonal normal, so
    /// that the pixel's part is nearly Gaussian too), over two spreads each
    /// side: within 1e-4 of the contrast (measured 1.4e-5 on a radius of
    /// 20 px under a spread of 2 px, 5.8e-6 on 10 px, which the expansion
    /// alone left at 3.1e-4, 2e-6 on radii of 6 and 3 px under a spread
    /// of 2.5 px, beyond the expansion's reach: `osculating.rs`), where the
    /// first order alone (the straight edge's profile moved by `v kappa /
    /// 2`) errs by up to 0.54.
    #[test]
    fn the_curved_edge_is_the_blurred_disc() {
        use crate::psf::simpson;
        // `exp(-x) I0(x)`.
        let i0e = |x: f64| simpson(0.0, PI, 200, |t| (x * (t.cos() - 1.0)).exp()) / PI;
        // The level at distance `rho` from the centre of a disc of radius
        // `r` under a Gaussian of variance `v`.
        let level = |rho: f64, r: f64, v: f64| {
            simpson(0.0, r, 2000, |s| {
                s / v * (-(s - rho).powi(2) / (2.0 * v)).exp() * i0e(s * rho / v)
            })
        };
        let n = FRAC_1_SQRT_2;
        let mut first_worst: f64 = 0.0;
        for (r, v) in [
            (10.0, 4.0),
            (20.0, 4.0),
            (10.0, 1.0),
            (6.0, 6.4),
            (3.0, 6.4),
        ] {
            let blur = (v - PIXEL_VARIANCE).sqrt();
            // The outward normal: the curvature is -1 / r.
            let kappa = -1.0 / r;
            let worst = (-20..=20)
                .map(|i| {
                    let d = i as f64 * 0.1 * v.sqrt();
                    let exact = level(r + d, r, v);
                    let (model, _) = curved_edge(d, n, n, (blur, blur, 0.0), kappa, 1.0);
                    let first = 1.0 - pixel_edge_cdf(d + 0.5 * v / r, n, n, blur).0;
                    first_worst = first_worst.max((first - exact).abs());
                    (model - exact).abs()
                })
                .fold(0.0, f64::max);
            println!("r {r}, v {v}: the curved edge within {worst:.2e} of the blurred disc");
            assert!(worst < 1e-4, "r {r}, v {v}: {worst}");
        }
        println!("the first order alone within {first_worst:.2e}");
        assert!(first_worst > 3e-3, "{first_worst}");
    }

    /// An anisotropic blur: a disc of radius 20 px under a Gaussian whose
    /// variance is 6 px² across the edge and 1 px² along it at the point
    /// looked at, the reverse, and 3.7 px² both ways with a covariance of
    /// 2.6 px² between them (a blur elongated along a diagonal of the
    /// normal and the tangent), from the integral over the disc in polar
    /// coordinates (smooth there; Simpson), against `curved_edge` with
    /// those blurs (a diagonal normal, as above): within 1e-3 of the
    /// contrast over two spreads each side (measured 2.5e-6, 3.9e-4 and
    /// 7.1e-4: the expansion's error grows with `v kappa`, 0.3 along in the
    /// second). With the blur across in place of both and no covariance
    /// (the isotropic model's curvature terms), it errs by 4.9e-2; without
    /// the covariance's skew, the third case by 9.5e-3.
    #[test]
    fn the_curved_edge_follows_the_blur_along_it() {
        use crate::psf::simpson;
        let (r, n) = (20.0, FRAC_1_SQRT_2);
        let (mut isotropic_worst, mut no_cross_worst): (f64, f64) = (0.0, 0.0);
        for (v_across, v_along, c) in [(6.0, 1.0, 0.0), (1.0, 6.0, 0.0), (3.7, 3.7, 2.6)] {
            // The frame at the point `(r + d) (n, n)`: across along the
            // normal, along the tangent; the level is the Gaussian's mass
            // over the disc.
            let det = v_across * v_along - c * c;
            let level = |d: f64| {
                let x = [(r + d) * n, (r + d) * n];
                let t = [-n, n];
                simpson(0.0, r, 400, |rho| {
                    rho * simpson(0.0, 2.0 * PI, 800, |phi| {
                        let q = [rho * phi.cos() - x[0], rho * phi.sin() - x[1]];
                        let a = q[0] * n + q[1] * n;
                        let b = q[0] * t[0] + q[1] * t[1];
                        let quad = (a * a * v_along - 2.0 * a * b * c + b * b * v_across) / det;
                        (-0.5 * quad).exp()
                    })
                }) / (2.0 * PI * det.sqrt())
            };
            let blurs = (
                (v_across - PIXEL_VARIANCE).sqrt(),
                (v_along - PIXEL_VARIANCE).sqrt(),
                c,
            );
            let worst = (-20..=20)
                .map(|i| {
                    let d = i as f64 * 0.1 * v_across.sqrt();
                    let exact = level(d);
                    let (model, _) = curved_edge(d, n, n, blurs, -1.0 / r, 1.0);
                    let iso = (blurs.0, blurs.0, 0.0);
                    let (iso, _) = curved_edge(d, n, n, iso, -1.0 / r, 1.0);
                    if c == 0.0 {
                        isotropic_worst = isotropic_worst.max((iso - exact).abs());
                    } else {
                        let (plain, _) =
                            curved_edge(d, n, n, (blurs.0, blurs.1, 0.0), -1.0 / r, 1.0);
                        no_cross_worst = no_cross_worst.max((plain - exact).abs());
                    }
                    (model - exact).abs()
                })
                .fold(0.0, f64::max);
            println!("across {v_across}, along {v_along}, covariance {c}: within {worst:.2e}");
            assert!(worst < 1e-3, "{worst}");
        }
        println!("the blur across alone within {isotropic_worst:.2e}; no covariance {no_cross_worst:.2e}");
        assert!(isotropic_worst > 3e-3, "{isotropic_worst}");
        assert!(no_cross_worst > 5e-3, "{no_cross_worst}");
    }

    /// `curved_edge`'s slope is its value's derivative.
    #[test]
    fn the_curved_edge_slope_is_its_derivative() {
        for kappa in [-0.08, 0.0, 0.03] {
            for i in -30..=30 {
                let r = i as f64 * 0.25;
                let h = 1e-6;
                let (_, d) = curved_edge(r, 0.6, 0.8, (3.0, 3.0, 0.0), kappa, 1.0);
                let fd = (curved_edge(r + h, 0.6, 0.8, (3.0, 3.0, 0.0), kappa, 1.0).0
                    - curved_edge(r - h, 0.6, 0.8, (3.0, 3.0, 0.0), kappa, 1.0).0)
                    / (2.0 * h);
                assert!((fd - d).abs() < 1e-6, "kappa {kappa}, r {r}: {fd} vs {d}");
            }
        }
    }

    use super::*;

    /// Brute force: the pixel's coverage by the half-plane, averaged over a
    /// fine grid of sub-pixels and over Gaussian-distributed shifts.
    fn brute(t: f64, nx: f64, ny: f64, sigma_b: f64) -> f64 {
        let n = 200;
        let shifts: Vec<(f64, f64)> = if sigma_b == 0.0 {
            vec![(0.0, 1.0)]
        } else {
            (-40..=40)
                .map(|k| {
                    let z = k as f64 * 0.15;
                    (z * sigma_b, normal_pdf(z) * 0.15)
                })
                .collect()
        };
        let mut total = 0.0;
        for (shift, w) in shifts {
            let mut inside = 0;
            for i in 0..n {
                for j in 0..n {
                    let x = (i as f64 + 0.5) / n as f64 - 0.5;
                    let y = (j as f64 + 0.5) / n as f64 - 0.5;
                    if x * nx + y * ny + shift <= t {
                        inside += 1;
                    }
                }
            }
            total += w * inside as f64 / (n * n) as f64;
        }
        total
    }

    proptest::proptest! {
        /// The one-exponential distribution and density against `libm`'s
        /// `erfc` and the plain density.
        #[test]
        fn normal_cdf_pdf_matches_erfc(x in -40.0f64..40.0) {
            let (cdf, pdf) = normal_cdf_pdf(x);
            let want = normal_cdf(x);
            // Relative in the lower half (the tail; the rounding of the
            // exponential's argument x^2 / 2 is relative to it), absolute
            // in the upper one (1 minus the tail, rounded). Below 1e-300
            // the values are subnormal or nearly so (x < -37) and keep
            // fewer significant digits than any relative bound; nothing
            // there weighs in a fit.
            let tol = if x < 0.0 {
                1e-15 * (1.0 + 0.5 * x * x) * want + 1e-300
            } else {
                5e-16
            };
            proptest::prop_assert!((cdf - want).abs() <= tol, "{x}: {cdf} vs {want}");
            let p = normal_pdf(x);
            proptest::prop_assert!((pdf - p).abs() <= 2e-16 * p + 1e-300, "{x}: {pdf} vs {p}");
        }
    }

    #[test]
    fn normal_cdf_pdf_at_the_branch_points() {
        // Both sides of each branch of the rational approximations.
        let y0 = 0.46875 * std::f64::consts::SQRT_2;
        let y1 = 4.0 * std::f64::consts::SQRT_2;
        for &x in &[0.0, y0, y1, 9.0, 38.0] {
            for sign in [-1.0, 1.0] {
                for dx in [-1e-12, 0.0, 1e-12] {
                    let v = sign * x + dx;
                    let (cdf, _) = normal_cdf_pdf(v);
                    let want = normal_cdf(v);
                    assert!(
                        (cdf - want).abs() <= 1e-15 * want.max(1e-300) + 4e-16,
                        "{v}"
                    );
                }
            }
        }
        assert!(normal_cdf_pdf(f64::NAN).0.is_nan());
        assert_eq!(normal_cdf_pdf(f64::INFINITY), (1.0, 0.0));
        assert_eq!(normal_cdf_pdf(f64::NEG_INFINITY), (0.0, 0.0));
    }

    proptest::proptest! {
        /// The tabulated profile against the direct one, over edge
        /// directions, blurs from none to 6 px, and the whole reach.
        #[test]
        fn tabulated_matches_direct(
            angle in 0.0f64..std::f64::consts::TAU,
            sigma_b in 0.0f64..6.0,
            frac in -1.05f64..1.05,
        ) {
            let (nx, ny) = (angle.cos(), angle.sin());
            let t = frac * (0.71 + 9.0 * sigma_b.max(MIN_BLUR));
            let (cdf, pdf) = pixel_edge_cdf(t, nx, ny, sigma_b);
            let (want_cdf, want_pdf) = pixel_edge_cdf_direct(t, nx, ny, sigma_b);
            let tol = 1e-9 * (1.0 + sigma_b * sigma_b);
            proptest::prop_assert!((cdf - want_cdf).abs() <= tol, "{cdf} vs {want_cdf}");
            // The density scales as 1 / sigma: compared in contrast per
            // spread.
            let spread = sigma_b.max(MIN_BLUR) + 0.3;
            proptest::prop_assert!((pdf - want_pdf).abs() * spread <= tol, "{pdf} vs {want_pdf}");
        }
    }

    #[test]
    fn matches_brute_force_coverage() {
        for &(angle, sigma_b) in &[(0.3, 0.0), (0.0, 0.5), (0.7, 0.8), (1.2, 0.0), (0.785, 0.3)] {
            let (nx, ny) = (f64::cos(angle), f64::sin(angle));
            for k in -8..=8 {
                let t = k as f64 * 0.11;
                let (cdf, _) = pixel_edge_cdf(t, nx, ny, sigma_b);
                let want = brute(t, nx, ny, sigma_b);
                assert!(
                    (cdf - want).abs() < 4e-3,
                    "{angle} {sigma_b} {t}: {cdf} vs {want}"
                );
            }
        }
    }

    #[test]
    fn density_is_the_derivative() {
        for &(nx, ny, s) in &[(0.6, 0.8, 0.0), (1.0, 0.0, 0.4), (0.28, -0.96, 1.5)] {
            for k in -20..=20 {
                let t = k as f64 * 0.07;
                let h = 1e-5;
                let fd = (pixel_edge_cdf(t + h, nx, ny, s).0 - pixel_edge_cdf(t - h, nx, ny, s).0)
                    / (2.0 * h);
                let pdf = pixel_edge_cdf(t, nx, ny, s).1;
                assert!((fd - pdf).abs() < 1e-5, "{nx} {ny} {s} {t}: {fd} vs {pdf}");
            }
        }
    }

    #[test]
    fn symmetric_and_centred() {
        for &(nx, ny, s) in &[(0.6, 0.8, 0.0), (1.0, 0.0, 0.4), (0.28, -0.96, 2.0)] {
            assert!((pixel_edge_cdf(0.0, nx, ny, s).0 - 0.5).abs() < 1e-12);
            for k in 1..30 {
                let t = k as f64 * 0.13;
                let (lo, hi) = (pixel_edge_cdf(-t, nx, ny, s), pixel_edge_cdf(t, nx, ny, s));
                assert!((lo.0 + hi.0 - 1.0).abs() < 1e-12);
                assert!((lo.1 - hi.1).abs() < 1e-12);
            }
        }
    }
}
