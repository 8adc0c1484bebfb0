//! The iteration with gray levels that vary along the curve; see
//! [`super::levels`] for the model and the one approximation.
//!
//! Two passes over the band per iteration: the first samples `f` (or
//! evaluates the pushed profile), keeps `f` and `gamma` per pixel and
//! accumulates the levels' normal equations; the levels are solved; the
//! second forms the residual with them and accumulates the displacement's
//! right-hand side and the contrast averaged over each function's support.
//! Nothing is allocated per iteration.

use super::censor::{observed, Censored};
use super::{left_image, polarity_sign, Correlation, Moments, Step, StepFailure};
use crate::band::Band;
use crate::correlation::levels::{features, LevelBasis};
use crate::error::{Error, Result};
use crate::interp::Sampler;
use crate::solver::chunked::chunked_sum;
use crate::solver::{BandCholesky, DenseCholesky};
use crate::spline::Basis;
use crate::virtual_image::Polarity;
use rayon::prelude::*;
use std::sync::OnceLock;

/// Partial sums of one chunk of band pixels.
#[derive(Clone, Debug)]
struct Chunk {
    /// Levels' right-hand side, `dim`.
    rhs_t: Vec<f64>,
    /// Levels' normal matrix as per-element blocks (pushed profile only,
    /// see [`LevelBasis::accumulate`]).
    mat_t: Vec<f64>,
    /// Displacement right-hand side `sum w c r dg N_i`, `n`.
    rhs_l: Vec<f64>,
    /// `sum w dg^2 N_i c(s)`, `n`.
    dnum: Vec<f64>,
    /// `w, w f, w gamma, w gamma^2, w f gamma, w f^2, w r^2, w a, w c`.
    sums: [f64; 9],
    outside: Option<[f64; 2]>,
    outside_count: usize,
}

/// The varying levels' state of a [`Correlation`].
#[derive(Clone, Debug)]
pub(crate) struct Varying {
    pub levels: LevelBasis,
    /// The levels' coefficients of the last iteration.
    pub theta: Vec<f64>,
    have_theta: bool,
    /// `B`, column-major, one column of `n` per coefficient: `sum w dg N_i
    /// M_k phi` for each feature `phi` (at `U = 0`).
    b: Vec<f64>,
    /// `M0^-1 B`, same layout.
    y: Vec<f64>,
    /// Factor of `K = S - B^T M0^-1 B`, dense `dim x dim`.
    k_factor: DenseCholesky,
    /// Factor of the levels' normal matrix `S` at `U = 0` (pulled image).
    s_factor: DenseCholesky,
    /// Factor of the levels' normal matrix at the current displacement
    /// (pushed profile), re-factored in place each iteration.
    mat_factor: DenseCholesky,
    /// `sum w dg^2 N_i` (the row sums of `M0`).
    dden: Vec<f64>,
    /// Per band pixel: `f`, `gamma` and its derivative `dg` of the
    /// current iteration.
    fbuf: Vec<f64>,
    gbuf: Vec<f64>,
    dbuf: Vec<f64>,
    /// Per band pixel, pushed profile: the light's relative slope across
    /// the curve, held fixed (see `tilt`); `None` without one.
    pub tilt: Option<Vec<f64>>,
    /// The measurement behind `tilt` (`None`: not measured).
    pub measured_tilt: Option<super::tilt::Measured>,
    /// Per band pixel: the tilt's factor `1 + tau r` of the current
    /// iteration (1 without tilt).
    sbuf: Vec<f64>,
    per: usize,
    chunks: Vec<Chunk>,
    /// Scratch: `dim`, `dim^2`, `n`.
    t: Vec<f64>,
    mat: Vec<f64>,
    d: Vec<f64>,
    /// The band of `Y K^-1 Y^T` (`n` rows of `2p + 1`, see
    /// [`Varying::variance_term`]), made on first use.
    variance_band: OnceLock<Vec<f64>>,
}

