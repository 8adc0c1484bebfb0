//! Settle: the reference a settle re-references on, taken to the fixed
//! point of the settles instead of the run's result.
//!
//! A pushed profile takes the curvature of the reference, averaged over
//! the blur (`band/blurred_curvature.rs`), so a reference off the edge by
//! `e(s)` puts the run's result off by `G e`, where `G` multiplies an
//! oscillation of wavenumber `k` along the curve by the loop gain `g(k) =
//! (v k^2 / 2) exp(-v k^2 / 4)` (`v` the spread variance; at most `2 / e`).
//! A settle that re-references on the result multiplies the error by `g`:
//! `g` peaks at the wavelength `pi sqrt(v)` (6 px under a 2 px blur, 13
//! px under 4 px) and is still about 0.5 at twice that, so one settle
//! removes only a third to a half of the error there, and the settles
//! stop (at their tolerance, or when they no longer contract by half)
//! with part of it left: an oscillation of that wavelength.
//!
//! The run's displacement is `U = (G - I) e`, so the fixed point is the
//! reference moved by `(I - G)^-1 U`: the extrapolated displacement
//! [`extrapolated`] returns, which one settle reaches as far as `G` is
//! linear (docs/benchmarks.md, "Settles that land on their fixed point",
//! gives the measurements).
//!
//! `U` is a B-spline of uniform elements `h` long, so filtering its control
//! values filters `U`: their discrete Fourier transform is multiplied by
//! `1 / (1 - g(w / h))` at the frequency `w` (radians per control value).
//!
//! Edge cases: a closed basis is periodic; an open one is reflected evenly
//! at its ends, and its `degree + 1` end values on each side keep `U`
//! (there the spline's end functions are not uniform, and an end value
//! that the image barely holds would be amplified from settle to settle);
//! a basis with breaks keeps `U` (its elements are not uniform across a
//! corner), and so does a reference whose curvature leaves the reach of
//! the profile's curved edge (a corner no break declares: the gain above
//! does not describe it) or reaches that of the blurred osculating circle
//! in full (`virtual_image/osculating.rs`: its terms change the profile's
//! answer to the curvature, which the gain leaves out); without blur there
//! is no feedback to undo.

use super::blur::{gain_of, within_curved_edge_reach};
use crate::curve::SplineCurve;
use crate::spline::Basis;
use crate::virtual_image::pixel_edge::spread_variance;
use std::f64::consts::TAU;

/// The displacement that moves `reference` to the settles' fixed point
/// for the run's displacement `lambda` (control values on `basis`, pixels)
/// under an optical blur of `blur` pixels, on a band whose profile takes
/// its blurred osculating circle in full somewhere or not (`osculates`,
/// [`crate::band::Band::osculates`]); `None` where `U` itself serves (see
/// the [module docs](self) for when).
pub(super) fn extrapolated(
    lambda: &[f64],
    basis: &Basis,
    reference: &SplineCurve,
    (blur, osculates): (f64, bool),
) -> Option<Vec<f64>> {
    let applies = blur.is_finite()
        && blur > 0.0
        && basis.breaks().is_empty()
        && lambda.len() == basis.n_functions()
        && within_curved_edge_reach(reference, blur)
        && !osculates;
    if !applies {
        return None;
    }
    let kept_ends = basis.degree() + 1;
    if !basis.is_closed() && lambda.len() <= 2 * kept_ends {
        return None;
    }
    let sequence: Vec<f64> = if basis.is_closed() {
        lambda.to_vec()
    } else {
        lambda.iter().chain(lambda.iter().rev()).copied().collect()
    };
    let v = spread_variance(blur);
    let h = basis.element_length();
    let mut out = filtered(&sequence, |w| {
        let k = w / h;
        1.0 / (1.0 - gain_of(0.5 * v * k * k))
    });
    if !basis.is_closed() {
        let n = lambda.len();
        out.truncate(n);
        out[..kept_ends].copy_from_slice(&lambda[..kept_ends]);
        out[n - kept_ends..].copy_from_slice(&lambda[n - kept_ends..]);
    }
    Some(out)
}

/// The periodic sequence `x` with its discrete Fourier transform
/// multiplied by `m(w)`, `w = 2 pi p / n` in `[0, pi]` (an even real
/// multiplier): a direct transform, `O(n^2)` on a table of the `n` roots
/// of unity, made once per settle.
fn filtered(x: &[f64], m: impl Fn(f64) -> f64) -> Vec<f64> {
    let n = x.len();
    let roots: Vec<(f64, f64)> = (0..n)
        .map(|j| {
            let a = TAU * j as f64 / n as f64;
            (a.cos(), a.sin())
        })
        .collect();
    let mut out = vec![0.0; n];
    for p in 0..=n / 2 {
        let (mut re, mut im) = (0.0, 0.0);
        for (j, xj) in x.iter().enumerate() {
            let (c, s) = roots[(p * j) % n];
            re += xj * c;
            im -= xj * s;
        }
        // A real sequence's transform at `n - p` is the conjugate of that
        // at `p`: both together add `2 Re(X_p e^(i w j))`.
        let twice = if p == 0 || 2 * p == n { 1.0 } else { 2.0 };
        let scale = twice * m(TAU * p as f64 / n as f64) / n as f64;
        for (j, o) in out.iter_mut().enumerate() {
            let (c, s) = roots[(p * j) % n];
            *o += scale * (re * c - im * s);
        }
    }
    out
}

#[cfg(test)]
mod tests {
    use super::*;

