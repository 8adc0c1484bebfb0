//! A measured curve as a DXF `SPLINE` entity, in an ASCII DXF R2000
//! (AC1015) drawing that CAD programs open.
//!
//! # The drawing
//! `SPLINE` exists since R13, and from R13 on a DXF file needs more than
//! its entities (AutoCAD refuses a bare `ENTITIES` section): the HEADER
//! (`$ACADVER`, `$HANDSEED`, units, extents), an empty CLASSES section but
//! for the two classes used by the OBJECTS, the nine symbol tables with their
//! standard entries (VPORT `*Active`; LTYPE `ByBlock`, `ByLayer`,
//! `Continuous`; LAYER `0`; STYLE and DIMSTYLE `Standard`; APPID `ACAD`;
//! BLOCK_RECORD `*Model_Space` and `*Paper_Space`), the two layout blocks,
//! the entity, and the root dictionary with `ACAD_GROUP` and the plot-style
//! dictionary that layers point to. This is the minimal content documented
//! by ezdxf for R13 and later, with the handles and owner pointers that
//! AutoCAD checks.
//!
//! # The spline (group codes of the DXF reference)
//! `70` flags (1 closed, 2 periodic, 8 planar), `71` degree, `72` number of
//! knots, `73` number of control points, `74` fit points (0), `42`/`43`
//! knot and control-point tolerances, `40` each knot, `10`/`20`/`30` each
//! control point; weights (`41`) are omitted: all 1.
//!
//! - **Open curves** are written *clamped*: the end knots raised to
//!   multiplicity `p + 1` by knot insertion, so the curve starts and ends
//!   at control points, the form every program evaluates alike. Flags: 8.
//! - **Closed curves**, by default ([`ClosedForm::Periodic`]), as the
//!   result file holds them: flags 1 + 2 + 8 = 11 (closed, periodic,
//!   planar), uniform knots, the first `p` control points repeated at the
//!   end (`72 = 73 + p + 1`), the form ezdxf writes for closed splines.
//!   [`ClosedForm::Clamped`] writes them clamped instead (flags 8, the
//!   first control point equal to the last): for programs that do not
//!   evaluate an unclamped knot vector on its domain. Seen while testing:
//!   LibreCAD 2.2 ignores the knots (it assumes clamped uniform knots, and
//!   wraps the control points of a spline flagged closed itself), so it
//!   draws the periodic form with a spurious loop at the start but the
//!   clamped form exactly; ezdxf 1.4 reads both forms and evaluates them
//!   right (`construction_tool().point`), but its `flattening` runs over
//!   the whole knot range, also for the closed splines it writes itself.
//!
//! The knots keep the measured curve's parameter (pixels of arc length,
//! `[0, L]`): a program that evaluates the knots finds the measured point
//! at the same parameter. Every number is written with the shortest
//! decimal form that reads back to the same double, so the file
//! reproduces the curve exactly (to ~1e-12 px).
//!
//! # Coordinates
//! Pixels, `x` = column. CAD's y axis points up and the image's down, so by
//! default ([`YAxis::Up`]) `y_dxf = -y`: the drawing looks like the image
//! (a closed curve still runs counterclockwise as seen). [`YAxis::Down`]
//! keeps `y_dxf = y` (the drawing is mirrored). Units: `$INSUNITS` 0
//! (unitless). A `999` comment line at the top of the file states the
//! mapping.

use super::emit::Tags;
use crate::curve::SplineCurveData;
use crate::error::Result;
use crate::nurbs::BSplineCurve;
use serde::{Deserialize, Serialize};

/// How image `y` (down) becomes DXF `y` (up).
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq, Serialize, Deserialize)]
#[serde(rename_all = "snake_case")]
pub enum YAxis {
    /// `y_dxf = -y`: the drawing looks like the image (default).
    #[default]
    Up,
    /// `y_dxf = y`: the pixel coordinates unchanged, the drawing mirrored.
    Down,
}

/// How a closed curve is written; see the [module documentation](self).
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq, Serialize, Deserialize)]
#[serde(rename_all = "snake_case")]
pub enum ClosedForm {
    /// Flags closed + periodic, uniform knots, `p` repeated control points
    /// (default).
    #[default]
    Periodic,
    /// Clamped knots, first control point = last, flagged open.
    Clamped,
}

