//! Bases with repeated knots ("breaks"): the general knot vector behind
//! [`Basis::with_breaks`](super::Basis::with_breaks).
//!
//! # Layout
//! The breaks cut `[0, L]` into *segments* (for a closed basis the points
//! `0` and `L` always bound segments too, so the segment that wraps round
//! the start is two segments with a simple knot at `0` between them). Each
//! segment is split into uniform elements, as many as make them closest to
//! the target length `h`, at least one: every break falls exactly on an
//! element boundary, at the position asked for (no snapping), and elements
//! differ in length only from one segment to the next. Locating a parameter
//! is a search among the few segments and a division, so evaluation stays
//! cheap; a basis without breaks never comes here (the uniform path of
//! [`Basis`](super::Basis) is unchanged).
//!
//! # Knots and indices
//! `K` lists the knots in `[0, L]` (open: `0` and `L` once each) or `[0, L)`
//! (closed) with their multiplicities: a simple knot at every element
//! boundary, `m` copies at a break of multiplicity `m`. Function `i` has the
//! knots `knot(i - p) ..= knot(i + 1)`, where `knot(j)` extends `K` by the
//! end elements' lengths beyond the ends (open) or periodically (closed).
//! On the element that starts at `K[j]` (the last copy of a repeated knot)
//! the non-zero functions are `j ..= j + p`: the same contract as the
//! uniform basis (`first` and `p + 1` values), so that the band, the
//! correlation and the banded solver need no change. A uniform basis is the
//! special case `K[j] = j h`.
//!
//! A knot of multiplicity `m` leaves the functions `C^(p - m)` there:
//! `m = p` gives `C^0` (a curve with a corner: its tangent may break), and
//! `m = p + 1` (allowed too) makes the functions discontinuous: the
//! two sides are independent. The functions of one element are stored as
//! polynomials in the element's local coordinate `t` in `[0, 1]`, computed
//! once by the Cox–de Boor recurrence run on polynomials.

use super::{mul_linear, MAX_DEGREE};

/// Power-basis coefficients of the `p + 1` functions of one element.
pub(crate) type Pieces = [[f64; MAX_DEGREE + 1]; MAX_DEGREE + 1];

/// A repeated knot: where, and how many copies.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Break {
    /// Parameter of the knot, pixels.
    pub at: f64,
    /// Multiplicity, 1 to `p + 1` (`p`: a corner; `p + 1`: a jump).
    pub multiplicity: usize,
}

/// The general knot vector; see the [module documentation](self).
#[derive(Clone, Debug, PartialEq)]
pub(crate) struct Knotted {
    pub(crate) breaks: Vec<Break>,
    /// Start of each segment (increasing, the first is 0).
    seg_start: Vec<f64>,
    /// Element length of each segment.
    seg_h: Vec<f64>,
    /// First element of each segment, then the element count.
    seg_el0: Vec<usize>,
    /// Start and length of each element.
    pub(crate) el_start: Vec<f64>,
    pub(crate) el_len: Vec<f64>,
    /// First non-zero function on each element.
    pub(crate) el_first: Vec<usize>,
    /// `K` (see the module docs).
    knots: Vec<f64>,
    /// Per element, the `p + 1` functions as polynomials in `t`.
    pub(crate) pieces: Vec<Pieces>,
    pub(crate) n_functions: usize,
    length: f64,
    closed: bool,
}

impl Knotted {
    /// The layout for `breaks` (sorted, distinct, inside the range: checked
    /// by the caller) with elements of about `h` pixels.
    pub(crate) fn new(degree: usize, h: f64, length: f64, closed: bool, breaks: &[Break]) -> Self {
        let mut bounds = vec![0.0];
        bounds.extend(breaks.iter().map(|b| b.at).filter(|&a| a > 0.0));
        bounds.push(length);
        let multiplicity = |at: f64| {
            breaks
                .iter()
                .find(|b| b.at == at)
                .map_or(1, |b| b.multiplicity)
        };
        let (mut seg_start, mut seg_h, mut seg_el0) = (Vec::new(), Vec::new(), vec![0]);
        let (mut el_start, mut el_len, mut el_first, mut knots) =
            (Vec::new(), Vec::new(), Vec::new(), Vec::new());
        for w in bounds.windows(2) {
            let span = w[1] - w[0];
            let count = ((span / h).round() as usize).max(1);
            let step = span / count as f64;
            seg_start.push(w[0]);
            seg_h.push(step);
            for i in 0..count {
                // The segment's first element starts exactly at the break.
                let start = if i == 0 { w[0] } else { w[0] + i as f64 * step };
                let m = if i == 0 { multiplicity(w[0]) } else { 1 };
                knots.extend(std::iter::repeat_n(start, m));
                el_start.push(start);
                el_len.push(step);
                el_first.push(knots.len() - 1);
            }
            seg_el0.push(el_start.len());
        }
        if !closed {
            knots.push(length);
        }
        let n_functions = if closed {
            knots.len()
        } else {
            knots.len() + degree - 1
        };
        let mut k = Knotted {
            breaks: breaks.to_vec(),
            seg_start,
            seg_h,
            seg_el0,
            el_start,
            el_len,
            el_first,
            knots,
            pieces: Vec::new(),
            n_functions,
            length,
            closed,
        };
        k.pieces = (0..k.el_start.len())
            .map(|e| k.element_pieces(degree, e))
            .collect();
        k
    }