impl Varying {
    /// Build the constant parts for `band` and the displacement's factor.
    ///
    /// Errors: [`Error::NotPositiveDefinite`] when the levels cannot be told
    /// apart from the displacement (an element of the levels without band
    /// pixels, say).
    pub fn new(band: &Band, basis: &Basis, chol: &BandCholesky, lb: Basis) -> Result<Varying> {
        let levels = LevelBasis::new(lb, &band.s);
        let n = basis.n_functions();
        let dim = levels.dim();
        let (b, s_blocks, dden) = assemble(band, basis, &levels)?;
        let mut s_mat = vec![0.0; dim * dim];
        levels.scatter(&s_blocks, &mut s_mat);
        let mut y = b.clone();
        for col in y.chunks_mut(n) {
            chol.solve_in_place(col);
        }
        let mut k = s_mat.clone();
        for r in 0..dim {
            for c in 0..dim {
                let dot: f64 = b[r * n..(r + 1) * n]
                    .iter()
                    .zip(&y[c * n..(c + 1) * n])
                    .map(|(u, v)| u * v)
                    .sum();
                k[r * dim + c] -= dot;
            }
        }
        let (Ok(k_factor), Ok(s_factor)) = (
            DenseCholesky::factor(&k, dim),
            DenseCholesky::factor(&s_mat, dim),
        ) else {
            return Err(Error::NotPositiveDefinite { index: n });
        };
        let chunks = (rayon::current_num_threads() * 2).clamp(1, 64);
        let per = band.len().div_ceil(chunks).max(1);
        let count = band.len().div_ceil(per);
        let chunk = Chunk {
            rhs_t: vec![0.0; dim],
            mat_t: vec![0.0; levels.blocks_len()],
            rhs_l: vec![0.0; n],
            dnum: vec![0.0; n],
            sums: [0.0; 9],
            outside: None,
            outside_count: 0,
        };
        Ok(Varying {
            levels,
            theta: vec![0.0; dim],
            have_theta: false,
            b,
            y,
            mat_factor: s_factor.clone(),
            k_factor,
            s_factor,
            dden,
            fbuf: vec![0.0; band.len()],
            gbuf: vec![0.0; band.len()],
            dbuf: band.dgamma.clone(),
            tilt: None,
            measured_tilt: None,
            sbuf: vec![1.0; band.len()],
            per,
            chunks: vec![chunk; count],
            t: vec![0.0; dim],
            mat: vec![0.0; dim * dim],
            d: vec![0.0; n],
            variance_band: OnceLock::new(),
        })
    }

    /// The levels' coefficients for constant levels `(a, c)` (the basis is
    /// a partition of unity).
    fn set_constant(&mut self, a: f64, c: f64) {
        let m = self.levels.m();
        self.theta[..m].fill(a);
        self.theta[m..2 * m].fill(c);
    }

    /// `q(s)` term of the levels in the variance of `U(s)`: `(Y^T N)^T
    /// K^-1 (Y^T N)` for the displacement functions `vals` from `first`,
    /// i.e. `N^T W N` with `W = Y K^-1 Y^T`. Only the band of `W` that two
    /// functions sharing an element reach is needed: it is made once (`n`
    /// solves with the levels' `dim x dim` factor), after which each call
    /// costs `(p + 1)^2` products instead of a dense solve.
    pub fn variance_term(&self, basis: &Basis, first: usize, vals: &[f64]) -> f64 {
        let p = basis.degree();
        let w = 2 * p + 1;
        let band = self
            .variance_band
            .get_or_init(|| self.make_variance_band(basis));
        let mut q = 0.0;
        for (k, vk) in vals.iter().enumerate() {
            let row = &band[basis.index(first, k) * w..][..w];
            for (l, vl) in vals.iter().enumerate() {
                q += vk * vl * row[l + p - k];
            }
        }
        q
    }