/// Options of [`spline_dxf`]; serialisable, defaults as documented.
#[derive(Clone, Debug, Default, PartialEq, Eq, Serialize, Deserialize)]
#[serde(default)]
pub struct DxfOptions {
    /// The y mapping (default [`YAxis::Up`]).
    pub y_axis: YAxis,
    /// The form of closed curves (default [`ClosedForm::Periodic`]).
    pub closed_form: ClosedForm,
    /// A line for the `999` comment, e.g. the input image (may be empty).
    pub comment: String,
}

/// The `SPLINE` entity's data, in DXF coordinates.
#[derive(Clone, Debug, PartialEq)]
pub struct DxfSpline {
    /// Group 70.
    pub flags: u16,
    /// Group 71.
    pub degree: usize,
    /// Groups 40.
    pub knots: Vec<f64>,
    /// Groups 10 and 20 (30 is 0).
    pub control_points: Vec<[f64; 2]>,
}

/// Flag bits of group 70.
pub const FLAG_CLOSED: u16 = 1;
/// Periodic.
pub const FLAG_PERIODIC: u16 = 2;
/// Planar.
pub const FLAG_PLANAR: u16 = 8;

/// The entity for `curve` (see the [module documentation](self)).
///
/// Errors: as [`BSplineCurve::from_data`] (inconsistent or non-finite
/// data).
pub fn dxf_spline(curve: &SplineCurveData, options: &DxfOptions) -> Result<DxfSpline> {
    let c = BSplineCurve::from_data(curve)?;
    let periodic = curve.closed && options.closed_form == ClosedForm::Periodic;
    let (c, flags) = if periodic {
        (c, FLAG_CLOSED | FLAG_PERIODIC | FLAG_PLANAR)
    } else {
        (c.clamped()?, FLAG_PLANAR)
    };
    let sign = match options.y_axis {
        YAxis::Up => -1.0,
        YAxis::Down => 1.0,
    };
    Ok(DxfSpline {
        flags,
        degree: c.degree(),
        knots: c.knots().to_vec(),
        control_points: c
            .control_points()
            .iter()
            .map(|p| [p[0], sign * p[1]])
            .collect(),
    })
}

// Handles of the drawing's fixed objects (hexadecimal, unique).
const H_BLOCK_RECORD_TABLE: &str = "1";
const H_LAYER_TABLE: &str = "2";
const H_STYLE_TABLE: &str = "3";
const H_LTYPE_TABLE: &str = "5";
const H_VIEW_TABLE: &str = "6";
const H_UCS_TABLE: &str = "7";
const H_VPORT_TABLE: &str = "8";
const H_APPID_TABLE: &str = "9";
const H_DIMSTYLE_TABLE: &str = "A";
const H_ROOT_DICT: &str = "C";
const H_GROUP_DICT: &str = "D";
const H_PLOTSTYLE_DICT: &str = "E";
const H_PLOTSTYLE_NORMAL: &str = "F";
const H_LAYER_0: &str = "10";
const H_STYLE_STANDARD: &str = "12";
const H_APPID_ACAD: &str = "13";
const H_LTYPES: [(&str, &str); 3] = [("14", "ByBlock"), ("15", "ByLayer"), ("16", "Continuous")];
const H_DIMSTYLE_STANDARD: &str = "17";
const H_MODEL_RECORD: &str = "18";
const H_PAPER_RECORD: &str = "19";
const H_MODEL_BLOCK: [&str; 2] = ["1A", "1B"];
const H_PAPER_BLOCK: [&str; 2] = ["1C", "1D"];
const H_VPORT_ACTIVE: &str = "1E";
const H_SPLINE: &str = "20";
/// Next free handle.
const HANDSEED: &str = "21";

