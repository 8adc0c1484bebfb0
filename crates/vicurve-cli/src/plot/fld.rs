//! The forming-limit scatter of a circle grid: minor strain `eps2`
//! horizontal, major strain `eps1` vertical, linear axes through zero, each
//! circle a dot with its two-sigma error bars, as SVG or PNG (drawn once
//! on the plots' canvases, [`super::Canvas`]).

use super::{write_png_with, write_svg_with, Anchor, Canvas};
use std::path::Path;
use vicurve::objects::GridStrain;

const W: f64 = 560.0;
const H: f64 = 480.0;
const M: f64 = 60.0;
const BLACK: [u8; 3] = [0, 0, 0];
const GRAY: [u8; 3] = [128, 128, 128];
const BLUE: [u8; 3] = [70, 130, 180];

/// Write the scatter of `strains` to `path`: PNG when its name ends in
/// `.png` (twice the SVG's size), else SVG. The axes span the strains and
/// their error bars with a 10 % margin, zero included; the lines `eps1 =
/// -eps2` (pure shear) and `eps1 = -2 eps2` (uniaxial tension) are drawn
/// dashed for reference.
pub fn write_fld(path: &Path, strains: &[&GridStrain], title: &str) -> Result<(), String> {
    let png = path
        .extension()
        .is_some_and(|e| e.eq_ignore_ascii_case("png"));
    let paint = |c: &mut dyn Canvas| draw(c, strains, title);
    if png {
        write_png_with(W, H, path, paint)
    } else {
        write_svg_with(W, H, path, paint)
    }
}

/// `(lo, hi)` of `values` and 0, widened by 10 % (at least 1e-4).
fn span(values: impl Iterator<Item = f64>) -> (f64, f64) {
    let (lo, hi) = values.fold((0.0f64, 0.0f64), |(lo, hi), x| (lo.min(x), hi.max(x)));
    let pad = 0.1 * (hi - lo).max(1e-3);
    (lo - pad, hi + pad)
}

fn draw(c: &mut dyn Canvas, strains: &[&GridStrain], title: &str) {
    let (x0, x1) = span(
        strains
            .iter()
            .flat_map(|s| [s.eps2 - 2.0 * s.sigma_eps2, s.eps2 + 2.0 * s.sigma_eps2]),
    );
    let (y0, y1) = span(
        strains
            .iter()
            .flat_map(|s| [s.eps1 - 2.0 * s.sigma_eps1, s.eps1 + 2.0 * s.sigma_eps1]),
    );
    let px = |x: f64| M + (x - x0) / (x1 - x0) * (W - 2.0 * M);
    let py = |y: f64| H - M - (y - y0) / (y1 - y0) * (H - 2.0 * M);
    c.text(W / 2.0, 24.0, title, 15.0, Anchor::Middle, false);
    let frame = [(M, M), (W - M, M), (W - M, H - M), (M, H - M), (M, M)];
    c.line(&frame, BLACK, 1.0, false);
    c.line(&[(px(0.0), M), (px(0.0), H - M)], GRAY, 1.0, false);
    c.line(&[(M, py(0.0)), (W - M, py(0.0))], GRAY, 1.0, false);
    for k in [1.0, 2.0] {
        // eps1 = -k eps2 through the frame (clipped by the frame's range).
        let (a, b) = (x0.max(-y1 / k), x1.min(-y0 / k));
        if a < b {
            c.line(&[(px(a), py(-k * a)), (px(b), py(-k * b))], GRAY, 1.0, true);
        }
    }
    for g in strains {
        let (cx, cy) = (px(g.eps2), py(g.eps1));
        let (ex, ey) = (2.0 * g.sigma_eps2, 2.0 * g.sigma_eps1);
        c.line(
            &[(px(g.eps2 - ex), cy), (px(g.eps2 + ex), cy)],
            BLUE,
            1.0,
            false,
        );
        c.line(
            &[(cx, py(g.eps1 - ey)), (cx, py(g.eps1 + ey))],
            BLUE,
            1.0,
            false,
        );
        c.dot(cx, cy, 2.5, BLUE);
    }
    c.text(
        W / 2.0,
        H - 18.0,
        "minor strain eps2",
        13.0,
        Anchor::Middle,
        false,
    );
    c.text(
        20.0,
        H / 2.0,
        "major strain eps1",
        13.0,
        Anchor::Middle,
        true,
    );
    for (v, x) in [(x0, M), (x1, W - M)] {
        let t = format!("{v:.3}");
        c.text(x, H - M + 16.0, &t, 13.0, Anchor::Middle, false);
    }
    for (v, y) in [(y0, H - M), (y1, M)] {
        c.text(
            M - 24.0,
            y + 4.0,
            &format!("{v:.3}"),
            13.0,
            Anchor::Middle,
            false,
        );
    }
}