    /// The band of `W = Y K^-1 Y^T`: row `i`, entry `d + p` is `W_{i, i+d}`
    /// (the index taken around a closed curve), `|d| <= p`.
    fn make_variance_band(&self, basis: &Basis) -> Vec<f64> {
        let n = basis.n_functions();
        let p = basis.degree() as isize;
        let dim = self.levels.dim();
        let w = (2 * p + 1) as usize;
        let mut z = vec![0.0; n * dim];
        for (i, zi) in z.chunks_mut(dim).enumerate() {
            for (a, v) in zi.iter_mut().enumerate() {
                *v = self.y[a * n + i];
            }
            self.k_factor.solve_in_place(zi);
        }
        let mut out = vec![0.0; n * w];
        for i in 0..n {
            for d in -p..=p {
                let j = i as isize + d;
                let j = if basis.is_closed() {
                    j.rem_euclid(n as isize)
                } else if (0..n as isize).contains(&j) {
                    j
                } else {
                    continue;
                } as usize;
                out[i * w + (d + p) as usize] =
                    (0..dim).map(|a| z[i * dim + a] * self.y[a * n + j]).sum();
            }
        }
        out
    }

    /// `(a, c)` at parameter `u` of the reference, from the last iteration.
    pub fn levels_at(&self, u: f64) -> (f64, f64) {
        self.levels.levels_at(u, &self.theta)
    }
}

/// The levels' constant parts for `band`, assembled over fixed chunks of
/// pixels in parallel (`solver::chunked`): `B` (column-major, one column of
/// `n` per coefficient), the levels' normal matrix `S` as per-element
/// blocks, and the row sums of `M0`.
fn assemble(
    band: &Band,
    basis: &Basis,
    levels: &LevelBasis,
) -> Result<(Vec<f64>, Vec<f64>, Vec<f64>)> {
    let n = basis.n_functions();
    let p = basis.degree();
    let m = levels.m();
    let dim = levels.dim();
    let width = levels.width();
    let sums = chunked_sum(
        band.len(),
        |range| {
            let mut b = vec![0.0; n * dim];
            let mut s_blocks = vec![0.0; levels.blocks_len()];
            let mut dden = vec![0.0; n];
            let mut tmp = vec![0.0; dim];
            for i in range {
                let w = band.weight[i];
                if w == 0.0 {
                    continue;
                }
                let (g, dg) = (band.gamma[i], band.dgamma[i]);
                let feats = features(g);
                levels.accumulate(i, w, feats, 0.0, Some(&mut s_blocks), &mut tmp);
                let first = band.first[i] as usize;
                let vals = &band.basis[i * (p + 1)..(i + 1) * (p + 1)];
                let lfirst = levels.first[i] as usize;
                let lvals = &levels.vals[i * width..(i + 1) * width];
                for (a, va) in vals.iter().enumerate() {
                    let ia = basis.index(first, a);
                    dden[ia] += w * dg * dg * va;
                    for (k, vk) in lvals.iter().enumerate() {
                        let j = levels.basis.index(lfirst, k);
                        let x = w * dg * va * vk;
                        for (f, phi) in feats.iter().enumerate() {
                            b[(f * m + j) * n + ia] += x * phi;
                        }
                    }
                }
            }
            (b, s_blocks, dden)
        },
        |t, part| {
            t.0.iter_mut().zip(&part.0).for_each(|(a, b)| *a += b);
            t.1.iter_mut().zip(&part.1).for_each(|(a, b)| *a += b);
            t.2.iter_mut().zip(&part.2).for_each(|(a, b)| *a += b);
        },
    );
    sums.ok_or(Error::EmptyBand {
        pixels: 0,
        unknowns: n + dim,
    })
}

