//! The regular quadrangle mesh over the band, and the exact curvilinear
//! data of its nodes.
//!
//! Nodes sit on the grid `(i h, j h)` (pixels; `i`, `j` integers, `h` the
//! mesh size), so that with an integer `h` they are pixel centres and the
//! element edges run along pixel rows and columns. Every grid node near the
//! curve is projected exactly onto it ([`SplineCurve::project`], started from
//! the closest chord of a polyline of the curve, as the band does). A cell
//! of the grid becomes a (square, bilinear) element when each of its four
//! corners is within `R + h sqrt(2)` of the curve (`R` the band half-width):
//! any point at a distance under `R` is then inside an element, since a
//! corner is at most one diagonal from it. Corners beyond (or at 0.9 times)
//! their radius of curvature on the concave side, where the closest point
//! jumps, are not used; nor are cells outside the image's pixel-centre hull
//! `[0, width - 1] x [0, height - 1]`. Of the remaining elements, only those
//! connected to the element around the curve's start are kept (one
//! least-squares problem, one gauge).
//!
//! # Past the ends of an open curve
//! A node whose closest point is an end of an open curve is given the
//! coordinates of the curve's tangent extension: `r` is its offset along the
//! end's normal and its foot parameter is the end's plus its offset along the
//! tangent (divided by the speed `|C'|`, so that it continues the parameter).
//! Both are continuous across the end's normal line, which keeps the
//! interpolation smooth in the elements that straddle it; its distance to
//! the curve (to the end point) decides whether it is used.

use crate::band::MIN_JACOBIAN;
use crate::curve::SplineCurve;
use crate::error::{Error, Result};
use rayon::prelude::*;

/// Tolerance on grid coordinates (in cells) for points on an edge: `x / h`
/// rounds, so a pixel on a node line may land a hair off it.
const EDGE: f64 = 1e-9;

/// Marks an absent node, element or degree of freedom in index tables.
pub(crate) const NONE: u32 = u32::MAX;

/// The exact curvilinear data of a mesh node.
#[derive(Clone, Copy, Debug)]
pub(crate) struct MeshNode {
    /// Position `[x, y]`, pixels.
    pub pos: [f64; 2],
    /// Curve parameter of the closest point, pixels; past an end of an open
    /// curve, the tangent extension's (see the module docs).
    pub foot: f64,
    /// Signed distance along the normal (positive on the normal's side),
    /// pixels.
    pub r: f64,
    /// Signed curvature at the foot, 1/pixels (0 past the ends).
    pub curvature: f64,
    /// Speed `|C'(u)|` of the parametrisation at the foot (about 1).
    pub speed: f64,
}

/// The mesh: geometry, nodes, elements and the cell lookup table.
#[derive(Clone, Debug)]
pub(crate) struct Mesh {
    /// Element side, pixels.
    pub h: f64,
    /// `1 / h`.
    inv_h: f64,
    /// Grid indices `(i, j)` of the lower-left corner of cell `(0, 0)`.
    base: [i64; 2],
    /// Cells per row and per column of the lookup table.
    cols: usize,
    rows: usize,
    /// The nodes used by at least one element.
    pub nodes: Vec<MeshNode>,
    /// Corner nodes of each element, in the order `(0, 0), (1, 0), (1, 1),
    /// (0, 1)` of its local coordinates `(xi, eta)` (`x` then `y`).
    pub elements: Vec<[u32; 4]>,
    /// Lower-left corner `[x, y]` of each element, pixels.
    pub origins: Vec<[f64; 2]>,
    /// Element of each cell of the table, or [`NONE`].
    cell_element: Vec<u32>,
}

/// The closest chord of a polyline of the curve, per grid node.
struct ChordSearch {
    d2: f64,
    u: f64,
}

