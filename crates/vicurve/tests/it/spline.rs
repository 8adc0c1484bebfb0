//! B-spline basis against an independent oracle (the truncated-power formula
//! of the cardinal B-spline), partition of unity, derivatives against finite
//! differences.

use proptest::prelude::*;
use vicurve::spline::{Basis, MAX_DEGREE};

/// Cardinal B-spline of degree p on [0, p+1]:
/// (1/p!) sum_j (-1)^j C(p+1, j) (x - j)_+^p.
fn cardinal(p: usize, x: f64) -> f64 {
    let mut fact = 1.0;
    for k in 1..=p {
        fact *= k as f64;
    }
    let mut sum = 0.0;
    let mut binom = 1.0;
    for j in 0..=p + 1 {
        let t = x - j as f64;
        if t > 0.0 {
            let sign = if j % 2 == 0 { 1.0 } else { -1.0 };
            sum += sign * binom * t.powi(p as i32);
        }
        binom = binom * (p + 1 - j) as f64 / (j + 1) as f64;
    }
    sum / fact
}

/// N_i(s) by the oracle: function i is the cardinal spline starting at (i-p)h
/// (and its periodic copies).
fn oracle(basis: &Basis, i: usize, s: f64) -> f64 {
    let p = basis.degree();
    let h = basis.element_length();
    let x = (s - (i as f64 - p as f64) * h) / h;
    if basis.is_closed() {
        let n = basis.n_elements() as f64;
        (-2..=2)
            .map(|m| {
                let xm = x + m as f64 * n;
                if (0.0..=(p + 1) as f64).contains(&xm) {
                    cardinal(p, xm)
                } else {
                    0.0
                }
            })
            .sum::<f64>()
    } else if (0.0..=(p + 1) as f64).contains(&x) {
        cardinal(p, x)
    } else {
        0.0
    }
}

fn basis_strategy() -> impl Strategy<Value = (Basis, f64)> {
    (
        1usize..=MAX_DEGREE,
        1usize..30,
        1.0f64..500.0,
        any::<bool>(),
        0.0f64..1.0,
    )
        .prop_filter_map("closed bases need n_el > p", |(p, n, l, closed, t)| {
            Basis::new(p, n, l, closed).ok().map(|b| (b, t * l))
        })
}

proptest! {
    #[test]
    fn values_match_the_truncated_power_oracle((basis, s) in basis_strategy()) {
        let mut v = [0.0; MAX_DEGREE + 1];
        let first = basis.eval(s, &mut v);
        let p = basis.degree();
        let mut dense = vec![0.0; basis.n_functions()];
        for k in 0..=p {
            dense[basis.index(first, k)] += v[k];
        }
        for (i, d) in dense.iter().enumerate() {
            let o = oracle(&basis, i, s);
            prop_assert!((d - o).abs() < 1e-9, "N_{i}({s}) = {d}, oracle {o}");
        }
    }

    #[test]
    fn partition_of_unity((basis, s) in basis_strategy()) {
        let mut v = [0.0; MAX_DEGREE + 1];
        basis.eval(s, &mut v);
        let sum: f64 = v[..=basis.degree()].iter().sum();
        prop_assert!((sum - 1.0).abs() < 1e-12);
        prop_assert!(v[..=basis.degree()].iter().all(|x| *x >= -1e-15));
    }

    #[test]
    fn derivatives_match_finite_differences((basis, s) in basis_strategy()) {
        let h = basis.element_length();
        // Stay inside one element (derivatives jump at knots for low degrees).
        let (e, t) = basis.locate(s);
        let t = t.clamp(0.1, 0.9);
        let s = (e as f64 + t) * h;
        let d = basis.eval_derivs(s);
        let eps = 1e-4 * h;
        let lo = basis.eval_derivs(s - eps);
        let hi = basis.eval_derivs(s + eps);
        for k in 0..=basis.degree() {
            let fd1 = (hi.value[k] - lo.value[k]) / (2.0 * eps);
            prop_assert!((fd1 - d.d1[k]).abs() < 1e-6 / h, "d1 {k}: {fd1} vs {}", d.d1[k]);
            if basis.degree() >= 2 {
                let fd2 = (hi.d1[k] - lo.d1[k]) / (2.0 * eps);
                prop_assert!((fd2 - d.d2[k]).abs() < 1e-5 / (h * h), "d2 {k}: {fd2} vs {}", d.d2[k]);
            }
        }
    }
}

proptest! {
    /// The uniform second difference of `eval_d2` against `eval_derivs`
    /// (itself checked against finite differences above), plain and broken
    /// bases alike.
    #[test]
    fn second_derivatives_alone_match_eval_derivs((basis, s) in basis_strategy()) {
        check_d2(&basis, s)?;
    }

    #[test]
    fn broken_second_derivatives_alone_match((basis, s) in broken_strategy()) {
        check_d2(&basis, s)?;
    }
}

