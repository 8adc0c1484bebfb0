//! The band's pixels by exact closest-point projection: the closest chord
//! of a polyline of the curve gives each pixel near it a starting parameter
//! (`raster`), Newton's method on the exact curve refines it
//! ([`crate::curve::SplineCurve::project`]).

use super::build::{Candidate, Distance, Foot, Pixels};
use super::raster::{unpack, Chords, GridShape};
use super::{BandScratch, MIN_JACOBIAN};
use crate::curve::Clearance;
use crate::virtual_image::pixel_edge::spread_variance;
use crate::virtual_image::{Anisotropy, Profile};
use rayon::prelude::*;

/// Cells of the band's grid per parallel task of the exact projection.
const TOUCHED_CHUNK: usize = 2048;

impl Pixels<'_> {
    /// The band pixels by exact projection, row by row (raster order).
    pub(super) fn exact_rows(&self, scratch: &mut BandScratch) -> Vec<Vec<Candidate>> {
        self.exact_with(scratch, |cell, c| self.project_cell(cell, c))
    }

    /// The centre, signed distance `r` (pixels) and the curve's unit
    /// normal at the foot of each pixel of [`Pixels::exact_rows`], row by
    /// row, without what else a band stores of it (its basis and profile
    /// values).
    pub(super) fn exact_distances(&self, scratch: &mut BandScratch) -> Vec<Vec<Distance>> {
        self.exact_with(scratch, |cell, c| {
            self.foot_of_cell(cell, c)
                .map(|(foot, _)| (foot.pos, foot.r, foot.normal))
        })
    }

    /// What `keep` makes of each grid cell near the curve (`None`: not a
    /// band pixel), row by row, in parallel runs of rows.
    fn exact_with<T: Send>(
        &self,
        scratch: &mut BandScratch,
        keep: impl Fn(&CellSearch, usize) -> Option<T> + Sync,
    ) -> Vec<Vec<T>> {
        let chords = Chords::new(self.curve, self.reach);
        // A pixel within `reach` of the curve is within `reach + sagitta`
        // of its nearest chord, which the grid reaches with a pixel to
        // spare; only such pixels need the exact projection.
        let sagitta = chords.sagitta();
        let grid = GridShape {
            thin: self.thin,
            ..GridShape::around(
                self.curve,
                self.reach + sagitta + 1.0,
                self.width,
                self.height,
            )
        };
        let mut touched = scratch.rasterize(&chords, &grid);
        // Raster order, whatever order the chords reached the cells in.
        radix_sort(&mut touched);
        let cutoff2 = (self.reach + sagitta + 1e-6).powi(2);
        let cell = self.cell_search(&grid, scratch.nearest(), cutoff2);
        let rows = touched
            .par_chunks(TOUCHED_CHUNK)
            .map(|cells| {
                let mut out = Vec::with_capacity(cells.len());
                out.extend(cells.iter().filter_map(|&c| keep(&cell, c as usize)));
                out
            })
            .collect();
        scratch.clear(&grid, &touched);
        rows
    }

    /// What a cell's search reads: the grid, `nearest` (the packed closest
    /// chords of [`BandScratch::rasterize`]), the squared cutoff on a
    /// cell's chord distance, and the corners of the curve.
    fn cell_search<'g>(
        &self,
        grid: &'g GridShape,
        nearest: &'g [u64],
        cutoff2: f64,
    ) -> CellSearch<'g> {
        // Pixels that see both sides of a corner (see `curve/corners.rs`).
        let blur = match self.profile {
            Profile::PixelEdge { blur, .. } | Profile::PixelLine { blur, .. } => blur,
            Profile::Paper { .. } => 0.0,
        };
        // The pixel-edge profile's blur, for the corners' wedge terms, and
        // its largest spread, for their reach.
        let spread = match self.profile {
            Profile::PixelEdge { blur, anisotropy } => Some((
                spread_variance(anisotropy.largest(blur)).sqrt(),
                (blur, anisotropy),
            )),
            _ => None,
        };
        CellSearch {
            grid,
            nearest,
            cutoff2,
            clearances: self.curve.corner_clearances(blur),
            spread,
        }
    }

    /// The band pixel of grid cell `c`, if it is one (see
    /// [`Pixels::foot_of_cell`]), with the corners' wedges that reach it.
    fn project_cell(&self, cell: &CellSearch, c: usize) -> Option<Candidate> {
        let (foot, jacobian) = self.foot_of_cell(cell, c)?;
        let (pos, u) = (foot.pos, foot.s);
        let mut candidate = self.candidate(foot, jacobian);
        if let Some((spread, blur)) = cell.spread {
            let (length, closed) = (self.curve.param_length(), self.curve.is_closed());
            let wedges = cell
                .clearances
                .iter()
                .filter_map(|c| c.wedge(pos, u, length, closed, spread));
            candidate.add_wedges(wedges, blur);
        }
        Some(candidate)
    }

    /// The foot on the curve of grid cell `c` and its area factor (the
    /// jacobian `1 - kappa r`), if the cell is a band pixel: kept (not
    /// thinned out), its chord within the cutoff, its closest point an
    /// interior point of the curve within `reach`, on the near side of the
    /// centre of curvature and clear of the corners.
    fn foot_of_cell(&self, cell: &CellSearch, c: usize) -> Option<(Foot, f64)> {
        let grid = cell.grid;
        let (i, j) = (c % grid.gw, c / grid.gw);
        if self.thinned_out(grid.gx0 + i, grid.gy0 + j) {
            return None;
        }
        let (key, u0) = unpack(cell.nearest[grid.slot(i, j)]);
        if f64::from(key) - 1.0 > cell.cutoff2 {
            return None;
        }
        let x = (grid.gx0 + i) as f64;
        let y = (grid.gy0 + j) as f64;
        let pr = self.curve.project(x, y, f64::from(u0));
        let jacobian = 1.0 - pr.curvature * pr.r;
        if pr.at_end || pr.r.abs() >= self.reach || jacobian <= MIN_JACOBIAN {
            return None;
        }
        let (length, closed) = (self.curve.param_length(), self.curve.is_closed());
        if cell
            .clearances
            .iter()
            .any(|c| c.covers([x, y], pr.u, length, closed))
        {
            return None;
        }
        let foot = Foot {
            pos: [x, y],
            s: pr.u,
            r: pr.r,
            normal: pr.normal,
            curvature: pr.curvature,
        };
        Some((foot, jacobian))
    }
}

