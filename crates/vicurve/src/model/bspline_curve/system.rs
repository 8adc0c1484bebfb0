//! The normal equations of the control-point fit: a banded block for the
//! `2n` control coordinates (interleaved `x0, y0, x1, y1, ...`; a pixel
//! touches the `p + 1` control points of its element, so the half-bandwidth
//! is `2p + 1`, cyclic for a closed curve) bordered by the two gray levels
//! `a, c`, which every pixel touches:
//!
//! ```text
//! [ B    C ] [dP]   [g_P]
//! [ C^T  D ] [dz] = [g_z]
//! ```
//!
//! solved through the banded Cholesky factor of `B` and the `2 x 2` Schur
//! complement `S = D - C^T B^-1 C`: `O(n p^2)` per factorisation instead of
//! the dense `O(n^3)`.

use crate::solver::{BandCholesky, SymBandMatrix};

/// `J^T J` and `J^T e` of the control-point fit.
#[derive(Clone, Debug)]
pub(crate) struct Normal {
    /// Control-point block, `2n x 2n`.
    pub b: SymBandMatrix,
    /// Coupling of each control coordinate with `(a, c)`.
    pub c: Vec<[f64; 2]>,
    /// `(a, c)` block: `[aa, ac, cc]`.
    pub d: [f64; 3],
    /// `J^T e` for the control coordinates.
    pub g: Vec<f64>,
    /// `J^T e` for `(a, c)`.
    pub g_z: [f64; 2],
}

impl Normal {
    /// Zero equations for `n` control points of degree `p`.
    pub fn zeros(n: usize, p: usize, closed: bool) -> Normal {
        Normal {
            // 2n >= 2 rows: zeros cannot fail.
            b: SymBandMatrix::zeros(2 * n, 2 * p + 1, closed)
                .unwrap_or_else(|_| unreachable!("2n > 0")),
            c: vec![[0.0; 2]; 2 * n],
            d: [0.0; 3],
            g: vec![0.0; 2 * n],
            g_z: [0.0; 2],
        }
    }

    /// The same equations with `mu` times the diagonal (at least
    /// `floor`) added: Levenberg–Marquardt damping.
    pub fn damped(&self, mu: f64, floor: f64) -> Normal {
        let mut out = self.clone();
        for i in 0..self.g.len() {
            out.b.add(i, i, mu * self.b.get(i, i).max(floor));
        }
        out.d[0] += mu * self.d[0].max(floor);
        out.d[2] += mu * self.d[2].max(floor);
        out
    }

    /// The largest diagonal entry of `B`.
    pub fn max_diag(&self) -> f64 {
        (0..self.g.len())
            .map(|i| self.b.get(i, i))
            .fold(0.0, f64::max)
    }
}

/// The factorised equations.
pub(crate) struct Factored {
    chol: BandCholesky,
    /// `C`.
    c: Vec<[f64; 2]>,
    /// `W = B^-1 C`.
    w: Vec<[f64; 2]>,
    /// `S^-1`, row-major `2 x 2`.
    s_inv: [f64; 4],
}

impl Factored {
    /// Factor; `None` when `B` or the Schur complement is not positive
    /// definite to working precision.
    pub fn new(eq: &Normal) -> Option<Factored> {
        let chol = BandCholesky::factor(&eq.b).ok()?;
        let mut w0: Vec<f64> = eq.c.iter().map(|c| c[0]).collect();
        let mut w1: Vec<f64> = eq.c.iter().map(|c| c[1]).collect();
        chol.solve_in_place(&mut w0);
        chol.solve_in_place(&mut w1);
        let (mut s00, mut s01, mut s11) = (eq.d[0], eq.d[1], eq.d[2]);
        for (c, (a, b)) in eq.c.iter().zip(w0.iter().zip(&w1)) {
            s00 -= c[0] * a;
            s01 -= c[0] * b;
            s11 -= c[1] * b;
        }
        let det = s00 * s11 - s01 * s01;
        if !(det.is_finite() && s00 > 0.0 && s11 > 0.0 && det > 1e-14 * s00 * s11) {
            return None;
        }
        Some(Factored {
            chol,
            c: eq.c.clone(),
            w: w0.into_iter().zip(w1).map(|(a, b)| [a, b]).collect(),
            s_inv: [s11 / det, -s01 / det, -s01 / det, s00 / det],
        })
    }

    /// Solve for the right-hand side `(r, r_z)`: `r` is overwritten with
    /// the control part, the gray-level part is returned.
    pub fn solve(&self, r: &mut [f64], r_z: [f64; 2]) -> [f64; 2] {
        // y = B^-1 r; z = S^-1 (r_z - C^T y); x = y - W z.
        self.chol.solve_in_place(r);
        let (mut t0, mut t1) = (r_z[0], r_z[1]);
        for (c, y) in self.c.iter().zip(r.iter()) {
            t0 -= c[0] * y;
            t1 -= c[1] * y;
        }
        let z = [
            self.s_inv[0] * t0 + self.s_inv[1] * t1,
            self.s_inv[2] * t0 + self.s_inv[3] * t1,
        ];
        for (x, w) in r.iter_mut().zip(&self.w) {
            *x -= w[0] * z[0] + w[1] * z[1];
        }
        z
    }