/// What a pass over the band reads besides the levels' state.
#[derive(Clone, Copy)]
struct Context<'a> {
    band: &'a Band,
    basis: &'a Basis,
    lambda: &'a [f64],
    /// The pixel values, when the profile is pushed.
    pushed: Option<&'a [f64]>,
    /// Pushed: the pixels the image's encoding clipped (`censor`).
    censored: Option<&'a Censored>,
}

impl Correlation {
    /// [`Correlation::iterate`] with varying levels.
    pub(super) fn iterate_varying(
        &mut self,
        lambda: &[f64],
        sampler: &Sampler,
        polarity: Polarity,
    ) -> std::result::Result<Step, StepFailure> {
        let Some(var) = self.varying.as_deref_mut() else {
            return Err(StepFailure::NonFinite);
        };
        let ctx = Context {
            band: &self.band,
            basis: &self.basis,
            lambda,
            pushed: self.pushed.as_deref(),
            censored: self.censored.as_ref(),
        };
        var.first_pass(ctx, sampler);
        left_image(
            var.chunks.iter().map(|a| (a.outside_count, a.outside)),
            ctx.band.len(),
        )?;
        let sums = var.gather_levels(ctx.pushed.is_some());
        var.solve_levels(&sums, ctx.pushed.is_some(), polarity)?;
        // The right-hand side takes the profile's derivative where the
        // profile is (pushed: at `r - U`); the contrast's average `D` stays
        // that of the reference's (it only scales the step).
        let displaced = ctx.pushed.is_some() && self.displaced_gradient;
        var.second_pass(ctx, displaced);
        let rhs = &mut self.delta;
        let (ssr, a_mean, c_mean) = var.gather_displacement(rhs, sums[0]);
        self.chol.solve_in_place(rhs);
        let max_step = var.woodbury(rhs);
        if !max_step.is_finite() {
            return Err(StepFailure::NonFinite);
        }
        self.ssr = ssr;
        self.levels = Some((a_mean, c_mean));
        Ok(Step {
            a: a_mean,
            c: c_mean,
            residual_rms: (ssr / sums[0]).sqrt(),
            max_step,
        })
    }
}

