//! A tensile specimen that necks: a bright bar along the x axis whose width
//! narrows at one section, with exactly known edges and width.
//!
//! The full width at abscissa `x` is
//!
//! `w(x) = width - neck / cosh²((x - x_neck) / neck_length)`,
//!
//! smooth, symmetric about `x_neck`, equal to `width` far from it and to
//! `width - neck` (its minimum) at `x_neck`; the bar is symmetric about the
//! row `axis_y`. Its two edges are open curves parametrised by `x` and
//! travelled in `+x`, like [`super::Shape::Sine`]:
//! - [`Edge::Top`]: `y = axis_y - w(x) / 2`,
//! - [`Edge::Bottom`]: `y = axis_y + w(x) / 2`,
//!
//! so the normal `n = (-t_y, t_x)` points to `+y` (down on screen) for both,
//! and signed distances are positive below an edge (larger `y`). The width
//! across the bar along a line `x = const` is `w(x)`: the section width that
//! a width profile along the x axis measures.
//!
//! Closest points are exact to rounding, as for the shapes of
//! [`super::Shape`]: a coarse sampling brackets every local minimum of the
//! distance, each is refined by a safeguarded Newton iteration, and the
//! global minimum wins. [`crate::render::specimen`] paints the bar by exact
//! pixel coverage.

use serde::{Deserialize, Serialize};

use crate::error::{Error, Result};

/// Largest turn of an edge's tangent between two samples of the coarse
/// closest-point search, rad (as in the shapes' search).
const TURN: f64 = 0.2;

/// Upper bound on the number of coarse samples of one search.
const MAX_SAMPLES: usize = 1 << 22;

/// One of the two edges of a [`NeckedBar`].
#[derive(Clone, Copy, Debug, PartialEq, Eq, Serialize, Deserialize)]
#[serde(rename_all = "snake_case")]
pub enum Edge {
    /// `y = axis_y - w(x) / 2` (smaller `y`: the upper edge on screen).
    Top,
    /// `y = axis_y + w(x) / 2`.
    Bottom,
}

impl Edge {
    /// Both edges, top first.
    pub const BOTH: [Edge; 2] = [Edge::Top, Edge::Bottom];

    /// `-1` for the top edge, `+1` for the bottom one: `y = axis_y + side w / 2`.
    pub fn side(self) -> f64 {
        match self {
            Edge::Top => -1.0,
            Edge::Bottom => 1.0,
        }
    }

    /// `"top"` or `"bottom"`.
    pub fn name(self) -> &'static str {
        match self {
            Edge::Top => "top",
            Edge::Bottom => "bottom",
        }
    }
}

/// A bar along the x axis with a neck; see the [module documentation](self).
/// Lengths in pixels.
#[derive(Clone, Copy, Debug, PartialEq, Serialize, Deserialize)]
pub struct NeckedBar {
    /// Row of the bar's axis of symmetry, px.
    pub axis_y: f64,
    /// Full width far from the neck, px (`> 0`).
    pub width: f64,
    /// Reduction of the width at the neck, px (`0 <= neck < width`).
    pub neck: f64,
    /// Length scale of the neck, px (`> 0`): the width is within 1 % of
    /// `width` beyond about `3 neck_length` from `x_neck` (for a neck of a
    /// few pixels).
    pub neck_length: f64,
    /// Abscissa of the narrowest section, px.
    pub x_neck: f64,
}

/// A point of an edge: position and first two derivatives in `x`.
#[derive(Clone, Copy, Debug)]
struct EdgePoint {
    y: f64,
    dy: f64,
    d2y: f64,
}

