//! The plots of a sequence's widths: for each width of the job, one figure
//! `DIR/NAME.svg` and `DIR/NAME.png` with two panels, the width profiles of
//! the frames overlaid (width against position along the axis) and the
//! minimum width against the frame. Linear axes; at most [`MAX_PROFILES`]
//! profiles are drawn, evenly spread over the sequence (the first and the
//! last included), in colours from blue (first) to red (last).
//!
//! The data are read back from the frames' width CSVs and the summary's
//! rows, so a resumed run plots the whole sequence.

use crate::plot::{write_png_with, write_svg_with, Anchor, Canvas};
use std::path::Path;
use vicurve::sequence::run::job::Job;
use vicurve::sequence::run::summary::{split_csv, COLUMNS};

/// Most profiles drawn in one panel.
pub const MAX_PROFILES: usize = 12;

const PANEL_W: f64 = 470.0;
const PANEL_H: f64 = 380.0;
const MARGIN_L: f64 = 78.0;
const MARGIN_R: f64 = 18.0;
const MARGIN_T: f64 = 34.0;
const MARGIN_B: f64 = 52.0;
const TITLE_H: f64 = 34.0;
const LEGEND_W: f64 = 230.0;
const FONT: f64 = 13.0;

/// A linear axis mapping data to canvas units, its range extended to
/// round ticks.
#[derive(Clone, Copy, Debug)]
struct LinAxis {
    lo: f64,
    hi: f64,
    step: f64,
    from: f64,
    to: f64,
}

impl LinAxis {
    fn new(values: impl Iterator<Item = f64>, from: f64, to: f64) -> LinAxis {
        let (mut lo, mut hi) = (f64::INFINITY, f64::NEG_INFINITY);
        for v in values.filter(|v| v.is_finite()) {
            lo = lo.min(v);
            hi = hi.max(v);
        }
        if !lo.is_finite() {
            (lo, hi) = (0.0, 1.0);
        }
        if hi - lo < 1e-9 * (1.0 + lo.abs()) {
            (lo, hi) = (lo - 0.5, hi + 0.5);
        }
        let raw = (hi - lo) / 6.0;
        let mag = 10f64.powf(raw.log10().floor());
        let step = [1.0, 2.0, 5.0, 10.0]
            .iter()
            .map(|k| k * mag)
            .find(|s| *s >= raw)
            .unwrap_or(10.0 * mag);
        LinAxis {
            lo: (lo / step).floor() * step,
            hi: (hi / step).ceil() * step,
            step,
            from,
            to,
        }
    }

    fn map(&self, v: f64) -> f64 {
        self.from + (v - self.lo) / (self.hi - self.lo) * (self.to - self.from)
    }

    fn ticks(&self) -> Vec<f64> {
        let n = ((self.hi - self.lo) / self.step).round() as i64;
        (0..=n).map(|k| self.lo + k as f64 * self.step).collect()
    }

    fn label(&self, v: f64) -> String {
        let decimals = (-self.step.log10().floor()).max(0.0) as usize;
        format!("{v:.decimals$}")
    }
}

/// Colour of frame `k` of `n`: blue to red.
fn ramp(k: usize, n: usize) -> [u8; 3] {
    let t = if n > 1 {
        k as f64 / (n - 1) as f64
    } else {
        0.0
    };
    let lerp = |a: f64, b: f64| (a + (b - a) * t).round() as u8;
    [lerp(31.0, 214.0), lerp(119.0, 39.0), lerp(180.0, 40.0)]
}

/// A series: its `(x, y)` points, colour, and whether it draws dots.
type Series = (Vec<(f64, f64)>, [u8; 3], bool);

/// One panel: title, labels and `(x, y)` series with their colours; a
/// series with `dots` draws its points.
struct Panel<'a> {
    title: &'a str,
    x_label: &'a str,
    y_label: &'a str,
    series: Vec<Series>,
}

