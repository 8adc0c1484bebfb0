//! The closest chord of every pixel near the curve: a polyline of the
//! curve rasterised onto a grid of the image, each cell keeping the
//! smallest (squared distance, foot parameter) of the chords that reach it,
//! as a starting point for the exact projection (`exact`).
//!
//! Per cell the grid holds one plus the squared distance to the closest
//! chord and the parameter of its foot, as `f32` bits packed in a `u64`;
//! the smaller packed value wins, so the grid does not depend on the order
//! of the chords. Zero marks a cell no chord reached. The cells reached are
//! listed (by their raster index, row after row), so that neither clearing
//! nor scanning costs the bounding box's area. The grid stores its cells
//! in tiles of [`TILE_W`] x [`TILE_H`] (one 4 KiB page each): a chord
//! reaches a compact patch of cells, which row-major storage spreads over
//! as many pages as the patch has rows (a page fault each on a fresh grid,
//! a TLB miss each on a kept one). The chords are rasterised in
//! [`GRID_PARTS`] runs in parallel, each on its own grid, merged after.

use crate::curve::SplineCurve;
use rayon::prelude::*;
use std::sync::Mutex;

/// Parallel runs of the chords' rasterisation.
const GRID_PARTS: usize = 2;
/// Columns of a tile of the grid's storage (a power of two).
const TILE_W: usize = 32;
/// Rows of a tile (a power of two): `TILE_W x TILE_H` cells of 8 bytes
/// fill a 4 KiB page.
const TILE_H: usize = 16;
/// Cells of a grid kept for the next band (128 MB); a larger one is freed.
const MAX_KEPT_GRID: usize = 1 << 24;
/// Scratches kept in the pool at most: one per band being built, for two
/// curves measured at once (at most 512 MB kept, for bands around curves
/// 4000 px across).
const MAX_KEPT_SCRATCHES: usize = 2;

/// Scratch grids of the exact projection's rasterisation (all zero between
/// bands), kept by the caller from band to band: a fresh grid costs a page
/// fault per row the curve crosses, a kept one only the cells the band
/// touches. [`BandScratch::default`] is empty (the grids are made by the
/// first band); [`crate::band::Band::new_in`] builds with one.
///
/// [`crate::band::Band::new`] and the other constructors take theirs from a
/// pool shared by the process and return it after: the callers that build
/// bands frame after frame (the schedule's stages, the tracking cache) do
/// not hold a scratch of their own yet, and a fresh one per band would cost
/// them the page faults above. Once they do, the pool can go.
#[derive(Debug, Default)]
pub struct BandScratch {
    grids: Vec<Vec<u64>>,
}

/// The scratches returned to the pool, all zero.
static POOL: Mutex<Vec<BandScratch>> = Mutex::new(Vec::new());

impl BandScratch {
    /// A scratch from the pool, or an empty one when the pool has none.
    pub(super) fn from_pool() -> BandScratch {
        POOL.lock()
            .ok()
            .and_then(|mut pool| pool.pop())
            .unwrap_or_default()
    }

    /// Return the scratch to the pool (freeing its grids above
    /// [`MAX_KEPT_GRID`] cells, all of it when the pool is full).
    pub(super) fn return_to_pool(mut self) {
        self.grids.retain(|g| g.len() <= MAX_KEPT_GRID);
        if let Ok(mut pool) = POOL.lock() {
            if pool.len() < MAX_KEPT_SCRATCHES {
                pool.push(self);
            }
        }
    }

    /// Rasterise `chords` onto `grid` (its closest chords into the first
    /// grid, [`BandScratch::nearest`]); returns the cells reached, in no
    /// particular order.
    pub(super) fn rasterize(&mut self, chords: &Chords, grid: &GridShape) -> Vec<u32> {
        let cells = grid.storage();
        self.grids.resize_with(GRID_PARTS, Vec::new);
        for g in &mut self.grids {
            if g.len() < cells {
                // A quarter to spare: a curve growing stage after stage
                // (a far start) would otherwise make its grid afresh, and
                // page-fault it, at every re-reference.
                *g = vec![0; cells + cells / 4];
            }
        }
        let nseg = chords.nseg;
        let per = nseg.div_ceil(GRID_PARTS).max(1);
        let mut touched: Vec<Vec<u32>> = self
            .grids
            .par_iter_mut()
            .enumerate()
            .map(|(part, best)| {
                let mut touched = Vec::new();
                let range = (part * per).min(nseg)..((part + 1) * per).min(nseg);
                chords.rasterize(range, grid, best, &mut touched);
                touched
            })
            .collect();
        let (first, others) = self.grids.split_at_mut(1);
        let best = &mut first[0];
        let mut all = touched.remove(0);
        for (other, cells) in others.iter_mut().zip(touched) {
            for cell in cells {
                let c = grid.slot_of(cell as usize);
                let v = std::mem::take(&mut other[c]);
                if best[c] == 0 {
                    all.push(cell);
                    best[c] = v;
                } else {
                    best[c] = best[c].min(v);
                }
            }
        }
        all
    }

