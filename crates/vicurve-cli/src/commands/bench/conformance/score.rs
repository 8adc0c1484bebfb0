//! Scoring one case against the exact truth (as `vicurve eval` does) and
//! the acceptance criteria of the sweep, each in its own column.

use super::cases::{centre, Case};
use super::run::Ran;
use vicurve::fit::{Measurement, Outcome};
use vicurve::render::RenderSpec;
use vicurve::truth::{evaluate, Shape};
use vicurve::virtual_image::Kind;

/// Largest |bias| for blur <= 2 px and noise <= 2 %, px.
pub const BIAS_EASY: f64 = 2e-3;
/// Largest |bias| elsewhere, px.
pub const BIAS_HARD: f64 = 5e-3;
/// The bias may exceed its bound by this many of its noise's standard
/// deviations ([`bias_noise`]).
pub const BIAS_NOISE_SDS: f64 = 3.0;
/// Largest max |error| in units of the scatter (no wiggles).
pub const MAX_OVER_SCATTER: f64 = 8.0;
/// Accepted range of observed scatter / reported sigma.
pub const SIGMA_RATIO: (f64, f64) = (0.7, 1.4);
/// Smallest fraction of a closed curve the result must cover.
pub const CLOSED_COVERAGE: f64 = 0.99;
/// Largest gap between an open result's end and the outermost pixel
/// centre it should reach, px.
pub const BORDER_GAP: f64 = 10.0;
/// Distance to the truth within which a sample counts as covering it, px.
const NEAR: f64 = 1.0;

/// One row of `conformance.csv`.
#[derive(Clone, Debug)]
pub struct Row {
    /// Stable readable id: `shape/blurB/noiseN/Dbit/polarity/start[/paper-stages]`.
    pub id: String,
    /// Shape name; an encoded image's is followed by its tone curve
    /// (`disc srgb`), an astigmatic one's by `astigmatic`, a shaded one's
    /// by `shaded`, so that the report counts them apart.
    pub shape: String,
    /// `silhouette` or `contour`.
    pub kind: String,
    /// `bright` or `dark` object (line).
    pub polarity: String,
    /// Quantisation depth.
    pub bits: u8,
    /// Blur sigma, px (along x when `blur_y` is given).
    pub blur: f64,
    /// Astigmatic images: the blur along y, px.
    pub blur_y: Option<f64>,
    /// Noise, % of the contrast.
    pub noise_pct: f64,
    /// Start name.
    pub start: String,
    /// `default` or the explicit stages.
    pub schedule: String,
    /// `converged`, `iteration_limit`, `diverged` or `error`.
    pub outcome: String,
    /// Why it diverged or failed (empty otherwise).
    pub message: String,
    /// Mean signed normal distance of the output samples to the exact
    /// curve, px.
    pub bias: f64,
    /// RMS of that distance about its mean, px.
    pub scatter: f64,
    /// Largest |distance|, px.
    pub max_abs: f64,
    /// RMS of the reported per-sample sigma, px.
    pub sigma_rms: f64,
    /// The reported uncertainty of a shift common to the whole curve
    /// (`Measurement::sigma_shift`: the tone curve's reading), px; not in
    /// the samples' sigma nor in the criteria.
    pub sigma_shift: f64,
    /// Observed scatter / reported sigma.
    pub scatter_over_sigma: f64,
    /// Output samples.
    pub samples: usize,
    /// Length of the measured curve over that of the true one (of its
    /// `x_min..x_max` part for open curves): well above 1 for a curve that
    /// loops or wiggles.
    pub length_ratio: f64,
    /// Fraction of the true curve covered by samples within 1 px of it
    /// (closed: of 360 angular sectors about the centre; open: of the x
    /// range from the first to the last pixel column).
    pub coverage: f64,
    /// Open curves: larger gap between an end of the result and the
    /// outermost pixel centre, px (NaN for closed curves).
    pub border_gap: f64,
    /// Wall-clock time of the start and the fit, s.
    pub seconds: f64,
    /// The |bias| bound of this case, px.
    pub bias_limit: f64,
    /// The smallest standard deviation the image's noise leaves to the
    /// bias of any measurement ([`bias_noise`]), px.
    pub bias_noise: f64,
    /// |bias| <= bias_limit + [`BIAS_NOISE_SDS`] x bias_noise.
    pub bias_ok: bool,
    /// max |error| <= 8 x scatter.
    pub max_ok: bool,
    /// scatter / sigma in [0.7, 1.4].
    pub sigma_ok: bool,
    /// Outcome converged.
    pub converged_ok: bool,
    /// Closed: coverage >= 0.99; open: border gap <= 10 px.
    pub covered_ok: bool,
    /// Every criterion holds.
    pub pass: bool,
}

