//! Figures: log–log line plots (the benchmark reports, the diagnostics'
//! convergence), as SVG and PNG; [`maps`]: colour maps of the diagnostics'
//! images.
//!
//! A [`Figure`] is a row of [`Panel`]s sharing one legend on the right. Both
//! axes of every panel are logarithmic (the paper's figures are): the range
//! is extended to whole decades, every decade is labelled, and when a panel
//! spans two decades or less the 2 and 5 multiples are labelled too. Points
//! that are not finite and positive cannot be shown on a log axis and are
//! left out (a series is broken there).
//!
//! One layout serves both outputs through the [`Canvas`] trait; the PNG is
//! drawn at twice the SVG's size with an 8x8 bitmap font (scaled) so that it
//! needs no font file.
//!
//! [`fld`]: the forming-limit scatter of `vicurve grid` (linear axes, SVG).

pub mod fld;
pub mod maps;

use font8x8::legacy::BASIC_LEGACY;
use std::fmt::Write as _;
use std::path::Path;
use tiny_skia::{LineCap, LineJoin, Paint, PathBuilder, Pixmap, Stroke, StrokeDash, Transform};

/// One line of a panel: `(x, y)` points in data units, drawn in order.
#[derive(Clone, Debug, PartialEq)]
pub struct Series {
    /// Legend text.
    pub label: String,
    /// The points, in the order they are joined.
    pub points: Vec<(f64, f64)>,
}

/// One plot: axes, labels and series (the series of every panel of a
/// figure share colours by index, and the legend).
#[derive(Clone, Debug, PartialEq)]
pub struct Panel {
    /// Title above the plot.
    pub title: String,
    /// Label of the horizontal axis.
    pub x_label: String,
    /// Label of the vertical axis.
    pub y_label: String,
    /// The lines.
    pub series: Vec<Series>,
}

/// Panels side by side with a legend on the right.
#[derive(Clone, Debug, PartialEq)]
pub struct Figure {
    /// Title above everything.
    pub title: String,
    /// Heading of the legend.
    pub legend_title: String,
    /// The panels, left to right.
    pub panels: Vec<Panel>,
}

const PANEL_W: f64 = 470.0;
const PANEL_H: f64 = 380.0;
const MARGIN_L: f64 = 78.0;
const MARGIN_R: f64 = 18.0;
const MARGIN_T: f64 = 34.0;
const MARGIN_B: f64 = 52.0;
const TITLE_H: f64 = 34.0;
const LEGEND_W: f64 = 190.0;
const FONT: f64 = 13.0;

/// Distinct colours for up to eight series (then they repeat).
pub(crate) const PALETTE: [[u8; 3]; 8] = [
    [31, 119, 180],
    [214, 39, 40],
    [44, 160, 44],
    [148, 103, 189],
    [255, 127, 14],
    [23, 190, 207],
    [140, 86, 75],
    [227, 119, 194],
];

/// Where text is anchored horizontally.
#[derive(Clone, Copy, Debug, PartialEq)]
pub(crate) enum Anchor {
    Start,
    Middle,
    End,
}

/// The drawing operations the layout needs (coordinates in SVG units, y
/// down).
pub(crate) trait Canvas {
    fn line(&mut self, pts: &[(f64, f64)], rgb: [u8; 3], width: f64, dash: bool);
    fn dot(&mut self, x: f64, y: f64, r: f64, rgb: [u8; 3]);
    /// Text whose baseline's anchor point is `(x, y)`; `vertical` turns it
    /// 90 degrees counter-clockwise (reading upwards).
    fn text(&mut self, x: f64, y: f64, s: &str, size: f64, anchor: Anchor, vertical: bool);
}

/// A log axis mapping data to canvas units.
#[derive(Clone, Copy, Debug)]
struct LogAxis {
    lo: f64,
    hi: f64,
    from: f64,
    to: f64,
}

