//! The least-squares problem for `s`: element systems, numbering of the
//! unknowns and the global (cyclic) banded system.
//!
//! On the mesh, `s(X) = sum_i N_i(X) s_i + sum_{i enriched} N_i(X) (H(X) -
//! H(x_i)) a_i` (see [`super::cut`] for `H`), and `s` minimises
//! `integral |grad s - g|^2` over the meshed domain, where the target `g`
//! is the curve's unit tangent field (or that field divided by `|C'| (1 -
//! kappa r)`, see [`super::Target`]). The normal equations are
//! `sum_j (integral grad phi_i . grad phi_j) q_j = integral grad phi_i . g`
//! for the unknowns `q = (s_i, a_i)`.
//!
//! # Quadrature
//! An uncut element is integrated with the 4 x 4 Gauss rule (the stiffness
//! integrand is of degree 2 in each variable; the target varies, fast near
//! a centre of curvature). A cut
//! element is split along the cut line into two convex polygons, each fanned
//! into triangles integrated with a 7-point rule of degree 5; on each part
//! `H` is constant, so the enriched gradients are `(H_part - H(x_i)) grad
//! N_i` there.
//!
//! # Unknowns and band
//! Nodes are numbered by the curve parameter of their closest point (the
//! tangent extension's past the ends of an open curve), each enriched
//! unknown right after its node: nodes that share an element then have
//! nearby numbers, so the matrix is banded, cyclically for a closed curve
//! (the cut joins the parameters near `L` to those near 0), and the
//! project's banded Cholesky ([`crate::solver::BandCholesky`]) solves it in
//! `O(n q^2)` for `n` unknowns and half-bandwidth `q` (about 20 for a 10 px
//! mesh over a 10 px band). One node is fixed to 0 (the gauge; the final
//! shift is in [`super::solve`]); with a [`Jump::Prescribed`] jump the
//! enriched values are known, `a_i = L`, and their terms move to the
//! right-hand side.

use super::cut::Cut;
use super::mesh::{Mesh, MeshNode, NONE};
use super::quadrature::{polygon_rule, shape, shape_gradients, square_rule};
use super::{Jump, LevelsetOptions, TangentSource, Target};
use crate::curve::SplineCurve;
use crate::error::{Error, Result};
use crate::solver::SymBandMatrix;
use rayon::prelude::*;

/// The Jacobian `1 - kappa r` in the [`Target::Parameter`] target is
/// bounded below by this (elements near the centre of curvature).
const MIN_TARGET_JACOBIAN: f64 = 0.05;
/// A free enriched unknown whose diagonal stiffness is under this (its
/// enrichment lives on a sliver of zero area) is dropped.
const MIN_ENRICHED_DIAGONAL: f64 = 1e-9;
/// Refuse systems whose banded storage would exceed this many entries.
const MAX_BAND_ENTRIES: usize = 50_000_000;

/// One element's stiffness (upper triangle used) and load on its 8 local
/// unknowns: `s` at the 4 corners, then `a` at the 4 corners.
#[derive(Clone, Copy, Debug)]
pub(crate) struct ElementSystem {
    pub k: [[f64; 8]; 8],
    pub f: [f64; 8],
}

/// The numbering of the unknowns.
pub(crate) struct Dofs {
    /// Unknown of each node's `s`, or [`NONE`] for the fixed node.
    pub std: Vec<u32>,
    /// Unknown of each node's `a`, or [`NONE`] (not enriched, prescribed
    /// or dropped).
    pub enr: Vec<u32>,
    /// Number of unknowns.
    pub n: usize,
}

/// The global system `M q = b`.
pub(crate) struct System {
    pub matrix: SymBandMatrix,
    pub rhs: Vec<f64>,
    pub dofs: Dofs,
}

/// Everything the element integrals need.
pub(crate) struct Problem<'a> {
    pub curve: &'a SplineCurve,
    pub mesh: &'a Mesh,
    pub cut: Option<&'a Cut>,
    pub options: LevelsetOptions,
}

