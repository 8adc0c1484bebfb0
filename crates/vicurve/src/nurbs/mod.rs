//! NURBS geometry beyond the measurement: B-spline curves on general knot
//! vectors, knot insertion, degree elevation, and surface patches between
//! two measured edges with h-refinement and VTK export.
//!
//! The measured curves are uniform B-splines ([`crate::spline`]); this
//! module takes them as ordinary B-spline curves
//! ([`curve::BSplineCurve::from_data`] reads the `curve` of a result file)
//! and changes their *representation* without changing their points:
//! every operation here is exact up to floating-point rounding (tests hold
//! them to 1e-9 px). References: Piegl & Tiller, *The NURBS Book* (2nd
//! ed., 1997), algorithms A2.1, A2.2 (basis), A5.1 (knot insertion).
//!
//! - [`basis`]: knot vectors, spans, basis functions.
//! - [`refine`]: Boehm's knot insertion, the knots of an h-refinement.
//! - [`curve`]: [`BSplineCurve`]: clamping, Bézier extraction, degree
//!   elevation, reversal, reparametrisation.
//! - [`patch`]: [`NurbsPatch`] between two open curves, h-refinement,
//!   JSON form [`PatchData`].
//! - [`vtu`]: ASCII VTK unstructured grids of a patch and its control net.

pub mod basis;
pub mod curve;
pub mod patch;
pub mod refine;
pub mod vtu;

pub use curve::BSplineCurve;
pub use patch::{NurbsPatch, PatchBuild, PatchConfig, PatchData};