impl NeckedBar {
    /// Check the parameters (see the fields).
    ///
    /// Errors: [`Error::InvalidParameter`] naming the field.
    pub fn validate(&self) -> Result<()> {
        let finite = |name: &'static str, v: f64| {
            if v.is_finite() {
                Ok(())
            } else {
                Err(Error::invalid(name, format!("{v} is not a finite number")))
            }
        };
        finite("axis_y", self.axis_y)?;
        finite("x_neck", self.x_neck)?;
        finite("width", self.width)?;
        finite("neck", self.neck)?;
        finite("neck_length", self.neck_length)?;
        if self.width <= 0.0 {
            return Err(Error::invalid(
                "width",
                format!("{} px must be > 0", self.width),
            ));
        }
        if !(0.0..self.width).contains(&self.neck) {
            return Err(Error::invalid(
                "neck",
                format!(
                    "{} px: the neck must be >= 0 and narrower than the bar ({} px)",
                    self.neck, self.width
                ),
            ));
        }
        if self.neck_length <= 0.0 {
            return Err(Error::invalid(
                "neck_length",
                format!("{} px must be > 0", self.neck_length),
            ));
        }
        Ok(())
    }

    /// The bar's full width at abscissa `x`, px.
    pub fn width_at(&self, x: f64) -> f64 {
        self.width - self.neck * sech2((x - self.x_neck) / self.neck_length)
    }

    /// The narrowest width, `width - neck`, px (at `x = x_neck`).
    pub fn min_width(&self) -> f64 {
        self.width - self.neck
    }

    /// The ordinate of `edge` at abscissa `x`, px.
    pub fn edge_y(&self, edge: Edge, x: f64) -> f64 {
        self.eval(edge, x).y
    }

    /// Smallest radius of curvature of the edges, px (`f64::INFINITY`
    /// without a neck): a bound from `|y''| <= neck / neck_length²`.
    pub fn min_curvature_radius_bound(&self) -> f64 {
        self.neck_length * self.neck_length / self.neck
    }

    fn eval(&self, edge: Edge, x: f64) -> EdgePoint {
        let l = self.neck_length;
        let u = (x - self.x_neck) / l;
        let s = sech2(u);
        let t = u.tanh();
        let k = 0.5 * edge.side();
        // w = width - neck s, s' = -2 s t / l, s'' = (4 s - 6 s²) / l².
        EdgePoint {
            y: self.axis_y + k * (self.width - self.neck * s),
            dy: k * self.neck * 2.0 * s * t / l,
            d2y: -k * self.neck * (4.0 * s - 6.0 * s * s) / (l * l),
        }
    }

    /// Signed distance, px, from `(x, y)` to `edge` (the whole infinite
    /// edge): positive below it (larger `y`, the `+n` side), zero on it.
    /// Exact to rounding. NaN for a non-finite point or an invalid bar.
    pub fn signed_distance(&self, edge: Edge, x: f64, y: f64) -> f64 {
        let (p, n) = self.closest_point(edge, x, y);
        let d = [x - p[0], y - p[1]];
        let dist = d[0].hypot(d[1]);
        if d[0] * n[0] + d[1] * n[1] < 0.0 {
            -dist
        } else {
            dist
        }
    }

    /// The point of `edge` closest to `(x, y)` and the unit normal
    /// `n = (-t_y, t_x)` there (pointing to `+y`), px. NaN for a
    /// non-finite point or an invalid bar.
    pub fn closest_point(&self, edge: Edge, x: f64, y: f64) -> ([f64; 2], [f64; 2]) {
        if self.validate().is_err() || !(x.is_finite() && y.is_finite()) {
            return ([f64::NAN; 2], [f64::NAN; 2]);
        }
        let s = self.closest_param(edge, [x, y]);
        let e = self.eval(edge, s);
        let v = (1.0 + e.dy * e.dy).sqrt();
        ([s, e.y], [-e.dy / v, 1.0 / v])
    }

    /// Points of `edge` from `x0` to `x1` (both included), at most
    /// `max_step` px apart in `x`.
    ///
    /// Errors: [`Error::InvalidParameter`] for an invalid bar, a bad step or
    /// range, or more than 50 million points.
    pub fn edge_points(
        &self,
        edge: Edge,
        x0: f64,
        x1: f64,
        max_step: f64,
    ) -> Result<Vec<[f64; 2]>> {
        self.validate()?;
        if !(max_step.is_finite() && max_step > 0.0) {
            return Err(Error::invalid(
                "max_step",
                format!("{max_step} must be a positive number of pixels"),
            ));
        }
        if !(x0.is_finite() && x1.is_finite() && x0 < x1) {
            return Err(Error::invalid("x range", format!("{x0} to {x1}")));
        }
        let n = ((x1 - x0) / max_step).ceil();
        if n > 5e7 {
            return Err(Error::invalid(
                "max_step",
                format!("{max_step} px would give {n} points"),
            ));
        }
        let n = (n as usize).max(1);
        Ok((0..=n)
            .map(|i| {
                let x = if i == n {
                    x1
                } else {
                    x0 + (x1 - x0) * (i as f64 / n as f64)
                };
                [x, self.edge_y(edge, x)]
            })
            .collect())
    }

    /// Parameter step over which an edge's tangent turns by at most
    /// [`TURN`]: `|y''| <= neck / neck_length²`.
    fn search_step(&self) -> f64 {
        let l = self.neck_length;
        if self.neck > 0.0 {
            (l / 16.0).min(TURN * l * l / self.neck)
        } else {
            l / 16.0
        }
    }

    /// Abscissa of the point of `edge` closest to `q` (global minimum).
    fn closest_param(&self, edge: Edge, q: [f64; 2]) -> f64 {
        let s_r = q[0];
        let d = (q[1] - self.eval(edge, s_r).y).abs();
        if d == 0.0 {
            return s_r;
        }
        // The closest point is within the disc of radius d about q.
        let reach = d * (1.0 + 1e-9) + 1e-12;
        let n = (2.0 * reach / self.search_step()).ceil();
        let n = if n.is_finite() {
            (n as usize).clamp(4, MAX_SAMPLES)
        } else {
            MAX_SAMPLES
        };
        let (lo, hi) = (s_r - reach, s_r + reach);
        let dist2 = |s: f64| {
            let e = self.eval(edge, s);
            (s - q[0]).powi(2) + (e.y - q[1]).powi(2)
        };
        let mut s_best = s_r;
        let mut g_best = dist2(s_r);
        let mut prev: Option<(f64, f64)> = None;
        for i in 0..=n {
            let s = if i == n {
                hi
            } else {
                lo + (hi - lo) * (i as f64 / n as f64)
            };
            let e = self.eval(edge, s);
            let g = dist2(s);
            if g < g_best {
                (g_best, s_best) = (g, s);
            }
            // g'(s) = (p - q) . p' with p' = (1, y').
            let f = (s - q[0]) + (e.y - q[1]) * e.dy;
            if let Some((s_prev, f_prev)) = prev {
                if f_prev < 0.0 && f >= 0.0 {
                    let s_min = self.refine(edge, q, s_prev, s);
                    let g_min = dist2(s_min);
                    if g_min < g_best {
                        (g_best, s_best) = (g_min, s_min);
                    }
                }
            }
            prev = Some((s, f));
        }
        s_best
    }

    /// Root of `g'(s) = (p - q) . p'` in `[lo, hi]` where `g'(lo) < 0 <=
    /// g'(hi)`: Newton's method, bisection when a step leaves the bracket.
    fn refine(&self, edge: Edge, q: [f64; 2], mut lo: f64, mut hi: f64) -> f64 {
        let mut s = 0.5 * (lo + hi);
        for _ in 0..200 {
            let e = self.eval(edge, s);
            let (dx, dy) = (s - q[0], e.y - q[1]);
            let f = dx + dy * e.dy;
            if f == 0.0 {
                return s;
            }
            if f < 0.0 {
                lo = s;
            } else {
                hi = s;
            }
            let fp = 1.0 + e.dy * e.dy + dy * e.d2y;
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
}

/// `1 / cosh²(u)`, 0 where `cosh` overflows.
fn sech2(u: f64) -> f64 {
    let c = u.cosh();
    1.0 / (c * c)
}

/// A sequence of frames of a specimen necking progressively: frame `k` of
/// `frames` has the neck `neck_first + (neck_last - neck_first) (k /
/// (frames - 1))²` (necking accelerates), the other parameters of `bar`
/// unchanged. One frame gets `neck_first`.
///
/// Errors: [`Error::InvalidParameter`] for no frame or an invalid bar
/// (either neck included).
pub fn necking_sequence(
    bar: &NeckedBar,
    neck_first: f64,
    neck_last: f64,
    frames: usize,
) -> Result<Vec<NeckedBar>> {
    if frames == 0 {
        return Err(Error::invalid("frames", "0 (need at least one frame)"));
    }
    let out: Vec<NeckedBar> = (0..frames)
        .map(|k| {
            let t = if frames == 1 {
                0.0
            } else {
                k as f64 / (frames - 1) as f64
            };
            NeckedBar {
                neck: neck_first + (neck_last - neck_first) * t * t,
                ..*bar
            }
        })
        .collect();
    for b in &out {
        b.validate()?;
    }
    Ok(out)
}

#[cfg(test)]
mod tests {
    use super::*;

    fn bar() -> NeckedBar {
        NeckedBar {
            axis_y: 100.3,
            width: 90.0,
            neck: 20.0,
            neck_length: 30.0,
            x_neck: 201.7,
        }
    }

    #[test]
    fn width_and_edges() {
        let b = bar();
        assert!((b.width_at(b.x_neck) - 70.0).abs() < 1e-12);
        assert!((b.width_at(1e4) - 90.0).abs() < 1e-12);
        for x in [0.0, 150.0, 201.7, 260.0] {
            let w = b.edge_y(Edge::Bottom, x) - b.edge_y(Edge::Top, x);
            assert!((w - b.width_at(x)).abs() < 1e-12);
        }
    }

    #[test]
    fn derivatives_match_differences() {
        let b = bar();
        let h = 1e-4;
        for edge in Edge::BOTH {
            for x in [150.0, 190.0, 201.7, 215.0] {
                let e = b.eval(edge, x);
                let d1 = (b.edge_y(edge, x + h) - b.edge_y(edge, x - h)) / (2.0 * h);
                let d2 = (b.edge_y(edge, x + h) - 2.0 * e.y + b.edge_y(edge, x - h)) / (h * h);
                assert!((e.dy - d1).abs() < 1e-8, "{edge:?} {x}");
                assert!((e.d2y - d2).abs() < 1e-5, "{edge:?} {x}");
            }
        }
    }

    #[test]
    fn signed_distance_of_offset_points() {
        // A point moved by d along the normal is at signed distance d (d
        // well below the radius of curvature).
        let b = bar();
        for edge in Edge::BOTH {
            for x in [120.0, 185.0, 201.7, 222.0] {
                let (p, n) = b.closest_point(edge, x, b.edge_y(edge, x));
                assert!((p[0] - x).abs() < 1e-9);
                for d in [-3.0, -0.25, 0.0, 0.4, 5.0] {
                    let q = [p[0] + d * n[0], p[1] + d * n[1]];
                    let got = b.signed_distance(edge, q[0], q[1]);
                    assert!((got - d).abs() < 1e-10, "{edge:?} x {x} d {d}: {got}");
                }
            }
        }
        // Below the bottom edge is positive, inside the bar too for the top.
        assert!(b.signed_distance(Edge::Bottom, 50.0, 160.0) > 0.0);
        assert!(b.signed_distance(Edge::Top, 50.0, 100.0) > 0.0);
        assert!(b.signed_distance(Edge::Top, 50.0, 20.0) < 0.0);
    }

    proptest::proptest! {
        #![proptest_config(proptest::test_runner::Config::with_cases(64))]
        /// The distance is the minimum over a dense sampling of the edge
        /// (which can only be larger, by at most the sampling's sagitta and
        /// half-step error), and never smaller.
        #[test]
        fn distance_is_the_minimum_over_the_edge(
            neck in 0.0f64..40.0,
            length in 5.0f64..60.0,
            qx in 100.0f64..300.0,
            off in -30.0f64..30.0,
            bottom in proptest::bool::ANY,
        ) {
            let b = NeckedBar { neck, neck_length: length, ..bar() };
            let edge = if bottom { Edge::Bottom } else { Edge::Top };
            let qy = b.edge_y(edge, qx) + off;
            let d = b.signed_distance(edge, qx, qy).abs();
            let reach = (qy - b.edge_y(edge, qx)).abs() + 1.0;
            let dist = |x: f64| (x - qx).hypot(b.edge_y(edge, x) - qy);
            // Coarse then fine: a foot between two coarse samples is up to
            // half a step from both, which alone overestimates a distance
            // of a few thousandths by more than the tolerance below.
            let scan = |from: f64, step: f64, n: usize| {
                (0..=n)
                    .map(|i| from + i as f64 * step)
                    .min_by(|a, c| dist(*a).total_cmp(&dist(*c)))
                    .unwrap_or(from)
            };
            let step = 1e-3;
            let coarse = scan(qx - reach, step, (2.0 * reach / step) as usize);
            let brute = dist(scan(coarse - step, 1e-6, 2000));
            proptest::prop_assert!(d <= brute + 1e-9, "{d} > {brute}");
            proptest::prop_assert!(brute - d < 1e-5, "{d} << {brute}");
        }
    }

    #[test]
    fn sequence_and_validation() {
        let seq = necking_sequence(&bar(), 4.0, 30.0, 8).unwrap();
        assert_eq!(seq.len(), 8);
        assert_eq!(seq[0].neck, 4.0);
        assert!((seq[7].neck - 30.0).abs() < 1e-12);
        assert!(seq.windows(2).all(|w| w[1].neck > w[0].neck));
        assert!(necking_sequence(&bar(), 4.0, 95.0, 3).is_err());
        assert!(necking_sequence(&bar(), 4.0, 5.0, 0).is_err());
        let bad = NeckedBar {
            neck_length: 0.0,
            ..bar()
        };
        assert!(bad.validate().is_err());
        assert!(bad.signed_distance(Edge::Top, 1.0, 2.0).is_nan());
    }
}