/// An element's corner nodes and their shape functions at a point.
struct Corners<'a> {
    nodes: [&'a MeshNode; 4],
    shape: [f64; 4],
}

impl Corners<'_> {
    /// The bilinear interpolation at the point of the corner values `f(k)`.
    fn interp(&self, f: impl Fn(usize) -> f64) -> f64 {
        (0..4).map(|k| self.shape[k] * f(k)).sum::<f64>()
    }
}

impl Problem<'_> {
    /// The target `g` at local coordinates `(xi, eta)` of element `e`.
    fn target(&self, e: usize, xi: f64, eta: f64) -> [f64; 2] {
        match self.options.tangent {
            TangentSource::Exact => self.exact_target(e, xi, eta),
            TangentSource::Levelset => self.levelset_target(e, xi, eta),
        }
    }

    /// The corners of element `e` with their shape functions at `(xi, eta)`.
    fn corners(&self, e: usize, xi: f64, eta: f64) -> Corners<'_> {
        let mesh = self.mesh;
        Corners {
            nodes: mesh.elements[e].map(|i| &mesh.nodes[i as usize]),
            shape: shape(xi, eta),
        }
    }

    /// [`Problem::target`] with the tangent of the point's exact closest
    /// point ([`TangentSource::Exact`]).
    fn exact_target(&self, e: usize, xi: f64, eta: f64) -> [f64; 2] {
        let mesh = self.mesh;
        let c = self.corners(e, xi, eta);
        let corners = c.nodes;
        let parameter = self.options.target == Target::Parameter;
        let curve = self.curve;
        let l = curve.param_length();
        let closed = curve.is_closed();
        // Newton's start: the corners' feet, interpolated (unwrapped
        // around the first corner on a closed curve).
        let f0 = corners[0].foot;
        let mut u0 = c.interp(|k| {
            let d = corners[k].foot - f0;
            if closed {
                f0 + d - l * (d / l).round()
            } else {
                f0 + d
            }
        });
        u0 = if closed {
            u0.rem_euclid(l)
        } else {
            u0.clamp(0.0, l)
        };
        let p = mesh.point(e, xi, eta);
        let pr = curve.project(p[0], p[1], u0);
        if pr.at_end {
            // The tangent extension past the end.
            let end = if pr.u <= 0.5 * l { 0.0 } else { l };
            let f = curve.frame(end);
            let w = if parameter { 1.0 / f.speed } else { 1.0 };
            return [w * f.tangent[0], w * f.tangent[1]];
        }
        // The tangent from the projection's normal n = (-t_y, t_x);
        // the speed, which varies slowly along the curve (about 1
        // for a chord-length parametrisation), from the corners.
        let t = [pr.normal[1], -pr.normal[0]];
        let w = if parameter {
            let speed = c.interp(|k| corners[k].speed);
            1.0 / (speed * (1.0 - pr.curvature * pr.r).max(MIN_TARGET_JACOBIAN))
        } else {
            1.0
        };
        [w * t[0], w * t[1]]
    }

    /// [`Problem::target`] with the tangent from the interpolated `r`
    /// ([`TangentSource::Levelset`], the paper's).
    fn levelset_target(&self, e: usize, xi: f64, eta: f64) -> [f64; 2] {
        let mesh = self.mesh;
        let c = self.corners(e, xi, eta);
        let corners = c.nodes;
        let parameter = self.options.target == Target::Parameter;
        // t = grad r turned by -90 degrees: (dr/dy, -dr/dx). With
        // grad r = n = (-t_y, t_x) this is (t_x, t_y), the curve's
        // tangent, pointing the way the parameter grows.
        let g = shape_gradients(xi, eta);
        let gx: f64 = (0..4).map(|k| g[k][0] * corners[k].r).sum::<f64>() / mesh.h;
        let gy: f64 = (0..4).map(|k| g[k][1] * corners[k].r).sum::<f64>() / mesh.h;
        let norm = gx.hypot(gy);
        if norm <= 0.0 {
            return [0.0, 0.0];
        }
        let w = if parameter {
            let speed = c.interp(|k| corners[k].speed);
            let kappa = c.interp(|k| corners[k].curvature);
            let r = c.interp(|k| corners[k].r);
            1.0 / (speed * (1.0 - kappa * r).max(MIN_TARGET_JACOBIAN))
        } else {
            1.0
        };
        [w * gy / norm, -w * gx / norm]
    }

    /// The system of element `e`.
    fn element(&self, e: usize) -> ElementSystem {
        let mut sys = ElementSystem {
            k: [[0.0; 8]; 8],
            f: [0.0; 8],
        };
        let h = self.mesh.h;
        let corners = self.mesh.elements[e];
        // Uncut elements have no enriched unknowns: 4 local unknowns.
        let mut add = |xi: f64, eta: f64, w: f64, part: Option<(bool, &Cut)>| {
            let m = if part.is_some() { 8 } else { 4 };
            let g = shape_gradients(xi, eta);
            let mut b = [[0.0; 2]; 8];
            for k in 0..4 {
                b[k] = [g[k][0] / h, g[k][1] / h];
            }
            if let Some((side, cut)) = part {
                for k in 0..4 {
                    let d = f64::from(u8::from(side))
                        - f64::from(u8::from(cut.node_side[corners[k] as usize]));
                    b[k + 4] = [d * b[k][0], d * b[k][1]];
                }
            }
            let t = self.target(e, xi, eta);
            let wa = w * h * h;
            for a in 0..m {
                sys.f[a] += wa * (b[a][0] * t[0] + b[a][1] * t[1]);
                for c in a..m {
                    sys.k[a][c] += wa * (b[a][0] * b[c][0] + b[a][1] * b[c][1]);
                }
            }
        };
        match self.cut.filter(|c| c.element_cut[e]) {
            Some(cut) => {
                for (side, poly) in cut.split(self.mesh, e) {
                    polygon_rule(poly.vertices(), |xi, eta, w| {
                        add(xi, eta, w, Some((side, cut)));
                    });
                }
            }
            None => {
                for (xi, eta, w) in square_rule() {
                    add(xi, eta, w, None);
                }
            }
        }
        sys
    }

    /// Assemble the global system.
    pub(crate) fn assemble(&self) -> Result<System> {
        let systems: Vec<ElementSystem> = (0..self.mesh.elements.len())
            .into_par_iter()
            .map(|e| self.element(e))
            .collect();
        let dofs = self.number_unknowns(&systems)?;
        let q = self.half_bandwidth(&dofs)?;
        self.scatter(&systems, dofs, q)
    }

    /// The unknowns, numbered by foot parameter: every node's `s` but the
    /// one in the middle of the order (fixed), and the free enriched values
    /// where their function has some support (`systems`' diagonal).
    ///
    /// Errors: [`Error::InvalidParameter`] when nothing is left unknown.
    fn number_unknowns(&self, systems: &[ElementSystem]) -> Result<Dofs> {
        let mesh = self.mesh;
        let n_nodes = mesh.nodes.len();
        let mut enr_diag = vec![0.0; n_nodes];
        if let Some(cut) = self.cut {
            for (e, sys) in systems.iter().enumerate() {
                if cut.element_cut[e] {
                    for (k, &i) in mesh.elements[e].iter().enumerate() {
                        enr_diag[i as usize] += sys.k[k + 4][k + 4];
                    }
                }
            }
        }
        let free = self.options.jump == Jump::Free;
        let has_enr = |i: usize| {
            free && self.cut.is_some_and(|c| c.enriched[i]) && enr_diag[i] > MIN_ENRICHED_DIAGONAL
        };
        let mut order: Vec<usize> = (0..n_nodes).collect();
        order.sort_by(|&a, &b| mesh.nodes[a].foot.total_cmp(&mesh.nodes[b].foot));
        let fixed = order[n_nodes / 2];
        let mut dofs = Dofs {
            std: vec![NONE; n_nodes],
            enr: vec![NONE; n_nodes],
            n: 0,
        };
        for &i in &order {
            if i != fixed {
                dofs.std[i] = dofs.n as u32;
                dofs.n += 1;
            }
            if has_enr(i) {
                dofs.enr[i] = dofs.n as u32;
                dofs.n += 1;
            }
        }
        if dofs.n == 0 {
            return Err(Error::invalid(
                "levelset mesh",
                "the mesh has a single node; use a smaller mesh size",
            ));
        }
        Ok(dofs)
    }

    /// The unknowns of element `e`'s 8 local ones ([`NONE`] where fixed or
    /// absent).
    fn local(&self, dofs: &Dofs, e: usize) -> [u32; 8] {
        let c = self.mesh.elements[e];
        let mut idx = [NONE; 8];
        for k in 0..4 {
            idx[k] = dofs.std[c[k] as usize];
            idx[k + 4] = dofs.enr[c[k] as usize];
        }
        idx
    }

    /// The half-bandwidth of the matrix in the numbering `dofs` (around
    /// the loop for a closed curve).
    ///
    /// Errors: [`Error::InvalidParameter`] when the banded storage would
    /// exceed [`MAX_BAND_ENTRIES`].
    fn half_bandwidth(&self, dofs: &Dofs) -> Result<usize> {
        let n = dofs.n;
        let closed = self.curve.is_closed();
        let distance = |a: u32, b: u32| {
            let d = (a as usize).abs_diff(b as usize);
            if closed {
                d.min(n - d)
            } else {
                d
            }
        };
        let mut q = 0;
        for e in 0..self.mesh.elements.len() {
            let idx = self.local(dofs, e);
            for a in idx.iter().filter(|&&a| a != NONE) {
                for b in idx.iter().filter(|&&b| b != NONE) {
                    q = q.max(distance(*a, *b));
                }
            }
        }
        if n.saturating_mul(q + 1) > MAX_BAND_ENTRIES {
            return Err(Error::invalid(
                "levelset mesh",
                format!(
                    "{n} unknowns with half-bandwidth {q} are too many for this curve; use a \
                     larger mesh size or exact coordinates"
                ),
            ));
        }
        Ok(q)
    }

    /// The element systems `systems` added into the global banded matrix
    /// (half-bandwidth `q`) and right-hand side, the prescribed enrichment
    /// moved to the right.
    fn scatter(&self, systems: &[ElementSystem], dofs: Dofs, q: usize) -> Result<System> {
        let n = dofs.n;
        let l = self.curve.param_length();
        let free = self.options.jump == Jump::Free;
        let mut matrix = SymBandMatrix::zeros(n, q, self.curve.is_closed())?;
        let mut rhs = vec![0.0; n];
        for (e, sys) in systems.iter().enumerate() {
            let idx = self.local(&dofs, e);
            // Prescribed enrichment: a = L on every corner of a cut element.
            let known = match self.cut {
                Some(cut) if !free && cut.element_cut[e] => l,
                _ => 0.0,
            };
            for a in 0..8 {
                if idx[a] == NONE {
                    continue;
                }
                let ia = idx[a] as usize;
                rhs[ia] += sys.f[a];
                if known != 0.0 {
                    for c in 4..8 {
                        let kac = if a <= c { sys.k[a][c] } else { sys.k[c][a] };
                        rhs[ia] -= kac * known;
                    }
                }
                for (c, &ic) in idx.iter().enumerate().skip(a) {
                    if ic != NONE {
                        matrix.add(ia, ic as usize, sys.k[a][c]);
                    }
                }
            }
        }
        Ok(System { matrix, rhs, dofs })
    }
}
