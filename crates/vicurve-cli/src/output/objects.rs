//! The outputs of `measure --all`: every object in one result file, the
//! samples with an `object` column, one table row per object, and the
//! overlays with every object's curve and id.

use super::overlay::{write_png_tagged, write_svg_tagged, Layer, Style, Tag};
use super::{sample_row, write_json, SAMPLE_COLUMNS};
use crate::args::Outputs;
use crate::failure::Failure;
use serde::Serialize;
use std::io::Write;
use std::path::Path;
use vicurve::model::ModelFit;
use vicurve::objects::{object_table, AllConfig, AllResult, Found, ObjectFailure, RegionInfo};
use vicurve::report::{InputInfo, ResultFile, CONVENTION};
use vicurve::Image;

/// The result file of `measure --all`.
#[derive(Serialize)]
struct AllFile<'a> {
    vicurve_version: &'static str,
    input: InputInfo<'a>,
    coordinates: &'static str,
    config: &'a AllConfig,
    found: &'a Found,
    measured: usize,
    failed: usize,
    objects: Vec<ObjectRecord<'a>>,
}

/// One object of [`AllFile`].
#[derive(Serialize)]
struct ObjectRecord<'a> {
    id: usize,
    outcome: String,
    failure: Option<&'a ObjectFailure>,
    message: Option<String>,
    region: &'a RegionInfo,
    /// The object's measurement, as `measure --out` writes one.
    result: Option<ResultFile<'a>>,
    model: Option<&'a ModelFit>,
}

/// Write `--out`, `--points`, `--table`, `--svg` and `--png` as asked;
/// independent, the first error reported.
pub fn write(
    all: &AllResult,
    config: &AllConfig,
    input: &str,
    image: &Image,
    outputs: &Outputs,
    table: Option<&Path>,
) -> Result<(), Failure> {
    let size = (image.width(), image.height());
    let mut first: Option<String> = None;
    let mut note = |r: Result<(), String>| {
        if let Err(e) = r {
            first.get_or_insert(e);
        }
    };
    if let Some(p) = &outputs.out {
        note(write_json(p, &record(all, config, input, size)));
    }
    if let Some(p) = &outputs.points {
        note(write_points(p, all));
    }
    if let Some(p) = table {
        note(write_table(p, all));
    }
    if outputs.svg.is_some() || outputs.png.is_some() {
        let (layers, tags) = overlay(all);
        if let Some(p) = &outputs.svg {
            note(write_svg_tagged(p, image, &layers, &tags));
        }
        if let Some(p) = &outputs.png {
            note(write_png_tagged(
                p,
                image,
                &layers,
                &tags,
                outputs.png_scale,
            ));
        }
    }
    first.map_or(Ok(()), |e| Err(Failure::Error(e)))
}

/// Every object's measured curve (red; orange for a failed object's last
/// curve, dashed blue for an object with no curve: its traced start) and
/// its id at its region's centroid.
fn overlay(all: &AllResult) -> (Vec<Layer>, Vec<Tag>) {
    let style = |color: [u8; 4], dash: Option<[f32; 2]>| Style {
        color,
        width: 1.0,
        dash,
    };
    let mut layers = Vec::new();
    let mut tags = Vec::new();
    for o in &all.objects {
        let (label, points, closed, st) = match (&o.measurement, &o.start) {
            (Some(m), _) if o.failure.is_none() => (
                "measured object (id at its centre)",
                m.points(),
                m.curve.is_closed(),
                style([255, 40, 40, 255], None),
            ),
            (Some(m), _) => (
                "failed object, its last curve",
                m.points(),
                m.curve.is_closed(),
                style([255, 150, 0, 255], None),
            ),
            (None, Some(init)) => (
                "failed object, its start",
                init.dense_points(1.0).unwrap_or_default(),
                init.is_closed(),
                style([40, 120, 255, 255], Some([4.0, 3.0])),
            ),
            (None, None) => continue,
        };
        layers.push(Layer {
            label: label.into(),
            points,
            closed,
            style: st,
        });
        let color = if o.failure.is_none() {
            [255, 40, 40]
        } else {
            [255, 150, 0]
        };
        tags.push(Tag {
            at: o.region.centroid,
            text: o.id.to_string(),
            color,
        });
    }
    (layers, tags)
}

fn record<'a>(
    all: &'a AllResult,
    config: &'a AllConfig,
    input: &'a str,
    size: (usize, usize),
) -> AllFile<'a> {
    let objects = all
        .objects
        .iter()
        .map(|o| ObjectRecord {
            id: o.id,
            outcome: o.outcome(),
            failure: o.failure.as_ref(),
            message: o.failure.as_ref().map(|f| f.to_string()),
            region: &o.region,
            result: match (&o.start, &o.measurement) {
                (Some(init), Some(m)) => Some(ResultFile::new(input, size, init, &o.config, m)),
                _ => None,
            },
            model: o.model.as_ref(),
        })
        .collect();
    AllFile {
        vicurve_version: env!("CARGO_PKG_VERSION"),
        input: InputInfo {
            path: input,
            width: size.0,
            height: size.1,
        },
        coordinates: CONVENTION,
        config,
        found: &all.found,
        measured: all.objects.len() - all.failed(),
        failed: all.failed(),
        objects,
    }
}

/// The samples of every measured object: the columns of `measure
/// --points` after `object` (its id); failed objects are left out.
fn write_points(path: &Path, all: &AllResult) -> Result<(), String> {
    let err = |e: std::io::Error| format!("cannot write {}: {e}", path.display());
    let file = std::fs::File::create(path).map_err(err)?;
    let mut w = std::io::BufWriter::new(file);
    writeln!(w, "object,{SAMPLE_COLUMNS}").map_err(err)?;
    for o in all.objects.iter().filter(|o| o.failure.is_none()) {
        let Some(m) = &o.measurement else { continue };
        for s in &m.samples {
            writeln!(w, "{},{}", o.id, sample_row(s)).map_err(err)?;
        }
    }
    w.flush().map_err(err)
}

/// One row per object ([`object_table`]): `id,outcome`, the numeric
/// columns, then `message` (quoted).
fn write_table(path: &Path, all: &AllResult) -> Result<(), String> {
    let t = object_table(all);
    let err = |e: std::io::Error| format!("cannot write {}: {e}", path.display());
    let file = std::fs::File::create(path).map_err(err)?;
    let mut w = std::io::BufWriter::new(file);
    let names: Vec<&str> = t.columns.iter().map(|(n, _)| n.as_str()).collect();
    writeln!(w, "id,outcome,{},message", names[1..].join(",")).map_err(err)?;
    for (k, outcome) in t.outcome.iter().enumerate() {
        let values: Vec<String> = t.columns[1..]
            .iter()
            .map(|(_, v)| format_value(v[k]))
            .collect();
        writeln!(
            w,
            "{},{},{},\"{}\"",
            t.columns[0].1[k],
            outcome,
            values.join(","),
            t.message[k].replace('"', "'")
        )
        .map_err(err)?;
    }
    w.flush().map_err(err)
}

/// A table value: empty for NaN (a value that does not exist).
pub fn format_value(v: f64) -> String {
    if v.is_finite() {
        format!("{v:.6e}")
    } else {
        String::new()
    }
}
