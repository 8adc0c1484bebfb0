//! Every object of an image: find each region of one polarity whose edge
//! can be measured, measure each from its own traced start, independently
//! and in parallel, and number them in a stable order.
//!
//! 1. [`find`]: the search rectangle is smoothed and thresholded at Otsu's
//!    level as for the single automatic start ([`crate::start`]); the
//!    objects are the 4-connected regions of the chosen polarity (by
//!    default the minority phase) that are large enough
//!    ([`AllConfig::min_area`]), long enough ([`AllConfig::min_length`]) and
//!    contrasted enough (mean edge gradient at least
//!    [`MIN_CONTRAST_TO_NOISE`] times the image noise). Regions cut by the
//!    rectangle's border are skipped unless [`AllConfig::include_border`].
//!    With [`AllConfig::holes`], the regions of the other phase inside an
//!    object that pass the same tests are objects too, of the opposite
//!    polarity (numbered after the objects, each with its `parent`).
//! 2. [`order`]: objects are numbered row-major by centroid (rows grouped
//!    by half the median object size), so that two images of the same
//!    scene number them alike.
//! 3. `measure_one` (`measure.rs`): each object's band is kept off its
//!    neighbours (the stages' half-widths are capped by the gap to the
//!    nearest other edge: another region of its phase, or one inside it);
//!    an object too close for a band of its own is measured on the
//!    narrowest band and kept only if the whole-object fit, which renders
//!    its neighbours with it (`fit/whole/`), takes over. An object too
//!    close to another to be
//!    measured, a fit that diverges, loops or runs away from its region,
//!    or a shape model that does not fit, is recorded as failed with its
//!    reason ([`ObjectFailure`]); the other objects are unaffected.
//!
//! # Lines
//!
//! With `fit.kind` contour, the objects are the image's lines instead:
//! every ridge (bright line) or valley (dark line) whose strength is at
//! least [`AllConfig::min_strength`], followed from its strongest pixel
//! and measured from the followed polyline (`lines.rs`: the strength
//! map, the following, the gaps between lines). A line that runs to
//! another is recorded as [`ObjectFailure::Strayed`].
//!
//! ```
//! use vicurve::objects::{measure_all, AllConfig};
//! use vicurve::Image;
//! // Two bright discs of radius 12 on a dark ground.
//! let image = Image::from_fn(160, 80, |x, y| {
//!     let d = |cx: f64| ((x as f64 - cx).powi(2) + (y as f64 - 40.0).powi(2)).sqrt();
//!     if d(40.0) < 12.0 || d(115.0) < 12.0 { 0.9 } else { 0.1 }
//! });
//! let all = measure_all(&image, &AllConfig::default())?;
//! assert_eq!(all.objects.len(), 2);
//! assert!(all.objects.iter().all(|o| o.failure.is_none()));
//! # Ok::<(), vicurve::Error>(())
//! ```

pub mod corners;
pub mod find;
pub mod grid;
mod lines;
mod measure;
pub mod order;
pub mod square_grid;
pub mod table;
mod tone;

pub use find::{Candidate, Found};
pub use grid::{grid_strains, GridStrain};
pub use square_grid::{cell_polarity, cell_strains, lattice_indices};
pub use table::{object_table, Table};

use crate::curve::InitialCurve;
use crate::derived::ClosedMeasures;
use crate::error::{Error, Result};
use crate::fit::{Divergence, FitConfig, Measurement};
use crate::image::Image;
use crate::interp::Sampler;
use crate::model::{ModelConfig, ModelFit, ShapeModel};
use rayon::prelude::*;
use serde::{Deserialize, Serialize};

/// An object's mean edge gradient must be at least this many times the
/// image noise (gray levels per pixel): a real edge of contrast `C` through
/// the light smoothing has a gradient of about `0.3 C`, noise blobs well
/// under the noise's deviation.
pub const MIN_CONTRAST_TO_NOISE: f64 = 3.0;

/// Which phase the objects are.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq, Serialize, Deserialize)]
#[serde(rename_all = "snake_case")]
pub enum ObjectPolarity {
    /// The minority phase (fewer pixels above or below the threshold):
    /// objects on a ground.
    #[default]
    Auto,
    /// Bright objects on a dark ground.
    Bright,
    /// Dark objects on a bright ground.
    Dark,
}

impl std::fmt::Display for ObjectPolarity {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        f.write_str(match self {
            ObjectPolarity::Auto => "auto",
            ObjectPolarity::Bright => "bright",
            ObjectPolarity::Dark => "dark",
        })
    }
}

