//! `summary.csv`: one row per curve and per width of every frame.
//!
//! The columns are a contract (tools read them by name): [`COLUMNS`].
//! Curve rows fill the fit's columns and, for closed curves, the derived
//! measures; width rows (the `curve` column holds the width's name) fill
//! the `min_width` columns. Cells that do not apply are empty. Lengths are
//! pixels, angles degrees (counterclockwise on screen from `+x`).

use crate::derived::{ClosedMeasures, WidthSample};
use crate::error::{Error, Result};
use crate::fit::{Measurement, Outcome};
use crate::io::write_atomic;
use std::collections::HashMap;
use std::path::Path;

/// The header of `summary.csv`, in order.
pub const COLUMNS: [&str; 34] = [
    "frame",
    "curve",
    "outcome",
    "reason",
    "started_from",
    "iterations",
    "residual",
    "length",
    "area",
    "centroid_x",
    "centroid_y",
    "equivalent_diameter",
    "circle_cx",
    "circle_cy",
    "circle_r",
    "circle_sigma_cx",
    "circle_sigma_cy",
    "circle_sigma_r",
    "circle_rms",
    "ellipse_cx",
    "ellipse_cy",
    "ellipse_a",
    "ellipse_b",
    "ellipse_angle_deg",
    "ellipse_sigma_cx",
    "ellipse_sigma_cy",
    "ellipse_sigma_a",
    "ellipse_sigma_b",
    "ellipse_sigma_angle_deg",
    "ellipse_rms",
    "min_width",
    "min_width_sigma",
    "min_width_position",
    "width_samples",
];

/// One row being filled.
#[derive(Clone, Debug, PartialEq)]
pub struct Row {
    cells: Vec<String>,
}

impl Row {
    /// A row for `frame` and `curve` (or width) with only those cells set.
    pub fn new(frame: &str, curve: &str) -> Row {
        let mut cells = vec![String::new(); COLUMNS.len()];
        cells[0] = frame.to_string();
        cells[1] = curve.to_string();
        Row { cells }
    }

    fn set(&mut self, column: &str, value: String) {
        if let Some(i) = COLUMNS.iter().position(|c| *c == column) {
            self.cells[i] = value;
        }
    }

    fn num(&mut self, column: &str, v: f64) {
        self.set(
            column,
            if v.is_finite() {
                format!("{v:.6}")
            } else {
                String::new()
            },
        );
    }

    fn sci(&mut self, column: &str, v: f64) {
        self.set(
            column,
            if v.is_finite() {
                format!("{v:.3e}")
            } else {
                String::new()
            },
        );
    }

    /// A failure: `outcome` is `failed` (nothing measured) or `diverged`.
    pub fn failed(mut self, outcome: &str, reason: &str) -> Row {
        self.set("outcome", outcome.into());
        self.set("reason", reason.into());
        self
    }

    /// A measured curve: fit columns, plus the derived measures of a
    /// closed curve as the result file has them (`closed`, or why there are
    /// none, which goes to `reason`).
    pub fn curve(
        mut self,
        m: &Measurement,
        started_from: &str,
        note: &str,
        closed: std::result::Result<Option<&ClosedMeasures>, &str>,
    ) -> Row {
        let (outcome, reason) = match m.outcome {
            Outcome::Converged => ("converged", String::new()),
            Outcome::IterationLimit => {
                ("iteration_limit", "the iteration limit was reached".into())
            }
            Outcome::Diverged { divergence } => ("diverged", divergence.to_string()),
        };
        let mut reasons: Vec<String> = [reason, note.to_string()]
            .into_iter()
            .filter(|r| !r.is_empty())
            .collect();
        self.set("outcome", outcome.into());
        self.set("started_from", started_from.into());
        self.set("iterations", m.iterations().to_string());
        self.sci("residual", m.residual_rms());
        self.num("length", m.length());
        if let Some(a) = m.area() {
            self.num("area", a);
        }
        match closed {
            Ok(Some(c)) => self.closed(c),
            Ok(None) => {}
            Err(e) => reasons.push(format!("no circle or ellipse: {e}")),
        }
        self.set("reason", reasons.join("; "));
        self
    }

