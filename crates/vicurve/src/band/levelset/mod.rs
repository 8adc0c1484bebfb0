//! The paper's curvilinear coordinates as finite-element levelsets
//! (method, section 7): a regular mesh of square bilinear elements over the
//! band carries nodal values of the signed distance `r` and of the abscissa
//! `s`, and a point's `(s, r)` are interpolated from its element's nodes.
//!
//! All lengths are in pixels, in the image frame of [`crate::image`].
//!
//! # The mesh
//! Square Q4 elements of side `h` (the mesh size, about 10 px in the paper)
//! on the grid `(i h, j h)`, aligned with the pixel grid, covering every
//! point within `R + h sqrt(2)` of the curve (`R` the band half-width), as
//! far as the image goes. Past the ends of an open curve the nodes carry the
//! coordinates of the curve's tangent extension; nodes at or beyond 0.9 of
//! their radius of curvature on the concave side are not used (their
//! closest point jumps there).
//!
//! # `r`
//! The nodal `r` is the exact signed distance of the node to the reference
//! curve, by closest-point projection, positive on the side of the curve's
//! normal `n` (as in [`crate::band`]).
//!
//! # `s`
//! The nodal `s` minimise `integral |grad s - g|^2` over the meshed domain.
//! In the paper the target `g` is `t = grad r` turned by -90 degrees:
//! `t = (dr/dy, -dr/dx)`. Since `grad r = n = (-t_y, t_x)`, that is the
//! curve's unit tangent `dx0/ds`, so `s` grows along the curve's parameter
//! (counterclockwise on screen for closed curves). [`TangentSource`] says
//! whether `t` comes from the exact projection of each quadrature point or
//! from the gradient of the interpolated `r`, as in the paper;
//! [`Target`] whether `g = t` (the paper: `s` is then an arc length along
//! the curve, but away from it `s` is *not* the parameter of the closest
//! point where the curvature varies, see below) or `g = t / (|x0'| (1 - kappa
//! r))`, the exact gradient of the closest point's parameter, which the
//! least-squares solution then reproduces up to the discretisation error.
//!
//! The gauge: one node is fixed to 0 during the solution, then `s` is
//! shifted so that it is 0 at the curve's start `x0(0)`, the smallest value
//! along the curve (an open curve's parameter starts there; past the start
//! the mesh carries negative values, so the paper's "minimum shifted to 0"
//! is taken along the curve, not over the nodes).
//!
//! # Closed curves: the jump
//! Going once around a closed curve, `s` must come back to its start plus
//! the length `L`: it jumps by `L` across one line, the normal line through
//! `x0(0)` (every point on it has its closest point at `s = 0`). The
//! elements that line cuts are enriched with the *shifted* Heaviside
//! functions `N_i (H(X) - H(x_i))`, `H = 1` before the start (see the
//! internal `cut` module): they vanish at every node, so the nodal `s_i` are
//! the values of `s` at the nodes, and outside the cut elements, so there
//! are no blending elements. Cut elements are integrated on their two parts
//! separately (the quad is split along the line into two polygons, fanned
//! into triangles, with Gauss points on the triangles). With
//! [`Jump::Prescribed`] (the default) the enriched values are `a_i = L`:
//! `s` then jumps by exactly `L` all along the line, as the closest point's
//! parameter does, and `s` is in `[0, L)` along the curve. With
//! [`Jump::Free`] the `a_i` are unknowns of the least-squares problem, which
//! then chooses the jump itself: for the unit target on an annulus it is `2
//! pi` times the logarithmic mean of the radii, not `L` (for a disc of
//! radius 200 px and a band of +-24 px, 0.5 % short). The free jump is kept
//! for that comparison; [`LevelsetCoords::eval`] wraps `s` into `[0, L)`
//! only for the prescribed one.
//!
//! # Accuracy
//! Bilinear interpolation of a smooth field `f` errs by about `h^2 |f''| /
//! 8` inside an element, here `h^2 kappa / 8` for `r` (0.06 px for `h = 10`
//! on a circle of radius 200 px). The measured figures, on a circle and on
//! the paper's sinusoid, are in the tests (`tests/levelset.rs`).

mod assemble;
mod cut;
mod mesh;
mod quadrature;
mod solve;

use crate::curve::SplineCurve;
use crate::error::{Error, Result};
use assemble::Problem;
use cut::Cut;
use mesh::Mesh;
use quadrature::shape;