fn check_d2(basis: &Basis, s: f64) -> Result<(), TestCaseError> {
    let mut d2 = [f64::NAN; MAX_DEGREE + 1];
    let first = basis.eval_d2(s, &mut d2);
    let d = basis.eval_derivs(s);
    prop_assert_eq!(first, d.first);
    let scale = 1.0 / basis.element_length().powi(2);
    for (k, (a, b)) in d2.iter().zip(&d.d2).take(basis.degree() + 1).enumerate() {
        prop_assert!((a - b).abs() <= 1e-12 * scale, "{k}: {a} vs {b}");
    }
    Ok(())
}

#[test]
fn counts_and_knots() {
    let open = Basis::new(3, 10, 100.0, false).unwrap();
    assert_eq!(open.n_functions(), 13);
    assert_eq!(open.knots().len(), 10 + 2 * 3 + 1);
    assert_eq!(open.knots()[3], 0.0);
    let closed = Basis::new(3, 10, 100.0, true).unwrap();
    assert_eq!(closed.n_functions(), 10);
    assert_eq!(closed.index(8, 3), 1);
}

#[test]
fn invalid_bases_are_errors() {
    assert!(Basis::new(0, 10, 1.0, false).is_err());
    assert!(Basis::new(6, 10, 1.0, false).is_err());
    assert!(Basis::new(3, 0, 1.0, false).is_err());
    assert!(Basis::new(3, 3, 1.0, true).is_err());
    assert!(Basis::new(3, 4, f64::NAN, true).is_err());
    assert!(Basis::new(3, 4, -1.0, false).is_err());
}

// ---------------------------------------------------------------------------
// Bases with breaks (repeated knots): against an independent Cox–de Boor
// evaluation on the explicit knot vector `Basis::knots`.

use vicurve::spline::Break;

/// `N_{i,p}(s)` on the explicit knot vector `xi` by the recursive
/// definition (half-open spans; 0/0 taken as 0).
fn cox_de_boor(xi: &[f64], i: usize, p: usize, s: f64) -> f64 {
    if p == 0 {
        return if xi[i] <= s && s < xi[i + 1] {
            1.0
        } else {
            0.0
        };
    }
    let mut out = 0.0;
    let d0 = xi[i + p] - xi[i];
    if d0 > 0.0 {
        out += (s - xi[i]) / d0 * cox_de_boor(xi, i, p - 1, s);
    }
    let d1 = xi[i + p + 1] - xi[i + 1];
    if d1 > 0.0 {
        out += (xi[i + p + 1] - s) / d1 * cox_de_boor(xi, i + 1, p - 1, s);
    }
    out
}

/// Function `i` of `basis` at `s` from its knot vector: for a closed basis
/// the unwrapped vector, on which functions `i` and `i + n` (`i < p`) are
/// the same periodic function.
fn knot_oracle(basis: &Basis, i: usize, s: f64) -> f64 {
    let xi = basis.knots();
    let p = basis.degree();
    let n = basis.n_functions();
    let mut v = cox_de_boor(&xi, i, p, s);
    if basis.is_closed() && i < p {
        v += cox_de_boor(&xi, i + n, p, s);
    }
    v
}

fn broken_strategy() -> impl Strategy<Value = (Basis, f64)> {
    (
        1usize..=MAX_DEGREE,
        1usize..30,
        1.0f64..500.0,
        any::<bool>(),
        prop::collection::vec((0.0f64..1.0, 0usize..=MAX_DEGREE), 1..4),
        0.0f64..1.0,
    )
        .prop_filter_map("valid breaks", |(p, n, l, closed, raw, t)| {
            let mut breaks: Vec<Break> = raw
                .iter()
                .map(|&(f, m)| Break {
                    at: if closed { f * l } else { (0.01 + 0.98 * f) * l },
                    multiplicity: 1 + m % (p + 1),
                })
                .collect();
            breaks.sort_by(|a, b| a.at.total_cmp(&b.at));
            if breaks.windows(2).any(|w| w[1].at - w[0].at < 1e-3 * l) {
                return None;
            }
            Basis::with_breaks(p, n, l, closed, &breaks)
                .ok()
                .map(|b| (b, t * l * 0.999_999))
        })
}

/// The values of all functions at `s` as a dense vector.
fn dense(basis: &Basis, first: usize, v: &[f64]) -> Vec<f64> {
    let mut out = vec![0.0; basis.n_functions()];
    for (k, x) in v.iter().enumerate().take(basis.degree() + 1) {
        out[basis.index(first, k)] += x;
    }
    out
}

