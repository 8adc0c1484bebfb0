//! Fit configuration, with documented defaults; serialisable so that every
//! result file records the configuration it was measured with.

pub use crate::band::Coords;
use crate::error::{Error, Result};
use crate::fit::levels::LevelModel;
use crate::interp::Interpolation;
use crate::tone::Tone;
use crate::virtual_image::Kind;
pub use crate::virtual_image::Polarity;
use serde::{Deserialize, Serialize};

/// How many elements a stage uses.
#[derive(Clone, Copy, Debug, PartialEq, Serialize, Deserialize)]
#[serde(rename_all = "snake_case")]
pub enum Elements {
    /// A fixed number of elements.
    Count(usize),
    /// Elements of about this length, pixels (the count follows the curve's
    /// length at the start of the stage).
    Length(f64),
    /// Start with elements of `longest` pixels and halve them while the
    /// finer curve differs from the coarser one by more than the noise
    /// explains, down to `shortest` pixels. Only for the last stage (earlier
    /// stages use `longest`).
    Auto {
        /// First (longest) element length, pixels.
        longest: f64,
        /// Shortest element length allowed, pixels.
        shortest: f64,
    },
}

/// One stage of the coarse-to-fine schedule.
#[derive(Clone, Copy, Debug, PartialEq, Serialize, Deserialize)]
pub struct Stage {
    /// Band half-width `R`, pixels.
    pub half_width: f64,
    /// Number or length of the B-spline elements of the displacement.
    pub elements: Elements,
}

impl Stage {
    /// Number of elements for a curve of `length` pixels (at least
    /// `min`).
    pub fn element_count(&self, length: f64, min: usize) -> usize {
        match self.elements {
            Elements::Count(n) => n.max(min),
            Elements::Length(h) | Elements::Auto { longest: h, .. } => {
                ((length / h).round() as usize).max(min)
            }
        }
    }
}

/// The default schedule: band half-widths 20, 10, 5 and 2 px with elements
/// of 80, 40 and 40 px, then automatic (40 px halved down to 5 px while it
/// pays); a closed curve gets at least 8 elements in every stage of it (4
/// are as round as a circle: a small square never reached its corners).
///
/// Wide bands first capture the coarse shape from a start up to ~R away;
/// the last, 2 px band matches a sharp, focused edge (the paper's optimum is
/// a virtual band as wide as the physical transition), where the bias is
/// smallest. The element length trades noise against shape: the scatter
/// falls as one over the square root of the element length, the error of
/// representing a detailed shape grows as its fourth power. No fixed length
/// suits a noisy disc and a detailed star alike, so the last stage chooses:
/// it halves its elements while the change in the curve exceeds what the
/// image noise explains. Earlier stages never use shorter elements than the
/// last one starts with, so that their noise stays within what the last
/// stage re-measures. Stages whose band is too wide for the curve (R above
/// half the radius of a circle of the same length) or that would leave the
/// image are skipped, the last one excepted; so are the 20 and 10 px stages
/// when the 5 px one, run first from the start, completes without a new
/// reference (the start was within its reach everywhere). With
/// [`FitConfig::blur_correction`] on, one more stage follows: for a
/// silhouette, the pixel-edge stage ([`crate::virtual_image::Profile::PixelEdge`]:
/// the step as a pixel records it through the blur, which is fitted); for a
/// line, the pixel-line stage ([`crate::virtual_image::Profile::PixelLine`]:
/// the bar as a pixel records it through the blur and width estimated on
/// the last stage's curve, see [`crate::psf::line_spread`]).
pub fn default_stages() -> Vec<Stage> {
    let fixed = |half_width: f64, h: f64| Stage {
        half_width,
        elements: Elements::Length(h),
    };
    vec![
        fixed(20.0, 80.0),
        fixed(10.0, 40.0),
        fixed(5.0, 40.0),
        Stage {
            half_width: 2.0,
            elements: Elements::Auto {
                longest: 40.0,
                shortest: 5.0,
            },
        },
    ]
}