    /// Number of elements.
    pub(crate) fn n_elements(&self) -> usize {
        self.el_start.len()
    }

    /// The extended knot `knot(j)` (see the module docs).
    pub(crate) fn knot(&self, j: isize) -> f64 {
        let n = self.knots.len() as isize;
        if self.closed {
            let (q, r) = (j.div_euclid(n), j.rem_euclid(n));
            self.knots[r as usize] + q as f64 * self.length
        } else if j < 0 {
            self.knots[0] + j as f64 * self.el_len[0]
        } else if j >= n {
            let last = self.el_len[self.el_len.len() - 1];
            self.knots[(n - 1) as usize] + (j - n + 1) as f64 * last
        } else {
            self.knots[j as usize]
        }
    }

    /// Element and local coordinate of `s`, already clamped or wrapped into
    /// `[0, L]` by the caller.
    #[inline]
    pub(crate) fn locate(&self, s: f64) -> (usize, f64) {
        let k = self
            .seg_start
            .partition_point(|&x| x <= s)
            .saturating_sub(1);
        let count = self.seg_el0[k + 1] - self.seg_el0[k];
        let u = (s - self.seg_start[k]) / self.seg_h[k];
        let mut i = u.floor();
        if i >= count as f64 {
            i = (count - 1) as f64;
        }
        let i = if i.is_finite() && i > 0.0 {
            i as usize
        } else {
            0
        };
        (self.seg_el0[k] + i, u - i as f64)
    }

    /// The `p + 1` functions of element `e` as polynomials in `t`: the
    /// Cox–de Boor recurrence (The NURBS Book, A2.2) on polynomials, with
    /// `u = start + t len`.
    #[allow(clippy::needless_range_loop)] // the indices mirror the recurrence
    fn element_pieces(&self, p: usize, e: usize) -> Pieces {
        type Poly = [f64; MAX_DEGREE + 1];
        // (c0 + c1 t) * q
        let j = self.el_first[e] as isize;
        let (a, len) = (self.el_start[e], self.el_len[e]);
        let mut n: Pieces = [[0.0; MAX_DEGREE + 1]; MAX_DEGREE + 1];
        n[0][0] = 1.0;
        for d in 1..=p {
            let mut saved = [0.0; MAX_DEGREE + 1];
            for r in 0..d {
                // left[d - r] = u - knot(j + 1 - d + r),
                // right[r + 1] = knot(j + r + 1) - u.
                let lo = self.knot(j + 1 - d as isize + r as isize);
                let hi = self.knot(j + r as isize + 1);
                let temp: Poly = n[r].map(|c| c / (hi - lo));
                let right = mul_linear(&temp, hi - a, -len);
                for m in 0..=MAX_DEGREE {
                    n[r][m] = saved[m] + right[m];
                }
                saved = mul_linear(&temp, a - lo, len);
            }
            n[d] = saved;
        }
        n
    }

    /// Start and length of element `e`, pixels.
    pub(crate) fn bounds(&self, e: usize) -> (f64, f64) {
        (self.el_start[e], self.el_len[e])
    }
}

/// Value, first and second `t`-derivatives of a polynomial at `t` (Horner).
#[inline]
pub(crate) fn horner(c: &[f64; MAX_DEGREE + 1], p: usize, t: f64) -> (f64, f64, f64) {
    let (mut v, mut d1, mut d2) = (c[p], 0.0, 0.0);
    for m in (0..p).rev() {
        d2 = d2 * t + 2.0 * d1;
        d1 = d1 * t + v;
        v = v * t + c[m];
    }
    (v, d1, d2)
}