    /// The band of the control points' block of the inverse,
    /// `(H^-1)_PP = B^-1 + W S^-1 W^T`: for control point `k` and offset
    /// `o = 0..=p`, the `2 x 2` block between `P_k` and `P_(k+o)` (indices
    /// modulo `n` for a closed curve; zero past the end of an open one),
    /// row-major `[xx, xy, yx, yy]`, at `out[k * (p + 1) + o]`. By one
    /// solve per column: `O(n^2 p)`.
    pub fn inverse_band(&self, p: usize, closed: bool) -> Vec<[f64; 4]> {
        let n2 = self.w.len();
        let n = n2 / 2;
        let mut out = vec![[0.0; 4]; n * (p + 1)];
        let mut col = vec![0.0; n2];
        for j in 0..n2 {
            col.fill(0.0);
            col[j] = 1.0;
            self.chol.solve_in_place(&mut col);
            // Column j of W S^-1 W^T: W (S^-1 W_j^T).
            let wj = self.w[j];
            let v = [
                self.s_inv[0] * wj[0] + self.s_inv[1] * wj[1],
                self.s_inv[2] * wj[0] + self.s_inv[3] * wj[1],
            ];
            let (m, beta) = (j / 2, j % 2);
            for o in 0..=p {
                let k = if closed {
                    (m + n * (p + 1) - o) % n
                } else if m >= o {
                    m - o
                } else {
                    continue;
                };
                for alpha in 0..2 {
                    let i = 2 * k + alpha;
                    let wi = self.w[i];
                    out[k * (p + 1) + o][2 * alpha + beta] = col[i] + wi[0] * v[0] + wi[1] * v[1];
                }
            }
        }
        out
    }

    /// `S^-1`: the `(a, c)` block of the inverse, row-major.
    #[cfg(test)]
    pub fn levels_inverse(&self) -> [f64; 4] {
        self.s_inv
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::solver::DenseCholesky;

    /// A random symmetric positive definite bordered system (n = 7 points,
    /// p = 2, closed), solved and inverted both ways.
    #[test]
    fn bordered_solve_and_inverse_match_dense() {
        let (n, p) = (7usize, 2usize);
        let n2 = 2 * n;
        let m = n2 + 2;
        let mut rng = crate::render::noise::Rng::new(3);
        // H = J^T J + I from random rows that respect the cyclic band.
        let mut eq = Normal::zeros(n, p, true);
        let mut dense = vec![0.0; m * m];
        for row in 0..60 {
            let first = row % n;
            let mut idx = Vec::new();
            let mut val = Vec::new();
            for k in 0..=p {
                for a in 0..2 {
                    idx.push(2 * ((first + k) % n) + a);
                    val.push(rng.normal());
                }
            }
            idx.push(n2);
            val.push(rng.normal());
            idx.push(n2 + 1);
            val.push(rng.normal());
            for (x, &i) in idx.iter().enumerate() {
                for (y, &j) in idx.iter().enumerate() {
                    dense[i * m + j] += val[x] * val[y];
                    if i < n2 && j < n2 && i <= j {
                        eq.b.add(i, j, val[x] * val[y]);
                    } else if i < n2 && j >= n2 {
                        eq.c[i][j - n2] += val[x] * val[y];
                    }
                }
            }
        }
        for i in 0..n2 {
            eq.b.add(i, i, 1.0);
            dense[i * m + i] += 1.0;
        }
        eq.d = [
            dense[n2 * m + n2],
            dense[n2 * m + n2 + 1],
            dense[(n2 + 1) * m + n2 + 1],
        ];
        let f = Factored::new(&eq).unwrap();
        let rhs: Vec<f64> = (0..m).map(|i| (i as f64 * 0.7).sin()).collect();
        let mut x = rhs[..n2].to_vec();
        let z = f.solve(&mut x, [rhs[n2], rhs[n2 + 1]]);
        let chol = DenseCholesky::factor(&dense, m).unwrap();
        let mut want = rhs.clone();
        chol.solve_in_place(&mut want);
        for i in 0..n2 {
            assert!(
                (x[i] - want[i]).abs() < 1e-10,
                "{i}: {} vs {}",
                x[i],
                want[i]
            );
        }
        assert!((z[0] - want[n2]).abs() < 1e-10 && (z[1] - want[n2 + 1]).abs() < 1e-10);
        let inv = chol.inverse();
        let band = f.inverse_band(p, true);
        for k in 0..n {
            for o in 0..=p {
                let l = (k + o) % n;
                for a in 0..2 {
                    for b in 0..2 {
                        let got = band[k * (p + 1) + o][2 * a + b];
                        let want = inv[(2 * k + a) * m + 2 * l + b];
                        assert!((got - want).abs() < 1e-10, "{k} {o}: {got} vs {want}");
                    }
                }
            }
        }
        let s = f.levels_inverse();
        assert!((s[1] - inv[n2 * m + n2 + 1]).abs() < 1e-10);
    }
}
