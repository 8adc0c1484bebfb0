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
        })
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

    /// Element length `h = L / n_el`, pixels.
    pub fn element_length(&self) -> f64 {
        self.h
    }

    /// Number of functions: `n_el + p` (open) or `n_el` (periodic).
    pub fn n_functions(&self) -> usize {
        if self.closed {
            self.n_el
        } else {
            self.n_el + self.degree
        }
    }

    /// Global index of the function `first + k` (wraps for periodic bases).
    #[inline]
    pub fn index(&self, first: usize, k: usize) -> usize {
        let i = first + k;
        if self.closed && i >= self.n_el {
            i - self.n_el
        } else {
            i
        }
    }

    /// The knot vector in the usual (non-periodic) form: `n + p + 1` knots
    /// `xi_i = (i - p) h` for open bases. For periodic bases this is the
    /// unwrapped vector of `n_el + 2p + 1` knots `(i - p) h` on which the
    /// first `p` control values are repeated at the end (the standard way to
    /// hand a periodic spline to other software).
    pub fn knots(&self) -> Vec<f64> {
        let count = self.n_el + 2 * self.degree + 1;
        (0..count)
            .map(|i| (i as f64 - self.degree as f64) * self.h)
            .collect()
    }

    /// Element index and local coordinate `t` in `[0, 1]` of `s`.
    /// Open bases clamp `s` to `[0, L]`; periodic ones wrap it.
    #[inline]
    pub fn locate(&self, s: f64) -> (usize, f64) {
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
        cardinal_values(self.degree, t, values);
        e
    }

    /// Values and first and second derivatives at `s`.
    pub fn eval_derivs(&self, s: f64) -> BasisValues {
        let (e, t) = self.locate(s);
        let p = self.degree;
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

/// Power-basis coefficients of the `p + 1` uniform B-spline pieces on one
/// element: `N_k(t) = sum_m polys[k][m] t^m`, `t` in `[0, 1]`. Obtained by
/// running the Cox–de Boor recurrence of [`cardinal_values`] on polynomials,
/// so the coefficients are exact up to rounding.
#[allow(clippy::needless_range_loop)] // the indices mirror the recurrence
pub fn cardinal_polynomials(p: usize) -> [[f64; MAX_DEGREE + 1]; MAX_DEGREE + 1] {
    type Poly = [f64; MAX_DEGREE + 1];
    // (c0 + c1 t) * q
    fn mul_linear(q: &Poly, c0: f64, c1: f64) -> Poly {
        let mut out = [0.0; MAX_DEGREE + 1];
        for m in 0..=MAX_DEGREE {
            out[m] += c0 * q[m];
            if m < MAX_DEGREE {
                out[m + 1] += c1 * q[m];
            }
        }
        out
    }
    let mut n = [[0.0; MAX_DEGREE + 1]; MAX_DEGREE + 1];
    n[0][0] = 1.0;
    for j in 1..=p {
        let inv_j = 1.0 / j as f64;
        let mut saved = [0.0; MAX_DEGREE + 1];
        for r in 0..j {
            let temp: Poly = n[r].map(|c| c * inv_j);
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