impl LogAxis {
    /// Whole decades around the finite positive values (1..10 when none).
    fn new(values: impl Iterator<Item = f64>, from: f64, to: f64) -> LogAxis {
        let (mut lo, mut hi) = (f64::INFINITY, f64::NEG_INFINITY);
        for v in values.filter(|v| v.is_finite() && *v > 0.0) {
            lo = lo.min(v.log10());
            hi = hi.max(v.log10());
        }
        if !lo.is_finite() {
            (lo, hi) = (0.0, 1.0);
        }
        let (mut lo, mut hi) = ((lo + 1e-9).floor(), (hi - 1e-9).ceil());
        if hi <= lo {
            hi = lo + 1.0;
        }
        if hi - lo > 12.0 {
            lo = hi - 12.0;
        }
        LogAxis { lo, hi, from, to }
    }

    fn map(&self, v: f64) -> f64 {
        self.from + (v.log10() - self.lo) / (self.hi - self.lo) * (self.to - self.from)
    }

    /// `(value, labelled)` of every tick.
    fn ticks(&self) -> Vec<(f64, bool)> {
        let dense = self.hi - self.lo <= 2.0;
        let mut out = Vec::new();
        for d in self.lo as i32..=self.hi as i32 {
            for k in 1..10 {
                let v = f64::from(k) * 10f64.powi(d);
                if v.log10() > self.hi + 1e-9 {
                    break;
                }
                out.push((v, k == 1 || (dense && (k == 2 || k == 5))));
            }
        }
        out
    }
}

/// A tick value as text: plain between 0.01 and 10^4, else `m e d`.
fn tick_label(v: f64) -> String {
    if (1e-2..1e4).contains(&v) {
        let s = format!("{v:.3}");
        s.trim_end_matches('0').trim_end_matches('.').to_string()
    } else {
        let d = v.log10().floor();
        let m = (v / 10f64.powf(d)).round();
        format!("{m}e{d}")
    }
}

/// Size of a figure in SVG units.
fn figure_size(fig: &Figure) -> (f64, f64) {
    (
        fig.panels.len().max(1) as f64 * PANEL_W + LEGEND_W,
        PANEL_H + TITLE_H,
    )
}

