//! Gray levels of the virtual image that vary along the curve.
//!
//! The paper's virtual image has one dark level `a` and one contrast `c` for
//! the whole band. Under uneven light (a backlight that falls off, a
//! vignetting lens) the physical edge's levels drift along the curve, and a
//! global pair then leaves a residual `g - f` that is odd in `r` where the
//! local levels differ from the global ones: the fit moves the curve to
//! absorb it, by up to a sizeable fraction of a pixel.
//!
//! With [`LevelModel::Varying`], `a(s) = sum alpha_k M_k(s)` and
//! `c(s) = sum beta_k M_k(s)` on a coarse cubic B-spline basis `M` of the
//! reference's parameter (elements of about `element_length` pixels). They
//! enter the Gauss–Newton iteration exactly as the global pair does (see
//! `fit::correlation`): at each iteration they are the linear least
//! squares fit at the current displacement, and the displacement step is
//! that of the Schur complement with them eliminated, applied with the
//! Woodbury identity on the constant banded factor of `M0`. The one
//! approximation is `sum c(s)^2 dg^2 N_i N_j ~ D_i D_j M0_ij` with `D_i` the
//! contrast averaged over the support of `N_i`: exact for a constant
//! contrast, and good to the contrast's relative change over a few elements
//! of the displacement (which are much shorter than those of the levels).
//! It changes the path of the iteration, not its fixed point (the
//! right-hand side is exact).

use crate::error::Result;
use crate::spline::{Basis, MAX_DEGREE};
use rayon::prelude::*;
use serde::{Deserialize, Serialize};

/// How the virtual image's gray levels may vary along the curve.
///
/// Serialised with a `"type"` tag: `{"type": "global"}` or
/// `{"type": "varying", "element_length": 64.0}`.
#[derive(Clone, Copy, Debug, PartialEq, Serialize, Deserialize)]
#[serde(tag = "type", rename_all = "snake_case")]
pub enum LevelModel {
    /// One dark level and one contrast for the whole band (the paper's).
    Global,
    /// Dark level and contrast are cubic B-splines of the arc length with
    /// elements of about `element_length` pixels (at least 4 elements on a
    /// closed curve, at most [`MAX_LEVEL_ELEMENTS`]). A curve shorter than
    /// two such elements (four, closed) gets the global pair. So does a
    /// measurement whose first converged stage finds that the varying
    /// levels explain no more than noise would (even light): they would
    /// only cost precision. The pixel-edge stage tries again, with
    /// elements of `element_length` and of a half and a quarter of it
    /// (each at most a quarter of a closed curve: an object smaller than
    /// the elements asked for still follows light that changes across it),
    /// and takes them when they explain significantly more (light that
    /// changes faster along the curve, as a star's lobes run in and out of
    /// a vignetted field; see `Correlation::levels_needed`). On a curve
    /// without corners its later runs, once the curve fits, test again
    /// and only ever shorten them.
    Varying {
        /// Length of the levels' elements along the curve, pixels (`>= 8`):
        /// the longest scale over which the light may change.
        element_length: f64,
    },
}

impl std::str::FromStr for LevelModel {
    type Err = crate::error::Error;
    /// `global`, `varying` (the default element length) or `varying:LEN`
    /// (elements of LEN pixels), as the command line's `--levels`. The
    /// length is checked when the configuration is validated, not here.
    fn from_str(s: &str) -> crate::error::Result<Self> {
        let bad = || crate::error::Error::Parse {
            what: format!("gray levels '{s}'"),
            line: 0,
            reason: "expected global, varying or varying:LEN with LEN in pixels, e.g. varying:200"
                .into(),
        };
        match s.trim().split_once(':') {
            None if s.trim() == "global" => Ok(LevelModel::Global),
            None if s.trim() == "varying" => Ok(LevelModel::default()),
            Some(("varying", len)) => Ok(LevelModel::Varying {
                element_length: len.trim().parse().map_err(|_| bad())?,
            }),
            _ => Err(bad()),
        }
    }
}

