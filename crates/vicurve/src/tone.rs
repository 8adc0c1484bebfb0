//! The image's tone curve: how its gray levels relate to the light.
//!
//! The virtual image is linear in the light: its profile across an edge is
//! the step seen through a symmetric blur, centred on the edge. A camera or
//! renderer that encodes its values by a power law, `v = L^(1 / gamma)`
//! (sRGB and most JPEG files, gamma about 2.2), bends that profile: the
//! dark half is stretched and the bright half compressed, so that the
//! profile's centre of symmetry is no longer the edge. Measured as if it
//! were linear, such an edge comes out moved towards its dark side by
//! about a quarter of the blur's width (docs/benchmarks.md, "Gamma-encoded
//! images"), with a `sigma` that knows nothing of it.
//!
//! [`estimate`] reads the exponent from the profile's asymmetry around a
//! measured curve; [`Tone::to_linear`] takes gray levels back to linear
//! light, where the method measures without that bias
//! ([`crate::fit::FitConfig::tone`]).

use crate::error::{Error, Result};
use crate::psf::{noise_variance, Binned};
use crate::solver::lm::{self, LmParams, Problem, Trial};
use crate::solver::DenseCholesky;
use serde::{Deserialize, Serialize};
use std::fmt;
use std::str::FromStr;

/// How an image's gray levels relate to the light, on the scale of its
/// bit depth (`[0, 1]`, see [`crate::image`]).
///
/// Words (the same for every front end): `auto`, `linear`, `srgb`, and a
/// number or `gamma:NUMBER` for a power law.
#[derive(Clone, Copy, Debug, Default, PartialEq, Serialize, Deserialize)]
#[serde(rename_all = "snake_case")]
pub enum Tone {
    /// Estimate the tone curve from the measured edge ([`estimate`]) and,
    /// when the image is clearly not linear, measure again on the image
    /// taken back to linear light. Silhouettes only: a thin line's centre
    /// does not move with the tone curve. The default.
    #[default]
    Auto,
    /// The gray levels are proportional to the light (raw camera data,
    /// linear renderers, scientific cameras).
    Linear,
    /// The light is `v^gamma` (`v` the gray level in `[0, 1]`); 2.2 for
    /// the usual displays' encoding. Between 0.2 and 5.
    Gamma(f64),
    /// The sRGB transfer function (IEC 61966-2-1): a linear toe below
    /// `v = 0.04045`, then `((v + 0.055) / 1.055)^2.4`.
    Srgb,
}

/// Smallest and largest exponent accepted for [`Tone::Gamma`].
const GAMMA_RANGE: (f64, f64) = (0.2, 5.0);

impl Tone {
    /// Check a [`Tone::Gamma`]'s exponent.
    ///
    /// Errors: [`Error::InvalidParameter`] for an exponent outside 0.2 to 5
    /// or not finite.
    pub fn validate(self) -> Result<()> {
        match self {
            Tone::Gamma(g) if !(g.is_finite() && (GAMMA_RANGE.0..=GAMMA_RANGE.1).contains(&g)) => {
                Err(Error::invalid(
                    "tone",
                    format!("gamma {g} (must be between 0.2 and 5)"),
                ))
            }
            _ => Ok(()),
        }
    }

    /// The light of a gray level `v` (on `[0, 1]`; values outside are
    /// clamped): `v` itself for [`Tone::Linear`] and [`Tone::Auto`].
    pub fn to_linear(self, v: f64) -> f64 {
        match self {
            Tone::Auto | Tone::Linear => v,
            Tone::Gamma(g) => v.clamp(0.0, 1.0).powf(g),
            Tone::Srgb => {
                let v = v.clamp(0.0, 1.0);
                if v <= 0.04045 {
                    v / 12.92
                } else {
                    ((v + 0.055) / 1.055).powf(2.4)
                }
            }
        }
    }

    /// The gray level of a light `l` (on `[0, 1]`, clamped to positive
    /// values) and its derivative: the inverse of [`Tone::to_linear`].
    fn encode(self, l: f64) -> (f64, f64) {
        match self {
            Tone::Auto | Tone::Linear => (l, 1.0),
            Tone::Gamma(g) => {
                let l = l.max(LIGHT_FLOOR);
                let v = l.powf(1.0 / g);
                (v, v / (g * l))
            }
            Tone::Srgb => {
                if l <= 0.0031308 {
                    (12.92 * l, 12.92)
                } else {
                    let p = l.powf(1.0 / 2.4);
                    (1.055 * p - 0.055, 1.055 * p / (2.4 * l))
                }
            }
        }
    }