    fn direct(x: &[f64], m: impl Fn(f64) -> f64) -> Vec<f64> {
        // The same filter by a full complex transform, every frequency.
        let n = x.len();
        (0..n)
            .map(|j| {
                (0..n)
                    .map(|p| {
                        let q = if 2 * p <= n {
                            p as f64
                        } else {
                            p as f64 - n as f64
                        };
                        let w = TAU * q / n as f64;
                        let (mut re, mut im) = (0.0, 0.0);
                        for (i, xi) in x.iter().enumerate() {
                            re += xi * (w * i as f64).cos();
                            im -= xi * (w * i as f64).sin();
                        }
                        m(w.abs()) * (re * (w * j as f64).cos() - im * (w * j as f64).sin())
                    })
                    .sum::<f64>()
                    / n as f64
            })
            .collect()
    }

    #[test]
    fn the_filter_matches_a_full_transform() {
        for n in [7, 8, 33] {
            let x: Vec<f64> = (0..n).map(|i| ((i * 37 % 11) as f64 - 5.0) * 0.1).collect();
            let m = |w: f64| 1.0 + w * w;
            let (a, b) = (filtered(&x, m), direct(&x, m));
            for (a, b) in a.iter().zip(&b) {
                assert!((a - b).abs() < 1e-12, "{n}: {a} vs {b}");
            }
        }
    }

    /// A circle of circumference `length` (a closed reference within the
    /// curved edge's reach), or a straight line `length` long.
    fn reference(length: f64, closed: bool) -> SplineCurve {
        let pts: Vec<[f64; 2]> = if closed {
            let r = length / TAU;
            (0..400)
                .map(|i| {
                    let t = TAU * i as f64 / 400.0;
                    [300.0 + r * t.cos(), 300.0 + r * t.sin()]
                })
                .collect()
        } else {
            (0..=100)
                .map(|i| [10.0 + length * i as f64 / 100.0, 50.0])
                .collect()
        };
        SplineCurve::fit(&pts, closed, 3, 2.0).unwrap()
    }

    #[test]
    fn an_oscillation_is_divided_by_one_less_its_gain() {
        // The shortest oscillation, 2 elements per wavelength (k = pi / h).
        let (n, h, blur) = (64, 5.0, 2.0);
        let basis = Basis::new(3, n, n as f64 * h, true).unwrap();
        let circle = reference(n as f64 * h, true);
        let lambda: Vec<f64> = (0..n).map(|j| (0.5 * TAU * j as f64).cos()).collect();
        let out = extrapolated(&lambda, &basis, &circle, (blur, false)).unwrap();
        let k = 0.5 * TAU / h;
        let g = gain_of(0.5 * spread_variance(blur) * k * k);
        assert!(g > 0.5, "gain {g}");
        for (o, l) in out.iter().zip(&lambda) {
            assert!((o - l / (1.0 - g)).abs() < 1e-12);
        }
        // A constant (k = 0) has no gain.
        let out = extrapolated(&[0.3; 64], &basis, &circle, (blur, false)).unwrap();
        assert!(out.iter().all(|o| (o - 0.3).abs() < 1e-12));
    }

    #[test]
    fn open_ends_keep_their_values() {
        let basis = Basis::new(3, 30, 150.0, false).unwrap();
        let line = reference(150.0, false);
        let lambda: Vec<f64> = (0..basis.n_functions())
            .map(|j| (j as f64 * 1.3).sin())
            .collect();
        let out = extrapolated(&lambda, &basis, &line, (2.0, false)).unwrap();
        let n = lambda.len();
        assert_eq!(&out[..4], &lambda[..4]);
        assert_eq!(&out[n - 4..], &lambda[n - 4..]);
        assert!(out[4..n - 4]
            .iter()
            .zip(&lambda[4..n - 4])
            .any(|(o, l)| (o - l).abs() > 1e-3));
    }

    #[test]
    fn corners_blur_free_profiles_osculating_bands_and_breaks_keep_the_displacement() {
        let basis = Basis::new(3, 40, 200.0, true).unwrap();
        let lambda = vec![0.1; basis.n_functions()];
        assert!(extrapolated(&lambda, &basis, &reference(200.0, true), (0.0, false)).is_none());
        // A band whose profile takes its osculating circle in full.
        assert!(extrapolated(&lambda, &basis, &reference(200.0, true), (2.0, true)).is_none());
        assert!(extrapolated(&lambda, &basis, &reference(200.0, true), (2.0, false)).is_some());
        // A square 50 px a side: its corners, rounded by the fit, are far
        // beyond the curved edge's reach under a 2 px blur.
        let square: Vec<[f64; 2]> = (0..200)
            .map(|i| {
                let (side, t) = (i / 50, (i % 50) as f64);
                match side {
                    0 => [t, 0.0],
                    1 => [50.0, t],
                    2 => [50.0 - t, 50.0],
                    _ => [0.0, 50.0 - t],
                }
            })
            .collect();
        let square = SplineCurve::fit(&square, true, 3, 1.0).unwrap();
        assert!(extrapolated(&lambda, &basis, &square, (2.0, false)).is_none());
        let corner = [crate::spline::Break {
            at: 70.0,
            multiplicity: 3,
        }];
        let broken = Basis::with_breaks(3, 30, 150.0, false, &corner).unwrap();
        let lambda = vec![0.1; broken.n_functions()];
        assert!(extrapolated(&lambda, &broken, &reference(150.0, false), (2.0, false)).is_none());
    }
}