impl std::str::FromStr for ObjectPolarity {
    type Err = Error;
    /// `auto`, `bright` or `dark` (also `bright-inside`, `dark-inside`,
    /// `bright-line`, `dark-line`, the fit's names of the same polarities).
    fn from_str(s: &str) -> Result<Self> {
        match s.trim() {
            "auto" => Ok(ObjectPolarity::Auto),
            "bright" | "bright-inside" | "bright-line" => Ok(ObjectPolarity::Bright),
            "dark" | "dark-inside" | "dark-line" => Ok(ObjectPolarity::Dark),
            other => Err(Error::invalid(
                "polarity",
                format!("'{other}' (expected auto, bright or dark)"),
            )),
        }
    }
}

/// How to find and measure every object. `AllConfig::default()` gives the
/// documented defaults.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
#[serde(default)]
pub struct AllConfig {
    /// The objects' phase. Default: auto (the minority phase).
    pub polarity: ObjectPolarity,
    /// Least boundary length, px (traced boundary pixels). Default (`None`):
    /// the perimeter of a disc of radius twice the last stage's band
    /// half-width (`4 pi R_last`, 25 px for the default schedule): a
    /// shorter edge gives the last band too few pixels to measure.
    pub min_length: Option<f64>,
    /// Least area, px^2 (pixels of the thresholded region). Default
    /// (`None`): the area of that disc, `pi (2 R_last)^2` (50 px^2).
    pub min_area: Option<f64>,
    /// Search rectangle `[x0, y0, x1, y1]` (pixel centres, inclusive).
    /// Default: the whole image.
    pub roi: Option<[f64; 4]>,
    /// Measure objects cut by the rectangle's border, as open curves along
    /// their visible edge. Default: false (they are skipped).
    pub include_border: bool,
    /// Also measure the holes inside the objects, as objects of the
    /// opposite polarity (regions of the other phase enclosed by an object,
    /// with the same least length, area and contrast), numbered after the
    /// objects. Default: false.
    pub holes: bool,
    /// Lines (`fit.kind` contour): the least line strength `s^2 |lambda|`
    /// (gray levels; module docs, "Lines") a line is followed from.
    /// Default (`None`): 8 times the strength's noise, and at least a tenth
    /// of the strongest line's.
    pub min_strength: Option<f64>,
    /// Objects are polygons of this many corners (the cells of a square
    /// grid: 4): each object's fit breaks at the start's sharpest turns
    /// ([`corners::corner_breaks`]), so that its sides are measured as
    /// smooth curves meeting at corners; an object whose corners are not
    /// found is measured as a smooth curve. Default: none (smooth).
    pub corners: Option<usize>,
    /// The shape model fitted to every object. Default: none.
    pub model: Option<ShapeModel>,
    /// The B-spline measurement's settings (its stages are capped per
    /// object, module docs).
    pub fit: FitConfig,
    /// The model fit's settings.
    pub model_config: ModelConfig,
}

impl Default for AllConfig {
    fn default() -> Self {
        AllConfig {
            polarity: ObjectPolarity::Auto,
            min_length: None,
            min_area: None,
            roi: None,
            include_border: false,
            holes: false,
            min_strength: None,
            corners: None,
            model: None,
            fit: FitConfig::default(),
            model_config: ModelConfig::default(),
        }
    }
}

impl AllConfig {
    /// Check the fields. Errors: [`Error::InvalidParameter`].
    pub fn validate(&self) -> Result<()> {
        for (name, v) in [
            ("min_length", self.min_length),
            ("min_area", self.min_area),
            ("min_strength", self.min_strength),
        ] {
            if let Some(v) = v {
                if !(v.is_finite() && v >= 0.0) {
                    return Err(Error::invalid(name, format!("{v}: must be >= 0")));
                }
            }
        }
        if let Some(n) = self.corners {
            if !(3..=1000).contains(&n) {
                return Err(Error::invalid(
                    "corners",
                    format!("{n}: a polygon has 3 to 1000 corners"),
                ));
            }
        }
        if self.model == Some(ShapeModel::BsplineCurve) || self.model == Some(ShapeModel::Line) {
            return Err(Error::invalid(
                "model",
                "every object is a closed region: use circle, ellipse or polygon:N",
            ));
        }
        self.fit.validate()?;
        self.model_config.validate()
    }
}

