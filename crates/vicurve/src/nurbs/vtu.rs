//! VTK XML unstructured grids (`.vtu`, ASCII) of a patch, for ParaView.
//!
//! [`patch_vtu`] samples the surface: every element (non-empty knot span
//! pair) is split into `nx x ny` quadrilateral cells (VTK_QUAD, type 9)
//! whose corners are points of the surface, so the element borders are cell
//! borders. Point data `parameter` holds `(u, v)`; cell data `element` holds
//! the element's span indices along and across (colour by it to see the
//! mesh after h-refinement). [`control_net_vtu`] writes the control net as
//! quads with point data `weight`.
//!
//! Coordinates are pixels as everywhere in vicurve: `x` = column, `y` =
//! row (pointing *down* the image), `z = 0`. ParaView draws `y` up, so the
//! patch appears mirrored top to bottom compared with the image (a camera
//! with view-up `(0, -1, 0)` shows it as in the image). The file says so in
//! an XML comment.
//!
//! Format: VTKFile `type="UnstructuredGrid"` version 0.1, one `Piece` with
//! `Points` (Float64, 3 components), `Cells` (`connectivity` and `offsets`
//! Int64, `types` UInt8), `PointData` and `CellData`; every `DataArray` is
//! `format="ascii"` (VTK's documented XML file format).

use super::patch::NurbsPatch;
use crate::error::{Error, Result};
use std::fmt::Write;

/// VTK's cell type number for a linear quadrilateral.
pub const VTK_QUAD: u8 = 9;

/// Largest number of cells written: a few hundred megabytes of text.
pub const MAX_CELLS: usize = 4_000_000;

/// The patch sampled into `cells.0 x cells.1` quads per element (along,
/// across); `comment` (one line, e.g. the sources) goes into an XML
/// comment with the coordinate convention.
///
/// Errors: [`Error::InvalidParameter`] for a zero count or more than
/// [`MAX_CELLS`] cells.
pub fn patch_vtu(patch: &NurbsPatch, cells: (usize, usize), comment: &str) -> Result<String> {
    let (nx, ny) = cells;
    if nx == 0 || ny == 0 {
        return Err(Error::invalid(
            "cells per element",
            format!("{nx}x{ny} (need at least 1x1)"),
        ));
    }
    let (ku, kv) = patch.knots();
    let (p, q) = patch.degrees();
    let (n_u, n_v) = patch.size();
    let (us, eu) = samples(&ku[p..=n_u], nx);
    let (vs, ev) = samples(&kv[q..=n_v], ny);
    let (mu, mv) = (us.len(), vs.len());
    let n_cells = (mu - 1) * (mv - 1);
    if n_cells > MAX_CELLS {
        return Err(Error::invalid(
            "cells per element",
            format!("{nx}x{ny} gives {n_cells} cells (at most {MAX_CELLS})"),
        ));
    }
    // Point (i, j) has index j * mu + i: rows of constant v.
    let mut points = Vec::with_capacity(mu * mv);
    let mut params = Vec::with_capacity(mu * mv);
    for &v in &vs {
        for &u in &us {
            points.push(patch.point(u, v));
            params.push([u, v]);
        }
    }
    let mut quads = Vec::with_capacity(n_cells);
    let mut element = Vec::with_capacity(n_cells);
    // One interval per cell: eu has mu - 1 entries, ev mv - 1.
    for (j, &e_v) in ev.iter().enumerate() {
        for (i, &e_u) in eu.iter().enumerate() {
            let c = j * mu + i;
            quads.push([c, c + 1, c + 1 + mu, c + mu]);
            element.push([e_u, e_v]);
        }
    }
    let mut point_data = String::new();
    data_array(
        &mut point_data,
        "Float64",
        "parameter",
        2,
        params.iter().flatten(),
    );
    let mut cell_data = String::new();
    data_array(
        &mut cell_data,
        "Int32",
        "element",
        2,
        element.iter().flatten(),
    );
    Ok(document(
        comment,
        &points,
        &quads,
        ("parameter", &point_data),
        ("element", &cell_data),
    ))
}

/// The control net as quads (`(n_u - 1) x (n_v - 1)` cells between
/// neighbouring control points) with point data `weight`.
pub fn control_net_vtu(patch: &NurbsPatch, comment: &str) -> String {
    let data = patch.to_data();
    let (n_u, n_v) = patch.size();
    // Point (i, j) has index j * n_u + i, as in `patch_vtu`.
    let mut points = Vec::with_capacity(n_u * n_v);
    let mut weights = Vec::with_capacity(n_u * n_v);
    for j in 0..n_v {
        for i in 0..n_u {
            points.push(data.control_points[i][j]);
            weights.push(data.weights[i][j]);
        }
    }
    let mut quads = Vec::new();
    for j in 0..n_v.saturating_sub(1) {
        for i in 0..n_u.saturating_sub(1) {
            let c = j * n_u + i;
            quads.push([c, c + 1, c + 1 + n_u, c + n_u]);
        }
    }
    let mut point_data = String::new();
    data_array(&mut point_data, "Float64", "weight", 1, weights.iter());
    document(comment, &points, &quads, ("weight", &point_data), ("", ""))
}

