//! Parametric evaluation, closest-point search and arc length of the true
//! shapes.
//!
//! The closest point minimises `g(s) = |p(s) - q|² / 2`. Its derivative
//! `g'(s) = (p - q)·p'` changes sign from `-` to `+` across every local
//! minimum, so sampling `g'` finely enough (the tangent turns by at most
//! [`TURN`] radians between samples) brackets each of them; each bracket is
//! refined by a safeguarded Newton iteration on `g'` and the smallest `g`
//! wins. The samples are restricted to the parameters whose points can be
//! closer than an easily found point of the curve, which keeps the search
//! short for points near the curve.

use std::f64::consts::{PI, TAU};

use super::Shape;
use crate::error::{Error, Result};

/// Largest turn of the tangent between two samples of the coarse search,
/// rad. Two local minima of the distance closer than this only occur for
/// points near a centre of curvature, where both are equally far.
const TURN: f64 = 0.2;

/// Upper bound on the number of coarse samples of one search (guards against
/// absurd inputs; reached only for points millions of wavelengths away).
const MAX_SAMPLES: usize = 1 << 22;

/// Gauss-Legendre nodes and weights (8 points) on `[-1, 1]`, positive half.
const GL_X: [f64; 4] = [
    0.183_434_642_495_649_8,
    0.525_532_409_916_329,
    0.796_666_477_413_626_7,
    0.960_289_856_497_536_2,
];
const GL_W: [f64; 4] = [
    0.362_683_783_378_362,
    0.313_706_645_877_887_3,
    0.222_381_034_453_374_5,
    0.101_228_536_290_376_26,
];

/// A point of a parametric curve and its first two derivatives in the
/// parameter, px.
#[derive(Clone, Copy, Debug)]
pub(crate) struct CurvePoint {
    /// Position.
    pub p: [f64; 2],
    /// First derivative.
    pub d1: [f64; 2],
    /// Second derivative.
    pub d2: [f64; 2],
}

impl CurvePoint {
    /// Speed `|p'|`, px per parameter unit.
    #[inline]
    pub fn speed(&self) -> f64 {
        self.d1[0].hypot(self.d1[1])
    }

    /// Unit normal `n = (-t_y, t_x)`.
    #[inline]
    pub fn normal(&self) -> [f64; 2] {
        let v = self.speed();
        [-self.d1[1] / v, self.d1[0] / v]
    }

    /// Signed curvature `k`, 1/px, defined by `dt/dσ = k n` (σ = arc
    /// length): negative where a counterclockwise closed curve is convex.
    #[inline]
    pub fn curvature(&self) -> f64 {
        let v = self.speed();
        (self.d1[0] * self.d2[1] - self.d1[1] * self.d2[0]) / (v * v * v)
    }
}

impl Shape {
    /// The curve at parameter `s` (angle for closed shapes, `x` for the sine).
    pub(crate) fn eval(&self, s: f64) -> CurvePoint {
        match *self {
            Shape::Circle { cx, cy, r } => {
                let (sn, cs) = s.sin_cos();
                CurvePoint {
                    p: [cx + r * cs, cy - r * sn],
                    d1: [-r * sn, -r * cs],
                    d2: [-r * cs, r * sn],
                }
            }
            Shape::Ellipse {
                cx,
                cy,
                a,
                b,
                angle,
            } => {
                let (sn, cs) = s.sin_cos();
                let (sa, ca) = angle.sin_cos();
                // Local (math, y up) frame, rotated by `angle`, then y flipped.
                let screen = |lx: f64, ly: f64| [lx * ca - ly * sa, -(lx * sa + ly * ca)];
                let p = screen(a * cs, b * sn);
                CurvePoint {
                    p: [cx + p[0], cy + p[1]],
                    d1: screen(-a * sn, b * cs),
                    d2: screen(-a * cs, -b * sn),
                }
            }
            Shape::Star {
                cx,
                cy,
                r0,
                amplitude,
                lobes,
                phase,
            } => {
                let k = f64::from(lobes);
                let (sk, ck) = (k * s + phase).sin_cos();
                let r = r0 * (1.0 + amplitude * ck);
                let r1 = -r0 * amplitude * k * sk;
                let r2 = -r0 * amplitude * k * k * ck;
                let (sn, cs) = s.sin_cos();
                CurvePoint {
                    p: [cx + r * cs, cy - r * sn],
                    d1: [r1 * cs - r * sn, -(r1 * sn + r * cs)],
                    d2: [
                        r2 * cs - 2.0 * r1 * sn - r * cs,
                        -(r2 * sn + 2.0 * r1 * cs - r * sn),
                    ],
                }
            }
            Shape::Polygon { sides, .. } => super::polygon::eval(self, sides, s),
            Shape::Sine {
                y0,
                amplitude,
                wavelength,
                phase,
                ..
            } => {
                let w = TAU / wavelength;
                let (sn, cs) = (w * s + phase).sin_cos();
                CurvePoint {
                    p: [s, y0 + amplitude * sn],
                    d1: [1.0, amplitude * w * cs],
                    d2: [0.0, -amplitude * w * w * sn],
                }
            }
        }
    }

