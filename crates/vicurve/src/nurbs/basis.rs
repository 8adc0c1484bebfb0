//! B-spline basis functions on a general (non-uniform) knot vector.
//!
//! The textbook algorithms (Piegl & Tiller, *The NURBS Book*, 2nd ed.,
//! A2.1 and A2.2): a knot vector `U` of `n + p + 1` non-decreasing values
//! carries `n` functions `N_{i,p}` of degree `p`, function `i` supported on
//! `[U_i, U_{i+p+1}]`; the *domain* of a curve on it is `[U_p, U_n]`,
//! where the functions sum to one.

use crate::error::{Error, Result};

/// Largest degree handled by [`crate::nurbs`]: far beyond what a measured
/// curve (degree 1 to 5) elevated across a patch needs, and small enough
/// that the per-point work stays trivial.
pub const MAX_DEGREE: usize = 12;

/// Check a knot vector for `n` functions of degree `p`: `n + p + 1` finite
/// non-decreasing values, `n >= p + 1`, a non-empty domain `[U_p, U_n]`,
/// no value repeated more than `p + 1` times and no value inside the domain
/// more than `p` times (the curve stays continuous).
///
/// Errors: [`Error::InvalidParameter`] for the degree,
/// [`Error::InvalidCurve`] for the rest, saying what is wrong.
pub fn check_knots(p: usize, knots: &[f64], n: usize) -> Result<()> {
    if !(1..=MAX_DEGREE).contains(&p) {
        return Err(Error::invalid(
            "degree",
            format!("{p} (must be 1 to {MAX_DEGREE})"),
        ));
    }
    let bad = |reason: String| Err(Error::InvalidCurve { reason });
    if n < p + 1 {
        return bad(format!(
            "{n} control points for degree {p} (need at least {})",
            p + 1
        ));
    }
    if knots.len() != n + p + 1 {
        return bad(format!(
            "{} knots for {n} control points of degree {p} (need {})",
            knots.len(),
            n + p + 1
        ));
    }
    if knots.iter().any(|k| !k.is_finite()) {
        return Err(Error::NonFinite {
            what: "knot vector".into(),
        });
    }
    if knots.windows(2).any(|w| w[1] < w[0]) {
        return bad("the knots are not in non-decreasing order".into());
    }
    let (a, b) = (knots[p], knots[n]);
    if b <= a {
        return bad(format!("empty parameter domain [{a}, {b}]"));
    }
    let mut i = 0;
    while i < knots.len() {
        let m = multiplicity(knots, knots[i]);
        let inside = knots[i] > a && knots[i] < b;
        if m > p + 1 || (inside && m > p) {
            return bad(format!(
                "knot {} repeated {m} times (at most {} {})",
                knots[i],
                if inside { p } else { p + 1 },
                if inside {
                    "inside the domain, so that the curve is continuous"
                } else {
                    "at the ends"
                }
            ));
        }
        i += m;
    }
    Ok(())
}

/// Number of knots equal to `u`.
pub fn multiplicity(knots: &[f64], u: f64) -> usize {
    knots.iter().filter(|&&k| k == u).count()
}

/// The span index `k` of `u` for `n` functions of degree `p`: `U_k <= u <
/// U_{k+1}` with `p <= k < n` and `U_k < U_{k+1}`. `u` is clamped to the
/// domain `[U_p, U_n]`; at its right end the last non-empty span is
/// returned. Assumes a knot vector that passed [`check_knots`].
pub fn find_span(p: usize, knots: &[f64], n: usize, u: f64) -> usize {
    let (a, b) = (knots[p], knots[n]);
    let u = if u.is_nan() { a } else { u.clamp(a, b) };
    if u >= b {
        let mut k = n - 1;
        while k > p && knots[k] >= b {
            k -= 1;
        }
        return k;
    }
    // Binary search for the last k in [p, n) with U_k <= u.
    let (mut lo, mut hi) = (p, n);
    while hi - lo > 1 {
        let mid = (lo + hi) / 2;
        if knots[mid] <= u {
            lo = mid;
        } else {
            hi = mid;
        }
    }
    lo
}

/// The `p + 1` functions `N_{k-p}, ..., N_k` that are non-zero on span `k`,
/// at `u` (the inverted triangle of Cox–de Boor, A2.2). `u` may be either
/// end of the span.
pub fn basis_funs(k: usize, u: f64, p: usize, knots: &[f64]) -> Vec<f64> {
    let mut n = vec![0.0; p + 1];
    let mut left = vec![0.0; p + 1];
    let mut right = vec![0.0; p + 1];
    n[0] = 1.0;
    for j in 1..=p {
        left[j] = u - knots[k + 1 - j];
        right[j] = knots[k + j] - u;
        let mut saved = 0.0;
        for r in 0..j {
            let denom = right[r + 1] + left[j - r];
            let temp = if denom != 0.0 { n[r] / denom } else { 0.0 };
            n[r] = saved + right[r + 1] * temp;
            saved = left[j - r] * temp;
        }
        n[j] = saved;
    }
    n
}

/// Greville abscissae `(U_{i+1} + ... + U_{i+p}) / p`, `i = 0..n`: the
/// parameters "belonging" to each control point, where a collocation
/// matrix is well conditioned.
pub fn greville(p: usize, knots: &[f64], n: usize) -> Vec<f64> {
    (0..n)
        .map(|i| knots[i + 1..=i + p].iter().sum::<f64>() / p as f64)
        .collect()
}

/// The distinct knot values in `(a, b)` with their multiplicities.
pub fn interior_knots(knots: &[f64], a: f64, b: f64) -> Vec<(f64, usize)> {
    let mut out: Vec<(f64, usize)> = Vec::new();
    for &k in knots.iter().filter(|&&k| k > a && k < b) {
        match out.last_mut() {
            Some((v, m)) if *v == k => *m += 1,
            _ => out.push((k, 1)),
        }
    }
    out
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn partition_of_unity_on_a_nonuniform_vector() {
        let knots = [0.0, 0.0, 0.0, 1.0, 2.5, 2.5, 4.0, 4.0, 4.0];
        check_knots(2, &knots, 6).unwrap();
        for i in 0..=40 {
            let u = 4.0 * i as f64 / 40.0;
            let k = find_span(2, &knots, 6, u);
            assert!(knots[k] <= u && (u < knots[k + 1] || u == 4.0));
            let s: f64 = basis_funs(k, u, 2, &knots).iter().sum();
            assert!((s - 1.0).abs() < 1e-14);
        }
    }

    #[test]
    fn rejects_bad_vectors() {
        assert!(check_knots(2, &[0.0, 0.0, 1.0, 1.0, 1.0], 2).is_err());
        assert!(check_knots(1, &[0.0, 1.0, 0.5, 2.0], 2).is_err());
        assert!(check_knots(1, &[0.0, 0.0, 0.5, 0.5, 0.5, 1.0, 1.0], 5).is_err());
        assert!(check_knots(1, &[0.0, f64::NAN, 1.0], 1).is_err());
    }
}
