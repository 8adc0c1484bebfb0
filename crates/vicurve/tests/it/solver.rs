//! Tests of the banded SPD solver against a dense reference.

use proptest::prelude::*;
use vicurve::solver::{BandCholesky, DenseCholesky, SolverError, SymBandMatrix};

/// Whether (i, j) is in the pattern, written from the definition.
fn in_pattern(n: usize, p: usize, cyclic: bool, i: usize, j: usize) -> bool {
    let d = i.abs_diff(j);
    if cyclic {
        d.min(n - d) <= p
    } else {
        d <= p
    }
}

/// A random diagonally dominant (hence SPD) matrix, as a band matrix and as a
/// dense one built independently.
fn build(
    n: usize,
    p: usize,
    cyclic: bool,
    off: &[f64],
    margin: &[f64],
) -> (SymBandMatrix, Vec<f64>) {
    let mut m = SymBandMatrix::zeros(n, p, cyclic).unwrap();
    let mut d = vec![0.0; n * n];
    for i in 0..n {
        for j in 0..i {
            if in_pattern(n, p, cyclic, i, j) {
                let v = off[i * n + j];
                m.add(i, j, v);
                d[i * n + j] += v;
                d[j * n + i] += v;
            }
        }
    }
    for i in 0..n {
        let row: f64 = (0..n).filter(|&j| j != i).map(|j| d[i * n + j].abs()).sum();
        let v = row + margin[i];
        m.add(i, i, v);
        d[i * n + i] = v;
    }
    (m, d)
}

fn matrix_case() -> impl Strategy<Value = (usize, usize, bool, Vec<f64>, Vec<f64>, Vec<f64>)> {
    (1..=60usize, 0..=5usize, any::<bool>()).prop_flat_map(|(n, p, c)| {
        (
            Just(n),
            Just(p),
            Just(c),
            prop::collection::vec(-1.0..1.0f64, n * n),
            prop::collection::vec(0.05..2.0f64, n),
            prop::collection::vec(-10.0..10.0f64, n),
        )
    })
}

/// The index of a NotPositiveDefinite error, None for anything else.
fn failed_pivot(r: Result<(), SolverError>) -> Option<usize> {
    match r {
        Err(SolverError::NotPositiveDefinite { index }) => Some(index),
        _ => None,
    }
}

fn max_abs(v: &[f64]) -> f64 {
    v.iter().fold(0.0, |a, b| a.max(b.abs()))
}

fn dense_mul(d: &[f64], x: &[f64]) -> Vec<f64> {
    let n = x.len();
    (0..n)
        .map(|i| (0..n).map(|j| d[i * n + j] * x[j]).sum())
        .collect()
}

