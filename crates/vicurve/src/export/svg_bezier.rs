//! A measured curve as an SVG path of exact cubic Bézier segments.
//!
//! On each knot span a B-spline of degree `p` is one polynomial piece, i.e.
//! one Bézier curve of degree `p`: [`BSplineCurve::bezier_segments`] finds
//! them by knot insertion. SVG's `C` command draws cubic pieces, so
//!
//! - **degree 3**: the pieces are written as they are;
//! - **degree 1 and 2**: each piece is raised to degree 3 by Bézier degree
//!   elevation (`Q_i = i/(d+1) P_{i-1} + (1 - i/(d+1)) P_i`), which is
//!   exact: the same polynomial, written with one more control point;
//! - **degree 4 and 5**: there is no exact cubic form (a degree cannot be
//!   lowered), and this module refuses with an error rather than
//!   approximating: measure with `--degree 3`, or export DXF, which keeps
//!   any degree.
//!
//! The path is `M x0,y0 C x1,y1 x2,y2 x3,y3 C ...` (closed curves end with
//! `Z`), one `C` per knot span, in the curve's direction. Coordinates are
//! the measured pixel coordinates (`x` = column, `y` = row, y down as in
//! SVG) written with the shortest decimal form that reads back to the same
//! double: the path reproduces the curve to ~1e-12 px.
//!
//! [`curve_svg`] wraps the path in a document whose user units are pixels,
//! like the overlays of `vicurve measure --svg`: with the image's size as
//! canvas the view box is `0 0 width height`, and the path sits in a group
//! translated by `(0.5, 0.5)` so that the centre of pixel `(i, j)`, at
//! `(j, i)`, falls at the centre of its square in an image drawn over the
//! canvas.

use crate::curve::SplineCurveData;
use crate::error::{Error, Result};
use crate::nurbs::BSplineCurve;
use serde::{Deserialize, Serialize};
use std::fmt::Write;

/// A chain of cubic Bézier segments.
#[derive(Clone, Debug, PartialEq)]
pub struct CubicPath {
    /// The start point.
    pub start: [f64; 2],
    /// Each segment's three other control points (the first is the
    /// previous segment's end, or `start`).
    pub segments: Vec<[[f64; 2]; 3]>,
    /// Whether the curve is closed (its end is its start).
    pub closed: bool,
}

/// The cubic Bézier segments of `curve`, one per knot span.
///
/// Errors: [`Error::InvalidParameter`] for a degree above 3 (see the
/// [module documentation](self)); as [`BSplineCurve::from_data`] for
/// inconsistent data.
pub fn cubic_segments(curve: &SplineCurveData) -> Result<CubicPath> {
    if curve.degree > 3 {
        return Err(Error::invalid(
            "degree",
            format!(
                "{}: a B-spline of degree above 3 has no exact cubic Bézier form; measure with --degree 3 (or lower), or export DXF, which keeps any degree",
                curve.degree
            ),
        ));
    }
    let c = BSplineCurve::from_data(curve)?;
    let pieces = c.bezier_segments()?;
    let mut segments = Vec::with_capacity(pieces.len());
    for piece in &pieces {
        let mut q = piece.clone();
        while q.len() < 4 {
            q = elevate(&q);
        }
        segments.push([q[1], q[2], q[3]]);
    }
    let start = pieces.first().map_or([0.0; 2], |p| p[0]);
    Ok(CubicPath {
        start,
        segments,
        closed: curve.closed,
    })
}

/// A Bézier curve of degree `d` written with degree `d + 1`.
fn elevate(p: &[[f64; 2]]) -> Vec<[f64; 2]> {
    let d = p.len() - 1;
    let n = (d + 1) as f64;
    (0..=d + 1)
        .map(|i| {
            if i == 0 {
                p[0]
            } else if i == d + 1 {
                p[d]
            } else {
                let a = i as f64 / n;
                [
                    a * p[i - 1][0] + (1.0 - a) * p[i][0],
                    a * p[i - 1][1] + (1.0 - a) * p[i][1],
                ]
            }
        })
        .collect()
}

/// The path's `d` attribute.
pub fn path_data(path: &CubicPath) -> String {
    let xy = |p: [f64; 2]| format!("{},{}", p[0], p[1]);
    let mut d = format!("M {}", xy(path.start));
    for s in &path.segments {
        let _ = write!(d, " C {} {} {}", xy(s[0]), xy(s[1]), xy(s[2]));
    }
    if path.closed {
        d.push_str(" Z");
    }
    d
}

