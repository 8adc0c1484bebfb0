//! The outputs of `measure --all`: every object in one result file, the
//! samples with an `object` column, one table row per object.

use super::write_json;
use crate::failure::Failure;
use serde::Serialize;
use std::io::Write;
use std::path::Path;
use vicurve::model::ModelFit;
use vicurve::objects::{object_table, AllConfig, AllResult, Found, ObjectFailure, RegionInfo};
use vicurve::report::{InputInfo, ResultFile, CONVENTION};

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

/// Write `--out`, `--points` and `--table` as asked; independent, the
/// first error reported.
pub fn write(
    all: &AllResult,
    config: &AllConfig,
    input: &str,
    size: (usize, usize),
    out: Option<&Path>,
    points: Option<&Path>,
    table: Option<&Path>,
) -> Result<(), Failure> {
    let mut first: Option<String> = None;
    let mut note = |r: Result<(), String>| {
        if let Err(e) = r {
            first.get_or_insert(e);
        }
    };
    if let Some(p) = out {
        note(write_json(p, &record(all, config, input, size)));
    }
    if let Some(p) = points {
        note(write_points(p, all));
    }
    if let Some(p) = table {
        note(write_table(p, all));
    }
    first.map_or(Ok(()), |e| Err(Failure::Error(e)))
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
    writeln!(w, "object,s,x,y,nx,ny,sigma,weight,sigma_noise,misfit").map_err(err)?;
    for o in all.objects.iter().filter(|o| o.failure.is_none()) {
        let Some(m) = &o.measurement else { continue };
        for s in &m.samples {
            writeln!(
                w,
                "{},{:.6},{:.6},{:.6},{:.6},{:.6},{:.3e},{:.3},{:.3e},{}",
                o.id,
                s.s,
                s.x,
                s.y,
                s.nx,
                s.ny,
                s.sigma,
                s.weight,
                s.sigma_noise,
                u8::from(s.misfit)
            )
            .map_err(err)?;
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
