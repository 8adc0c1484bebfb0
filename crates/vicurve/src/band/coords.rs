//! How the band's pixels get their curvilinear coordinates `(s, r)`.

use crate::error::{Error, Result};
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
    /// `tests/it/levelset.rs`).
    Levelset {
        /// Element side, pixels.
        mesh_size: f64,
    },
}

impl std::fmt::Display for Coords {
    /// `exact` or `levelset:MESH` (the mesh size in pixels), which
    /// [`FromStr`](std::str::FromStr) reads back.
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        match self {
            Coords::Exact => f.write_str("exact"),
            Coords::Levelset { mesh_size } => write!(f, "levelset:{mesh_size}"),
        }
    }
}

impl std::str::FromStr for Coords {
    type Err = Error;
    /// `exact`, `levelset` (elements of 10 px, the paper's) or
    /// `levelset:MESH` (elements of MESH px), case ignored: the command
    /// line's `--coords`. The mesh size is checked when the configuration
    /// is validated, not here.
    fn from_str(s: &str) -> Result<Self> {
        let bad = || {
            Error::invalid(
                "coords",
                format!("'{s}' (expected exact, levelset or levelset:MESH with MESH in pixels)"),
            )
        };
        let norm = s.trim().to_ascii_lowercase();
        match norm.split_once(':') {
            None if norm == "exact" => Ok(Coords::Exact),
            None if norm == "levelset" => Ok(Coords::Levelset { mesh_size: 10.0 }),
            Some(("levelset", mesh)) => Ok(Coords::Levelset {
                mesh_size: mesh.trim().parse().map_err(|_| bad())?,
            }),
            _ => Err(bad()),
        }
    }
}