/// The figures of a measured curve.
struct Figures {
    bias: f64,
    scatter: f64,
    max_abs: f64,
    sigma_rms: f64,
    sigma_shift: f64,
    samples: usize,
    length_ratio: f64,
    coverage: f64,
    border_gap: f64,
}

impl Figures {
    const NONE: Figures = Figures {
        bias: f64::NAN,
        scatter: f64::NAN,
        max_abs: f64::NAN,
        sigma_rms: f64::NAN,
        sigma_shift: f64::NAN,
        samples: 0,
        length_ratio: f64::NAN,
        coverage: 0.0,
        border_gap: f64::NAN,
    };
}

/// The row of `case` from what running it gave.
pub fn score(case: &Case, ran: &Ran) -> Row {
    let (outcome, message, fig, seconds) = match ran {
        Ran::Measured { m, seconds } => {
            let (outcome, message) = outcome_text(&m.outcome);
            let fig = figures(m, &case.image.spec.shape, case.image.spec.width);
            (outcome, message, fig, *seconds)
        }
        Ran::Failed { message, seconds } => ("error", message.clone(), Figures::NONE, *seconds),
    };
    row(case, outcome, message, fig, seconds)
}

/// The samples of `m` with their signed normal distance to the truth of
/// `case` (px), as CSV: `s,x,y,error,sigma,sigma_noise,misfit,weight`.
pub fn samples_csv(case: &Case, m: &Measurement) -> String {
    let shape = &case.image.spec.shape;
    let mut out = String::from("s,x,y,error,sigma,sigma_noise,misfit,weight\n");
    for q in &m.samples {
        out.push_str(&format!(
            "{},{},{},{:e},{:e},{:e},{},{}\n",
            q.s,
            q.x,
            q.y,
            shape.signed_distance(q.x, q.y),
            q.sigma,
            q.sigma_noise,
            u8::from(q.misfit),
            q.weight
        ));
    }
    out
}

fn outcome_text(o: &Outcome) -> (&'static str, String) {
    match o {
        Outcome::Converged => ("converged", String::new()),
        Outcome::IterationLimit => ("iteration_limit", String::new()),
        Outcome::Diverged { divergence } => ("diverged", divergence.to_string()),
    }
}

fn figures(m: &Measurement, shape: &Shape, width: usize) -> Figures {
    let points = m.points();
    let Ok(stats) = evaluate(&points, shape) else {
        return Figures::NONE;
    };
    let sig: Vec<f64> = m.samples.iter().map(|s| s.sigma).collect();
    let sigma_rms = if sig.iter().all(|s| s.is_finite()) && !sig.is_empty() {
        (sig.iter().map(|s| s * s).sum::<f64>() / sig.len() as f64).sqrt()
    } else {
        f64::NAN
    };
    let (coverage, border_gap) = if shape.is_closed() {
        (closed_coverage(&points, shape), f64::NAN)
    } else {
        open_coverage(&points, shape, width)
    };
    Figures {
        bias: stats.bias,
        scatter: stats.scatter,
        max_abs: stats.max_abs,
        sigma_rms,
        sigma_shift: m.sigma_shift(),
        samples: points.len(),
        length_ratio: m.length() / shape.length(),
        coverage,
        border_gap,
    }
}

/// Fraction of 360 sectors about the centre holding the foot of a sample
/// within [`NEAR`] of the curve.
fn closed_coverage(points: &[[f64; 2]], shape: &Shape) -> f64 {
    let (cx, cy) = centre(shape);
    let mut hit = [false; 360];
    for p in points {
        let (foot, _) = shape.closest_point(p[0], p[1]);
        if (foot[0] - p[0]).hypot(foot[1] - p[1]) > NEAR {
            continue;
        }
        let th = (-(foot[1] - cy))
            .atan2(foot[0] - cx)
            .rem_euclid(std::f64::consts::TAU);
        let k = ((th / std::f64::consts::TAU * 360.0) as usize).min(359);
        hit[k] = true;
    }
    hit.iter().filter(|&&h| h).count() as f64 / 360.0
}

/// Open curve: the x range of the samples within [`NEAR`] of the curve,
/// as a fraction of `0..width-1`, and the larger gap to those columns.
fn open_coverage(points: &[[f64; 2]], shape: &Shape, width: usize) -> (f64, f64) {
    let near = points
        .iter()
        .filter(|p| shape.signed_distance(p[0], p[1]).abs() <= NEAR);
    let (lo, hi) = near.fold((f64::INFINITY, f64::NEG_INFINITY), |(lo, hi), p| {
        (lo.min(p[0]), hi.max(p[0]))
    });
    let last = width as f64 - 1.0;
    if lo > hi {
        return (0.0, f64::NAN);
    }
    ((hi - lo) / last, lo.max(last - hi))
}

