//! Residuals correlated along the curve: the factor on the noise variance
//! of the output's `sigma` when the image's deviations from the model are
//! not white.
//!
//! The Gauss–Newton `sigma` takes the residuals for independent pixel
//! noise. A textured surface (machining marks, a cloth, a painted
//! speckle), vignetting or JPEG blocks give deviations that are smooth
//! over several pixels: neighbouring pixels share them, so they move the
//! curve far more than independent noise of the same variance would. The
//! residuals of the converged fit, projected on the position in 1 px bins
//! of the reference's parameter ([`crate::correlation`]'s residual bins)
//! and normalised by their noise-only deviation, measure it: their long-run
//! variance (lag-weighted sum of autocovariances, Bartlett weights up to
//! half an element) is 1 for white noise, and is the factor on the variance
//! of a displacement averaged over that scale otherwise.
//!
//! The fit itself removes from the residuals what its B-splines can
//! represent, which lowers that sum even for white noise. The same sum
//! for white noise after the same least-squares projection (bin level,
//! `NULL_DRAWS` draws from a fixed seed: deterministic) is the reference;
//! the factor is their ratio, over chunks of `CHUNK_ELEMENTS` elements:
//! their mean less twice its standard error, so that white noise's chance
//! excursions (and a single corner or speck, the local misfit term's
//! business) do not inflate the whole curve.
//!
//! Three things are left to others. The bins where the misfit term flags a
//! request are left out: a shape the elements cannot follow leaves
//! residuals correlated over the whole misfit, which that term covers.
//! Requests larger than the noise explains (a lag-0 variance over white
//! noise's) are systematic residuals, the misfit term's too: that
//! magnitude is divided out, or a noiseless line whose profile does not
//! quite match would get a `sigma` several times its error.
//!
//! Requests smaller than white noise's mean that the Rice noise estimate
//! took systematic residuals for noise: a model that misses the image's
//! profile in the same way at every part of the edge (a sharp 16-bit
//! edge's aliasing, a line's not quite matching profile) leaves
//! differences along `r` that do not move the curve. The factor then
//! lowers `sigma` to what the requests show (their long-run ratio plus
//! twice its standard error, so white noise's chance dips do not), but
//! never below the image's own noise ([`crate::interp::Sampler::pixel_noise`]
//! and the rounding to its gray levels). The caller keeps the factor at 1
//! or more on curves with corners (`fit/output.rs`).
//!
//! What it cannot see: elements short enough to follow the texture (the
//! automatic length goes down to 5 px on a textured star) take its effect
//! into the curve, and the residuals keep none of it; `sigma` then stays
//! the white-noise one (`tests/it/realistic.rs`, docs/benchmarks.md).

use crate::correlation::ResidualBin;
use crate::render::noise::Rng;
use crate::solver::{BandCholesky, SymBandMatrix};
use crate::spline::{Basis, MAX_DEGREE};

/// A chunk's variances of the normalised requests: long-run (lag-weighted
/// sum of autocovariances) and lag-0.
#[derive(Clone, Copy, Debug, Default)]
struct Variances {
    long_run: f64,
    lag0: f64,
}

/// Draws of white noise for the projection's own effect.
const NULL_DRAWS: usize = 8;
/// Seed of those draws (any fixed value: the factor is reproducible).
const NULL_SEED: u64 = 0x5eed_c0de;
/// Elements per chunk whose factors are compared (their median is kept).
const CHUNK_ELEMENTS: f64 = 4.0;