/// Parameters splitting each non-empty span of `knots` into `parts`, with
/// the span index of each interval: `(params, span_of_interval)`.
fn samples(knots: &[f64], parts: usize) -> (Vec<f64>, Vec<usize>) {
    let mut params = Vec::new();
    let mut spans = Vec::new();
    let mut e = 0;
    for w in knots.windows(2) {
        let (a, b) = (w[0], w[1]);
        if b > a {
            for k in 0..parts {
                params.push(a + (b - a) * k as f64 / parts as f64);
                spans.push(e);
            }
            e += 1;
        }
    }
    params.push(*knots.last().unwrap_or(&1.0));
    (params, spans)
}

/// One `<DataArray>` with its values, 6 per line.
fn data_array<'a, T: std::fmt::Display + 'a>(
    out: &mut String,
    ty: &str,
    name: &str,
    components: usize,
    values: impl Iterator<Item = &'a T>,
) {
    let _ = writeln!(
        out,
        r#"        <DataArray type="{ty}" Name="{name}" NumberOfComponents="{components}" format="ascii">"#
    );
    write_values(out, values);
    let _ = writeln!(out, "        </DataArray>");
}

fn write_values<'a, T: std::fmt::Display + 'a>(
    out: &mut String,
    values: impl Iterator<Item = &'a T>,
) {
    for (k, v) in values.enumerate() {
        if k % 6 == 0 {
            if k > 0 {
                out.push('\n');
            }
            out.push_str("          ");
        } else {
            out.push(' ');
        }
        let _ = write!(out, "{v}");
    }
    out.push('\n');
}

/// The whole file: points, quads, one point-data and one cell-data block
/// (each `(name of the active array, its DataArray text)`; empty text for
/// none).
fn document(
    comment: &str,
    points: &[[f64; 2]],
    quads: &[[usize; 4]],
    point_data: (&str, &str),
    cell_data: (&str, &str),
) -> String {
    let mut s = String::new();
    let _ = writeln!(s, r#"<?xml version="1.0"?>"#);
    let _ = writeln!(
        s,
        r#"<VTKFile type="UnstructuredGrid" version="0.1" byte_order="LittleEndian">"#
    );
    let _ = writeln!(
        s,
        "  <!-- vicurve {}: {}; coordinates in pixels, x = column, y = row (the image's y axis points down; ParaView draws it up), z = 0 -->",
        env!("CARGO_PKG_VERSION"),
        comment.replace("--", "- -").replace('\n', " ")
    );
    let _ = writeln!(s, "  <UnstructuredGrid>");
    let _ = writeln!(
        s,
        r#"    <Piece NumberOfPoints="{}" NumberOfCells="{}">"#,
        points.len(),
        quads.len()
    );
    let _ = writeln!(s, r#"      <PointData Scalars="{}">"#, point_data.0);
    s.push_str(point_data.1);
    let _ = writeln!(s, "      </PointData>");
    if cell_data.1.is_empty() {
        let _ = writeln!(s, "      <CellData>");
    } else {
        let _ = writeln!(s, r#"      <CellData Scalars="{}">"#, cell_data.0);
    }
    s.push_str(cell_data.1);
    let _ = writeln!(s, "      </CellData>");
    let _ = writeln!(s, "      <Points>");
    let xyz: Vec<f64> = points.iter().flat_map(|p| [p[0], p[1], 0.0]).collect();
    data_array(&mut s, "Float64", "Points", 3, xyz.iter());
    let _ = writeln!(s, "      </Points>");
    let _ = writeln!(s, "      <Cells>");
    let conn: Vec<usize> = quads.iter().flatten().copied().collect();
    let offsets: Vec<usize> = (1..=quads.len()).map(|c| 4 * c).collect();
    let types = vec![VTK_QUAD; quads.len()];
    cells_array(&mut s, "Int64", "connectivity", conn.iter());
    cells_array(&mut s, "Int64", "offsets", offsets.iter());
    cells_array(&mut s, "UInt8", "types", types.iter());
    let _ = writeln!(s, "      </Cells>");
    let _ = writeln!(s, "    </Piece>");
    let _ = writeln!(s, "  </UnstructuredGrid>");
    let _ = writeln!(s, "</VTKFile>");
    s
}

/// A `<Cells>` array (no component count: VTK's own writer omits it).
fn cells_array<'a, T: std::fmt::Display + 'a>(
    out: &mut String,
    ty: &str,
    name: &str,
    values: impl Iterator<Item = &'a T>,
) {
    let _ = writeln!(
        out,
        r#"        <DataArray type="{ty}" Name="{name}" format="ascii">"#
    );
    write_values(out, values);
    let _ = writeln!(out, "        </DataArray>");
}
