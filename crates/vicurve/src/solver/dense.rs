//! Plain dense Cholesky factorisation.
//!
//! Deliberately simple (textbook row-by-row `L L^T`, `O(n^3)`): it is the
//! reference the banded solver is tested against, and is fine for systems of
//! a few dozen unknowns.

use super::SolverError;
use super::{pivot_ok, pivot_threshold};

/// The Cholesky factor `L` (lower triangular, `A = L L^T`) of a dense
/// symmetric matrix.
#[derive(Clone, Debug)]
pub struct DenseCholesky {
    n: usize,
    /// Row-major `n x n`; the strict upper triangle is zero.
    l: Vec<f64>,
}

impl DenseCholesky {
    /// Factors the symmetric `n x n` matrix `a` (row-major; only its lower
    /// triangle is read).
    ///
    /// Errors: [`SolverError::Empty`] when `n == 0`,
    /// [`SolverError::DimensionMismatch`] when `a.len() != n * n`,
    /// [`SolverError::NotPositiveDefinite`] with the index of
    /// the first pivot that is not finite or not above
    /// [`PIVOT_RTOL`](super::PIVOT_RTOL) times the largest diagonal entry
    /// (same rule as [`BandCholesky`](super::BandCholesky)).
    pub fn factor(a: &[f64], n: usize) -> Result<Self, SolverError> {
        if n == 0 {
            return Err(SolverError::Empty);
        }
        let mut chol = DenseCholesky {
            n,
            l: vec![0.0; n * n],
        };
        chol.refactor(a)?;
        Ok(chol)
    }

    /// Factors another `n x n` matrix `a` (same size) into this factor's
    /// storage, without allocating: for systems re-factored in a loop.
    ///
    /// Errors: those of [`DenseCholesky::factor`]; after an error the factor
    /// is not usable (refactor again before solving).
    pub fn refactor(&mut self, a: &[f64]) -> Result<(), SolverError> {
        let n = self.n;
        if a.len() != n * n {
            return Err(SolverError::DimensionMismatch {
                expected: n * n,
                found: a.len(),
            });
        }
        let threshold = pivot_threshold((0..n).map(|i| a[i * n + i]))
            .map_err(|index| SolverError::NotPositiveDefinite { index })?;
        let l = &mut self.l;
        for i in 0..n {
            for j in 0..=i {
                let mut s = a[i * n + j];
                for k in 0..j {
                    s -= l[i * n + k] * l[j * n + k];
                }
                if j < i {
                    l[i * n + j] = s / l[j * n + j];
                } else if pivot_ok(s, threshold) {
                    l[i * n + i] = s.sqrt();
                } else {
                    return Err(SolverError::NotPositiveDefinite { index: i });
                }
            }
        }
        Ok(())
    }

    /// Size `n` of the factored matrix.
    pub fn n(&self) -> usize {
        self.n
    }

    /// The factor `L`, row-major `n x n`, zero above the diagonal.
    pub fn factor_matrix(&self) -> &[f64] {
        &self.l
    }

    /// Solves `A x = b` in place (`b` becomes `x`).
    ///
    /// Panics if `b.len() != n` (a programming error).
    pub fn solve_in_place(&self, b: &mut [f64]) {
        let n = self.n;
        assert_eq!(b.len(), n, "solve_in_place: wrong right-hand side length");
        let l = &self.l;
        for i in 0..n {
            let mut s = b[i];
            for k in 0..i {
                s -= l[i * n + k] * b[k];
            }
            b[i] = s / l[i * n + i];
        }
        for i in (0..n).rev() {
            let mut s = b[i];
            for k in i + 1..n {
                s -= l[k * n + i] * b[k];
            }
            b[i] = s / l[i * n + i];
        }
    }

    /// The inverse `A^{-1}`, row-major `n x n` (column by column, `O(n^3)`).
    pub fn inverse(&self) -> Vec<f64> {
        let n = self.n;
        let mut inv = vec![0.0; n * n];
        let mut e = vec![0.0; n];
        for c in 0..n {
            e.fill(0.0);
            e[c] = 1.0;
            self.solve_in_place(&mut e);
            for (r, v) in e.iter().enumerate() {
                inv[r * n + c] = *v;
            }
        }
        inv
    }
}
