//! Storage of symmetric (cyclic) banded matrices.

use super::SolverError;

/// How the entries are laid out in memory.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub(super) enum Layout {
    /// `data[i * (q + 1) + d] = M[i][(i - d) mod n]` for `d = 0..=q`: each row
    /// keeps its diagonal and the `q` entries to its left (wrapping around for
    /// a cyclic matrix; unused, left at 0, for an open one when `d > i`).
    /// For a cyclic matrix this needs `n > 2 q + 1` so that every unordered
    /// pair has exactly one slot.
    Band {
        /// Stored half-bandwidth: `min(p, n - 1)`.
        q: usize,
    },
    /// Full `n x n` row-major storage: a cyclic matrix so small
    /// (`n <= 2 p + 1`) that its pattern covers the whole matrix.
    Dense,
}

/// A real symmetric `n x n` matrix whose non-zero entries lie in a band.
///
/// *Open* (`cyclic == false`): `M[i][j]` may be non-zero only when
/// `|i - j| <= p`, where `p` is the half-bandwidth. *Cyclic*: when
/// `min(|i - j|, n - |i - j|) <= p`, i.e. the band plus the two `p x p`
/// corners that periodic B-splines create. Memory is `O(n p)` except for tiny
/// cyclic matrices (`n <= 2 p + 1`), whose pattern is the whole matrix and
/// which are stored densely.
///
/// Indices are 0-based; an index `>= n` is a programming error and panics.
#[derive(Clone, Debug, PartialEq)]
pub struct SymBandMatrix {
    n: usize,
    half_bandwidth: usize,
    cyclic: bool,
    layout: Layout,
    data: Vec<f64>,
}

impl SymBandMatrix {
    /// The zero `n x n` matrix with the given half-bandwidth `p` (any `p` is
    /// accepted; `p >= n - 1` simply means "full").
    ///
    /// Errors: [`SolverError::Empty`] when `n == 0`.
    pub fn zeros(n: usize, half_bandwidth: usize, cyclic: bool) -> Result<Self, SolverError> {
        if n == 0 {
            return Err(SolverError::Empty);
        }
        let q = half_bandwidth.min(n - 1);
        // `q <= n - 1`, so `2 q` cannot overflow for any real matrix size.
        let (layout, len) = if cyclic && n - 1 <= 2 * q {
            (Layout::Dense, n * n)
        } else {
            (Layout::Band { q }, n * (q + 1))
        };
        Ok(SymBandMatrix {
            n,
            half_bandwidth,
            cyclic,
            layout,
            data: vec![0.0; len],
        })
    }

    /// Number of rows (and columns).
    pub fn n(&self) -> usize {
        self.n
    }

    /// The half-bandwidth `p` given to [`SymBandMatrix::zeros`].
    pub fn half_bandwidth(&self) -> usize {
        self.half_bandwidth
    }

    /// Whether the band wraps around (closed curves).
    pub fn is_cyclic(&self) -> bool {
        self.cyclic
    }

    pub(super) fn layout(&self) -> Layout {
        self.layout
    }

    /// Whether `(i, j)` lies in the sparsity pattern (where entries may be
    /// non-zero). Panics if `i >= n` or `j >= n`.
    pub fn in_pattern(&self, i: usize, j: usize) -> bool {
        assert!(i < self.n && j < self.n, "index out of range");
        match self.layout {
            Layout::Dense => true,
            Layout::Band { .. } => self.band_slot(i, j).is_some(),
        }
    }

    /// Position in `data` of the unordered pair `{i, j}` in the band layout.
    #[inline]
    fn band_slot(&self, i: usize, j: usize) -> Option<usize> {
        let Layout::Band { q } = self.layout else {
            return None;
        };
        let w = q + 1;
        if self.cyclic {
            // Distance from j forward to i, going around: slot of row i.
            let d = (i + self.n - j) % self.n;
            if d <= q {
                return Some(i * w + d);
            }
            // Otherwise from i forward to j: slot of row j (d > 0 here).
            let d = self.n - d;
            (d <= q).then_some(j * w + d)
        } else {
            let (r, d) = if i >= j { (i, i - j) } else { (j, j - i) };
            (d <= q).then_some(r * w + d)
        }
    }

    /// Adds `v` to `M[i][j]` and, when `i != j`, to `M[j][i]` too, keeping the
    /// matrix symmetric: callers add each unordered pair once.
    ///
    /// `(i, j)` must lie in the pattern (see [`SymBandMatrix::in_pattern`]);
    /// outside it this is a programming error: it panics in debug builds and
    /// the value is dropped in release builds. Panics if an index is `>= n`.
    #[inline]
    pub fn add(&mut self, i: usize, j: usize, v: f64) {
        assert!(i < self.n && j < self.n, "index out of range");
        match self.layout {
            Layout::Dense => {
                self.data[i * self.n + j] += v;
                if i != j {
                    self.data[j * self.n + i] += v;
                }
            }
            Layout::Band { .. } => match self.band_slot(i, j) {
                Some(k) => self.data[k] += v,
                None => debug_assert!(false, "({i}, {j}) is outside the band"),
            },
        }
    }