impl Mesh {
    /// The mesh of side `h` over the band of half-width `half_width` around
    /// `curve`, clipped to an image of `width x height` pixels. Parameters
    /// are checked by the caller.
    pub(crate) fn build(
        curve: &SplineCurve,
        half_width: f64,
        h: f64,
        width: usize,
        height: usize,
    ) -> Result<Mesh> {
        let keep = half_width + h * std::f64::consts::SQRT_2;
        // Chords short enough that the closest one leads Newton to the global
        // closest point (as in the band); the search reaches a little farther
        // than `keep` to allow for the polyline's sagitta.
        let step = (0.5 * half_width).clamp(0.5, 4.0);
        let search = keep + step + 1.0;
        let grid = NodeGrid::around(curve, search, h, width, height)?;
        let best = grid.closest_chords(curve, step, search);
        let nodes = grid.project_nodes(curve, &best, search, keep);
        let candidate = grid.candidate_cells(&nodes);
        let (parent, root) = grid.start_component(curve, &candidate, width, height)?;
        Ok(grid.into_mesh(&nodes, &candidate, parent, root))
    }

    /// The element containing `(x, y)` (pixels) and the local coordinates
    /// `(xi, eta)` in `[0, 1]` of the point in it. A point on an edge or a
    /// corner shared by several cells belongs to any of their elements
    /// (the interpolation is continuous there). `None` outside the mesh.
    #[inline]
    pub(crate) fn locate(&self, x: f64, y: f64) -> Option<(usize, f64, f64)> {
        let gx = x * self.inv_h - self.base[0] as f64;
        let gy = y * self.inv_h - self.base[1] as f64;
        if !(gx >= -EDGE
            && gy >= -EDGE
            && gx <= self.cols as f64 + EDGE
            && gy <= self.rows as f64 + EDGE)
        {
            return None;
        }
        let (gx, gy) = (gx.max(0.0), gy.max(0.0));
        // Non-negative: truncation is the floor.
        let ci = (gx as usize).min(self.cols - 1);
        let cj = (gy as usize).min(self.rows - 1);
        let e = self.cell_element[cj * self.cols + ci];
        if e != NONE {
            return Some((e as usize, gx - ci as f64, gy - cj as f64));
        }
        // On an edge or a corner of an absent cell: a neighbour may hold it.
        for c in cells_around(gx, gy, self.cols, self.rows)
            .into_iter()
            .flatten()
        {
            let e = self.cell_element[c];
            if e != NONE {
                let (ci, cj) = ((c % self.cols) as f64, (c / self.cols) as f64);
                let xi = (gx - ci).clamp(0.0, 1.0);
                let eta = (gy - cj).clamp(0.0, 1.0);
                return Some((e as usize, xi, eta));
            }
        }
        None
    }

    /// The intervals `[x0, x1]` (pixels, increasing, disjoint) where the
    /// horizontal line at `y` lies in the meshed domain, into `spans`
    /// (cleared first).
    pub(crate) fn row_spans(&self, y: f64, spans: &mut Vec<[f64; 2]>) {
        spans.clear();
        let gy = y * self.inv_h - self.base[1] as f64;
        if !(gy >= -EDGE && gy <= self.rows as f64 + EDGE) {
            return;
        }
        let gy = gy.max(0.0);
        let cj = (gy as usize).min(self.rows - 1);
        // Near a row of nodes the line also borders the cells on its other
        // side.
        let f = gy - cj as f64;
        let other = other(cj, f, self.rows);
        let present = |ci: usize| {
            self.cell_element[cj * self.cols + ci] != NONE
                || other.is_some_and(|o| self.cell_element[o * self.cols + ci] != NONE)
        };
        let x_of = |ci: usize| (self.base[0] + ci as i64) as f64 * self.h;
        let mut start = None;
        for ci in 0..=self.cols {
            let here = ci < self.cols && present(ci);
            match (here, start) {
                (true, None) => start = Some(ci),
                (false, Some(s)) => {
                    spans.push([x_of(s), x_of(ci)]);
                    start = None;
                }
                _ => {}
            }
        }
    }

    /// Point of element `e` at local coordinates `(xi, eta)`, pixels.
    #[inline]
    pub(crate) fn point(&self, e: usize, xi: f64, eta: f64) -> [f64; 2] {
        let o = self.origins[e];
        [o[0] + xi * self.h, o[1] + eta * self.h]
    }

    /// The bounding box `[xmin, ymin, xmax, ymax]` of the meshed domain,
    /// pixels.
    pub(crate) fn bounds(&self) -> [f64; 4] {
        self.origins.iter().fold(
            [
                f64::INFINITY,
                f64::INFINITY,
                f64::NEG_INFINITY,
                f64::NEG_INFINITY,
            ],
            |b, o| {
                [
                    b[0].min(o[0]),
                    b[1].min(o[1]),
                    b[2].max(o[0] + self.h),
                    b[3].max(o[1] + self.h),
                ]
            },
        )
    }
}