/// The whole DXF file for `curve`.
///
/// Errors: as [`dxf_spline`].
pub fn spline_dxf(curve: &SplineCurveData, options: &DxfOptions) -> Result<String> {
    let s = dxf_spline(curve, options)?;
    let (lo, hi) = extents(&s.control_points);
    let mut t = Tags::default();
    t.comment(&format!(
        "vicurve {}: measured {} B-spline curve of degree {}{}",
        env!("CARGO_PKG_VERSION"),
        if curve.closed { "closed" } else { "open" },
        curve.degree,
        if options.comment.is_empty() {
            String::new()
        } else {
            format!(" ({})", options.comment)
        }
    ));
    t.comment(match options.y_axis {
        YAxis::Up => "coordinates: pixels; x_dxf = x (image column), y_dxf = -y (image row; the image's y axis points down, DXF's up, so the drawing looks like the image); pixel (row i, column j) centre at (j, -i)",
        YAxis::Down => "coordinates: pixels; x_dxf = x (image column), y_dxf = y (image row, pointing down in the image; the drawing is mirrored top to bottom); pixel (row i, column j) centre at (j, i)",
    });
    t.comment("spline parameter: the measured curve's (close to arc length in pixels)");
    header(&mut t, lo, hi);
    classes(&mut t);
    tables(&mut t, lo, hi);
    blocks(&mut t);
    t.section("ENTITIES");
    spline_entity(&mut t, &s);
    t.end_section();
    objects(&mut t);
    t.tag(0, "EOF");
    Ok(t.finish())
}

/// Bounding box of the control points (which contains the curve).
fn extents(pts: &[[f64; 2]]) -> ([f64; 2], [f64; 2]) {
    pts.iter().fold(
        ([f64::INFINITY; 2], [f64::NEG_INFINITY; 2]),
        |(lo, hi), p| {
            (
                [lo[0].min(p[0]), lo[1].min(p[1])],
                [hi[0].max(p[0]), hi[1].max(p[1])],
            )
        },
    )
}

fn header(t: &mut Tags, lo: [f64; 2], hi: [f64; 2]) {
    t.section("HEADER");
    t.var("$ACADVER").tag(1, "AC1015");
    t.var("$HANDSEED").tag(5, HANDSEED);
    // 0: unitless (pixels); 1 would be inches.
    t.var("$INSUNITS").int(70, 0);
    t.var("$MEASUREMENT").int(70, 1);
    t.var("$EXTMIN").point(10, [lo[0], lo[1]]);
    t.var("$EXTMAX").point(10, [hi[0], hi[1]]);
    t.end_section();
}

fn classes(t: &mut Tags) {
    t.section("CLASSES");
    for (dxf_name, cpp_name) in [
        ("ACDBDICTIONARYWDFLT", "AcDbDictionaryWithDefault"),
        ("ACDBPLACEHOLDER", "AcDbPlaceHolder"),
    ] {
        t.tag(0, "CLASS").tag(1, dxf_name).tag(2, cpp_name);
        t.tag(3, "ObjectDBX Classes")
            .int(90, 0)
            .int(280, 0)
            .int(281, 0);
    }
    t.end_section();
}

/// `0 TABLE` header of a symbol table with `count` entries.
fn table(t: &mut Tags, name: &str, handle: &str, count: i64) {
    t.tag(0, "TABLE").tag(2, name).tag(5, handle).tag(330, "0");
    t.tag(100, "AcDbSymbolTable").int(70, count);
}

/// Start of a table record: type, handle, owner, subclass markers.
fn record(t: &mut Tags, kind: &str, handle: &str, owner: &str, subclass: &str) {
    t.tag(0, kind);
    // DIMSTYLE records carry their handle in group 105.
    t.tag(if kind == "DIMSTYLE" { 105 } else { 5 }, handle);
    t.tag(330, owner)
        .tag(100, "AcDbSymbolTableRecord")
        .tag(100, subclass);
}