/// The factor on the noise variance of the positions: the long-run
/// variance of the residual requests `bins` (bins of the reference's
/// parameter, `bin` px long, per-pixel noise variance `noise`) over that of
/// white noise after the fit's projection on `basis` (module docs), the
/// bins where the misfit term speaks (`misfit`) left out: a shape the
/// elements cannot follow leaves residuals correlated over the whole
/// misfit, which are that term's. At least `floor` (the image's own noise
/// variance over `noise`, at most 1). 1 with fewer than two chunks of bins
/// or no noise estimate.
pub(super) fn noise_correlation_factor(
    bins: &[ResidualBin],
    misfit: &[bool],
    (noise, floor): (f64, f64),
    basis: &Basis,
    bin: f64,
) -> f64 {
    let n = bins.len();
    let lags = ((0.5 * basis.element_length() / bin).round() as usize).max(1);
    let chunk = ((CHUNK_ELEMENTS * basis.element_length() / bin).round() as usize).max(4 * lags);
    if noise <= 0.0 || n < 2 * chunk {
        return 1.0;
    }
    let closed = basis.is_closed();
    let observed: Vec<f64> = bins
        .iter()
        .zip(misfit)
        .map(|(b, &m)| {
            if b.info > 0.0 && !m {
                b.projected / (noise * b.info).sqrt()
            } else {
                0.0
            }
        })
        .collect();
    let Some(projection) = Projection::new(bins, basis, bin) else {
        return 1.0;
    };
    let null = white_long_run(bins, misfit, &projection, chunk, lags, closed);
    let seen = long_run(&observed, bins, misfit, chunk, lags, closed);
    let pairs: Vec<(Variances, Variances)> = seen
        .into_iter()
        .zip(null)
        .filter(|(s, z)| s.lag0 > 0.0 && z.long_run > 0.0 && z.lag0 > 0.0)
        .collect();
    factor_of(&pairs, floor.min(1.0))
}

/// The factor (module docs) from each chunk's variances, observed and white
/// noise's: the mean ratio of the long-run ones less twice its standard
/// error, over the magnitude of the requests when it exceeds white noise's,
/// at least 1; or, when that mean plus twice its standard error is under
/// 1, that, at least `floor`.
fn factor_of(pairs: &[(Variances, Variances)], floor: f64) -> f64 {
    let m = pairs.len();
    if m < 2 {
        return 1.0;
    }
    let magnitude =
        pairs.iter().map(|p| p.0.lag0).sum::<f64>() / pairs.iter().map(|p| p.1.lag0).sum::<f64>();
    let ratios: Vec<f64> = pairs.iter().map(|(s, z)| s.long_run / z.long_run).collect();
    let mean = ratios.iter().sum::<f64>() / m as f64;
    let error = 2.0
        * ((ratios.iter().map(|r| (r - mean).powi(2)).sum::<f64>()) / ((m - 1) * m) as f64).sqrt();
    if mean + error < 1.0 {
        return (mean + error).max(floor);
    }
    ((mean - error) / magnitude.max(1.0)).max(1.0)
}

/// Each chunk's variances of white noise after the
/// fit's `projection`, averaged over `NULL_DRAWS` draws from a fixed seed,
/// the bins of `misfit` left out as they are from the observed requests.
fn white_long_run(
    bins: &[ResidualBin],
    misfit: &[bool],
    projection: &Projection,
    chunk: usize,
    lags: usize,
    closed: bool,
) -> Vec<Variances> {
    let n = bins.len();
    let mut null = vec![Variances::default(); n.div_ceil(chunk)];
    let mut rng = Rng::new(NULL_SEED);
    let mut draw = vec![0.0; n];
    for _ in 0..NULL_DRAWS {
        for (d, b) in draw.iter_mut().zip(bins) {
            *d = if b.info > 0.0 { rng.normal() } else { 0.0 };
        }
        projection.remove_fit(&mut draw);
        for (d, _) in draw.iter_mut().zip(misfit).filter(|(_, m)| **m) {
            *d = 0.0;
        }
        for (z, v) in null
            .iter_mut()
            .zip(long_run(&draw, bins, misfit, chunk, lags, closed))
        {
            z.long_run += v.long_run / NULL_DRAWS as f64;
            z.lag0 += v.lag0 / NULL_DRAWS as f64;
        }
    }
    null
}

