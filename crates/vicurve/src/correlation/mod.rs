//! The Gauss–Newton system of one reference curve.
//!
//! Every sum below runs over the band pixels with the weight `w` of
//! [`Band`] (`1 / (1 - kappa r)` for the paper's profiles, 1 for the
//! pushed ones; left out of the formulas).
//!
//! With `g = a + c gamma(r / R)` and the gradient of the physical image `f`
//! replaced by that of `g`, the normal matrix is `c^2 M0` with
//!
//! ```text
//! M0_ij = sum_X gamma'(r/R)^2 / R^2 N_i(s) N_j(s)
//! ```
//!
//! which depends on the reference only: it is assembled and factorised once
//! ([`Correlation::new`]). Each iteration ([`Correlation::iterate`]) is one
//! pass over the band: sample `f` at the displaced pixels `X + U(s) n(s)`,
//! accumulate `F_i = sum f dg N_i` and the moments of `f`, then
//!
//! * the gray levels `(a, c)` are the linear least-squares fit of
//!   `f(X + u)` by `a + c gamma` (closed form, 2 x 2);
//! * `b_i = sum (g - f) c dg N_i = c (a G1_i + c G2_i - F_i)` with the
//!   constant vectors `G1_i = sum dg N_i` and `G2_i = sum gamma dg N_i`;
//! * the step is the joint Gauss–Newton step in `(Lambda, a, c)`: with
//!   `B = [G1 G2]` and `S` the 2 x 2 normal matrix of `(a, c)`, the Schur
//!   complement gives `dLambda = (M0 - B S^-1 B^T)^-1 b / c^2`, applied with
//!   the Woodbury identity on the banded factor of `M0` (`Y = M0^-1 B` and the
//!   2 x 2 matrix `K = S - B^T Y` are computed once per reference). Stepping
//!   in `Lambda` alone (`M0^-1 b / c^2`) converges only linearly, with ratio
//!   `(sum dg)^2 / (n sum dg^2)` (0.81 for a silhouette): that fraction of a
//!   shift of the edge is absorbed by the refitted dark level `a`.
//!
//! # Pulling the image or pushing the profile
//! The method samples `f` at the displaced pixels (`pull back`, above),
//! which interpolates the physical image. With the pixel-edge profile
//! [`Correlation::prepare`] instead
//! keeps `f` at the pixel centres, exactly as recorded, and moves the virtual
//! profile: `g = a + c gamma(r - U(s))`, `r - U` being the pixel's distance
//! to the displaced curve to first order (exact at `U = 0`, so a stage that
//! re-references until `U` is negligible converges to the exact optimum). No
//! interpolation means no interpolation error: with a virtual profile that
//! matches the physical edge, a sharp edge is fitted without aliasing. The
//! moments of `gamma` then change with `U` and are accumulated in the pass,
//! and so does the gradient: `F`, `G1` and `H` take the profile's
//! derivative at `r - U`, so that the iteration's fixed point is the
//! least-squares optimum of the displaced profile. (With the derivative
//! at `r`, as the pulled image has it, the fixed point was an optimum
//! weighted by the reference's profile: a tracked frame's settle then moved
//! the curve by 3 % of the frame's motion at a blur of 1 px, by 14 to 35 %
//! at 0.5 px, and needed two or three settles; now 0.1 to 1 % and 2 to
//! 4 %, one settle.) `B`, `K` and the factor stay those of `U = 0`: they
//! set the step's size, not where the iteration stops.
//!
//! What the settle still corrects is the band: centred on the reference,
//! not on the edge, it holds more of one plateau than of the other, which
//! tips the balance where the physical profile is not exactly the virtual
//! one. A band with a margin ([`Band::build_windowed`]) is re-windowed on
//! the displaced curve at the start of every iteration
//! ([`Band::recentre`]), and its fixed point no longer depends on the
//! reference (within 2e-5 px for references 0.4 px off a disc, against
//! 8.5e-3 px without: the test
//! `the_fixed_point_hardly_depends_on_the_reference`). Out-of-window pixels
//! (weight 0) are skipped.
//!
//! No allocation happens in `iterate`: the per-thread accumulators are made
//! once in `new`.

mod censor;
mod global;
pub mod levels;
mod misfit;
mod tilt;
mod varying;

pub(crate) use misfit::ResidualBin;
pub(crate) use tilt::Measured as MeasuredTilt;

use crate::band::Band;
use crate::error::{Error, Result};
use crate::interp::Sampler;
use crate::solver::chunked::chunked_sum;
use crate::solver::{BandCholesky, DenseCholesky, SymBandMatrix};
use crate::spline::Basis;
use crate::virtual_image::Polarity;
use crate::virtual_image::Profile;
use censor::{observed, Censored};
use levels::{LevelBasis, LevelModel};
use rayon::prelude::*;
use std::sync::OnceLock;

/// Band pixels displaced out of the image that an iteration tolerates (or
/// 2 % of the band if more): they are taken as fitting exactly.
const MAX_OUTSIDE: usize = 8;

/// Band pixels used by [`Correlation::estimate_noise`] at most.
const NOISE_PIXELS: usize = 8192;

/// Partial sums of one chunk of band pixels.
#[derive(Clone, Debug)]
struct Accumulator {
    start: usize,
    end: usize,
    f_proj: Vec<f64>,
    /// Pushed profile only: `sum gamma(r - U) dg N_i`.
    g_proj: Vec<f64>,
    /// Pushed profile only: `sum dg N_i`.
    d_proj: Vec<f64>,
    sum_f: f64,
    sum_g: f64,
    sum_gg: f64,
    sum_fg: f64,
    sum_ff: f64,
    /// The weight of the pixels the pass counted (pushed profile with
    /// censored pixels: fewer than the band's).
    sum_w: f64,
    outside: Option<[f64; 2]>,
    outside_count: usize,
}

impl Accumulator {
    /// Accumulators for a band of `len` pixels in fixed chunks (two per
    /// thread, at most 64), `n` unknowns.
    fn chunks(len: usize, n: usize) -> Vec<Accumulator> {
        let chunks = (rayon::current_num_threads() * 2).clamp(1, 64);
        let per = len.div_ceil(chunks);
        (0..chunks)
            .map(|k| Accumulator {
                start: (k * per).min(len),
                end: ((k + 1) * per).min(len),
                f_proj: vec![0.0; n],
                g_proj: vec![0.0; n],
                d_proj: vec![0.0; n],
                sum_f: 0.0,
                sum_g: 0.0,
                sum_gg: 0.0,
                sum_fg: 0.0,
                sum_ff: 0.0,
                sum_w: 0.0,
                outside: None,
                outside_count: 0,
            })
            .collect()
    }