/// The Cramér–Rao bound on the standard deviation of the bias (the mean
/// normal displacement) that the noise of `spec` leaves (px): no method
/// measures the mean position of the whole curve more precisely from one
/// image, so a bias within a few of these is no evidence of a systematic
/// one (which the noiseless images of the same case show).
///
/// The information on the mean displacement is the curve's length times
/// `c^2 integral p'(t)^2 dt / s^2` per pixel of length: `p` the unit
/// profile across the curve (an error-function step, or a line of the
/// rendered width, of variance `v = blur^2 + 1/12` with the pixel's own
/// integration), `c` the contrast and `s^2` the noise variance with the
/// rounding of the quantised levels (`q^2 / 12`). Curvature and the
/// image's border are left out (a few per cent).
pub fn bias_noise(spec: &RenderSpec) -> f64 {
    let c = (spec.foreground - spec.background).abs();
    let q = match spec.bits {
        Some(8) => 1.0 / 255.0,
        Some(16) => 1.0 / 65535.0,
        _ => 0.0,
    };
    let var = (spec.noise * c).powi(2) + q * q / 12.0;
    // An astigmatic blur: its mean variance over the directions.
    let y = spec.blur_sigma_y.unwrap_or(spec.blur_sigma);
    let sd = (0.5 * (spec.blur_sigma.powi(2) + y * y) + 1.0 / 12.0).sqrt();
    // integral of phi_sd(t)^2 dt.
    let edge = 1.0 / (2.0 * std::f64::consts::PI.sqrt() * sd);
    let profile = match spec.kind {
        Kind::Silhouette => edge,
        // (phi(t + w/2) - phi(t - w/2))^2: two bells and their overlap.
        Kind::Contour => 2.0 * edge * (1.0 - (-(spec.line_width / (2.0 * sd)).powi(2)).exp()),
    };
    let information = spec.shape.length() * c * c * profile / var;
    1.0 / information.sqrt()
}

fn row(case: &Case, outcome: &str, message: String, f: Figures, seconds: f64) -> Row {
    let img = &case.image;
    // An astigmatic image is as blurred as its larger blur.
    let blur = img.blur.max(img.blur_y.unwrap_or(0.0));
    let bias_limit = if blur <= 2.0 && img.noise <= 0.02 {
        BIAS_EASY
    } else {
        BIAS_HARD
    };
    let ratio = f.scatter / f.sigma_rms;
    let bias_noise = bias_noise(&img.spec);
    let bias_ok = f.bias.abs() <= bias_limit + BIAS_NOISE_SDS * bias_noise;
    let max_ok = f.max_abs <= MAX_OVER_SCATTER * f.scatter;
    let sigma_ok = ratio >= SIGMA_RATIO.0 && ratio <= SIGMA_RATIO.1;
    let converged_ok = outcome == "converged";
    let covered_ok = if img.spec.shape.is_closed() {
        f.coverage >= CLOSED_COVERAGE
    } else {
        f.border_gap <= BORDER_GAP
    };
    Row {
        id: case.id.clone(),
        shape: match (img.tone.is_identity(), img.blur_y, img.shading.is_even()) {
            (true, None, true) => img.shape.name(),
            (true, None, false) => format!("{} shaded", img.shape.name()),
            (true, Some(_), _) => format!("{} astigmatic", img.shape.name()),
            (false, _, _) => format!("{} {}", img.shape.name(), img.tone),
        },
        kind: format!("{:?}", img.shape.kind()).to_lowercase(),
        polarity: if img.bright { "bright" } else { "dark" }.into(),
        bits: img.bits,
        blur: img.blur,
        blur_y: img.blur_y,
        noise_pct: (img.noise * 100.0 * 1e6).round() / 1e6,
        start: case.start.name().into(),
        schedule: case.stages.unwrap_or("default").into(),
        outcome: outcome.into(),
        message,
        bias: f.bias,
        scatter: f.scatter,
        max_abs: f.max_abs,
        sigma_rms: f.sigma_rms,
        sigma_shift: f.sigma_shift,
        scatter_over_sigma: ratio,
        samples: f.samples,
        length_ratio: f.length_ratio,
        coverage: f.coverage,
        border_gap: f.border_gap,
        seconds,
        bias_limit,
        bias_noise,
        bias_ok,
        max_ok,
        sigma_ok,
        converged_ok,
        covered_ok,
        pass: bias_ok && max_ok && sigma_ok && converged_ok && covered_ok,
    }
}