fn tables(t: &mut Tags, lo: [f64; 2], hi: [f64; 2]) {
    t.section("TABLES");

    table(t, "VPORT", H_VPORT_TABLE, 1);
    record(
        t,
        "VPORT",
        H_VPORT_ACTIVE,
        H_VPORT_TABLE,
        "AcDbViewportTableRecord",
    );
    let centre = [(lo[0] + hi[0]) / 2.0, (lo[1] + hi[1]) / 2.0];
    let height = ((hi[1] - lo[1]).max(hi[0] - lo[0]) * 1.1).max(1.0);
    t.tag(2, "*Active").int(70, 0);
    t.point2(10, [0.0, 0.0])
        .point2(11, [1.0, 1.0])
        .point2(12, centre);
    t.point2(13, [0.0, 0.0])
        .point2(14, [1.0, 1.0])
        .point2(15, [1.0, 1.0]);
    // View direction (0, 0, 1), target (0, 0, 0).
    t.point3(16, [0.0, 0.0, 1.0]).point3(17, [0.0, 0.0, 0.0]);
    t.real(40, height)
        .real(41, 1.0)
        .real(42, 50.0)
        .real(43, 0.0)
        .real(44, 0.0);
    t.real(50, 0.0)
        .real(51, 0.0)
        .int(71, 0)
        .int(72, 1000)
        .int(73, 1)
        .int(74, 3);
    t.int(75, 0).int(76, 0).int(77, 0).int(78, 0);
    t.tag(0, "ENDTAB");

    table(t, "LTYPE", H_LTYPE_TABLE, 3);
    for (handle, name) in H_LTYPES {
        record(t, "LTYPE", handle, H_LTYPE_TABLE, "AcDbLinetypeTableRecord");
        t.tag(2, name).int(70, 0).tag(
            3,
            if name == "Continuous" {
                "Solid line"
            } else {
                ""
            },
        );
        t.int(72, 65).int(73, 0).real(40, 0.0);
    }
    t.tag(0, "ENDTAB");

    table(t, "LAYER", H_LAYER_TABLE, 1);
    record(t, "LAYER", H_LAYER_0, H_LAYER_TABLE, "AcDbLayerTableRecord");
    // 390: the plot style (AutoCAD requires the pointer).
    t.tag(2, "0").int(70, 0).int(62, 7).tag(6, "Continuous");
    t.int(370, -3).tag(390, H_PLOTSTYLE_NORMAL);
    t.tag(0, "ENDTAB");

    table(t, "STYLE", H_STYLE_TABLE, 1);
    record(
        t,
        "STYLE",
        H_STYLE_STANDARD,
        H_STYLE_TABLE,
        "AcDbTextStyleTableRecord",
    );
    t.tag(2, "Standard")
        .int(70, 0)
        .real(40, 0.0)
        .real(41, 1.0)
        .real(50, 0.0);
    t.int(71, 0).real(42, 2.5).tag(3, "txt").tag(4, "");
    t.tag(0, "ENDTAB");

    table(t, "VIEW", H_VIEW_TABLE, 0);
    t.tag(0, "ENDTAB");
    table(t, "UCS", H_UCS_TABLE, 0);
    t.tag(0, "ENDTAB");

    table(t, "APPID", H_APPID_TABLE, 1);
    record(
        t,
        "APPID",
        H_APPID_ACAD,
        H_APPID_TABLE,
        "AcDbRegAppTableRecord",
    );
    t.tag(2, "ACAD").int(70, 0);
    t.tag(0, "ENDTAB");

    table(t, "DIMSTYLE", H_DIMSTYLE_TABLE, 1);
    t.tag(100, "AcDbDimStyleTable");
    record(
        t,
        "DIMSTYLE",
        H_DIMSTYLE_STANDARD,
        H_DIMSTYLE_TABLE,
        "AcDbDimStyleTableRecord",
    );
    t.tag(2, "Standard").int(70, 0).tag(340, H_STYLE_STANDARD);
    t.tag(0, "ENDTAB");

    table(t, "BLOCK_RECORD", H_BLOCK_RECORD_TABLE, 2);
    for (handle, name) in [
        (H_MODEL_RECORD, "*Model_Space"),
        (H_PAPER_RECORD, "*Paper_Space"),
    ] {
        record(
            t,
            "BLOCK_RECORD",
            handle,
            H_BLOCK_RECORD_TABLE,
            "AcDbBlockTableRecord",
        );
        t.tag(2, name);
    }
    t.tag(0, "ENDTAB");

    t.end_section();
}