    /// Zero the sums for a new pass.
    fn clear(&mut self) {
        self.f_proj.iter_mut().for_each(|v| *v = 0.0);
        self.g_proj.iter_mut().for_each(|v| *v = 0.0);
        self.d_proj.iter_mut().for_each(|v| *v = 0.0);
        self.sum_f = 0.0;
        self.sum_g = 0.0;
        self.sum_gg = 0.0;
        self.sum_fg = 0.0;
        self.sum_ff = 0.0;
        self.sum_w = 0.0;
        self.outside = None;
        self.outside_count = 0;
    }
}

/// What depends on the reference only: `M0`, `G1_i = sum dg N_i`,
/// `G2_i = sum gamma dg N_i` and the sums of `w`, `w gamma`, `w gamma^2`.
struct Constants {
    m: SymBandMatrix,
    g1: Vec<f64>,
    g2: Vec<f64>,
    sums: [f64; 3],
}

impl Constants {
    /// Assembled over fixed chunks of the band's pixels in parallel
    /// (`solver::chunked`, so the sums do not depend on the threads).
    fn assemble(band: &Band, basis: &Basis) -> Result<Self> {
        let n = basis.n_functions();
        let p = basis.degree();
        let zero = SymBandMatrix::zeros(n, p, basis.is_closed())?;
        let (m, g1, g2, sums) = chunked_sum(
            band.len(),
            |range| {
                let mut m = zero.clone();
                let mut g1 = vec![0.0; n];
                let mut g2 = vec![0.0; n];
                let mut sums = [0.0; 3];
                for i in range {
                    let w = band.weight[i];
                    if w == 0.0 {
                        continue;
                    }
                    let first = band.first[i] as usize;
                    let vals = &band.basis[i * (p + 1)..(i + 1) * (p + 1)];
                    let dg = band.dgamma[i];
                    let g = band.gamma[i];
                    sums[0] += w;
                    sums[1] += w * g;
                    sums[2] += w * g * g;
                    for (a, va) in vals.iter().enumerate() {
                        let ia = basis.index(first, a);
                        g1[ia] += w * dg * va;
                        g2[ia] += w * g * dg * va;
                    }
                    m.add_outer(first, w * dg * dg, vals);
                }
                (m, g1, g2, sums)
            },
            |t, part| {
                t.0.add_matrix(&part.0);
                t.1.iter_mut().zip(&part.1).for_each(|(a, b)| *a += b);
                t.2.iter_mut().zip(&part.2).for_each(|(a, b)| *a += b);
                t.3.iter_mut().zip(part.3).for_each(|(a, b)| *a += b);
            },
        )
        .ok_or(Error::EmptyBand {
            pixels: band.len(),
            unknowns: n + 2,
        })?;
        Ok(Constants { m, g1, g2, sums })
    }
}

/// Weighted moments of a pass: the weight `n` (or pixel count), and the
/// sums of `f`, `gamma`, `gamma^2`, `f gamma` and `f^2` (`f` the image at
/// the band pixels, `gamma` the virtual profile).
#[derive(Clone, Copy, Debug, Default)]
struct Moments {
    n: f64,
    sf: f64,
    sg: f64,
    sgg: f64,
    sfg: f64,
    sff: f64,
}

impl Moments {
    /// The linear least-squares levels `(a, c)` of `f ~ a + c gamma`.
    fn levels(&self) -> (f64, f64) {
        let Moments {
            n,
            sf,
            sg,
            sgg,
            sfg,
            ..
        } = *self;
        let det = n * sgg - sg * sg;
        ((sgg * sf - sg * sfg) / det, (n * sfg - sg * sf) / det)
    }

    /// Standard deviation of `f` over the band.
    fn spread(&self) -> f64 {
        (self.sff / self.n - (self.sf / self.n).powi(2))
            .max(0.0)
            .sqrt()
    }

    /// The levels when a forced polarity (`sign`) disagrees with the
    /// band's content (the curve still far from the edge): the contrast
    /// from the band's spread, which is that of a step between two levels.
    fn forced(&self, sign: f64) -> (f64, f64) {
        let c = sign * 2.0 * self.spread();
        (self.sf / self.n - c * self.sg / self.n, c)
    }

    /// Whether contrast `c` is too small for the band to see an edge.
    fn no_contrast(&self, c: f64) -> bool {
        c.abs() <= 1e-9 || c.abs() < 1e-6 * self.spread()
    }

    /// The residual sum of squares of `f - (a + c gamma)`.
    fn ssr(&self, a: f64, c: f64) -> f64 {
        let Moments {
            n,
            sf,
            sg,
            sgg,
            sfg,
            sff,
        } = *self;
        (n * a * a + c * c * sgg + sff + 2.0 * a * c * sg - 2.0 * a * sf - 2.0 * c * sfg).max(0.0)
    }
}

/// The sign a forced polarity gives the contrast (0: estimated).
fn polarity_sign(polarity: Polarity) -> f64 {
    match polarity {
        Polarity::Auto => 0.0,
        Polarity::Positive => 1.0,
        Polarity::Negative => -1.0,
    }
}

/// A pass whose chunks displaced more than `MAX_OUTSIDE` pixels (or 2 % of
/// the band's `len`) out of the image has left it, at the first such
/// point; `chunks` gives each chunk's count and first point.
fn left_image(
    chunks: impl Iterator<Item = (usize, Option<[f64; 2]>)> + Clone,
    len: usize,
) -> std::result::Result<(), StepFailure> {
    let outside: usize = chunks.clone().map(|(n, _)| n).sum();
    if outside > MAX_OUTSIDE.max(len / 50) {
        let q = chunks
            .filter_map(|(_, q)| q)
            .next()
            .unwrap_or([f64::NAN; 2]);
        return Err(StepFailure::LeftImage(q));
    }
    Ok(())
}

/// Why an iteration could not produce a step.
#[derive(Clone, Copy, Debug, PartialEq)]
pub(crate) enum StepFailure {
    /// A displaced pixel fell outside the image at this point.
    LeftImage([f64; 2]),
    /// The band sees no contrast.
    NoContrast,
    /// NaN or infinity appeared.
    NonFinite,
}

/// What one iteration found.
#[derive(Clone, Copy, Debug, PartialEq)]
pub(crate) struct Step {
    /// Dark level `a` of the virtual image.
    pub a: f64,
    /// Contrast `c`.
    pub c: f64,
    /// RMS of `g - f(X + u)` over the band, gray levels.
    pub residual_rms: f64,
    /// `max |dLambda|` before any step limit, pixels.
    pub max_step: f64,
}

