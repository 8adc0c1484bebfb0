//! Cholesky factorisation of symmetric (cyclic) banded matrices.

use super::band::{Layout, SymBandMatrix};
use super::SolverError;
use super::{pivot_ok, pivot_threshold};
use rayon::prelude::*;

/// The Cholesky factor `L` (lower triangular, `M = L L^T`) of a
/// [`SymBandMatrix`].
///
/// Shape of `L`, which is also the shape Cholesky fill-in produces (fill-in
/// never leaves a row's envelope, from its first non-zero column to the
/// diagonal):
/// - open matrix: banded like `M`, rows `0..n` keep `q + 1` entries;
/// - cyclic matrix (`n > 2 p + 1`): rows `0..n - p` are banded; the last `p`
///   rows hold the corner entries, which start at column 0, so they are
///   stored in full (an "arrow"). Time `O(n p^2)`, memory `O(n p)`;
/// - tiny cyclic matrix (`n <= 2 p + 1`): every row is stored in full (a
///   dense factorisation of at most `(2 p + 1)^2` entries).
///
/// Indices `0..m` are the banded rows and `m..n` the full rows.
#[derive(Clone, Debug)]
pub struct BandCholesky {
    n: usize,
    /// Half-bandwidth of the banded rows.
    q: usize,
    /// Number of banded rows.
    m: usize,
    /// `band[i * (q + 1) + d] = L[i][i - d]` for `i < m`, `d <= min(i, q)`.
    band: Vec<f64>,
    /// Full rows `i = m..n`: `L[i][0..=i]` starts at `row_offset(i)`.
    arrow: Vec<f64>,
}

impl BandCholesky {
    /// Factors `M = L L^T`.
    ///
    /// Errors: [`SolverError::NotPositiveDefinite`] with the index of the first
    /// pivot that is not finite or not above
    /// [`PIVOT_RTOL`](super::PIVOT_RTOL) times the largest diagonal entry
    /// (or of the first non-finite diagonal entry): the matrix is not
    /// positive definite, or is singular to working precision.
    pub fn factor(mat: &SymBandMatrix) -> Result<Self, SolverError> {
        let n = mat.n();
        let (q, m) = match mat.layout() {
            Layout::Band { q } if mat.is_cyclic() => (q, n - q),
            Layout::Band { q } => (q, n),
            Layout::Dense => (0, 0),
        };
        let threshold = pivot_threshold((0..n).map(|i| mat.get(i, i)))
            .map_err(|index| SolverError::NotPositiveDefinite { index })?;
        let w = q + 1;
        let not_pd = |index| SolverError::NotPositiveDefinite { index };

        // Banded rows: L[i][j] for j in [i - q, i]; the dot product only
        // runs over the columns both rows i and j share.
        let mut band = vec![0.0; m * w];
        for i in 0..m {
            let lo = i.saturating_sub(q);
            for j in lo..=i {
                let mut s = mat.get(i, j);
                for k in lo..j {
                    s -= band[i * w + i - k] * band[j * w + j - k];
                }
                if j < i {
                    band[i * w + i - j] = s / band[j * w];
                } else if pivot_ok(s, threshold) {
                    band[i * w] = s.sqrt();
                } else {
                    return Err(not_pd(i));
                }
            }
        }

        // Full rows: against a banded row j only its q + 1 entries count;
        // against an earlier full row, all columns.
        let mut arrow = vec![0.0; row_offset(m, n)];
        for i in m..n {
            let (done, rest) = arrow.split_at_mut(row_offset(m, i));
            let row = &mut rest[..=i];
            for j in 0..=i {
                let mut s = mat.get(i, j);
                if j < m {
                    for k in j.saturating_sub(q)..j {
                        s -= row[k] * band[j * w + j - k];
                    }
                    row[j] = s / band[j * w];
                } else {
                    let oj = row_offset(m, j);
                    if j < i {
                        let rj = &done[oj..=oj + j];
                        s -= dot(&row[..j], &rj[..j]);
                        row[j] = s / rj[j];
                    } else {
                        s -= dot(&row[..j], &row[..j]);
                        if !pivot_ok(s, threshold) {
                            return Err(not_pd(i));
                        }
                        row[i] = s.sqrt();
                    }
                }
            }
        }
        Ok(BandCholesky {
            n,
            q,
            m,
            band,
            arrow,
        })
    }

    /// Size `n` of the factored matrix.
    pub fn n(&self) -> usize {
        self.n
    }

    /// Row `i >= m` of `L`, columns `0..=i`.
    #[inline]
    fn full_row(&self, i: usize) -> &[f64] {
        let o = row_offset(self.m, i);
        &self.arrow[o..=o + i]
    }