impl Default for LevelModel {
    /// Varying, with elements of [`DEFAULT_LEVEL_ELEMENT`] pixels.
    fn default() -> Self {
        LevelModel::Varying {
            element_length: DEFAULT_LEVEL_ELEMENT,
        }
    }
}

/// Default element length of varying levels, pixels: light that changes
/// over a few hundred pixels is followed (`tests/it/fit/levels.rs`: a ±35 %
/// gradient across a 220 px disc), while each element holds many band
/// pixels, so that kept levels add little noise through their coupling with
/// the displacement (shorter elements add more).
pub const DEFAULT_LEVEL_ELEMENT: f64 = 128.0;

/// Shortest element of varying levels, pixels: each element needs enough
/// band pixels to fit its levels.
pub(crate) const MIN_LEVEL_ELEMENT: f64 = 8.0;

/// Most elements of varying levels (longer elements beyond): the dense
/// systems of the levels stay small.
pub const MAX_LEVEL_ELEMENTS: usize = 24;

/// Degree of the levels' B-splines.
const LEVEL_DEGREE: usize = 3;
/// Coefficients one band pixel touches: the features times the levels'
/// `LEVEL_DEGREE + 1` functions.
const BLOCK: usize = FEATURES * (LEVEL_DEGREE + 1);

impl LevelModel {
    /// The levels' basis on a reference of parameter length `length`, or
    /// `None` for the global pair (asked for, or the curve is too short).
    pub(crate) fn basis(self, length: f64, closed: bool) -> Option<Basis> {
        let LevelModel::Varying { element_length } = self else {
            return None;
        };
        let min = if closed { LEVEL_DEGREE + 1 } else { 2 };
        let count = (length / element_length).round() as usize;
        if count < min {
            return None;
        }
        Basis::new(LEVEL_DEGREE, count.min(MAX_LEVEL_ELEMENTS), length, closed).ok()
    }

    /// The longest element that gives varying levels on a closed reference
    /// of parameter length `length` (pixels): a quarter of it
    /// ([`LevelModel::basis`]'s fewest elements). Open curves get none
    /// shorter than asked: on a short open curve round a corner, two level
    /// elements took up the corner's misfit and the fit went 3.7 px off.
    pub(crate) fn longest_closed_element(length: f64) -> f64 {
        length / (LEVEL_DEGREE + 1) as f64
    }

    /// Errors: [`crate::Error::InvalidParameter`] for an element length
    /// that is not finite or under [`MIN_LEVEL_ELEMENT`].
    pub(crate) fn validate(self) -> Result<()> {
        if let LevelModel::Varying { element_length } = self {
            if !(element_length.is_finite() && element_length >= MIN_LEVEL_ELEMENT) {
                return Err(crate::Error::invalid(
                    "levels element_length",
                    format!("{element_length} (must be at least {MIN_LEVEL_ELEMENT} px)"),
                ));
            }
        }
        Ok(())
    }
}

/// Features of the levels' model at one band pixel: `1` and `gamma`.
///
/// Light that changes across the image also tilts both plateaus of an edge
/// across the band. Fitted jointly with the curve in the narrow last band,
/// tilts are confounded with its position (a trial multiplied the scatter
/// at 1 % noise); the pixel-edge stage instead measures the light's
/// relative tilt on the plateaus beyond the band and holds it fixed (see
/// `correlation::tilt`; the effect: `tests/it/fit/levels.rs`).
pub(crate) const FEATURES: usize = 2;

/// The features at a pixel of profile value `gamma`.
#[inline]
pub(crate) fn features(gamma: f64) -> [f64; FEATURES] {
    [1.0, gamma]
}

/// The levels' basis values at each band pixel, and small dense algebra on
/// the `FEATURES m` coefficients (the feature's B-spline coefficients one
/// feature after the other).
#[derive(Clone, Debug)]
pub(crate) struct LevelBasis {
    pub basis: Basis,
    /// First function index per band pixel.
    pub first: Vec<u32>,
    /// `LEVEL_DEGREE + 1` values per band pixel.
    pub vals: Vec<f64>,
}

