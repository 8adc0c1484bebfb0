//! Uniform B-spline bases on an interval (open) or a circle (periodic).
//!
//! A [`Basis`] of degree `p` splits the parameter range `[0, L]` into `n_el`
//! elements of equal length `h = L / n_el`.
//!
//! * **Open**: simple knots `xi_i = (i - p) h`, `i = 0 .. n_el + 2p`, extend `p`
//!   elements beyond each end, so there are `n = n_el + p` functions, all
//!   `C^(p-1)`, and `[0, L]` is covered by exactly the `n_el` active elements.
//!   Function `i` is supported on `[(i - p) h, (i + 1) h]`.
//! * **Periodic**: the same knots wrapped modulo `L`; there are `n = n_el`
//!   functions and function `i` is supported on `[(i - p) h, (i + 1) h]`
//!   modulo `L`. Needs `n_el >= p + 1` so that the `p + 1` functions that are
//!   non-zero on an element are distinct.
//!
//! On element `e` (`s` in `[e h, (e + 1) h)`) the non-zero functions are
//! `e, e + 1, ..., e + p` (modulo `n` when periodic): [`Basis::eval`] returns
//! `e` and the `p + 1` values.
//!
//! # Breaks (repeated knots)
//! [`Basis::with_breaks`] repeats knots at chosen parameters, lowering the
//! continuity there to `C^(p - m)` for a knot of multiplicity `m` (a corner
//! at `m = p`, independent sides at `m = p + 1`). Each break lies exactly on
//! an element boundary: the stretches between breaks get uniform elements
//! of about the requested length (see [`knots`] for the layout and the
//! indexing, which keeps the contract above: first index plus `p + 1`
//! values, half-bandwidth `p`). A basis without breaks is the uniform one,
//! evaluated by the same fast path as before.
//!
//! ```
//! use vicurve::spline::Basis;
//! let basis = Basis::new(3, 10, 100.0, false).unwrap();
//! let mut v = [0.0; 6];
//! let first = basis.eval(42.0, &mut v);
//! assert_eq!(first, 4);
//! let sum: f64 = v[..4].iter().sum();
//! assert!((sum - 1.0).abs() < 1e-14); // partition of unity
//! ```

use crate::error::{Error, Result};

pub mod knots;

pub use knots::Break;
use knots::{horner, Knotted};

/// Largest degree supported.
pub const MAX_DEGREE: usize = 5;

/// A uniform B-spline basis; see the [module documentation](self).
#[derive(Clone, Debug, PartialEq)]
pub struct Basis {
    degree: usize,
    n_el: usize,
    length: f64,
    closed: bool,
    h: f64,
    n_fn: usize,
    /// `None` for the uniform basis (the fast path).
    knotted: Option<Box<Knotted>>,
}

/// Values and derivatives of the `p + 1` non-zero functions at a point,
/// with respect to the parameter `s` (pixels).
#[derive(Clone, Copy, Debug, Default, PartialEq)]
pub struct BasisValues {
    /// Index of the first non-zero function (before wrapping for periodic
    /// bases: use [`Basis::index`]).
    pub first: usize,
    /// `N_{first + k}(s)`, `k = 0..=p`; entries past `p` are 0.
    pub value: [f64; MAX_DEGREE + 1],
    /// First derivatives `dN/ds`.
    pub d1: [f64; MAX_DEGREE + 1],
    /// Second derivatives `d2N/ds2` (0 for degree 1).
    pub d2: [f64; MAX_DEGREE + 1],
}

impl Basis {
    /// A basis of `degree` (1 to 5) with `n_el` elements on `[0, length]`
    /// (pixels), open or periodic (`closed`).
    ///
    /// Errors ([`Error::InvalidParameter`]): degree outside 1..=5, `n_el == 0`,
    /// a periodic basis with `n_el < degree + 1`, a length that is not
    /// finite and positive.
    pub fn new(degree: usize, n_el: usize, length: f64, closed: bool) -> Result<Self> {
        if !(1..=MAX_DEGREE).contains(&degree) {
            return Err(Error::invalid(
                "degree",
                format!("{degree} (B-spline degree must be 1 to {MAX_DEGREE})"),
            ));
        }
        if n_el == 0 {
            return Err(Error::invalid("elements", "0 (need at least 1 element)"));
        }
        if closed && n_el < degree + 1 {
            return Err(Error::invalid(
                "elements",
                format!(
                    "{n_el} elements for a closed curve of degree {degree} (need at least {})",
                    degree + 1
                ),
            ));
        }
        if !(length.is_finite() && length > 0.0) {
            return Err(Error::invalid(
                "curve length",
                format!("{length} (must be finite and positive)"),
            ));
        }
        Ok(Basis {
            degree,
            n_el,
            length,
            closed,
            h: length / n_el as f64,
            n_fn: if closed { n_el } else { n_el + degree },
            knotted: None,
        })
    }