fn draw_panel(c: &mut dyn Canvas, k: usize, p: &Panel) {
    let x0 = k as f64 * PANEL_W + MARGIN_L;
    let x1 = (k + 1) as f64 * PANEL_W - MARGIN_R;
    let y0 = TITLE_H + MARGIN_T;
    let y1 = TITLE_H + PANEL_H - MARGIN_B;
    let pts = || p.series.iter().flat_map(|s| s.0.iter());
    let ax = LinAxis::new(pts().map(|q| q.0), x0, x1);
    let ay = LinAxis::new(pts().map(|q| q.1), y1, y0);
    for v in ax.ticks() {
        let x = ax.map(v);
        c.line(&[(x, y0), (x, y1)], [225; 3], 0.6, false);
        c.line(&[(x, y1), (x, y1 + 4.0)], [0; 3], 1.0, false);
        c.text(
            x,
            y1 + 17.0,
            &ax.label(v),
            FONT - 2.0,
            Anchor::Middle,
            false,
        );
    }
    for v in ay.ticks() {
        let y = ay.map(v);
        c.line(&[(x0, y), (x1, y)], [225; 3], 0.6, false);
        c.line(&[(x0 - 4.0, y), (x0, y)], [0; 3], 1.0, false);
        c.text(
            x0 - 7.0,
            y + 4.0,
            &ay.label(v),
            FONT - 2.0,
            Anchor::End,
            false,
        );
    }
    c.line(
        &[(x0, y0), (x1, y0), (x1, y1), (x0, y1), (x0, y0)],
        [0; 3],
        1.0,
        false,
    );
    c.text(
        (x0 + x1) / 2.0,
        y0 - 10.0,
        p.title,
        FONT,
        Anchor::Middle,
        false,
    );
    c.text(
        (x0 + x1) / 2.0,
        y1 + 38.0,
        p.x_label,
        FONT,
        Anchor::Middle,
        false,
    );
    c.text(
        x0 - 58.0,
        (y0 + y1) / 2.0,
        p.y_label,
        FONT,
        Anchor::Middle,
        true,
    );
    for (points, rgb, dots) in &p.series {
        let mapped: Vec<(f64, f64)> = points
            .iter()
            .filter(|q| q.0.is_finite() && q.1.is_finite())
            .map(|q| (ax.map(q.0), ay.map(q.1)))
            .collect();
        c.line(&mapped, *rgb, if *dots { 0.8 } else { 1.4 }, false);
        if *dots {
            for q in &mapped {
                c.dot(q.0, q.1, 3.0, *rgb);
            }
        }
    }
}

