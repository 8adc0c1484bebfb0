//! A NURBS surface patch between two measured edges (the paper's
//! isogeometric example): the region between two open curves as one
//! B-spline patch, ready for isogeometric analysis or meshing.
//!
//! # Construction ([`NurbsPatch::between`])
//! - **Along** (`u` in `[0, 1]`): both curves are clamped and their
//!   parameters mapped affinely onto `[0, 1]`. A measured curve's parameter
//!   is its chord-length parameter, within a small fraction of a percent of
//!   its arc length, so `u` is (nearly) the *fraction of arc length* on each
//!   edge: the points joined across the patch are at the same fraction of
//!   each edge's length. A curve of lower degree is raised to the other's
//!   ([`BSplineCurve::elevated`]), then each gets the other's knots by knot
//!   insertion, so both have the same degree `p`, knot vector and number of
//!   control points. None of this moves the curves: the patch's boundary
//!   `v = 0` *is* the first curve and `v = 1` the second (to rounding,
//!   ~1e-12 px).
//! - **Across** (`v` in `[0, 1]`): the straight segment between matching
//!   points, as a B-spline of degree `q` (default 1) on knots
//!   `[0 x (q+1), 1 x (q+1)]`: row `j` of the control net is
//!   `A_i + (j / q) (B_i - A_i)` (a linear function written in degree `q`).
//! - **Direction**: when the second curve runs the other way (its start is
//!   nearer the first curve's end), it is reversed, so that the patch does
//!   not twist; [`PatchBuild::reversed_second`] says so.
//! - **Weights**: all 1 (a non-rational B-spline patch), stored anyway so
//!   that NURBS consumers read them, and carried through knot insertion in
//!   homogeneous coordinates.
//!
//! # h-refinement
//! [`NurbsPatch::refine`] splits every knot span into equal parts in either
//! direction by knot insertion, which leaves the surface unchanged.
//!
//! Control net indices: `(i, j)`, `i` along `u` (`0..n_u`), `j` across
//! (`0..n_v`), stored row-major (`i * n_v + j`).

use super::basis::{basis_funs, check_knots, find_span, interior_knots, multiplicity};
use super::curve::BSplineCurve;
use super::refine::{insert_knot, split_spans};
use crate::curve::SplineCurveData;
use crate::error::{Error, Result};
use serde::{Deserialize, Serialize};

/// How to build a patch; serialisable, every field has a default.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
#[serde(default)]
pub struct PatchConfig {
    /// Degree `q` across the patch (1 to 5; default 1, straight lines
    /// between the edges).
    pub degree_across: usize,
    /// Split every knot span along the edges into this many (default 1:
    /// no refinement).
    pub refine_along: usize,
    /// Split every knot span across into this many (default 1).
    pub refine_across: usize,
    /// Reverse the second curve when it runs against the first (default
    /// true).
    pub match_direction: bool,
}

impl Default for PatchConfig {
    fn default() -> Self {
        PatchConfig {
            degree_across: 1,
            refine_along: 1,
            refine_across: 1,
            match_direction: true,
        }
    }
}

/// Knots of the two curves closer than this (on the common domain
/// `[0, 1]`) are made equal before merging: rounding leaves near-duplicates
/// about 1e-16 apart, which would be zero-width elements. Moving a knot by
/// 1e-13 moves the curve by at most ~1e-10 px for measured curves.
pub const KNOT_SNAP: f64 = 1e-13;

/// Largest refinement factor: 1000 x the measured curve's elements is far
/// past any use, and keeps a typo from exhausting the memory.
pub const MAX_REFINE: usize = 1000;

impl PatchConfig {
    /// Check the ranges documented on the fields.
    ///
    /// Errors: [`Error::InvalidParameter`] naming the field.
    pub fn validate(&self) -> Result<()> {
        if !(1..=5).contains(&self.degree_across) {
            return Err(Error::invalid(
                "degree across",
                format!("{} (must be 1 to 5)", self.degree_across),
            ));
        }
        for (name, v) in [
            ("refinement along", self.refine_along),
            ("refinement across", self.refine_across),
        ] {
            if !(1..=MAX_REFINE).contains(&v) {
                return Err(Error::invalid(
                    name,
                    format!("{v} (must be 1 to {MAX_REFINE})"),
                ));
            }
        }
        Ok(())
    }
}