/// The prepared system of one reference; see the [module docs](self).
pub(crate) struct Correlation {
    band: Band,
    basis: Basis,
    chol: BandCholesky,
    g1: Vec<f64>,
    g2: Vec<f64>,
    /// `M0^-1 G1` and `M0^-1 G2`.
    y1: Vec<f64>,
    y2: Vec<f64>,
    /// `K^-1`, row-major 2 x 2.
    k_inv: [f64; 4],
    /// Sum of the weights (about the number of pixels).
    count: f64,
    pixels: f64,
    acc: Vec<Accumulator>,
    /// Scratch: `sum gamma dg N_i` of the current iteration.
    h: Vec<f64>,
    /// Scratch, pushed profile: `sum dg N_i` of the current iteration.
    g1_now: Vec<f64>,
    /// The gray levels `(a, c)` of the last iteration.
    levels: Option<(f64, f64)>,
    /// Robust weight of each band pixel (1: kept whole, 0: rejected), already
    /// folded into the band's weights; see `robust_refit` in the fit.
    robust: Vec<f64>,
    /// The pixel values at the band pixels when the profile is pushed (see
    /// the [module docs](self)); `None` when the image is pulled back.
    pushed: Option<Vec<f64>>,
    /// Pushed profile: the band pixels the image's encoding clipped, when
    /// any are (see `censor`).
    censored: Option<Censored>,
    /// The last step, `dLambda`.
    delta: Vec<f64>,
    /// The last residual sum of squares.
    ssr: f64,
    /// Pure-noise variance of the gray levels, once estimated
    /// ([`Correlation::estimate_noise`]).
    noise_var: Option<f64>,
    /// Gray levels that vary along the curve ([`LevelModel::Varying`]);
    /// `None`: the global pair.
    varying: Option<Box<varying::Varying>>,
    /// With the global pair and a pixel profile (an edge's, a thin
    /// line's): the light's tilt across the band, already taken out of
    /// the pushed values (see `new_pushed`); the varying levels keep
    /// theirs.
    global_tilt: Option<MeasuredTilt>,
    /// The band of `M0^-1` ([`BandCholesky::inverse_band`]), made on the
    /// first [`Self::position_sigma`].
    inverse_band: OnceLock<Vec<f64>>,
    /// Pushed profile: whether the gradient takes the profile's derivative
    /// at `r - U` (the default, see the module docs) or at `r`
    /// ([`Self::use_reference_gradient`]).
    displaced_gradient: bool,
    /// The slowest contraction its runs have shown: the largest ratio of
    /// a step to the one before it in the same run (`None` before a run's
    /// second step). A property of the system (how far `M0` is from the
    /// residual's own curvature), which stays as long as `M0` and the
    /// gradient do: a kept band's next frames may rely on it
    /// (`fit::run::error_left`).
    contraction: Option<f64>,
}

impl Correlation {
    /// Assemble and factorise `M0` and the constant vectors for `band`,
    /// with gray levels as `levels` asks (the global pair when the curve is
    /// too short for varying ones, or they cannot be told apart from the
    /// displacement).
    pub fn new(mut band: Band, basis: Basis, levels: LevelModel) -> Result<Self> {
        // A band with a margin: `M0` (and everything constant) is that of
        // the pixels around the reference, whatever window the band was
        // left with (a robust reweighting's, a finished run's), so that a
        // system is the same however its band got here (a tracked
        // sequence may build it again, see `fit::track`). The iterations
        // window it on the displaced curve.
        band.window_at_reference();
        let n = basis.n_functions();
        if band.len() < 2 * n + 2 {
            return Err(Error::EmptyBand {
                pixels: band.len(),
                unknowns: n + 2,
            });
        }
        let Constants { m, g1, g2, sums } = Constants::assemble(&band, &basis)?;
        let [count, sum_g, sum_gg] = sums;
        let chol = BandCholesky::factor(&m)?;
        let mut y1 = g1.clone();
        let mut y2 = g2.clone();
        chol.solve_in_place(&mut y1);
        chol.solve_in_place(&mut y2);
        let dot = |u: &[f64], v: &[f64]| u.iter().zip(v).map(|(a, b)| a * b).sum::<f64>();
        let k = [
            count - dot(&g1, &y1),
            sum_g - dot(&g1, &y2),
            sum_g - dot(&g2, &y1),
            sum_gg - dot(&g2, &y2),
        ];
        let det = k[0] * k[3] - k[1] * k[2];
        if !(det.is_finite() && det > 1e-12 * (k[0] * k[3]).abs().max(1e-300)) {
            // The gray levels cannot be told apart from a displacement.
            return Err(Error::NotPositiveDefinite { index: n });
        }
        let k_inv = [k[3] / det, -k[1] / det, -k[2] / det, k[0] / det];
        let acc = Accumulator::chunks(band.len(), n);
        let band_len = band.len();
        let varying = levels
            .basis(basis.length(), basis.is_closed())
            .and_then(|lb| varying::Varying::new(&band, &basis, &chol, lb).ok())
            .map(Box::new);
        Ok(Correlation {
            varying,
            global_tilt: None,
            count,
            pixels: band.inside() as f64,
            y1,
            y2,
            k_inv,
            band,
            basis,
            chol,
            g1,
            g2,
            acc,
            h: vec![0.0; n],
            g1_now: vec![0.0; n],
            robust: vec![1.0; band_len],
            levels: None,
            pushed: None,
            censored: None,
            delta: vec![0.0; n],
            ssr: 0.0,
            noise_var: None,
            inverse_band: OnceLock::new(),
            displaced_gradient: true,
            contraction: None,
        })
    }

    /// The system for `band`, comparing as its profile requires: the
    /// pixel-edge profile is pushed (module docs), the paper's profiles pull
    /// the image back. `tilt`: the light's tilt measured on an earlier
    /// reference of the stage, taken instead of measuring it again when it
    /// serves (see `tilt`).
    pub fn prepare(
        band: Band,
        basis: Basis,
        sampler: &Sampler,
        levels: LevelModel,
        tilt: Option<&MeasuredTilt>,
    ) -> Result<Self> {
        match band.profile() {
            Profile::PixelEdge { .. } | Profile::PixelLine { .. } => {
                Correlation::new_pushed(band, basis, sampler, levels, tilt)
            }
            Profile::Paper { .. } => Correlation::new(band, basis, levels),
        }
    }