    /// A basis of `degree` on `[0, length]` with repeated knots at
    /// `breaks` and elements of about `length / n_el` pixels between them
    /// (see [`knots`]); the element count is what that makes (at least one
    /// element between consecutive breaks). Without breaks this is
    /// [`Basis::new`].
    ///
    /// Errors ([`Error::InvalidParameter`]): those of [`Basis::new`]; a
    /// break that is not finite, not strictly inside `(0, L)` (open) or in
    /// `[0, L)` (closed), a multiplicity outside `1..=p + 1`, two breaks at
    /// the same parameter; a closed basis with fewer than `p + 1` functions.
    pub fn with_breaks(
        degree: usize,
        n_el: usize,
        length: f64,
        closed: bool,
        breaks: &[Break],
    ) -> Result<Self> {
        let uniform = Basis::new(degree, n_el, length, closed)?;
        if breaks.is_empty() {
            return Ok(uniform);
        }
        let mut sorted = breaks.to_vec();
        sorted.sort_by(|a, b| a.at.total_cmp(&b.at));
        for b in &sorted {
            let inside = if closed {
                (0.0..length).contains(&b.at)
            } else {
                b.at > 0.0 && b.at < length
            };
            if !(b.at.is_finite() && inside) {
                return Err(Error::invalid(
                    "break",
                    format!(
                        "{} px (must lie inside the curve, length {length} px)",
                        b.at
                    ),
                ));
            }
            if !(1..=degree + 1).contains(&b.multiplicity) {
                return Err(Error::invalid(
                    "break multiplicity",
                    format!("{} (must be 1 to {})", b.multiplicity, degree + 1),
                ));
            }
        }
        if let Some(w) = sorted.windows(2).find(|w| w[0].at == w[1].at) {
            return Err(Error::invalid(
                "break",
                format!("{} px given twice", w[0].at),
            ));
        }
        let k = Knotted::new(degree, uniform.h, length, closed, &sorted);
        if closed && k.n_functions < degree + 1 {
            return Err(Error::invalid(
                "elements",
                format!("too few for a closed curve of degree {degree}"),
            ));
        }
        Ok(Basis {
            n_el: k.n_elements(),
            h: length / k.n_elements() as f64,
            n_fn: k.n_functions,
            knotted: Some(Box::new(k)),
            ..uniform
        })
    }

    /// The repeated knots, sorted (empty for a uniform basis).
    pub fn breaks(&self) -> &[Break] {
        self.knotted.as_ref().map_or(&[], |k| &k.breaks)
    }

    /// Start and length of element `e` (pixels).
    #[inline]
    pub fn element_bounds(&self, e: usize) -> (f64, f64) {
        match &self.knotted {
            None => (e as f64 * self.h, self.h),
            Some(k) => k.bounds(e),
        }
    }

    /// [`Basis::locate`], except that a parameter on an element boundary
    /// belongs to the element that ends there (`t = 1`): the left-hand
    /// limit at a break. The first element keeps `s = 0` of an open basis.
    pub fn locate_left(&self, s: f64) -> (usize, f64) {
        let (e, t) = self.locate(s);
        if t > 0.0 {
            return (e, t);
        }
        if e > 0 {
            (e - 1, 1.0)
        } else if self.closed {
            (self.n_el - 1, 1.0)
        } else {
            (e, t)
        }
    }

    /// The first function of element `e` and the power-basis coefficients
    /// of its `p + 1` functions in the local coordinate `t` in `[0, 1]`.
    pub fn element_polynomials(
        &self,
        e: usize,
    ) -> (usize, [[f64; MAX_DEGREE + 1]; MAX_DEGREE + 1]) {
        match &self.knotted {
            None => (e, cardinal_table()[self.degree]),
            Some(k) => (k.el_first[e], k.pieces[e]),
        }
    }