    fn closed(&mut self, c: &ClosedMeasures) {
        self.num("centroid_x", c.centroid[0]);
        self.num("centroid_y", c.centroid[1]);
        self.num("equivalent_diameter", c.equivalent_diameter);
        let k = &c.circle;
        self.num("circle_cx", k.cx);
        self.num("circle_cy", k.cy);
        self.num("circle_r", k.r);
        self.sci("circle_sigma_cx", k.sigma_cx);
        self.sci("circle_sigma_cy", k.sigma_cy);
        self.sci("circle_sigma_r", k.sigma_r);
        self.sci("circle_rms", k.rms);
        let e = &c.ellipse;
        self.num("ellipse_cx", e.cx);
        self.num("ellipse_cy", e.cy);
        self.num("ellipse_a", e.a);
        self.num("ellipse_b", e.b);
        self.num("ellipse_angle_deg", e.angle.to_degrees());
        self.sci("ellipse_sigma_cx", e.sigma_cx);
        self.sci("ellipse_sigma_cy", e.sigma_cy);
        self.sci("ellipse_sigma_a", e.sigma_a);
        self.sci("ellipse_sigma_b", e.sigma_b);
        self.sci("ellipse_sigma_angle_deg", e.sigma_angle.to_degrees());
        self.sci("ellipse_rms", e.rms);
    }

    /// A width profile: its minimum (width, uncertainty, position along
    /// the axis) and how many sections it has.
    pub fn width(mut self, min: Option<&WidthSample>, count: usize) -> Row {
        self.set("outcome", "measured".into());
        self.set("width_samples", count.to_string());
        match min {
            Some(s) => {
                self.num("min_width", s.width);
                self.sci("min_width_sigma", s.sigma);
                self.num("min_width_position", s.position);
            }
            None => {
                self.set("outcome", "failed".into());
                self.set("reason", "the two curves have no section in common".into());
            }
        }
        self
    }

    /// The row as a CSV line (no newline).
    pub fn to_line(&self) -> String {
        self.cells
            .iter()
            .map(|c| csv_cell(c))
            .collect::<Vec<_>>()
            .join(",")
    }
}

/// The header line (no newline).
pub fn header() -> String {
    COLUMNS.join(",")
}

/// Quote a cell when it holds a comma, a quote or a line break.
fn csv_cell(text: &str) -> String {
    let clean = text.replace(['\n', '\r'], " ");
    if clean.contains([',', '"']) {
        format!("\"{}\"", clean.replace('"', "\"\""))
    } else {
        clean
    }
}

/// The first cell of a CSV line (quoted or not): the frame.
pub fn first_cell(line: &str) -> String {
    match line.strip_prefix('"') {
        Some(rest) => {
            let mut out = String::new();
            let mut chars = rest.chars().peekable();
            while let Some(c) = chars.next() {
                if c == '"' {
                    if chars.peek() == Some(&'"') {
                        out.push('"');
                        chars.next();
                    } else {
                        break;
                    }
                } else {
                    out.push(c);
                }
            }
            out
        }
        None => line.split(',').next().unwrap_or("").to_string(),
    }
}

/// The cells of a CSV line written here.
pub fn split_csv(line: &str) -> Vec<String> {
    let mut cells = Vec::new();
    let mut cur = String::new();
    let mut quoted = false;
    let mut chars = line.chars().peekable();
    while let Some(c) = chars.next() {
        match (c, quoted) {
            ('"', true) if chars.peek() == Some(&'"') => {
                cur.push('"');
                chars.next();
            }
            ('"', _) => quoted = !quoted,
            (',', false) => cells.push(std::mem::take(&mut cur)),
            _ => cur.push(c),
        }
    }
    cells.push(cur);
    cells
}

