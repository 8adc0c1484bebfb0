//! Solution of the least-squares system for `s`.
//!
//! The matrix is symmetric positive definite once one node is fixed (the
//! meshed domain is connected, so the only null vector of the
//! unconstrained problem is a constant). It is factored by the project's
//! banded Cholesky and the nodal values are read back; the caller then
//! shifts them to the gauge (`s = 0` at the curve's start).

use super::assemble::System;
use super::mesh::NONE;
use crate::error::{Error, Result};
use crate::solver::BandCholesky;

/// Nodal values of the solution.
pub(crate) struct Nodal {
    /// `s_i`, pixels (0 at the fixed node, before the gauge shift).
    pub s: Vec<f64>,
    /// `a_i` of the enriched nodes, pixels (0 elsewhere); the prescribed
    /// jump is filled in by the caller.
    pub a: Vec<f64>,
}

/// Solve `system` and return the nodal values.
///
/// Errors: [`Error::InvalidParameter`] when the matrix is not positive
/// definite to working precision (a part of the mesh cut off from the
/// rest, which the mesh construction prevents).
pub(crate) fn solve(system: System) -> Result<Nodal> {
    let System {
        matrix,
        mut rhs,
        dofs,
    } = system;
    let chol = BandCholesky::factor(&matrix).map_err(|_| {
        Error::invalid(
            "levelset mesh",
            "the least-squares system for s is singular; use another mesh size or exact \
             coordinates",
        )
    })?;
    chol.solve_in_place(&mut rhs);
    let value = |d: u32| if d == NONE { 0.0 } else { rhs[d as usize] };
    let s = dofs.std.iter().map(|&d| value(d)).collect();
    let a = dofs.enr.iter().map(|&d| value(d)).collect();
    Ok(Nodal { s, a })
}
