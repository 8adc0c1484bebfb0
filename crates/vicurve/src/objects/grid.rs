//! Circle-grid strain analysis: each printed circle of diameter `D0`,
//! measured as an ellipse after forming, gives the principal true strains
//! (square grids: [`super::square_grid`]).

use super::{AllResult, ObjectResult};
use serde::{Deserialize, Serialize};

/// The strains of one circle of the grid. Strains are true (logarithmic)
/// strains, dimensionless; angles in radians, counterclockwise on screen
/// from `+x`; each with its standard deviation from the ellipse's noise
/// covariance (first-order propagation).
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub struct GridStrain {
    /// The object's id.
    pub id: usize,
    /// Ellipse centre `[x, y]`, px.
    pub centre: [f64; 2],
    /// Semi-axes `a >= b`, px.
    pub a: f64,
    /// Minor semi-axis, px.
    pub b: f64,
    /// Major strain `ln(2a / D0)`.
    pub eps1: f64,
    /// Its standard deviation, `sigma_a / a`.
    pub sigma_eps1: f64,
    /// Minor strain `ln(2b / D0)`.
    pub eps2: f64,
    /// Its standard deviation.
    pub sigma_eps2: f64,
    /// Thickness strain `-(eps1 + eps2)` (constant volume).
    pub eps3: f64,
    /// Its standard deviation (with the covariance of `a` and `b`).
    pub sigma_eps3: f64,
    /// Direction of the major axis, rad, in `(-pi/2, pi/2]`.
    pub angle: f64,
    /// Its standard deviation, rad (large when `a` is close to `b`).
    pub sigma_angle: f64,
    /// Square grids: the deviation `[x, y]` of the cell's centroid
    /// (`centre`), px.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub sigma_centre: Option<[f64; 2]>,
    /// Square grids: the cell's lattice index `[column, row]`.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub cell: Option<[i64; 2]>,
    /// Square grids: the local deformation gradient `F` (row-major,
    /// `F[r][c] = dx_r / dX_c`, reference axes along the columns and rows).
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub gradient: Option<[[f64; 2]; 2]>,
    /// Square grids: whether `F` is from central differences in both
    /// directions (second order); `false` at the grid's edge (one-sided,
    /// first order: biased by about half a pitch times the strain's
    /// gradient).
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub central: Option<bool>,
}

/// The strains of every measured object of `all` for circles printed with
/// diameter `d0` px: from the ellipse model's fit when `all` was measured
/// with the ellipse model (its covariance), else from the ellipse fitted to
/// the measured curve. `None` for a failed object or one without an
/// ellipse; `d0` must be positive (NaN strains otherwise).
pub fn grid_strains(all: &AllResult, d0: f64) -> Vec<Option<GridStrain>> {
    all.objects.iter().map(|o| strain_of(o, d0)).collect()
}

/// The ellipse of `o` as `(centre, a, b, angle, sigma_a, sigma_b, cov_ab,
/// sigma_angle)`.
type Axes = ([f64; 2], f64, f64, f64, f64, f64, f64, f64);

fn ellipse_of(o: &ObjectResult) -> Option<Axes> {
    if let Some(f) = o.model.as_ref().filter(|f| f.parameter("b").is_some()) {
        let idx = |n: &str| f.parameters.iter().position(|p| p.name == n);
        let (ia, ib) = (idx("a")?, idx("b")?);
        let v = |n: &str| f.parameter(n).map_or(f64::NAN, |p| p.value);
        let s = |n: &str| f.parameter(n).map_or(f64::NAN, |p| p.sigma);
        let cov = f.covariance.get(ia).and_then(|r| r.get(ib)).copied();
        return Some((
            [v("cx"), v("cy")],
            v("a"),
            v("b"),
            v("angle"),
            s("a"),
            s("b"),
            cov.unwrap_or(0.0),
            s("angle"),
        ));
    }
    let e = &o.closed.as_ref()?.ellipse;
    Some((
        [e.cx, e.cy],
        e.a,
        e.b,
        e.angle,
        e.sigma_a,
        e.sigma_b,
        0.0,
        e.sigma_angle,
    ))
}

fn strain_of(o: &ObjectResult, d0: f64) -> Option<GridStrain> {
    if o.failure.is_some() {
        return None;
    }
    let (centre, a, b, angle, sa, sb, cab, sang) = ellipse_of(o)?;
    let (s1, s2) = (sa / a, sb / b);
    let c12 = cab / (a * b);
    Some(GridStrain {
        id: o.id,
        centre,
        a,
        b,
        eps1: (2.0 * a / d0).ln(),
        sigma_eps1: s1,
        eps2: (2.0 * b / d0).ln(),
        sigma_eps2: s2,
        eps3: -((2.0 * a / d0).ln() + (2.0 * b / d0).ln()),
        sigma_eps3: (s1 * s1 + s2 * s2 + 2.0 * c12).max(0.0).sqrt(),
        angle,
        sigma_angle: sang,
        sigma_centre: None,
        cell: None,
        gradient: None,
        central: None,
    })
}