    /// Pushed profile only: the same band and reference on another image of
    /// the same size (the next frame of a sequence, see `fit::track`). The
    /// pixel values at the band pixels are read again; everything that
    /// depends on the band alone is kept (`M0` and its factor, the levels'
    /// constant matrices, the light's tilt measured when it was prepared);
    /// what the previous image left (its noise estimate, its last gray
    /// levels and residual, a switch to the reference's gradient) is reset,
    /// so that the system is as [`Correlation::prepare`] made it, apart from
    /// the tilt.
    ///
    /// Errors: [`Error::BandOutsideImage`] when a band pixel has no value
    /// (an image of another size), [`Error::InvalidParameter`] for a pulled
    /// profile.
    pub fn reload(&mut self, sampler: &Sampler) -> Result<()> {
        let Some(values) = self.pushed.as_mut() else {
            return Err(Error::invalid(
                "reloaded system",
                "only a pushed profile's system reads the image once",
            ));
        };
        let band = &self.band;
        let missing = values
            .par_iter_mut()
            .zip(&band.pos)
            .map(|(v, &[x, y])| match sampler.pixel(x as usize, y as usize) {
                Some(f) => {
                    *v = f;
                    None
                }
                None => Some([x, y]),
            })
            .find_first(Option::is_some)
            .flatten();
        if let Some([x, y]) = missing {
            return Err(Error::BandOutsideImage {
                x,
                y,
                half_width: band.half_width(),
            });
        }
        self.noise_var = None;
        self.levels = None;
        self.ssr = 0.0;
        self.displaced_gradient = true;
        Ok(())
    }

    /// Whether a robust refit reweighted some band pixel.
    pub fn reweighted(&self) -> bool {
        self.robust.iter().any(|&w| w != 1.0)
    }

    /// The light's tilt this system measured or took (`None` without a
    /// pixel profile, or on a curve too short for the levels' elements).
    pub fn measured_tilt(&self) -> Option<&MeasuredTilt> {
        match &self.varying {
            Some(var) => var.measured_tilt.as_ref(),
            None => self.global_tilt.as_ref(),
        }
    }

    /// [`Correlation::new`] for the pushed profile (module docs): the
    /// image's values at the band pixels are read once here.
    ///
    /// Errors: those of `new`, and [`Error::BandOutsideImage`] when a band
    /// pixel has no value.
    fn new_pushed(
        band: Band,
        basis: Basis,
        sampler: &Sampler,
        levels: LevelModel,
        known_tilt: Option<&MeasuredTilt>,
    ) -> Result<Self> {
        // Band pixels are pixel centres: no interpolation.
        let read: Vec<Option<f64>> = band
            .pos
            .par_iter()
            .map(|&[x, y]| sampler.pixel(x as usize, y as usize))
            .collect();
        if let Some(i) = read.iter().position(Option::is_none) {
            let [x, y] = band.pos[i];
            return Err(Error::BandOutsideImage {
                x,
                y,
                half_width: band.half_width(),
            });
        }
        let mut values: Vec<f64> = read.into_iter().flatten().collect();
        let mut corr = Correlation::new(band, basis, levels)?;
        corr.censored = sampler
            .clip_levels()
            .and_then(|clip| Censored::find(&values, clip, || sampler.pixel_noise()));
        let Some(tail) = tilt::tail_end(corr.band.profile()) else {
            corr.pushed = Some(values);
            return Ok(corr);
        };
        // The light's tilt across the band too, on the levels' default
        // elements whatever the levels' own: shorter ones leave fewer
        // plateau pixels to each function, and the tilt's noise moves the
        // edge (docs/benchmarks.md, "Vignetting").
        let Some(lb) = LevelModel::default()
            .basis(corr.basis.length(), corr.basis.is_closed())
            .map(|b| LevelBasis::new(b, &corr.band.s))
        else {
            corr.pushed = Some(values);
            return Ok(corr);
        };
        let measured = match known_tilt {
            Some(m) if m.serves(&lb, tail) => m.clone(),
            _ => tilt::estimate(&corr.band, sampler, &lb, tail),
        };
        let tau = measured
            .coefs
            .as_deref()
            .and_then(|c| tilt::at_pixels(&lb, c));
        if let Some(var) = corr.varying.as_deref_mut() {
            // Varying levels: a factor of the virtual image.
            var.tilt = tau;
            var.measured_tilt = Some(measured);
        } else {
            // The global pair (even light along the curve, as the levels'
            // test found, or asked for): the light can still change across
            // it (a vignetting lens centred on a round part). Taken out of
            // the pixels' values: `f / (1 + tau r)` against `a + c gamma`
            // is `f` against `(a + c gamma) (1 + tau r)` up to `tau U`, a
            // change of the levels' scale the levels absorb.
            if let Some(tau) = tau {
                for ((v, t), r) in values.iter_mut().zip(&tau).zip(&corr.band.r) {
                    *v /= 1.0 + t * r;
                }
            }
            corr.global_tilt = Some(measured);
        }
        corr.pushed = Some(values);
        Ok(corr)
    }

    /// From now on, take the profile's derivative at the reference (`r`)
    /// in the gradient, as the pulled image does, instead of at `r - U`:
    /// for a run that does not contract. With residuals far larger than
    /// the noise (a model that does not fit the image: global levels under
    /// uneven light), the displaced derivative adds a second-order term
    /// that the constant matrix does not hold, and the steps may no longer
    /// shrink; the reference's derivative contracts as the matrix does,
    /// towards an optimum weighted by the reference's profile, which a
    /// settle brings to the displaced one's.
    pub fn use_reference_gradient(&mut self) {
        self.displaced_gradient = false;
        // Another iteration: what the old one showed does not carry over.
        self.contraction = None;
    }

    /// The slowest contraction the system's runs have shown (the largest
    /// ratio of successive steps), if any.
    pub fn contraction(&self) -> Option<f64> {
        self.contraction
    }

    /// Record the ratio of a step to the one before it in the same run
    /// (see [`Self::contraction`]); also to restore a written one.
    pub fn observe_contraction(&mut self, ratio: f64) {
        if ratio.is_finite() {
            self.contraction = Some(self.contraction.map_or(ratio, |q| q.max(ratio)));
        }
    }

    /// Whether the gradient takes the profile's derivative at `r - U`.
    pub fn displaced_gradient(&self) -> bool {
        self.pushed.is_some() && self.displaced_gradient
    }

    /// The band the system is built on.
    pub fn band(&self) -> &Band {
        &self.band
    }

    /// Bend the band's profile to the curvature of the curve at `lambda`
    /// ([`Band::bend_to`]): a kept band's next frame.
    pub fn bend_to(&mut self, lambda: &[f64]) {
        self.band.bend_to(&self.basis, lambda);
    }

    /// The displacement's basis.
    pub fn basis(&self) -> &Basis {
        &self.basis
    }

    /// The robust weight of each band pixel (see `robust_refit` in the fit).
    pub fn robust(&self) -> &[f64] {
        &self.robust
    }