/// Where the tangent `t` in the least-squares target comes from, at each
/// quadrature point.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub enum TangentSource {
    /// The unit tangent at the point's exact closest point on the curve
    /// (one projection per quadrature point; past the ends of an open
    /// curve, the end's tangent).
    #[default]
    Exact,
    /// `grad r` of the interpolated levelset `r`, turned by -90 degrees and
    /// normalised (the paper's; with [`Target::Parameter`] the curvature,
    /// speed and `r` of the weight are interpolated from the nodes too).
    Levelset,
}

/// The gradient that `s` is fitted to.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub enum Target {
    /// `t / (|x0'(u)| (1 - kappa r))`: the exact gradient of the parameter
    /// `u` of the closest point (`1 - kappa r` is the parallel curves'
    /// length ratio, `|x0'|` the parametrisation's speed). `s` is then that
    /// parameter up to the discretisation error, whatever the curve.
    #[default]
    Parameter,
    /// The unit tangent `t` (the paper's). Where the curvature is constant
    /// (a circle, a line) the solution is the same as with
    /// [`Target::Parameter`]; where it varies, the least-squares `s`
    /// differs from the closest point's parameter away from the curve, by
    /// about `kappa' (W^2 r / 2 - r^3 / 6)` for a band of half-width `W`.
    ArcLength,
}

/// How the jump of `s` across the cut of a closed curve is determined.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub enum Jump {
    /// `a_i = L`: `s` jumps by the curve's parameter length `L`.
    #[default]
    Prescribed,
    /// The `a_i` are unknowns of the least-squares problem.
    Free,
}

/// Choices of the levelset construction; the default is what the band uses.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub struct LevelsetOptions {
    /// Source of the tangent. Default: [`TangentSource::Exact`].
    pub tangent: TangentSource,
    /// Target gradient. Default: [`Target::Parameter`].
    pub target: Target,
    /// Jump across the cut (closed curves). Default: [`Jump::Prescribed`].
    pub jump: Jump,
}

/// A node of the mesh with its values.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Node {
    /// Position `[x, y]`, pixels.
    pub position: [f64; 2],
    /// Nodal `s`, pixels. For a closed curve, the value at the node itself:
    /// about `L` just before the cut, about 0 just after it.
    pub s: f64,
    /// Nodal `r`: the exact signed distance, pixels.
    pub r: f64,
    /// The curve parameter of the node's exact closest point, pixels (past
    /// the ends of an open curve, the end's parameter plus the offset along
    /// the end's tangent: the tangent extension's).
    pub foot: f64,
    /// The enriched value `a_i` of a node of a cut element (closed curves),
    /// pixels; `None` elsewhere.
    pub enrichment: Option<f64>,
}

/// An element of the mesh.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct Element {
    /// Indices into [`LevelsetCoords::nodes`] of the corners `(x, y)`,
    /// `(x + h, y)`, `(x + h, y + h)`, `(x, y + h)`.
    pub nodes: [usize; 4],
    /// Whether the cut of a closed curve crosses it (enriched).
    pub cut: bool,
}

/// Levelset coordinates `(s, r)` around a reference curve; see the
/// [module documentation](self).
#[derive(Debug)]
pub struct LevelsetCoords {
    mesh: Mesh,
    cut: Option<Cut>,
    s: Vec<f64>,
    r: Vec<f64>,
    a: Vec<f64>,
    nodes: Vec<Node>,
    elements: Vec<Element>,
    length: f64,
    closed: bool,
    jump: Option<f64>,
    options: LevelsetOptions,
    unknowns: usize,
    half_bandwidth: usize,
}

impl LevelsetCoords {
    /// The levelsets of `curve` on a mesh of side `mesh_size` (pixels) over
    /// its band of half-width `half_width` (pixels), clipped to an image of
    /// `width x height` pixels, with the default [`LevelsetOptions`].
    ///
    /// Errors: [`Error::InvalidParameter`] for a half-width under 0.5 px, a
    /// mesh size under 1 px or not finite, a closed curve too small or thin
    /// for its band and mesh (the cut would reach other parts of it), or a
    /// system too large; [`Error::EmptyImage`] for a zero size;
    /// [`Error::CurveOutsideImage`] when the curve's start is outside the
    /// image.
    pub fn build(
        curve: &SplineCurve,
        half_width: f64,
        mesh_size: f64,
        width: usize,
        height: usize,
    ) -> Result<Self> {
        Self::build_with(
            curve,
            half_width,
            mesh_size,
            width,
            height,
            LevelsetOptions::default(),
        )
    }