/// A tensor-product NURBS surface in the plane; see the [module
/// documentation](self).
#[derive(Clone, Debug, PartialEq)]
pub struct NurbsPatch {
    degree_u: usize,
    degree_v: usize,
    knots_u: Vec<f64>,
    knots_v: Vec<f64>,
    /// Homogeneous control points `[w x, w y, w]`, `i * n_v + j`.
    net: Vec<[f64; 3]>,
    n_u: usize,
    n_v: usize,
}

/// A patch and how it was made from its two curves.
#[derive(Clone, Debug, PartialEq)]
pub struct PatchBuild {
    /// The patch.
    pub patch: NurbsPatch,
    /// Whether the second curve was reversed to run with the first.
    pub reversed_second: bool,
    /// Degree along before any elevation, first and second curve.
    pub curve_degrees: [usize; 2],
}

/// The serialisable form of a [`NurbsPatch`].
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub struct PatchData {
    /// Degree along the edges (`u`).
    pub degree_u: usize,
    /// Degree across (`v`).
    pub degree_v: usize,
    /// Knot vector along, `n_u + degree_u + 1` values on `[0, 1]`.
    pub knots_u: Vec<f64>,
    /// Knot vector across, `n_v + degree_v + 1` values on `[0, 1]`.
    pub knots_v: Vec<f64>,
    /// Control points `[x, y]` (pixels), `control_points[i][j]`, `i` along
    /// (`n_u` rows), `j` across (`n_v` each).
    pub control_points: Vec<Vec<[f64; 2]>>,
    /// Weights, same shape (all 1 for a patch built from measured curves).
    pub weights: Vec<Vec<f64>>,
}

impl NurbsPatch {
    /// The patch between the open curves `first` (`v = 0`) and `second`
    /// (`v = 1`); see the [module documentation](self).
    ///
    /// Errors: [`Error::InvalidParameter`] for a bad `config`;
    /// [`Error::InvalidCurve`] when the two curves coincide at both ends
    /// (no region between them).
    pub fn between(
        first: &BSplineCurve,
        second: &BSplineCurve,
        config: &PatchConfig,
    ) -> Result<PatchBuild> {
        config.validate()?;
        let mut a = first.clamped()?.reparametrised(0.0, 1.0)?;
        let mut b = second.clamped()?.reparametrised(0.0, 1.0)?;
        let curve_degrees = [a.degree(), b.degree()];
        let d = |p: [f64; 2], q: [f64; 2]| (p[0] - q[0]).hypot(p[1] - q[1]);
        let (a0, a1) = (a.point(0.0), a.point(1.0));
        let (b0, b1) = (b.point(0.0), b.point(1.0));
        let straight = d(a0, b0) + d(a1, b1);
        let crossed = d(a0, b1) + d(a1, b0);
        let reversed_second = config.match_direction && crossed < straight;
        if reversed_second {
            b = b.reversed();
        }
        if a == b {
            return Err(Error::InvalidCurve {
                reason: "the two curves are the same: there is no region between them".into(),
            });
        }
        // Same degree, then same knots.
        let p = a.degree().max(b.degree());
        a = a.elevated(p)?;
        b = b.elevated(p)?;
        // Knots equal but for rounding become equal (see `snap_knots`).
        b.snap_knots(a.knots(), KNOT_SNAP)?;
        let (ka, kb) = (
            interior_knots(a.knots(), 0.0, 1.0),
            interior_knots(b.knots(), 0.0, 1.0),
        );
        for (c, other) in [(&mut a, &kb), (&mut b, &ka)] {
            for &(u, m) in other.iter() {
                let have = multiplicity(c.knots(), u);
                if have < m {
                    c.insert_knot(u, m - have)?;
                }
            }
        }
        debug_assert_eq!(a.knots(), b.knots());
        let q = config.degree_across;
        let n_u = a.control_points().len();
        let n_v = q + 1;
        let mut net = Vec::with_capacity(n_u * n_v);
        for (pa, pb) in a.control_points().iter().zip(b.control_points()) {
            for j in 0..n_v {
                let t = j as f64 / q as f64;
                net.push([
                    pa[0] + t * (pb[0] - pa[0]),
                    pa[1] + t * (pb[1] - pa[1]),
                    1.0,
                ]);
            }
        }
        let mut knots_v = vec![0.0; q + 1];
        knots_v.extend(std::iter::repeat_n(1.0, q + 1));
        let mut patch = NurbsPatch {
            degree_u: p,
            degree_v: q,
            knots_u: a.knots().to_vec(),
            knots_v,
            net,
            n_u,
            n_v,
        };
        patch.refine(config.refine_along, config.refine_across)?;
        Ok(PatchBuild {
            patch,
            reversed_second,
            curve_degrees,
        })
    }