/// The cell of `column` (one of [`COLUMNS`]) in a row's cells
/// ([`split_csv`]); empty when there is no such column or cell.
pub fn cell<'a>(cells: &'a [String], column: &str) -> &'a str {
    COLUMNS
        .iter()
        .position(|c| *c == column)
        .and_then(|i| cells.get(i))
        .map_or("", String::as_str)
}

/// The rows of an existing summary by frame, when its header is today's
/// (else none: every frame is measured again).
pub fn read_summary(path: &Path) -> HashMap<String, Vec<String>> {
    let mut out: HashMap<String, Vec<String>> = HashMap::new();
    let Ok(text) = std::fs::read_to_string(path) else {
        return out;
    };
    let mut it = text.lines();
    if it.next() != Some(header().as_str()) {
        return out;
    }
    for line in it.filter(|l| !l.is_empty()) {
        out.entry(first_cell(line))
            .or_default()
            .push(line.to_string());
    }
    out
}

/// Write the summary (atomically): the header, then every frame's rows.
///
/// Errors: [`Error::Job`] naming the file when it cannot be written.
pub fn write_summary(path: &Path, lines: &[Vec<String>]) -> Result<()> {
    let mut text = header();
    text.push('\n');
    for l in lines.iter().flatten() {
        text.push_str(l);
        text.push('\n');
    }
    write_atomic(path, text.as_bytes()).map_err(Error::job)
}

/// How a sequence ended, from the `outcome` column of its rows (the
/// command line's exit status: 0, 3 and 1).
#[derive(Clone, Debug, PartialEq, Eq)]
pub enum RunStatus {
    /// Every frame measured.
    Complete,
    /// Some frames failed, the others are measured: how many and the
    /// first reason, in one line naming the summary.
    SomeFailed(String),
    /// No frame could be measured at all: the first reason, in one line.
    NoneMeasured(String),
}

/// The sequence's status, from the `outcome` column of its rows: frames
/// that failed or diverged, of `total`.
pub fn status(lines: &[Vec<String>], total: usize, summary: &Path) -> RunStatus {
    let outcome = COLUMNS.iter().position(|c| *c == "outcome").unwrap_or(2);
    let reason = COLUMNS.iter().position(|c| *c == "reason").unwrap_or(3);
    let mut failed_frames = 0;
    let mut good_rows = 0;
    let mut first: Option<String> = None;
    for frame in lines {
        let mut failed = false;
        for l in frame {
            let cells = split_csv(l);
            let o = cells.get(outcome).map(String::as_str).unwrap_or("");
            if o == "failed" || o == "diverged" {
                failed = true;
                if first.is_none() {
                    first = Some(format!(
                        "{} {}: {}",
                        cells.first().cloned().unwrap_or_default(),
                        cells.get(1).cloned().unwrap_or_default(),
                        cells.get(reason).cloned().unwrap_or_default()
                    ));
                }
            } else {
                good_rows += 1;
            }
        }
        failed_frames += usize::from(failed);
    }
    match (failed_frames, good_rows) {
        (0, _) => RunStatus::Complete,
        (_, 0) => RunStatus::NoneMeasured(format!(
            "no frame could be measured ({}); see {}",
            first.unwrap_or_default(),
            summary.display()
        )),
        (n, _) => RunStatus::SomeFailed(format!(
            "{n} of {total} frames failed (first: {}); the others are measured, see {}",
            first.unwrap_or_default(),
            summary.display()
        )),
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn cells_are_quoted_when_needed() {
        let r = Row::new("f,1", "top").failed("failed", "cannot decode \"x\", truncated");
        let line = r.to_line();
        assert!(line.starts_with("\"f,1\",top,failed,\"cannot decode \"\"x\"\", truncated\""));
        assert_eq!(first_cell(&line), "f,1");
        assert_eq!(line.matches(',').count(), COLUMNS.len() - 1 + 2);
        assert_eq!(first_cell("frame_003,top,converged"), "frame_003");
    }
}