impl LevelBasis {
    /// Evaluate `basis` at the band pixels' parameters `s`.
    pub fn new(basis: Basis, s: &[f64]) -> Self {
        let w = basis.degree() + 1;
        let mut first = vec![0; s.len()];
        let mut vals = vec![0.0; s.len() * w];
        // In parallel: each pixel's values are its own.
        const CHUNK: usize = 1024;
        first
            .par_chunks_mut(CHUNK)
            .zip(vals.par_chunks_mut(CHUNK * w))
            .zip(s.par_chunks(CHUNK))
            .for_each(|((first, vals), s)| {
                let mut v = [0.0; MAX_DEGREE + 1];
                for ((f, out), &u) in first.iter_mut().zip(vals.chunks_exact_mut(w)).zip(s) {
                    *f = basis.eval(u, &mut v) as u32;
                    out.copy_from_slice(&v[..w]);
                }
            });
        LevelBasis { basis, first, vals }
    }

    /// Number of functions `m` per feature.
    pub fn m(&self) -> usize {
        self.basis.n_functions()
    }

    /// Number of coefficients, `FEATURES m`.
    pub fn dim(&self) -> usize {
        FEATURES * self.m()
    }

    /// Values per pixel.
    pub fn width(&self) -> usize {
        self.basis.degree() + 1
    }

    /// The dark level and contrast `(a, c)` at band pixel `i` with
    /// coefficients `theta`.
    #[inline]
    pub fn levels(&self, i: usize, theta: &[f64]) -> (f64, f64) {
        let w = self.width();
        let first = self.first[i] as usize;
        let v = self.coefs(first, &self.vals[i * w..(i + 1) * w], theta);
        (v[0], v[1])
    }

    /// One function of the levels' basis, with the `m` coefficients
    /// `coefs`, at band pixel `i` (the light's tilt, say).
    #[inline]
    pub fn value(&self, i: usize, coefs: &[f64]) -> f64 {
        let w = self.width();
        let first = self.first[i] as usize;
        self.vals[i * w..(i + 1) * w]
            .iter()
            .enumerate()
            .map(|(k, v)| coefs[self.basis.index(first, k)] * v)
            .sum()
    }

    /// The features' functions at basis values `vals` from `first`.
    #[inline]
    fn coefs(&self, first: usize, vals: &[f64], theta: &[f64]) -> [f64; FEATURES] {
        let m = self.m();
        let mut out = [0.0; FEATURES];
        for (k, v) in vals.iter().enumerate() {
            let j = self.basis.index(first, k);
            for (f, o) in out.iter_mut().enumerate() {
                *o += theta[f * m + j] * v;
            }
        }
        out
    }

    /// `(a, c)` at parameter `u` of the reference.
    pub fn levels_at(&self, u: f64, theta: &[f64]) -> (f64, f64) {
        let mut v = [0.0; MAX_DEGREE + 1];
        let first = self.basis.eval(u, &mut v);
        let c = self.coefs(first, &v[..self.width()], theta);
        (c[0], c[1])
    }

    /// Length of the per-element blocks that [`LevelBasis::accumulate`]
    /// fills: one `BLOCK x BLOCK` block per element.
    pub fn blocks_len(&self) -> usize {
        self.basis.n_elements() * BLOCK * BLOCK
    }

