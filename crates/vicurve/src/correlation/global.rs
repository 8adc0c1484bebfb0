//! One iteration with the global pair of gray levels: a pass over the
//! band pixels (the image pulled back at the displaced pixels, or the
//! profile pushed), the levels `(a, c)` in closed form, and the joint
//! Gauss–Newton step by the Woodbury identity (see the [module
//! docs](super)).

use super::censor::{observed, Censored};
use super::{left_image, polarity_sign, Accumulator, Correlation, Moments, Step, StepFailure};
use crate::band::Band;
use crate::interp::Sampler;
use crate::spline::Basis;
use crate::virtual_image::Polarity;
use rayon::prelude::*;

/// What a pixel pass reads besides its chunk.
struct Pass<'a> {
    band: &'a Band,
    basis: &'a Basis,
    lambda: &'a [f64],
    sampler: &'a Sampler,
    /// The pixel values, when the profile is pushed.
    pushed: Option<&'a [f64]>,
    /// Pushed: the pixels the image's encoding clipped (`censor`).
    censored: Option<&'a Censored>,
    /// The last iteration's levels (pixels displaced out of the image take
    /// them).
    levels: Option<(f64, f64)>,
    /// Pushed: the gradient at `r - U` rather than at `r`.
    displaced_gradient: bool,
}

impl Pass<'_> {
    /// Accumulate the chunk `acc` of band pixels.
    fn run(&self, acc: &mut Accumulator) {
        let Pass {
            band,
            basis,
            lambda,
            sampler,
            pushed,
            censored,
            levels,
            displaced_gradient,
        } = *self;
        let p = basis.degree();
        acc.clear();
        for i in acc.start..acc.end {
            let w = band.weight[i];
            if w == 0.0 && pushed.is_some() {
                // Out of the window (or rejected): counts for nothing.
                continue;
            }
            let first = band.first[i] as usize;
            let vals = &band.basis[i * (p + 1)..(i + 1) * (p + 1)];
            let u = band.displacement_at(basis, i, lambda);
            let mut dg = band.dgamma[i];
            let (f, gamma) = match pushed {
                Some(values) => {
                    let (gamma, d) = band.profile_at(i, u);
                    let model = || levels.map(|(a, c)| a + c * gamma);
                    let Some(f) = observed(censored, i, values[i], model) else {
                        continue;
                    };
                    if displaced_gradient {
                        dg = d;
                    }
                    let (wg, wd) = (w * gamma * dg, w * dg);
                    for (k, v) in vals.iter().enumerate() {
                        let j = basis.index(first, k);
                        acc.g_proj[j] += wg * v;
                        acc.d_proj[j] += wd * v;
                    }
                    (f, gamma)
                }
                None => {
                    let [x, y] = band.pos[i];
                    let [nx, ny] = band.normal[i];
                    let (xd, yd) = (x + u * nx, y + u * ny);
                    let f = match (sampler.value(xd, yd), levels) {
                        (Some(f), _) => f,
                        // Beyond a border that cuts the band (a dot near
                        // it): as fitting exactly, or before any levels
                        // the image extended by its border; never the
                        // curve leaving the image.
                        (None, lv) if band.cut_by_border(i, u, |x, y| sampler.in_domain(x, y)) => {
                            match (lv, sampler.value_clamped(xd, yd)) {
                                (Some((a, c)), _) => a + c * band.gamma[i],
                                (None, Some(f)) => f,
                                (None, None) => {
                                    acc.outside = Some([xd, yd]);
                                    acc.outside_count = usize::MAX / 1024;
                                    return;
                                }
                            }
                        }
                        // Displaced out of the image (an open curve's end
                        // at the border): taken as fitting exactly, as
                        // long as few pixels are.
                        (None, Some((a, c))) => {
                            acc.outside.get_or_insert([xd, yd]);
                            acc.outside_count += 1;
                            a + c * band.gamma[i]
                        }
                        (None, None) => {
                            acc.outside = Some([xd, yd]);
                            acc.outside_count = usize::MAX / 1024;
                            return;
                        }
                    };
                    (f, band.gamma[i])
                }
            };
            let wf = w * f;
            let proj = wf * dg;
            for (k, v) in vals.iter().enumerate() {
                acc.f_proj[basis.index(first, k)] += proj * v;
            }
            acc.sum_f += wf;
            acc.sum_g += w * gamma;
            acc.sum_gg += w * gamma * gamma;
            acc.sum_fg += wf * gamma;
            acc.sum_ff += wf * f;
            acc.sum_w += w;
        }
    }
}

