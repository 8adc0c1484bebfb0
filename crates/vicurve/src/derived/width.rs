//! Width between two open curves (a specimen's two edges) along an axis.
//!
//! For a position `p`, the *section* is the straight line perpendicular to
//! the axis through `origin + p direction`; the width there is the distance
//! between the points where the two curves cross that line. Each crossing is
//! bracketed on a dense parameter grid of the B-spline (at most 1 px apart)
//! and refined on the B-spline itself by safeguarded Newton steps, so the
//! width is that of the measured curves to rounding, whatever `step`.

use crate::curve::SplineCurve;
use crate::error::{Error, Result};
use crate::measurement::{Measurement, Sample};
use serde::{Deserialize, Serialize};

/// The axis along which a width is profiled: positions are measured along
/// `direction` (a unit vector) from `origin`, widths perpendicular to it.
/// Pixels.
#[derive(Clone, Copy, Debug, PartialEq, Serialize, Deserialize)]
pub struct WidthAxis {
    /// The point of position 0, `[x, y]`, px.
    pub origin: [f64; 2],
    /// Unit vector of increasing position, `[x, y]`.
    pub direction: [f64; 2],
}

impl WidthAxis {
    /// The axis through `origin` along `direction` (normalised).
    ///
    /// Errors: [`Error::InvalidParameter`] for a zero or non-finite
    /// direction or a non-finite origin.
    pub fn new(origin: [f64; 2], direction: [f64; 2]) -> Result<Self> {
        let len = direction[0].hypot(direction[1]);
        if !(len.is_finite() && len > 0.0) {
            return Err(Error::invalid(
                "width axis",
                format!("direction {direction:?} must be a non-zero vector"),
            ));
        }
        if !(origin[0].is_finite() && origin[1].is_finite()) {
            return Err(Error::invalid(
                "width axis",
                format!("origin {origin:?} must be finite"),
            ));
        }
        Ok(WidthAxis {
            origin,
            direction: [direction[0] / len, direction[1] / len],
        })
    }

    /// Positions are `x` (columns), widths are measured along `y`: a
    /// horizontal specimen.
    pub fn x() -> Self {
        WidthAxis {
            origin: [0.0, 0.0],
            direction: [1.0, 0.0],
        }
    }

    /// Positions are `y` (rows), widths are measured along `x`: a vertical
    /// specimen.
    pub fn y() -> Self {
        WidthAxis {
            origin: [0.0, 0.0],
            direction: [0.0, 1.0],
        }
    }

    /// The axis through `origin` at `angle` radians from `+x`,
    /// counterclockwise on screen (direction `(cos angle, -sin angle)`, the
    /// convention of [`crate::truth::Shape::Ellipse`]).
    ///
    /// Errors: [`Error::InvalidParameter`] for a non-finite angle or origin.
    pub fn from_angle(origin: [f64; 2], angle: f64) -> Result<Self> {
        if !angle.is_finite() {
            return Err(Error::invalid("width axis", format!("angle {angle}")));
        }
        Self::new(origin, [angle.cos(), -angle.sin()])
    }

    /// The principal direction of the two measured curves' samples taken
    /// together, through their centroid, pointing along the direction of
    /// travel of `a` (from its first sample to its last). Positions are
    /// then relative to the middle of the specimen; keep one axis for a
    /// whole sequence so that positions compare between frames.
    ///
    /// Errors: [`Error::InvalidCurve`] with fewer than 2 samples in all or
    /// when they do not define a direction.
    pub fn estimate(a: &Measurement, b: &Measurement) -> Result<Self> {
        let pts: Vec<[f64; 2]> = a.points().into_iter().chain(b.points()).collect();
        let travel = match (a.samples.first(), a.samples.last()) {
            (Some(p), Some(q)) => [q.x - p.x, q.y - p.y],
            _ => [0.0, 0.0],
        };
        Self::principal(&pts, travel)
    }

    /// [`WidthAxis::estimate`] for B-spline curves (sampled every pixel).
    pub fn estimate_curves(a: &SplineCurve, b: &SplineCurve) -> Result<Self> {
        let sample = |c: &SplineCurve| -> Vec<[f64; 2]> {
            let n = (c.param_length().ceil() as usize).clamp(2, 1_000_000);
            c.sample_params(n).into_iter().map(|u| c.point(u)).collect()
        };
        let pa = sample(a);
        let travel = [
            pa[pa.len() - 1][0] - pa[0][0],
            pa[pa.len() - 1][1] - pa[0][1],
        ];
        let pts: Vec<[f64; 2]> = pa.into_iter().chain(sample(b)).collect();
        Self::principal(&pts, travel)
    }

