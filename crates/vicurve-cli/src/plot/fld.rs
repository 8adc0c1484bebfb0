//! The forming-limit scatter of a circle grid: minor strain `eps2`
//! horizontal, major strain `eps1` vertical, linear axes through zero, each
//! circle a dot with its two-sigma error bars, as SVG.

use std::fmt::Write as _;
use std::path::Path;
use vicurve::objects::GridStrain;

const W: f64 = 560.0;
const H: f64 = 480.0;
const M: f64 = 60.0;

/// Write the scatter of `strains` to `path` (SVG). The axes span the
/// strains and their error bars with a 10 % margin, zero included; the
/// lines `eps1 = -eps2` (pure shear) and `eps1 = -2 eps2` (uniaxial
/// tension) are drawn dashed for reference.
pub fn write_fld_svg(path: &Path, strains: &[&GridStrain], title: &str) -> Result<(), String> {
    let span = |v: &mut dyn Iterator<Item = f64>| {
        let (lo, hi) = v.fold((0.0f64, 0.0f64), |(lo, hi), x| (lo.min(x), hi.max(x)));
        let pad = 0.1 * (hi - lo).max(1e-3);
        (lo - pad, hi + pad)
    };
    let (x0, x1) = span(
        &mut strains
            .iter()
            .flat_map(|s| [s.eps2 - 2.0 * s.sigma_eps2, s.eps2 + 2.0 * s.sigma_eps2]),
    );
    let (y0, y1) = span(
        &mut strains
            .iter()
            .flat_map(|s| [s.eps1 - 2.0 * s.sigma_eps1, s.eps1 + 2.0 * s.sigma_eps1]),
    );
    let px = |x: f64| M + (x - x0) / (x1 - x0) * (W - 2.0 * M);
    let py = |y: f64| H - M - (y - y0) / (y1 - y0) * (H - 2.0 * M);
    let mut s = String::new();
    let _ = writeln!(
        s,
        r#"<svg xmlns="http://www.w3.org/2000/svg" width="{W}" height="{H}" viewBox="0 0 {W} {H}">"#
    );
    let _ = writeln!(s, r#"<rect width="{W}" height="{H}" fill="white"/>"#);
    let _ = writeln!(
        s,
        r#"<text x="{}" y="24" font-size="15" text-anchor="middle" font-family="sans-serif">{title}</text>"#,
        W / 2.0
    );
    // Axes through zero, and the frame.
    let _ = writeln!(
        s,
        r#"<rect x="{M}" y="{M}" width="{}" height="{}" fill="none" stroke="black"/>"#,
        W - 2.0 * M,
        H - 2.0 * M
    );
    let _ = writeln!(
        s,
        r#"<line x1="{}" y1="{M}" x2="{}" y2="{}" stroke="gray"/>"#,
        px(0.0),
        px(0.0),
        H - M
    );
    let _ = writeln!(
        s,
        r#"<line x1="{M}" y1="{}" x2="{}" y2="{}" stroke="gray"/>"#,
        py(0.0),
        W - M,
        py(0.0)
    );
    for k in [1.0, 2.0] {
        // eps1 = -k eps2 through the frame (clipped by the frame's range).
        let (a, b) = (x0.max(-y1 / k), x1.min(-y0 / k));
        if a < b {
            let _ = writeln!(
                s,
                r#"<line x1="{:.2}" y1="{:.2}" x2="{:.2}" y2="{:.2}" stroke="gray" stroke-dasharray="4 4"/>"#,
                px(a),
                py(-k * a),
                px(b),
                py(-k * b)
            );
        }
    }
    for g in strains {
        let (cx, cy) = (px(g.eps2), py(g.eps1));
        let (ex, ey) = (2.0 * g.sigma_eps2, 2.0 * g.sigma_eps1);
        let _ = writeln!(
            s,
            r#"<g class="circle" data-id="{}"><line x1="{:.2}" y1="{cy:.2}" x2="{:.2}" y2="{cy:.2}" stroke="steelblue"/><line x1="{cx:.2}" y1="{:.2}" x2="{cx:.2}" y2="{:.2}" stroke="steelblue"/><circle cx="{cx:.2}" cy="{cy:.2}" r="2.5" fill="steelblue"/></g>"#,
            g.id,
            px(g.eps2 - ex),
            px(g.eps2 + ex),
            py(g.eps1 - ey),
            py(g.eps1 + ey)
        );
    }
    let label = |s: &mut String, x: f64, y: f64, t: &str, rot: bool| {
        let r = if rot {
            format!(r#" transform="rotate(-90 {x} {y})""#)
        } else {
            String::new()
        };
        let _ = writeln!(
            s,
            r#"<text x="{x}" y="{y}" font-size="13" text-anchor="middle" font-family="sans-serif"{r}>{t}</text>"#
        );
    };
    label(&mut s, W / 2.0, H - 18.0, "minor strain eps2", false);
    label(&mut s, 20.0, H / 2.0, "major strain eps1", true);
    for (v, x, y) in [(x0, M, H - M + 16.0), (x1, W - M, H - M + 16.0)] {
        label(&mut s, x, y, &format!("{v:.3}"), false);
    }
    for (v, y) in [(y0, H - M), (y1, M)] {
        label(&mut s, M - 24.0, y + 4.0, &format!("{v:.3}"), false);
    }
    s.push_str("</svg>\n");
    std::fs::write(path, s).map_err(|e| format!("cannot write {}: {e}", path.display()))
}