    /// [`Self::between`] for two curves as result files record them.
    ///
    /// Errors: [`Error::InvalidCurve`] for a closed curve (a patch between
    /// two edges needs two open curves: measure the edges from segments or
    /// open polylines), and as [`BSplineCurve::from_data`] and
    /// [`Self::between`].
    pub fn between_data(
        first: &SplineCurveData,
        second: &SplineCurveData,
        config: &PatchConfig,
    ) -> Result<PatchBuild> {
        for (which, c) in [("first", first), ("second", second)] {
            if c.closed {
                return Err(Error::InvalidCurve {
                    reason: format!(
                        "the {which} curve is closed; a patch between two edges needs two open curves (measure each edge from a segment or an open polyline)"
                    ),
                });
            }
        }
        let a = BSplineCurve::from_data(first)?;
        let b = BSplineCurve::from_data(second)?;
        NurbsPatch::between(&a, &b, config)
    }

    /// A patch from its data (checked: shapes, knots, finite values,
    /// positive weights).
    ///
    /// Errors: [`Error::InvalidCurve`], [`Error::InvalidParameter`] or
    /// [`Error::NonFinite`] saying what is inconsistent.
    pub fn from_data(data: &PatchData) -> Result<Self> {
        let n_u = data.control_points.len();
        let n_v = data.control_points.first().map_or(0, |r| r.len());
        check_knots(data.degree_u, &data.knots_u, n_u)?;
        check_knots(data.degree_v, &data.knots_v, n_v)?;
        let shape_ok = data.control_points.iter().all(|r| r.len() == n_v)
            && data.weights.len() == n_u
            && data.weights.iter().all(|r| r.len() == n_v);
        if !shape_ok {
            return Err(Error::InvalidCurve {
                reason: "the control net and weights are not all n_u x n_v".into(),
            });
        }
        let mut net = Vec::with_capacity(n_u * n_v);
        for (row, wrow) in data.control_points.iter().zip(&data.weights) {
            for (p, &w) in row.iter().zip(wrow) {
                if !(p[0].is_finite() && p[1].is_finite() && w.is_finite()) {
                    return Err(Error::NonFinite {
                        what: "patch control net".into(),
                    });
                }
                if w <= 0.0 {
                    return Err(Error::invalid("weight", format!("{w} (must be > 0)")));
                }
                net.push([w * p[0], w * p[1], w]);
            }
        }
        Ok(NurbsPatch {
            degree_u: data.degree_u,
            degree_v: data.degree_v,
            knots_u: data.knots_u.clone(),
            knots_v: data.knots_v.clone(),
            net,
            n_u,
            n_v,
        })
    }

    /// The serialisable form.
    pub fn to_data(&self) -> PatchData {
        let rows = |f: &dyn Fn(&[f64; 3]) -> Vec<f64>| -> Vec<Vec<Vec<f64>>> {
            (0..self.n_u)
                .map(|i| {
                    (0..self.n_v)
                        .map(|j| f(&self.net[i * self.n_v + j]))
                        .collect()
                })
                .collect()
        };
        PatchData {
            degree_u: self.degree_u,
            degree_v: self.degree_v,
            knots_u: self.knots_u.clone(),
            knots_v: self.knots_v.clone(),
            control_points: rows(&|h| vec![h[0] / h[2], h[1] / h[2]])
                .into_iter()
                .map(|r| r.into_iter().map(|p| [p[0], p[1]]).collect())
                .collect(),
            weights: rows(&|h| vec![h[2]])
                .into_iter()
                .map(|r| r.into_iter().map(|w| w[0]).collect())
                .collect(),
        }
    }