/// The variances of `d` in each chunk of `chunk` bins, over its bins with
/// information outside `misfit`: the lag-0 mean of `d_b^2`, and the
/// long-run mean of `d_b (d_b + 2 sum_k w_k d_(b+k))` with `w_k = 1 - k /
/// (lags + 1)` (Bartlett), the lags reaching past the chunk (around a closed
/// curve; not past an open one's end).
fn long_run(
    d: &[f64],
    bins: &[ResidualBin],
    misfit: &[bool],
    chunk: usize,
    lags: usize,
    closed: bool,
) -> Vec<Variances> {
    let n = d.len();
    (0..n.div_ceil(chunk))
        .map(|c| {
            let (mut sum, mut zero, mut count) = (0.0, 0.0, 0.0);
            for b in c * chunk..((c + 1) * chunk).min(n) {
                if bins[b].info <= 0.0 || misfit[b] {
                    continue;
                }
                let mut cross = 0.0;
                for k in 1..=lags {
                    let j = b + k;
                    let j = if j < n {
                        j
                    } else if closed {
                        j - n
                    } else {
                        break;
                    };
                    cross += (1.0 - k as f64 / (lags + 1) as f64) * d[j];
                }
                sum += d[b] * (d[b] + 2.0 * cross);
                zero += d[b] * d[b];
                count += 1.0;
            }
            if count > 0.0 {
                Variances {
                    long_run: sum / count,
                    lag0: zero / count,
                }
            } else {
                Variances::default()
            }
        })
        .collect()
}

/// The least-squares fit of normalised bin values by the displacement's
/// B-splines (each bin weighted by its information, as the correlation
/// weighs its pixels), factored once.
struct Projection<'a> {
    /// `sqrt(A_b)` of each bin.
    root_info: Vec<f64>,
    /// Basis values and first index at each bin's centre.
    values: Vec<([f64; MAX_DEGREE + 1], usize)>,
    chol: BandCholesky,
    basis: &'a Basis,
}

impl<'a> Projection<'a> {
    fn new(bins: &[ResidualBin], basis: &'a Basis, bin: f64) -> Option<Self> {
        let p = basis.degree();
        let mut m = SymBandMatrix::zeros(basis.n_functions(), p, basis.is_closed()).ok()?;
        let mut values = Vec::with_capacity(bins.len());
        let root_info: Vec<f64> = bins.iter().map(|b| b.info.max(0.0).sqrt()).collect();
        for (k, b) in bins.iter().enumerate() {
            let u = ((k as f64 + 0.5) * bin).min(basis.length());
            let mut v = [0.0; MAX_DEGREE + 1];
            let first = basis.eval(u, &mut v);
            if b.info > 0.0 {
                m.add_outer(first, b.info, &v[..=p]);
            }
            values.push((v, first));
        }
        let chol = BandCholesky::factor(&m).ok()?;
        Some(Projection {
            root_info,
            values,
            chol,
            basis,
        })
    }