/// `all` (a schedule) within a band half-width of `cap` pixels (see
/// [`FitConfig::max_half_width`]): the wider stages left out but the last,
/// and, when the first one left is under 4 px and the cap leaves room, a
/// first stage of the cap's width (at most 5 px, elements of 40 px), so
/// that a start a few pixels off still finds the edge. `all` not empty.
pub(crate) fn capped_stages(all: Vec<Stage>, cap: f64) -> Vec<Stage> {
    let n = all.len();
    let mut kept: Vec<Stage> = all
        .into_iter()
        .enumerate()
        .filter(|(k, s)| s.half_width <= cap || k + 1 == n)
        .map(|(_, s)| s)
        .collect();
    if kept[0].half_width < 4.0 && cap > kept[0].half_width + 0.5 {
        kept.insert(
            0,
            Stage {
                half_width: cap.min(5.0),
                elements: Elements::Length(40.0),
            },
        );
    }
    kept
}

/// Everything that controls a measurement. `FitConfig::default()` is the
/// documented default of each field.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
#[serde(default)]
pub struct FitConfig {
    /// Thin line or edge. Default: silhouette.
    pub kind: Kind,
    /// Polarity. Default: auto.
    pub polarity: Polarity,
    /// Degree of the displacement B-splines, 1 to 5. Default: 3.
    pub degree: usize,
    /// The stages; `None` is the [`default_stages`] schedule (with its
    /// skipping rules).
    pub stages: Option<Vec<Stage>>,
    /// Image interpolation. Default: see [`Interpolation::default`].
    pub interpolation: Interpolation,
    /// Convergence: stop a run when `max |dLambda|` is under this, pixels,
    /// or when the steps contract fast enough that the ones still to come
    /// would add up to less (estimated from the last three steps, with a
    /// factor 2 of safety). Default: 1e-4.
    pub tolerance: f64,
    /// Iteration limit per stage. Default: 200.
    pub max_iterations: usize,
    /// Re-reference within a stage when `max |U|` exceeds this fraction of
    /// `R` (the linearisation holds while `U` is small against `R`; each
    /// re-reference costs a new band). Default: 0.75.
    pub rereference_fraction: f64,
    /// Limit each Gauss–Newton step to this fraction of `R`, pixels per
    /// pixel of band half-width (keeps a start far from the edge from
    /// overshooting). Default: 0.5.
    pub max_step_fraction: f64,
    /// Largest spacing of the output samples along the curve, pixels.
    /// Default: 1.
    pub sample_spacing: f64,
    /// Estimate the blur of the edge (silhouettes) or line (contours) from
    /// the image and account for it, so that the result is the true boundary
    /// or centre line rather than the blurred one: the default schedule of a
    /// silhouette ends with the pixel-edge stage (the virtual edge is a pixel
    /// seen through the fitted blur, curvature shift included); a line's
    /// with the pixel-line stage (the bar seen through the estimated blur
    /// and width, the shift `s^2 kappa / 2` the blur causes on curved lines
    /// included; see [`crate::psf`]).
    /// With explicit stages, the shift is removed when the last band is
    /// matched to the blur. Turn it off for images whose profile is not a
    /// blurred step or bar, such as the paper's synthetic disc rendered with
    /// the virtual profile itself. Default: true.
    pub blur_correction: bool,
    /// Curvilinear coordinates of the band pixels. Default: exact
    /// projection.
    pub coords: Coords,
    /// Whether the virtual image's gray levels may vary along the curve
    /// (uneven light). Default: varying, elements of 128 px (see
    /// [`LevelModel`]).
    pub levels: LevelModel,
    /// Corners: arc lengths (pixels) along the initial curve, from its
    /// start, where the measured curve may have a corner or a tangent break
    /// (repeated knots; see [`crate::fit::breaks`] for the
    /// model and how the positions follow the curve). Each must be finite,
    /// inside the curve (`0 < s < L` open, `0 <= s < L` closed: checked when
    /// the curve is known) and distinct; they need exact coordinates.
    /// Default: none (a smooth curve).
    pub breaks: Vec<f64>,
    /// Look for corners the start did not give: when the measured curve
    /// turns sharply within a few pixels and hardly beside (a polygon's
    /// vertex), measure it again with breaks there and keep the corners
    /// where the image looks more like a sharp corner than like the
    /// smooth curve (`fit/corner_check.rs`; [`crate::fit::measure_from`];
    /// [`crate::measurement::Measurement::corners_found`] says where).
    /// Not when `breaks` are given or the start has corners. Default: true.
    pub find_corners: bool,
    /// How the image's gray levels relate to the light ([`Tone`]): with
    /// [`Tone::Auto`] a silhouette's tone curve is estimated around the
    /// measured edge and, when the image is clearly not linear (a power
    /// law such as an sRGB encoding), the edge is measured again on the
    /// image taken back to linear light; an explicit tone curve is undone
    /// before measuring. Default: auto.
    pub tone: Tone,
    /// The widest band half-width of the default schedule, pixels, when
    /// another edge lies beyond it (`measure --all` sets it from the gap
    /// to the nearest object): its wider stages are left out (the last one
    /// stays; a first band of this width, at most 5 px, comes first when
    /// only narrow ones remain) and the matched stage's band (the pixel
    /// edge or line) is at most this wide, so that it is still appended.
    /// Explicit `stages` ignore it. Default: none.
    #[serde(skip_serializing_if = "Option::is_none")]
    pub max_half_width: Option<f64>,
}