proptest! {
    #![proptest_config(ProptestConfig::with_cases(200))]

    /// Outer products of consecutive (wrapping) indices, as B-spline
    /// assemblies add them, against a dense matrix summed from the
    /// definition, on top of a random matrix.
    #[test]
    fn add_outer_matches_dense(
        (n, p, c, off, margin, x) in matrix_case(),
        blocks in prop::collection::vec((0..60usize, 0..=5usize, -3.0..3.0f64), 1..8),
    ) {
        let (mut m, mut d) = build(n, p, c, &off, &margin);
        for (first, len, scale) in blocks {
            // A block in the pattern: at most p + 1 long, within an open
            // matrix's rows.
            let len = len.min(p.min(n - 1)) + 1;
            let first = if c { first % n } else { first % (n - len + 1) };
            let v: Vec<f64> = (0..len).map(|k| x[(first + 3 * k) % n] * 0.1 + 0.5).collect();
            m.add_outer(first, scale, &v);
            for a in 0..len {
                for b in 0..len {
                    d[((first + a) % n) * n + (first + b) % n] += scale * v[a] * v[b];
                }
            }
        }
        let got = m.to_dense();
        for (g, want) in got.iter().zip(&d) {
            prop_assert!((g - want).abs() <= 1e-12 * (1.0 + want.abs()), "{} vs {}", g, want);
        }
    }

    #[test]
    fn storage_matches_dense((n, p, c, off, margin, x) in matrix_case()) {
        let (m, d) = build(n, p, c, &off, &margin);
        prop_assert_eq!(m.n(), n);
        prop_assert_eq!(m.half_bandwidth(), p);
        prop_assert_eq!(m.is_cyclic(), c);
        prop_assert_eq!(m.to_dense(), d.clone());
        for i in 0..n {
            for j in 0..n {
                prop_assert_eq!(m.get(i, j), d[i * n + j]);
                prop_assert_eq!(m.in_pattern(i, j), in_pattern(n, p, c, i, j));
            }
        }
        let mut y = vec![f64::NAN; n];
        m.mul_vec(&x, &mut y);
        let yd = dense_mul(&d, &x);
        let scale = max_abs(&yd).max(1.0);
        for (a, b) in y.iter().zip(&yd) {
            prop_assert!((a - b).abs() <= 1e-12 * scale, "{} vs {}", a, b);
        }
    }

    #[test]
    fn factor_and_solve_match_dense((n, p, c, off, margin, b) in matrix_case()) {
        let (m, d) = build(n, p, c, &off, &margin);
        let f = BandCholesky::factor(&m).unwrap();
        let fd = DenseCholesky::factor(&d, n).unwrap();
        prop_assert_eq!(f.n(), n);

        // L L^T = M, and L is the (unique) Cholesky factor of the dense oracle.
        let l = f.to_dense_factor();
        let scale = max_abs(&d);
        for i in 0..n {
            for j in 0..n {
                let llt: f64 = (0..n).map(|k| l[i * n + k] * l[j * n + k]).sum();
                prop_assert!((llt - d[i * n + j]).abs() <= 1e-12 * scale);
                prop_assert!((l[i * n + j] - fd.factor_matrix()[i * n + j]).abs() <= 1e-12 * scale.sqrt());
            }
        }
        // The claimed shape: banded except for the last p rows of a cyclic
        // matrix (a tiny cyclic matrix, n <= 2p + 1, is full anyway).
        let arrow = match (c, n > 2 * p + 1) {
            (false, _) => 0,
            (true, true) => p,
            (true, false) => n,
        };
        for i in 0..n - arrow {
            for j in 0..i.saturating_sub(p) {
                prop_assert_eq!(l[i * n + j], 0.0);
            }
        }

        let mut x = b.clone();
        f.solve_in_place(&mut x);
        let mut xd = b.clone();
        fd.solve_in_place(&mut xd);
        let norm = xd.iter().map(|v| v * v).sum::<f64>().sqrt().max(1e-300);
        let err = x.iter().zip(&xd).map(|(a, b)| (a - b) * (a - b)).sum::<f64>().sqrt();
        prop_assert!(err <= 1e-9 * norm, "relative error {}", err / norm);
        // And it is a solution: residual small.
        let r = dense_mul(&d, &x);
        for (ri, bi) in r.iter().zip(&b) {
            prop_assert!((ri - bi).abs() <= 1e-9 * max_abs(&b).max(1.0));
        }
    }

    #[test]
    fn inverse_quadratic_form_matches_dense_inverse(
        (n, p, c, off, margin, _b) in matrix_case(),
        first in 0..100usize,
        values in prop::collection::vec(-2.0..2.0f64, 0..8),
    ) {
        let (m, d) = build(n, p, c, &off, &margin);
        let f = BandCholesky::factor(&m).unwrap();
        let inv = DenseCholesky::factor(&d, n).unwrap().inverse();
        let mut x = vec![0.0; n];
        for (k, v) in values.iter().enumerate() {
            x[(first + k) % n] += v;
        }
        let expected: f64 = (0..n)
            .flat_map(|i| (0..n).map(move |j| (i, j)))
            .map(|(i, j)| x[i] * inv[i * n + j] * x[j])
            .sum();
        // A longer scratch is allowed, and its content does not matter.
        let mut scratch = vec![f64::NAN; n + 3];
        let got = f.inverse_quadratic_form(first, &values, &mut scratch);
        let scale: f64 = x.iter().map(|v| v * v).sum::<f64>() * max_abs(&inv).max(1e-300);
        prop_assert!((got - expected).abs() <= 1e-10 * scale.max(1e-300), "{} vs {}", got, expected);
        prop_assert!(got >= 0.0);
    }

    #[test]
    fn inverse_band_matches_dense_inverse(
        (n, p, c, off, margin, _b) in matrix_case(),
        first in 0..100usize,
        values in prop::collection::vec(-2.0..2.0f64, 1..8),
    ) {
        let (m, d) = build(n, p, c, &off, &margin);
        let f = BandCholesky::factor(&m).unwrap();
        let inv = DenseCholesky::factor(&d, n).unwrap().inverse();
        let scale = max_abs(&inv).max(1e-300);
        // The band asked for may be wider or narrower than the matrix's.
        let q = values.len() - 1;
        let w = 2 * q + 1;
        let band = f.inverse_band(q, c);
        prop_assert_eq!(band.len(), n * w);
        for i in 0..n {
            for k in 0..w {
                let j = i as isize + k as isize - q as isize;
                let expected = if c {
                    inv[i * n + j.rem_euclid(n as isize) as usize]
                } else if (0..n as isize).contains(&j) {
                    inv[i * n + j as usize]
                } else {
                    0.0
                };
                prop_assert!((band[i * w + k] - expected).abs() <= 1e-10 * scale,
                    "({}, {}): {} vs {}", i, j, band[i * w + k], expected);
            }
        }
        // The quadratic form of consecutive values from the band, as
        // `Correlation::position_sigma` takes it, is the substitution's.
        if c || first + q < n {
            let idx = |k: usize| (first + k) % n;
            let mut got = 0.0;
            for (k, vk) in values.iter().enumerate() {
                for (l, vl) in values.iter().enumerate() {
                    got += vk * vl * band[idx(k) * w + l + q - k];
                }
            }
            let mut scratch = vec![0.0; n];
            let expected = f.inverse_quadratic_form(first, &values, &mut scratch);
            let norm: f64 = values.iter().map(|v| v * v).sum::<f64>() * scale;
            prop_assert!((got - expected).abs() <= 1e-10 * norm * values.len() as f64,
                "{} vs {}", got, expected);
        }
    }

    /// The band of the matrix's own width (what `position_sigma` asks
    /// for), taken by selected inversion, is the dense inverse's, open,
    /// cyclic and tiny cyclic alike.
    #[test]
    fn the_selected_inverse_is_the_dense_inverse((n, p, c, off, margin, _b) in matrix_case()) {
        let (m, d) = build(n, p, c, &off, &margin);
        let f = BandCholesky::factor(&m).unwrap();
        let inv = DenseCholesky::factor(&d, n).unwrap().inverse();
        let scale = max_abs(&inv).max(1e-300);
        let w = 2 * p + 1;
        let band = f.inverse_band(p, c);
        for i in 0..n {
            for k in 0..w {
                let j = i as isize + k as isize - p as isize;
                let expected = match (c, usize::try_from(j)) {
                    (true, _) => inv[i * n + j.rem_euclid(n as isize) as usize],
                    (false, Ok(j)) if j < n => inv[i * n + j],
                    _ => 0.0,
                };
                prop_assert!((band[i * w + k] - expected).abs() <= 1e-10 * scale,
                    "({}, {}): {} vs {}", i, j, band[i * w + k], expected);
            }
        }
    }

    #[test]
    fn negative_diagonal_is_reported((n, p, c, off, margin, _b) in matrix_case(), k in 0..60usize) {
        let k = k % n;
        let (mut m, mut d) = build(n, p, c, &off, &margin);
        let dk = d[k * n + k];
        m.add(k, k, -dk - 0.5);
        d[k * n + k] = -0.5;
        // The leading k x k block is still SPD, so the pivot k is the first
        // to fail: both solvers must name it.
        prop_assert_eq!(failed_pivot(BandCholesky::factor(&m).map(|_| ())), Some(k));
        prop_assert_eq!(failed_pivot(DenseCholesky::factor(&d, n).map(|_| ())), Some(k));
    }

    #[test]
    fn zero_row_is_reported((n, p, c, off, margin, _b) in matrix_case(), k in 0..60usize) {
        let k = k % n;
        let (mut m, _) = build(n, p, c, &off, &margin);
        for j in 0..n {
            if in_pattern(n, p, c, k, j) {
                let v = m.get(k, j);
                m.add(k, j, -v);
            }
        }
        prop_assert!((0..n).all(|j| m.get(k, j) == 0.0 && m.get(j, k) == 0.0));
        prop_assert_eq!(failed_pivot(BandCholesky::factor(&m).map(|_| ())), Some(k));
    }
}

