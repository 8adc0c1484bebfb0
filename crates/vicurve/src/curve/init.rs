//! Initial curves: a circle, a segment or a polyline, as given by the user.

use super::SplineCurve;
use crate::error::{Error, Result};
use serde::{Deserialize, Serialize};
use std::f64::consts::TAU;

/// Control-point spacing of the B-spline that represents an initial curve,
/// pixels: fine enough that a circle is represented to ~1e-7 px.
const INIT_SPACING: f64 = 2.0;

/// The starting curve of a measurement (pixels, image coordinates).
///
/// A user's rough start, turned into a B-spline by
/// [`InitialCurve::to_curve`]; its circle is not the exact
/// [`crate::truth::Shape::Circle`] nor a model's
/// [`crate::model::ModelShape::Circle`]: it has its own checks (a radius
/// of at least 2 px), segments and polylines instead of ellipses, and its
/// own JSON form (a `"type"` tag, as written in result and job files).
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
#[serde(tag = "type", rename_all = "snake_case")]
pub enum InitialCurve {
    /// A circle of centre `(cx, cy)` and radius `r` (closed).
    Circle {
        /// Centre x (column).
        cx: f64,
        /// Centre y (row).
        cy: f64,
        /// Radius.
        r: f64,
    },
    /// The straight segment from `(x0, y0)` to `(x1, y1)` (open).
    Segment {
        /// Start x.
        x0: f64,
        /// Start y.
        y0: f64,
        /// End x.
        x1: f64,
        /// End y.
        y1: f64,
    },
    /// A polyline through the points, closed or open; it is resampled and
    /// smoothed by a cubic B-spline with control points 2 px apart, so its
    /// corners are rounded over about 2 px.
    Polyline {
        /// The vertices `[x, y]`.
        points: Vec<[f64; 2]>,
        /// Whether the last vertex joins the first.
        closed: bool,
    },
}

impl InitialCurve {
    /// Whether the curve is closed.
    pub fn is_closed(&self) -> bool {
        match self {
            InitialCurve::Circle { .. } => true,
            InitialCurve::Segment { .. } => false,
            InitialCurve::Polyline { closed, .. } => *closed,
        }
    }

    /// Dense points along the curve, at most `step` pixels apart.
    pub fn dense_points(&self, step: f64) -> Result<Vec<[f64; 2]>> {
        self.validate()?;
        Ok(match self {
            InitialCurve::Circle { cx, cy, r } => {
                let n = ((TAU * r / step).ceil() as usize).max(16);
                (0..n)
                    .map(|i| {
                        let th = TAU * i as f64 / n as f64;
                        // Counterclockwise on screen (y down).
                        [cx + r * th.cos(), cy - r * th.sin()]
                    })
                    .collect()
            }
            InitialCurve::Segment { x0, y0, x1, y1 } => {
                resample(&[[*x0, *y0], [*x1, *y1]], false, step)
            }
            InitialCurve::Polyline { points, closed } => resample(points, *closed, step),
        })
    }

    /// The curve as a [`SplineCurve`] (cubic, control points 2 px apart;
    /// a segment is represented exactly).
    pub fn to_curve(&self) -> Result<SplineCurve> {
        let pts = self.dense_points(0.25)?;
        SplineCurve::fit(&pts, self.is_closed(), 3, INIT_SPACING)
    }

    fn validate(&self) -> Result<()> {
        let finite = |v: &[f64]| v.iter().all(|x| x.is_finite());
        match self {
            InitialCurve::Circle { cx, cy, r } => {
                if !finite(&[*cx, *cy, *r]) {
                    return Err(Error::NonFinite {
                        what: "initial circle".into(),
                    });
                }
                if *r < 2.0 {
                    return Err(Error::invalid(
                        "initial circle",
                        format!("radius {r} px (must be at least 2 px)"),
                    ));
                }
            }
            InitialCurve::Segment { x0, y0, x1, y1 } => {
                if !finite(&[*x0, *y0, *x1, *y1]) {
                    return Err(Error::NonFinite {
                        what: "initial segment".into(),
                    });
                }
                if (x1 - x0).hypot(y1 - y0) < 2.0 {
                    return Err(Error::invalid(
                        "initial segment",
                        "shorter than 2 px".to_string(),
                    ));
                }
            }
            InitialCurve::Polyline { points, closed } => {
                if points.iter().any(|p| !finite(p)) {
                    return Err(Error::NonFinite {
                        what: "initial polyline".into(),
                    });
                }
                let need = if *closed { 3 } else { 2 };
                if points.len() < need {
                    return Err(Error::InvalidCurve {
                        reason: format!(
                            "the polyline has {} points (need at least {need})",
                            points.len()
                        ),
                    });
                }
            }
        }
        Ok(())
    }
}

impl std::str::FromStr for InitialCurve {
    type Err = Error;
    /// `circle:CX,CY,R` or `segment:X0,Y0,X1,Y1` (pixels). Polylines come
    /// from files; the CLI reads them.
    fn from_str(spec: &str) -> Result<Self> {
        let parse_err = |reason: String| Error::Parse {
            what: format!("initial curve '{spec}'"),
            line: 0,
            reason,
        };
        let (kind, rest) = spec.split_once(':').ok_or_else(|| {
            parse_err("expected circle:CX,CY,R or segment:X0,Y0,X1,Y1 or polyline:FILE.csv".into())
        })?;
        let nums: std::result::Result<Vec<f64>, _> =
            rest.split(',').map(|t| t.trim().parse::<f64>()).collect();
        let nums = nums.map_err(|e| parse_err(format!("{e}")))?;
        match (kind.trim(), nums.as_slice()) {
            ("circle", &[cx, cy, r]) => Ok(InitialCurve::Circle { cx, cy, r }),
            ("segment", &[x0, y0, x1, y1]) => Ok(InitialCurve::Segment { x0, y0, x1, y1 }),
            ("circle", v) => Err(parse_err(format!(
                "circle needs 3 numbers CX,CY,R, got {}",
                v.len()
            ))),
            ("segment", v) => Err(parse_err(format!(
                "segment needs 4 numbers X0,Y0,X1,Y1, got {}",
                v.len()
            ))),
            (k, _) => Err(parse_err(format!(
                "unknown curve type '{k}' (expected circle or segment)"
            ))),
        }
    }
}

/// The polyline resampled at most `step` apart (vertices kept).
fn resample(points: &[[f64; 2]], closed: bool, step: f64) -> Vec<[f64; 2]> {
    let mut out = Vec::new();
    let n = points.len();
    let segs = if closed { n } else { n - 1 };
    for i in 0..segs {
        let a = points[i];
        let b = points[(i + 1) % n];
        let len = (b[0] - a[0]).hypot(b[1] - a[1]);
        let k = ((len / step).ceil() as usize).max(1);
        for j in 0..k {
            let t = j as f64 / k as f64;
            out.push([a[0] + t * (b[0] - a[0]), a[1] + t * (b[1] - a[1])]);
        }
    }
    if !closed {
        out.push(points[n - 1]);
    }
    out
}
