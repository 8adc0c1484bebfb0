//! The virtual image: the gray-level profile across the curve.
//!
//! Around a reference curve, a point at signed distance `r` (pixels, positive
//! on the normal's side, i.e. outside a closed curve) has the virtual gray
//! level `g = a + c * gamma(r / R)` inside the band `|r| < R`:
//!
//! * [`Kind::Silhouette`]: `gamma_s(rho) = (1 - sin(pi rho / 2)) / 2`, a
//!   smooth step from 1 at `rho = -1` (inside) to 0 at `rho = 1`, so `c > 0`
//!   means *bright inside* (bright on the left of the direction of travel as
//!   seen on screen for open curves);
//! * [`Kind::Contour`]: `gamma_c(rho) = (1 + cos(pi rho)) / 2`, a bell that is
//!   1 on the curve, so `c > 0` means a *bright line on a dark ground*.
//!
//! The dark level `a` and the contrast `c` are estimated by the fit; the sign
//! of `c` is the polarity.
//!
//! These are the paper's profiles: smooth, with a width set by the band, not
//! by the image. For the last stage of a silhouette the engine can instead use
//! [`Profile::PixelEdge`], the step as an ideal pixel records it through the
//! estimated blur ([`pixel_edge`]): the virtual image then matches the
//! physical one, which removes the sub-pixel aliasing of a sharp edge and
//! the curvature shift of a blurred one.

pub mod anisotropy;
pub mod corner;
pub(crate) mod ellipse;
pub(crate) mod osculating;
pub mod pixel_edge;
mod polarity;
mod psi;

pub use anisotropy::Anisotropy;
pub use polarity::Polarity;

use serde::{Deserialize, Serialize};
use std::f64::consts::{FRAC_PI_2, PI};

/// What is measured: a thin line or an edge.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq, Hash, Serialize, Deserialize)]
#[serde(rename_all = "snake_case")]
pub enum Kind {
    /// The boundary between a dark and a bright region (a step across it).
    #[default]
    Silhouette,
    /// A thin line: a bell across it, the curve is its axis.
    Contour,
}

impl Kind {
    /// `gamma(rho)` for `|rho| <= 1` (clamped outside).
    #[inline]
    pub fn gamma(self, rho: f64) -> f64 {
        let rho = rho.clamp(-1.0, 1.0);
        match self {
            Kind::Silhouette => 0.5 * (1.0 - (FRAC_PI_2 * rho).sin()),
            Kind::Contour => 0.5 * (1.0 + (PI * rho).cos()),
        }
    }

    /// `d gamma / d rho` for `|rho| < 1`, 0 outside.
    #[inline]
    pub fn gamma_prime(self, rho: f64) -> f64 {
        if rho.abs() >= 1.0 {
            return 0.0;
        }
        match self {
            Kind::Silhouette => -0.25 * PI * (FRAC_PI_2 * rho).cos(),
            Kind::Contour => -0.5 * PI * (PI * rho).sin(),
        }
    }
}

/// The profile of the virtual image across the curve.
#[derive(Clone, Copy, Debug, PartialEq, Serialize, Deserialize)]
#[serde(rename_all = "snake_case", tag = "type")]
pub enum Profile {
    /// The paper's profile of [`Kind`], `gamma(r / R)` over the band
    /// half-width `R`.
    Paper {
        /// Silhouette or contour.
        kind: Kind,
    },
    /// A silhouette as an ideal square pixel records it through a Gaussian
    /// blur of `blur` pixels: `gamma = 1 - P(T <= r - v kappa / 2)`
    /// ([`pixel_edge::pixel_edge_cdf`]) to the first order, where the
    /// pixel's trapezoid follows the local normal and `v = blur^2 + 1/12`
    /// is the variance of the whole spread. The term `v kappa / 2` is the
    /// first-order displacement of the half-level of a blurred curved edge
    /// (`kappa` the signed curvature, see [`crate::psf::curvature_shift`]):
    /// with it, the fitted curve is the true boundary, not the blurred
    /// image's half-level. The second order (the curvature's widening and
    /// skew of the profile too) is `pixel_edge::curved_edge`'s.
    PixelEdge {
        /// Standard deviation of the optical blur, pixels (0: a focused
        /// edge, only the pixel's own integration); its mean over the
        /// directions when `anisotropy` is not zero.
        blur: f64,
        /// How the blur differs with direction ([`Anisotropy`]; zero, and
        /// absent from JSON, for an isotropic blur): the profile's width
        /// follows the blur across the edge, its curvature shift the blur
        /// along it.
        #[serde(default, skip_serializing_if = "Anisotropy::is_none")]
        anisotropy: Anisotropy,
    },
    /// A thin line (a bar of `width` pixels) as an ideal square pixel
    /// records it through a Gaussian blur of `blur` pixels: the two curved
    /// pixel edges (`pixel_edge::curved_edge`) of the bar's sides, `gamma
    /// = g(r - width / 2) - g(r + width / 2)` (`g` the level on an edge's
    /// bright side). The bar is symmetric, so its curve is the line's
    /// axis; the curvature moves, widens and skews both sides alike, the
    /// blur's displacement of a curved line's centre (`v kappa / 2` to the
    /// first order, as of an edge's half level). Exact where the paper's bell is not: on a
    /// focused line a few pixels wide the bell's misfit aliases with the
    /// pixel grid, by some hundredths of a pixel where the line runs along
    /// a row.
    PixelLine {
        /// Standard deviation of the optical blur, pixels.
        blur: f64,
        /// The line's full width before blurring, pixels.
        width: f64,
    },
}

