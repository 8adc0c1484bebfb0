//! The blurred image of a corner, where a one-edge profile is wrong.
//!
//! A band pixel is modelled by the edge of the side its closest point lies
//! on: the half-plane `H1` behind that side's line is bright (`gamma = 1`,
//! the curve's `-n` side). Near a vertex the image is that of two sides:
//! `H1 ∩ H2` when the curve turns towards its bright side (a convex
//! corner of a bright object), `H1 ∪ H2` when it turns away. The one-edge
//! profile then counts too much light from `H1 \ H2` (convex) or too
//! little from `H2 \ H1` (concave): a wedge with its apex at the vertex,
//! between this side's line continued past the vertex and the other side.
//! Through the blur that wedge reaches pixels several blur widths away,
//! and fitting them with one edge pulls the sides' ends towards each other
//! (a pentagon's vertices came out 1.1 to 1.5 px inside at a blur of 4 px).
//!
//! The wedge's share of a pixel is the probability that a point spread
//! around the pixel centre by the blur falls in it: with `d1`, `d2` the
//! centre's signed distances to the two lines (positive on their `n`
//! sides), the bivariate normal distribution `Phi2(h, k; rho)` of the two
//! normal coordinates of the spread ([`bivariate_normal_cdf`]). The pixel's
//! own square is taken as a Gaussian of variance 1/12 added to the blur's
//! (the wedge's term is a correction; within a pixel of the wedge, where
//! the square's shape matters, the band still leaves pixels out:
//! `crate::curve::corners`).
//!
//! Edge cases: the lines are the sides' tangents at the vertex, so a side
//! that bends within a few blur widths of it is followed to first order;
//! sides that meet at a very shallow or a very sharp angle (`|rho|` near 1)
//! are handled by the integral's other form; a pixel farther than
//! [`REACH`] spreads from the wedge gets no term (under 1e-12).

use super::anisotropy::Anisotropy;
use super::pixel_edge::{normal_cdf_pdf, spread_variance};

/// Beyond this many spreads from the wedge, a pixel's term is taken as 0.
pub const REACH: f64 = 7.0;
/// `|rho|` above which [`bivariate_normal_cdf`] integrates along `h`
/// (the angle integral's integrand steepens as `|rho|` nears 1).
const STEEP_RHO: f64 = 0.925;

/// 20-point Gauss–Legendre nodes on `[-1, 1]` (the positive half).
#[allow(clippy::excessive_precision)]
const GL_X: [f64; 10] = [
    0.0765265211334973337546404,
    0.2277858511416450780804962,
    0.3737060887154195606725482,
    0.5108670019508270980043641,
    0.6360536807265150254528367,
    0.7463319064601507926143051,
    0.8391169718222188233945291,
    0.9122344282513259058677524,
    0.9639719272779137912676661,
    0.9931285991850949247861224,
];
/// Their weights.
#[allow(clippy::excessive_precision)]
const GL_W: [f64; 10] = [
    0.1527533871307258506980843,
    0.1491729864726037467878287,
    0.1420961093183820513292983,
    0.1316886384491766268984945,
    0.1181945319615184173123774,
    0.1019301198172404350367501,
    0.0832767415767047487247581,
    0.0626720483341090635695065,
    0.0406014298003869413310400,
    0.0176140071391521183118620,
];

/// `int_a^b f` by 20-point Gauss–Legendre.
fn gauss_legendre(a: f64, b: f64, f: impl Fn(f64) -> f64) -> f64 {
    let (mid, half) = (0.5 * (a + b), 0.5 * (b - a));
    let mut sum = 0.0;
    for (x, w) in GL_X.iter().zip(GL_W) {
        sum += w * (f(mid - half * x) + f(mid + half * x));
    }
    sum * half
}

/// Standard normal distribution function.
fn phi_cdf(x: f64) -> f64 {
    normal_cdf_pdf(x).0
}

