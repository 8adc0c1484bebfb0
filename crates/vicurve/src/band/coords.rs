//! How the band's pixels get their curvilinear coordinates `(s, r)`.

use serde::{Deserialize, Serialize};

/// How the band's pixels get their curvilinear coordinates `(s, r)`
/// (method, section 7).
#[derive(Clone, Copy, Debug, Default, PartialEq, Serialize, Deserialize)]
#[serde(rename_all = "snake_case")]
pub enum Coords {
    /// Exact closest-point projection of every band pixel onto the
    /// reference curve (the default: exact, and cheap).
    #[default]
    Exact,
    /// The paper's finite-element levelsets ([`crate::band::levelset`]):
    /// nodal `r` and `s` on a mesh of square bilinear elements of side
    /// `mesh_size` pixels (at least 1; the paper's is about 10) over the
    /// band, interpolated at the pixels. A pixel's normal and curvature are
    /// the curve's at the interpolated `s`. Bilinear interpolation of the
    /// convex distance overestimates it, by `mesh_size^2 |kappa| / 12` px on
    /// average, and the measured curve moves out by as much (about 4e-2 px
    /// on the paper's disc of radius 200 px with 10 px elements); the
    /// scatter is the same as with exact coordinates (see
    /// `tests/levelset.rs`).
    Levelset {
        /// Element side, pixels.
        mesh_size: f64,
    },
}