    /// The gray level that records a light `l` (on `[0, 1]`; clamped):
    /// the inverse of [`Tone::to_linear`].
    pub fn from_linear(self, l: f64) -> f64 {
        let l = l.clamp(0.0, 1.0);
        match self {
            Tone::Auto | Tone::Linear => l,
            Tone::Gamma(g) => l.powf(1.0 / g),
            Tone::Srgb => self.encode(l).0,
        }
    }

    /// [`Tone::Linear`]: the serde default of the records written before
    /// the tone curve was one of their fields.
    pub(crate) fn linear() -> Tone {
        Tone::Linear
    }

    /// Whether gray levels are taken as they are ([`Tone::Linear`], or
    /// [`Tone::Auto`] before an estimate).
    pub fn is_identity(self) -> bool {
        matches!(self, Tone::Auto | Tone::Linear)
    }
}

impl fmt::Display for Tone {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        match self {
            Tone::Auto => write!(f, "auto"),
            Tone::Linear => write!(f, "linear"),
            Tone::Gamma(g) => write!(f, "gamma:{g}"),
            Tone::Srgb => write!(f, "srgb"),
        }
    }
}

impl FromStr for Tone {
    type Err = Error;

    /// `auto`, `linear`, `srgb`, `gamma:G` or `G` (a number, 0.2 to 5).
    fn from_str(s: &str) -> Result<Tone> {
        let word = s.trim().to_ascii_lowercase();
        let tone = match word.as_str() {
            "auto" => Tone::Auto,
            "linear" => Tone::Linear,
            "srgb" => Tone::Srgb,
            _ => {
                let number = word.strip_prefix("gamma:").unwrap_or(&word);
                let g: f64 = number.parse().map_err(|_| {
                    Error::invalid(
                        "tone",
                        format!("'{s}' (expected auto, linear, srgb, or a gamma such as 2.2)"),
                    )
                })?;
                Tone::Gamma(g)
            }
        };
        tone.validate()?;
        Ok(tone)
    }
}

/// The tone curve read from an edge's profile by [`estimate`].
#[derive(Clone, Copy, Debug, PartialEq, Serialize, Deserialize)]
pub struct ToneEstimate {
    /// The tone curve the reading chose: [`Tone::Linear`] when the power
    /// law does not fit clearly better than a linear tone (evidence 25,
    /// or a fifth of the degrees of freedom where the profile misfits
    /// beyond the noise) or its exponent is not an encoding's (1.5 or
    /// less); else the standard encoding ([`STANDARD_TONES`]) that fits
    /// the profile best, when it fits it as well as the fitted power law
    /// (within 4 noise variances), else that power law, [`Tone::Gamma`]
    /// of [`ToneEstimate::gamma`].
    pub curve: Tone,
    /// The exponent of the power law that makes the edge's profile
    /// symmetric: the light is `v^gamma` (1: linear).
    pub gamma: f64,
    /// Where that power law's symmetric profile is centred from the
    /// curve measured as linear, along the curve's normal, pixels: about
    /// how far the power law had moved that curve, with the sign that
    /// takes it back.
    pub shift: f64,
    /// How much better the profile fits with `gamma` than with a linear
    /// tone: the drop of its residual sum of squares, in noise variances
    /// (a chi-square of one degree of freedom for a linear image).
    pub evidence: f64,
    /// The standard deviation of the edge's position that the reading
    /// leaves once its curve is undone, pixels, common to the whole curve:
    /// the spread of where the standard encodings and the power law would
    /// put the edge, each weighted by its likelihood; the power law's own
    /// uncertainty (`|shift| / sqrt(evidence)`: the shift is nearly
    /// proportional to `ln gamma`); and, when the power law is the curve
    /// chosen, a quarter of the shift (the reading mixes profiles of
    /// several shapes, and was seen 15 % off `ln gamma`). When the curve
    /// chosen is linear: the shift itself if the power law has an
    /// encoding's exponent (over 1.5) and is preferred by some evidence
    /// (over 9), not enough to be chosen; else 0.
    pub position_sd: f64,
    /// Band pixels read.
    pub pixels: usize,
}

