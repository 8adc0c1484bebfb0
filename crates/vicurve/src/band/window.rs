//! The weights the pixels count with, and the window of a band with a
//! margin: the pixels within the half-width of the displaced curve count,
//! the others weigh 0 (see the [module docs](super)).

use super::{displacement, Band, RECENTRE_CHUNK};
use crate::spline::Basis;
use rayon::prelude::*;

impl Band {
    /// Pixels that count at the last [`Band::recentre`]: those within the
    /// half-width of the displaced curve ([`Band::len`] without a margin).
    pub fn inside(&self) -> usize {
        self.inside
    }

    /// Each pixel's weight before the window: `1 / (1 - kappa r)` for the
    /// paper's profiles, 1 for the pushed ones (module docs), times any
    /// robust factor.
    pub fn full_weights(&self) -> &[f64] {
        &self.full_weight
    }

    /// Set the weights before the window (one per pixel; a robust fit's
    /// reweighting) and window them on the curve displaced by `lambda`
    /// (coefficients in `basis`, the band's), as [`Band::recentre`].
    ///
    /// Panics if `weights` does not hold one weight per pixel.
    pub(crate) fn set_full_weights(&mut self, weights: Vec<f64>, basis: &Basis, lambda: &[f64]) {
        assert_eq!(weights.len(), self.len(), "one weight per band pixel");
        self.full_weight = weights;
        if self.margin > 0.0 {
            self.recentre(basis, lambda);
        } else {
            self.weight.clone_from(&self.full_weight);
        }
    }

    /// Window a band with a margin on its reference (`U = 0`, as
    /// [`Band::recentre`] with a zero displacement, without evaluating
    /// it): the window it is built with, and the one a system's constant
    /// matrix is assembled over. Without a margin, nothing changes.
    pub(crate) fn window_at_reference(&mut self) {
        if self.margin == 0.0 {
            return;
        }
        let h = self.half_width;
        let mut inside = 0;
        for ((w, full), r) in self.weight.iter_mut().zip(&self.full_weight).zip(&self.r) {
            let counts = r.abs() < h;
            *w = if counts { *full } else { 0.0 };
            inside += usize::from(counts);
        }
        self.inside = inside;
    }

    /// Window a band with a margin on the curve displaced by `lambda`
    /// (coefficients in `basis`, the band's): a pixel counts with its
    /// weight when `|r - U| < R`, with 0 otherwise (module docs). Returns
    /// the sum of the weights. Without a margin, nothing changes.
    pub fn recentre(&mut self, basis: &Basis, lambda: &[f64]) -> f64 {
        if self.margin == 0.0 {
            return self.weight.iter().sum();
        }
        let p = self.degree;
        let h = self.half_width;
        let (r, first, values, full) = (&self.r, &self.first, &self.basis, &self.full_weight);
        // Per chunk in parallel, added in the chunks' order: the same bits
        // however rayon splits the work.
        let parts: Vec<(f64, usize)> = self
            .weight
            .par_chunks_mut(RECENTRE_CHUNK)
            .enumerate()
            .map(|(k, chunk)| {
                let mut sum = 0.0;
                let mut inside = 0;
                for (j, w) in chunk.iter_mut().enumerate() {
                    let i = k * RECENTRE_CHUNK + j;
                    let u = displacement(basis, first[i], &values[i * (p + 1)..], lambda);
                    *w = if (r[i] - u).abs() < h {
                        inside += 1;
                        full[i]
                    } else {
                        0.0
                    };
                    sum += *w;
                }
                (sum, inside)
            })
            .collect();
        let (sum, inside) = parts.iter().fold((0.0, 0), |a, b| (a.0 + b.0, a.1 + b.1));
        self.inside = inside;
        sum
    }
}
