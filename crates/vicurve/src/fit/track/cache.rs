//! What a tracked frame leaves for the next one of the same curve: the
//! band it measured on, with its prepared system and displacement, and how
//! far the curve moved.
//!
//! The band of a tracked frame has a margin and counts the pixels around
//! the displaced curve (see [`super::TRACK_MARGIN`]), so the result does
//! not depend on its reference as long as the displacement stays within
//! the margin. The next frame then needs no band of its own: it reads its
//! pixel values on the kept band and starts from the kept displacement
//! (`Correlation::reload`), which saves the band's construction and the
//! system's preparation, half of a tracked frame's cost. It does so when
//! the kept displacement plus the last frame's motion is within the
//! margin. A new band's margin is sized from that motion
//! ([`REUSE_MOTIONS`] times it, between `TRACK_MARGIN` and
//! [`MAX_TRACK_MARGIN`]), so that a curve moving steadily is measured on
//! each band for up to four frames; a curve that moves more than half the
//! largest margin per frame gets the smallest (no frame could reuse its
//! band). A frame on a kept band starts from the kept displacement moved
//! on as the curve moved over the last frame (a steady motion then needs
//! fewer iterations, and stops after two steps when the band's earlier
//! frames showed a fast contraction: `fit::run::error_left`), with the
//! curvature of that curve in the profile (`Band::bend_to`). The light's
//! tilt measured on the band's first frame, and the blur it fitted, serve
//! its later ones (a sequence's light and focus change slowly; the next
//! band measures them again).
//!
//! # Resuming
//! A sequence that is stopped and resumed must give the same results to
//! the last digit as an uninterrupted run, so what the cache holds can be
//! written down ([`TrackCache::snapshot`], a few hundred numbers: the
//! band's reference, its displacement and tilt, how fast its iteration
//! contracted, the margin and the motion) and read back
//! ([`TrackCache::from_snapshot`]): the band is then built again on the
//! next frame, and everything built from it (the band,
//! `M0`, the levels' matrices, the tilt at the pixels from its recorded
//! coefficients) is a deterministic function of what was written
//! (`solver::chunked` sums, bands in raster order), so the system is the
//! one the uninterrupted run kept. Bands whose reference has corners are
//! not kept (their basis is not written).

use super::TrackState;
use crate::band::Band;
use crate::correlation::{Correlation, MeasuredTilt};
use crate::curve::SplineCurve;
use crate::error::Result;
use crate::fit::{Coords, LevelModel};
use crate::interp::Sampler;
use crate::spline::Basis;
use crate::virtual_image::{Anisotropy, Profile};
use serde::{Deserialize, Serialize};

/// A new band's margin is this many times the last frame's motion (see
/// the module docs): a curve moving steadily stays within it for four
/// frames (the factor's measurements: docs/benchmarks.md).
pub(super) const REUSE_MOTIONS: f64 = 4.1;
/// Largest margin of a tracked band, pixels: a curve moving faster gets a
/// band of its own more often (a wider margin costs pixels in every
/// iteration).
pub(super) const MAX_TRACK_MARGIN: f64 = 2.5;

/// What a frame of a sequence leaves for the next one of the same curve:
/// the band it measured on, with its prepared system and displacement.
/// The next frame measures on that band, when the curve stays within its
/// margin, instead of building one (the tracked band counts the pixels
/// around the displaced curve, so the result hardly depends on its
/// reference). [`TrackCache::snapshot`] writes it down and
/// [`TrackCache::from_snapshot`] reads it back, so that a resumed
/// sequence gives the same numbers as an uninterrupted one.
///
/// A cache belongs to one curve of one sequence, used in frame order
/// ([`super::measure_tracked_cached`]); an empty one
/// (`TrackCache::default()`) reuses nothing.
#[derive(Default)]
pub struct TrackCache {
    held: Option<Held>,
    /// How far the curve moved over the last tracked frame, pixels (the
    /// largest change of the displacement; summed over its bands when it
    /// re-referenced: a bound).
    motion: Option<f64>,
}

/// The kept band, built or as written.
enum Held {
    Built(Box<Kept>),
    Written(Box<BandRecord>),
}