/// The grid the mesh's nodes sit on: nodes `(i h, j h)` for `i` in
/// `i_lo..=i_hi`, `j` in `j_lo..=j_hi` (`ni x nj` of them, numbered row
/// after row from the lower corner), cells between them (`cols x rows`).
struct NodeGrid {
    h: f64,
    i_lo: i64,
    j_lo: i64,
    i_hi: i64,
    j_hi: i64,
    cols: usize,
    rows: usize,
    ni: usize,
}

impl NodeGrid {
    /// The grid over the points within `search` (pixels) of the curve's
    /// control-polygon box, clipped to an image of `width x height`.
    ///
    /// Errors: [`Error::CurveOutsideImage`] when no cell is left.
    fn around(
        curve: &SplineCurve,
        search: f64,
        h: f64,
        width: usize,
        height: usize,
    ) -> Result<NodeGrid> {
        let bb = curve.bounding_box();
        let x_max = width as f64 - 1.0;
        let y_max = height as f64 - 1.0;
        let i_lo = ((bb[0] - search) / h).floor().max(0.0) as i64;
        let j_lo = ((bb[1] - search) / h).floor().max(0.0) as i64;
        let i_hi = ((bb[2] + search) / h).ceil().min((x_max / h).ceil()) as i64;
        let j_hi = ((bb[3] + search) / h).ceil().min((y_max / h).ceil()) as i64;
        if i_hi <= i_lo || j_hi <= j_lo {
            let p = curve.point(0.0);
            return Err(Error::CurveOutsideImage {
                x: p[0],
                y: p[1],
                width,
                height,
            });
        }
        let cols = (i_hi - i_lo) as usize;
        let rows = (j_hi - j_lo) as usize;
        Ok(NodeGrid {
            h,
            i_lo,
            j_lo,
            i_hi,
            j_hi,
            cols,
            rows,
            ni: cols + 1,
        })
    }

    /// Number of grid nodes.
    fn nodes(&self) -> usize {
        self.ni * (self.rows + 1)
    }

    /// Position of grid node `g`, pixels.
    fn node_pos(&self, g: usize) -> [f64; 2] {
        let (i, j) = (g % self.ni, g / self.ni);
        [
            (self.i_lo + i as i64) as f64 * self.h,
            (self.j_lo + j as i64) as f64 * self.h,
        ]
    }

    /// The grid nodes at the corners of cell `c`, in the elements' order.
    fn corner_ids(&self, c: usize) -> [usize; 4] {
        let (ci, cj) = (c % self.cols, c / self.cols);
        let g = cj * self.ni + ci;
        [g, g + 1, g + self.ni + 1, g + self.ni]
    }

    /// The closest chord of each grid node, of a polyline of `curve` with
    /// chords about `step` pixels long, among those within `search` pixels
    /// of it (infinitely far when none is).
    fn closest_chords(&self, curve: &SplineCurve, step: f64, search: f64) -> Vec<ChordSearch> {
        let (h, l) = (self.h, curve.param_length());
        let count = ((l / step).ceil() as usize).max(4);
        let closed = curve.is_closed();
        let params = curve.sample_params(if closed { count } else { count + 1 });
        let verts: Vec<[f64; 2]> = params.iter().map(|&u| curve.point(u)).collect();
        let nseg = if closed { verts.len() } else { verts.len() - 1 };
        let mut best: Vec<ChordSearch> = (0..self.nodes())
            .map(|_| ChordSearch {
                d2: f64::INFINITY,
                u: 0.0,
            })
            .collect();
        for k in 0..nseg {
            let a = verts[k];
            let b = verts[(k + 1) % verts.len()];
            let (ua, ub) = (
                params[k],
                if k + 1 < params.len() {
                    params[k + 1]
                } else {
                    l
                },
            );
            let d = [b[0] - a[0], b[1] - a[1]];
            let dd = (d[0] * d[0] + d[1] * d[1]).max(1e-300);
            let gi0 = (((a[0].min(b[0]) - search) / h).floor() as i64).max(self.i_lo);
            let gi1 = (((a[0].max(b[0]) + search) / h).ceil() as i64).min(self.i_hi);
            let gj0 = (((a[1].min(b[1]) - search) / h).floor() as i64).max(self.j_lo);
            let gj1 = (((a[1].max(b[1]) + search) / h).ceil() as i64).min(self.j_hi);
            for gj in gj0..=gj1 {
                for gi in gi0..=gi1 {
                    let g = (gj - self.j_lo) as usize * self.ni + (gi - self.i_lo) as usize;
                    let p = self.node_pos(g);
                    let (px, py) = (p[0] - a[0], p[1] - a[1]);
                    let t = ((px * d[0] + py * d[1]) / dd).clamp(0.0, 1.0);
                    let (ex, ey) = (px - t * d[0], py - t * d[1]);
                    let d2 = ex * ex + ey * ey;
                    if d2 < best[g].d2 {
                        best[g] = ChordSearch {
                            d2,
                            u: ua + t * (ub - ua),
                        };
                    }
                }
            }
        }
        best
    }

