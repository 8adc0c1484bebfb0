//! Overlays: the image with curves drawn over it, as SVG or PNG, for
//! checking a measurement by eye.
//!
//! Point `(x, y)` is in image pixels with the library's convention: the
//! centre of pixel (row `i`, column `j`) is at `(j, i)`. In both outputs the
//! image's pixel `j` spans `[j, j + 1]` (times the PNG's scale), so a point
//! is drawn at `(x + 0.5, y + 0.5)`: a curve through pixel centres is drawn
//! through the middle of the drawn pixels.
//!
//! Gray levels are stretched for display, the smallest to black and the
//! largest to white (`round(255 (v - min) / (max - min))`, mid-gray for a
//! uniform image): the overlay is for looking, not for measuring.

use std::fmt::Write as _;
use std::path::Path;

use crate::plot::{draw_text, Anchor};
use tiny_skia::{LineCap, LineJoin, Paint, PathBuilder, Pixmap, Stroke, StrokeDash, Transform};
use vicurve::Image;

/// Largest PNG overlay, in pixels: beyond this the file is too big to be
/// useful and the drawing could exhaust memory (4 bytes per pixel).
const MAX_PNG_PIXELS: u64 = 100_000_000;

/// How a layer is stroked.
#[derive(Clone, Debug, PartialEq)]
pub struct Style {
    /// Red, green, blue, alpha (0 transparent .. 255 opaque).
    pub color: [u8; 4],
    /// Stroke width in image pixels (scaled with the PNG's scale); > 0.
    pub width: f32,
    /// Dash pattern: lengths on and off in image pixels (both > 0), or a
    /// solid line.
    pub dash: Option<[f32; 2]>,
}

/// One curve drawn over the image.
#[derive(Clone, Debug, PartialEq)]
pub struct Layer {
    /// Name shown in the SVG's legend and tooltip.
    pub label: String,
    /// Vertices `(x, y)` in image pixels (pixel-centre convention). One point
    /// is drawn as a dot of the stroke's width; none draws nothing.
    pub points: Vec<[f64; 2]>,
    /// Whether the last point joins the first.
    pub closed: bool,
    /// Stroke colour, width and dashes.
    pub style: Style,
}

/// A short text drawn over the image, centred on a point (an object's id).
#[derive(Clone, Debug, PartialEq)]
pub struct Tag {
    /// Centre of the text `(x, y)`, image pixels.
    pub at: [f64; 2],
    /// The text (Basic Latin in the PNG).
    pub text: String,
    /// Red, green, blue (opaque).
    pub color: [u8; 3],
}

/// The tags' font size, image pixels: readable at the overlays' display
/// sizes whatever the image's size.
fn tag_size(image: &Image) -> f64 {
    (image.width().max(image.height()) as f64 / 100.0).max(6.0)
}

/// [`write_svg`] without tags.
pub fn write_svg(path: &Path, image: &Image, layers: &[Layer]) -> Result<(), String> {
    write_svg_tagged(path, image, layers, &[])
}

/// [`write_png`] without tags.
pub fn write_png(path: &Path, image: &Image, layers: &[Layer], scale: u32) -> Result<(), String> {
    write_png_tagged(path, image, layers, &[], scale)
}