    /// The merged grid of the last [`BandScratch::rasterize`], in the
    /// storage order of its [`GridShape`] ([`GridShape::slot`]).
    pub(super) fn nearest(&self) -> &[u64] {
        &self.grids[0]
    }

    /// Zero the cells `touched` (raster indices) of the merged grid of
    /// shape `grid` again.
    pub(super) fn clear(&mut self, grid: &GridShape, touched: &[u32]) {
        for &cell in touched {
            self.grids[0][grid.slot_of(cell as usize)] = 0;
        }
    }
}

/// Where [`Chords::rasterize`] writes: the grid's box of pixel centres
/// `[gx0, gx1] x [gy0, gy1]`, `gw x gh` cells, and how far from a chord it
/// looks, pixels. Cell `(i, j)` (column and row from the box's corner) has
/// the raster index `j gw + i` and is stored at [`GridShape::slot`].
pub(super) struct GridShape {
    pub gx0: usize,
    pub gy0: usize,
    pub gx1: usize,
    pub gy1: usize,
    pub gw: usize,
    pub gh: usize,
    pub reach: f64,
    /// Keep one cell in `thin` (as `Pixels::thinned_out`): 1 all, 2 a
    /// checkerboard (x + y even), 4 even x and even y.
    pub thin: usize,
}

impl GridShape {
    /// The grid of the pixels within `reach` (pixels) of the control
    /// polygon's box (which contains the curve and its polyline), clipped
    /// to an image of `width x height` pixels.
    pub fn around(curve: &SplineCurve, reach: f64, width: usize, height: usize) -> GridShape {
        let bb = curve.bounding_box();
        let gx0 = ((bb[0] - reach).floor().max(0.0)) as usize;
        let gy0 = ((bb[1] - reach).floor().max(0.0)) as usize;
        let gx1 = ((bb[2] + reach).ceil().min(width as f64 - 1.0)).max(0.0) as usize;
        let gy1 = ((bb[3] + reach).ceil().min(height as f64 - 1.0)).max(0.0) as usize;
        GridShape {
            gx0,
            gy0,
            gx1,
            gy1,
            gw: gx1 + 1 - gx0,
            gh: gy1 + 1 - gy0,
            reach,
            thin: 1,
        }
    }

    /// Cells of the grid's storage: whole tiles covering its box.
    pub fn storage(&self) -> usize {
        self.gw.div_ceil(TILE_W) * self.gh.div_ceil(TILE_H) * TILE_W * TILE_H
    }

    /// Where the cell of column `i` and row `j` (from the box's corner) is
    /// stored: its tile's place (row-major among the tiles), then its
    /// place in the tile (row-major).
    #[inline]
    pub fn slot(&self, i: usize, j: usize) -> usize {
        let tiles_x = self.gw.div_ceil(TILE_W);
        let tile = (j / TILE_H) * tiles_x + i / TILE_W;
        tile * (TILE_W * TILE_H) + (j % TILE_H) * TILE_W + i % TILE_W
    }

    /// [`GridShape::slot`] of the cell of raster index `cell`.
    #[inline]
    pub fn slot_of(&self, cell: usize) -> usize {
        self.slot(cell % self.gw, cell / self.gw)
    }
}

/// The polyline of a curve: vertices at parameters `params`, `nseg`
/// chords (closing back to the first vertex when closed), about `step`
/// pixels long.
pub(super) struct Chords {
    verts: Vec<[f64; 2]>,
    params: Vec<f64>,
    nseg: usize,
    closed: bool,
    length: f64,
    step: f64,
}

/// One chord: from `a` (parameter `ua`) to `b` (parameter `ub`), pixels;
/// `d = b - a`, `len = |d|` and `dd = len^2` (at least 1e-300).
struct Chord {
    a: [f64; 2],
    b: [f64; 2],
    ua: f64,
    ub: f64,
    d: [f64; 2],
    len: f64,
    dd: f64,
}

