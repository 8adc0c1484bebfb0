//! Colour maps and the PNG encoding of the diagnostics' `(s, r)` maps: one
//! PNG pixel per grid cell, rows top to bottom. Non-finite cells (outside
//! the image) are magenta in every map.

use image::ImageEncoder as _;
use std::path::Path;

/// Colour of a non-finite cell.
const MISSING: [u8; 3] = [255, 0, 255];
/// Ends of the diverging map (ColorBrewer RdBu): negative, positive.
const NEGATIVE: [u8; 3] = [33, 102, 172];
const POSITIVE: [u8; 3] = [178, 24, 43];
/// Share of the residuals inside the diverging map's scale.
const SCALE_QUANTILE: f64 = 0.99;

/// Gray from black at `lo` to white at `hi` (clamped; mid-gray when the
/// range is empty), as RGB triples.
pub fn gray_rgb(values: &[f64], lo: f64, hi: f64) -> Vec<u8> {
    let range = hi - lo;
    values
        .iter()
        .flat_map(|&v| {
            if !v.is_finite() {
                MISSING
            } else if range > 0.0 {
                [(255.0 * (v - lo) / range).round().clamp(0.0, 255.0) as u8; 3]
            } else {
                [128; 3]
            }
        })
        .collect()
}

/// The symmetric scale of the diverging map: the `SCALE_QUANTILE` quantile
/// of the finite `|values|` (a few outliers, clutter, would otherwise wash
/// the rest out), and positive (the smallest positive number when all are
/// 0 or none is finite).
pub fn symmetric_scale(values: &[f64]) -> f64 {
    let mut abs: Vec<f64> = values
        .iter()
        .filter(|v| v.is_finite())
        .map(|v| v.abs())
        .collect();
    if abs.is_empty() {
        return f64::MIN_POSITIVE;
    }
    let k = ((abs.len() - 1) as f64 * SCALE_QUANTILE).round() as usize;
    let q = *abs.select_nth_unstable_by(k, f64::total_cmp).1;
    q.max(f64::MIN_POSITIVE)
}

/// Diverging colours: `NEGATIVE` at `-scale`, white at 0, `POSITIVE` at
/// `scale` (clamped beyond), as RGB triples.
pub fn diverging_rgb(values: &[f64], scale: f64) -> Vec<u8> {
    values
        .iter()
        .flat_map(|&v| {
            if !v.is_finite() {
                return MISSING;
            }
            let t = (v / scale).clamp(-1.0, 1.0);
            let end = if t < 0.0 { NEGATIVE } else { POSITIVE };
            end.map(|e| (255.0 + t.abs() * (f64::from(e) - 255.0)).round() as u8)
        })
        .collect()
}

/// Write `rgb` (`width x height` triples, row after row) as an 8-bit RGB
/// PNG.
pub fn write_rgb_png(path: &Path, width: usize, height: usize, rgb: &[u8]) -> Result<(), String> {
    let fail = |e: String| format!("cannot write {}: {e}", path.display());
    let (w, h) = (
        u32::try_from(width).map_err(|_| fail("too wide".into()))?,
        u32::try_from(height).map_err(|_| fail("too high".into()))?,
    );
    let mut png = Vec::new();
    image::codecs::png::PngEncoder::new(&mut png)
        .write_image(rgb, w, h, image::ExtendedColorType::Rgb8)
        .map_err(|e| fail(e.to_string()))?;
    std::fs::write(path, png).map_err(|e| fail(e.to_string()))
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn colour_maps() {
        assert_eq!(
            gray_rgb(&[0.0, 1.0, 2.0, f64::NAN], 0.0, 2.0),
            [0, 0, 0, 128, 128, 128, 255, 255, 255, 255, 0, 255]
        );
        let d = diverging_rgb(&[-2.0, 0.0, 0.5, 9.0], 1.0);
        assert_eq!(&d[0..3], &NEGATIVE);
        assert_eq!(&d[3..6], &[255, 255, 255]);
        assert_eq!(&d[9..12], &POSITIVE);
        // Half-way to the positive end.
        assert_eq!(d[6], ((255.0 + 178.0) / 2.0f64).round() as u8);
        let v: Vec<f64> = (0..=100).map(|k| k as f64 - 50.0).collect();
        assert_eq!(symmetric_scale(&v), 50.0);
        assert_eq!(symmetric_scale(&[0.0, f64::NAN]), f64::MIN_POSITIVE);
    }
}