    /// The exact data of the grid nodes whose closest chord `best` is
    /// within `search` pixels; `None` for the nodes no element may use
    /// (farther than `keep` from the curve, see [`node_data`]).
    fn project_nodes(
        &self,
        curve: &SplineCurve,
        best: &[ChordSearch],
        search: f64,
        keep: f64,
    ) -> Vec<Option<MeshNode>> {
        let search2 = search * search;
        best.par_iter()
            .enumerate()
            .map(|(g, b)| {
                if b.d2 > search2 {
                    return None;
                }
                node_data(curve, self.node_pos(g), b.u, keep)
            })
            .collect()
    }

    /// The cells whose four corners are usable (`Some` in `grid`).
    fn candidate_cells(&self, grid: &[Option<MeshNode>]) -> Vec<bool> {
        (0..self.cols * self.rows)
            .map(|c| self.corner_ids(c).iter().all(|&g| grid[g].is_some()))
            .collect()
    }

    /// The components (through shared corners) of the `candidate` cells,
    /// as a union-find forest over the grid nodes, and the root of the one
    /// around the curve's start.
    ///
    /// Errors: [`Error::CurveOutsideImage`] when the start is outside the
    /// image, [`Error::InvalidParameter`] when no candidate cell holds it.
    fn start_component(
        &self,
        curve: &SplineCurve,
        candidate: &[bool],
        width: usize,
        height: usize,
    ) -> Result<(Vec<usize>, usize)> {
        let start = curve.point(0.0);
        let mut parent: Vec<usize> = (0..self.nodes()).collect();
        for c in (0..self.cols * self.rows).filter(|&c| candidate[c]) {
            let ids = self.corner_ids(c);
            for &g in &ids[1..] {
                union(&mut parent, ids[0], g);
            }
        }
        let gx = start[0] / self.h - self.i_lo as f64;
        let gy = start[1] / self.h - self.j_lo as f64;
        let start_cell = cells_around(gx, gy, self.cols, self.rows)
            .into_iter()
            .flatten()
            .find(|&c| candidate[c]);
        let Some(start_cell) = start_cell else {
            let (x_max, y_max) = (width as f64 - 1.0, height as f64 - 1.0);
            if !(start[0] >= 0.0 && start[1] >= 0.0 && start[0] <= x_max && start[1] <= y_max) {
                return Err(Error::CurveOutsideImage {
                    x: start[0],
                    y: start[1],
                    width,
                    height,
                });
            }
            return Err(Error::invalid(
                "levelset mesh",
                "no element around the start of the curve (is the curve inside the image?)",
            ));
        };
        let root = find(&mut parent, self.corner_ids(start_cell)[0]);
        Ok((parent, root))
    }