    /// Set the robust weights the band's weights were multiplied by.
    pub fn set_robust(&mut self, robust: Vec<f64>) {
        self.robust = robust;
    }

    /// The last step, `dLambda`, pixels.
    pub fn delta(&self) -> &[f64] {
        &self.delta
    }

    /// Pure-noise variance of the gray levels, once estimated.
    pub fn noise_var(&self) -> Option<f64> {
        self.noise_var
    }

    /// The factor on the noise-only `sigma` that the rounding to the
    /// image's gray-level steps adds (at least 1): the noise estimate
    /// ([`Self::estimate_noise`]) misses it, and `sigma` scales as the root
    /// of the noise variance. 1 before the noise is estimated, or when it
    /// is estimated as none.
    pub fn rounding_gain(&self, sampler: &Sampler) -> f64 {
        self.noise_var
            .filter(|v| *v > 0.0)
            .map_or(1.0, |v| (sampler.rounding_variance() / v).max(1.0).sqrt())
    }

    /// Take the noise variance estimated on another run of the stage.
    pub fn set_noise_var(&mut self, noise_var: Option<f64>) {
        self.noise_var = noise_var;
        if let (Some(c), Some(v)) = (self.censored.as_mut(), noise_var) {
            c.set_noise(v.sqrt());
        }
    }

    /// Number of unknowns of the displacement.
    pub fn n_unknowns(&self) -> usize {
        self.basis.n_functions()
    }

    /// One Gauss–Newton iteration at `lambda`; the step is left in
    /// [`Correlation::delta`].
    pub fn iterate(
        &mut self,
        lambda: &[f64],
        sampler: &Sampler,
        polarity: Polarity,
    ) -> std::result::Result<Step, StepFailure> {
        // A band with a margin counts the pixels around the displaced curve.
        if self.band.margin() > 0.0 {
            self.count = self.band.recentre(&self.basis, lambda);
            self.pixels = self.band.inside() as f64;
        }
        if self.varying.is_some() {
            self.iterate_varying(lambda, sampler, polarity)
        } else {
            self.iterate_global(lambda, sampler, polarity)
        }
    }

    /// Pushed profile only (else `None`): the weighted residual sum of
    /// squares at `lambda` of the virtual image with `profile` in place of
    /// the band's, the gray levels refitted (linear least squares, with the
    /// band's level model), over every `stride`-th band pixel. For choosing
    /// a profile parameter (the blur) at a fixed curve.
    pub fn pushed_ssr(&self, lambda: &[f64], profile: Profile, stride: usize) -> Option<f64> {
        let band = &self.band;
        let half_width = band.half_width();
        let corner = match profile {
            Profile::PixelEdge { blur, anisotropy } => band.corner_terms(blur, anisotropy),
            Profile::PixelLine { .. } | Profile::Paper { .. } => None,
        };
        self.pushed_ssr_by(lambda, stride, |i, r| {
            profile
                .eval_at(
                    r,
                    half_width,
                    band.normal[i],
                    (band.curvature[i], band.osculating_at(i)),
                )
                .0
                + corner.as_ref().map_or(0.0, |c| c[i])
        })
    }

    /// [`Correlation::pushed_ssr`] of the virtual image whose profile at
    /// band pixel `i`, at signed distance `r` from the displaced curve, is
    /// `gamma(i, r)`.
    pub(crate) fn pushed_ssr_by(
        &self,
        lambda: &[f64],
        stride: usize,
        gamma: impl Fn(usize, f64) -> f64 + Sync,
    ) -> Option<f64> {
        let values = self.pushed.as_deref()?;
        let band = &self.band;
        let levels = self.varying.as_ref().map(|v| &v.levels);
        let censored = self.censored.as_ref();
        levels_ssr(levels, values.len(), stride, |i| {
            let w = band.weight[i];
            if w == 0.0 {
                return None;
            }
            let u = self.displacement_at(i, lambda);
            let (g, k) = (gamma(i, band.r[i] - u), self.tilt_factor(i, u));
            // A clipped pixel's light as the last iteration's levels expect.
            let model = || self.levels_of_pixel(i).map(|(a, c)| (a + c * g) * k);
            let f = observed(censored, i, values[i], model)?;
            Some([w, f, g, k])
        })
    }

    /// The light's tilt factor `1 + tau r` at band pixel `i` displaced by
    /// `u` (1 without a tilt: see `tilt`).
    fn tilt_factor(&self, i: usize, u: f64) -> f64 {
        match self.varying.as_ref().and_then(|v| v.tilt.as_ref()) {
            Some(t) => 1.0 + t[i] * (self.band.r[i] - u),
            None => 1.0,
        }
    }

    /// `U` at band pixel `i` for `lambda`.
    fn displacement_at(&self, i: usize, lambda: &[f64]) -> f64 {
        self.band.displacement_at(&self.basis, i, lambda)
    }

    /// The gray levels `(a, c)` of the last iteration at band pixel `i`
    /// (`None` before the first iteration).
    fn levels_of_pixel(&self, i: usize) -> Option<(f64, f64)> {
        match &self.varying {
            Some(var) => self.levels.map(|_| var.levels.levels(i, &var.theta)),
            None => self.levels,
        }
    }

    /// The gray levels `(a, c)` of the last iteration at parameter `u` of
    /// the reference (`None` before the first iteration).
    pub fn levels_at(&self, u: f64) -> Option<(f64, f64)> {
        match &self.varying {
            Some(var) => self.levels.map(|_| var.levels_at(u)),
            None => self.levels,
        }
    }

    /// Whether some band pixels are at a clip level of the image's
    /// encoding (pushed profile only; see `censor`).
    pub fn censored(&self) -> bool {
        self.censored.is_some()
    }

    /// How many band pixels are at a clip level of the image's encoding
    /// (pushed profile only; see `censor`).
    pub fn clipped(&self) -> usize {
        self.censored.as_ref().map_or(0, Censored::count)
    }

    /// Whether the levels vary along the curve.
    pub fn varying_levels(&self) -> bool {
        self.varying.is_some()
    }