/// A kept band with its prepared system; see [`TrackCache`].
pub(crate) struct Kept {
    pub reference: SplineCurve,
    pub corr: Correlation,
    pub lambda: Vec<f64>,
    /// How the displacement changed over the last frame, when that frame
    /// measured on this band alone: the next frame starts from `lambda`
    /// plus this.
    pub velocity: Option<Vec<f64>>,
    /// The level model the system was prepared with.
    pub levels: LevelModel,
    /// The image size the band was built in, pixels.
    pub size: (usize, usize),
}

/// What [`TrackCache`] holds, written down. Serialisable (JSON keeps
/// every bit of its numbers), to be read back by
/// [`TrackCache::from_snapshot`]; its fields are not an interface.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub struct TrackSnapshot {
    /// The last frame's motion, pixels.
    motion: Option<f64>,
    /// The kept band, if any.
    band: Option<BandRecord>,
}

/// A kept band as written.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
struct BandRecord {
    /// The reference: a uniform B-spline of this degree, closure,
    /// parameter length (pixels) and elements, and its control points.
    degree: usize,
    closed: bool,
    length: f64,
    elements: usize,
    control_points: Vec<[f64; 2]>,
    /// The displacement's basis: degree and elements (on the reference's
    /// parameter), and its coefficients, pixels.
    displacement_degree: usize,
    displacement_elements: usize,
    lambda: Vec<f64>,
    /// The displacement's change over the last frame (see `Kept`).
    #[serde(default)]
    velocity: Option<Vec<f64>>,
    /// The band: half-width and margin, pixels, and the pixel edge's blur.
    half_width: f64,
    margin: f64,
    blur: f64,
    /// The blur's anisotropy (none in files written before it was, and
    /// not written when none).
    #[serde(default, skip_serializing_if = "Anisotropy::is_none")]
    anisotropy: Anisotropy,
    levels: LevelModel,
    width: usize,
    height: usize,
    /// The light's tilt, in the levels' basis (varying levels); `None`:
    /// none measured.
    tilt: Option<Vec<f64>>,
    /// The slowest contraction the system's runs showed (see
    /// `Correlation::contraction`); `None` in files written before it was.
    #[serde(default)]
    contraction: Option<f64>,
}

impl BandRecord {
    fn of(kept: &Kept) -> Option<BandRecord> {
        let basis = kept.reference.basis();
        let Profile::PixelEdge { blur, anisotropy } = kept.corr.band().profile() else {
            return None;
        };
        if !(basis.breaks().is_empty() && kept.corr.basis().breaks().is_empty()) {
            return None;
        }
        Some(BandRecord {
            degree: basis.degree(),
            closed: basis.is_closed(),
            length: basis.length(),
            elements: basis.n_elements(),
            control_points: kept.reference.control_points().to_vec(),
            displacement_degree: kept.corr.basis().degree(),
            displacement_elements: kept.corr.basis().n_elements(),
            lambda: kept.lambda.clone(),
            velocity: kept.velocity.clone(),
            half_width: kept.corr.band().half_width(),
            margin: kept.corr.band().margin(),
            blur,
            anisotropy,
            levels: kept.levels,
            width: kept.size.0,
            height: kept.size.1,
            tilt: kept.corr.measured_tilt().and_then(|t| t.coefs.clone()),
            contraction: kept.corr.contraction(),
        })
    }

    /// The band and its system, built again on the image of `sampler`.
    fn build(self, sampler: &Sampler, coords: Coords) -> Result<Kept> {
        let ref_basis = Basis::new(self.degree, self.elements, self.length, self.closed)?;
        let reference = SplineCurve::new(ref_basis, self.control_points)?;
        let basis = Basis::new(
            self.displacement_degree,
            self.displacement_elements,
            self.length,
            self.closed,
        )?;
        let profile = Profile::PixelEdge {
            blur: self.blur,
            anisotropy: self.anisotropy,
        };
        let size = (self.width, self.height);
        let band = Band::build_windowed(
            &reference,
            &basis,
            self.half_width,
            self.margin,
            profile,
            size.0,
            size.1,
            coords,
        )?;
        let tilt = MeasuredTilt::known(profile, self.tilt);
        let mut corr = Correlation::prepare(band, basis, sampler, self.levels, tilt.as_ref())?;
        if let Some(q) = self.contraction {
            corr.observe_contraction(q);
        }
        Ok(Kept {
            reference,
            corr,
            lambda: self.lambda,
            velocity: self.velocity,
            levels: self.levels,
            size,
        })
    }
}