/// Options of [`curve_svg`]; serialisable, defaults as documented.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
#[serde(default)]
pub struct SvgOptions {
    /// The image's `(width, height)` in pixels: the canvas (`None`: the
    /// curve's bounding box with a 10 px margin).
    pub canvas: Option<(usize, usize)>,
    /// Stroke colour (default `"red"`).
    pub stroke: String,
    /// Stroke width in pixels (default 0.5).
    pub stroke_width: f64,
    /// Text for the document's `<desc>` (e.g. the input image).
    pub comment: String,
}

impl Default for SvgOptions {
    fn default() -> Self {
        SvgOptions {
            canvas: None,
            stroke: "red".into(),
            stroke_width: 0.5,
            comment: String::new(),
        }
    }
}

/// An SVG document with the curve as one `<path>` of cubic Bézier
/// segments; see the [module documentation](self).
///
/// Errors: as [`cubic_segments`]; [`Error::InvalidParameter`] for a stroke
/// width that is not finite and positive or a stroke colour with
/// characters that would break the XML.
pub fn curve_svg(curve: &SplineCurveData, options: &SvgOptions) -> Result<String> {
    if !(options.stroke_width.is_finite() && options.stroke_width > 0.0) {
        return Err(Error::invalid(
            "stroke width",
            format!("{} (must be > 0)", options.stroke_width),
        ));
    }
    if options.stroke.contains(['"', '<', '>', '&']) || options.stroke.is_empty() {
        return Err(Error::invalid(
            "stroke colour",
            format!(
                "'{}' (an SVG colour such as red or #ff0000)",
                options.stroke
            ),
        ));
    }
    let path = cubic_segments(curve)?;
    let (x0, y0, w, h) = match options.canvas {
        Some((w, h)) => (0.0, 0.0, w as f64, h as f64),
        None => {
            let mut lo = path.start;
            let mut hi = path.start;
            for p in path.segments.iter().flatten() {
                lo = [lo[0].min(p[0]), lo[1].min(p[1])];
                hi = [hi[0].max(p[0]), hi[1].max(p[1])];
            }
            let m = 10.0;
            (
                (lo[0] + 0.5 - m).floor(),
                (lo[1] + 0.5 - m).floor(),
                (hi[0] - lo[0] + 2.0 * m).ceil() + 1.0,
                (hi[1] - lo[1] + 2.0 * m).ceil() + 1.0,
            )
        }
    };
    let mut s = String::new();
    let _ = writeln!(s, r#"<?xml version="1.0" encoding="UTF-8"?>"#);
    let _ = writeln!(
        s,
        r#"<svg xmlns="http://www.w3.org/2000/svg" width="{w}" height="{h}" viewBox="{x0} {y0} {w} {h}">"#
    );
    let desc = format!(
        "vicurve {}: measured {} B-spline of degree {} as {} exact cubic Bezier segments{}. Path coordinates: pixels, x = column, y = row (down); the group's translate(0.5 0.5) puts pixel centres at the centres of the image's pixel squares.",
        env!("CARGO_PKG_VERSION"),
        if curve.closed { "closed" } else { "open" },
        curve.degree,
        path.segments.len(),
        if options.comment.is_empty() {
            String::new()
        } else {
            format!(" ({})", options.comment)
        }
    );
    let _ = writeln!(s, "<desc>{}</desc>", xml_escape(&desc));
    let _ = writeln!(s, r#"<g transform="translate(0.5 0.5)">"#);
    let _ = writeln!(
        s,
        r#"<path fill="none" stroke="{}" stroke-width="{}" stroke-linejoin="round" d="{}"/>"#,
        options.stroke,
        options.stroke_width,
        path_data(&path)
    );
    let _ = writeln!(s, "</g>");
    let _ = writeln!(s, "</svg>");
    Ok(s)
}

fn xml_escape(t: &str) -> String {
    t.replace('&', "&amp;")
        .replace('<', "&lt;")
        .replace('>', "&gt;")
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn elevation_keeps_the_polynomial() {
        let p = vec![[0.0, 0.0], [1.0, 2.0], [3.0, -1.0]];
        let q = elevate(&p);
        assert_eq!(q.len(), 4);
        for i in 0..=10 {
            let t = i as f64 / 10.0;
            let b2 = |k: usize| {
                let u = 1.0 - t;
                [u * u, 2.0 * u * t, t * t][k]
            };
            let b3 = |k: usize| {
                let u = 1.0 - t;
                [u * u * u, 3.0 * u * u * t, 3.0 * u * t * t, t * t * t][k]
            };
            for d in 0..2 {
                let a: f64 = (0..3).map(|k| b2(k) * p[k][d]).sum();
                let b: f64 = (0..4).map(|k| b3(k) * q[k][d]).sum();
                assert!((a - b).abs() < 1e-14);
            }
        }
    }
}