    /// Add the pixel's contribution `w x x^T` to the per-element `blocks`
    /// (when given; [`LevelBasis::blocks_len`] long, see
    /// [`LevelBasis::scatter`]) and `w f x` to `rhs`, `x` being the
    /// features times the basis values.
    ///
    /// Why blocks: the `BLOCK^2` products of a pixel go to one contiguous
    /// block (no index arithmetic, vectorised) instead of scattered rows of
    /// the dense matrix; the blocks are scattered once per pass.
    #[inline]
    pub fn accumulate(
        &self,
        i: usize,
        w: f64,
        feats: [f64; FEATURES],
        f: f64,
        blocks: Option<&mut [f64]>,
        rhs: &mut [f64],
    ) {
        const WIDTH: usize = LEVEL_DEGREE + 1;
        let m = self.m();
        let first = self.first[i] as usize;
        let vals = &self.vals[i * WIDTH..(i + 1) * WIDTH];
        let mut x = [0.0; BLOCK];
        for (fi, phi) in feats.iter().enumerate() {
            for (k, v) in vals.iter().enumerate() {
                x[fi * WIDTH + k] = phi * v;
            }
        }
        for (k, _) in vals.iter().enumerate() {
            let j = self.basis.index(first, k);
            for fi in 0..FEATURES {
                rhs[fi * m + j] += w * f * x[fi * WIDTH + k];
            }
        }
        if let Some(blocks) = blocks {
            let block = &mut blocks[first * BLOCK * BLOCK..(first + 1) * BLOCK * BLOCK];
            for (a, row) in block.chunks_exact_mut(BLOCK).enumerate() {
                let wa = w * x[a];
                for (r, xb) in row.iter_mut().zip(&x) {
                    *r += wa * xb;
                }
            }
        }
    }

    /// Add the per-element `blocks` of [`LevelBasis::accumulate`] to the
    /// dense row-major `dim x dim` matrix `mat`.
    pub fn scatter(&self, blocks: &[f64], mat: &mut [f64]) {
        const WIDTH: usize = LEVEL_DEGREE + 1;
        let (m, dim) = (self.m(), self.dim());
        for (first, block) in blocks.chunks_exact(BLOCK * BLOCK).enumerate() {
            let mut idx = [0usize; BLOCK];
            for (a, ix) in idx.iter_mut().enumerate() {
                *ix = (a / WIDTH) * m + self.basis.index(first, a % WIDTH);
            }
            for (a, row) in block.chunks_exact(BLOCK).enumerate() {
                let out = &mut mat[idx[a] * dim..(idx[a] + 1) * dim];
                for (b, v) in row.iter().enumerate() {
                    out[idx[b]] += v;
                }
            }
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// The per-element blocks, scattered, against the dense normal matrix
    /// accumulated entry by entry, on open and closed bases.
    #[test]
    fn blocks_scatter_to_the_dense_matrix() {
        for closed in [false, true] {
            let basis = Basis::new(LEVEL_DEGREE, 6, 100.0, closed).unwrap();
            let s: Vec<f64> = (0..257).map(|k| k as f64 * 0.3891 % 100.0).collect();
            let lb = LevelBasis::new(basis, &s);
            let (m, dim) = (lb.m(), lb.dim());
            let mut blocks = vec![0.0; lb.blocks_len()];
            let mut rhs = vec![0.0; dim];
            let mut dense = vec![0.0; dim * dim];
            let mut dense_rhs = vec![0.0; dim];
            for i in 0..s.len() {
                let (w, g, f) = (
                    1.0 + 0.01 * i as f64,
                    (i as f64 * 0.7).sin(),
                    0.3 + 0.001 * i as f64,
                );
                let feats = features(g);
                lb.accumulate(i, w, feats, f, Some(&mut blocks), &mut rhs);
                // Independently: the full coefficient vector of the pixel.
                let mut x = vec![0.0; dim];
                let first = lb.first[i] as usize;
                for k in 0..=LEVEL_DEGREE {
                    let j = lb.basis.index(first, k);
                    for (fi, phi) in feats.iter().enumerate() {
                        x[fi * m + j] += phi * lb.vals[i * (LEVEL_DEGREE + 1) + k];
                    }
                }
                for a in 0..dim {
                    dense_rhs[a] += w * f * x[a];
                    for b in 0..dim {
                        dense[a * dim + b] += w * x[a] * x[b];
                    }
                }
            }
            let mut mat = vec![0.0; dim * dim];
            lb.scatter(&blocks, &mut mat);
            for (a, b) in mat.iter().zip(&dense).chain(rhs.iter().zip(&dense_rhs)) {
                assert!(
                    (a - b).abs() < 1e-9 * (1.0 + b.abs()),
                    "{closed}: {a} vs {b}"
                );
            }
        }
    }
}
