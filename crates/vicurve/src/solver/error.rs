//! What can go wrong in the solvers, in terms of the matrix only.
//!
//! The solvers do not know what their matrices mean; each caller turns a
//! [`SolverError`] into the crate's [`Error`](crate::Error) with the
//! message of its own domain (the fit's, through the `From` conversion in
//! [`crate::error`]; the level-set mesh and the circle fit with their own).

/// Why a matrix could not be built or factored.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum SolverError {
    /// The matrix would have no row.
    Empty,
    /// `found` values were given where the matrix holds `expected`.
    DimensionMismatch {
        /// Values the matrix holds (`n * n` for a dense one).
        expected: usize,
        /// Values given.
        found: usize,
    },
    /// Pivot `index` (from 0) is not finite or not above
    /// [`PIVOT_RTOL`](super::PIVOT_RTOL) times the largest diagonal entry,
    /// or diagonal entry `index` is not finite: the matrix is not positive
    /// definite, or is singular to working precision.
    NotPositiveDefinite {
        /// Index of the failing pivot (or non-finite diagonal entry).
        index: usize,
    },
}

impl std::fmt::Display for SolverError {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        match self {
            SolverError::Empty => f.write_str("the matrix has no row"),
            SolverError::DimensionMismatch { expected, found } => {
                write!(f, "{found} values for a matrix of {expected}")
            }
            SolverError::NotPositiveDefinite { index } => {
                write!(f, "the matrix is not positive definite at pivot {index}")
            }
        }
    }
}

impl std::error::Error for SolverError {}