impl From<Kind> for Profile {
    fn from(kind: Kind) -> Profile {
        Profile::Paper { kind }
    }
}

impl Profile {
    /// The pixel edge through an isotropic blur of `blur` pixels.
    pub fn pixel_edge(blur: f64) -> Profile {
        Profile::PixelEdge {
            blur,
            anisotropy: Anisotropy::NONE,
        }
    }

    /// What the profile measures.
    pub fn kind(self) -> Kind {
        match self {
            Profile::Paper { kind } => kind,
            Profile::PixelEdge { .. } => Kind::Silhouette,
            Profile::PixelLine { .. } => Kind::Contour,
        }
    }

    /// Whether the fit pushes this profile to the pixel centres (the pixel
    /// edge and line, which model the pixels' own integration) rather than
    /// pulling the image back onto the reference (the paper's profiles);
    /// see `fit::correlation`.
    pub fn is_pushed(self) -> bool {
        matches!(self, Profile::PixelEdge { .. } | Profile::PixelLine { .. })
    }

    /// The optical blur of a pushed profile, pixels (`None` for the
    /// paper's).
    pub fn blur(self) -> Option<f64> {
        match self {
            Profile::PixelEdge { blur, .. } | Profile::PixelLine { blur, .. } => Some(blur),
            Profile::Paper { .. } => None,
        }
    }

    /// How far from the curve (pixels) a pushed profile's band must lie in
    /// the image: the transition, out to the narrow band a noiseless image
    /// takes (`pixel_edge::pixel_edge_band`). Beyond it, a noisy image's
    /// wider band adds pixels of the flat levels, there to fix the gray
    /// levels; an open curve's band may lose those to the image border
    /// (`band::Band::new`), and its ends are trimmed only where this part
    /// leaves the image. `None` for the paper's profiles, whose band must
    /// lie in the image whole.
    pub fn transition_half_width(self) -> Option<f64> {
        match self {
            Profile::PixelEdge { blur, .. } => Some(pixel_edge::pixel_edge_band(blur)),
            Profile::PixelLine { blur, width } => {
                Some(0.5 * width + pixel_edge::pixel_edge_band(blur))
            }
            Profile::Paper { .. } => None,
        }
    }

    /// `(gamma, d gamma / d r)` at signed distance `r` (pixels) from the
    /// curve, for a band of half-width `half_width` (pixels), at a point whose
    /// closest point on the curve has unit normal `normal` and signed
    /// curvature `curvature` (1/px), taken as constant over the blur (a
    /// circle's: [`Profile::eval_at`] with a weight of 1).
    #[inline]
    pub fn eval(self, r: f64, half_width: f64, normal: [f64; 2], curvature: f64) -> (f64, f64) {
        self.eval_at(r, half_width, normal, (curvature, 1.0))
    }

    /// [`Profile::eval`] with the weight `osculating` (0 to 1) of the pixel
    /// edge's blurred osculating circle beyond its expansion
    /// (`pixel_edge::curved_edge`): 1 where the curvature is constant over
    /// the blur, 0 where it changes fast (a rounded corner), whose
    /// osculating circle is no model of the edge
    /// (`band/blurred_curvature.rs`).
    #[inline]
    pub fn eval_at(
        self,
        r: f64,
        half_width: f64,
        normal: [f64; 2],
        (curvature, osculating): (f64, f64),
    ) -> (f64, f64) {
        match self {
            Profile::Paper { kind } => {
                let rho = r / half_width;
                (kind.gamma(rho), kind.gamma_prime(rho) / half_width)
            }
            Profile::PixelEdge { blur, anisotropy } => {
                let blurs = anisotropy.blurs(blur, normal);
                pixel_edge::curved_edge(r, normal[0], normal[1], blurs, curvature, osculating)
            }
            Profile::PixelLine { blur, width } => {
                // The bar between its sides at `r = -w/2` and `r = w/2`:
                // the level on the bright side of the outer one less that
                // on the bright side of the inner one.
                let half = 0.5 * width;
                let side = |r: f64| {
                    let blurs = (blur, blur, 0.0);
                    pixel_edge::curved_edge(r, normal[0], normal[1], blurs, curvature, osculating)
                };
                let ((outer, d_outer), (inner, d_inner)) = (side(r - half), side(r + half));
                (outer - inner, d_outer - d_inner)
            }
        }
    }
}