    fn principal(pts: &[[f64; 2]], travel: [f64; 2]) -> Result<Self> {
        if pts.len() < 2 || pts.iter().any(|p| !(p[0].is_finite() && p[1].is_finite())) {
            return Err(Error::InvalidCurve {
                reason: "too few (finite) points to estimate a width axis".into(),
            });
        }
        let n = pts.len() as f64;
        let m = pts
            .iter()
            .fold([0.0, 0.0], |a, p| [a[0] + p[0] / n, a[1] + p[1] / n]);
        let (mut sxx, mut sxy, mut syy) = (0.0, 0.0, 0.0);
        for p in pts {
            let (x, y) = (p[0] - m[0], p[1] - m[1]);
            sxx += x * x;
            sxy += x * y;
            syy += y * y;
        }
        let spread = sxx + syy;
        if spread.is_nan() || spread <= 0.0 {
            return Err(Error::InvalidCurve {
                reason: "the curves' points coincide: no width axis".into(),
            });
        }
        let theta = 0.5 * (2.0 * sxy).atan2(sxx - syy);
        let mut d = [theta.cos(), theta.sin()];
        if d[0] * travel[0] + d[1] * travel[1] < 0.0 {
            d = [-d[0], -d[1]];
        }
        Self::new(m, d)
    }

    /// Unit vector along the sections, `direction` turned by +90 degrees in
    /// `(x, y)`: `(-d_y, d_x)`.
    pub fn across(&self) -> [f64; 2] {
        [-self.direction[1], self.direction[0]]
    }

    /// Position of a point along the axis, px.
    pub fn position(&self, q: [f64; 2]) -> f64 {
        (q[0] - self.origin[0]) * self.direction[0] + (q[1] - self.origin[1]) * self.direction[1]
    }
}

/// One section of a width profile. Pixels.
#[derive(Clone, Copy, Debug, PartialEq, Serialize, Deserialize)]
pub struct WidthSample {
    /// Position along the axis, px.
    pub position: f64,
    /// Distance between the two curves along the section, px (`>= 0`).
    pub width: f64,
    /// Standard deviation of `width`, px, from both curves' per-sample
    /// `sigma` (NaN without them; infinite where a curve runs along the
    /// section).
    pub sigma: f64,
}

/// The width between two curves along an axis. Pixels.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub struct WidthProfile {
    /// The axis of the positions.
    pub axis: WidthAxis,
    /// Sections at every multiple of the step where both curves cross the
    /// section line exactly once, in increasing position.
    pub samples: Vec<WidthSample>,
    /// The smallest width: the smallest sample, its position refined on the
    /// curves by a golden-section search between its neighbours when both
    /// are present (so not limited by the step); `None` without samples.
    pub min: Option<WidthSample>,
}

/// The width between the measured curves `a` and `b` along `axis`, at the
/// positions `k step` (integer `k`) where both are defined; see
/// [`width_profile_curves`].
///
/// Errors: as [`width_profile_curves`].
pub fn width_profile(
    a: &Measurement,
    b: &Measurement,
    axis: &WidthAxis,
    step: f64,
) -> Result<WidthProfile> {
    width_profile_curves(
        &a.curve,
        Some(&a.samples),
        &b.curve,
        Some(&b.samples),
        axis,
        step,
    )
}