    /// Degree `p`.
    pub fn degree(&self) -> usize {
        self.degree
    }

    /// Number of elements.
    pub fn n_elements(&self) -> usize {
        self.n_el
    }

    /// Length `L` of the parameter range, pixels.
    pub fn length(&self) -> f64 {
        self.length
    }

    /// Whether the basis is periodic.
    pub fn is_closed(&self) -> bool {
        self.closed
    }

    /// Element length `h = L / n_el`, pixels (the mean element length of a
    /// basis with breaks).
    pub fn element_length(&self) -> f64 {
        self.h
    }

    /// Number of functions: `n_el + p` (open) or `n_el` (periodic).
    /// With breaks, each knot of multiplicity `m` adds `m - 1`.
    pub fn n_functions(&self) -> usize {
        self.n_fn
    }

    /// Global index of the function `first + k` (wraps for periodic bases).
    #[inline]
    pub fn index(&self, first: usize, k: usize) -> usize {
        let i = first + k;
        if self.closed && i >= self.n_fn {
            i - self.n_fn
        } else {
            i
        }
    }

    /// The knot vector in the usual (non-periodic) form: `n + p + 1` knots
    /// `xi_i = (i - p) h` for open bases. For periodic bases this is the
    /// unwrapped vector of `n_el + 2p + 1` knots `(i - p) h` on which the
    /// first `p` control values are repeated at the end (the standard way to
    /// hand a periodic spline to other software).
    /// With breaks, the same form with the repeated knots.
    pub fn knots(&self) -> Vec<f64> {
        if let Some(k) = &self.knotted {
            let p = self.degree as isize;
            let count = if self.closed {
                self.n_fn + 2 * self.degree + 1
            } else {
                self.n_fn + self.degree + 1
            };
            return (0..count as isize).map(|i| k.knot(i - p)).collect();
        }
        let count = self.n_el + 2 * self.degree + 1;
        (0..count)
            .map(|i| (i as f64 - self.degree as f64) * self.h)
            .collect()
    }

    /// Element index and local coordinate `t` in `[0, 1]` of `s`.
    /// Open bases clamp `s` to `[0, L]`; periodic ones wrap it.
    #[inline]
    pub fn locate(&self, s: f64) -> (usize, f64) {
        if let Some(k) = &self.knotted {
            let l = self.length;
            let mut s = s;
            if self.closed {
                if !(0.0..l).contains(&s) {
                    s = s.rem_euclid(l);
                    if s >= l {
                        s = 0.0;
                    }
                }
            } else {
                s = s.clamp(0.0, l);
            }
            return k.locate(s);
        }
        let n = self.n_el as f64;
        let mut u = s / self.h;
        if self.closed {
            // rem_euclid is slow; most calls are already in range.
            if !(0.0..n).contains(&u) {
                u = u.rem_euclid(n);
            }
        } else {
            u = u.clamp(0.0, n);
        }
        let mut e = u.floor();
        if e >= n {
            // s = L on an open basis, or rounding on a periodic one.
            e = n - 1.0;
        }
        let e = if e.is_finite() && e > 0.0 {
            e as usize
        } else {
            0
        };
        (e, u - e as f64)
    }

    /// Values of the `p + 1` non-zero functions at `s` into `values[..=p]`;
    /// returns the index of the first one. `values` past `p` are untouched.
    #[inline]
    pub fn eval(&self, s: f64, values: &mut [f64; MAX_DEGREE + 1]) -> usize {
        let (e, t) = self.locate(s);
        if let Some(k) = &self.knotted {
            let pieces = &k.pieces[e];
            for (v, c) in values.iter_mut().zip(pieces).take(self.degree + 1) {
                *v = horner(c, self.degree, t).0;
            }
            return k.el_first[e];
        }
        cardinal_values(self.degree, t, values);
        e
    }

