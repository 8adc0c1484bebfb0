//! Knot insertion (Boehm's algorithm) and the knots of an h-refinement.
//!
//! Inserting a knot adds one control point and changes none of the curve's
//! points: the new control points are convex combinations of `p` pairs of
//! neighbours (Piegl & Tiller A5.1 with one insertion). Working on
//! homogeneous points `[w x, w y, w]` makes the same routine valid for
//! rational curves and surfaces, which is how [`crate::nurbs::patch`] uses
//! it.

use super::basis::multiplicity;
use crate::error::{Error, Result};

/// Insert `u` once into the knot vector of a curve of degree `p` with
/// control points `ctrl` (`knots.len() == ctrl.len() + p + 1`). The
/// geometry is unchanged.
///
/// Errors ([`Error::InvalidParameter`]): `u` outside the domain
/// `[U_p, U_n]` or not finite, or already of multiplicity `p` inside the
/// domain (one more would break the curve) or `p + 1` at its ends.
pub fn insert_knot<const D: usize>(
    p: usize,
    knots: &mut Vec<f64>,
    ctrl: &mut Vec<[f64; D]>,
    u: f64,
) -> Result<()> {
    let n = ctrl.len();
    debug_assert_eq!(knots.len(), n + p + 1);
    let (a, b) = (knots[p], knots[n]);
    if !(u.is_finite() && u >= a && u <= b) {
        return Err(Error::invalid(
            "knot to insert",
            format!("{u} is outside the domain [{a}, {b}]"),
        ));
    }
    let s = multiplicity(knots, u);
    let limit = if u > a && u < b { p } else { p + 1 };
    if s >= limit {
        return Err(Error::invalid(
            "knot to insert",
            format!("{u} already has multiplicity {s} (at most {limit} here)"),
        ));
    }
    // k: the last index with U_k <= u, kept below the last knot so that
    // the right end of the domain is handled like any knot.
    let k = knots
        .iter()
        .rposition(|&t| t <= u)
        .unwrap_or(0)
        .min(knots.len() - 2);
    // The points k - p + 1 ..= k - s change; an index below 0 cannot occur
    // for u in the domain (k >= p), but the guard keeps it panic-free.
    let first = (k + 1).saturating_sub(p);
    let last = k.saturating_sub(s);
    let mut out = Vec::with_capacity(n + 1);
    out.extend_from_slice(&ctrl[..first.min(n)]);
    for i in first..=last {
        let denom = knots[i + p] - knots[i];
        let alpha = if denom > 0.0 {
            (u - knots[i]) / denom
        } else {
            0.0
        };
        let (pi, pm) = (ctrl[i.min(n - 1)], ctrl[i.saturating_sub(1)]);
        let mut q = [0.0; D];
        for d in 0..D {
            q[d] = alpha * pi[d] + (1.0 - alpha) * pm[d];
        }
        out.push(q);
    }
    out.extend_from_slice(&ctrl[last.min(n)..]);
    knots.insert(k + 1, u);
    *ctrl = out;
    Ok(())
}

/// Insert `u` as many times as needed to reach multiplicity `m` (no-op
/// when it is already there).
pub fn insert_to_multiplicity<const D: usize>(
    p: usize,
    knots: &mut Vec<f64>,
    ctrl: &mut Vec<[f64; D]>,
    u: f64,
    m: usize,
) -> Result<()> {
    while multiplicity(knots, u) < m {
        insert_knot(p, knots, ctrl, u)?;
    }
    Ok(())
}

/// The knots that split every non-empty span of `[knots[p], knots[n]]`
/// into `parts` equal spans (`parts - 1` new knots per span; none for
/// `parts <= 1`): the knots of a uniform h-refinement.
pub fn split_spans(p: usize, knots: &[f64], n: usize, parts: usize) -> Vec<f64> {
    let mut new = Vec::new();
    if parts <= 1 {
        return new;
    }
    for w in knots[p..=n].windows(2) {
        let (a, b) = (w[0], w[1]);
        if b > a {
            for j in 1..parts {
                new.push(a + (b - a) * j as f64 / parts as f64);
            }
        }
    }
    new
}

#[cfg(test)]
mod tests {
    use super::*;

    fn eval(p: usize, knots: &[f64], ctrl: &[[f64; 1]], u: f64) -> f64 {
        let n = ctrl.len();
        let k = super::super::basis::find_span(p, knots, n, u);
        let v = super::super::basis::basis_funs(k, u, p, knots);
        (0..=p).map(|j| v[j] * ctrl[k - p + j][0]).sum()
    }

    #[test]
    fn insertion_keeps_the_function() {
        let p = 3;
        let mut knots: Vec<f64> = (0..12).map(|i| i as f64 - 3.0).collect();
        let mut ctrl: Vec<[f64; 1]> = (0..8).map(|i| [((i * 7) % 5) as f64]).collect();
        let (k0, c0) = (knots.clone(), ctrl.clone());
        for u in [0.0, 0.3, 2.0, 2.0, 5.0] {
            insert_knot(p, &mut knots, &mut ctrl, u).unwrap();
        }
        assert!(insert_knot(p, &mut knots, &mut ctrl, 2.0).is_err());
        assert!(insert_knot(p, &mut knots, &mut ctrl, 5.5).is_err());
        for i in 0..=100 {
            let u = 5.0 * i as f64 / 100.0;
            let d = eval(p, &k0, &c0, u) - eval(p, &knots, &ctrl, u);
            assert!(d.abs() < 1e-12, "u {u}: {d}");
        }
    }
}