/// The encodings real images use, tried before a fitted power law: sRGB
/// (most cameras' JPEG files, screens, renderers' default view) and the
/// plain power laws 2.2 (displays, many renderers' output) and 2.4
/// (ITU-R BT.1886 video).
pub const STANDARD_TONES: [Tone; 3] = [Tone::Srgb, Tone::Gamma(2.2), Tone::Gamma(2.4)];
/// A standard encoding is chosen when its residual sum of squares is
/// within this many noise variances of the fitted power law's (two
/// standard deviations of a chi-square of one degree of freedom).
const CONSISTENT: f64 = 4.0;
/// Share of its shift a fitted power law (no standard encoding fits)
/// may leave: the reading mixes the profiles of a band (the pixels'
/// orientations, curvature, uneven levels) whose encoded mean is not the
/// encoding of their mean: a noiseless 8-bit disc of true gamma 2.2 was
/// read as 1.95 (15 % of `ln gamma`), which left its edge 0.058 px off.
pub(crate) const FITTED_SYSTEMATIC: f64 = 0.25;

/// The estimate chooses a tone curve other than linear when the power law
/// explains this many noise variances more than a linear tone (a
/// chi-square of one degree of freedom beyond 5 standard deviations for a
/// linear image)...
const EVIDENCE: f64 = 25.0;
/// Below [`EVIDENCE`], a power law of an exponent over [`LEAST_GAMMA`] that
/// explains this many noise variances more than a linear tone (three
/// standard deviations of a chi-square of one degree of freedom: noise
/// alone rarely gets there) is not chosen, but its shift is the
/// uncertainty the reading leaves ([`ToneEstimate::position_sd`]):
/// gamma-encoded objects of low contrast or under 2 % noise read as 1.7
/// to 2.5 at evidence 10 to 22, and came out 0.15 to 0.3 px off with no
/// uncertainty said. Linear images may get there too (a pentagon under 5
/// % noise read as 1.6 at evidence 22): their shift is then said, not
/// undone.
const UNDECIDED: f64 = 9.0;
/// ... and its exponent exceeds this: the encodings in use raise the light
/// to 1.8 to 2.6 (a true 2.2 was read as 1.95 to 2.24, sRGB as 2.24 to
/// 2.43), while the other asymmetries of linear images read as 0.63 to
/// 1.28 (motion blur, astigmatism, uneven light; docs/benchmarks.md,
/// "Gamma-encoded images").
pub(crate) const LEAST_GAMMA: f64 = 1.5;
/// The profile misfits when the power law's residual variance exceeds the
/// neighbouring pixels' noise this many times...
const MISFIT: f64 = 2.0;
/// ... and the power law then chooses a curve only when it removes this
/// share of the residual sum of squares it leaves (`evidence > MISFIT_SHARE
/// x degrees of freedom`).
const MISFIT_SHARE: f64 = 0.2;
/// Width of the distance bins of the profile fit, pixels: the profile's
/// mean over a bin differs from its value at the bin's mean distance by
/// `g'' w^2 / 24`, 1e-4 of the contrast for the sharpest edge.
const BIN_WIDTH: f64 = 0.05;

/// Pairs of bumps of the line spread function (`k = 0..BUMPS`).
const BUMPS: usize = 13;
/// Unknowns of the profile fit: the mid level, the bumps' weights, the
/// two plateaus' slopes, the centre `r0` and `ln gamma`.
const UNKNOWNS: usize = BUMPS + 5;
/// Index of the plateaus' slopes (odd and even parts), of `r0` and of `ln
/// gamma` among the unknowns.
const SLOPES: usize = BUMPS + 1;
const R0: usize = BUMPS + 3;
const LOG_GAMMA: usize = BUMPS + 4;
/// The light is kept above this in the fit (a power of a negative level
/// is not defined; real dark levels are far above).
const LIGHT_FLOOR: f64 = 1e-4;

/// The band's half-width [`estimate`] reads for an edge of spread `s`
/// (pixels): four spreads and 2 px of the flat levels. Not wider: another
/// edge within the band (the far side of a 10 px line between a grid's
/// cells) makes the profile asymmetric, and a band of 7 spreads read
/// such cells as gamma 1.7 to 2.0. The profile's bumps are spaced to
/// reach a pixel short of it (`h = (half-width - 1) / 14`).
pub fn band_half_width(spread: f64) -> f64 {
    4.0 * spread.max(0.5) + 2.0
}