/// `P(Z1 < h, Z2 < k)` for standard normal `Z1`, `Z2` of correlation
/// `rho` (clamped to `[-1, 1]`; infinite limits allowed).
///
/// For `|rho| <= 0.925`, the integral over the angle `asin rho` (Drezner
/// and Wesolowsky's form, as in A. Genz's `BVN`):
/// `Phi(h) Phi(k) + 1/(2 pi) int_0^asin(rho) exp(-(h^2 + k^2 - 2 h k sin t)
/// / (2 cos^2 t)) dt`, smooth there. Beyond, `int_-inf^h phi(z) Phi((k -
/// rho z) / sqrt(1 - rho^2)) dz`, whose step (of width `sqrt(1 - rho^2) /
/// |rho|`, about `k / rho`) gets a panel of its own, the flat parts on
/// either side being `Phi` differences. Accurate to about 1e-12.
pub fn bivariate_normal_cdf(h: f64, k: f64, rho: f64) -> f64 {
    let rho = rho.clamp(-1.0, 1.0);
    if h == f64::NEG_INFINITY || k == f64::NEG_INFINITY {
        return 0.0;
    }
    if h == f64::INFINITY {
        return phi_cdf(k);
    }
    if k == f64::INFINITY {
        return phi_cdf(h);
    }
    if rho.abs() <= STEEP_RHO {
        let end = rho.asin();
        let (hk, hh) = (h * k, 0.5 * (h * h + k * k));
        let integral = gauss_legendre(0.0, end, |t| {
            let (s, c) = t.sin_cos();
            ((hk * s - hh) / (c * c)).exp()
        });
        return (phi_cdf(h) * phi_cdf(k) + integral / (2.0 * std::f64::consts::PI)).clamp(0.0, 1.0);
    }
    let sd = (1.0 - rho * rho).max(0.0).sqrt();
    // The limits of `Z1` below which the integrand's `Phi` is ~1 or ~0.
    const TAIL: f64 = 9.0;
    let top = h.min(TAIL);
    let lo = -TAIL;
    if top <= lo {
        return 0.0;
    }
    let centre = k / rho;
    let width = TAIL * sd / rho.abs();
    // Where `(k - rho z) / sd` is above `TAIL` (the step's `Phi` is 1).
    let (a, b) = ((centre - width).max(lo), (centre + width).min(top));
    let step = |z: f64| {
        normal_cdf_pdf(z).1
            * phi_cdf(if sd > 0.0 {
                (k - rho * z) / sd
            } else if k - rho * z > 0.0 {
                f64::INFINITY
            } else {
                f64::NEG_INFINITY
            })
    };
    // `Phi` of the step is 1 below `a` when `rho > 0`, above `b` when
    // `rho < 0`, and 0 on the other side.
    let mut sum = 0.0;
    if a < b {
        // Two panels: the step is steep, about its centre.
        let m = 0.5 * (a + b);
        sum += gauss_legendre(a, m, step) + gauss_legendre(m, b, step);
    }
    let flat = |from: f64, to: f64| {
        if to > from {
            phi_cdf(to) - phi_cdf(from)
        } else {
            0.0
        }
    };
    if rho > 0.0 {
        sum += flat(lo, a.min(top));
    } else {
        sum += flat(b.max(lo), top);
    }
    sum.clamp(0.0, 1.0)
}

/// What a corner's wedge does to one band pixel, whatever the blur: the
/// arguments of [`bivariate_normal_cdf`] times the spread, and the sign of
/// the term.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct CornerWedge {
    /// `h` times the spread, pixels.
    pub h: f64,
    /// `k` times the spread, pixels.
    pub k: f64,
    /// The correlation of the two normal coordinates.
    pub rho: f64,
    /// The directions `u`, `v` of the two coordinates: the term is
    /// `P(Z.u < h, Z.v < k)` for the spread `Z` (`rho = u.v` under an
    /// isotropic one).
    pub directions: [[f64; 2]; 2],
    /// -1: the wedge is light the one-edge profile counts and the image
    /// does not have (a convex corner); +1: the reverse.
    pub sign: f64,
}

impl CornerWedge {
    /// The wedge of the corner at `vertex` between the side that ends there
    /// (unit tangent `into`) and the one that starts there (`out`), for a
    /// pixel at `x` modelled by the first side (`on_into`) or the second,
    /// unless it is farther than [`REACH`] spreads of `spread` pixels from
    /// the wedge's two lines' nearest point (then `None`).
    pub fn new(
        x: [f64; 2],
        vertex: [f64; 2],
        into: [f64; 2],
        out: [f64; 2],
        on_into: bool,
        spread: f64,
    ) -> Option<CornerWedge> {
        let normal = |t: [f64; 2]| [-t[1], t[0]];
        let (n1, n2) = (normal(into), normal(out));
        let p = [x[0] - vertex[0], x[1] - vertex[1]];
        let d1 = p[0] * n1[0] + p[1] * n1[1];
        let d2 = p[0] * n2[0] + p[1] * n2[1];
        // The curve turns towards its bright (`-n`) side: a convex corner.
        let convex = into[0] * out[1] - into[1] * out[0] < 0.0;
        // This side's line and the other's, as the pixel sees them.
        let (d_own, d_other) = if on_into { (d1, d2) } else { (d2, d1) };
        // Convex: P(own bright, other dark) = P(Z.n_own < -d_own / s,
        // Z.(-n_other) < d_other / s); concave: P(own dark, other bright).
        let (h, k, sign) = if convex {
            (-d_own, d_other, -1.0)
        } else {
            (d_own, -d_other, 1.0)
        };
        let (n_own, n_other) = if on_into { (n1, n2) } else { (n2, n1) };
        let directions = if convex {
            [n_own, [-n_other[0], -n_other[1]]]
        } else {
            [[-n_own[0], -n_own[1]], n_other]
        };
        // The term is at most the smaller one-dimensional tail.
        if h.min(k) < -REACH * spread {
            return None;
        }
        Some(CornerWedge {
            h,
            k,
            rho: -(n1[0] * n2[0] + n1[1] * n2[1]),
            directions,
            sign,
        })
    }