impl Row {
    /// `(column, cell)` in the CSV's order: numbers in full precision
    /// (NaN when unknown), text quoted.
    pub fn cells(&self) -> Vec<(&'static str, String)> {
        let q = |t: &str| format!("\"{}\"", t.replace('"', "\"\"").replace('\n', " "));
        let f = |v: f64| format!("{v:e}");
        let b = |v: bool| v.to_string();
        vec![
            ("id", q(&self.id)),
            ("shape", q(&self.shape)),
            ("kind", q(&self.kind)),
            ("polarity", q(&self.polarity)),
            ("bits", self.bits.to_string()),
            ("blur", self.blur.to_string()),
            (
                "blur_y",
                self.blur_y.map_or(String::new(), |y| y.to_string()),
            ),
            ("noise_pct", self.noise_pct.to_string()),
            ("start", q(&self.start)),
            ("schedule", q(&self.schedule)),
            ("outcome", q(&self.outcome)),
            ("message", q(&self.message)),
            ("bias", f(self.bias)),
            ("scatter", f(self.scatter)),
            ("max_abs", f(self.max_abs)),
            ("sigma_rms", f(self.sigma_rms)),
            ("sigma_shift", f(self.sigma_shift)),
            ("scatter_over_sigma", f(self.scatter_over_sigma)),
            ("samples", self.samples.to_string()),
            ("length_ratio", self.length_ratio.to_string()),
            ("coverage", self.coverage.to_string()),
            ("border_gap", self.border_gap.to_string()),
            ("seconds", format!("{:.4}", self.seconds)),
            ("bias_limit", f(self.bias_limit)),
            ("bias_noise", f(self.bias_noise)),
            ("bias_ok", b(self.bias_ok)),
            ("max_ok", b(self.max_ok)),
            ("sigma_ok", b(self.sigma_ok)),
            ("converged_ok", b(self.converged_ok)),
            ("covered_ok", b(self.covered_ok)),
            ("pass", b(self.pass)),
        ]
    }

    /// The failed criteria, e.g. `bias 3.1e-3 > 2e-3; not converged
    /// (iteration_limit)`; empty when the case passes.
    pub fn reasons(&self) -> String {
        if self.outcome == "error" {
            // No curve: the other criteria say nothing more.
            return format!("error: {}", self.message);
        }
        let mut r = Vec::new();
        if !self.converged_ok {
            r.push(match self.outcome.as_str() {
                "diverged" => format!("diverged: {}", self.message),
                o => format!("not converged ({o})"),
            });
        }
        if !self.bias_ok {
            r.push(format!(
                "|bias| {:.2e} > {:.0e} + {BIAS_NOISE_SDS} x {:.1e}{}",
                self.bias.abs(),
                self.bias_limit,
                self.bias_noise,
                if self.sigma_shift > 0.0 {
                    format!(" (reported shift sigma {:.1e})", self.sigma_shift)
                } else {
                    String::new()
                }
            ));
        }
        if !self.max_ok {
            r.push(format!(
                "max {:.2e} > 8 x scatter {:.2e}",
                self.max_abs, self.scatter
            ));
        }
        if !self.sigma_ok {
            r.push(format!("scatter/sigma {:.2}", self.scatter_over_sigma));
        }
        if !self.covered_ok {
            r.push(if self.border_gap.is_nan() {
                format!("covers {:.1} %", 100.0 * self.coverage)
            } else {
                format!("ends {:.1} px from the border", self.border_gap)
            });
        }
        r.join("; ")
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use vicurve::render::render;

    /// The bound against the information summed over a rendered disc's
    /// pixels: each pixel's derivative with respect to the radius by
    /// central differences of two exact-coverage renderings, so pixel
    /// integration, curvature and the renderer's own blur all count.
    #[test]
    fn the_bias_bound_is_the_information_of_the_rendered_pixels() {
        for (blur, kind) in [
            (0.0, Kind::Silhouette),
            (1.5, Kind::Silhouette),
            (1.0, Kind::Contour),
        ] {
            let spec = |r: f64| RenderSpec {
                width: 160,
                height: 160,
                shape: Shape::Circle {
                    cx: 80.3,
                    cy: 79.6,
                    r,
                },
                kind,
                line_width: 2.5,
                blur_sigma: blur,
                noise: 0.02,
                bits: None,
                ..RenderSpec::default()
            };
            let h = 0.05;
            let (plus, minus) = (
                render(&spec(50.0 + h)).unwrap(),
                render(&spec(50.0 - h)).unwrap(),
            );
            let c = 0.6;
            let var = (0.02 * c) * (0.02 * c);
            let information: f64 = plus
                .data()
                .iter()
                .zip(minus.data())
                .map(|(p, m)| ((p - m) / (2.0 * h)).powi(2) / var)
                .sum();
            let expected = 1.0 / information.sqrt();
            let bound = bias_noise(&spec(50.0));
            let rel = bound / expected - 1.0;
            assert!(
                rel.abs() < 0.05,
                "blur {blur} {kind:?}: {bound:e} vs {expected:e}"
            );
        }
    }
}