/// The width between the B-spline curves `a` and `b` (open or closed) along
/// `axis`, at the positions `k step` (integer `k`) within the range where
/// both curves are defined.
///
/// A position is absent when either curve does not cross its section line,
/// or crosses it more than once (the width would be ambiguous). The width's
/// uncertainty combines both curves' normal uncertainties, interpolated in
/// `s` from their samples `sa`, `sb` (whose `s` is the curve's parameter, as
/// in a [`Measurement`]), each divided by `|cos|` of the angle between the
/// curve's normal and the section: `sqrt(sa^2 / cos_a^2 + sb^2 / cos_b^2)`.
/// The two curves are measured independently, hence the quadrature sum;
/// neighbouring positions are correlated (each curve is a smooth B-spline).
///
/// Errors: [`Error::InvalidParameter`] for a step that is not a positive
/// number, an axis whose direction is not a unit vector, or more than ten
/// million positions.
pub fn width_profile_curves(
    a: &SplineCurve,
    sa: Option<&[Sample]>,
    b: &SplineCurve,
    sb: Option<&[Sample]>,
    axis: &WidthAxis,
    step: f64,
) -> Result<WidthProfile> {
    if !(step.is_finite() && step > 0.0) {
        return Err(Error::invalid(
            "width step",
            format!("{step} must be a positive number of pixels"),
        ));
    }
    let dn = axis.direction[0].hypot(axis.direction[1]);
    if !((dn - 1.0).abs() < 1e-9 && axis.origin.iter().all(|v| v.is_finite())) {
        return Err(Error::invalid(
            "width axis",
            "the direction must be a unit vector and the origin finite (use WidthAxis::new)",
        ));
    }
    let ca = Crossings::new(a, sa, axis);
    let cb = Crossings::new(b, sb, axis);
    let lo = ca.range.0.max(cb.range.0);
    let hi = ca.range.1.min(cb.range.1);
    let mut samples = Vec::new();
    if lo <= hi {
        let k0 = (lo / step).ceil() as i64;
        let k1 = (hi / step).floor() as i64;
        if k1 - k0 > 10_000_000 {
            return Err(Error::invalid(
                "width step",
                format!("{step} px gives more than ten million positions"),
            ));
        }
        for k in k0..=k1 {
            let p = k as f64 * step;
            if let Some(s) = section(&ca, &cb, axis, p) {
                samples.push(s);
            }
        }
    }
    let min = minimum(&samples, step, |p| section(&ca, &cb, axis, p));
    Ok(WidthProfile {
        axis: *axis,
        samples,
        min,
    })
}

/// The width sample at position `p`, if both curves cross its line once.
fn section(ca: &Crossings, cb: &Crossings, axis: &WidthAxis, p: f64) -> Option<WidthSample> {
    let (qa, sig_a) = ca.cross(p)?;
    let (qb, sig_b) = cb.cross(p)?;
    let across = axis.across();
    let width = ((qa[0] - qb[0]) * across[0] + (qa[1] - qb[1]) * across[1]).abs();
    Some(WidthSample {
        position: p,
        width,
        sigma: sig_a.hypot(sig_b),
    })
}

/// The smallest sample, refined between its neighbours.
fn minimum(
    samples: &[WidthSample],
    step: f64,
    at: impl Fn(f64) -> Option<WidthSample>,
) -> Option<WidthSample> {
    let (k, best) = samples
        .iter()
        .enumerate()
        .filter(|(_, s)| s.width.is_finite())
        .min_by(|x, y| x.1.width.total_cmp(&y.1.width))?;
    let neighbour = |j: Option<usize>, sign: f64| {
        j.and_then(|j| samples.get(j))
            .filter(|s| (s.position - (best.position + sign * step)).abs() < 1e-6 * step)
    };
    let (Some(_), Some(_)) = (
        neighbour(k.checked_sub(1), -1.0),
        neighbour(Some(k + 1), 1.0),
    ) else {
        return Some(*best);
    };
    // Golden-section search on [p - step, p + step]: the width of two
    // smooth curves is smooth, and unimodal there in practice. 60 steps
    // shrink the interval by 3e-13.
    let w = |p: f64| at(p).map_or(f64::INFINITY, |s| s.width);
    let p = crate::psf::golden(best.position - step, best.position + step, 60, w);
    match at(p) {
        Some(s) if s.width <= best.width => Some(s),
        _ => Some(*best),
    }
}

/// A curve prepared for crossing section lines: its parameter grid and the
/// positions of the grid points along the axis.
struct Crossings<'a> {
    curve: &'a SplineCurve,
    samples: Option<&'a [Sample]>,
    axis: WidthAxis,
    /// Grid parameters; for a closed curve the first is repeated at the end
    /// (at `L`).
    u: Vec<f64>,
    /// Position along the axis of each grid point.
    q: Vec<f64>,
    /// `(min q, max q)`.
    range: (f64, f64),
    /// Whether `q` is strictly increasing or decreasing (binary search).
    monotone: Option<bool>,
}