    /// Parameter interval of the curve: `[0, 2π]` for closed shapes,
    /// `[x_min, x_max]` for the sine.
    pub(crate) fn param_span(&self) -> (f64, f64) {
        match *self {
            Shape::Sine { x_min, x_max, .. } => (x_min, x_max),
            _ => (0.0, TAU),
        }
    }

    /// Parameter step over which the tangent turns by at most [`TURN`].
    pub(crate) fn search_step(&self) -> f64 {
        match *self {
            Shape::Circle { .. } => TURN,
            Shape::Ellipse { a, b, .. } => TURN * a.min(b) / a.max(b),
            Shape::Star {
                amplitude, lobes, ..
            } => {
                // |dψ/dθ| = |r² + 2r'² - r r''| / (r² + r'²)
                //        <= 1 + 2 (r'/r)² + |r''|/r.
                let a = amplitude.abs();
                let k = f64::from(lobes);
                let ratio = a * k / (1.0 - a);
                TURN / (1.0 + 2.0 * ratio * ratio + ratio * k)
            }
            // Straight edges: any step integrates the (constant) speed
            // exactly; a quarter edge keeps the panels short.
            Shape::Polygon { sides, .. } => 0.25 * TAU / f64::from(sides),
            Shape::Sine {
                amplitude,
                wavelength,
                ..
            } => {
                let w = TAU / wavelength;
                (wavelength / 16.0).min(TURN / (amplitude.abs() * w * w))
            }
        }
    }

    /// Arc length between the parameters `s0 < s1`, px.
    pub(crate) fn length_between(&self, s0: f64, s1: f64) -> f64 {
        arc_length(self, s0, s1, self.panels(s0, s1))
    }

    /// Number of panels for integrating over `[s0, s1]`.
    pub(crate) fn panels(&self, s0: f64, s1: f64) -> usize {
        let n = ((s1 - s0) / self.search_step()).ceil();
        if n.is_finite() {
            (n as usize).clamp(64, MAX_SAMPLES)
        } else {
            64
        }
    }

    /// Parameter of the point of the curve closest to `q` (global minimum).
    pub(crate) fn closest_param(&self, q: [f64; 2]) -> f64 {
        if !(q[0].is_finite() && q[1].is_finite()) {
            return f64::NAN;
        }
        let step = self.search_step();
        match *self {
            Shape::Circle { cx, cy, .. } => (-(q[1] - cy)).atan2(q[0] - cx),
            Shape::Ellipse {
                cx,
                cy,
                a,
                b,
                angle,
            } => {
                let (sa, ca) = angle.sin_cos();
                let (x, y) = (q[0] - cx, -(q[1] - cy));
                let (u, v) = (x * ca + y * sa, -x * sa + y * ca);
                let phi = v.atan2(u);
                // Eccentric anomaly of the point of polar angle `phi`.
                let anomaly = |phi: f64| {
                    let (s, c) = phi.sin_cos();
                    (a * s).atan2(b * c)
                };
                self.search_polar(q, u.hypot(v), phi, anomaly, step)
            }
            Shape::Star { cx, cy, .. } => {
                let (x, y) = (q[0] - cx, -(q[1] - cy));
                self.search_polar(q, x.hypot(y), y.atan2(x), |phi| phi, step)
            }
            Shape::Polygon { sides, .. } => super::polygon::closest_param(self, sides, q),
            Shape::Sine { .. } => {
                let s_r = q[0];
                let d = (q[1] - self.eval(s_r).p[1]).abs();
                if d == 0.0 {
                    return s_r;
                }
                let reach = d * (1.0 + 1e-9) + 1e-12;
                let n = samples(2.0 * reach / step);
                self.search(q, s_r - reach, s_r + reach, n, s_r)
            }
        }
    }