/// Lay out and draw a figure.
fn draw(fig: &Figure, c: &mut dyn Canvas) {
    let (w, _) = figure_size(fig);
    c.text(w / 2.0, 22.0, &fig.title, FONT + 3.0, Anchor::Middle, false);
    for (k, panel) in fig.panels.iter().enumerate() {
        let x0 = k as f64 * PANEL_W + MARGIN_L;
        let x1 = (k + 1) as f64 * PANEL_W - MARGIN_R;
        let y0 = TITLE_H + MARGIN_T;
        let y1 = TITLE_H + PANEL_H - MARGIN_B;
        let pts = || panel.series.iter().flat_map(|s| s.points.iter());
        let ax = LogAxis::new(pts().map(|p| p.0), x0, x1);
        let ay = LogAxis::new(pts().map(|p| p.1), y1, y0);
        for (v, labelled) in ax.ticks() {
            let x = ax.map(v);
            let grey = if labelled { 200 } else { 232 };
            c.line(&[(x, y0), (x, y1)], [grey; 3], 0.6, false);
            c.line(&[(x, y1), (x, y1 + 4.0)], [0; 3], 1.0, false);
            if labelled {
                c.text(
                    x,
                    y1 + 17.0,
                    &tick_label(v),
                    FONT - 2.0,
                    Anchor::Middle,
                    false,
                );
            }
        }
        for (v, labelled) in ay.ticks() {
            let y = ay.map(v);
            let grey = if labelled { 200 } else { 232 };
            c.line(&[(x0, y), (x1, y)], [grey; 3], 0.6, false);
            c.line(&[(x0 - 4.0, y), (x0, y)], [0; 3], 1.0, false);
            if labelled {
                c.text(
                    x0 - 7.0,
                    y + 4.0,
                    &tick_label(v),
                    FONT - 2.0,
                    Anchor::End,
                    false,
                );
            }
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
            &panel.title,
            FONT,
            Anchor::Middle,
            false,
        );
        c.text(
            (x0 + x1) / 2.0,
            y1 + 38.0,
            &panel.x_label,
            FONT,
            Anchor::Middle,
            false,
        );
        c.text(
            x0 - 58.0,
            (y0 + y1) / 2.0,
            &panel.y_label,
            FONT,
            Anchor::Middle,
            true,
        );
        for (i, s) in panel.series.iter().enumerate() {
            let rgb = PALETTE[i % PALETTE.len()];
            let dashed = i >= PALETTE.len();
            let mut run: Vec<(f64, f64)> = Vec::new();
            for &(x, y) in &s.points {
                if x.is_finite() && x > 0.0 && y.is_finite() && y > 0.0 {
                    let p = (ax.map(x), ay.map(y));
                    c.dot(p.0, p.1, 2.5, rgb);
                    run.push(p);
                } else {
                    c.line(&run, rgb, 1.6, dashed);
                    run.clear();
                }
            }
            c.line(&run, rgb, 1.6, dashed);
        }
    }
    // Legend: the first panel's series (panels share them by index).
    let lx = fig.panels.len() as f64 * PANEL_W + 10.0;
    let mut ly = TITLE_H + MARGIN_T + 4.0;
    c.text(lx, ly, &fig.legend_title, FONT, Anchor::Start, false);
    if let Some(panel) = fig.panels.first() {
        for (i, s) in panel.series.iter().enumerate() {
            ly += 20.0;
            let rgb = PALETTE[i % PALETTE.len()];
            c.line(
                &[(lx, ly - 4.0), (lx + 24.0, ly - 4.0)],
                rgb,
                1.6,
                i >= PALETTE.len(),
            );
            c.dot(lx + 12.0, ly - 4.0, 2.5, rgb);
            c.text(lx + 32.0, ly, &s.label, FONT - 1.0, Anchor::Start, false);
        }
    }
}

/// An SVG document being written.
struct SvgCanvas(String);

impl Canvas for SvgCanvas {
    fn line(&mut self, pts: &[(f64, f64)], rgb: [u8; 3], width: f64, dash: bool) {
        if pts.len() < 2 {
            return;
        }
        let coords: Vec<String> = pts.iter().map(|(x, y)| format!("{x:.2},{y:.2}")).collect();
        let dash = if dash {
            " stroke-dasharray=\"6 4\""
        } else {
            ""
        };
        let _ = writeln!(
            self.0,
            "<polyline points=\"{}\" fill=\"none\" stroke=\"rgb({},{},{})\" stroke-width=\"{width}\"{dash}/>",
            coords.join(" "),
            rgb[0],
            rgb[1],
            rgb[2]
        );
    }

    fn dot(&mut self, x: f64, y: f64, r: f64, rgb: [u8; 3]) {
        let _ = writeln!(
            self.0,
            "<circle cx=\"{x:.2}\" cy=\"{y:.2}\" r=\"{r}\" fill=\"rgb({},{},{})\"/>",
            rgb[0], rgb[1], rgb[2]
        );
    }

    fn text(&mut self, x: f64, y: f64, s: &str, size: f64, anchor: Anchor, vertical: bool) {
        let anchor = match anchor {
            Anchor::Start => "start",
            Anchor::Middle => "middle",
            Anchor::End => "end",
        };
        let rotate = if vertical {
            format!(" transform=\"rotate(-90 {x:.2} {y:.2})\"")
        } else {
            String::new()
        };
        let _ = writeln!(
            self.0,
            "<text x=\"{x:.2}\" y=\"{y:.2}\" font-size=\"{size}\" text-anchor=\"{anchor}\"{rotate}>{}</text>",
            xml_escape(s)
        );
    }
}

/// A raster being drawn, `scale` pixels per SVG unit.
struct PngCanvas {
    pixmap: Pixmap,
    scale: f64,
}