    /// After convergence at `lambda` with varying levels of elements
    /// `length` pixels (or with the global pair, to try levels of that
    /// length): the element length the band asks for, `None` for the
    /// global pair. Varying levels fitted to even light only take up
    /// noise, and cost precision through their coupling with the
    /// displacement; levels whose elements are too long for the light
    /// (an object whose edge runs in and out of a vignetted field: a
    /// star's lobes) explain little more than the global pair, and leave
    /// the rest to the displacement, which wiggles.
    ///
    /// The levels are fitted by least squares at `lambda` with elements
    /// of `length` and, when `shorter`, half and a quarter of it (each at
    /// most [`LevelModel::longest_closed_element`] of a closed curve, down to
    /// [`levels::MIN_LEVEL_ELEMENT`], and while the number of elements
    /// grows): each is taken over the best before it (the global pair
    /// first) when the drop of the residual sum of squares exceeds its
    /// distribution under a model that fits, `sigma^2 chi^2` with as many
    /// degrees of freedom as the extra unknowns, by 5 standard deviations;
    /// `sigma^2` is the pure-noise variance ([`Self::estimate_noise`]) or
    /// the residual variance the finer levels leave, whichever is larger
    /// (an F-test where the profile misfits). The band pixels within
    /// `CORNER_CLEARANCE` half-widths of a corner (a break of the
    /// displacement's basis) are left out. When the noise or the sums
    /// cannot be had: `Some(length)` for a system of varying levels, `None`
    /// for the global pair (what it has).
    pub fn levels_needed(
        &mut self,
        lambda: &[f64],
        sampler: &Sampler,
        length: f64,
        shorter: bool,
    ) -> Option<f64> {
        let keep = self.varying.is_some().then_some(length);
        let Some(noise) = self
            .noise_var
            .or_else(|| self.estimate_noise(lambda, sampler))
        else {
            return keep;
        };
        // The sums are weighted (about one per pixel).
        let sigma2 = noise * self.count / self.pixels;
        // Not near a corner: there the profile misfits (a wedge the edge's
        // model only approximates) whatever the light, and shorter levels
        // took that misfit up and the corners' fit apart.
        let clear = CORNER_CLEARANCE * self.band.half_width();
        let (total, closed) = (self.basis.length(), self.basis.is_closed());
        let corners: Vec<f64> = self.basis.breaks().iter().map(|b| b.at).collect();
        let near_corner = |s: f64| {
            corners.iter().any(|&c| {
                let d = (s - c).abs();
                (if closed { d.min(total - d) } else { d }) < clear
            })
        };
        // Each pixel's weight, value, profile and tilt, read once for the
        // four fits; a regular subsample of a wide band (the test needs a
        // few hundred pixels per level function, not every pixel).
        let stride = self.band.len().div_ceil(LEVELS_TEST_PIXELS).max(1);
        let pixels: Vec<Option<[f64; 4]>> = (0..self.band.len().div_ceil(stride))
            .into_par_iter()
            .map(|k| {
                let i = k * stride;
                if near_corner(self.band.s[i]) {
                    return None;
                }
                self.levels_sample(i, lambda, sampler)
            })
            .collect();
        let len = self.band.len();
        // The subsample's weights (about one per pixel).
        let counted: f64 = pixels.iter().flatten().map(|p| p[0]).sum();
        let ssr =
            |levels: Option<&LevelBasis>| levels_ssr(levels, len, stride, |i| pixels[i / stride]);
        let Some(global) = ssr(None) else {
            return keep;
        };
        let (mut best, mut best_ssr, mut best_dim) = (None, global, levels::FEATURES);
        let tries = if shorter { 3 } else { 1 };
        // A closed curve shorter than the fewest elements of `length`
        // tries the longest elements it can have.
        let longest = match closed {
            true => LevelModel::longest_closed_element(total),
            false => f64::INFINITY,
        };
        for len in [length, length / 2.0, length / 4.0].into_iter().take(tries) {
            let len = len.min(longest);
            if len < levels::MIN_LEVEL_ELEMENT {
                break;
            }
            let model = LevelModel::Varying {
                element_length: len,
            };
            let Some(basis) = model.basis(total, closed) else {
                continue;
            };
            let lb = LevelBasis::new(basis, &self.band.s);
            if lb.dim() <= best_dim {
                continue;
            }
            let Some(fitted) = ssr(Some(&lb)) else {
                return keep;
            };
            let extra = (lb.dim() - best_dim) as f64;
            // The larger of the noise and the residual variance left by
            // these levels: a profile that misfits (a coarse stage's, or
            // light tilted across the band before the pixel edge models
            // it) leaves residuals that any finer model would take up,
            // and their pattern along the curve follows the pixel grid,
            // not the light.
            let dof =
                (counted - self.n_unknowns() as f64 / stride as f64 - lb.dim() as f64).max(1.0);
            let variance = sigma2.max(fitted / dof);
            if best_ssr - fitted > variance * (extra + 5.0 * (2.0 * extra).sqrt()) {
                (best, best_ssr, best_dim) = (Some(len), fitted, lb.dim());
            }
        }
        best
    }

    /// Band pixel `i`'s weight, value, profile and the virtual image's
    /// factor there (the light's tilt, else 1) at `lambda`, for a fit of
    /// the levels at this displacement; `None` for a pixel that does not
    /// count (no weight, or displaced out of the image).
    fn levels_sample(&self, i: usize, lambda: &[f64], sampler: &Sampler) -> Option<[f64; 4]> {
        let band = &self.band;
        let w = band.weight[i];
        if w == 0.0 {
            return None;
        }
        let u = self.displacement_at(i, lambda);
        match &self.pushed {
            Some(values) => {
                let gamma = band.profile_at(i, u).0;
                let k = self.tilt_factor(i, u);
                let model = || self.levels_of_pixel(i).map(|(a, c)| (a + c * gamma) * k);
                let f = observed(self.censored.as_ref(), i, values[i], model)?;
                Some([w, f, gamma, k])
            }
            None => {
                let [x, y] = band.pos[i];
                let [nx, ny] = band.normal[i];
                let f = sampler.value(x + u * nx, y + u * ny)?;
                Some([w, f, band.gamma[i], 1.0])
            }
        }
    }

    /// The residual `g - f` of band pixel `i` at `lambda` with the gray
    /// levels of the last iteration (`None` before the first iteration or
    /// when the displaced pixel leaves the image).
    pub fn residual(&self, i: usize, lambda: &[f64], sampler: &Sampler) -> Option<f64> {
        let band = &self.band;
        let (a, c) = self.levels_of_pixel(i)?;
        let u = self.displacement_at(i, lambda);
        let (f, gamma) = match &self.pushed {
            Some(values) => {
                let (gamma, _) = band.profile_at(i, u);
                let g = (a + c * gamma) * self.tilt_factor(i, u);
                return Some(g - observed(self.censored.as_ref(), i, values[i], || Some(g))?);
            }
            None => {
                let [x, y] = band.pos[i];
                let [nx, ny] = band.normal[i];
                (sampler.value(x + u * nx, y + u * ny)?, band.gamma[i])
            }
        };
        Some(a + c * gamma - f)
    }

