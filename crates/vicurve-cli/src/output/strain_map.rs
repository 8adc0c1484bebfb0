//! `grid --map`: the strain map, every measured circle drawn over the image
//! in a colour by its major strain `eps1` (blue lowest to red highest, in
//! `MAP_BINS` equal bins whose ranges make the SVG's legend), with its id.

use super::overlay::{write_png_tagged, write_svg_tagged, Layer, Style, Tag};
use std::path::Path;
use vicurve::objects::{AllResult, GridStrain};
use vicurve::Image;

/// Colour bins of the map.
const MAP_BINS: usize = 6;

/// The colour of bin `k` of `MAP_BINS`: blue, through cyan, green, yellow,
/// to red.
fn bin_colour(k: usize) -> [u8; 3] {
    const RAMP: [[u8; 3]; MAP_BINS] = [
        [40, 80, 255],
        [0, 190, 230],
        [40, 200, 80],
        [230, 220, 0],
        [255, 140, 0],
        [230, 30, 30],
    ];
    RAMP[k.min(MAP_BINS - 1)]
}

/// Write the map of `strains` (one per object of `all`, `None` where none)
/// over `image` to `path`: PNG when its name ends in `.png`, else SVG.
pub fn write_strain_map(
    path: &Path,
    image: &Image,
    all: &AllResult,
    strains: &[Option<GridStrain>],
) -> Result<(), String> {
    let measured = || strains.iter().flatten();
    let lo = measured().map(|s| s.eps1).fold(f64::INFINITY, f64::min);
    let hi = measured().map(|s| s.eps1).fold(f64::NEG_INFINITY, f64::max);
    let step = ((hi - lo) / MAP_BINS as f64).max(1e-9);
    let mut layers = Vec::new();
    let mut tags = Vec::new();
    for (o, s) in all.objects.iter().zip(strains) {
        let (Some(s), Some(m)) = (s, &o.measurement) else {
            continue;
        };
        let k = (((s.eps1 - lo) / step) as usize).min(MAP_BINS - 1);
        let [r, g, b] = bin_colour(k);
        let from = lo + k as f64 * step;
        layers.push(Layer {
            label: format!("eps1 {:.4} to {:.4}", from, from + step),
            points: m.points(),
            closed: m.curve.is_closed(),
            style: Style {
                color: [r, g, b, 255],
                width: 2.0,
                dash: None,
            },
        });
        tags.push(Tag {
            at: s.centre,
            text: o.id.to_string(),
            color: [r, g, b],
        });
    }
    // The legend lists the bins from the lowest.
    layers.sort_by(|a, b| a.label.cmp(&b.label));
    let png = path
        .extension()
        .is_some_and(|e| e.eq_ignore_ascii_case("png"));
    if png {
        write_png_tagged(path, image, &layers, &tags, 1)
    } else {
        write_svg_tagged(path, image, &layers, &tags)
    }
}