/// Why an object was not measured, or its result is not to be trusted.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize, thiserror::Error)]
#[serde(tag = "reason", rename_all = "snake_case")]
pub enum ObjectFailure {
    /// Another region lies too close for a band to see this edge alone.
    #[error("another region lies {gap:.1} px away (object {neighbour:?}); at least {needed:.1} px needed for a band that sees this edge alone")]
    TooClose {
        /// The neighbour's object id (`None`: a region not listed, e.g. a
        /// speck or a border object).
        neighbour: Option<usize>,
        /// Gap between the two thresholded edges, px.
        gap: f64,
        /// Gap needed, px.
        needed: f64,
    },
    /// The start could not be made (an edge too short, all along the border).
    #[error("no start: {message}")]
    Start {
        /// What went wrong.
        message: String,
    },
    /// The measurement could not start (band outside the image, ...).
    #[error("not measured: {message}")]
    Measure {
        /// The library's error.
        message: String,
    },
    /// The B-spline fit diverged (left the image, crossed or folded on
    /// itself, lost the edge).
    #[error("the fit diverged: {divergence}")]
    Diverged {
        /// Why.
        divergence: Divergence,
    },
    /// The measured curve encloses an area far from the region's: it ran
    /// to another edge.
    #[error("the measured curve encloses {measured:.1} px^2 but the region has {region:.0} px^2: the fit ran to another edge")]
    Wandered {
        /// Area inside the measured curve, px^2.
        measured: f64,
        /// Pixels of the thresholded region and of its holes.
        region: f64,
    },
    /// A measured line ran away from the line it was followed along (to
    /// another line).
    #[error("the measured line lies {distance:.2} px (RMS) from the followed line: it ran to another line")]
    Strayed {
        /// RMS distance of its samples to the followed polyline, px.
        distance: f64,
    },
    /// The shape model could not be fitted.
    #[error("the model fit failed: {message}")]
    Model {
        /// Why.
        message: String,
    },
    /// The shape model does not describe the object: its residual is much
    /// larger than the free curve's (two objects merged, a wrong model).
    #[error("the model does not fit: residual {model_rms:.4} against {curve_rms:.4} for the free curve (objects merged or touching?)")]
    ModelMisfit {
        /// RMS residual of the model, gray levels.
        model_rms: f64,
        /// RMS residual of the B-spline curve's last stage, gray levels.
        curve_rms: f64,
    },
}

/// The thresholded region an object was found as.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub struct RegionInfo {
    /// Centroid of its pixels `[x, y]`, px.
    pub centroid: [f64; 2],
    /// Its pixels (area, px^2).
    pub pixels: usize,
    /// Traced boundary length, px (boundary pixels).
    pub boundary: usize,
    /// Bounding box `[x0, y0, x1, y1]` (pixel centres, inclusive).
    pub bbox: [usize; 4],
    /// Whether it is cut by the search rectangle's border.
    pub touches_border: bool,
    /// Gap to the nearest other edge (a region of the same phase, or one
    /// inside this one), px (infinite beyond the search reach).
    pub gap: f64,
    /// For a hole: the id of the object it is inside.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub parent: Option<usize>,
}

/// One object: where it was found, its start, and its measurement or why
/// it failed.
#[derive(Clone, Debug)]
pub struct ObjectResult {
    /// Its number (row-major by centroid, from 0).
    pub id: usize,
    /// The region it was found as.
    pub region: RegionInfo,
    /// Its start (the smoothed traced boundary).
    pub start: Option<InitialCurve>,
    /// The configuration it was measured with (stages capped by the gap).
    pub config: FitConfig,
    /// The B-spline measurement (kept for a failed object when it ran).
    pub measurement: Option<Measurement>,
    /// Closed-curve measures of a closed measured curve.
    pub closed: Option<ClosedMeasures>,
    /// The shape model's fit, when one was asked for.
    pub model: Option<ModelFit>,
    /// Why it failed; `None` for a measured object.
    pub failure: Option<ObjectFailure>,
}

impl ObjectResult {
    /// `"measured"` or the failure's reason tag.
    pub fn outcome(&self) -> String {
        match &self.failure {
            None => "measured".into(),
            Some(f) => serde_json::to_value(f)
                .ok()
                .and_then(|v| v.get("reason").and_then(|r| r.as_str().map(String::from)))
                .unwrap_or_else(|| "failed".into()),
        }
    }
}

/// Every object of an image.
#[derive(Clone, Debug)]
pub struct AllResult {
    /// The objects, in their numbering order.
    pub objects: Vec<ObjectResult>,
    /// What the search found and left out.
    pub found: Found,
}

impl AllResult {
    /// Objects that failed.
    pub fn failed(&self) -> usize {
        self.objects.iter().filter(|o| o.failure.is_some()).count()
    }
}

/// Find every object of `image` and measure each (module docs).
///
/// Errors: [`Error::InvalidParameter`] for a bad configuration or region of
/// interest, [`Error::NoSilhouette`] for an image without contrast. Each
/// object's own failure is in its [`ObjectResult::failure`].
pub fn measure_all(image: &Image, config: &AllConfig) -> Result<AllResult> {
    config.validate()?;
    if config.fit.kind == crate::virtual_image::Kind::Contour {
        return lines::measure_all_lines(image, config);
    }
    let found = find::find_objects(image, config)?;
    // The image's interpolant, prepared once for every object.
    let sampler = Sampler::new(image, config.fit.interpolation);
    let mut objects = found
        .candidates
        .par_iter()
        .map(|c| measure::measure_one(image, &sampler, c, config))
        .collect();
    if config.fit.tone == crate::tone::Tone::Auto {
        objects = tone::agreed(image, &sampler, &found.candidates, objects, config);
    }
    Ok(AllResult { objects, found })
}