impl Default for FitConfig {
    fn default() -> Self {
        FitConfig {
            kind: Kind::Silhouette,
            polarity: Polarity::Auto,
            degree: 3,
            stages: None,
            interpolation: Interpolation::CubicBSpline,
            tolerance: 1e-4,
            max_iterations: 200,
            rereference_fraction: 0.75,
            max_step_fraction: 0.5,
            sample_spacing: 1.0,
            blur_correction: true,
            coords: Coords::Exact,
            levels: LevelModel::default(),
            breaks: Vec::new(),
            find_corners: true,
            tone: Tone::Auto,
            max_half_width: None,
        }
    }
}

impl FitConfig {
    /// Check every field; errors name the field and the accepted range.
    pub fn validate(&self) -> Result<()> {
        self.levels.validate()?;
        self.tone.validate()?;
        if !(1..=crate::spline::MAX_DEGREE).contains(&self.degree) {
            return Err(Error::invalid(
                "degree",
                format!("{} (must be 1 to 5)", self.degree),
            ));
        }
        if let Some(cap) = self.max_half_width {
            if !(cap.is_finite() && cap > 0.0) {
                return Err(Error::invalid(
                    "max_half_width",
                    format!("{cap} px (must be a positive number)"),
                ));
            }
        }
        if let Some(stages) = &self.stages {
            if stages.is_empty() {
                return Err(Error::invalid(
                    "stages",
                    "empty list (give at least one R:elements pair)",
                ));
            }
            for st in stages {
                if !(st.half_width.is_finite() && st.half_width >= 0.5) {
                    return Err(Error::invalid(
                        "stages",
                        format!(
                            "band half-width {} px (must be at least 0.5)",
                            st.half_width
                        ),
                    ));
                }
                match st.elements {
                    Elements::Count(0) => return Err(Error::invalid("stages", "0 elements")),
                    Elements::Length(h) if !(h.is_finite() && h > 0.0) => {
                        return Err(Error::invalid("stages", format!("element length {h}")))
                    }
                    Elements::Auto { longest, shortest }
                        if !(shortest.is_finite()
                            && shortest > 0.0
                            && longest.is_finite()
                            && longest >= shortest) =>
                    {
                        return Err(Error::invalid(
                            "stages",
                            format!("automatic elements from {longest} to {shortest} px"),
                        ))
                    }
                    _ => {}
                }
            }
        }
        let positive = |v: f64| v.is_finite() && v > 0.0;
        if !positive(self.tolerance) {
            return Err(Error::invalid(
                "tolerance",
                format!("{} (must be > 0)", self.tolerance),
            ));
        }
        if self.max_iterations == 0 {
            return Err(Error::invalid("max iterations", "0"));
        }
        if !positive(self.rereference_fraction) {
            return Err(Error::invalid(
                "rereference fraction",
                format!("{}", self.rereference_fraction),
            ));
        }
        if !positive(self.max_step_fraction) {
            return Err(Error::invalid(
                "max step fraction",
                format!("{}", self.max_step_fraction),
            ));
        }
        if let Coords::Levelset { mesh_size } = self.coords {
            crate::levelset::check_mesh_size(mesh_size)?;
        }
        self.validate_breaks()?;
        if !(self.sample_spacing.is_finite() && self.sample_spacing >= 0.01) {
            return Err(Error::invalid(
                "sample spacing",
                format!("{} (must be >= 0.01 px)", self.sample_spacing),
            ));
        }
        Ok(())
    }
}