/// Write an SVG overlay: the image, embedded as a base64 8-bit gray PNG shown
/// with `image-rendering: pixelated`, and each layer as a `<polyline>` (or
/// `<polygon>` when closed) titled with its label, plus a legend in the top
/// left corner.
///
/// User units are image pixels (`viewBox="0 0 width height"`); the
/// displayed size is the image's times the smallest integer that makes it at
/// least 800 units wide or high, so that small images open at a usable size.
/// Coordinates are written with 4 decimals (1/10000 pixel), enough for
/// sub-pixel measurements.
///
/// Layers of the same label and style share one legend entry; the `tags`
/// are drawn on top, centred on their points.
///
/// Errors (one line naming the file): a layer with a non-finite point or an
/// invalid style, or the file cannot be written.
pub fn write_svg_tagged(
    path: &Path,
    image: &Image,
    layers: &[Layer],
    tags: &[Tag],
) -> Result<(), String> {
    let fail = |what: String| format!("cannot write SVG overlay {}: {what}", path.display());
    for layer in layers {
        check_layer(layer).map_err(fail)?;
    }
    let (w, h) = (image.width(), image.height());
    let png = gray_png(image).map_err(fail)?;
    let zoom = 800usize.div_ceil(w.max(h)).max(1);

    let mut svg = String::new();
    // `write!` into a String cannot fail; the results are ignored.
    let _ = writeln!(svg, r#"<?xml version="1.0" encoding="UTF-8"?>"#);
    let _ = writeln!(
        svg,
        r#"<svg xmlns="http://www.w3.org/2000/svg" xmlns:xlink="http://www.w3.org/1999/xlink" width="{}" height="{}" viewBox="0 0 {w} {h}">"#,
        w * zoom,
        h * zoom
    );
    let _ = writeln!(
        svg,
        r#"<image x="0" y="0" width="{w}" height="{h}" preserveAspectRatio="none" image-rendering="optimizeSpeed" style="image-rendering:pixelated" xlink:href="data:image/png;base64,{}"/>"#,
        base64(&png)
    );
    let _ = writeln!(
        svg,
        r#"<g fill="none" stroke-linejoin="round" stroke-linecap="round">"#
    );
    for layer in layers {
        svg_layer(&mut svg, layer);
    }
    let _ = writeln!(svg, "</g>");
    svg_tags(&mut svg, tags, tag_size(image));
    svg_legend(&mut svg, layers, w.max(h) as f64);
    let _ = writeln!(svg, "</svg>");
    std::fs::write(path, svg).map_err(|e| fail(e.to_string()))
}

/// Write a PNG overlay: the image upscaled by the integer `scale` (nearest
/// neighbour, 1 = native size), gray levels stretched as the module says,
/// with the layers drawn anti-aliased on top, then the `tags` (the plots'
/// 8x8 font). No legend.
///
/// Errors (one line naming the file): `scale` is 0, the result would exceed
/// 100 Mpixel, a layer has a non-finite point or an invalid style, or the
/// file cannot be written.
pub fn write_png_tagged(
    path: &Path,
    image: &Image,
    layers: &[Layer],
    tags: &[Tag],
    scale: u32,
) -> Result<(), String> {
    let fail = |what: String| format!("cannot write PNG overlay {}: {what}", path.display());
    if scale == 0 {
        return Err(fail("the scale must be at least 1".to_string()));
    }
    let (out_w, out_h) = (
        image.width() as u64 * u64::from(scale),
        image.height() as u64 * u64::from(scale),
    );
    if out_w * out_h > MAX_PNG_PIXELS {
        return Err(fail(format!(
            "{out_w}x{out_h} pixels at scale {scale} exceeds the {} Mpixel limit; use a smaller scale",
            MAX_PNG_PIXELS / 1_000_000
        )));
    }
    for layer in layers {
        check_layer(layer).map_err(fail)?;
    }
    // Both sides are at most 1e8 here, so they fit in u32.
    let mut pixmap = Pixmap::new(out_w as u32, out_h as u32)
        .ok_or_else(|| fail(format!("cannot allocate {out_w}x{out_h} pixels")))?;

    let levels = display_levels(image);
    let (w, s) = (image.width(), scale as usize);
    for (row, out_row) in pixmap.data_mut().chunks_exact_mut(4 * w * s).enumerate() {
        let src = &levels[(row / s) * w..(row / s + 1) * w];
        for (col, px) in out_row.chunks_exact_mut(4).enumerate() {
            let g = src[col / s];
            px.copy_from_slice(&[g, g, g, 255]);
        }
    }

    let s = f64::from(scale);
    for layer in layers {
        let mut paint = Paint::default();
        let [r, g, b, a] = layer.style.color;
        paint.set_color_rgba8(r, g, b, a);
        paint.anti_alias = true;
        // In f64 then rounded once, to keep sub-pixel positions on big images.
        let map = |p: &[f64; 2]| (((p[0] + 0.5) * s) as f32, ((p[1] + 0.5) * s) as f32);
        if let [point] = layer.points[..] {
            let (cx, cy) = map(&point);
            if let Some(dot) =
                PathBuilder::from_circle(cx, cy, layer.style.width * scale as f32 / 2.0)
            {
                pixmap.fill_path(
                    &dot,
                    &paint,
                    tiny_skia::FillRule::Winding,
                    Transform::identity(),
                    None,
                );
            }
            continue;
        }
        let mut builder = PathBuilder::new();
        for (k, p) in layer.points.iter().enumerate() {
            let (x, y) = map(p);
            if k == 0 {
                builder.move_to(x, y);
            } else {
                builder.line_to(x, y);
            }
        }
        if layer.closed {
            builder.close();
        }
        let Some(path) = builder.finish() else {
            continue; // no point: nothing to draw
        };
        let stroke = Stroke {
            width: layer.style.width * scale as f32,
            line_cap: LineCap::Round,
            line_join: LineJoin::Round,
            dash: layer.style.dash.and_then(|[on, off]| {
                StrokeDash::new(vec![on * scale as f32, off * scale as f32], 0.0)
            }),
            ..Stroke::default()
        };
        pixmap.stroke_path(&path, &paint, &stroke, Transform::identity(), None);
    }
    let k = ((tag_size(image) * s / 9.0).round() as i64).max(1);
    for t in tags {
        // The baseline 3.5 cells below the centre: the text centred on it.
        let at = (
            ((t.at[0] + 0.5) * s) as i64,
            ((t.at[1] + 0.5) * s) as i64 + 7 * k / 2,
        );
        draw_text(&mut pixmap, at, &t.text, k, Anchor::Middle, false, t.color);
    }
    let png = pixmap.encode_png().map_err(|e| fail(e.to_string()))?;
    std::fs::write(path, png).map_err(|e| fail(e.to_string()))
}

/// A layer's points are finite and its style drawable.
fn check_layer(layer: &Layer) -> Result<(), String> {
    let name = &layer.label;
    if let Some(k) = layer
        .points
        .iter()
        .position(|p| !(p[0].is_finite() && p[1].is_finite()))
    {
        return Err(format!("layer `{name}`: point {k} is not finite"));
    }
    let width = layer.style.width;
    if !(width.is_finite() && width > 0.0) {
        return Err(format!("layer `{name}`: stroke width {width} must be > 0"));
    }
    if let Some([on, off]) = layer.style.dash {
        if !(on.is_finite() && off.is_finite() && on > 0.0 && off > 0.0) {
            return Err(format!(
                "layer `{name}`: dash lengths {on},{off} must be > 0"
            ));
        }
    }
    Ok(())
}

/// One `<polyline>`/`<polygon>` (or a dot for a single point).
fn svg_layer(svg: &mut String, layer: &Layer) {
    let style = stroke_attributes(&layer.style, layer.style.width);
    let title = xml_escape(&layer.label);
    match layer.points[..] {
        [] => {}
        [p] => {
            let _ = writeln!(
                svg,
                r#"<circle cx="{:.4}" cy="{:.4}" r="{}" {style} fill="{}"><title>{title}</title></circle>"#,
                p[0] + 0.5,
                p[1] + 0.5,
                layer.style.width / 2.0,
                rgb(&layer.style.color),
            );
        }
        _ => {
            let element = if layer.closed { "polygon" } else { "polyline" };
            let mut points = String::with_capacity(layer.points.len() * 20);
            for (k, p) in layer.points.iter().enumerate() {
                let sep = if k == 0 { "" } else { " " };
                let _ = write!(points, "{sep}{:.4},{:.4}", p[0] + 0.5, p[1] + 0.5);
            }
            let _ = writeln!(
                svg,
                r#"<{element} points="{points}" {style}><title>{title}</title></{element}>"#
            );
        }
    }
}

/// The tags as `<text>` centred on their points, `size` user units high.
fn svg_tags(svg: &mut String, tags: &[Tag], size: f64) {
    if tags.is_empty() {
        return;
    }
    let _ = writeln!(
        svg,
        r#"<g font-family="sans-serif" font-size="{size:.3}" text-anchor="middle">"#
    );
    for t in tags {
        let _ = writeln!(
            svg,
            r#"<text x="{:.3}" y="{:.3}" fill="rgb({},{},{})">{}</text>"#,
            t.at[0] + 0.5,
            t.at[1] + 0.5 + 0.35 * size,
            t.color[0],
            t.color[1],
            t.color[2],
            xml_escape(&t.text)
        );
    }
    let _ = writeln!(svg, "</g>");
}

/// A legend box in the top left corner, sized relative to the image so that
/// it stays readable whatever the image's size; one entry per label and
/// style.
fn svg_legend(svg: &mut String, layers: &[Layer], image_size: f64) {
    let mut entries: Vec<&Layer> = Vec::new();
    for l in layers {
        if !entries
            .iter()
            .any(|e| e.label == l.label && e.style == l.style)
        {
            entries.push(l);
        }
    }
    let layers = &entries[..];
    if layers.is_empty() {
        return;
    }
    let f = (image_size / 60.0).max(1.0); // font size, user units
    let longest = layers
        .iter()
        .map(|l| l.label.chars().count())
        .max()
        .unwrap_or(0);
    let _ = writeln!(
        svg,
        r#"<g font-family="sans-serif" font-size="{f:.3}" stroke-linecap="round">"#
    );
    let _ = writeln!(
        svg,
        r#"<rect x="{:.3}" y="{:.3}" width="{:.3}" height="{:.3}" fill="white" fill-opacity="0.75"/>"#,
        0.25 * f,
        0.25 * f,
        f * (3.5 + 0.6 * longest as f64),
        f * (0.5 + 1.4 * layers.len() as f64)
    );
    for (k, layer) in layers.iter().enumerate() {
        let y = f * (1.2 + 1.4 * k as f64);
        let style = stroke_attributes(&layer.style, (0.25 * f) as f32);
        let _ = writeln!(
            svg,
            r#"<line x1="{:.3}" y1="{y:.3}" x2="{:.3}" y2="{y:.3}" {style}/>"#,
            0.6 * f,
            2.6 * f
        );
        let _ = writeln!(
            svg,
            r#"<text x="{:.3}" y="{:.3}" fill="black">{}</text>"#,
            3.0 * f,
            y + 0.35 * f,
            xml_escape(&layer.label)
        );
    }
    let _ = writeln!(svg, "</g>");
}

/// `stroke`, `stroke-opacity`, `stroke-width` and `stroke-dasharray`.
fn stroke_attributes(style: &Style, width: f32) -> String {
    let mut out = format!(
        r#"stroke="{}" stroke-opacity="{:.3}" stroke-width="{}""#,
        rgb(&style.color),
        f32::from(style.color[3]) / 255.0,
        short(width)
    );
    if let Some([on, off]) = style.dash {
        let _ = write!(out, r#" stroke-dasharray="{} {}""#, short(on), short(off));
    }
    out
}

/// A length with at most 4 decimals and no trailing zeros (`0.3`, not
/// `0.30000001` from the `f32`).
fn short(value: f32) -> String {
    let text = format!("{value:.4}");
    text.trim_end_matches('0').trim_end_matches('.').to_string()
}

fn rgb(color: &[u8; 4]) -> String {
    format!("rgb({},{},{})", color[0], color[1], color[2])
}

fn xml_escape(text: &str) -> String {
    let mut out = String::with_capacity(text.len());
    for c in text.chars() {
        match c {
            '&' => out.push_str("&amp;"),
            '<' => out.push_str("&lt;"),
            '>' => out.push_str("&gt;"),
            '"' => out.push_str("&quot;"),
            '\'' => out.push_str("&apos;"),
            c => out.push(c),
        }
    }
    out
}

/// Display gray levels (see the module's doc), row after row.
fn display_levels(image: &Image) -> Vec<u8> {
    let (lo, hi) = image.min_max();
    let range = hi - lo;
    image
        .data()
        .iter()
        .map(|&v| {
            if range > 0.0 {
                (255.0 * (v - lo) / range).round().clamp(0.0, 255.0) as u8
            } else {
                128
            }
        })
        .collect()
}

/// The image's display levels as an 8-bit gray PNG file in memory.
fn gray_png(image: &Image) -> Result<Vec<u8>, String> {
    use image::ImageEncoder as _;
    let (w, h) = (
        u32::try_from(image.width()).map_err(|_| "image too wide".to_string())?,
        u32::try_from(image.height()).map_err(|_| "image too high".to_string())?,
    );
    let mut png = Vec::new();
    image::codecs::png::PngEncoder::new(&mut png)
        .write_image(&display_levels(image), w, h, image::ExtendedColorType::L8)
        .map_err(|e| e.to_string())?;
    Ok(png)
}

/// Standard base64 (RFC 4648, with `=` padding).
fn base64(bytes: &[u8]) -> String {
    const ALPHABET: &[u8; 64] = b"ABCDEFGHIJKLMNOPQRSTUVWXYZabcdefghijklmnopqrstuvwxyz0123456789+/";
    let mut out = String::with_capacity(bytes.len().div_ceil(3) * 4);
    for chunk in bytes.chunks(3) {
        let b = [
            chunk[0],
            *chunk.get(1).unwrap_or(&0),
            *chunk.get(2).unwrap_or(&0),
        ];
        let n = (u32::from(b[0]) << 16) | (u32::from(b[1]) << 8) | u32::from(b[2]);
        for k in 0..4 {
            if k <= chunk.len() {
                out.push(char::from(ALPHABET[(n >> (18 - 6 * k)) as usize & 63]));
            } else {
                out.push('=');
            }
        }
    }
    out
}

#[cfg(test)]
mod tests {
    use super::*;

    /// Independent decoder for the tests (accepts only what `base64` writes).
    fn unbase64(text: &str) -> Vec<u8> {
        let value = |c: u8| match c {
            b'A'..=b'Z' => c - b'A',
            b'a'..=b'z' => c - b'a' + 26,
            b'0'..=b'9' => c - b'0' + 52,
            b'+' => 62,
            b'/' => 63,
            _ => panic!("bad base64 character {c}"),
        };
        let mut out = Vec::new();
        for quad in text.as_bytes().chunks(4) {
            let pad = quad.iter().filter(|&&c| c == b'=').count();
            let mut n = 0u32;
            for &c in quad {
                n = (n << 6) | u32::from(if c == b'=' { 0 } else { value(c) });
            }
            let bytes = n.to_be_bytes();
            out.extend_from_slice(&bytes[1..4 - pad]);
        }
        out
    }

    fn layer(label: &str, points: Vec<[f64; 2]>, closed: bool, color: [u8; 4]) -> Layer {
        Layer {
            label: label.to_string(),
            points,
            closed,
            style: Style {
                color,
                width: 1.0,
                dash: None,
            },
        }
    }

    fn read_rgba(path: &Path) -> image::RgbaImage {
        image::open(path).unwrap().to_rgba8()
    }

    #[test]
    fn base64_rfc4648_vectors() {
        for (plain, coded) in [
            ("", ""),
            ("f", "Zg=="),
            ("fo", "Zm8="),
            ("foo", "Zm9v"),
            ("foob", "Zm9vYg=="),
            ("fooba", "Zm9vYmE="),
            ("foobar", "Zm9vYmFy"),
        ] {
            assert_eq!(base64(plain.as_bytes()), coded);
            assert_eq!(unbase64(coded), plain.as_bytes());
        }
        let all: Vec<u8> = (0..=255).collect();
        assert_eq!(unbase64(&base64(&all)), all);
    }

    #[test]
    fn svg_holds_image_layers_and_shifted_coordinates() {
        let dir = tempfile::tempdir().unwrap();
        let path = dir.path().join("o.svg");
        // 5x3 gradient from 0.2 to 0.6: display levels stretch to 0..255.
        let image = Image::from_fn(5, 3, |x, y| 0.2 + 0.1 * x as f64 * (y as f64 / 2.0));
        let layers = [
            layer(
                "fit <a&b>",
                vec![[1.0, 2.0], [3.25, 0.125], [4.0, -0.5]],
                false,
                [255, 0, 0, 255],
            ),
            Layer {
                style: Style {
                    color: [0, 128, 255, 128],
                    width: 0.5,
                    dash: Some([2.0, 1.0]),
                },
                ..layer(
                    "initial",
                    vec![[0.0, 0.0], [2.0, 0.0], [1.0, 1.5]],
                    true,
                    [0; 4],
                )
            },
        ];
        write_svg(&path, &image, &layers).unwrap();
        let svg = std::fs::read_to_string(&path).unwrap();
        assert!(svg.starts_with("<?xml"));
        assert!(svg.trim_end().ends_with("</svg>"));
        assert!(svg.contains(r#"viewBox="0 0 5 3""#));
        assert!(
            svg.contains(r#"<polyline points="1.5000,2.5000 3.7500,0.6250 4.5000,0.0000""#),
            "{svg}"
        );
        assert!(
            svg.contains(r#"<polygon points="0.5000,0.5000 2.5000,0.5000 1.5000,2.0000""#),
            "{svg}"
        );
        assert!(svg.contains("<title>fit &lt;a&amp;b&gt;</title>"));
        assert!(svg.contains("<title>initial</title>"));
        assert!(svg.contains(r#"stroke-dasharray="2 1""#));
        assert!(svg.contains(r#"stroke-width="0.5""#));
        assert!(svg.contains(r#"stroke="rgb(0,128,255)" stroke-opacity="0.502""#));
        assert!(!svg.contains("fit <a&b>"), "label must be escaped");
        // Tags balance for the elements we write.
        for tag in ["svg", "g", "title", "text"] {
            assert_eq!(
                svg.matches(&format!("<{tag}")).count() - svg.matches(&format!("<{tag}s")).count(),
                svg.matches(&format!("</{tag}>")).count(),
                "<{tag}>"
            );
        }

        let start = svg.find("base64,").unwrap() + "base64,".len();
        let end = start + svg[start..].find('"').unwrap();
        let png = image::load_from_memory(&unbase64(&svg[start..end])).unwrap();
        let gray = png.as_luma8().expect("8-bit gray PNG");
        assert_eq!(gray.dimensions(), (5, 3));
        // min 0.2 (row 0) -> 0, max 0.6 (x=4, y=2) -> 255, 0.3 -> 63.75 -> 64.
        assert_eq!(gray.get_pixel(0, 0)[0], 0);
        assert_eq!(gray.get_pixel(4, 2)[0], 255);
        assert_eq!(gray.get_pixel(2, 1)[0], 64);
    }

    #[test]
    fn svg_single_point_and_errors() {
        let dir = tempfile::tempdir().unwrap();
        let image = Image::from_fn(4, 4, |_, _| 0.5);
        let path = dir.path().join("p.svg");
        write_svg(
            &path,
            &image,
            &[layer("dot", vec![[1.0, 1.0]], false, [0, 255, 0, 255])],
        )
        .unwrap();
        let svg = std::fs::read_to_string(&path).unwrap();
        assert!(svg.contains(r#"<circle cx="1.5000" cy="1.5000""#));

        let bad = layer("bad", vec![[1.0, 1.0], [f64::NAN, 2.0]], false, [0; 4]);
        let e = write_svg(&path, &image, &[bad]).unwrap_err();
        assert!(
            e.contains("p.svg") && e.contains("bad") && e.contains("point 1"),
            "{e}"
        );
        let missing = dir.path().join("no/such/dir/o.svg");
        let e = write_svg(&missing, &image, &[]).unwrap_err();
        assert!(e.contains("no/such/dir/o.svg") && !e.contains('\n'), "{e}");
    }

    #[test]
    fn png_upscales_nearest_and_stretches_levels() {
        let dir = tempfile::tempdir().unwrap();
        let path = dir.path().join("o.png");
        // Checkerboard of 0.3 / 0.7: displayed black / white.
        let image = Image::from_fn(4, 3, |x, y| if (x + y) % 2 == 0 { 0.3 } else { 0.7 });
        write_png(&path, &image, &[], 3).unwrap();
        let out = read_rgba(&path);
        assert_eq!(out.dimensions(), (12, 9));
        for (x, y, px) in out.enumerate_pixels() {
            let expected = if (x / 3 + y / 3) % 2 == 0 { 0 } else { 255 };
            assert_eq!(px.0, [expected, expected, expected, 255], "({x}, {y})");
        }
    }

    #[test]
    fn png_line_lands_on_the_pixel_centres() {
        let dir = tempfile::tempdir().unwrap();
        let path = dir.path().join("l.png");
        let image = Image::from_fn(10, 10, |_, _| 0.0); // uniform: mid-gray
                                                        // A vertical line through the centres of column 3, 1 pixel wide:
                                                        // it covers exactly column 3 at scale 1 (from x = 3.5 +- 0.5).
        let line = layer("v", vec![[3.0, 1.0], [3.0, 8.0]], false, [255, 0, 0, 255]);
        write_png(&path, &image, std::slice::from_ref(&line), 1).unwrap();
        let out = read_rgba(&path);
        assert_eq!(out.dimensions(), (10, 10));
        assert_eq!(out.get_pixel(3, 5).0, [255, 0, 0, 255]);
        assert_eq!(out.get_pixel(2, 5).0, [128, 128, 128, 255]);
        assert_eq!(out.get_pixel(4, 5).0, [128, 128, 128, 255]);

        // At scale 4, the same line covers output columns 12..16.
        write_png(&path, &image, std::slice::from_ref(&line), 4).unwrap();
        let out = read_rgba(&path);
        assert_eq!(out.dimensions(), (40, 40));
        for col in 12..16 {
            assert_eq!(out.get_pixel(col, 20).0, [255, 0, 0, 255], "column {col}");
        }
        assert_eq!(out.get_pixel(11, 20).0, [128, 128, 128, 255]);
        assert_eq!(out.get_pixel(16, 20).0, [128, 128, 128, 255]);
    }

    #[test]
    fn png_dashes_alternate() {
        let dir = tempfile::tempdir().unwrap();
        let path = dir.path().join("d.png");
        let image = Image::from_fn(40, 5, |_, _| 0.0);
        let mut dashed = layer("d", vec![[0.0, 2.0], [39.0, 2.0]], false, [0, 0, 255, 255]);
        dashed.style.dash = Some([4.0, 4.0]);
        dashed.style.width = 2.0;
        write_png(&path, &image, &[dashed], 1).unwrap();
        let out = read_rgba(&path);
        // The path starts at x = 0.5: "on" over [0.5, 4.5] (with a round cap
        // at each end), "off" over [4.5, 8.5], on again from 8.5.
        assert_eq!(out.get_pixel(2, 2).0, [0, 0, 255, 255]);
        assert_eq!(out.get_pixel(6, 2).0, [128, 128, 128, 255]);
        assert_eq!(out.get_pixel(10, 2).0, [0, 0, 255, 255]);
    }

    #[test]
    fn png_refuses_huge_zero_scale_and_bad_styles() {
        let dir = tempfile::tempdir().unwrap();
        let path = dir.path().join("h.png");
        let image = Image::from_fn(1000, 1000, |_, _| 0.0);
        let e = write_png(&path, &image, &[], 11).unwrap_err();
        assert!(e.contains("h.png") && e.contains("Mpixel"), "{e}");
        assert!(!path.exists());
        let e = write_png(&path, &image, &[], 0).unwrap_err();
        assert!(e.contains("scale"), "{e}");
        let mut thin = layer("thin", vec![[0.0, 0.0], [1.0, 1.0]], false, [0; 4]);
        thin.style.width = 0.0;
        assert!(write_png(&path, &image, &[thin.clone()], 1)
            .unwrap_err()
            .contains("thin"));
        thin.style.width = 1.0;
        thin.style.dash = Some([1.0, -1.0]);
        assert!(write_png(&path, &image, &[thin], 1)
            .unwrap_err()
            .contains("dash"));
    }
}
