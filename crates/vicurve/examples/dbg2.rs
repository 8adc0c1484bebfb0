use vicurve::curve::InitialCurve;
use vicurve::fit::{measure, FitConfig, parse_stages};
use vicurve::render::{render, Method, RenderSpec};
use vicurve::truth::{evaluate, Shape};
use vicurve::virtual_image::Kind;
fn main() {
    let args: Vec<String> = std::env::args().collect();
    let rho: f64 = args[3].parse().unwrap();
    let tilt: f64 = std::env::var("VIC_TILT").map_or(0.3, |v| v.parse().unwrap());
    let (cx, cy) = (200.0 + rho * tilt.sin(), 200.3 + rho * tilt.cos());
    let spec = RenderSpec { width: 400, height: 400, shape: Shape::Circle { cx, cy, r: rho }, kind: Kind::Silhouette,
        method: Method::Coverage, foreground: 0.8, background: 0.2, bits: None, blur_sigma: args[2].parse().unwrap(), ..RenderSpec::default() };
    let img = render(&spec).unwrap();
    let mut cfg = FitConfig::default();
    cfg.stages = Some(parse_stages(&args[1]).unwrap());
    if std::env::var("VIC_BILINEAR").is_ok() { cfg.interpolation = vicurve::interp::Interpolation::Bilinear; }
    // A segment through the top of the circle, tilted like it.
    let (tx, ty) = (tilt.cos(), -tilt.sin());
    let (px, py) = (cx - rho * tilt.sin(), cy - rho * tilt.cos());
    let init = InitialCurve::Segment { x0: px - 120.0 * tx, y0: py - 120.0 * ty + 1.0, x1: px + 120.0 * tx, y1: py + 120.0 * ty + 1.0 };
    let m = measure(&img, &init, &cfg).unwrap();
    let st = evaluate(&m.points(), &spec.shape).unwrap();
    let pts = m.points(); let n = pts.len();
    let mid = evaluate(&pts[n / 4..3 * n / 4], &spec.shape).unwrap();
    let d: Vec<f64> = pts.iter().map(|p| spec.shape.signed_distance(p[0], p[1])).collect();
    if std::env::var("VIC_DUMP").is_ok() { for (i, v) in d.iter().enumerate() { if i % 5 == 0 { println!("{i} {v:+.4e}"); } } }
    println!("middle half: bias {:+.3e} scatter {:.2e}", mid.bias, mid.scatter);
    println!("{} a {:.5} c {:.5} bias {:+.3e} scatter {:.2e}", m.outcome, m.stages.last().unwrap().a, m.stages.last().unwrap().c, st.bias, st.scatter);
}