impl Chords {
    /// The polyline of `curve` for a band reaching `reach` pixels: chords
    /// short enough that the closest chord leads Newton to the global
    /// closest point.
    pub fn new(curve: &SplineCurve, reach: f64) -> Chords {
        let length = curve.param_length();
        let closed = curve.is_closed();
        let step = (0.5 * reach).clamp(0.5, 4.0);
        let count = ((length / step).ceil() as usize).max(4);
        let params = curve.sample_params(if closed { count } else { count + 1 });
        let verts: Vec<[f64; 2]> = params.iter().map(|&u| curve.point(u)).collect();
        let nseg = if closed { verts.len() } else { verts.len() - 1 };
        Chords {
            verts,
            params,
            nseg,
            closed,
            length,
            step,
        }
    }

    /// The largest distance of the polyline from the curve, pixels: its
    /// largest sagitta (about chord * turning angle / 8; bounded by a
    /// quarter for safety).
    pub fn sagitta(&self) -> f64 {
        let turns = if self.closed {
            self.nseg
        } else {
            self.nseg - 1
        };
        (0..turns)
            .map(|k| {
                let (t0, t1) = (self.dir(k), self.dir(k + 1));
                self.step * (t0[0] * t1[1] - t0[1] * t1[0]).abs().asin() / 4.0
            })
            .fold(0.0, f64::max)
    }

    /// Chord `k`.
    fn chord(&self, k: usize) -> Chord {
        let a = self.verts[k];
        let b = self.verts[(k + 1) % self.verts.len()];
        let d = [b[0] - a[0], b[1] - a[1]];
        let len = (d[0] * d[0] + d[1] * d[1]).sqrt();
        Chord {
            a,
            b,
            ua: self.params[k],
            ub: if k + 1 < self.params.len() {
                self.params[k + 1]
            } else {
                self.length
            },
            d,
            len,
            dd: (len * len).max(1e-300),
        }
    }

    /// Unit direction of chord `k` (wrapping around).
    fn dir(&self, k: usize) -> [f64; 2] {
        let n = self.verts.len();
        let a = self.verts[k % n];
        let b = self.verts[(k + 1) % n];
        let d = [b[0] - a[0], b[1] - a[1]];
        let len = (d[0] * d[0] + d[1] * d[1]).sqrt().max(1e-12);
        [d[0] / len, d[1] / len]
    }

    /// How far past its ends chord `k` looks, pixels, for pixels `reach`
    /// from it: only the pixels whose foot falls on the chord (give or
    /// take this) can have it as their closest chord. It covers the wedge
    /// between this chord's rectangle and its neighbours' on the convex
    /// side, which widens with the distance and the turning.
    fn overhang(&self, k: usize, reach: f64) -> f64 {
        let t = self.dir(k);
        let turn = |j: usize| {
            let o = self.dir(j);
            (t[0] * o[1] - t[1] * o[0]).abs().asin()
        };
        let prev = if self.closed {
            turn(k + self.nseg - 1)
        } else if k > 0 {
            turn(k - 1)
        } else {
            0.0
        };
        let next = if k + 1 < self.nseg || self.closed {
            turn(k + 1)
        } else {
            0.0
        };
        1.0 + reach * prev.max(next).min(1.0) * 2.0
    }

    /// Write, for every cell near chords `range`, the smaller of its value
    /// and the packed (squared distance, foot parameter) of the chord; the
    /// cells first reached go to `touched`.
    fn rasterize(
        &self,
        range: std::ops::Range<usize>,
        grid: &GridShape,
        best: &mut [u64],
        touched: &mut Vec<u32>,
    ) {
        for k in range {
            self.rasterize_chord(k, grid, best, touched);
        }
    }