/// Set the pixel `(x, y)` of `pixmap` to `rgb` (opaque); nothing outside.
fn set_pixel(pixmap: &mut Pixmap, x: i64, y: i64, rgb: [u8; 3]) {
    let (w, h) = (pixmap.width() as i64, pixmap.height() as i64);
    if (0..w).contains(&x) && (0..h).contains(&y) {
        let i = ((y * w + x) * 4) as usize;
        pixmap.data_mut()[i..i + 4].copy_from_slice(&[rgb[0], rgb[1], rgb[2], 255]);
    }
}

/// Draw `s` in `rgb` into `pixmap` with the 8x8 font scaled by the whole
/// factor `k`, the baseline's anchor point at pixel `(ox, oy)`; `vertical`
/// turns it 90 degrees counter-clockwise (reading upwards). Basic Latin
/// only; other characters are drawn as `?`.
pub(crate) fn draw_text(
    pixmap: &mut Pixmap,
    (ox, oy): (i64, i64),
    s: &str,
    k: i64,
    anchor: Anchor,
    vertical: bool,
    rgb: [u8; 3],
) {
    let advance = 8 * k;
    let len = s.chars().count() as i64 * advance;
    let shift = match anchor {
        Anchor::Start => 0,
        Anchor::Middle => len / 2,
        Anchor::End => len,
    };
    for (n, ch) in s.chars().enumerate() {
        let code = if ch.is_ascii() {
            ch as usize
        } else {
            '?' as usize
        };
        let glyph = BASIC_LEGACY[code];
        let along = n as i64 * advance - shift;
        for (row, bits) in glyph.iter().enumerate() {
            for col in 0..8 {
                if bits >> col & 1 == 0 {
                    continue;
                }
                // Cell position: `along + col` along the text, `row - 7`
                // from the baseline (the cell's last row is below it).
                let (u, v) = (along + col * k, (row as i64 - 7) * k);
                for du in 0..k {
                    for dv in 0..k {
                        let (px, py) = if vertical {
                            (ox + v + dv, oy - (u + du))
                        } else {
                            (ox + u + du, oy + v + dv)
                        };
                        set_pixel(pixmap, px, py, rgb);
                    }
                }
            }
        }
    }
}

impl Canvas for PngCanvas {
    fn line(&mut self, pts: &[(f64, f64)], rgb: [u8; 3], width: f64, dash: bool) {
        let s = self.scale;
        let mut b = PathBuilder::new();
        for (k, &(x, y)) in pts.iter().enumerate() {
            let (x, y) = ((x * s) as f32, (y * s) as f32);
            if k == 0 {
                b.move_to(x, y);
            } else {
                b.line_to(x, y);
            }
        }
        let Some(path) = b.finish() else { return };
        let mut paint = Paint::default();
        paint.set_color_rgba8(rgb[0], rgb[1], rgb[2], 255);
        paint.anti_alias = true;
        let stroke = Stroke {
            width: (width * s) as f32,
            line_cap: LineCap::Butt,
            line_join: LineJoin::Round,
            dash: if dash {
                StrokeDash::new(vec![(6.0 * s) as f32, (4.0 * s) as f32], 0.0)
            } else {
                None
            },
            ..Stroke::default()
        };
        self.pixmap
            .stroke_path(&path, &paint, &stroke, Transform::identity(), None);
    }

    fn dot(&mut self, x: f64, y: f64, r: f64, rgb: [u8; 3]) {
        let s = self.scale;
        if let Some(c) = PathBuilder::from_circle((x * s) as f32, (y * s) as f32, (r * s) as f32) {
            let mut paint = Paint::default();
            paint.set_color_rgba8(rgb[0], rgb[1], rgb[2], 255);
            paint.anti_alias = true;
            self.pixmap.fill_path(
                &c,
                &paint,
                tiny_skia::FillRule::Winding,
                Transform::identity(),
                None,
            );
        }
    }