impl Varying {
    /// Pass 1: `f` and `gamma` (and the pushed profile's derivative and
    /// tilt factor) at the current displacement, kept per pixel; the
    /// levels' normal equations and the moments, per chunk.
    fn first_pass(&mut self, ctx: Context<'_>, sampler: &Sampler) {
        let Context {
            band,
            basis,
            lambda,
            pushed,
            censored,
        } = ctx;
        let lb = &self.levels;
        let theta = &self.theta;
        let have_theta = self.have_theta;
        let per = self.per;
        let tilt = self.tilt.as_deref();
        self.chunks
            .par_iter_mut()
            .zip(self.fbuf.par_chunks_mut(per))
            .zip(self.gbuf.par_chunks_mut(per))
            .zip(self.dbuf.par_chunks_mut(per))
            .zip(self.sbuf.par_chunks_mut(per))
            .enumerate()
            .for_each(|(k, ((((acc, fb), gb), db), sb))| {
                acc.rhs_t.fill(0.0);
                if pushed.is_some() {
                    acc.mat_t.fill(0.0);
                }
                acc.sums = [0.0; 9];
                acc.outside = None;
                acc.outside_count = 0;
                let start = k * per;
                for (j, (((fo, go), dgo), so)) in fb
                    .iter_mut()
                    .zip(gb.iter_mut())
                    .zip(db.iter_mut())
                    .zip(sb.iter_mut())
                    .enumerate()
                {
                    let i = start + j;
                    let w = band.weight[i];
                    if w == 0.0 && pushed.is_some() {
                        // Out of the window (or rejected): counts for nothing.
                        continue;
                    }
                    let u = band.displacement_at(basis, i, lambda);
                    let mut scale = 1.0;
                    let (f, gamma) = match pushed {
                        Some(values) => {
                            let (gamma, dg) = band.profile_at(i, u);
                            *dgo = dg;
                            if let Some(t) = tilt {
                                scale = 1.0 + t[i] * (band.r[i] - u);
                            }
                            // A clipped pixel's light as the last iteration's
                            // levels expect, or left out of both passes (a
                            // NaN value marks it).
                            let model = || {
                                have_theta.then(|| {
                                    let (a, c) = lb.levels(i, theta);
                                    (a + c * gamma) * scale
                                })
                            };
                            let Some(f) = observed(censored, i, values[i], model) else {
                                *fo = f64::NAN;
                                continue;
                            };
                            (f, gamma)
                        }
                        None => {
                            let [x, y] = band.pos[i];
                            let [nx, ny] = band.normal[i];
                            let (xd, yd) = (x + u * nx, y + u * ny);
                            let gamma = band.gamma[i];
                            let cut = || band.cut_by_border(i, u, |x, y| sampler.in_domain(x, y));
                            match sampler.value(xd, yd) {
                                Some(f) => (f, gamma),
                                // Beyond a border that cuts the band: as in
                                // the global pass.
                                None if cut() => {
                                    match (have_theta, sampler.value_clamped(xd, yd)) {
                                        (true, _) => {
                                            let (a, c) = lb.levels(i, theta);
                                            (a + c * gamma, gamma)
                                        }
                                        (false, Some(f)) => (f, gamma),
                                        (false, None) => {
                                            acc.outside = Some([xd, yd]);
                                            acc.outside_count = usize::MAX / 1024;
                                            return;
                                        }
                                    }
                                }
                                None if have_theta => {
                                    acc.outside.get_or_insert([xd, yd]);
                                    acc.outside_count += 1;
                                    let (a, c) = lb.levels(i, theta);
                                    (a + c * gamma, gamma)
                                }
                                None => {
                                    acc.outside = Some([xd, yd]);
                                    acc.outside_count = usize::MAX / 1024;
                                    return;
                                }
                            }
                        }
                    };
                    *fo = f;
                    *go = gamma;
                    *so = scale;
                    let mat = pushed.is_some().then_some(&mut acc.mat_t[..]);
                    let [f0, f1] = features(gamma);
                    let feats = [f0 * scale, f1 * scale];
                    lb.accumulate(i, w, feats, f, mat, &mut acc.rhs_t);
                    let s = &mut acc.sums;
                    s[0] += w;
                    s[1] += w * f;
                    s[2] += w * gamma;
                    s[3] += w * gamma * gamma;
                    s[4] += w * f * gamma;
                    s[5] += w * f * f;
                }
            });
    }

    /// The first pass's chunks summed: the moments (returned), the levels'
    /// right-hand side into `t` and, pushed, their matrix into `mat`.
    fn gather_levels(&mut self, pushed: bool) -> [f64; 9] {
        let mut sums = [0.0; 9];
        self.t.fill(0.0);
        if pushed {
            self.mat.fill(0.0);
        }
        for acc in &self.chunks {
            for (s, v) in sums.iter_mut().zip(acc.sums) {
                *s += v;
            }
            for (t, v) in self.t.iter_mut().zip(&acc.rhs_t) {
                *t += v;
            }
            if pushed {
                self.levels.scatter(&acc.mat_t, &mut self.mat);
            }
        }
        sums
    }