    /// [`LevelsetCoords::build`] with explicit options.
    pub fn build_with(
        curve: &SplineCurve,
        half_width: f64,
        mesh_size: f64,
        width: usize,
        height: usize,
        options: LevelsetOptions,
    ) -> Result<Self> {
        if !(half_width.is_finite() && half_width >= 0.5) {
            return Err(Error::invalid(
                "band half-width",
                format!("{half_width} px (must be at least 0.5 px)"),
            ));
        }
        check_mesh_size(mesh_size)?;
        if width == 0 || height == 0 {
            return Err(Error::EmptyImage { width, height });
        }
        let mesh = Mesh::build(curve, half_width, mesh_size, width, height)?;
        let cut = if curve.is_closed() {
            Some(Cut::build(curve, &mesh)?)
        } else {
            None
        };
        let system = Problem {
            curve,
            mesh: &mesh,
            cut: cut.as_ref(),
            options,
        }
        .assemble()?;
        let unknowns = system.matrix.n();
        let half_bandwidth = system.matrix.half_bandwidth();
        let nodal = solve::solve(system)?;
        let length = curve.param_length();
        let mut a = nodal.a;
        if let (Some(cut), Jump::Prescribed) = (&cut, options.jump) {
            for (ai, &enriched) in a.iter_mut().zip(&cut.enriched) {
                if enriched {
                    *ai = length;
                }
            }
        }
        let mut coords = LevelsetCoords {
            r: mesh.nodes.iter().map(|n| n.r).collect(),
            s: nodal.s,
            a,
            nodes: Vec::new(),
            elements: Vec::new(),
            mesh,
            cut,
            length,
            closed: curve.is_closed(),
            jump: None,
            options,
            unknowns,
            half_bandwidth,
        };

        coords.fix_gauge(curve.point(0.0))?;
        coords.nodes = coords.node_views();
        coords.elements = coords.element_views();
        Ok(coords)
    }

    /// The gauge: shift `s` to 0 at the curve's start `start`, on the side
    /// after the cut, and take the jump across the cut there.
    ///
    /// Errors: [`Error::InvalidParameter`] when the start is not inside the
    /// mesh.
    fn fix_gauge(&mut self, start: [f64; 2]) -> Result<()> {
        let (e, xi, eta) = self.mesh.locate(start[0], start[1]).ok_or_else(|| {
            Error::invalid(
                "levelset mesh",
                "the start of the curve is not inside the mesh",
            )
        })?;
        let shift = self.interpolate(e, xi, eta, false).0;
        for s in &mut self.s {
            *s -= shift;
        }
        self.jump = self.jump_at(start);
        Ok(())
    }

    /// The jump of `s` across the cut at the point `start` of the cut line
    /// (closed curves; `None` for open ones).
    fn jump_at(&self, start: [f64; 2]) -> Option<f64> {
        let cut = self.cut.as_ref()?;
        let tol = 1e-9 * self.mesh.h;
        (0..self.mesh.elements.len())
            .filter(|&e| cut.element_cut[e])
            .find_map(|e| {
                let o = self.mesh.origins[e];
                let xi = (start[0] - o[0]) / self.mesh.h;
                let eta = (start[1] - o[1]) / self.mesh.h;
                let inside = (-tol..=1.0 + tol).contains(&xi) && (-tol..=1.0 + tol).contains(&eta);
                inside.then(|| {
                    let (xi, eta) = (xi.clamp(0.0, 1.0), eta.clamp(0.0, 1.0));
                    self.interpolate(e, xi, eta, true).0 - self.interpolate(e, xi, eta, false).0
                })
            })
    }

    /// The nodes with their values, for [`LevelsetCoords::nodes`].
    fn node_views(&self) -> Vec<Node> {
        (0..self.mesh.nodes.len())
            .map(|i| {
                let n = &self.mesh.nodes[i];
                Node {
                    position: n.pos,
                    s: self.s[i],
                    r: n.r,
                    foot: n.foot,
                    enrichment: self
                        .cut
                        .as_ref()
                        .is_some_and(|c| c.enriched[i])
                        .then_some(self.a[i]),
                }
            })
            .collect()
    }