    /// Forward substitution `L y = b` in place over rows `start..n`, assuming
    /// `b[..start]` is (and stays) zero.
    fn forward(&self, b: &mut [f64], start: usize) {
        let w = self.q + 1;
        for i in start..self.m {
            // The band row holds L[i][i - d] at d: walk b backwards from i.
            let lo = i.saturating_sub(self.q).max(start);
            let row = &self.band[i * w..=i * w + (i - lo)];
            let s: f64 = row[1..]
                .iter()
                .zip(b[lo..i].iter().rev())
                .map(|(l, x)| l * x)
                .sum();
            b[i] = (b[i] - s) / row[0];
        }
        for i in start.max(self.m)..self.n {
            let row = self.full_row(i);
            b[i] = (b[i] - dot(&row[start..i], &b[start..i])) / row[i];
        }
    }

    /// Solves `M x = b` in place (`b` becomes `x`) without allocating, in
    /// `O(n p)`.
    ///
    /// Panics if `b.len() != n` (a programming error).
    pub fn solve_in_place(&self, b: &mut [f64]) {
        assert_eq!(
            b.len(),
            self.n,
            "solve_in_place: wrong right-hand side length"
        );
        self.forward(b, 0);
        // Backward substitution L^T x = y, row by row of L: once x[i] is
        // known, remove its contribution L[i][k] x[i] from the earlier rows.
        for i in (self.m..self.n).rev() {
            let row = self.full_row(i);
            b[i] /= row[i];
            let xi = b[i];
            for (bk, l) in b[..i].iter_mut().zip(&row[..i]) {
                *bk -= l * xi;
            }
        }
        let w = self.q + 1;
        for i in (0..self.m).rev() {
            let lo = i.saturating_sub(self.q);
            let row = &self.band[i * w..=i * w + (i - lo)];
            b[i] /= row[0];
            let xi = b[i];
            for (bk, l) in b[lo..i].iter_mut().rev().zip(&row[1..]) {
                *bk -= l * xi;
            }
        }
    }

    /// The band of the inverse: `out[i * (2 p + 1) + d + p] = (M^-1)_{i,
    /// i + d}` for `|d| <= p`, the column index taken modulo `n` when
    /// `cyclic` (a closed curve's basis; an index reached twice in a tiny
    /// matrix holds the same entry), and 0 past either end otherwise.
    ///
    /// With it, the quadratic form `x^T M^-1 x` of a vector whose non-zero
    /// entries are `p + 1` consecutive ones (B-spline basis values at a
    /// point) costs `(p + 1)^2` products instead of
    /// [`Self::inverse_quadratic_form`]'s substitution.
    ///
    /// When the band asked for lies within the factor's pattern (`p` up to
    /// its half-bandwidth, or a dense factor), by selected inversion
    /// (Takahashi's recurrence on the factor's pattern), `O(n (q + a)^2)`
    /// for `a` arrow rows. A wider band takes one solve per row (row `i`
    /// of the symmetric inverse is its column `i`), `O(n^2 q)`: a
    /// 456-unknown star's refinement spent 5 ms on those.
    pub fn inverse_band(&self, p: usize, cyclic: bool) -> Vec<f64> {
        if p > self.q && self.m > 0 {
            return self.inverse_band_by_solves(p, cyclic);
        }
        let inverse = SelectedInverse::new(self);
        let (n, w) = (self.n, 2 * p + 1);
        let mut out = vec![0.0; n * w];
        for (i, row) in out.chunks_exact_mut(w).enumerate() {
            fill_band_row(row, i, (n, p, cyclic), |j| inverse.get(i, j));
        }
        out
    }

    /// [`Self::inverse_band`] by one solve per row, in parallel.
    fn inverse_band_by_solves(&self, p: usize, cyclic: bool) -> Vec<f64> {
        let n = self.n;
        let w = 2 * p + 1;
        let mut out = vec![0.0; n * w];
        out.par_chunks_mut(w.max(1)).enumerate().for_each_init(
            || vec![0.0; n],
            |col, (i, row)| {
                col.fill(0.0);
                col[i] = 1.0;
                self.solve_in_place(col);
                fill_band_row(row, i, (n, p, cyclic), |j| col[j]);
            },
        );
        out
    }

    /// `x^T M^{-1} x` for the vector `x` that is zero except
    /// `x[(first + k) mod n] += values[k]` for `k = 0..values.len()` — the
    /// `p + 1` B-spline basis values at a curve point, so that the variance of
    /// the curve position there is `sigma^2 * N^T M^{-1} N`. Indices that wrap
    /// onto the same entry (tiny cyclic matrices) add up.
    ///
    /// Computed as `|L^{-1} x|^2` with a forward substitution that starts at
    /// the first non-zero entry: `O(n p)`, no allocation. `scratch` is a
    /// work buffer of length at least `n` whose content is overwritten.
    /// Panics if `scratch.len() < n`.
    pub fn inverse_quadratic_form(&self, first: usize, values: &[f64], scratch: &mut [f64]) -> f64 {
        let n = self.n;
        assert!(
            scratch.len() >= n,
            "inverse_quadratic_form: scratch is shorter than n"
        );
        let y = &mut scratch[..n];
        y.fill(0.0);
        let mut start = n;
        let first = first % n;
        for (k, &v) in values.iter().enumerate() {
            let idx = (first + k) % n;
            y[idx] += v;
            start = start.min(idx);
        }
        if start == n {
            return 0.0;
        }
        self.forward(y, start);
        y[start..].iter().map(|v| v * v).sum()
    }

