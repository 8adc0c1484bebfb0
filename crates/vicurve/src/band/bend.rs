//! The displaced curve's curvature for a band kept over several frames
//! (see the [module docs](super)).

use super::{displacement, Band, MIN_JACOBIAN, RECENTRE_CHUNK};
use crate::spline::{Basis, MAX_DEGREE};
use rayon::prelude::*;

impl Band {
    /// Take the curvature of the curve displaced by `lambda` (coefficients
    /// in `basis`, the band's) at every pixel, instead of the reference's,
    /// until the next call (module docs). The first call also evaluates the
    /// basis' second derivatives at the pixels (kept for the next). Does
    /// nothing on the bands of the paper's profiles, which do not take the
    /// curvature. Where `1 - kappa U` falls under the band's smallest
    /// Jacobian (`U` beyond the centre of curvature) the reference's stays.
    pub fn bend_to(&mut self, basis: &Basis, lambda: &[f64]) {
        if !self.profile.is_pushed() {
            return;
        }
        if self.basis_d2.is_empty() {
            self.basis_d2 = self.second_derivatives(basis);
        }
        if self.reference_curvature.is_empty() {
            self.reference_curvature = self.curvature.clone();
        }
        let p = self.degree;
        let (first, values, d2) = (&self.first, &self.basis, &self.basis_d2);
        let kappa = &self.reference_curvature;
        self.curvature
            .par_chunks_mut(RECENTRE_CHUNK)
            .enumerate()
            .for_each(|(k, chunk)| {
                for (j, bent) in chunk.iter_mut().enumerate() {
                    let i = k * RECENTRE_CHUNK + j;
                    let u = displacement(basis, first[i], &values[i * (p + 1)..], lambda);
                    let u2 = displacement(basis, first[i], &d2[i * (p + 1)..], lambda);
                    let q = 1.0 - kappa[i] * u;
                    *bent = if q > MIN_JACOBIAN {
                        kappa[i] / q + u2 / (q * q)
                    } else {
                        kappa[i]
                    };
                }
            });
    }

    /// The second derivatives of the `p + 1` functions of `basis` (the
    /// band's) at each pixel's `s`, 1/px^2, laid out as the band's values.
    fn second_derivatives(&self, basis: &Basis) -> Vec<f64> {
        let p = self.degree;
        let s = &self.s;
        let mut basis_d2 = vec![0.0; s.len() * (p + 1)];
        basis_d2
            .par_chunks_mut(RECENTRE_CHUNK * (p + 1))
            .enumerate()
            .for_each(|(k, chunk)| {
                let mut v = [0.0; MAX_DEGREE + 1];
                for (j, d2) in chunk.chunks_exact_mut(p + 1).enumerate() {
                    basis.eval_d2(s[k * RECENTRE_CHUNK + j], &mut v);
                    d2.copy_from_slice(&v[..=p]);
                }
            });
        basis_d2
    }
}