    /// The levels' coefficients `theta` of this iteration: solved from the
    /// normal equations, or constant when a forced polarity disagrees with
    /// the band (or the levels' matrix is singular); with the global pair's
    /// polarity and contrast checks.
    fn solve_levels(
        &mut self,
        sums: &[f64; 9],
        pushed: bool,
        polarity: Polarity,
    ) -> std::result::Result<(), StepFailure> {
        // The global pair, for the polarity and contrast checks.
        let [n, sf, sg, sgg, sfg, sff, ..] = *sums;
        let m = Moments {
            n,
            sf,
            sg,
            sgg,
            sfg,
            sff,
        };
        let (a_global, c_global) = m.levels();
        if !(a_global.is_finite() && c_global.is_finite()) {
            return Err(StepFailure::NonFinite);
        }
        let sign = polarity_sign(polarity);
        if sign * c_global < 0.0 || (sign != 0.0 && c_global == 0.0) {
            // As with the global pair: the forced polarity disagrees with
            // the band, the curve is still far from the edge.
            let (a, c) = m.forced(sign);
            self.set_constant(a, c);
        } else {
            if m.no_contrast(c_global) {
                return Err(StepFailure::NoContrast);
            }
            // Pulled back, the levels' matrix is that of U = 0, factored
            // once; pushed, it follows U.
            let factor = match pushed {
                true => self
                    .mat_factor
                    .refactor(&self.mat)
                    .ok()
                    .map(|_| &self.mat_factor),
                false => Some(&self.s_factor),
            };
            match factor {
                Some(f) => {
                    f.solve_in_place(&mut self.t);
                    self.theta.copy_from_slice(&self.t);
                }
                None => self.set_constant(a_global, c_global),
            }
        }
        self.have_theta = true;
        Ok(())
    }

    /// Pass 2: residuals with the levels; per chunk, the displacement's
    /// right-hand side (with the profile's derivative at `r - U` when
    /// `displaced`, else at `r`), the contrast's sums over each function's
    /// support, and the sums of `w r^2`, `w a`, `w c`.
    fn second_pass(&mut self, ctx: Context<'_>, displaced: bool) {
        let Context {
            band,
            basis,
            pushed,
            ..
        } = ctx;
        let p = basis.degree();
        let per = self.per;
        let lb = &self.levels;
        let theta = &self.theta;
        let (fbuf, gbuf, sbuf) = (&self.fbuf, &self.gbuf, &self.sbuf);
        let dnow = if displaced {
            &self.dbuf[..]
        } else {
            &band.dgamma[..]
        };
        self.chunks.par_iter_mut().enumerate().for_each(|(k, acc)| {
            acc.rhs_l.fill(0.0);
            acc.dnum.fill(0.0);
            let mut s = [0.0; 3];
            let start = k * per;
            let end = (start + per).min(band.len());
            for i in start..end {
                let w = band.weight[i];
                if (w == 0.0 || fbuf[i].is_nan()) && pushed.is_some() {
                    continue;
                }
                let first = band.first[i] as usize;
                let vals = &band.basis[i * (p + 1)..(i + 1) * (p + 1)];
                let (a, c) = lb.levels(i, theta);
                let dg = band.dgamma[i];
                let r = (a + c * gbuf[i]) * sbuf[i] - fbuf[i];
                let x = w * c * r * dnow[i];
                let y = w * dg * dg * c;
                for (k, v) in vals.iter().enumerate() {
                    let j = basis.index(first, k);
                    acc.rhs_l[j] += x * v;
                    acc.dnum[j] += y * v;
                }
                s[0] += w * r * r;
                s[1] += w * a;
                s[2] += w * c;
            }
            acc.sums[6] = s[0];
            acc.sums[7] = s[1];
            acc.sums[8] = s[2];
        });
    }

    /// The second pass's chunks summed: the displacement's right-hand side
    /// into `rhs`, divided by `D_i`, the contrast averaged over the
    /// support of `N_i` (kept away from zero, and on the mean's side,
    /// where the band sees little); `n` the pass's weight. Returns the
    /// residual sum of squares and the mean levels.
    fn gather_displacement(&mut self, rhs: &mut [f64], n: f64) -> (f64, f64, f64) {
        rhs.fill(0.0);
        self.d.fill(0.0);
        let (mut ssr, mut sa, mut sc) = (0.0, 0.0, 0.0);
        for acc in &self.chunks {
            for (r, v) in rhs.iter_mut().zip(&acc.rhs_l) {
                *r += v;
            }
            for (d, v) in self.d.iter_mut().zip(&acc.dnum) {
                *d += v;
            }
            ssr += acc.sums[6];
            sa += acc.sums[7];
            sc += acc.sums[8];
        }
        let (a_mean, c_mean) = (sa / n, sc / n);
        let floor = 0.25 * c_mean.abs();
        for (d, den) in self.d.iter_mut().zip(&self.dden) {
            let v = if *den > 0.0 { *d / den } else { c_mean };
            *d = if v * c_mean.signum() < floor {
                floor * c_mean.signum()
            } else {
                v
            };
        }
        for (r, d) in rhs.iter_mut().zip(&self.d) {
            *r /= d;
        }
        (ssr, a_mean, c_mean)
    }