/// The 1-D Laplacian with free ends (open) or periodic (cyclic): positive
/// semi-definite with the constant vector in its kernel. The last pivot is
/// pure rounding noise and must be reported.
#[test]
fn singular_laplacian_is_reported() {
    for cyclic in [false, true] {
        for n in [3usize, 4, 10, 57] {
            let mut m = SymBandMatrix::zeros(n, 1, cyclic).unwrap();
            let last = if cyclic { n } else { n - 1 };
            for e in 0..last {
                let (a, b) = (e, (e + 1) % n);
                m.add(a, a, 1.0);
                m.add(b, b, 1.0);
                m.add(a, b, -1.0);
            }
            let r = BandCholesky::factor(&m);
            assert!(
                matches!(r, Err(SolverError::NotPositiveDefinite { index }) if index == n - 1),
                "n={n} cyclic={cyclic}: {r:?}"
            );
            let r = DenseCholesky::factor(&m.to_dense(), n);
            assert!(matches!(r, Err(SolverError::NotPositiveDefinite { index }) if index == n - 1));
        }
    }
}

#[test]
fn non_finite_entries_are_reported() {
    let mut m = SymBandMatrix::zeros(5, 1, false).unwrap();
    for i in 0..5 {
        m.add(i, i, 4.0);
    }
    m.add(3, 2, f64::NAN);
    assert!(matches!(
        BandCholesky::factor(&m),
        Err(SolverError::NotPositiveDefinite { index: 3 })
    ));
    m.fill_zero();
    for i in 0..5 {
        m.add(i, i, 4.0);
    }
    m.add(4, 4, f64::INFINITY);
    assert!(matches!(
        BandCholesky::factor(&m),
        Err(SolverError::NotPositiveDefinite { index: 4 })
    ));
}

