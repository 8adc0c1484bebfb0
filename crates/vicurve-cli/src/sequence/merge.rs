//! `vicurve merge DIR...`: the parts of a job run with `run --shard K/N`
//! joined into the `summary.csv` a single run writes.
//!
//! Each part wrote its rows to `summary.shard-K-of-N.csv` and the job's
//! manifest to `job.json`; the parts must be of one job (the same
//! fingerprint) and all present (every K from 1 to N once). Their rows are
//! joined in the order of K, which is the order of the frames: the merged
//! summary is the single run's, byte for byte.

use crate::failure::Failure;
use std::path::{Path, PathBuf};
use vicurve::sequence::run::job::{MANIFEST_STEM, SUMMARY_STEM};
use vicurve::sequence::run::resume::read_fingerprint;
use vicurve::sequence::run::summary::{first_cell, header, status, write_summary};

/// One part found in a folder.
struct Part {
    index: usize,
    count: usize,
    path: PathBuf,
}

/// Join the parts found in `dirs` into `out/summary.csv`.
pub fn merge(dirs: &[PathBuf], out: &Path) -> Result<(), Failure> {
    let mut parts = Vec::new();
    let mut fingerprint: Option<(String, PathBuf)> = None;
    for dir in dirs {
        let found = parts_in(dir)?;
        if found.is_empty() {
            continue;
        }
        let manifest = dir.join(format!("{MANIFEST_STEM}.json"));
        let f = read_fingerprint(&manifest).ok_or_else(|| {
            format!(
                "{}: no readable job manifest next to the parts",
                manifest.display()
            )
        })?;
        match &fingerprint {
            Some((g, first)) if *g != f => {
                return Err(Failure::Error(format!(
                    "{} and {} hold parts of different jobs (the job manifests differ)",
                    first.display(),
                    dir.display()
                )))
            }
            _ => fingerprint = Some((f, dir.clone())),
        }
        parts.extend(found);
    }
    let Some(count) = parts.first().map(|p| p.count) else {
        return Err(Failure::Error(format!(
            "no {SUMMARY_STEM}.shard-K-of-N.csv in {} (run the job with --shard K/N first)",
            dirs.iter()
                .map(|d| d.display().to_string())
                .collect::<Vec<_>>()
                .join(", ")
        )));
    };
    parts.sort_by_key(|p| p.index);
    for k in 1..=count {
        let n = parts
            .iter()
            .filter(|p| p.index == k && p.count == count)
            .count();
        if n != 1 {
            return Err(Failure::Error(format!(
                "part {k} of {count}: {} found (each part once, and all of one split)",
                if n == 0 { "none" } else { "several" }
            )));
        }
    }
    if parts.len() != count {
        return Err(Failure::Error(format!(
            "parts of different splits (of {count} and others): merge the parts of one run"
        )));
    }
    let mut lines: Vec<Vec<String>> = Vec::new();
    for p in &parts {
        let text = std::fs::read_to_string(&p.path)
            .map_err(|e| format!("cannot read {}: {e}", p.path.display()))?;
        let mut it = text.lines();
        if it.next() != Some(header().as_str()) {
            return Err(Failure::Error(format!(
                "{}: not a summary of this version of vicurve (its header differs)",
                p.path.display()
            )));
        }
        // One entry per frame (rows of a frame are consecutive).
        let mut last: Option<String> = None;
        for line in it.filter(|l| !l.is_empty()) {
            let frame = first_cell(line);
            if last.as_deref() != Some(frame.as_str()) {
                lines.push(Vec::new());
                last = Some(frame);
            }
            if let Some(l) = lines.last_mut() {
                l.push(line.to_string());
            }
        }
    }
    std::fs::create_dir_all(out)
        .map_err(|e| format!("cannot create the output folder {}: {e}", out.display()))?;
    let summary = out.join(format!("{SUMMARY_STEM}.csv"));
    write_summary(&summary, &lines)?;
    eprintln!(
        "vicurve: {count} part(s) merged into {} ({} frame(s))",
        summary.display(),
        lines.len()
    );
    super::exit_status(status(&lines, lines.len(), &summary))
}

/// The parts' summaries in `dir`.
fn parts_in(dir: &Path) -> Result<Vec<Part>, Failure> {
    let entries = std::fs::read_dir(dir)
        .map_err(|e| format!("cannot read the folder {}: {e}", dir.display()))?;
    let prefix = format!("{SUMMARY_STEM}.shard-");
    let mut parts = Vec::new();
    for e in entries.flatten() {
        let name = e.file_name().to_string_lossy().into_owned();
        let Some(rest) = name
            .strip_prefix(&prefix)
            .and_then(|r| r.strip_suffix(".csv"))
        else {
            continue;
        };
        let Some((k, n)) = rest.split_once("-of-") else {
            continue;
        };
        if let (Ok(index), Ok(count)) = (k.parse(), n.parse()) {
            parts.push(Part {
                index,
                count,
                path: e.path(),
            });
        }
    }
    Ok(parts)
}
