//! Linear solvers for the symmetric positive definite systems of the fit.
//!
//! The Gauss-Newton normal matrix of a B-spline curve of degree `p` couples
//! control points `i` and `j` only when their basis functions overlap, i.e.
//! when `|i - j| <= p`: it is *banded* with half-bandwidth `p`. For a closed
//! (periodic) curve the indices wrap around, so the matrix is *cyclic*
//! banded: `(i, j)` may be non-zero when `min(|i - j|, n - |i - j|) <= p`,
//! which adds two `p x p` corners.
//!
//! - [`SymBandMatrix`] stores such a matrix in `O(n p)` memory.
//! - [`BandCholesky`] factors it as `L L^T` in `O(n p^2)` time, including the
//!   cyclic case (banded `L` plus `p` dense last rows, an "arrow").
//! - [`DenseCholesky`] is a plain dense factorisation, used as a reference in
//!   tests and for tiny systems.
//! - `lm` is the one Levenberg–Marquardt loop of the nonlinear fits (the
//!   shape models, the best-fit circle and ellipse).
//! - `chunked` sums the pixels' contributions to a system in parallel, in
//!   fixed chunks, so that the sum has the same bits on every run.
//!
//! Errors are [`SolverError`]s, which speak of matrices only; callers turn
//! them into the crate's [`Error`](crate::Error).

mod band;
mod cholesky;
pub(crate) mod chunked;
mod dense;
mod error;
pub(crate) mod lm;

pub use band::SymBandMatrix;
pub use cholesky::BandCholesky;
pub use dense::DenseCholesky;
pub use error::SolverError;

/// Relative pivot tolerance of the Cholesky factorisations.
///
/// A pivot `d_k` (the square of `L[k][k]`) is rejected when
/// `d_k <= PIVOT_RTOL * max_i M[i][i]`. Every pivot of a positive definite
/// matrix is at least its smallest eigenvalue and the largest diagonal entry
/// is at most its largest eigenvalue, so any matrix whose condition number is
/// below `1 / PIVOT_RTOL = 1e12` is always accepted, while a singular matrix
/// (whose pivot is only rounding noise, about `1e-16` relative) is reported.
pub const PIVOT_RTOL: f64 = 1e-12;

/// The pivot threshold of a matrix whose diagonal is `diag`, or the index of
/// the first non-finite diagonal entry.
fn pivot_threshold(diag: impl Iterator<Item = f64>) -> Result<f64, usize> {
    let mut max_diag = 0.0_f64;
    for (i, d) in diag.enumerate() {
        if !d.is_finite() {
            return Err(i);
        }
        max_diag = max_diag.max(d);
    }
    Ok(PIVOT_RTOL * max_diag)
}

/// Whether `pivot` is acceptable against `threshold`; written so that a NaN
/// pivot is rejected too.
#[inline]
fn pivot_ok(pivot: f64, threshold: f64) -> bool {
    pivot > threshold && pivot.is_finite()
}