    /// Estimate the variance of the image noise from the residuals at
    /// `lambda` (after convergence), and keep it for [`Self::position_sigma`].
    ///
    /// The residual `g - f` holds the noise and, where the physical profile
    /// differs from the virtual one, a systematic part that is a smooth
    /// function of `r`: sorted by `r`, neighbouring pixels share the
    /// systematic part, so half the mean squared difference of consecutive
    /// residuals estimates the noise variance alone (Rice's difference
    /// estimator), on at most `NOISE_PIXELS` band pixels taken at a regular
    /// stride. Pixels of about the same `r` have about the same level, and
    /// so the same rounding to the image's gray-level steps: the estimate
    /// misses that noise ([`Sampler::rounding_variance`], which the output's
    /// `sigma` adds). Allocates: call it once per stage, not per iteration.
    pub fn estimate_noise(&mut self, lambda: &[f64], sampler: &Sampler) -> Option<f64> {
        let band = &self.band;
        // A regular subsample bounds the cost (the sort) on wide bands; the
        // variance of the estimate is then about 2 / NOISE_PIXELS relative.
        // Pixels the robust weights rejected (clutter) are left out, and so
        // are those out of a band's window (`Band::recentre`): they do not
        // count in the fit, and with them a tracked frame on a kept band
        // (wide margin) found varying levels significant on a disc under
        // even light where a band of its own did not (tests/it/fit/track.rs).
        let stride = band.len().div_ceil(NOISE_PIXELS).max(1);
        // In parallel; `collect` keeps the pixels' order.
        let mut res: Vec<(f64, f64)> = (0..band.len().div_ceil(stride))
            .into_par_iter()
            .map(|k| k * stride)
            .filter(|&i| self.robust[i] >= 0.5 && band.weight[i] > 0.0)
            // A clipped pixel's residual is its expected light's, no noise.
            .filter(|&i| !self.censored.as_ref().is_some_and(|c| c.is_clipped(i)))
            .filter_map(|i| Some((band.r[i], self.residual(i, lambda, sampler)?)))
            .collect();
        if res.len() < 3 {
            return None;
        }
        res.sort_unstable_by(|l, r| l.0.total_cmp(&r.0));
        let sum: f64 = res.windows(2).map(|w| (w[1].1 - w[0].1).powi(2)).sum();
        let var = sum / (2.0 * (res.len() - 1) as f64);
        self.set_noise_var(Some(var));
        Some(var)
    }

    /// Standard deviation of the normal position `U(s)` at `s`, pixels:
    /// `var U = N^T Cov(Lambda) N` with `Cov(Lambda) = sigma^2 / c^2
    /// (M0 - B S^-1 B^T)^-1` (the gray levels estimated jointly; `c` the
    /// contrast at `s`) and `sigma^2` the noise variance per pixel (method,
    /// section 8): the pure-noise estimate when [`Self::estimate_noise`] has
    /// run, else the residual variance (an upper bound: it includes profile
    /// mismatch). NaN before the first iteration. The first call makes the
    /// band of `M0^-1` (one solve per unknown); each call then costs a few
    /// dozen products.
    pub fn position_sigma(&self, s: f64) -> f64 {
        let Some((_, c)) = self.levels_at(s) else {
            return f64::NAN;
        };
        let sigma2 = self.noise_var.unwrap_or_else(|| {
            // ssr is weighted; scale it back to a per-pixel variance.
            let dof = (self.pixels - self.n_unknowns() as f64 - 2.0).max(1.0);
            self.ssr / dof * (self.pixels / self.count)
        });
        let mut v = [0.0; crate::spline::MAX_DEGREE + 1];
        let first = self.basis.eval(s, &mut v);
        let vals = &v[..=self.basis.degree()];
        let p = self.basis.degree();
        let w = 2 * p + 1;
        let inverse = self
            .inverse_band
            .get_or_init(|| self.chol.inverse_band(p, self.basis.is_closed()));
        let mut q = 0.0;
        for (k, vk) in vals.iter().enumerate() {
            let row = &inverse[self.basis.index(first, k) * w..][..w];
            for (l, vl) in vals.iter().enumerate() {
                q += vk * vl * row[l + p - k];
            }
        }
        match &self.varying {
            Some(var) => q += var.variance_term(&self.basis, first, vals),
            None => {
                let (mut n1, mut n2) = (0.0, 0.0);
                for (k, vk) in vals.iter().enumerate() {
                    let i = self.basis.index(first, k);
                    n1 += vk * self.y1[i];
                    n2 += vk * self.y2[i];
                }
                q += n1 * (self.k_inv[0] * n1 + self.k_inv[1] * n2)
                    + n2 * (self.k_inv[2] * n1 + self.k_inv[3] * n2);
            }
        }
        (sigma2 * q / (c * c)).max(0.0).sqrt()
    }
}

/// Band pixels the levels' test reads at most (`levels_needed`; a
/// regular subsample beyond).
const LEVELS_TEST_PIXELS: usize = 12_000;

/// Band pixels nearer a corner along the curve than this many band
/// half-widths are left out of the levels' test (`levels_needed`).
const CORNER_CLEARANCE: f64 = 2.0;