    /// The factor `L` as a dense row-major `n x n` lower triangular matrix.
    /// For tests and debugging: `O(n^2)` memory.
    pub fn to_dense_factor(&self) -> Vec<f64> {
        let n = self.n;
        let w = self.q + 1;
        let mut out = vec![0.0; n * n];
        for i in 0..self.m {
            for k in i.saturating_sub(self.q)..=i {
                out[i * n + k] = self.band[i * w + i - k];
            }
        }
        for i in self.m..self.n {
            out[i * n..=i * n + i].copy_from_slice(self.full_row(i));
        }
        out
    }
}

/// The entries of `M^-1` on the pattern of `L + L^T` (Takahashi, Fagan &
/// Chen 1973), from the last row up: for `j >= i` in the pattern,
/// `S_ij = (delta_ij / L_ii - sum_{k > i} L_ki S_kj) / L_ii`, the sum over
/// the rows `k` where column `i` of `L` is non-zero (the band below the
/// diagonal and the arrow rows), every `S_kj` it reads being on the
/// pattern and already known. Banded rows keep `S_{i, i..=i + q}`, arrow
/// rows their whole row.
struct SelectedInverse {
    n: usize,
    m: usize,
    q: usize,
    /// `band[i * (q + 1) + d] = S_{i, i + d}`, `i + d < m`.
    band: Vec<f64>,
    /// `arrow[(a - m) * n + j] = S_{a, j}` for the arrow rows `a >= m`.
    arrow: Vec<f64>,
}

impl SelectedInverse {
    fn new(l: &BandCholesky) -> Self {
        let (n, m, q) = (l.n, l.m, l.q);
        let mut s = SelectedInverse {
            n,
            m,
            q,
            band: vec![0.0; m * (q + 1)],
            arrow: vec![0.0; (n - m) * n],
        };
        let w = q + 1;
        // `L_ki` for `k >= i` on the pattern.
        let factor = |k: usize, i: usize| {
            if k < m {
                l.band[k * w + k - i]
            } else {
                l.full_row(k)[i]
            }
        };
        let mut below = Vec::with_capacity(q + n - m);
        for i in (0..n).rev() {
            below.clear();
            if i < m {
                below.extend(i + 1..(i + q + 1).min(m));
            }
            below.extend(m.max(i + 1)..n);
            let diagonal = factor(i, i);
            for &j in &below {
                let sum: f64 = below.iter().map(|&k| factor(k, i) * s.get(k, j)).sum();
                s.set(i, j, -sum / diagonal);
            }
            let sum: f64 = below.iter().map(|&k| factor(k, i) * s.get(k, i)).sum();
            s.set(i, i, (1.0 / diagonal - sum) / diagonal);
        }
        s
    }

    /// `S_kj` (symmetric), on the pattern.
    #[inline]
    fn get(&self, k: usize, j: usize) -> f64 {
        if k >= self.m {
            self.arrow[(k - self.m) * self.n + j]
        } else if j >= self.m {
            self.arrow[(j - self.m) * self.n + k]
        } else {
            let (lo, hi) = if k <= j { (k, j) } else { (j, k) };
            self.band[lo * (self.q + 1) + hi - lo]
        }
    }

    /// Set `S_ij = S_ji` (`i <= j`, on the pattern).
    fn set(&mut self, i: usize, j: usize, v: f64) {
        if j >= self.m {
            self.arrow[(j - self.m) * self.n + i] = v;
            if i >= self.m {
                self.arrow[(i - self.m) * self.n + j] = v;
            }
        } else {
            self.band[i * (self.q + 1) + j - i] = v;
        }
    }
}

/// Row `i` of [`BandCholesky::inverse_band`]'s output (`2 p + 1` slots,
/// columns `i - p..=i + p` of an `n x n` matrix, taken modulo `n` when
/// `cyclic`, left as they are past either end otherwise) from `entry(j)`.
fn fill_band_row(
    row: &mut [f64],
    i: usize,
    (n, p, cyclic): (usize, usize, bool),
    entry: impl Fn(usize) -> f64,
) {
    for (k, v) in row.iter_mut().enumerate() {
        let j = i as isize + k as isize - p as isize;
        let j = if cyclic {
            j.rem_euclid(n as isize)
        } else if (0..n as isize).contains(&j) {
            j
        } else {
            continue;
        };
        *v = entry(j as usize);
    }
}

/// Offset of full row `i` in the arrow storage, whose first full row is `m`:
/// rows `m..i` hold `m + 1, m + 2, ..., i` entries.
#[inline]
fn row_offset(m: usize, i: usize) -> usize {
    (i * (i + 1) - m * (m + 1)) / 2
}

#[inline]
fn dot(a: &[f64], b: &[f64]) -> f64 {
    a.iter().zip(b).map(|(x, y)| x * y).sum()
}
