//! `measure --diagnostics DIR`: the measurement's band unwrapped on the
//! measured curve's `(s, r)` grid ([`vicurve::diagnostics`]) and the
//! convergence of its stages, as PNG files with a JSON record of what they
//! show (docs/diagnostics.md describes each file):
//!
//! * `band.png`: the image on the grid, gray, scaled to the image's gray
//!   range (s horizontal, r vertical, inside at the top);
//! * `residual.png`: `image - virtual image`, diverging colours on a
//!   symmetric scale (recorded);
//! * `weights.png`: the robust weights, black 0 to white 1;
//! * `convergence.png`: `max |dLambda|` and the residual RMS against the
//!   iteration, one line per stage (log axes);
//! * `diagnostics.json`: grid, scales, colour maps, the stages' histories,
//!   configuration, input and coordinate convention.
//!
//! One PNG pixel per grid cell (`ds` by `dr` pixels of the image). A fit
//! in which no iteration succeeded has no band to unwrap: it gets the plot
//! and the JSON (saying why) only, with a warning, and keeps its exit
//! status.

use super::write_json;
use crate::plot::maps::{diverging_rgb, gray_rgb, symmetric_scale, write_rgb_png};
use crate::plot::{Figure, Panel, Series};
use serde::Serialize;
use std::path::Path;
use vicurve::curve::InitialCurve;
use vicurve::diagnostics::{unwrap_band, UnwrapConfig, UnwrappedBand, GRID_CONVENTION};
use vicurve::fit::{FitConfig, IterationRecord, Measurement, Outcome};
use vicurve::report::{InputInfo, CONVENTION};
use vicurve::virtual_image::Profile;
use vicurve::Image;

/// The JSON record, written as `diagnostics.json`.
#[derive(Serialize)]
struct Record<'a> {
    vicurve_version: &'static str,
    input: InputInfo<'a>,
    coordinates: &'static str,
    #[serde(flatten)]
    maps: Option<Maps>,
    /// Why there are no maps (a fit in which no iteration succeeded).
    #[serde(skip_serializing_if = "Option::is_none")]
    maps_missing: Option<String>,
    convergence_png: ConvergenceNote,
    stages: Vec<StageHistory<'a>>,
    initial_curve: &'a InitialCurve,
    config: &'a FitConfig,
}

/// The part of the record about the unwrapped band.
#[derive(Serialize)]
struct Maps {
    grid: Grid,
    virtual_image: VirtualImage,
    band_png: MapNote,
    residual_png: MapNote,
    weights_png: MapNote,
    /// RMS of the residual over the grid, gray levels.
    residual_rms: f64,
    /// Grid cells outside the image (magenta in the maps).
    outside_cells: usize,
}

#[derive(Serialize)]
struct Grid {
    convention: &'static str,
    ds: f64,
    dr: f64,
    half_width: f64,
    columns: usize,
    rows: usize,
    /// `s` of the first and last column, pixels.
    s_range: [f64; 2],
    /// `r` of the first (top) and last (bottom) row, pixels.
    r_range: [f64; 2],
    requested: UnwrapConfig,
}

#[derive(Serialize)]
struct VirtualImage {
    profile: Profile,
    /// Band half-width `R` of the last stage, pixels.
    half_width: f64,
    varying_levels: bool,
    /// The last stage's gray levels (those used when they do not vary).
    a: f64,
    c: f64,
}

/// What a map PNG shows and how values map to colours.
#[derive(Serialize)]
struct MapNote {
    file: &'static str,
    shows: &'static str,
    colours: &'static str,
    /// Values mapped to the two ends of the colour map.
    scale: [f64; 2],
    #[serde(skip_serializing_if = "Option::is_none")]
    robust_scale: Option<f64>,
}

#[derive(Serialize)]
struct ConvergenceNote {
    file: &'static str,
    shows: &'static str,
    tolerance: f64,
}

#[derive(Serialize)]
struct StageHistory<'a> {
    half_width: f64,
    profile: Profile,
    elements: usize,
    outcome: Outcome,
    iterations: usize,
    history: &'a [IterationRecord],
}

