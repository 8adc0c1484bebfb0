//! The residuals of a converged fit gathered along the curve, for the
//! model-misfit term of the output's `sigma` (`fit::output`).
//!
//! Each band pixel's residual `e = g - f` is projected on the position's
//! direction: a displacement `dU` of the curve changes `g` by `-c gamma'
//! dU`, so the pixels whose foot lies in one bin of the reference's
//! parameter ask, in the least-squares sense, for the extra displacement
//! `d = sum w e c gamma' / sum w (c gamma')^2` there. At convergence the
//! displacement's B-splines have taken up every such request they can
//! represent: what is left in `d` is noise (variance `sigma^2 / A`, `A =
//! sum w (c gamma')^2` the bin's information and `sigma^2` the per-pixel
//! noise variance) and the part of the image's edge that the model cannot
//! follow (a shape finer than the elements, a corner without a break,
//! clutter). Computed once, after the last stage (allocates).

use super::Correlation;
use crate::interp::Sampler;
use rayon::prelude::*;

/// One bin of the reference's parameter: the information `A` and the
/// projected residual `sum w e c gamma'` of its band pixels.
#[derive(Clone, Copy, Debug, Default)]
pub(crate) struct ResidualBin {
    /// `A = sum w (c gamma')^2`, 1 / px^2 per gray level^2 (0: no pixel).
    pub info: f64,
    /// `sum w e c gamma'`.
    pub projected: f64,
}

impl Correlation {
    /// The band's residuals at `lambda` gathered in bins `bin` pixels long
    /// of the reference's parameter (`ceil(L / bin)` bins; pixels out of
    /// the band's window, rejected by the robust weights or displaced out
    /// of the image are left out). Empty before the first iteration.
    pub(crate) fn residual_bins(
        &self,
        lambda: &[f64],
        sampler: &Sampler,
        bin: f64,
    ) -> Vec<ResidualBin> {
        let band = &self.band;
        let length = self.basis.length();
        let nbins = ((length / bin).ceil() as usize).max(1);
        let mut bins = vec![ResidualBin::default(); nbins];
        if self.levels.is_none() {
            return Vec::new();
        }
        // Each pixel's terms in parallel, summed in the band's order (the
        // same sums on any number of threads).
        let terms: Vec<Option<(usize, f64, f64)>> = (0..band.len())
            .into_par_iter()
            .map(|i| {
                let w = band.weight[i];
                if w <= 0.0 {
                    return None;
                }
                let (Some((_, c)), Some(e)) =
                    (self.levels_of_pixel(i), self.residual(i, lambda, sampler))
                else {
                    return None;
                };
                let dg = match &self.pushed {
                    Some(_) => band.profile_at(i, self.displacement_at(i, lambda)).1,
                    None => band.dgamma[i],
                };
                let j = c * dg;
                let k = ((band.s[i].max(0.0) / bin) as usize).min(nbins - 1);
                Some((k, w * j * j, w * e * j))
            })
            .collect();
        for (k, info, projected) in terms.into_iter().flatten() {
            bins[k].info += info;
            bins[k].projected += projected;
        }
        bins
    }
}