/// The tone curve of the image around a measured edge, from the band's
/// pixels `data` (`(r, v)`: signed distance to the curve, pixels, and
/// gray level on `[0, 1]`; sorted by `r`, as `psf::band_data` gives them)
/// and the edge's spread `spread` (pixels, [`crate::psf::edge_spread`]).
///
/// The profile is fitted as `v = (a + sum_k w_k E_k(x) + b x + d |x|)^(1 /
/// gamma)` with `x = r - r0`, where the `E_k` are the edge responses of
/// symmetric pairs of cubic bumps spaced across the band
/// ([`band_half_width`]) and `b`, `d` the two flat levels' slopes (uneven
/// light): any symmetric blur (a Gaussian, a defocus pillbox, a halo) is
/// such a sum, so only the profile's asymmetry is left to `gamma`. The
/// fit with `gamma = 1` is the reference of [`ToneEstimate::evidence`].
///
/// `None` when the data cannot say: gray levels outside `[0, 1]`, fewer
/// than 200 pixels, no contrast, or a fit that does not converge.
pub fn estimate(data: &[(f64, f64)], spread: f64) -> Option<ToneEstimate> {
    if data.len() < 200
        || data
            .iter()
            .any(|&(_, v)| !(-1e-9..=1.0 + 1e-9).contains(&v))
    {
        return None;
    }
    let binned = Binned::with_width(data, BIN_WIDTH);
    let fit = ProfileFit {
        bins: &binned.bins,
        h: (band_half_width(spread) - 1.0) / 14.0,
        free: [false, false],
        fixed: None,
    };
    let mean = data.iter().map(|d| d.1).sum::<f64>() / data.len() as f64;
    let mut start = [0.0; UNKNOWNS];
    start[0] = mean.max(LIGHT_FLOOR);
    let with = |free, fixed| ProfileFit { free, fixed, ..fit };
    // The linear fit is the reference of the evidence: it must settle.
    let linear = with([true, false], None).minimise(start, true)?;
    let power = with([true, true], None).minimise(linear.0, false)?;
    // The noise: that of neighbouring pixels, or the power law's own
    // residual variance where the profile misfits more (a blur the sum of
    // bumps cannot follow, the rounding of a noiseless image's levels,
    // another edge within the band): evidence is then counted against the
    // misfit, not against a quantisation step.
    let dof = (data.len() - UNKNOWNS) as f64;
    let pixel_noise = noise_variance(data);
    let misfit = power.1 / dof;
    let noise = pixel_noise.max(misfit).max(1e-30);
    let point = power.0;
    let gamma = point[LOG_GAMMA].exp();
    let evidence = (linear.1 - power.1).max(0.0) / noise;
    // Where the profile misfits beyond the noise, its residuals are not
    // independent and a chi-square says little: the power law must then
    // explain a fifth of what it leaves. Noiseless 8-bit discs whose dark
    // level falls between two integers (25.5 of 255; their rounded tails
    // flatten one side sooner than the other) read as gamma 1.0 to 1.09
    // at evidence 0.005 x dof at most; a noiseless gamma-encoded disc as
    // 1.95 at 0.49 x dof.
    let needed = if misfit > MISFIT * pixel_noise {
        EVIDENCE.max(MISFIT_SHARE * dof)
    } else {
        EVIDENCE
    };
    if !(evidence > needed && gamma > LEAST_GAMMA) {
        // Linear enough: the standard encodings are not tried. A power law
        // of an encoding's exponent that the profile prefers, though not
        // by enough to be chosen (a faint or noisy edge), leaves the edge
        // where that law would put it as likely as not.
        let undecided = gamma > LEAST_GAMMA && evidence > UNDECIDED;
        return Some(ToneEstimate {
            curve: Tone::Linear,
            gamma,
            shift: point[R0],
            evidence,
            position_sd: if undecided { point[R0].abs() } else { 0.0 },
            pixels: data.len(),
        });
    }
    let (curve, position_sd) = choose(with, start, power, noise, evidence);
    Some(ToneEstimate {
        curve,
        gamma,
        shift: point[R0],
        evidence,
        position_sd,
        pixels: data.len(),
    })
}