/// Write the diagnostics of `m` into `dir` (created if missing). Errors are
/// one line naming the file or directory. A measurement without a band to
/// unwrap (no iteration succeeded) gets the convergence plot and the JSON
/// only, with a warning.
pub fn write(
    dir: &Path,
    image_path: &str,
    image: &Image,
    init: &InitialCurve,
    config: &FitConfig,
    m: &Measurement,
) -> Result<(), String> {
    std::fs::create_dir_all(dir).map_err(|e| {
        format!(
            "cannot create the diagnostics directory {}: {e}",
            dir.display()
        )
    })?;
    let grid = UnwrapConfig::default();
    let (maps, maps_missing) = match unwrap_band(image, m, config, &grid) {
        Ok(band) => (Some(write_maps(dir, image, m, &band, grid)?), None),
        Err(e) => {
            eprintln!(
                "vicurve: warning: diagnostics: {e}; band.png, residual.png and weights.png not written"
            );
            (None, Some(e.to_string()))
        }
    };
    crate::plot::write_png(&convergence_figure(m, config), &dir.join("convergence.png"))?;
    let record = Record {
        vicurve_version: env!("CARGO_PKG_VERSION"),
        input: InputInfo {
            path: image_path,
            width: image.width(),
            height: image.height(),
        },
        coordinates: CONVENTION,
        maps,
        maps_missing,
        convergence_png: ConvergenceNote {
            file: "convergence.png",
            shows: "max |dLambda| (px) and residual RMS against the iteration within each stage, log axes, one line per stage; refinement and reweighting runs restart from the current curve (see each record's run)",
            tolerance: config.tolerance,
        },
        stages: m
            .stages
            .iter()
            .map(|s| StageHistory {
                half_width: s.half_width,
                profile: s.profile,
                elements: s.elements,
                outcome: s.outcome,
                iterations: s.iterations,
                history: &s.history,
            })
            .collect(),
        initial_curve: init,
        config,
    };
    write_json(&dir.join("diagnostics.json"), &record)
}

/// Write the three maps of `band` and describe them.
fn write_maps(
    dir: &Path,
    image: &Image,
    m: &Measurement,
    band: &UnwrappedBand,
    grid: UnwrapConfig,
) -> Result<Maps, String> {
    let (lo, hi) = image.min_max();
    let (w, h) = (band.columns, band.rows);
    write_rgb_png(&dir.join("band.png"), w, h, &gray_rgb(&band.image, lo, hi))?;
    let scale = symmetric_scale(&band.residual);
    let residual = diverging_rgb(&band.residual, scale);
    write_rgb_png(&dir.join("residual.png"), w, h, &residual)?;
    let weights = gray_rgb(&band.weight, 0.0, 1.0);
    write_rgb_png(&dir.join("weights.png"), w, h, &weights)?;
    let last = m.stages.last();
    let map = |file, shows, colours, scale| MapNote {
        file,
        shows,
        colours,
        scale,
        robust_scale: None,
    };
    Ok(Maps {
        grid: Grid {
            convention: GRID_CONVENTION,
            ds: band.ds,
            dr: band.dr,
            half_width: band.half_width,
            columns: band.columns,
            rows: band.rows,
            s_range: [0.0, band.s(band.columns.saturating_sub(1))],
            r_range: [band.r(0), band.r(band.rows - 1)],
            requested: grid,
        },
        virtual_image: VirtualImage {
            profile: band.profile,
            half_width: band.fit_half_width,
            varying_levels: band.varying_levels,
            a: last.map_or(f64::NAN, |s| s.a),
            c: last.map_or(f64::NAN, |s| s.c),
        },
        band_png: map(
            "band.png",
            "the image interpolated on the grid (as the fit interpolates it)",
            "gray: black at the image's smallest gray level, white at its largest; magenta: outside the image",
            [lo, hi],
        ),
        residual_png: map(
            "residual.png",
            "image - virtual image, gray levels",
            "blue (image darker than the virtual image) - white (0) - red (brighter), saturated beyond the scale (the 99th percentile of |residual|); magenta: outside the image",
            [-scale, scale],
        ),
        weights_png: MapNote {
            robust_scale: band.robust_scale,
            ..map(
                "weights.png",
                "the robust (Tukey) weight of each cell's residual; all 1 when the band holds no clutter (the fit does not reweight then)",
                "gray: black 0 (rejected) to white 1 (kept whole); magenta: outside the image",
                [0.0, 1.0],
            )
        },
        residual_rms: band.residual_rms(),
        outside_cells: band.outside,
    })
}

/// Two panels, `max |dLambda|` and residual RMS against the iteration
/// (from 1), one series per stage (labelled by its band half-width, with
/// `(x)` when it did not converge).
fn convergence_figure(m: &Measurement, config: &FitConfig) -> Figure {
    let series = |value: fn(&IterationRecord) -> f64| -> Vec<Series> {
        m.stages
            .iter()
            .enumerate()
            .map(|(k, s)| Series {
                label: format!(
                    "{}: R = {} px{}",
                    k + 1,
                    s.half_width,
                    if s.outcome.is_converged() { "" } else { " (x)" }
                ),
                points: s
                    .history
                    .iter()
                    .map(|rec| ((rec.iteration + 1) as f64, value(rec)))
                    .collect(),
            })
            .collect()
    };
    Figure {
        title: format!(
            "Convergence (tolerance {:.0e} px; (x): not converged)",
            config.tolerance
        ),
        legend_title: "Stage".into(),
        panels: vec![
            Panel {
                title: "Step".into(),
                x_label: "iteration within the stage".into(),
                y_label: "max |dLambda| (px)".into(),
                series: series(|r| r.max_step),
            },
            Panel {
                title: "Residual".into(),
                x_label: "iteration within the stage".into(),
                y_label: "residual RMS (gray)".into(),
                series: series(|r| r.residual_rms),
            },
        ],
    }
}