impl Correlation {
    /// [`Correlation::iterate`] with the global pair of levels.
    pub(super) fn iterate_global(
        &mut self,
        lambda: &[f64],
        sampler: &Sampler,
        polarity: Polarity,
    ) -> std::result::Result<Step, StepFailure> {
        let pass = Pass {
            band: &self.band,
            basis: &self.basis,
            lambda,
            sampler,
            pushed: self.pushed.as_deref(),
            censored: self.censored.as_ref(),
            levels: self.levels,
            displaced_gradient: self.displaced_gradient,
        };
        self.acc.par_iter_mut().for_each(|acc| pass.run(acc));
        left_image(
            self.acc.iter().map(|a| (a.outside_count, a.outside)),
            self.band.len(),
        )?;
        let m = self.gather();
        let n = m.n;
        let (mut a, mut c) = m.levels();
        let sign = polarity_sign(polarity);
        if sign * c < 0.0 || (sign != 0.0 && c == 0.0) {
            // The forced polarity disagrees with the band's content (the
            // curve is still far from the edge): take the contrast from the
            // band's spread, which is that of a step between two levels.
            (a, c) = m.forced(sign);
        }
        if !(a.is_finite() && c.is_finite()) {
            return Err(StepFailure::NonFinite);
        }
        if m.no_contrast(c) {
            return Err(StepFailure::NoContrast);
        }
        let max_step = self.solve_step(a, c)?;
        let ssr = m.ssr(a, c);
        self.ssr = ssr;
        self.levels = Some((a, c));
        Ok(Step {
            a,
            c,
            residual_rms: (ssr / n).sqrt(),
            max_step,
        })
    }

    /// The chunks' sums: the moments (with the system's pixel count), `F`
    /// into `delta`, and the current `H = sum gamma dg N_i` and
    /// `sum dg N_i` (pulled back, the constants `G2` and `G1`; pushed, the
    /// current profile's).
    fn gather(&mut self) -> Moments {
        let pushed = self.pushed.is_some();
        // With censored pixels, the weight of those the pass counted.
        let n = match self.censored {
            Some(_) => self.acc.iter().map(|a| a.sum_w).sum(),
            None => self.count,
        };
        let mut m = Moments {
            n,
            ..Moments::default()
        };
        let rhs = &mut self.delta;
        rhs.iter_mut().for_each(|v| *v = 0.0);
        let h = &mut self.h;
        let g1_now = &mut self.g1_now;
        if pushed {
            h.iter_mut().for_each(|v| *v = 0.0);
            g1_now.iter_mut().for_each(|v| *v = 0.0);
        } else {
            h.copy_from_slice(&self.g2);
            g1_now.copy_from_slice(&self.g1);
        }
        for acc in &self.acc {
            m.sf += acc.sum_f;
            m.sg += acc.sum_g;
            m.sgg += acc.sum_gg;
            m.sfg += acc.sum_fg;
            m.sff += acc.sum_ff;
            for (r, v) in rhs.iter_mut().zip(&acc.f_proj) {
                *r += v;
            }
            if pushed {
                for (r, v) in h.iter_mut().zip(&acc.g_proj) {
                    *r += v;
                }
                for (r, v) in g1_now.iter_mut().zip(&acc.d_proj) {
                    *r += v;
                }
            }
        }
        m
    }

    /// The step `dLambda` into `delta` for levels `(a, c)`, `F` being in
    /// `delta`: `b_i = c (a G1_i + c H_i - F_i)`, `z = M0^-1 b`, then the
    /// Woodbury term `Y K^-1 B^T z`, over `c^2`. Returns `max |dLambda|`.
    fn solve_step(&mut self, a: f64, c: f64) -> std::result::Result<f64, StepFailure> {
        let rhs = &mut self.delta;
        for ((r, g1), h) in rhs.iter_mut().zip(self.g1_now.iter()).zip(self.h.iter()) {
            *r = c * (a * g1 + c * h - *r);
        }
        self.chol.solve_in_place(rhs);
        let t0: f64 = self.g1.iter().zip(rhs.iter()).map(|(g, z)| g * z).sum();
        let t1: f64 = self.g2.iter().zip(rhs.iter()).map(|(g, z)| g * z).sum();
        let w0 = self.k_inv[0] * t0 + self.k_inv[1] * t1;
        let w1 = self.k_inv[2] * t0 + self.k_inv[3] * t1;
        let inv_c2 = 1.0 / (c * c);
        let mut max_step: f64 = 0.0;
        for ((r, y1), y2) in rhs.iter_mut().zip(&self.y1).zip(&self.y2) {
            *r = (*r + y1 * w0 + y2 * w1) * inv_c2;
            max_step = max_step.max(r.abs());
        }
        if !max_step.is_finite() {
            return Err(StepFailure::NonFinite);
        }
        Ok(max_step)
    }
}