/// What [`Pixels::project_cell`] reads: the grid, its packed closest
/// chords, the squared cutoff distance (px^2), the corners' clearances
/// ([`crate::curve::SplineCurve::corner_clearances`]) and, for the
/// pixel-edge profile, its spread (`sqrt(blur^2 + 1/12)`, px), with which
/// the corners' wedges enter the profile.
struct CellSearch<'a> {
    grid: &'a GridShape,
    nearest: &'a [u64],
    cutoff2: f64,
    clearances: Vec<Clearance>,
    /// The pixel edge's largest spread (px) and its blur and anisotropy.
    spread: Option<(f64, (f64, Anisotropy))>,
}

/// Sort distinct cell indices ascending (LSD radix, 11 bits a pass; the
/// same order as a comparison sort).
fn radix_sort(v: &mut Vec<u32>) {
    const BITS: u32 = 11;
    const BUCKETS: usize = 1 << BITS;
    let max = v.iter().copied().max().unwrap_or(0);
    let mut buf = vec![0u32; v.len()];
    let mut shift = 0;
    while shift < 32 && (shift == 0 || (max >> shift) > 0) {
        let mut counts = [0usize; BUCKETS];
        for &x in v.iter() {
            counts[((x >> shift) as usize) & (BUCKETS - 1)] += 1;
        }
        let mut sum = 0;
        for c in counts.iter_mut() {
            let k = *c;
            *c = sum;
            sum += k;
        }
        for &x in v.iter() {
            let b = ((x >> shift) as usize) & (BUCKETS - 1);
            buf[counts[b]] = x;
            counts[b] += 1;
        }
        std::mem::swap(v, &mut buf);
        shift += BITS;
    }
}

#[cfg(test)]
mod tests {
    use super::radix_sort;
    use proptest::prelude::*;

    proptest! {
        /// The radix sort orders distinct cell indices as a comparison
        /// sort does, whatever their range (one to three passes).
        #[test]
        fn the_radix_sort_is_a_sort(
            cells in prop::collection::hash_set(any::<u32>(), 0..3000),
            shift in 0u32..24,
        ) {
            let mut v: Vec<u32> = cells.into_iter().map(|c| c >> shift).collect();
            v.sort_unstable();
            v.dedup();
            let mut want = v.clone();
            v.reverse();
            radix_sort(&mut v);
            want.sort_unstable();
            prop_assert_eq!(v, want);
        }
    }
}