    /// Second derivatives (along `s`, 1/px^2) of the `p + 1` non-zero
    /// functions at `s` into `d2[..=p]`; returns the index of the first
    /// one (as [`Basis::eval`]). On uniform knots the second difference of
    /// the degree `p - 2` values (cheaper than [`Basis::eval_derivs`]);
    /// zeros for degree 1.
    #[inline]
    pub fn eval_d2(&self, s: f64, d2: &mut [f64; MAX_DEGREE + 1]) -> usize {
        let p = self.degree;
        if self.knotted.is_some() || p < 2 {
            let b = self.eval_derivs(s);
            d2[..=p].copy_from_slice(&b.d2[..=p]);
            return b.first;
        }
        let (e, t) = self.locate(s);
        let mut lower = [0.0; MAX_DEGREE + 1];
        cardinal_values(p - 2, t, &mut lower);
        // d2 N_k = (M_{k-2} - 2 M_{k-1} + M_k) / h^2, M the degree p - 2
        // functions of this element (indices past 0..=p-2 are zero).
        let at = |j: usize| if j <= p - 2 { lower[j] } else { 0.0 };
        let inv_h2 = 1.0 / (self.h * self.h);
        for (k, v) in d2.iter_mut().take(p + 1).enumerate() {
            let m2 = if k >= 2 { at(k - 2) } else { 0.0 };
            let m1 = if k >= 1 { at(k - 1) } else { 0.0 };
            *v = (m2 - 2.0 * m1 + at(k)) * inv_h2;
        }
        e
    }

    /// Values and first and second derivatives at `s`.
    pub fn eval_derivs(&self, s: f64) -> BasisValues {
        let (e, t) = self.locate(s);
        self.eval_derivs_at(e, t)
    }

    /// [`Basis::eval_derivs`] on element `e` at local coordinate `t` (with
    /// [`Basis::locate_left`]: the left-hand limits at a break).
    pub fn eval_derivs_at(&self, e: usize, t: f64) -> BasisValues {
        let p = self.degree;
        if let Some(k) = &self.knotted {
            let inv = 1.0 / k.el_len[e];
            let mut out = BasisValues {
                first: k.el_first[e],
                ..Default::default()
            };
            for (i, c) in k.pieces[e].iter().enumerate().take(p + 1) {
                let (v, d1, d2) = horner(c, p, t);
                out.value[i] = v;
                out.d1[i] = d1 * inv;
                out.d2[i] = d2 * inv * inv;
            }
            return out;
        }
        let mut out = BasisValues {
            first: e,
            ..Default::default()
        };
        let mut tri = [[0.0; MAX_DEGREE + 1]; MAX_DEGREE + 1];
        cardinal_triangle(p, t, &mut tri);
        out.value[..=p].copy_from_slice(&tri[p][..=p]);
        // dN_{i,p}/ds = (N_{i,p-1} - N_{i+1,p-1}) / h on uniform knots; the
        // degree p-1 values on this element belong to functions e+1..e+p.
        let lower = &tri[p - 1];
        for k in 0..=p {
            let left = if k >= 1 { lower[k - 1] } else { 0.0 };
            let right = if k < p { lower[k] } else { 0.0 };
            out.d1[k] = (left - right) / self.h;
        }
        if p >= 2 {
            let lower2 = &tri[p - 2];
            let h2 = self.h * self.h;
            for k in 0..=p {
                let at = |j: isize| -> f64 {
                    if j >= 0 && (j as usize) < p - 1 {
                        lower2[j as usize]
                    } else {
                        0.0
                    }
                };
                let k = k as isize;
                out.d2[k as usize] = (at(k - 2) - 2.0 * at(k - 1) + at(k)) / h2;
            }
        }
        out
    }
}

/// The `p + 1` uniform B-spline values on one element at local coordinate
/// `t` in `[0, 1]` (Cox–de Boor on integer knots, where every denominator
/// is the current degree).
#[inline]
#[allow(clippy::needless_range_loop)] // the indices mirror the recurrence
pub(crate) fn cardinal_values(p: usize, t: f64, n: &mut [f64; MAX_DEGREE + 1]) {
    n[0] = 1.0;
    for j in 1..=p {
        let inv_j = 1.0 / j as f64;
        let mut saved = 0.0;
        for r in 0..j {
            // right[r+1] = r + 1 - t, left[j-r] = t + j - r - 1.
            let temp = n[r] * inv_j;
            n[r] = saved + (r as f64 + 1.0 - t) * temp;
            saved = (t + (j - r) as f64 - 1.0) * temp;
        }
        n[j] = saved;
    }
}