    /// The elements, for [`LevelsetCoords::elements`].
    fn element_views(&self) -> Vec<Element> {
        self.mesh
            .elements
            .iter()
            .enumerate()
            .map(|(e, c)| Element {
                nodes: c.map(|i| i as usize),
                cut: self.cut.as_ref().is_some_and(|cut| cut.element_cut[e]),
            })
            .collect()
    }

    /// `(s, r)` at the point `(x, y)` (pixels), interpolated from the nodes;
    /// `None` outside the meshed domain.
    ///
    /// For a closed curve with the prescribed jump, `s` is wrapped into
    /// `[0, L)`; for an open curve it may be below 0 or above `L` past the
    /// ends (the tangent extension's values), where the caller decides.
    #[inline]
    pub fn eval(&self, x: f64, y: f64) -> Option<(f64, f64)> {
        let (e, xi, eta) = self.mesh.locate(x, y)?;
        let side = self
            .cut
            .as_ref()
            .is_some_and(|c| c.element_cut[e] && c.side([x, y]));
        let (s, r) = self.interpolate(e, xi, eta, side);
        if self.closed && self.options.jump == Jump::Prescribed && !(0.0..self.length).contains(&s)
        {
            // Rare (near the cut), and rem_euclid is slow.
            let mut w = s.rem_euclid(self.length);
            if w >= self.length {
                w = 0.0;
            }
            return Some((w, r));
        }
        Some((s, r))
    }

    /// `(s, r)` at local coordinates `(xi, eta)` of element `e`, on the side
    /// `side` (`H`) of the cut when the element is cut; `s` not wrapped.
    #[inline]
    fn interpolate(&self, e: usize, xi: f64, eta: f64, side: bool) -> (f64, f64) {
        let c = self.mesh.elements[e];
        let n = shape(xi, eta);
        let (mut s, mut r) = (0.0, 0.0);
        for k in 0..4 {
            let i = c[k] as usize;
            s += n[k] * self.s[i];
            r += n[k] * self.r[i];
        }
        if let Some(cut) = &self.cut {
            if cut.element_cut[e] {
                let h = f64::from(u8::from(side));
                for k in 0..4 {
                    let i = c[k] as usize;
                    s += n[k] * (h - f64::from(u8::from(cut.node_side[i]))) * self.a[i];
                }
            }
        }
        (s, r)
    }

    /// The intervals `[x0, x1]` (pixels, increasing, disjoint) where the
    /// horizontal line at `y` crosses the meshed domain, into `spans`
    /// (cleared first): the points worth [`LevelsetCoords::eval`]uating on
    /// a row of pixels.
    pub fn row_spans(&self, y: f64, spans: &mut Vec<[f64; 2]>) {
        self.mesh.row_spans(y, spans);
    }

    /// The nodes with their values.
    pub fn nodes(&self) -> &[Node] {
        &self.nodes
    }

    /// The elements.
    pub fn elements(&self) -> &[Element] {
        &self.elements
    }

    /// Element side `h`, pixels.
    pub fn mesh_size(&self) -> f64 {
        self.mesh.h
    }

    /// Bounding box `[xmin, ymin, xmax, ymax]` of the meshed domain, pixels.
    pub fn bounds(&self) -> [f64; 4] {
        self.mesh.bounds()
    }

    /// The jump of `s` across the cut at the curve's start (closed curves):
    /// `L` for the prescribed jump, the solved one for the free jump;
    /// `None` for open curves.
    pub fn jump(&self) -> Option<f64> {
        self.jump
    }

    /// The options used.
    pub fn options(&self) -> LevelsetOptions {
        self.options
    }

    /// Number of unknowns of the least-squares system and half-bandwidth of
    /// its matrix in the numbering along the curve.
    pub fn system_size(&self) -> (usize, usize) {
        (self.unknowns, self.half_bandwidth)
    }

    /// The start of the cut line, `x0(0)` (closed curves), pixels.
    pub fn cut_origin(&self) -> Option<[f64; 2]> {
        self.cut.as_ref().map(Cut::origin)
    }
}

/// Check a mesh size: finite and at least 1 px (a finer mesh costs more
/// than projecting every pixel).
pub fn check_mesh_size(mesh_size: f64) -> Result<()> {
    if mesh_size.is_finite() && mesh_size >= 1.0 {
        Ok(())
    } else {
        Err(Error::invalid(
            "mesh size",
            format!("{mesh_size} px (must be at least 1 px)"),
        ))
    }
}