    /// Closest-point search for a closed shape that is star-shaped about its
    /// centre. `rho, phi`: polar coordinates of `q` about the centre (math
    /// angle, counterclockwise on screen); `anomaly` maps a polar angle to the
    /// parameter of the curve point in that direction (increasing).
    ///
    /// The curve point `p_r` in the direction of `q` is at distance `D`; the
    /// closest point is within the disc of radius `D` about `q`, whose polar
    /// angles are within `asin(D / rho)` of `phi` when `D < rho`.
    fn search_polar(
        &self,
        q: [f64; 2],
        rho: f64,
        phi: f64,
        anomaly: impl Fn(f64) -> f64,
        step: f64,
    ) -> f64 {
        let s_r = anomaly(phi);
        let p = self.eval(s_r).p;
        let d = (p[0] - q[0]).hypot(p[1] - q[1]);
        if d == 0.0 {
            return s_r;
        }
        let full = samples(TAU / step);
        if d >= rho * (1.0 - 1e-9) {
            return self.search(q, 0.0, TAU, full, s_r);
        }
        let w = (d / rho).asin() * (1.0 + 1e-9) + 1e-12;
        let wrap = |x: f64| (x + PI).rem_euclid(TAU) - PI;
        let lo = s_r - wrap(s_r - anomaly(phi - w)).max(0.0);
        let hi = s_r + wrap(anomaly(phi + w) - s_r).max(0.0);
        let n = samples((hi - lo) / step);
        self.search(q, lo, hi, n, s_r)
    }

    /// Global minimum of the distance to `q` over `[lo, hi]` from `n` sample
    /// intervals, starting from the candidate parameter `s_best`.
    fn search(&self, q: [f64; 2], lo: f64, hi: f64, n: usize, mut s_best: f64) -> f64 {
        let mut g_best = dist2(self.eval(s_best).p, q);
        let mut prev: Option<(f64, f64)> = None;
        for i in 0..=n {
            let s = if i == n {
                hi
            } else {
                lo + (hi - lo) * (i as f64 / n as f64)
            };
            let e = self.eval(s);
            let g = dist2(e.p, q);
            if g < g_best {
                g_best = g;
                s_best = s;
            }
            let f = (e.p[0] - q[0]) * e.d1[0] + (e.p[1] - q[1]) * e.d1[1];
            if let Some((s_prev, f_prev)) = prev {
                if f_prev < 0.0 && f >= 0.0 {
                    let s_min = self.refine(q, s_prev, s);
                    let g_min = dist2(self.eval(s_min).p, q);
                    if g_min < g_best {
                        g_best = g_min;
                        s_best = s_min;
                    }
                }
            }
            prev = Some((s, f));
        }
        s_best
    }

    /// Root of `g'(s) = (p - q)·p'` in `[lo, hi]` where `g'(lo) < 0 <= g'(hi)`:
    /// Newton's method, falling back to bisection when a step leaves the
    /// bracket.
    fn refine(&self, q: [f64; 2], mut lo: f64, mut hi: f64) -> f64 {
        let mut s = 0.5 * (lo + hi);
        for _ in 0..200 {
            let e = self.eval(s);
            let (dx, dy) = (e.p[0] - q[0], e.p[1] - q[1]);
            let f = dx * e.d1[0] + dy * e.d1[1];
            if f == 0.0 {
                return s;
            }
            if f < 0.0 {
                lo = s;
            } else {
                hi = s;
            }
            let fp = e.d1[0] * e.d1[0] + e.d1[1] * e.d1[1] + dx * e.d2[0] + dy * e.d2[1];
            let newton = s - f / fp;
            let next = if fp > 0.0 && newton > lo && newton < hi {
                newton
            } else {
                0.5 * (lo + hi)
            };
            let done = (next - s).abs() <= 4.0 * f64::EPSILON * s.abs().max(1.0);
            s = next;
            if done || hi - lo <= 4.0 * f64::EPSILON * s.abs().max(1.0) {
                break;
            }
        }
        s
    }