impl FitConfig {
    /// The checks of [`FitConfig::breaks`] that do not need the curve.
    fn validate_breaks(&self) -> Result<()> {
        if let Some(b) = self.breaks.iter().find(|b| !(b.is_finite() && **b >= 0.0)) {
            return Err(Error::invalid(
                "breaks",
                format!("{b} (arc lengths must be finite and >= 0 px)"),
            ));
        }
        let mut sorted = self.breaks.clone();
        sorted.sort_by(f64::total_cmp);
        if let Some(w) = sorted.windows(2).find(|w| w[0] == w[1]) {
            return Err(Error::invalid("breaks", format!("{} px given twice", w[0])));
        }
        if !self.breaks.is_empty() && self.coords != Coords::Exact {
            return Err(Error::invalid(
                "breaks",
                "need exact coordinates (not levelsets)",
            ));
        }
        Ok(())
    }
}

/// Parse a schedule `R:N,R:N,...` (band half-width in pixels : number of
/// elements), e.g. `20:25,10:50,5:100`. An element count may also be given
/// as a length with a `px` suffix, `2:40px`, or as `auto` (elements of 40
/// px halved down to 5 px while it pays, see [`Elements::Auto`]).
pub fn parse_stages(spec: &str) -> Result<Vec<Stage>> {
    let err = |reason: String| Error::Parse {
        what: format!("stages '{spec}'"),
        line: 0,
        reason,
    };
    let mut out = Vec::new();
    for item in spec.split(',').map(str::trim).filter(|s| !s.is_empty()) {
        let (r, n) = item
            .split_once(':')
            .ok_or_else(|| err(format!("'{item}' is not R:ELEMENTS (e.g. 10:50)")))?;
        let half_width: f64 = r
            .trim()
            .parse()
            .map_err(|_| err(format!("'{r}' is not a number")))?;
        let n = n.trim();
        let elements = if n == "auto" {
            Elements::Auto {
                longest: 40.0,
                shortest: 5.0,
            }
        } else if let Some(len) = n.strip_suffix("px") {
            Elements::Length(
                len.trim()
                    .parse()
                    .map_err(|_| err(format!("'{n}' is not a length")))?,
            )
        } else {
            Elements::Count(
                n.parse()
                    .map_err(|_| err(format!("'{n}' is not a whole number of elements")))?,
            )
        };
        out.push(Stage {
            half_width,
            elements,
        });
    }
    if out.is_empty() {
        return Err(err("no stage given".into()));
    }
    let cfg = FitConfig {
        stages: Some(out.clone()),
        ..Default::default()
    };
    cfg.validate()?;
    Ok(out)
}