impl<'a> Crossings<'a> {
    fn new(curve: &'a SplineCurve, samples: Option<&'a [Sample]>, axis: &WidthAxis) -> Self {
        let l = curve.param_length();
        let h = curve.basis().element_length();
        // At most 1 px and a quarter element apart: no crossing pair hides
        // between two grid points of a smooth curve.
        let spacing = (0.25 * h).min(1.0);
        let n = ((l / spacing).ceil() as usize).clamp(2, 50_000_000);
        let u: Vec<f64> = (0..=n).map(|i| l * i as f64 / n as f64).collect();
        let q: Vec<f64> = u.iter().map(|&u| axis.position(curve.point(u))).collect();
        let range = q.iter().fold((f64::INFINITY, f64::NEG_INFINITY), |r, &v| {
            (r.0.min(v), r.1.max(v))
        });
        let monotone = if curve.is_closed() {
            None
        } else if q.windows(2).all(|w| w[1] > w[0]) {
            Some(true)
        } else if q.windows(2).all(|w| w[1] < w[0]) {
            Some(false)
        } else {
            None
        };
        Crossings {
            curve,
            samples,
            axis: *axis,
            u,
            q,
            range,
            monotone,
        }
    }

    /// The single point where the curve crosses the section at `p`, and its
    /// uncertainty along the section; `None` for no or several crossings.
    fn cross(&self, p: f64) -> Option<([f64; 2], f64)> {
        let q = &self.q;
        let last = q.len() - 1;
        // Interval i spans [q_i, q_{i+1}]; the crossing is counted in
        // (q_i, q_{i+1}] or at q_0 so that a grid point on the line counts once.
        let hit = |i: usize| {
            let (a, b) = (q[i] - p, q[i + 1] - p);
            (a < 0.0 && b >= 0.0) || (a > 0.0 && b <= 0.0) || (i == 0 && a == 0.0)
        };
        let i = match self.monotone {
            Some(up) => {
                let j = if up {
                    q.partition_point(|&v| v < p)
                } else {
                    q.partition_point(|&v| v > p)
                };
                if j > last || (j == 0 && q[0] != p) {
                    return None;
                }
                j.saturating_sub(1)
            }
            None => {
                let mut found = None;
                for i in 0..last {
                    if hit(i) {
                        if found.is_some() {
                            return None;
                        }
                        found = Some(i);
                    }
                }
                found?
            }
        };
        let u = self.refine(self.u[i], self.u[i + 1], p);
        let f = self.curve.frame(u);
        let across = self.axis.across();
        let cos = (f.normal[0] * across[0] + f.normal[1] * across[1]).abs();
        let sigma = self.sigma_at(u) / cos;
        Some((f.point, sigma))
    }

    /// The parameter in `[u0, u1]` where the position equals `p`
    /// (safeguarded Newton on the bracket).
    fn refine(&self, u0: f64, u1: f64, p: f64) -> f64 {
        let d = self.axis.direction;
        let g = |u: f64| {
            let [c, c1, _] = self.curve.derivatives(u);
            (self.axis.position(c) - p, c1[0] * d[0] + c1[1] * d[1])
        };
        let (mut lo, mut hi) = (u0, u1);
        let (glo, _) = g(lo);
        if glo == 0.0 {
            return lo;
        }
        let rising = glo < 0.0;
        let mut u = 0.5 * (lo + hi);
        for _ in 0..100 {
            let (f, df) = g(u);
            if f == 0.0 {
                return u;
            }
            if (f < 0.0) == rising {
                lo = u;
            } else {
                hi = u;
            }
            let newton = u - f / df;
            let next = if newton > lo && newton < hi && newton.is_finite() {
                newton
            } else {
                0.5 * (lo + hi)
            };
            if (next - u).abs() <= 1e-14 * (1.0 + u.abs()) {
                return next;
            }
            u = next;
        }
        u
    }

    /// The samples' `sigma` interpolated linearly in `s` (NaN without
    /// samples).
    fn sigma_at(&self, u: f64) -> f64 {
        let Some(s) = self.samples.filter(|s| !s.is_empty()) else {
            return f64::NAN;
        };
        let j = s.partition_point(|x| x.s < u);
        if j == 0 {
            return s[0].sigma;
        }
        if j >= s.len() {
            return s[s.len() - 1].sigma;
        }
        let (a, b) = (&s[j - 1], &s[j]);
        let t = if b.s > a.s {
            (u - a.s) / (b.s - a.s)
        } else {
            0.0
        };
        a.sigma + t * (b.sigma - a.sigma)
    }
}
