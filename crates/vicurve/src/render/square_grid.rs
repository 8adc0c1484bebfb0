//! A printed square grid after forming, with its truth: bright square cells
//! separated by dark lines, every point of the grid moved by a known smooth
//! deformation `x = phi(X)`, painted by exact coverage (each cell's
//! deformed outline a dense polygon, 32 vertices per side), then blurred,
//! noised and quantised as [`super::scene`]'s scenes.
//!
//! The field, about the grid's middle `X0` with `xi = (X - X0) / L` (`L`
//! half the grid's larger side): `phi(X) = X0 + F0 (X - X0) + L (0.04
//! xi_x^2, 0.03 xi_x xi_y)`, `F0` a stretch of 1.12 along `+x` and 0.94
//! along `+y` turned by 0.15 rad. Its gradient `F(X)` varies linearly
//! across the grid, so central differences of the cells' centres give it
//! exactly; the truth gives, per cell, `F` at the reference centre and its
//! principal strains, and the exact centroid of the painted cell.

use super::scene::{paint, Rendering};
use crate::error::{Error, Result};
use crate::image::Image;
use crate::objects::square_grid::principal_strains;
use serde::{Deserialize, Serialize};

/// Largest stretch of the field over the grid (to size the image).
const MAX_STRETCH: f64 = 1.25;
/// Vertices per side of a painted cell: a side bends by less than 0.02 px
/// under the field, and by under 1e-5 px between two vertices.
const VERTICES_PER_SIDE: usize = 32;

/// One cell of the grid and its truth.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub struct CellTruth {
    /// Lattice index `[column, row]`, from 0.
    pub index: [i64; 2],
    /// Centre before deformation, px.
    pub reference: [f64; 2],
    /// Exact centroid of the painted (deformed) cell, px.
    pub centroid: [f64; 2],
    /// The field's gradient at `reference` (row-major, `dx_r / dX_c`).
    pub gradient: [[f64; 2]; 2],
    /// Its principal true strains and the major direction `[eps1, eps2,
    /// angle]` (rad, counterclockwise on screen from `+x`).
    pub strain: [f64; 3],
}

/// A deformed square grid: its layout, rendering and cells. It is its own
/// truth file.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub struct SquareGrid {
    /// Image width, px.
    pub width: usize,
    /// Image height, px.
    pub height: usize,
    /// Cell rows.
    pub rows: usize,
    /// Cell columns.
    pub cols: usize,
    /// Pitch before deformation, px (cell side plus line width).
    pub pitch: f64,
    /// Width of the printed lines before deformation, px.
    pub line_width: f64,
    /// Whether the field deforms the grid (else it is the printed grid).
    pub strained: bool,
    /// Levels (`foreground` the cells', `background` the lines'), blur,
    /// noise, quantisation.
    #[serde(flatten)]
    pub rendering: Rendering,
    /// The cells, row after row.
    pub cells: Vec<CellTruth>,
}

/// A `rows x cols` grid of square cells separated by lines `line_width` px
/// wide in a `width x height` image: the largest pitch that keeps the
/// deformed grid a pitch from the border, the grid centred (off the pixel
/// grid), deformed by the module's field when `strained`. Rendering
/// [`Rendering::standard`] (0.8 cells on 0.2, blur 1 px, noise 1 %, 8 bits).
///
/// Errors: [`Error::InvalidParameter`] for no cell, a line width that is
/// not positive, or cells that would come out under 8 px across.
pub fn square_grid(
    width: usize,
    height: usize,
    rows: usize,
    cols: usize,
    line_width: f64,
    strained: bool,
    seed: u64,
) -> Result<SquareGrid> {
    let stretch = if strained { MAX_STRETCH } else { 1.0 };
    let pitch = (width as f64 / (cols as f64 * stretch + 2.0))
        .min(height as f64 / (rows as f64 * stretch + 2.0));
    if rows == 0 || cols == 0 || !(line_width.is_finite() && line_width > 0.0) {
        return Err(Error::invalid(
            "grid",
            format!("{rows}x{cols} cells, lines {line_width} px: give at least one cell and a positive line width"),
        ));
    }
    if pitch - line_width < 8.0 {
        return Err(Error::invalid(
            "size",
            format!(
                "a {rows}x{cols} grid in {width}x{height} px has a pitch of {pitch:.1} px: cells of {:.1} px between lines of {line_width} px; at least 8 px needed (a larger image, fewer cells or thinner lines)",
                pitch - line_width
            ),
        ));
    }
    let mut grid = SquareGrid {
        width,
        height,
        rows,
        cols,
        pitch,
        line_width,
        strained,
        rendering: Rendering::standard(seed),
        cells: Vec::new(),
    };
    for i in 0..rows {
        for j in 0..cols {
            let reference = grid.reference_centre(i, j);
            let ring = grid.cell_ring(i, j);
            let f = grid.gradient(reference);
            let e = principal_strains(f);
            grid.cells.push(CellTruth {
                index: [j as i64, i as i64],
                reference,
                centroid: polygon_centroid(&ring),
                gradient: f,
                strain: [e[0], e[1], e[3]],
            });
        }
    }
    Ok(grid)
}