proptest! {
    #[test]
    fn broken_values_match_cox_de_boor((basis, s) in broken_strategy()) {
        let mut v = [0.0; MAX_DEGREE + 1];
        let first = basis.eval(s, &mut v);
        for (i, d) in dense(&basis, first, &v).iter().enumerate() {
            let o = knot_oracle(&basis, i, s);
            prop_assert!((d - o).abs() < 1e-9, "N_{i}({s}) = {d}, oracle {o}, knots {:?}", basis.knots());
        }
    }

    #[test]
    fn broken_partition_of_unity((basis, s) in broken_strategy()) {
        let mut v = [0.0; MAX_DEGREE + 1];
        basis.eval(s, &mut v);
        let sum: f64 = v[..=basis.degree()].iter().sum();
        prop_assert!((sum - 1.0).abs() < 1e-12);
        prop_assert!(v[..=basis.degree()].iter().all(|x| *x >= -1e-14));
    }

    #[test]
    fn broken_derivatives_match_finite_differences((basis, s) in broken_strategy()) {
        let (e, t) = basis.locate(s);
        let (start, len) = basis.element_bounds(e);
        let s = start + t.clamp(0.1, 0.9) * len;
        let d = basis.eval_derivs(s);
        let eps = 1e-4 * len;
        let lo = basis.eval_derivs(s - eps);
        let hi = basis.eval_derivs(s + eps);
        prop_assert_eq!(lo.first, d.first);
        prop_assert_eq!(hi.first, d.first);
        for k in 0..=basis.degree() {
            let fd1 = (hi.value[k] - lo.value[k]) / (2.0 * eps);
            prop_assert!((fd1 - d.d1[k]).abs() < 1e-6 / len, "d1 {k}: {fd1} vs {}", d.d1[k]);
            if basis.degree() >= 2 {
                let fd2 = (hi.d1[k] - lo.d1[k]) / (2.0 * eps);
                prop_assert!((fd2 - d.d2[k]).abs() < 1e-5 / (len * len), "d2 {k}: {fd2} vs {}", d.d2[k]);
            }
        }
    }

    /// At a knot of multiplicity m the functions are C^(p - m): derivatives
    /// of order up to p - m agree from both sides, and (when that order is
    /// one we evaluate) the next one jumps for some function.
    #[test]
    fn continuity_at_a_break((basis, _s) in broken_strategy()) {
        let p = basis.degree();
        for b in basis.breaks() {
            let (el, tl) = basis.locate_left(b.at);
            let left = basis.eval_derivs_at(el, tl);
            let right = basis.eval_derivs(b.at);
            let (h, _) = (basis.element_bounds(el).1, ());
            let orders = [
                (dense(&basis, left.first, &left.value), dense(&basis, right.first, &right.value), 1.0),
                (dense(&basis, left.first, &left.d1), dense(&basis, right.first, &right.d1), 1.0 / h),
                (dense(&basis, left.first, &left.d2), dense(&basis, right.first, &right.d2), 1.0 / (h * h)),
            ];
            for (order, (l, r, scale)) in orders.iter().enumerate() {
                if order == 2 && p < 2 {
                    continue;
                }
                let jump = l.iter().zip(r).map(|(a, b)| (a - b).abs()).fold(0.0, f64::max);
                if order + b.multiplicity <= p {
                    prop_assert!(jump < 1e-8 * scale.max(1.0), "order {order} jumps by {jump} at m = {}", b.multiplicity);
                } else if order + b.multiplicity == p + 1 {
                    prop_assert!(jump > 1e-6 * scale, "order {order} continuous at m = {}", b.multiplicity);
                }
            }
        }
    }
}

#[test]
fn breaks_fall_on_element_boundaries() {
    let b = Basis::with_breaks(
        3,
        10,
        100.0,
        false,
        &[Break {
            at: 37.0,
            multiplicity: 3,
        }],
    )
    .unwrap();
    // 37 px in 4 elements, 63 px in 6: 10 elements, 2 extra functions.
    assert_eq!(b.n_elements(), 10);
    assert_eq!(b.n_functions(), 10 + 3 + 2);
    assert_eq!(b.knots().iter().filter(|&&k| k == 37.0).count(), 3);
    let (e, t) = b.locate(37.0);
    assert_eq!((b.element_bounds(e).0, t), (37.0, 0.0));
    // A corner: only one function is non-zero at the break.
    let mut v = [0.0; MAX_DEGREE + 1];
    b.eval(37.0, &mut v);
    assert!((v[0] - 1.0).abs() < 1e-14, "{v:?}");
    // Without breaks, the uniform basis.
    assert_eq!(
        Basis::with_breaks(3, 10, 100.0, false, &[]).unwrap(),
        Basis::new(3, 10, 100.0, false).unwrap()
    );
}

#[test]
fn invalid_breaks_are_errors() {
    let at = |at: f64, multiplicity: usize| Break { at, multiplicity };
    assert!(Basis::with_breaks(3, 10, 100.0, false, &[at(0.0, 3)]).is_err());
    assert!(Basis::with_breaks(3, 10, 100.0, false, &[at(100.0, 3)]).is_err());
    assert!(Basis::with_breaks(3, 10, 100.0, true, &[at(100.0, 3)]).is_err());
    assert!(Basis::with_breaks(3, 10, 100.0, true, &[at(0.0, 3)]).is_ok());
    assert!(Basis::with_breaks(3, 10, 100.0, false, &[at(f64::NAN, 3)]).is_err());
    assert!(Basis::with_breaks(3, 10, 100.0, false, &[at(50.0, 5)]).is_err());
    assert!(Basis::with_breaks(3, 10, 100.0, false, &[at(50.0, 0)]).is_err());
    assert!(Basis::with_breaks(3, 10, 100.0, false, &[at(50.0, 3), at(50.0, 2)]).is_err());
}