    /// Points evenly spaced in arc length, at most `max_step` px apart; at
    /// most `max_points` of them.
    pub(crate) fn polyline_unchecked(
        &self,
        max_step: f64,
        max_points: usize,
    ) -> Result<Vec<[f64; 2]>> {
        let (s0, s1) = self.param_span();
        let m = self.panels(s0, s1);
        let h = (s1 - s0) / m as f64;
        let mut cum = Vec::with_capacity(m + 1);
        cum.push(0.0);
        let mut total = 0.0;
        for j in 0..m {
            total += arc_length(self, s0 + j as f64 * h, s0 + (j + 1) as f64 * h, 1);
            cum.push(total);
        }
        let segments = (total / max_step * (1.0 + 1e-9)).ceil().max(1.0);
        let closed = self.is_closed();
        let segments = if closed { segments.max(3.0) } else { segments };
        let count = if closed { segments } else { segments + 1.0 };
        if count.is_nan() || count > max_points as f64 {
            return Err(Error::invalid(
                "max_step",
                format!("{max_step} px would give {count} points (at most {max_points})"),
            ));
        }
        let segments = segments as usize;
        let mut out = Vec::with_capacity(count as usize);
        let mut j = 0;
        for i in 0..count as usize {
            if !closed && i == segments {
                out.push(self.eval(s1).p);
                break;
            }
            let target = total * (i as f64 / segments as f64);
            while j + 1 < m && cum[j + 1] < target {
                j += 1;
            }
            let (a, b) = (s0 + j as f64 * h, s0 + (j + 1) as f64 * h);
            // Newton on the arc length inside panel j, from linear
            // interpolation.
            let span = cum[j + 1] - cum[j];
            let mut s = if span > 0.0 {
                a + (b - a) * ((target - cum[j]) / span).clamp(0.0, 1.0)
            } else {
                a
            };
            for _ in 0..6 {
                let len = cum[j] + arc_length(self, a, s, 1);
                let v = self.eval(s).speed();
                if v <= 0.0 {
                    break;
                }
                s = (s - (len - target) / v).clamp(a, b);
            }
            out.push(self.eval(s).p);
        }
        Ok(out)
    }
}

/// Number of sample intervals for a span covering `x` search steps.
fn samples(x: f64) -> usize {
    if x.is_finite() {
        (x.ceil() as usize).clamp(4, MAX_SAMPLES)
    } else {
        MAX_SAMPLES
    }
}

#[inline]
fn dist2(p: [f64; 2], q: [f64; 2]) -> f64 {
    let (dx, dy) = (p[0] - q[0], p[1] - q[1]);
    dx * dx + dy * dy
}

/// Arc length of `shape` over the parameters `[s0, s1]` with `panels`
/// 8-point Gauss-Legendre panels, px.
pub(crate) fn arc_length(shape: &Shape, s0: f64, s1: f64, panels: usize) -> f64 {
    let h = (s1 - s0) / panels as f64;
    let mut total = 0.0;
    for j in 0..panels {
        let mid = s0 + (j as f64 + 0.5) * h;
        let half = 0.5 * h;
        let mut sum = 0.0;
        for (x, w) in GL_X.iter().zip(GL_W) {
            sum += w * (shape.eval(mid - half * x).speed() + shape.eval(mid + half * x).speed());
        }
        total += sum * half;
    }
    total
}

/// Smallest absolute radius of curvature of a star: the curvature repeats
/// with each lobe, so one lobe is sampled, then refined by golden section.
pub(crate) fn star_min_curvature_radius(shape: &Shape) -> f64 {
    let Shape::Star { lobes, .. } = *shape else {
        return f64::NAN;
    };
    let period = TAU / f64::from(lobes);
    let n = 2048;
    let kappa = |s: f64| shape.eval(s).curvature().abs();
    let h = period / n as f64;
    let (mut best_i, mut best) = (0, f64::NEG_INFINITY);
    for i in 0..n {
        let k = kappa(i as f64 * h);
        if k > best {
            best = k;
            best_i = i;
        }
    }
    // Golden-section search for the maximum of |k| around the best sample.
    let (a, b) = ((best_i as f64 - 1.0) * h, (best_i as f64 + 1.0) * h);
    let peak = crate::psf::golden(a, b, 80, |s| -kappa(s));
    1.0 / best.max(kappa(peak))
}