#[test]
fn empty_matrix_is_rejected() {
    assert!(matches!(
        SymBandMatrix::zeros(0, 3, true),
        Err(SolverError::Empty)
    ));
    assert!(DenseCholesky::factor(&[], 0).is_err());
    assert!(DenseCholesky::factor(&[1.0, 0.0], 1).is_err());
}

#[test]
fn tiny_sizes_and_huge_bandwidths() {
    for cyclic in [false, true] {
        for p in [0usize, 1, 3, 7, usize::MAX] {
            for n in 1..=4usize {
                let mut m = SymBandMatrix::zeros(n, p, cyclic).unwrap();
                // For a small cyclic matrix any pair is in the pattern.
                for i in 0..n {
                    m.add(i, i, 10.0);
                    for j in 0..i {
                        if m.in_pattern(i, j) {
                            m.add(i, j, 1.0);
                        }
                    }
                }
                let f = BandCholesky::factor(&m).unwrap();
                let mut x = vec![1.0; n];
                f.solve_in_place(&mut x);
                let mut y = vec![0.0; n];
                m.mul_vec(&x, &mut y);
                for v in &y {
                    assert!((v - 1.0).abs() < 1e-12, "n={n} p={p} cyclic={cyclic}");
                }
                let mut s = vec![0.0; n];
                let q = f.inverse_quadratic_form(n + 2, &[1.0; 9], &mut s);
                assert!(q.is_finite() && q > 0.0);
            }
        }
    }
}

/// A cyclic system far too large for a dense factorisation (it would need
/// 3.2 TB): the arrow factorisation must stay O(n p).
#[test]
fn large_cyclic_system() {
    let n = 200_000;
    let p = 3;
    let mut m = SymBandMatrix::zeros(n, p, true).unwrap();
    for i in 0..n {
        m.add(i, i, 4.0);
        for d in 1..=p {
            m.add(i, (i + d) % n, 1.0 / (d as f64 + 1.0));
        }
    }
    let f = BandCholesky::factor(&m).unwrap();
    let b: Vec<f64> = (0..n).map(|i| ((i * 7919) % 101) as f64 - 50.0).collect();
    let mut x = b.clone();
    f.solve_in_place(&mut x);
    let mut r = vec![0.0; n];
    m.mul_vec(&x, &mut r);
    for (ri, bi) in r.iter().zip(&b) {
        assert!((ri - bi).abs() < 1e-9 * 50.0);
    }
    // The corner couples the last and first unknowns.
    assert_eq!(m.get(0, n - 1), 1.0 / 2.0);
    assert_eq!(m.get(n - 3, 0), 1.0 / 4.0);
    assert_eq!(m.get(n - 4, 0), 0.0);
}

/// Re-factoring in place gives the factor of the new matrix, also after a
/// failed attempt, and rejects a matrix of another size.
#[test]
fn dense_refactor_matches_a_fresh_factor() {
    let a = [4.0, 1.0, 0.5, 1.0, 3.0, 0.2, 0.5, 0.2, 2.0];
    let b = [9.0, -2.0, 1.0, -2.0, 5.0, 0.3, 1.0, 0.3, 4.0];
    let singular = [1.0, 1.0, 0.0, 1.0, 1.0, 0.0, 0.0, 0.0, 1.0];
    let mut chol = DenseCholesky::factor(&a, 3).unwrap();
    assert!(chol.refactor(&singular).is_err());
    chol.refactor(&b).unwrap();
    let fresh = DenseCholesky::factor(&b, 3).unwrap();
    for (x, y) in chol.factor_matrix().iter().zip(fresh.factor_matrix()) {
        assert!((x - y).abs() < 1e-15, "{x} {y}");
    }
    assert!(chol.refactor(&[1.0; 4]).is_err());
}
