//! The cut of a closed curve's mesh: the line across which `s` jumps from
//! `L` back to 0, and the elements it splits.
//!
//! The cut is the normal line through the curve's start `x0(0)`. With `t0`
//! the unit tangent there, `phi(X) = (X - x0(0)) . t0` is negative just
//! before the start (where `s` is close to `L`) and positive just after it;
//! the Heaviside function is `H(X) = 1` where `phi < 0` and 0 elsewhere.
//!
//! An element whose corners do not all have the same `H` is *mixed*. The
//! line also crosses the mesh far from the start (on the other side of a
//! disc, say), where nothing jumps: the *cut* elements are the mixed ones
//! connected to the start through other mixed elements, i.e. the chain of
//! elements the line crosses from the start outwards until it leaves the
//! mesh. Their corners are the enriched nodes. An element that is not mixed
//! lies wholly on one side (`phi` is linear and the element convex), so the
//! shifted enrichment `N_i (H - H(x_i))` vanishes in it: there are no
//! blending elements.
//!
//! A band that folds back onto itself within reach of the start (a shape
//! thinner than the band) would let the chain run into the far crossing:
//! that is detected (an enriched node whose closest point is far from the
//! start along the curve) and reported as an error.

use super::mesh::Mesh;
use crate::curve::SplineCurve;
use crate::error::{Error, Result};

/// The cut line and the elements and nodes it concerns.
#[derive(Clone, Debug)]
pub(crate) struct Cut {
    /// `x0(0)`, pixels.
    origin: [f64; 2],
    /// Unit tangent at `x0(0)`.
    tangent: [f64; 2],
    /// `H(x_i)` of each mesh node.
    pub node_side: Vec<bool>,
    /// Whether each element is cut.
    pub element_cut: Vec<bool>,
    /// Whether each node is enriched (a corner of a cut element).
    pub enriched: Vec<bool>,
}

/// A convex polygon of at most 6 vertices, local coordinates.
#[derive(Clone, Copy, Debug)]
pub(crate) struct Polygon {
    /// The vertices, in order; only the first `len` are used.
    pub pts: [[f64; 2]; 6],
    /// Number of vertices.
    pub len: usize,
}

impl Polygon {
    const EMPTY: Polygon = Polygon {
        pts: [[0.0; 2]; 6],
        len: 0,
    };

    fn push(&mut self, p: [f64; 2]) {
        if self.len < self.pts.len() {
            self.pts[self.len] = p;
            self.len += 1;
        }
    }

    /// The vertices in use.
    pub fn vertices(&self) -> &[[f64; 2]] {
        &self.pts[..self.len]
    }
}

impl Cut {
    /// The cut of the mesh of a closed `curve`.
    pub(crate) fn build(curve: &SplineCurve, mesh: &Mesh) -> Result<Cut> {
        let f = curve.frame(0.0);
        let mut cut = Cut {
            origin: f.point,
            tangent: f.tangent,
            node_side: Vec::new(),
            element_cut: vec![false; mesh.elements.len()],
            enriched: vec![false; mesh.nodes.len()],
        };
        cut.node_side = mesh.nodes.iter().map(|n| cut.side(n.pos)).collect();
        let mixed: Vec<bool> = mesh
            .elements
            .iter()
            .map(|c| {
                let first = cut.node_side[c[0] as usize];
                c.iter().any(|&i| cut.node_side[i as usize] != first)
            })
            .collect();

        // Flood fill through mixed elements sharing a node, from those whose
        // closure holds the start.
        let mut node_elements: Vec<Vec<u32>> = vec![Vec::new(); mesh.nodes.len()];
        for (e, c) in mesh.elements.iter().enumerate() {
            for &i in c {
                node_elements[i as usize].push(e as u32);
            }
        }
        let tol = 1e-9 * mesh.h;
        let mut stack: Vec<usize> = (0..mesh.elements.len())
            .filter(|&e| {
                let o = mesh.origins[e];
                mixed[e]
                    && cut.origin[0] >= o[0] - tol
                    && cut.origin[0] <= o[0] + mesh.h + tol
                    && cut.origin[1] >= o[1] - tol
                    && cut.origin[1] <= o[1] + mesh.h + tol
            })
            .collect();
        if stack.is_empty() {
            return Err(Error::invalid(
                "levelset mesh",
                "the start of the closed curve is not inside the mesh",
            ));
        }
        for &e in &stack {
            cut.element_cut[e] = true;
        }
        while let Some(e) = stack.pop() {
            for &i in &mesh.elements[e] {
                cut.enriched[i as usize] = true;
                for &o in &node_elements[i as usize] {
                    let o = o as usize;
                    if mixed[o] && !cut.element_cut[o] {
                        cut.element_cut[o] = true;
                        stack.push(o);
                    }
                }
            }
        }

        // The enriched nodes must lie near the start along the curve, and no
        // element crossed elsewhere may touch them.
        let l = curve.param_length();
        for (i, n) in mesh.nodes.iter().enumerate() {
            if cut.enriched[i] && n.foot.min(l - n.foot) > 0.25 * l {
                return Err(Error::invalid(
                    "levelset mesh",
                    "the cut at the start of the closed curve reaches parts of the curve far \
                     from the start (the curve is too small or too thin for the band and the \
                     mesh); use exact coordinates or a smaller mesh",
                ));
            }
        }
        Ok(cut)
    }

    /// `phi(X)`: signed distance from the cut line, positive after the
    /// start, pixels.
    #[inline]
    pub(crate) fn phi(&self, p: [f64; 2]) -> f64 {
        (p[0] - self.origin[0]) * self.tangent[0] + (p[1] - self.origin[1]) * self.tangent[1]
    }

    /// `H(X)`: true before the start (`phi < 0`).
    #[inline]
    pub(crate) fn side(&self, p: [f64; 2]) -> bool {
        self.phi(p) < 0.0
    }

    /// The start of the curve, `x0(0)`, pixels.
    pub(crate) fn origin(&self) -> [f64; 2] {
        self.origin
    }

    /// The two parts of element `e` of `mesh`, in its local coordinates:
    /// `(H, polygon)` for the side `phi >= 0` (`H = 0`) then `phi < 0`
    /// (`H = 1`). A part may be empty or of zero area.
    pub(crate) fn split(&self, mesh: &Mesh, e: usize) -> [(bool, Polygon); 2] {
        const CORNERS: [[f64; 2]; 4] = [[0.0, 0.0], [1.0, 0.0], [1.0, 1.0], [0.0, 1.0]];
        let phis = CORNERS.map(|c| self.phi(mesh.point(e, c[0], c[1])));
        let mut after = Polygon::EMPTY;
        let mut before = Polygon::EMPTY;
        for k in 0..4 {
            let (a, b) = (CORNERS[k], CORNERS[(k + 1) % 4]);
            let (pa, pb) = (phis[k], phis[(k + 1) % 4]);
            if pa >= 0.0 {
                after.push(a);
            } else {
                before.push(a);
            }
            if (pa >= 0.0) != (pb >= 0.0) {
                let t = pa / (pa - pb);
                let p = [a[0] + t * (b[0] - a[0]), a[1] + t * (b[1] - a[1])];
                after.push(p);
                before.push(p);
            }
        }
        [(false, after), (true, before)]
    }
}
