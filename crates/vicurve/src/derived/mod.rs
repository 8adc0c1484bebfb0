//! Quantities derived from measured curves: what users measure curves for.
//!
//! - closed curves ([`closed_measures`]): length, area, centroid, equivalent
//!   diameter, best-fit circle ([`fit_circle`]) and ellipse
//!   ([`fit_ellipse`]) with their uncertainties;
//! - two open curves, a specimen's edges ([`width_profile`]): the width
//!   between them along an axis, its uncertainty and its minimum;
//! - any curve ([`curvature_along`]): the curvature at its samples.
//!
//! All lengths are pixels, in the crate's coordinates (`x` column, `y` row,
//! y down; see [`crate::image`]).
//!
//! # Uncertainty of fits to a measured curve
//! The circle and ellipse are *geometric* least-squares fits (orthogonal
//! distances), solved by Levenberg–Marquardt from an algebraic start (Kåsa
//! for the circle; Fitzgibbon's direct fit as Halíř and Flusser stabilised
//! it for the ellipse). Their covariance is `s² (Jᵀ W J)⁻¹`, `W` from the
//! samples' `sigma` and `s²` the reduced chi-square.
//!
//! The samples of a measured curve are not independent: the normal
//! displacement the correlation fits is a B-spline with as many unknowns as
//! the last stage has elements (closed curve), and the samples are a dense
//! reading of it. For uniform band weights, the variance of any smooth
//! functional of the displacement (a mean, a first harmonic: what a centre
//! or radius is) is what `n_eff` = that number of unknowns independent
//! points with the samples' mean variance would give. Counting every sample
//! as independent would understate the deviations by `sqrt(N / n_eff)`
//! (about 4 to 10 on usual curves); [`closed_measures`] therefore scales the
//! covariance by `N / n_eff` and computes `s²` with `N (n_eff - k) / n_eff`
//! degrees of freedom for `k` parameters. `tests/derived.rs` checks the
//! predicted deviation of a disc's radius and centre against the scatter of
//! repeated measurements on noisy images.
//!
//! The deviations are noise only: they do not include the measurement's
//! bias (under 2e-3 px on exact-coverage images, see docs/benchmarks.md).

mod circle;
mod closed;
mod curvature;
mod ellipse;
mod lsq;
mod width;

pub use circle::{fit_circle, fit_circle_with, CircleFit};
pub use closed::{closed_measures, closed_measures_curve, ClosedMeasures};
pub use curvature::{curvature_along, curvature_at, CurvatureSample, CurvatureSummary};
pub use ellipse::{fit_ellipse, fit_ellipse_with, EllipseFit};
pub use width::{width_profile, width_profile_curves, WidthAxis, WidthProfile, WidthSample};

use crate::measurement::Measurement;
use serde::{Deserialize, Serialize};

/// The derived quantities of one measured curve, as written in result files
/// (the `derived` field of [`crate::report::ResultFile`]).
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub struct Derived {
    /// Closed curves: [`closed_measures`]; `None` for open curves or when
    /// they could not be computed (then `closed_error` says why).
    pub closed: Option<ClosedMeasures>,
    /// Why `closed` is `None` for a closed curve.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub closed_error: Option<String>,
    /// Summary of the curvature along the samples (the per-sample values:
    /// [`curvature_along`]); `None` without finite values.
    pub curvature: Option<CurvatureSummary>,
}

impl Derived {
    /// The derived quantities of `m`. Never fails: a computation that
    /// cannot be done (a degenerate curve) is recorded as absent.
    pub fn new(m: &Measurement) -> Self {
        let (closed, closed_error) = if m.curve.is_closed() {
            match closed_measures(m) {
                Ok(c) => (Some(c), None),
                Err(e) => (None, Some(e.to_string())),
            }
        } else {
            (None, None)
        };
        Derived {
            closed,
            closed_error,
            curvature: CurvatureSummary::new(&curvature_along(m)),
        }
    }
}