    /// `z` minus its weighted least-squares fit: `z_b - sqrt(A_b) N_b^T x`
    /// with `x` minimising `sum_b (z_b - sqrt(A_b) N_b^T x)^2`.
    fn remove_fit(&self, z: &mut [f64]) {
        let p = self.basis.degree();
        let mut rhs = vec![0.0; self.basis.n_functions()];
        for ((zb, ri), (v, first)) in z.iter().zip(&self.root_info).zip(&self.values) {
            for (k, vk) in v[..=p].iter().enumerate() {
                rhs[self.basis.index(*first, k)] += ri * vk * zb;
            }
        }
        self.chol.solve_in_place(&mut rhs);
        for ((zb, ri), (v, first)) in z.iter_mut().zip(&self.root_info).zip(&self.values) {
            let fit: f64 = v[..=p]
                .iter()
                .enumerate()
                .map(|(k, vk)| vk * rhs[self.basis.index(*first, k)])
                .sum();
            *zb -= ri * fit;
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// Bins of unit information whose normalised requests are `d`.
    fn bins_of(d: &[f64]) -> Vec<ResidualBin> {
        d.iter()
            .map(|&v| ResidualBin {
                info: 1.0,
                projected: v,
            })
            .collect()
    }

    /// A closed cubic basis of 40 elements on 800 px.
    fn closed_basis() -> Basis {
        Basis::new(3, 40, 800.0, true).unwrap()
    }

    /// The projection on `basis` of 800 bins of unit information.
    fn unit_projection(basis: &Basis) -> Projection<'_> {
        Projection::new(&bins_of(&[0.0; 800]), basis, 1.0).unwrap()
    }

    /// White requests after the fit's projection: a factor of about 1
    /// (held at 1 from below: their chance dips stay within twice the
    /// standard error), whatever the seed.
    #[test]
    fn white_residuals_leave_sigma_alone() {
        let basis = closed_basis();
        let proj = unit_projection(&basis);
        for seed in 1..=8 {
            let mut rng = Rng::new(seed);
            let mut d: Vec<f64> = (0..800).map(|_| rng.normal()).collect();
            proj.remove_fit(&mut d);
            let f = noise_correlation_factor(&bins_of(&d), &[false; 800], (1.0, 0.0), &basis, 1.0);
            assert!((1.0..1.35).contains(&f), "seed {seed}: {f}");
        }
    }

    /// Requests a tenth of white noise's (the noise estimate took
    /// systematic residuals for noise): the factor falls to about their
    /// variance ratio, 0.01, but not below the image's own noise.
    #[test]
    fn small_requests_lower_sigma_to_the_image_noise() {
        let basis = closed_basis();
        let proj = unit_projection(&basis);
        let mut rng = Rng::new(3);
        let mut d: Vec<f64> = (0..800).map(|_| 0.1 * rng.normal()).collect();
        proj.remove_fit(&mut d);
        let f = noise_correlation_factor(&bins_of(&d), &[false; 800], (1.0, 0.0), &basis, 1.0);
        assert!((0.008..0.02).contains(&f), "{f}");
        let f = noise_correlation_factor(&bins_of(&d), &[false; 800], (1.0, 0.05), &basis, 1.0);
        assert_eq!(f, 0.05);
    }

    /// Requests smoothed along the curve (a moving average of 5 white
    /// values: long-run variance 5 times the white one): a factor near 5.
    #[test]
    fn smooth_residuals_inflate_sigma_by_their_long_run_variance() {
        let basis = closed_basis();
        let proj = unit_projection(&basis);
        let mut rng = Rng::new(5);
        let white: Vec<f64> = (0..800).map(|_| rng.normal()).collect();
        // Variance 1 per bin, lag-k correlation (5 - k) / 5.
        let mut d: Vec<f64> = (0..800)
            .map(|i| (0..5).map(|k| white[(i + k) % 800]).sum::<f64>() / 5f64.sqrt())
            .collect();
        proj.remove_fit(&mut d);
        let f = noise_correlation_factor(&bins_of(&d), &[false; 800], (1.0, 0.0), &basis, 1.0);
        // Bartlett weights over 10 lags keep most of the 5, less twice the
        // standard error of the chunks' mean.
        assert!((2.0..6.0).contains(&f), "{f}");
    }

    /// Too few bins, or no noise estimate: no factor.
    #[test]
    fn short_curves_get_no_factor() {
        let basis = Basis::new(3, 4, 40.0, true).unwrap();
        let d = vec![1.0; 40];
        assert_eq!(
            noise_correlation_factor(&bins_of(&d), &[false; 40], (1.0, 0.0), &basis, 1.0),
            1.0
        );
        let basis = Basis::new(3, 40, 800.0, true).unwrap();
        assert_eq!(
            noise_correlation_factor(
                &bins_of(&vec![1.0; 800]),
                &[false; 800],
                (0.0, 0.0),
                &basis,
                1.0
            ),
            1.0
        );
    }
}