    fn text(&mut self, x: f64, y: f64, s: &str, size: f64, anchor: Anchor, vertical: bool) {
        // Glyphs are 8 px cells scaled by a whole factor near the font size
        // (an 8 px cell's letters are about 7 px: size / 7 per unit).
        let k = ((size * self.scale / 9.0).round() as i64).max(1);
        let at = ((x * self.scale) as i64, (y * self.scale) as i64);
        draw_text(&mut self.pixmap, at, s, k, anchor, vertical, [0, 0, 0]);
    }
}

/// Write `fig` as an SVG file.
pub fn write_svg(fig: &Figure, path: &Path) -> Result<(), String> {
    let (w, h) = figure_size(fig);
    write_svg_with(w, h, path, |c| draw(fig, c))
}

/// Write a PNG of `fig`, twice the SVG's size.
pub fn write_png(fig: &Figure, path: &Path) -> Result<(), String> {
    let (w, h) = figure_size(fig);
    write_png_with(w, h, path, |c| draw(fig, c))
}

/// Write an SVG of `w x h` units drawn by `paint` (for other layouts than
/// [`Figure`]'s, sharing the canvases).
pub(crate) fn write_svg_with(
    w: f64,
    h: f64,
    path: &Path,
    paint: impl FnOnce(&mut dyn Canvas),
) -> Result<(), String> {
    let mut c = SvgCanvas(String::new());
    let _ = writeln!(
        c.0,
        "<svg xmlns=\"http://www.w3.org/2000/svg\" width=\"{w}\" height=\"{h}\" viewBox=\"0 0 {w} {h}\" font-family=\"sans-serif\">"
    );
    let _ = writeln!(c.0, "<rect width=\"{w}\" height=\"{h}\" fill=\"white\"/>");
    paint(&mut c);
    c.0.push_str("</svg>\n");
    std::fs::write(path, c.0).map_err(|e| format!("cannot write {}: {e}", path.display()))
}

/// Write a PNG of the `w x h` units drawn by `paint`, at twice that size.
pub(crate) fn write_png_with(
    w: f64,
    h: f64,
    path: &Path,
    paint: impl FnOnce(&mut dyn Canvas),
) -> Result<(), String> {
    let scale = 2.0;
    let fail = |e: String| format!("cannot write {}: {e}", path.display());
    let mut pixmap = Pixmap::new((w * scale) as u32, (h * scale) as u32)
        .ok_or_else(|| fail("cannot allocate the image".into()))?;
    pixmap.fill(tiny_skia::Color::WHITE);
    let mut c = PngCanvas { pixmap, scale };
    paint(&mut c);
    let png = c.pixmap.encode_png().map_err(|e| fail(e.to_string()))?;
    std::fs::write(path, png).map_err(|e| fail(e.to_string()))
}

fn xml_escape(text: &str) -> String {
    text.replace('&', "&amp;")
        .replace('<', "&lt;")
        .replace('>', "&gt;")
        .replace('"', "&quot;")
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn decades_cover_the_data() {
        let a = LogAxis::new([12.0, 95.0].into_iter(), 0.0, 100.0);
        assert_eq!((a.lo, a.hi), (1.0, 2.0));
        assert!((a.map(10.0) - 0.0).abs() < 1e-9);
        assert!((a.map(100.0) - 100.0).abs() < 1e-9);
        let labelled: Vec<f64> = a.ticks().iter().filter(|t| t.1).map(|t| t.0).collect();
        assert_eq!(labelled, vec![10.0, 20.0, 50.0, 100.0]);
        let b = LogAxis::new([3e-4, 2e-2, -1.0, f64::NAN].into_iter(), 0.0, 1.0);
        assert_eq!((b.lo, b.hi), (-4.0, -1.0));
    }

    #[test]
    fn tick_labels() {
        assert_eq!(tick_label(10.0), "10");
        assert_eq!(tick_label(0.5), "0.5");
        assert_eq!(tick_label(1e-3), "1e-3");
        assert_eq!(tick_label(5e-4), "5e-4");
    }
}