    /// The mesh of the `candidate` cells in the component `root` of
    /// `parent`, with the used nodes of `grid` numbered in the order the
    /// cells (row after row) first use them.
    fn into_mesh(
        self,
        grid: &[Option<MeshNode>],
        candidate: &[bool],
        mut parent: Vec<usize>,
        root: usize,
    ) -> Mesh {
        let mut node_index = vec![NONE; self.nodes()];
        let mut nodes = Vec::new();
        let mut elements = Vec::new();
        let mut origins = Vec::new();
        let mut cell_element = vec![NONE; self.cols * self.rows];
        for c in 0..self.cols * self.rows {
            if !candidate[c] || find(&mut parent, self.corner_ids(c)[0]) != root {
                continue;
            }
            let mut corners = [0u32; 4];
            for (k, &g) in self.corner_ids(c).iter().enumerate() {
                if node_index[g] == NONE {
                    node_index[g] = nodes.len() as u32;
                    // Candidate corners are usable: `grid[g]` is `Some`.
                    nodes.extend(grid[g]);
                }
                corners[k] = node_index[g];
            }
            cell_element[c] = elements.len() as u32;
            elements.push(corners);
            origins.push(self.node_pos(self.corner_ids(c)[0]));
        }
        Mesh {
            h: self.h,
            inv_h: 1.0 / self.h,
            base: [self.i_lo, self.j_lo],
            cols: self.cols,
            rows: self.rows,
            nodes,
            elements,
            origins,
            cell_element,
        }
    }
}

/// The exact data of the grid node at `pos`, whose closest chord has its
/// foot at parameter `u0`; `None` when the node is farther than `keep` from
/// the curve or too near its centre of curvature.
fn node_data(curve: &SplineCurve, pos: [f64; 2], u0: f64, keep: f64) -> Option<MeshNode> {
    let l = curve.param_length();
    let pr = curve.project(pos[0], pos[1], u0);
    if pr.at_end {
        let end = if pr.u <= 0.5 * l { 0.0 } else { l };
        let f = curve.frame(end);
        let (dx, dy) = (pos[0] - f.point[0], pos[1] - f.point[1]);
        let along = dx * f.tangent[0] + dy * f.tangent[1];
        let r = dx * f.normal[0] + dy * f.normal[1];
        let usable = dx.hypot(dy) < keep && f.speed > 0.0;
        return usable.then(|| MeshNode {
            pos,
            foot: end + along / f.speed,
            r,
            curvature: 0.0,
            speed: f.speed,
        });
    }
    let f = curve.frame(pr.u);
    let usable = pr.r.abs() < keep && 1.0 - pr.curvature * pr.r > MIN_JACOBIAN && f.speed > 0.0;
    usable.then_some(MeshNode {
        pos,
        foot: pr.u,
        r: pr.r,
        curvature: pr.curvature,
        speed: f.speed,
    })
}

/// The cell at grid coordinates `(gx, gy)` (in cells from the table's
/// origin) and, when the point lies on an edge or a corner, the cells on the
/// other sides: up to four candidates, the containing cell first.
#[inline]
fn cells_around(gx: f64, gy: f64, cols: usize, rows: usize) -> [Option<usize>; 4] {
    let mut out = [None; 4];
    if !(gx >= 0.0 && gy >= 0.0 && gx <= cols as f64 + EDGE && gy <= rows as f64 + EDGE) {
        return out;
    }
    let ci = (gx.floor() as usize).min(cols - 1);
    let cj = (gy.floor() as usize).min(rows - 1);
    let (fx, fy) = (gx - ci as f64, gy - cj as f64);
    let xs = [Some(ci), other(ci, fx, cols)];
    let ys = [Some(cj), other(cj, fy, rows)];
    let mut k = 0;
    for y in ys.into_iter().flatten() {
        for x in xs.into_iter().flatten() {
            out[k] = Some(y * cols + x);
            k += 1;
        }
    }
    out
}

/// The neighbouring cell index along one axis when the fractional position
/// `f` in cell `c` is on its lower or upper edge.
#[inline]
fn other(c: usize, f: f64, n: usize) -> Option<usize> {
    if f <= EDGE && c > 0 {
        Some(c - 1)
    } else if f >= 1.0 - EDGE && c + 1 < n {
        Some(c + 1)
    } else {
        None
    }
}

fn find(parent: &mut [usize], mut a: usize) -> usize {
    while parent[a] != a {
        parent[a] = parent[parent[a]];
        a = parent[a];
    }
    a
}

fn union(parent: &mut [usize], a: usize, b: usize) {
    let (ra, rb) = (find(parent, a), find(parent, b));
    if ra != rb {
        parent[ra.max(rb)] = ra.min(rb);
    }
}