fn blocks(t: &mut Tags) {
    t.section("BLOCKS");
    for (owner, [begin, end], name, paper) in [
        (H_MODEL_RECORD, H_MODEL_BLOCK, "*Model_Space", false),
        (H_PAPER_RECORD, H_PAPER_BLOCK, "*Paper_Space", true),
    ] {
        t.tag(0, "BLOCK")
            .tag(5, begin)
            .tag(330, owner)
            .tag(100, "AcDbEntity");
        if paper {
            t.int(67, 1);
        }
        t.tag(8, "0")
            .tag(100, "AcDbBlockBegin")
            .tag(2, name)
            .int(70, 0);
        t.point(10, [0.0, 0.0]).tag(3, name).tag(1, "");
        t.tag(0, "ENDBLK")
            .tag(5, end)
            .tag(330, owner)
            .tag(100, "AcDbEntity");
        if paper {
            t.int(67, 1);
        }
        t.tag(8, "0").tag(100, "AcDbBlockEnd");
    }
    t.end_section();
}

fn spline_entity(t: &mut Tags, s: &DxfSpline) {
    t.tag(0, "SPLINE").tag(5, H_SPLINE).tag(330, H_MODEL_RECORD);
    t.tag(100, "AcDbEntity").tag(8, "0").tag(100, "AcDbSpline");
    // Normal of the plane (planar flag set).
    t.real(210, 0.0).real(220, 0.0).real(230, 1.0);
    t.int(70, i64::from(s.flags)).int(71, s.degree as i64);
    t.int(72, s.knots.len() as i64)
        .int(73, s.control_points.len() as i64)
        .int(74, 0);
    t.real(42, 1e-10).real(43, 1e-10);
    for &k in &s.knots {
        t.real(40, k);
    }
    for &p in &s.control_points {
        t.point(10, p);
    }
}

fn objects(t: &mut Tags) {
    t.section("OBJECTS");
    t.tag(0, "DICTIONARY").tag(5, H_ROOT_DICT).tag(330, "0");
    t.tag(100, "AcDbDictionary").int(281, 1);
    t.tag(3, "ACAD_GROUP").tag(350, H_GROUP_DICT);
    t.tag(3, "ACAD_PLOTSTYLENAME").tag(350, H_PLOTSTYLE_DICT);
    t.tag(0, "DICTIONARY")
        .tag(5, H_GROUP_DICT)
        .tag(330, H_ROOT_DICT);
    t.tag(100, "AcDbDictionary").int(281, 1);
    t.tag(0, "ACDBDICTIONARYWDFLT")
        .tag(5, H_PLOTSTYLE_DICT)
        .tag(330, H_ROOT_DICT);
    t.tag(100, "AcDbDictionary").int(281, 1);
    t.tag(3, "Normal").tag(350, H_PLOTSTYLE_NORMAL);
    t.tag(100, "AcDbDictionaryWithDefault")
        .tag(340, H_PLOTSTYLE_NORMAL);
    t.tag(0, "ACDBPLACEHOLDER")
        .tag(5, H_PLOTSTYLE_NORMAL)
        .tag(330, H_PLOTSTYLE_DICT);
    t.end_section();
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn handles_are_unique_and_below_the_seed() {
        let mut all = vec![
            H_BLOCK_RECORD_TABLE,
            H_LAYER_TABLE,
            H_STYLE_TABLE,
            H_LTYPE_TABLE,
            H_VIEW_TABLE,
            H_UCS_TABLE,
            H_VPORT_TABLE,
            H_APPID_TABLE,
            H_DIMSTYLE_TABLE,
            H_ROOT_DICT,
            H_GROUP_DICT,
            H_PLOTSTYLE_DICT,
            H_PLOTSTYLE_NORMAL,
            H_LAYER_0,
            H_STYLE_STANDARD,
            H_APPID_ACAD,
            H_DIMSTYLE_STANDARD,
            H_MODEL_RECORD,
            H_PAPER_RECORD,
            H_VPORT_ACTIVE,
            H_SPLINE,
        ];
        all.extend(H_LTYPES.iter().map(|h| h.0));
        all.extend(H_MODEL_BLOCK);
        all.extend(H_PAPER_BLOCK);
        let mut v: Vec<u32> = all
            .iter()
            .map(|h| u32::from_str_radix(h, 16).unwrap())
            .collect();
        v.sort_unstable();
        let n = v.len();
        v.dedup();
        assert_eq!(v.len(), n, "duplicate handle");
        assert!(*v.last().unwrap() < u32::from_str_radix(HANDSEED, 16).unwrap());
    }
}