    /// Degrees `(p, q)` along and across.
    pub fn degrees(&self) -> (usize, usize) {
        (self.degree_u, self.degree_v)
    }

    /// Knot vectors along and across.
    pub fn knots(&self) -> (&[f64], &[f64]) {
        (&self.knots_u, &self.knots_v)
    }

    /// Control net size `(n_u, n_v)`.
    pub fn size(&self) -> (usize, usize) {
        (self.n_u, self.n_v)
    }

    /// Number of elements (non-empty knot spans) along and across.
    pub fn elements(&self) -> (usize, usize) {
        let count =
            |k: &[f64], p: usize, n: usize| k[p..=n].windows(2).filter(|w| w[1] > w[0]).count();
        (
            count(&self.knots_u, self.degree_u, self.n_u),
            count(&self.knots_v, self.degree_v, self.n_v),
        )
    }

    /// The point `S(u, v)`, pixels; `u` and `v` are clamped to `[0, 1]`
    /// (the domain).
    pub fn point(&self, u: f64, v: f64) -> [f64; 2] {
        let (p, q) = (self.degree_u, self.degree_v);
        let (ku, kv) = (
            find_span(p, &self.knots_u, self.n_u, u),
            find_span(q, &self.knots_v, self.n_v, v),
        );
        let (u, v) = (
            u.clamp(self.knots_u[p], self.knots_u[self.n_u]),
            v.clamp(self.knots_v[q], self.knots_v[self.n_v]),
        );
        let (nu, nv) = (
            basis_funs(ku, u, p, &self.knots_u),
            basis_funs(kv, v, q, &self.knots_v),
        );
        let mut h = [0.0; 3];
        for (a, wa) in nu.iter().enumerate() {
            for (b, wb) in nv.iter().enumerate() {
                let c = self.net[(ku - p + a) * self.n_v + (kv - q + b)];
                for d in 0..3 {
                    h[d] += wa * wb * c[d];
                }
            }
        }
        [h[0] / h[2], h[1] / h[2]]
    }

    /// Insert the knot `u` along (`along = true`) or `v` across, once; the
    /// surface is unchanged. Errors as [`insert_knot`].
    pub fn insert_knot(&mut self, t: f64, along: bool) -> Result<()> {
        if along {
            // Every column j is a curve in u.
            let mut knots = Vec::new();
            let mut cols = Vec::with_capacity(self.n_v);
            for j in 0..self.n_v {
                let mut k = self.knots_u.clone();
                let mut col: Vec<[f64; 3]> =
                    (0..self.n_u).map(|i| self.net[i * self.n_v + j]).collect();
                insert_knot(self.degree_u, &mut k, &mut col, t)?;
                knots = k;
                cols.push(col);
            }
            self.n_u += 1;
            self.knots_u = knots;
            self.net = (0..self.n_u)
                .flat_map(|i| cols.iter().map(move |c| c[i]))
                .collect();
        } else {
            let mut knots = Vec::new();
            let mut net = Vec::with_capacity(self.n_u * (self.n_v + 1));
            for i in 0..self.n_u {
                let mut k = self.knots_v.clone();
                let mut row = self.net[i * self.n_v..(i + 1) * self.n_v].to_vec();
                insert_knot(self.degree_v, &mut k, &mut row, t)?;
                knots = k;
                net.extend(row);
            }
            self.n_v += 1;
            self.knots_v = knots;
            self.net = net;
        }
        Ok(())
    }

    /// h-refinement: split every knot span along into `along` equal spans
    /// and every span across into `across` (1: unchanged). The surface is
    /// unchanged. Errors: [`Error::InvalidParameter`] for 0 or above
    /// [`MAX_REFINE`].
    pub fn refine(&mut self, along: usize, across: usize) -> Result<()> {
        for (name, v) in [("refinement along", along), ("refinement across", across)] {
            if !(1..=MAX_REFINE).contains(&v) {
                return Err(Error::invalid(
                    name,
                    format!("{v} (must be 1 to {MAX_REFINE})"),
                ));
            }
        }
        for t in split_spans(self.degree_u, &self.knots_u, self.n_u, along) {
            self.insert_knot(t, true)?;
        }
        for t in split_spans(self.degree_v, &self.knots_v, self.n_v, across) {
            self.insert_knot(t, false)?;
        }
        Ok(())
    }
}