impl TrackCache {
    /// The cache as written down: `None` when it holds nothing.
    pub fn snapshot(&self) -> Option<TrackSnapshot> {
        let band = match &self.held {
            Some(Held::Built(kept)) => BandRecord::of(kept),
            Some(Held::Written(record)) => Some((**record).clone()),
            None => None,
        };
        (band.is_some() || self.motion.is_some()).then_some(TrackSnapshot {
            motion: self.motion,
            band,
        })
    }

    /// The cache a [`TrackCache::snapshot`] describes; its band is built
    /// again when the next frame takes it.
    pub fn from_snapshot(snapshot: TrackSnapshot) -> TrackCache {
        TrackCache {
            held: snapshot.band.map(|b| Held::Written(Box::new(b))),
            motion: snapshot.motion,
        }
    }

    /// Whether a band is kept for the next frame.
    pub fn holds_band(&self) -> bool {
        self.held.is_some()
    }

    /// Forget the kept band (the next frame builds its own); the motion
    /// stays.
    pub fn clear(&mut self) {
        self.held = None;
    }

    /// The margin of a new band, pixels (see the module's docs).
    pub(crate) fn margin(&self) -> f64 {
        let Some(m) = self.motion else {
            return super::TRACK_MARGIN;
        };
        if REUSE_MOTIONS * m <= MAX_TRACK_MARGIN {
            (REUSE_MOTIONS * m).max(super::TRACK_MARGIN)
        } else if 2.0 * m < MAX_TRACK_MARGIN {
            // At least the next frame may reuse it.
            MAX_TRACK_MARGIN
        } else {
            // Too fast for any frame to reuse the band: no wider margin
            // than a band of its own needs.
            super::TRACK_MARGIN
        }
    }

    /// The kept band, taken out (built again on `sampler`'s image if it
    /// was read back), when it serves a frame with the tracking stage of
    /// `state` and the level model `levels` on `sampler`'s image: the same
    /// profile and half-width, and a displacement that the last frame's
    /// motion keeps within the margin.
    pub(crate) fn take_for(
        &mut self,
        state: &TrackState,
        levels: LevelModel,
        sampler: &Sampler,
        coords: Coords,
    ) -> Option<Box<Kept>> {
        let motion = self.motion?;
        let size = (sampler.width(), sampler.height());
        let fits = |lambda: &[f64], profile: Profile, half_width: f64, margin: f64| {
            let at = lambda.iter().fold(0.0, |m: f64, l| m.max(l.abs()));
            profile == state.profile()
                && half_width == state.stage().half_width
                && at + motion <= margin
        };
        match self.held.take()? {
            Held::Built(kept) => {
                let band = &kept.corr.band();
                let serves = kept.levels == levels
                    && kept.size == size
                    && fits(
                        &kept.lambda,
                        band.profile(),
                        band.half_width(),
                        band.margin(),
                    );
                serves.then_some(kept)
            }
            Held::Written(r) => {
                let profile = Profile::PixelEdge {
                    blur: r.blur,
                    anisotropy: r.anisotropy,
                };
                let serves = r.levels == levels
                    && (r.width, r.height) == size
                    && fits(&r.lambda, profile, r.half_width, r.margin);
                serves
                    .then(|| r.build(sampler, coords).ok().map(Box::new))
                    .flatten()
            }
        }
    }

    /// After a frame: keep `kept` (when its band may serve the next frame)
    /// and the frame's motion (`None`: not measured, the last one stands).
    /// A band that could not be written down is not kept either, so that
    /// a resumed run goes on as an uninterrupted one.
    pub(crate) fn update(&mut self, kept: Option<Box<Kept>>, motion: Option<f64>) {
        self.held = kept
            .filter(|k| BandRecord::of(k).is_some())
            .map(Held::Built);
        if motion.is_some() {
            self.motion = motion;
        }
    }
}