impl std::fmt::Display for Profile {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        match self {
            Profile::Paper { kind } => write!(f, "{kind}"),
            Profile::PixelEdge { blur, anisotropy } if anisotropy.is_none() => {
                write!(f, "pixel edge (blur {blur:.3} px)")
            }
            Profile::PixelEdge { blur, anisotropy } => {
                write!(f, "pixel edge (blur {blur:.3} px, {anisotropy})")
            }
            Profile::PixelLine { blur, width } => {
                write!(f, "pixel line (blur {blur:.3} px, width {width:.3} px)")
            }
        }
    }
}

impl std::fmt::Display for Kind {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        f.write_str(match self {
            Kind::Silhouette => "silhouette",
            Kind::Contour => "contour",
        })
    }
}

impl std::str::FromStr for Kind {
    type Err = crate::Error;
    /// `silhouette` or `contour` (the [`Display`](std::fmt::Display)
    /// names), case ignored: the one parser of the command line's `--kind`,
    /// job files' `kind` and Python's `kind=`.
    fn from_str(s: &str) -> crate::Result<Self> {
        match s.trim().to_ascii_lowercase().as_str() {
            "silhouette" => Ok(Kind::Silhouette),
            "contour" => Ok(Kind::Contour),
            _ => Err(crate::Error::invalid(
                "kind",
                format!("'{s}' (expected silhouette or contour)"),
            )),
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn derivative_matches_finite_difference() {
        for kind in [Kind::Silhouette, Kind::Contour] {
            for i in -9..=9 {
                let rho = i as f64 / 10.0;
                let h = 1e-6;
                let fd = (kind.gamma(rho + h) - kind.gamma(rho - h)) / (2.0 * h);
                assert!((fd - kind.gamma_prime(rho)).abs() < 1e-8, "{kind} {rho}");
            }
        }
    }

    /// The pixel line's derivative is its value's, a straight one is
    /// symmetric, and a line far wider than its blur is the two pixel
    /// edges of its sides.
    #[test]
    fn the_pixel_line_is_two_pixel_edges() {
        let line = Profile::PixelLine {
            blur: 0.7,
            width: 2.5,
        };
        let n = [0.6, 0.8];
        for i in -40..=40 {
            let r = i as f64 / 10.0;
            let h = 1e-6;
            let (g, d) = line.eval(r, 5.0, n, 0.01);
            let fd =
                (line.eval(r + h, 5.0, n, 0.01).0 - line.eval(r - h, 5.0, n, 0.01).0) / (2.0 * h);
            assert!((fd - d).abs() < 1e-6, "{r}: {fd} {d}");
            // Straight, it is symmetric about its axis.
            let straight = line.eval(r, 5.0, n, 0.0).0;
            let mirrored = line.eval(-r, 5.0, n, 0.0).0;
            assert!((straight - mirrored).abs() < 1e-9, "{r}");
            assert!(g.is_finite());
        }
        let wide = Profile::PixelLine {
            blur: 0.5,
            width: 40.0,
        };
        let edge = Profile::PixelEdge {
            blur: 0.5,
            anisotropy: Anisotropy::NONE,
        };
        for i in -30..=30 {
            let r = i as f64 / 10.0;
            let (g, _) = wide.eval(20.0 + r, 25.0, n, 0.0);
            let (e, _) = edge.eval(r, 25.0, n, 0.0);
            assert!((g - e).abs() < 1e-9, "{r}: {g} {e}");
        }
    }

    #[test]
    fn profile_ends() {
        assert_eq!(Kind::Silhouette.gamma(-1.0), 1.0);
        assert!(Kind::Silhouette.gamma(1.0).abs() < 1e-16);
        assert_eq!(Kind::Contour.gamma(0.0), 1.0);
        assert!(Kind::Contour.gamma(1.0).abs() < 1e-16);
    }
}
