//! Exporting a measured curve to other programs, exactly.
//!
//! - [`dxf`]: a DXF R2000 drawing with the curve as a `SPLINE` entity
//!   (degree, knots, control points, closed flag) for CAD programs.
//! - [`svg_bezier`]: an SVG path of exact cubic Bézier segments (degree 3
//!   or lower).
//! - [`source`]: the curve read back from a result file, to export it
//!   without measuring again.
//!
//! Both exports are changes of representation by knot insertion
//! ([`crate::nurbs`]), not approximations: they reproduce the measured
//! B-spline to rounding (the tests hold them to 1e-9 px).

pub mod dxf;
mod emit;
pub mod source;
pub mod svg_bezier;

pub use dxf::{spline_dxf, ClosedForm, DxfOptions, YAxis};
pub use source::{read_result_curve, ResultCurve};
pub use svg_bezier::{curve_svg, SvgOptions};
