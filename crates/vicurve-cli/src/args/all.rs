//! `measure --all`: every object of the image, and the per-object table.

use crate::failure::Failure;
use std::path::PathBuf;
use vicurve::objects::ObjectPolarity;

/// The options of `measure --all` (and of `grid`).
#[derive(clap::Args, Clone, Debug, Default)]
pub struct AllArgs {
    /// Measure every object of the image: each region of the objects'
    /// phase (`--polarity bright|dark|auto`, default the minority phase)
    /// whose edge is long and contrasted enough, each from its own traced
    /// start, in parallel; one object's failure is recorded and never stops
    /// the others (exit 3 when some failed). Within `--roi` if given.
    /// With `--kind contour`: every ridge or valley line above a strength
    /// (`--min-strength`), each followed and measured.
    #[arg(long)]
    pub all: bool,
    /// With --all: least boundary length, px (default: 4 pi R_last, 25 px
    /// for the default stages).
    #[arg(long, value_name = "PX")]
    pub min_length: Option<f64>,
    /// With --all: least area, px^2 (default: pi (2 R_last)^2, 50 px^2).
    #[arg(long, value_name = "PX2")]
    pub min_area: Option<f64>,
    /// With --all: also measure the objects cut by the border (or the
    /// --roi), as open curves along their visible edge.
    #[arg(long)]
    pub include_border: bool,
    /// With --all: also measure the holes inside the objects, as objects of
    /// the opposite polarity (numbered after the objects; the table's
    /// `parent` column gives the object each is in).
    #[arg(long)]
    pub holes: bool,
    /// With --all --kind contour: the least line strength a line is
    /// followed from (s^2 |lambda| of the smoothed image across the line,
    /// gray levels; default 8 times its noise and at least a tenth of the
    /// strongest line's).
    #[arg(long, value_name = "STRENGTH")]
    pub min_strength: Option<f64>,
    /// With --all: the objects are polygons of N corners (square holes,
    /// the cells of a square grid: 4); each fit breaks at its start's N
    /// sharpest turns, so that the sides are measured as smooth curves
    /// meeting at corners (an object whose corners are not found is
    /// measured smooth).
    #[arg(long, value_name = "N")]
    pub corners: Option<usize>,
    /// With --all: write one row per object as CSV (id, outcome, centroid,
    /// area, equivalent diameter, circle and ellipse with sigmas, model
    /// parameters with sigmas, RMS residual, message).
    #[arg(long, value_name = "FILE")]
    pub table: Option<PathBuf>,
}

impl AllArgs {
    /// Refuse the --all options without --all.
    pub fn check(&self) -> Result<(), Failure> {
        if !self.all
            && (self.min_length.is_some()
                || self.min_area.is_some()
                || self.include_border
                || self.holes
                || self.min_strength.is_some()
                || self.corners.is_some()
                || self.table.is_some())
        {
            return Err(Failure::Error(
                "--min-length, --min-area, --include-border, --holes, --min-strength, --corners and --table go with --all"
                    .into(),
            ));
        }
        Ok(())
    }
}

/// `--polarity` read as the objects' phase (`auto`, `bright`, `dark`,
/// `bright-inside`, `dark-inside`).
pub fn object_polarity(text: &str) -> Result<ObjectPolarity, Failure> {
    Ok(text.parse()?)
}