/// Write the figures of every width of `job`; `lines` are the summary's
/// rows per frame.
pub fn write_plots(job: &Job, stems: &[String], lines: &[Vec<String>]) -> Result<(), String> {
    let col = |name: &str| COLUMNS.iter().position(|c| *c == name).unwrap_or(0);
    let (c_curve, c_outcome) = (col("curve"), col("outcome"));
    let (c_min, c_pos) = (col("min_width"), col("min_width_position"));
    for w in &job.widths {
        // (frame index, stem, minimum width and its position) of the frames
        // whose width was measured.
        let mut frames: Vec<(usize, &str, f64, f64)> = Vec::new();
        for (i, (stem, rows)) in stems.iter().zip(lines).enumerate() {
            for l in rows {
                let cells = split_csv(l);
                let cell = |k: usize| cells.get(k).map(String::as_str).unwrap_or("");
                if cell(c_curve) == w.name && cell(c_outcome) == "measured" {
                    let num = |k: usize| cell(k).parse::<f64>().unwrap_or(f64::NAN);
                    frames.push((i, stem, num(c_min), num(c_pos)));
                }
            }
        }
        if frames.is_empty() {
            continue;
        }
        let n = frames.len();
        let shown: Vec<usize> = if n <= MAX_PROFILES {
            (0..n).collect()
        } else {
            let mut v: Vec<usize> = (0..MAX_PROFILES)
                .map(|k| (k * (n - 1) + (MAX_PROFILES - 1) / 2) / (MAX_PROFILES - 1))
                .collect();
            v.dedup();
            v
        };
        let mut profiles = Vec::new();
        for &k in &shown {
            let (_, stem, _, _) = frames[k];
            let path = job.out_dir.join(format!("{stem}.{}.csv", w.name));
            profiles.push((read_profile(&path)?, ramp(k, n), false));
        }
        let mins: Vec<(f64, f64)> = frames.iter().map(|f| (f.0 as f64, f.2)).collect();
        let (ca, cb) = (
            &job.curves[w.between[0]].name,
            &job.curves[w.between[1]].name,
        );
        let title = if w.name == "width" {
            format!("width between {ca} and {cb}")
        } else {
            format!("{}: width between {ca} and {cb}", w.name)
        };
        let profile_panel = Panel {
            title: "width profile per frame",
            x_label: "position along the axis (px)",
            y_label: "width (px)",
            series: profiles,
        };
        let mut min_series: Vec<Series> = vec![(mins.clone(), [120; 3], false)];
        for (k, q) in mins.iter().enumerate() {
            min_series.push((vec![*q], ramp(k, n), true));
        }
        let min_panel = Panel {
            title: "minimum width",
            x_label: "frame",
            y_label: "minimum width (px)",
            series: min_series,
        };
        let legend: Vec<(String, [u8; 3])> = shown
            .iter()
            .map(|&k| {
                let (_, stem, min, _) = frames[k];
                (format!("{stem} ({min:.2})"), ramp(k, n))
            })
            .collect();
        let (wd, ht) = (2.0 * PANEL_W + LEGEND_W, PANEL_H + TITLE_H);
        let paint = |c: &mut dyn Canvas| {
            c.text(wd / 2.0, 22.0, &title, FONT + 3.0, Anchor::Middle, false);
            draw_panel(c, 0, &profile_panel);
            draw_panel(c, 1, &min_panel);
            let lx = 2.0 * PANEL_W + 4.0;
            let mut ly = TITLE_H + MARGIN_T + 4.0;
            c.text(
                lx,
                ly,
                "frame (minimum, px)",
                FONT - 3.0,
                Anchor::Start,
                false,
            );
            for (label, rgb) in &legend {
                ly += 18.0;
                c.line(&[(lx, ly - 4.0), (lx + 18.0, ly - 4.0)], *rgb, 1.6, false);
                c.text(lx + 24.0, ly, label, FONT - 3.0, Anchor::Start, false);
            }
        };
        write_svg_with(wd, ht, &job.out_dir.join(format!("{}.svg", w.name)), paint)?;
        write_png_with(wd, ht, &job.out_dir.join(format!("{}.png", w.name)), paint)?;
    }
    Ok(())
}

/// `(position, width)` of a width CSV.
fn read_profile(path: &Path) -> Result<Vec<(f64, f64)>, String> {
    let text = std::fs::read_to_string(path)
        .map_err(|e| format!("cannot read {}: {e}", path.display()))?;
    Ok(text
        .lines()
        .skip(1)
        .filter_map(|l| {
            let mut it = l.split(',');
            let p = it.next()?.parse().ok()?;
            let w = it.next()?.parse().ok()?;
            Some((p, w))
        })
        .collect())
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn round_ticks_cover_the_data() {
        let a = LinAxis::new([3.2, 97.0].into_iter(), 0.0, 100.0);
        assert_eq!((a.lo, a.hi, a.step), (0.0, 100.0, 20.0));
        assert_eq!(a.ticks().len(), 6);
        assert_eq!(a.label(40.0), "40");
        let b = LinAxis::new([75.91, 76.48, f64::NAN].into_iter(), 0.0, 1.0);
        assert_eq!(b.step, 0.1);
        assert!(b.lo <= 75.91 && b.hi >= 76.48);
        assert_eq!(b.label(75.9), "75.9");
        let c = LinAxis::new([5.0].into_iter(), 0.0, 1.0);
        assert!(c.lo < 5.0 && c.hi > 5.0);
    }
}