    /// The step from `z = M0^-1 b` in `rhs`: the Woodbury term
    /// `Y K^-1 B^T z` added, over `D_i`. Returns `max |dLambda|`.
    fn woodbury(&mut self, rhs: &mut [f64]) -> f64 {
        let nn = rhs.len();
        for (col, t) in self.t.iter_mut().enumerate() {
            *t = self.b[col * nn..(col + 1) * nn]
                .iter()
                .zip(rhs.iter())
                .map(|(b, z)| b * z)
                .sum();
        }
        self.k_factor.solve_in_place(&mut self.t);
        let mut max_step: f64 = 0.0;
        for (i, (r, d)) in rhs.iter_mut().zip(&self.d).enumerate() {
            let corr: f64 = self
                .t
                .iter()
                .enumerate()
                .map(|(col, t)| self.y[col * nn + i] * t)
                .sum();
            *r = (*r + corr) / d;
            max_step = max_step.max(r.abs());
        }
        max_step
    }
}

#[cfg(test)]
mod tests {
    use crate::band::Band;
    use crate::correlation::levels::LevelModel;
    use crate::correlation::Correlation;
    use crate::curve::InitialCurve;
    use crate::spline::{Basis, MAX_DEGREE};
    use crate::virtual_image::Kind;

    /// The band of `Y K^-1 Y^T` against the dense solve it replaces, on a
    /// closed and an open curve.
    #[test]
    fn variance_band_matches_the_dense_solve() {
        let starts = [
            InitialCurve::Circle {
                cx: 100.0,
                cy: 100.0,
                r: 60.0,
            },
            InitialCurve::Segment {
                x0: 20.0,
                y0: 40.0,
                x1: 180.0,
                y1: 150.0,
            },
        ];
        for init in starts {
            let curve = init.to_curve().unwrap();
            let l = curve.param_length();
            let basis = Basis::new(3, 12, l, curve.is_closed()).unwrap();
            let band = Band::build(&curve, &basis, 3.0, Kind::Silhouette, 200, 200).unwrap();
            let levels = LevelModel::Varying {
                element_length: 30.0,
            };
            let corr = Correlation::new(band, basis.clone(), levels).unwrap();
            let var = corr.varying.as_deref().unwrap();
            let (n, dim) = (basis.n_functions(), var.levels.dim());
            for k in 0..97 {
                let u = (k as f64 + 0.5) / 97.0 * l;
                let mut v = [0.0; MAX_DEGREE + 1];
                let first = basis.eval(u, &mut v);
                let vals = &v[..4];
                let fast = var.variance_term(&basis, first, vals);
                let t: Vec<f64> = (0..dim)
                    .map(|col| {
                        vals.iter()
                            .enumerate()
                            .map(|(k, v)| v * var.y[col * n + basis.index(first, k)])
                            .sum()
                    })
                    .collect();
                let mut z = t.clone();
                var.k_factor.solve_in_place(&mut z);
                let direct: f64 = t.iter().zip(&z).map(|(a, b)| a * b).sum();
                assert!(direct > 0.0);
                assert!(
                    (fast - direct).abs() <= 1e-9 * direct,
                    "{u}: {fast} vs {direct}"
                );
            }
        }
    }
}
