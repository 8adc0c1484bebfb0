//! Measures of a closed curve: length, area, centroid, equivalent diameter,
//! best-fit circle and ellipse.

use super::circle::{fit_circle_with, CircleFit};
use super::ellipse::{fit_ellipse_with, EllipseFit};
use crate::curve::SplineCurve;
use crate::error::{Error, Result};
use crate::measurement::Measurement;
use serde::{Deserialize, Serialize};

/// Measures of a closed curve. Pixels.
#[derive(Clone, Copy, Debug, PartialEq, Serialize, Deserialize)]
pub struct ClosedMeasures {
    /// Arc length of the B-spline, px.
    pub length: f64,
    /// Enclosed area, px² (positive: closed curves run counterclockwise on
    /// screen).
    pub area: f64,
    /// Centroid of the enclosed region, `[x, y]`, px.
    pub centroid: [f64; 2],
    /// Diameter of the disc of the same area, `sqrt(4 area / pi)`, px.
    pub equivalent_diameter: f64,
    /// Best-fit circle (orthogonal distances to the samples).
    pub circle: CircleFit,
    /// Best-fit ellipse (orthogonal distances to the samples).
    pub ellipse: EllipseFit,
}

/// The measures of a closed measured curve.
///
/// Length, area and centroid are integrals over the measured B-spline
/// (Gauss–Legendre quadrature on each element, exact to rounding for the
/// polynomial integrands of area and centroid). The circle and ellipse are
/// fitted to the samples, weighted by their `sigma` when it is known; their
/// deviations account for the samples' correlation by taking the last
/// stage's number of elements as the number of independent points (see
/// [`crate::derived`]). A curve measured in linear light by a tone curve
/// read from its own edge ([`Measurement::tone_estimate`]) may be off by
/// the reading's uncertainty all round: the radius and the semi-axes carry
/// it too ([`Measurement::sigma_shift`], in quadrature; the fits' own
/// deviations, from their residuals, cannot see a term common to every
/// sample).
///
/// Errors: [`Error::InvalidCurve`] for an open curve, or when the samples
/// determine no circle or ellipse.
pub fn closed_measures(m: &Measurement) -> Result<ClosedMeasures> {
    let independent = m.stages.last().map(|s| s.elements as f64);
    let sigma: Vec<f64> = m.samples.iter().map(|s| s.sigma).collect();
    let mut c = measures(&m.curve, &m.points(), Some(&sigma), independent)?;
    let shift = m.sigma_shift();
    c.circle.sigma_r = c.circle.sigma_r.hypot(shift);
    c.ellipse.sigma_a = c.ellipse.sigma_a.hypot(shift);
    c.ellipse.sigma_b = c.ellipse.sigma_b.hypot(shift);
    Ok(c)
}

/// The measures of a closed B-spline curve without a fit behind it: the
/// circle and ellipse are fitted, unweighted, to points about 1 px apart
/// along it, taken as independent.
///
/// Errors: as [`closed_measures`].
pub fn closed_measures_curve(curve: &SplineCurve) -> Result<ClosedMeasures> {
    let n = (curve.param_length().ceil() as usize).clamp(16, 10_000_000);
    let pts: Vec<[f64; 2]> = curve
        .sample_params(n)
        .into_iter()
        .map(|u| curve.point(u))
        .collect();
    measures(curve, &pts, None, None)
}

fn measures(
    curve: &SplineCurve,
    points: &[[f64; 2]],
    sigma: Option<&[f64]>,
    independent: Option<f64>,
) -> Result<ClosedMeasures> {
    if !curve.is_closed() {
        return Err(Error::InvalidCurve {
            reason: "the curve is open: length, area and best-fit circle or ellipse \
                     are computed for closed curves"
                .into(),
        });
    }
    let (signed_area, centroid) = area_centroid(curve);
    let area = signed_area.abs();
    if !(area > 0.0 && area.is_finite()) {
        return Err(Error::InvalidCurve {
            reason: "the closed curve encloses no area".into(),
        });
    }
    Ok(ClosedMeasures {
        length: curve.arc_length(),
        area,
        centroid,
        equivalent_diameter: (4.0 * area / std::f64::consts::PI).sqrt(),
        circle: fit_circle_with(points, sigma, independent)?,
        ellipse: fit_ellipse_with(points, sigma, independent)?,
    })
}

/// Signed area `A = ∮ x dy` and centroid `(∮ x²/2 dy, -∮ y²/2 dx) / A` by
/// Green's theorem (the signs cancel in the centroid whatever the
/// orientation). The integrands are polynomials of degree at most
/// `3 p - 1 <= 14` in each element, which 8-point Gauss–Legendre
/// integrates exactly.
fn area_centroid(curve: &SplineCurve) -> (f64, [f64; 2]) {
    let (mut a, mut mx, mut my) = (0.0, 0.0, 0.0);
    for e in 0..curve.basis().n_elements() {
        // Elements differ in length between breaks (corners).
        let (start, len) = curve.basis().element_bounds(e);
        let (c, r) = (start + 0.5 * len, 0.5 * len);
        for (x, w) in GL8_X.iter().zip(GL8_W) {
            let [p, d, _] = curve.derivatives(c + r * x);
            let wr = w * r;
            a += wr * p[0] * d[1];
            mx += wr * 0.5 * p[0] * p[0] * d[1];
            my -= wr * 0.5 * p[1] * p[1] * d[0];
        }
    }
    (a, [mx / a, my / a])
}

/// 8-point Gauss–Legendre nodes on `[-1, 1]`.
const GL8_X: [f64; 8] = [
    -0.960_289_856_497_536_2,
    -0.796_666_477_413_626_7,
    -0.525_532_409_916_329,
    -0.183_434_642_495_649_8,
    0.183_434_642_495_649_8,
    0.525_532_409_916_329,
    0.796_666_477_413_626_7,
    0.960_289_856_497_536_2,
];
/// 8-point Gauss–Legendre weights.
const GL8_W: [f64; 8] = [
    0.101_228_536_290_376_3,
    0.222_381_034_453_374_5,
    0.313_706_645_877_887_3,
    0.362_683_783_378_362,
    0.362_683_783_378_362,
    0.313_706_645_877_887_3,
    0.222_381_034_453_374_5,
    0.101_228_536_290_376_3,
];

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn gauss_legendre_8_is_exact_to_degree_15() {
        for k in 0..=15 {
            let num: f64 = GL8_X.iter().zip(GL8_W).map(|(x, w)| w * x.powi(k)).sum();
            let exact = if k % 2 == 1 {
                0.0
            } else {
                2.0 / (k as f64 + 1.0)
            };
            assert!((num - exact).abs() < 1e-14, "degree {k}: {num} vs {exact}");
        }
    }
}