    /// Adds `scale v v^T` to the block of rows and columns `first,
    /// first + 1, ..., first + v.len() - 1` (wrapping around past `n - 1`
    /// when cyclic): one point's contribution to a B-spline least-squares
    /// matrix, whose `p + 1` non-zero functions are consecutive. The same
    /// as [`SymBandMatrix::add`] over the pairs `a <= b` with `scale v[a]
    /// v[b]`, writing each row's slots in turn instead of locating every
    /// pair (a modulo per pair on a cyclic matrix): this sits in the
    /// per-pixel and per-point loops that assemble the systems.
    ///
    /// `first` is taken modulo `n` on a cyclic matrix. Panics when `v` is
    /// longer than `n` or when an open matrix's block would pass its last
    /// row; the block must lie in the pattern (`v.len() <= p + 1`), as for
    /// `add`.
    #[inline]
    pub fn add_outer(&mut self, first: usize, scale: f64, v: &[f64]) {
        let n = self.n;
        let len = v.len();
        // A periodic basis may number its first function past the end.
        let first = if self.cyclic { first % n } else { first };
        assert!(
            len <= n && (self.cyclic || first + len <= n),
            "add_outer: block out of range"
        );
        match self.layout {
            Layout::Band { q } if len <= q + 1 => {
                let w = q + 1;
                for (b, vb) in v.iter().enumerate() {
                    let mut row = first + b;
                    if row >= n {
                        row -= n;
                    }
                    // Slot `d` of row `first + b` is column `first + b - d`.
                    let slots = &mut self.data[row * w..row * w + b + 1];
                    let sb = scale * vb;
                    for (slot, va) in slots.iter_mut().zip(v[..=b].iter().rev()) {
                        *slot += sb * va;
                    }
                }
            }
            _ => {
                for b in 0..len {
                    for a in 0..=b {
                        let (i, j) = ((first + a) % n, (first + b) % n);
                        self.add(i, j, scale * v[b] * v[a]);
                    }
                }
            }
        }
    }

    /// `M[i][j]`: 0 outside the pattern. Panics if an index is `>= n`.
    #[inline]
    pub fn get(&self, i: usize, j: usize) -> f64 {
        assert!(i < self.n && j < self.n, "index out of range");
        match self.layout {
            Layout::Dense => self.data[i * self.n + j],
            Layout::Band { .. } => self.band_slot(i, j).map_or(0.0, |k| self.data[k]),
        }
    }

    /// `M += other`, entry by entry (partial sums of one matrix assembled
    /// in parallel). Panics unless `other` has the same size, half-bandwidth
    /// and closure.
    pub fn add_matrix(&mut self, other: &SymBandMatrix) {
        assert!(
            self.n == other.n
                && self.half_bandwidth == other.half_bandwidth
                && self.cyclic == other.cyclic,
            "add_matrix: the matrices differ in shape"
        );
        self.data
            .iter_mut()
            .zip(&other.data)
            .for_each(|(a, b)| *a += b);
    }

    /// Sets every entry to 0, keeping the storage (to reuse the matrix from
    /// one iteration to the next without allocating).
    pub fn fill_zero(&mut self) {
        self.data.fill(0.0);
    }

    /// Calls `f(i, j, M[i][j])` once for every stored unordered pair, with
    /// `j == i` or `j` the row's neighbour at distance `d = 1..=q` to the left
    /// (wrapping around when cyclic). Band layout only.
    fn for_each_band_entry(&self, q: usize, mut f: impl FnMut(usize, usize, f64)) {
        let w = q + 1;
        for i in 0..self.n {
            for d in 0..=q {
                let j = if d <= i {
                    i - d
                } else if self.cyclic {
                    i + self.n - d
                } else {
                    break;
                };
                f(i, j, self.data[i * w + d]);
            }
        }
    }

    /// The whole matrix, row-major (`n * n` values, `out[i * n + j] =
    /// M[i][j]`). For tests and debugging: `O(n^2)` memory.
    pub fn to_dense(&self) -> Vec<f64> {
        let n = self.n;
        match self.layout {
            Layout::Dense => self.data.clone(),
            Layout::Band { q } => {
                let mut out = vec![0.0; n * n];
                self.for_each_band_entry(q, |i, j, v| {
                    out[i * n + j] = v;
                    out[j * n + i] = v;
                });
                out
            }
        }
    }

    /// `y = M x`. Panics if `x` or `y` does not have length `n`.
    pub fn mul_vec(&self, x: &[f64], y: &mut [f64]) {
        let n = self.n;
        assert_eq!(x.len(), n, "mul_vec: x has the wrong length");
        assert_eq!(y.len(), n, "mul_vec: y has the wrong length");
        match self.layout {
            Layout::Dense => {
                for (yi, row) in y.iter_mut().zip(self.data.chunks_exact(n)) {
                    *yi = row.iter().zip(x).map(|(a, b)| a * b).sum();
                }
            }
            Layout::Band { q } => {
                y.fill(0.0);
                self.for_each_band_entry(q, |i, j, v| {
                    y[i] += v * x[j];
                    if i != j {
                        y[j] += v * x[i];
                    }
                });
            }
        }
    }
}