    /// [`Chords::rasterize`] for chord `k`, row by row.
    fn rasterize_chord(
        &self,
        k: usize,
        grid: &GridShape,
        best: &mut [u64],
        touched: &mut Vec<u32>,
    ) {
        let reach = grid.reach;
        let chord = self.chord(k);
        let (a, b) = (chord.a, chord.b);
        let ext = self.overhang(k, reach);
        let t = self.dir(k);
        let box_ = ChordBox {
            t,
            n: [-t[1], t[0]],
            lo: -ext,
            hi: chord.len + ext,
            reach,
        };
        let y_lo = ((a[1].min(b[1]) - reach - ext).floor().max(grid.gy0 as f64)) as usize;
        let y_hi = ((a[1].max(b[1]) + reach + ext).ceil().min(grid.gy1 as f64)) as usize;
        let thin = match grid.thin {
            0 | 1 => 1,
            2 | 3 => 2,
            _ => 4,
        };
        for y in y_lo..=y_hi {
            if thin == 4 && y % 2 == 1 {
                continue;
            }
            let py = y as f64 - a[1];
            let (x_min, x_max) = box_.row_span(py);
            if x_min > x_max {
                continue;
            }
            let x_lo = ((a[0] + x_min).floor().max(grid.gx0 as f64)) as usize;
            let x_hi = (a[0] + x_max).ceil().min(grid.gx1 as f64);
            if x_hi < x_lo as f64 {
                continue;
            }
            let j = y - grid.gy0;
            let row = j * grid.gw;
            // First kept x at or after x_lo.
            let (x_first, step) = match thin {
                1 => (x_lo, 1),
                2 => (x_lo + ((x_lo + y) % 2), 2),
                _ => (x_lo + (x_lo % 2), 2),
            };
            if x_first as f64 > x_hi {
                continue;
            }
            for x in (x_first..=x_hi as usize).step_by(step) {
                let i = x - grid.gx0;
                let slot = grid.slot(i, j);
                let packed = chord.packed_foot(x as f64 - a[0], py);
                let old = best[slot];
                if old == 0 {
                    touched.push((row + i) as u32);
                    best[slot] = packed;
                } else if packed < old {
                    best[slot] = packed;
                }
            }
        }
    }
}

impl Chord {
    /// The packed (one plus squared distance, foot parameter) of the point
    /// `(px, py)` from `a` (pixels) to this chord.
    #[inline]
    fn packed_foot(&self, px: f64, py: f64) -> u64 {
        let (d, dd) = (self.d, self.dd);
        let t = ((px * d[0] + py * d[1]) / dd).clamp(0.0, 1.0);
        let ex = px - t * d[0];
        let ey = py - t * d[1];
        let d2 = ex * ex + ey * ey;
        pack(
            (1.0 + d2) as f32,
            (self.ua + t * (self.ub - self.ua)) as f32,
        )
    }
}

/// The region a chord rasterises, in its frame from its start `a`: along
/// its unit direction `t` in `[lo, hi]`, along its normal `n` within
/// `reach` (pixels).
struct ChordBox {
    t: [f64; 2],
    n: [f64; 2],
    lo: f64,
    hi: f64,
    reach: f64,
}

impl ChordBox {
    /// The `x` range (from `a`, pixels) of the row `py` below `a` that
    /// lies in the box; empty (`min > max`) when none does.
    #[inline]
    fn row_span(&self, py: f64) -> (f64, f64) {
        let mut x_min = f64::NEG_INFINITY;
        let mut x_max = f64::INFINITY;
        for (axis, (mn, mx)) in [
            (self.t, (self.lo, self.hi)),
            (self.n, (-self.reach, self.reach)),
        ] {
            let rest = py * axis[1];
            if axis[0].abs() < 1e-12 {
                if rest < mn || rest > mx {
                    x_min = f64::INFINITY;
                }
                continue;
            }
            let e0 = (mn - rest) / axis[0];
            let e1 = (mx - rest) / axis[0];
            x_min = x_min.max(e0.min(e1));
            x_max = x_max.min(e0.max(e1));
        }
        (x_min, x_max)
    }
}

/// Two `f32` in one `u64` (the first in the high half).
#[inline]
fn pack(a: f32, b: f32) -> u64 {
    (u64::from(a.to_bits()) << 32) | u64::from(b.to_bits())
}

/// The two `f32` of [`pack`].
#[inline]
pub(super) fn unpack(v: u64) -> (f32, f32) {
    (f32::from_bits((v >> 32) as u32), f32::from_bits(v as u32))
}

#[cfg(test)]
mod tests {
    use super::GridShape;
    use proptest::prelude::*;

    proptest! {
        /// Every cell of a grid, whatever its size, has a slot of its own
        /// within the storage.
        #[test]
        fn the_tiled_slots_are_a_bijection(gw in 1usize..150, gh in 1usize..90) {
            let grid = GridShape {
                gx0: 3,
                gy0: 5,
                gx1: 2 + gw,
                gy1: 4 + gh,
                gw,
                gh,
                reach: 1.0,
                thin: 1,
            };
            let storage = grid.storage();
            let mut seen = vec![false; storage];
            for j in 0..gh {
                for i in 0..gw {
                    let slot = grid.slot(i, j);
                    prop_assert!(slot < storage);
                    prop_assert!(!seen[slot]);
                    seen[slot] = true;
                    prop_assert_eq!(grid.slot_of(j * gw + i), slot);
                }
            }
        }
    }
}