/// `(c0 + c1 t) q` for a polynomial `q` (coefficients of `t^0 ..`; the
/// degree stays within `MAX_DEGREE`).
#[allow(clippy::needless_range_loop)]
pub(crate) fn mul_linear(q: &[f64; MAX_DEGREE + 1], c0: f64, c1: f64) -> [f64; MAX_DEGREE + 1] {
    let mut out = [0.0; MAX_DEGREE + 1];
    for m in 0..=MAX_DEGREE {
        out[m] += c0 * q[m];
        if m < MAX_DEGREE {
            out[m + 1] += c1 * q[m];
        }
    }
    out
}

/// [`cardinal_polynomials`] of every degree, made once: a curve's
/// constructor asks for them on each of its elements.
fn cardinal_table() -> &'static [[[f64; MAX_DEGREE + 1]; MAX_DEGREE + 1]; MAX_DEGREE + 1] {
    static TABLE: std::sync::OnceLock<[[[f64; MAX_DEGREE + 1]; MAX_DEGREE + 1]; MAX_DEGREE + 1]> =
        std::sync::OnceLock::new();
    TABLE.get_or_init(|| std::array::from_fn(cardinal_polynomials))
}

/// Power-basis coefficients of the `p + 1` uniform B-spline pieces on one
/// element: `N_k(t) = sum_m polys[k][m] t^m`, `t` in `[0, 1]`. Obtained by
/// running the Cox–de Boor recurrence of `cardinal_values` on polynomials,
/// so the coefficients are exact up to rounding.
#[allow(clippy::needless_range_loop)] // the indices mirror the recurrence
pub fn cardinal_polynomials(p: usize) -> [[f64; MAX_DEGREE + 1]; MAX_DEGREE + 1] {
    let mut n = [[0.0; MAX_DEGREE + 1]; MAX_DEGREE + 1];
    n[0][0] = 1.0;
    for j in 1..=p {
        let inv_j = 1.0 / j as f64;
        let mut saved = [0.0; MAX_DEGREE + 1];
        for r in 0..j {
            let temp: [f64; MAX_DEGREE + 1] = n[r].map(|c| c * inv_j);
            let right = mul_linear(&temp, r as f64 + 1.0, -1.0);
            for m in 0..=MAX_DEGREE {
                n[r][m] = saved[m] + right[m];
            }
            saved = mul_linear(&temp, (j - r) as f64 - 1.0, 1.0);
        }
        n[j] = saved;
    }
    n
}

/// All the intermediate degrees of [`cardinal_values`]: `tri[j][..=j]` holds
/// the degree-`j` values on the element.
#[allow(clippy::needless_range_loop)] // the indices mirror the recurrence
fn cardinal_triangle(p: usize, t: f64, tri: &mut [[f64; MAX_DEGREE + 1]; MAX_DEGREE + 1]) {
    tri[0][0] = 1.0;
    for j in 1..=p {
        let inv_j = 1.0 / j as f64;
        let mut saved = 0.0;
        for r in 0..j {
            let temp = tri[j - 1][r] * inv_j;
            tri[j][r] = saved + (r as f64 + 1.0 - t) * temp;
            saved = (t + (j - r) as f64 - 1.0) * temp;
        }
        tri[j][j] = saved;
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn cubic_values_at_knot() {
        // Uniform cubic B-spline at a knot: 1/6, 4/6, 1/6, 0.
        let mut v = [0.0; 6];
        cardinal_values(3, 0.0, &mut v);
        let expect = [1.0 / 6.0, 4.0 / 6.0, 1.0 / 6.0, 0.0];
        for k in 0..4 {
            assert!((v[k] - expect[k]).abs() < 1e-15, "{v:?}");
        }
    }

    #[test]
    fn locate_clamps_and_wraps() {
        let open = Basis::new(2, 4, 8.0, false).unwrap();
        assert_eq!(open.locate(8.0), (3, 1.0));
        assert_eq!(open.locate(-1.0), (0, 0.0));
        let closed = Basis::new(2, 4, 8.0, true).unwrap();
        let (e, t) = closed.locate(9.0);
        assert_eq!(e, 0);
        assert!((t - 0.5).abs() < 1e-15);
        let (e, _) = closed.locate(-1.0);
        assert_eq!(e, 3);
    }
}
