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