impl SquareGrid {
    /// The grid's middle `X0` (off the pixel grid) and the field's length
    /// scale `L`, px.
    fn frame(&self) -> ([f64; 2], f64) {
        let mid = [
            0.5 * self.width as f64 + 0.31,
            0.5 * self.height as f64 - 0.17,
        ];
        (mid, 0.5 * self.pitch * self.rows.max(self.cols) as f64)
    }

    /// Centre of cell (row `i`, column `j`) before deformation.
    fn reference_centre(&self, i: usize, j: usize) -> [f64; 2] {
        let (mid, _) = self.frame();
        [
            mid[0] + (j as f64 - 0.5 * (self.cols as f64 - 1.0)) * self.pitch,
            mid[1] + (i as f64 - 0.5 * (self.rows as f64 - 1.0)) * self.pitch,
        ]
    }

    /// `F0`: the stretch turned (identity when not strained).
    fn f0(&self) -> [[f64; 2]; 2] {
        if !self.strained {
            return [[1.0, 0.0], [0.0, 1.0]];
        }
        let (c, s) = (0.15f64.cos(), 0.15f64.sin());
        [[c * 1.12, -s * 0.94], [s * 1.12, c * 0.94]]
    }

    /// The deformed position of `x`.
    pub fn deform(&self, x: [f64; 2]) -> [f64; 2] {
        let (mid, l) = self.frame();
        let d = [x[0] - mid[0], x[1] - mid[1]];
        let f = self.f0();
        let mut p = [
            mid[0] + f[0][0] * d[0] + f[0][1] * d[1],
            mid[1] + f[1][0] * d[0] + f[1][1] * d[1],
        ];
        if self.strained {
            let xi = [d[0] / l, d[1] / l];
            p[0] += l * 0.04 * xi[0] * xi[0];
            p[1] += l * 0.03 * xi[0] * xi[1];
        }
        p
    }

    /// The field's gradient at `x` (row-major).
    pub fn gradient(&self, x: [f64; 2]) -> [[f64; 2]; 2] {
        let (mid, l) = self.frame();
        let mut f = self.f0();
        if self.strained {
            let xi = [(x[0] - mid[0]) / l, (x[1] - mid[1]) / l];
            f[0][0] += 0.08 * xi[0];
            f[1][0] += 0.03 * xi[1];
            f[1][1] += 0.03 * xi[0];
        }
        f
    }

    /// The deformed outline of cell (row `i`, column `j`), counterclockwise
    /// on screen.
    fn cell_ring(&self, i: usize, j: usize) -> Vec<[f64; 2]> {
        let c = self.reference_centre(i, j);
        let h = 0.5 * (self.pitch - self.line_width);
        // Top right, top left, bottom left, bottom right (y down).
        let corners = [[h, -h], [-h, -h], [-h, h], [h, h]];
        let mut ring = Vec::with_capacity(4 * VERTICES_PER_SIDE);
        for k in 0..4 {
            let (a, b) = (corners[k], corners[(k + 1) % 4]);
            for t in 0..VERTICES_PER_SIDE {
                let t = t as f64 / VERTICES_PER_SIDE as f64;
                let x = [
                    c[0] + a[0] + t * (b[0] - a[0]),
                    c[1] + a[1] + t * (b[1] - a[1]),
                ];
                ring.push(self.deform(x));
            }
        }
        ring
    }

    /// Render the grid (module docs). Errors: those of the coverage and
    /// the blur (a zero-sized image).
    pub fn render(&self) -> Result<Image> {
        let rings: Vec<Vec<[f64; 2]>> = (0..self.rows)
            .flat_map(|i| (0..self.cols).map(move |j| (i, j)))
            .map(|(i, j)| self.cell_ring(i, j))
            .collect();
        paint(&rings, (self.width, self.height), &self.rendering)
    }
}

/// Centroid of a simple polygon (shoelace), px.
fn polygon_centroid(ring: &[[f64; 2]]) -> [f64; 2] {
    // About the first vertex, against cancellation.
    let o = ring[0];
    let rel = |p: [f64; 2]| [p[0] - o[0], p[1] - o[1]];
    let (mut a, mut cx, mut cy) = (0.0, 0.0, 0.0);
    for k in 0..ring.len() {
        let (p, q) = (rel(ring[k]), rel(ring[(k + 1) % ring.len()]));
        let cross = p[0] * q[1] - q[0] * p[1];
        a += cross;
        cx += (p[0] + q[0]) * cross;
        cy += (p[1] + q[1]) * cross;
    }
    [o[0] + cx / (3.0 * a), o[1] + cy / (3.0 * a)]
}