/// The curve a reading chooses ([`ToneEstimate::curve`]) and the
/// uncertainty it leaves ([`ToneEstimate::position_sd`]), from the fitted
/// power law `power` (its unknowns and residual sum of squares) and the
/// fits `with` makes of each standard encoding from `start`.
fn choose<'a>(
    with: impl Fn([bool; 2], Option<Tone>) -> ProfileFit<'a>,
    start: [f64; UNKNOWNS],
    (point, rss): ([f64; UNKNOWNS], f64),
    noise: f64,
    evidence: f64,
) -> (Tone, f64) {
    let fitted = Tone::Gamma(point[LOG_GAMMA].exp());
    // Each standard encoding, from its own start (its light is not the
    // power law's).
    let candidates: Vec<(Tone, f64, f64)> = STANDARD_TONES
        .iter()
        .filter_map(|&tone| {
            let fit = with([true, false], Some(tone)).minimise(start, false)?;
            Some((tone, fit.1, fit.0[R0]))
        })
        .chain(std::iter::once((fitted, rss, point[R0])))
        .collect();
    // The standard encoding that fits best if it fits as well as the power
    // law, else the power law (always a candidate).
    let (curve, _, centre) = candidates
        .iter()
        .copied()
        .filter(|c| c.0 == fitted || c.1 <= rss + CONSISTENT * noise)
        .min_by(|a, b| {
            (a.0 == fitted)
                .cmp(&(b.0 == fitted))
                .then(a.1.total_cmp(&b.1))
        })
        .unwrap_or((fitted, rss, point[R0]));
    // Where the curves the data allow would put the edge, each weighted by
    // its likelihood against the power law's.
    let (mut square, mut weights) = (0.0, 0.0);
    for c in &candidates {
        let w = (-(c.1 - rss).max(0.0) / (2.0 * noise)).exp();
        square += w * (c.2 - centre).powi(2);
        weights += w;
    }
    let own = point[R0].abs() / evidence.max(1.0).sqrt();
    let systematic = if curve == fitted {
        FITTED_SYSTEMATIC * point[R0]
    } else {
        0.0
    };
    (
        curve,
        (square / weights + own * own + systematic * systematic).sqrt(),
    )
}

/// `integral_{-inf}^{x} beta_3`, the edge response of the cubic B-spline
/// bump.
fn bump_edge(x: f64) -> f64 {
    let t = x.abs();
    let half = if t < 1.0 {
        t * (2.0 / 3.0 - t * t / 3.0 + t * t * t / 8.0)
    } else if t < 2.0 {
        0.5 - (2.0 - t).powi(4) / 24.0
    } else {
        0.5
    };
    0.5 + half.copysign(x)
}

/// The cubic B-spline bump `beta_3`.
fn bump(x: f64) -> f64 {
    let t = x.abs();
    if t < 1.0 {
        2.0 / 3.0 - t * t + t * t * t / 2.0
    } else if t < 2.0 {
        (2.0 - t).powi(3) / 6.0
    } else {
        0.0
    }
}

/// The profile fit of [`estimate`] as a Levenberg–Marquardt problem on the
/// binned band; `free` says whether `r0` and `ln gamma` are unknowns (else
/// they keep their starting values).
#[derive(Clone, Copy)]
struct ProfileFit<'a> {
    bins: &'a [[f64; 4]],
    h: f64,
    free: [bool; 2],
    /// A fixed encoding instead of the power law of `ln gamma` (which is
    /// then not an unknown).
    fixed: Option<Tone>,
}

/// A point of the fit: its residual sum of squares (the bins' means
/// against the model, weighted by their pixels), the gradient `J^T e` and
/// the Gauss–Newton matrix `J^T J`.
struct Eval {
    cost: f64,
    gradient: [f64; UNKNOWNS],
    matrix: [[f64; UNKNOWNS]; UNKNOWNS],
}