/// The residual sum of squares of the gray levels fitted by least squares
/// to band pixels `0, stride, 2 stride...` of a band of `len`: on the
/// levels' basis `levels` (features `1` and `gamma`), or the global pair
/// when `None`. `sample(i)` gives pixel `i`'s weight, value, profile and
/// the factor of the virtual image there (the light's tilt, else 1), or
/// `None` to leave it out. `None` when no pixel counts or the levels are
/// not determined. Allocates the dense normal equations of `levels`: a
/// few calls per stage, not per iteration.
fn levels_ssr(
    levels: Option<&LevelBasis>,
    len: usize,
    stride: usize,
    sample: impl Fn(usize) -> Option<[f64; 4]> + Sync,
) -> Option<f64> {
    let stride = stride.max(1);
    let count = len.div_ceil(stride);
    if let Some(lb) = levels {
        let dim = lb.dim();
        let (blocks, mut rhs, sff) = chunked_sum(
            count,
            |range| {
                let mut blocks = vec![0.0; lb.blocks_len()];
                let mut rhs = vec![0.0; dim];
                let mut sff = 0.0;
                for i in range.map(|k| k * stride) {
                    let Some([w, f, gamma, k]) = sample(i) else {
                        continue;
                    };
                    let [f0, f1] = levels::features(gamma);
                    lb.accumulate(i, w, [f0 * k, f1 * k], f, Some(&mut blocks), &mut rhs);
                    sff += w * f * f;
                }
                (blocks, rhs, sff)
            },
            |total, part| {
                total.0.iter_mut().zip(&part.0).for_each(|(t, p)| *t += p);
                total.1.iter_mut().zip(&part.1).for_each(|(t, p)| *t += p);
                total.2 += part.2;
            },
        )?;
        let mut mat = vec![0.0; dim * dim];
        lb.scatter(&blocks, &mut mat);
        let b = rhs.clone();
        DenseCholesky::factor(&mat, dim)
            .ok()?
            .solve_in_place(&mut rhs);
        let fit: f64 = b.iter().zip(&rhs).map(|(u, v)| u * v).sum();
        return Some((sff - fit).max(0.0));
    }
    let sums = chunked_sum(
        count,
        |range| {
            let mut acc = [0.0; 6];
            for i in range.map(|k| k * stride) {
                let Some([w, f, g, k]) = sample(i) else {
                    continue;
                };
                // The features `k` and `k g` (`k` is 1 without a tilt).
                let (wk, gk) = (w * k, g * k);
                for (a, v) in acc.iter_mut().zip([
                    wk * k,
                    wk * gk,
                    w * gk * gk,
                    wk * f,
                    w * f * gk,
                    w * f * f,
                ]) {
                    *a += v;
                }
            }
            acc
        },
        |total, part| total.iter_mut().zip(part).for_each(|(t, p)| *t += p),
    )?;
    let [n, sg, sgg, sf, sfg, sff] = sums;
    let det = n * sgg - sg * sg;
    if det.is_nan() || det <= 0.0 {
        return None;
    }
    let a = (sgg * sf - sg * sfg) / det;
    let c = (n * sfg - sg * sf) / det;
    Some((sff - a * sf - c * sfg).max(0.0))
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::curve::InitialCurve;
    use crate::interp::Interpolation;
    use crate::render::{render, Method, RenderSpec};
    use crate::spline::MAX_DEGREE;
    use crate::truth::Shape;
    use crate::virtual_image::Kind;

    /// The largest and the mean signed distance (pixels) between the
    /// curves measured from references `0.4` px inside and outside a disc
    /// and from the disc's own circle, iterating the pushed profile to its
    /// fixed point on each (plain Gauss–Newton steps). `reference_gradient`:
    /// with the profile's derivative at `r` instead of `r - U`; `margin`:
    /// the band's (pixels, `Band::build_windowed`).
    fn spread_over_references(
        levels: LevelModel,
        reference_gradient: bool,
        margin: f64,
    ) -> (f64, f64) {
        let (cx, cy, r0, blur) = (100.3, 99.6, 60.0, 0.5);
        let image = render(&RenderSpec {
            width: 200,
            height: 200,
            shape: Shape::Circle { cx, cy, r: r0 },
            kind: Kind::Silhouette,
            method: Method::Coverage,
            foreground: 0.8,
            background: 0.2,
            blur_sigma: blur,
            noise: 0.01,
            seed: 5,
            bits: Some(8),
            ..RenderSpec::default()
        })
        .unwrap();
        let sampler = Sampler::new(&image, Interpolation::Bilinear);
        let profile = Profile::pixel_edge(blur);
        // The measured radius every 2 degrees, from a reference circle.
        let measure = |r: f64| -> Vec<f64> {
            let curve = InitialCurve::Circle { cx, cy, r }.to_curve().unwrap();
            let basis = Basis::new(3, 16, curve.param_length(), true).unwrap();
            let band = Band::build_windowed(
                &curve,
                &basis,
                2.0,
                margin,
                profile,
                200,
                200,
                crate::band::Coords::Exact,
            )
            .unwrap();
            let mut corr = Correlation::prepare(band, basis, &sampler, levels, None).unwrap();
            if reference_gradient {
                corr.use_reference_gradient();
            }
            let mut lambda = vec![0.0; corr.n_unknowns()];
            for _ in 0..60 {
                let step = corr.iterate(&lambda, &sampler, Polarity::Auto).unwrap();
                lambda
                    .iter_mut()
                    .zip(&corr.delta)
                    .for_each(|(l, d)| *l += d);
                if step.max_step < 1e-9 {
                    break;
                }
            }
            let l = curve.param_length();
            (0..180)
                .map(|k| {
                    let s = l * k as f64 / 180.0;
                    let mut v = [0.0; MAX_DEGREE + 1];
                    let first = corr.basis.eval(s, &mut v);
                    let u: f64 = (0..=3)
                        .map(|j| lambda[corr.basis.index(first, j)] * v[j])
                        .sum();
                    let f = curve.frame(s);
                    let p = [f.point[0] + u * f.normal[0], f.point[1] + u * f.normal[1]];
                    (p[0] - cx).hypot(p[1] - cy)
                })
                .collect()
        };
        let own = measure(r0);
        let (mut worst, mut mean) = (0.0f64, 0.0f64);
        for r in [r0 - 0.4, r0 + 0.4] {
            let other = measure(r);
            let d: Vec<f64> = other.iter().zip(&own).map(|(a, b)| a - b).collect();
            worst = d.iter().fold(worst, |m, v| m.max(v.abs()));
            mean = mean.max((d.iter().sum::<f64>() / d.len() as f64).abs());
        }
        (worst, mean)
    }

    /// The pushed profile's gradient takes the profile's derivative at
    /// `r - U`, so that where the iteration stops depends little on the
    /// reference (module docs): on a disc of blur 0.5 px (8 bits, 1 %
    /// noise), references 0.4 px off give curves within 4.9e-4 px of the
    /// one from the disc's own circle with global levels and 4.3e-3 px with
    /// varying ones (measured), against 3.9e-3 and 5.3e-3 px with the
    /// reference's derivative. A band with a margin of 0.5 px, whose pixels
    /// count around the displaced curve (`Band::build_windowed`), leaves
    /// 1.9e-5 px with either level model (measured).
    #[test]
    fn the_fixed_point_hardly_depends_on_the_reference() {
        let varying = LevelModel::Varying {
            element_length: 40.0,
        };
        for levels in [LevelModel::Global, varying] {
            let (worst, mean) = spread_over_references(levels, false, 0.0);
            let (worst_ref, mean_ref) = spread_over_references(levels, true, 0.0);
            let (worst_win, mean_win) = spread_over_references(levels, false, 0.5);
            eprintln!(
                "{levels:?}: displaced derivative {worst:.2e} (mean {mean:.2e}), \
                 reference derivative {worst_ref:.2e} (mean {mean_ref:.2e}), \
                 windowed {worst_win:.2e} (mean {mean_win:.2e})"
            );
            assert!(worst < 5e-3, "{levels:?}: {worst}");
            assert!(worst <= worst_ref, "{levels:?}: {worst} vs {worst_ref}");
            if levels == LevelModel::Global {
                assert!(worst < 0.25 * worst_ref, "{worst} vs {worst_ref}");
            }
            assert!(worst_win < 1e-3, "{levels:?}: windowed {worst_win}");
        }
    }
}