    /// The term added to the one-edge `gamma` under a spread of `spread`
    /// pixels (the blur's and the pixel's: `sqrt(blur^2 + 1/12)`).
    pub fn term(&self, spread: f64) -> f64 {
        let s = spread.max(1e-6);
        self.sign * bivariate_normal_cdf(self.h / s, self.k / s, self.rho)
    }

    /// The term under the optical blur `blur` (pixels, its mean over the
    /// directions) with `anisotropy`, and the pixel's own 1/12 px²: each
    /// coordinate scaled by its own deviation, their correlation that of
    /// the blur's covariance (a blur longer along the corner's bisector
    /// reaches further into the wedge).
    pub fn term_for(&self, blur: f64, anisotropy: Anisotropy) -> f64 {
        let base = spread_variance(blur);
        if anisotropy.is_none() {
            return self.term(base.sqrt());
        }
        let [u, v] = self.directions;
        let var = |w: [f64; 2]| (base + anisotropy.along(w)).max(1e-12);
        let (su, sv) = (var(u).sqrt(), var(v).sqrt());
        let cov = base * (u[0] * v[0] + u[1] * v[1]) + anisotropy.cross(u, v);
        let rho = (cov / (su * sv)).clamp(-1.0, 1.0);
        self.sign * bivariate_normal_cdf(self.h / su, self.k / sv, rho)
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// `P(Z1 < h, Z2 < k)` by the trapezoidal rule over `Z1` on a fine
    /// grid: the oracle, independent of both branches.
    fn oracle(h: f64, k: f64, rho: f64) -> f64 {
        let sd = (1.0 - rho * rho).sqrt();
        let (lo, hi) = (-12.0, h.min(12.0));
        if hi <= lo {
            return 0.0;
        }
        let n = 400_000;
        let dz = (hi - lo) / n as f64;
        let f = |z: f64| {
            let pdf = (-0.5 * z * z).exp() / (2.0 * std::f64::consts::PI).sqrt();
            let arg = if sd > 0.0 {
                (k - rho * z) / sd
            } else if k - rho * z > 0.0 {
                50.0
            } else {
                -50.0
            };
            pdf * 0.5 * libm::erfc(-arg / std::f64::consts::SQRT_2)
        };
        let mut sum = 0.5 * (f(lo) + f(hi));
        for i in 1..n {
            sum += f(lo + i as f64 * dz);
        }
        sum * dz
    }

    #[test]
    fn the_bivariate_distribution_matches_its_integral() {
        for &rho in &[
            -0.999, -0.97, -0.93, -0.9, -0.6, -0.3, 0.0, 0.31, 0.7, 0.92, 0.93, 0.99, 0.9999,
        ] {
            for &h in &[-3.0, -1.2, -0.3, 0.0, 0.4, 1.5, 3.5] {
                for &k in &[-2.5, -0.7, 0.0, 0.2, 1.1, 4.0] {
                    let got = bivariate_normal_cdf(h, k, rho);
                    let want = oracle(h, k, rho);
                    assert!(
                        (got - want).abs() < 2e-9,
                        "rho {rho} h {h} k {k}: {got} vs {want}"
                    );
                }
            }
        }
    }

    #[test]
    fn the_bivariate_distribution_has_its_limits() {
        // Independent: a product; rho = +-1: the smaller tail or the
        // overlap of two tails; an infinite limit: the other margin.
        let cdf = phi_cdf;
        assert!((bivariate_normal_cdf(0.3, -0.8, 0.0) - cdf(0.3) * cdf(-0.8)).abs() < 1e-14);
        assert!((bivariate_normal_cdf(0.3, -0.8, 1.0) - cdf(-0.8)).abs() < 1e-9);
        assert!((bivariate_normal_cdf(0.3, 0.8, -1.0) - (cdf(0.3) + cdf(0.8) - 1.0)).abs() < 1e-9);
        assert!(bivariate_normal_cdf(-0.3, -0.8, -1.0).abs() < 1e-12);
        assert_eq!(bivariate_normal_cdf(f64::INFINITY, 0.4, 0.5), cdf(0.4));
        assert_eq!(bivariate_normal_cdf(0.4, f64::NEG_INFINITY, 0.5), 0.0);
    }

    /// What a brute-force blurred picture of the corner at `vertex`
    /// (sides along `into` then `out`) says the one-edge profile misses at
    /// `x`, under a Gaussian of covariance `cov`: quadrature on a grid
    /// whose cell edges pass through the vertex (the midpoint rule's error
    /// along a line is then that of an oblique line, which averages out).
    fn brute_term(
        vertex: [f64; 2],
        (into, out): ([f64; 2], [f64; 2]),
        x: [f64; 2],
        cov: [[f64; 2]; 2],
    ) -> f64 {
        let n = |t: [f64; 2]| [-t[1], t[0]];
        let (n1, n2) = (n(into), n(out));
        let convex = into[0] * out[1] - into[1] * out[0] < 0.0;
        let side =
            |q: [f64; 2], m: [f64; 2]| (q[0] - vertex[0]) * m[0] + (q[1] - vertex[1]) * m[1] < 0.0;
        // Bright where both (convex) or either (concave) sides say so.
        let bright = |q: [f64; 2]| {
            let (a, b) = (side(q, n1), side(q, n2));
            if convex {
                a && b
            } else {
                a || b
            }
        };
        let det = cov[0][0] * cov[1][1] - cov[0][1] * cov[1][0];
        let inv = [
            [cov[1][1] / det, -cov[0][1] / det],
            [-cov[1][0] / det, cov[0][0] / det],
        ];
        let largest = cov[0][0].max(cov[1][1]).sqrt() * 1.5;
        let (mut corner, mut one_edge, mut total) = (0.0, 0.0, 0.0);
        let m = 1600;
        let far = (x[0] - vertex[0]).abs().max((x[1] - vertex[1]).abs());
        let h = 2.0 * (8.0 * largest + far) / m as f64;
        for i in 0..m {
            for j in 0..m {
                let q = [
                    vertex[0] + (i as f64 + 0.5 - 0.5 * m as f64) * h,
                    vertex[1] + (j as f64 + 0.5 - 0.5 * m as f64) * h,
                ];
                let d = [q[0] - x[0], q[1] - x[1]];
                let quad = d[0] * (inv[0][0] * d[0] + inv[0][1] * d[1])
                    + d[1] * (inv[1][0] * d[0] + inv[1][1] * d[1]);
                let w = (-0.5 * quad).exp();
                total += w;
                if bright(q) {
                    corner += w;
                }
                if side(q, n1) {
                    one_edge += w;
                }
            }
        }
        (corner - one_edge) / total
    }

    /// A right-angled turn each way, and a pentagon's 72 degrees.
    fn turns() -> [([f64; 2], [f64; 2]); 3] {
        let a = 72f64.to_radians();
        [
            ([1.0, 0.0], [0.0, -1.0]),
            ([1.0, 0.0], [0.0, 1.0]),
            ([1.0, 0.0], [a.cos(), -a.sin()]),
        ]
    }

    /// The wedge's term is what a brute-force blurred picture of the
    /// corner says the one-edge profile misses, for both turns.
    #[test]
    fn the_wedge_term_is_the_corner_minus_one_edge() {
        let s = 2.0;
        let vertex = [0.3, -0.2];
        for (into, out) in turns() {
            for x in [[-3.0, 1.5], [-1.0, -2.0], [1.0, 0.7], [-6.0, 2.5]] {
                let want = brute_term(vertex, (into, out), x, [[s * s, 0.0], [0.0, s * s]]);
                let got =
                    CornerWedge::new(x, vertex, into, out, true, s).map_or(0.0, |w| w.term(s));
                assert!(
                    (got - want).abs() < 2e-4,
                    "{into:?} {out:?} at {x:?}: {got} vs {want}"
                );
            }
        }
    }

    /// Under an anisotropic blur (an astigmatism along a slant, 2.6 px one
    /// way and 1.2 px the other), the term scales each side's coordinate
    /// by its own deviation and correlates them through the covariance:
    /// the brute-force picture again, for both turns.
    #[test]
    fn the_anisotropic_wedge_term_is_the_corner_minus_one_edge() {
        let (blur, a) = (2.0f64, Anisotropy { p: 1.5, q: -2.0 });
        let v = spread_variance(blur);
        let cov = [[v + a.p, a.q], [a.q, v - a.p]];
        let vertex = [0.3, -0.2];
        for (into, out) in turns() {
            for x in [[-3.0, 1.5], [-1.0, -2.0], [1.0, 0.7], [-6.0, 2.5]] {
                let want = brute_term(vertex, (into, out), x, cov);
                let got = CornerWedge::new(x, vertex, into, out, true, 3.0)
                    .map_or(0.0, |w| w.term_for(blur, a));
                assert!(
                    (got - want).abs() < 2e-4,
                    "{into:?} {out:?} at {x:?}: {got} vs {want}"
                );
            }
        }
    }
}