impl ProfileFit<'_> {
    /// The minimum from `start` and its residual sum of squares (that of
    /// the pixels, the spread within each bin included); `None` when the
    /// fit does not converge, or, when `settled` is false, also a fit at
    /// its iteration limit, where it stands (its cost only fell: a power
    /// law's evidence from it is at most the converged one's; the bumps of
    /// a small object's band, about 700 pixels, can take more than 100
    /// steps to settle to 1e-7).
    fn minimise(&self, start: [f64; UNKNOWNS], settled: bool) -> Option<([f64; UNKNOWNS], f64)> {
        let eval = self.eval(&start)?;
        let params = LmParams {
            max_iterations: 100,
            ..LmParams::default()
        };
        let min = lm::minimise(self, start, eval, &params);
        match min.end {
            lm::End::Converged | lm::End::Stalled => {}
            lm::End::IterationLimit if !settled => {}
            lm::End::IterationLimit | lm::End::Stopped(()) => return None,
        }
        let within: f64 = self
            .bins
            .iter()
            .map(|b| (b[3] - b[2] * b[2] / b[0]).max(0.0))
            .sum();
        Some((min.point, min.eval.cost + within))
    }

    /// The evaluation at `x`; `None` when it is not finite.
    fn eval(&self, x: &[f64; UNKNOWNS]) -> Option<Eval> {
        let mut e = Eval {
            cost: 0.0,
            gradient: [0.0; UNKNOWNS],
            matrix: [[0.0; UNKNOWNS]; UNKNOWNS],
        };
        let gamma = x[LOG_GAMMA].exp();
        let mut j = [0.0; UNKNOWNS];
        for &[n, r, sum, _] in self.bins {
            let t = (r - x[R0]) / self.h;
            let mut light = x[0];
            let mut slope = 0.0;
            for k in 0..BUMPS {
                let kf = k as f64;
                let edge = bump_edge(t - kf) + bump_edge(t + kf) - 1.0;
                light += x[1 + k] * edge;
                slope += x[1 + k] * (bump(t - kf) + bump(t + kf)) / self.h;
                j[1 + k] = edge;
            }
            // The plateaus' slopes: `b x` and `d |x|` (smoothed over the
            // first bump), in the light.
            let x_r = t * self.h;
            let sign = 2.0 * bump_edge(t) - 1.0;
            light += x[SLOPES] * x_r + x[SLOPES + 1] * x_r * sign;
            slope += x[SLOPES] + x[SLOPES + 1] * (sign + x_r * 2.0 * bump(t) / self.h);
            j[SLOPES] = x_r;
            j[SLOPES + 1] = x_r * sign;
            let clamped = light.max(LIGHT_FLOOR);
            let (v, dv) = match self.fixed {
                Some(tone) => tone.encode(clamped),
                None => Tone::Gamma(gamma).encode(clamped),
            };
            let dv = if light > LIGHT_FLOOR { dv } else { 0.0 };
            j[0] = dv;
            for jk in &mut j[1..R0] {
                *jk *= dv;
            }
            j[R0] = if self.free[0] { -dv * slope } else { 0.0 };
            j[LOG_GAMMA] = if self.free[1] && self.fixed.is_none() {
                -v * clamped.ln() / gamma
            } else {
                0.0
            };
            let res = v - sum / n;
            e.cost += n * res * res;
            for a in 0..UNKNOWNS {
                e.gradient[a] += n * j[a] * res;
                for b in 0..=a {
                    e.matrix[a][b] += n * j[a] * j[b];
                }
            }
        }
        for a in 0..UNKNOWNS {
            for b in 0..a {
                e.matrix[b][a] = e.matrix[a][b];
            }
        }
        e.cost.is_finite().then_some(e)
    }
}

impl Problem for ProfileFit<'_> {
    type Point = [f64; UNKNOWNS];
    type Eval = Eval;
    type Stop = ();

    fn cost(&self, eval: &Eval) -> f64 {
        eval.cost
    }

    fn trial(&self, x: &[f64; UNKNOWNS], cur: &Eval, mu: f64) -> Trial<[f64; UNKNOWNS], Eval, ()> {
        let n = UNKNOWNS;
        let max_diag = (0..n).map(|i| cur.matrix[i][i]).fold(0.0, f64::max);
        let mut damped = vec![0.0; n * n];
        for a in 0..n {
            for b in 0..n {
                damped[a * n + b] = cur.matrix[a][b];
            }
            let d = cur.matrix[a][a];
            damped[a * n + a] = if d > 0.0 {
                d + mu * d.max(1e-9 * max_diag)
            } else {
                1.0
            };
        }
        let Ok(chol) = DenseCholesky::factor(&damped, n) else {
            return Trial::Retry;
        };
        let mut step: Vec<f64> = cur.gradient.iter().map(|g| -g).collect();
        chol.solve_in_place(&mut step);
        if step.iter().any(|s| !s.is_finite()) {
            return Trial::Retry;
        }
        let mut next = *x;
        for (v, s) in next.iter_mut().zip(&step) {
            *v += s;
        }
        // A step of more than a pixel in r0 or a factor 1.5 in gamma is
        // damped again: the profile is linear enough only closer.
        if step[R0].abs() > 1.0 || step[LOG_GAMMA].abs() > 0.4 {
            return Trial::Retry;
        }
        let Some(eval) = self.eval(&next) else {
            return Trial::Retry;
        };
        // Steps far below what moves the residuals by a noise variance.
        let small = step[R0].abs() < 1e-5
            && step[LOG_GAMMA].abs() < 1e-5
            && step[..R0].iter().all(|s| s.abs() < 1e-7);
        Trial::Step {
            point: next,
            eval,
            small,
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn the_bump_edge_integrates_the_bump() {
        for i in -30..=30 {
            let x = i as f64 * 0.1;
            let n = 2000;
            let lo = -2.0;
            let h = (x - lo) / n as f64;
            let integral: f64 = (0..n).map(|k| bump(lo + (k as f64 + 0.5) * h) * h).sum();
            assert!(
                (bump_edge(x) - integral).abs() < 1e-6,
                "{x}: {} {integral}",
                bump_edge(x)
            );
        }
    }

    /// `(r, v)` of an edge profile `p` (light, 0.2 to 0.8) encoded by
    /// `tone`, 20,000 pixels over +-8 px with noise of 1e-3 (a fixed
    /// pseudo-random sequence), sorted by `r`.
    fn profile(tone: Tone, p: impl Fn(f64) -> f64) -> Vec<(f64, f64)> {
        let mut state = 12345u64;
        (0..20_000)
            .map(|i| {
                state = state
                    .wrapping_mul(6364136223846793005)
                    .wrapping_add(1442695040888963407);
                let u = (state >> 11) as f64 / (1u64 << 53) as f64 - 0.5;
                let r = -8.0 + 16.0 * i as f64 / 20_000.0;
                (r, tone.from_linear(p(r)) + 3.5e-3 * u)
            })
            .collect()
    }

    fn gaussian_edge(r: f64) -> f64 {
        0.2 + 0.6 * 0.5 * libm::erfc(r / (1.2 * std::f64::consts::SQRT_2))
    }

    #[test]
    fn a_power_law_is_read_from_the_profile() {
        let e = estimate(&profile(Tone::Gamma(2.2), gaussian_edge), 1.2).unwrap();
        assert!((e.gamma / 2.2 - 1.0).abs() < 0.05, "{e:?}");
        assert!(e.evidence > 1000.0 && !e.curve.is_identity(), "{e:?}");
        // The power law's centre is where the edge is.
        assert!(e.shift.abs() < 0.02, "{e:?}");
    }

    #[test]
    fn symmetric_blurs_are_not_taken_for_a_tone_curve() {
        // A defocus pillbox of radius 4 px: the edge response of a disc.
        let pillbox = |r: f64| {
            let t = (r / 4.0).clamp(-1.0, 1.0);
            let cut = (t * (1.0 - t * t).sqrt() + t.asin()) / std::f64::consts::PI;
            0.2 + 0.6 * (0.5 - cut)
        };
        for (p, spread) in [
            (&pillbox as &dyn Fn(f64) -> f64, 2.3),
            (&gaussian_edge, 1.2),
        ] {
            let e = estimate(&profile(Tone::Linear, p), spread).unwrap();
            assert_eq!(e.curve, Tone::Linear, "{e:?}");
            assert!((e.gamma - 1.0).abs() < 0.05, "{e:?}");
        }
    }

    #[test]
    fn words_parse_and_print_back() {
        for w in ["auto", "linear", "srgb", "gamma:2.2"] {
            let t: Tone = w.parse().unwrap();
            assert_eq!(t.to_string(), w);
        }
        assert_eq!("2.2".parse::<Tone>().ok(), Some(Tone::Gamma(2.2)));
        for bad in ["", "gamma", "gamma:0", "7", "nan", "srgbx"] {
            assert!(bad.parse::<Tone>().is_err(), "{bad}");
        }
    }

    #[test]
    fn srgb_is_continuous_at_its_toe() {
        let a = Tone::Srgb.to_linear(0.04045 - 1e-12);
        let b = Tone::Srgb.to_linear(0.04045 + 1e-12);
        assert!((a - b).abs() < 1e-7, "{a} {b}");
        assert_eq!(Tone::Srgb.to_linear(1.0), 1.0);
    }
}
