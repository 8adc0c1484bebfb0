use vicurve::curve::InitialCurve;
use vicurve::fit::{measure, FitConfig, parse_stages};
use vicurve::render::{render, Method, RenderSpec};
use vicurve::truth::{evaluate, Shape};
use vicurve::virtual_image::Kind;
fn main() {
    let args: Vec<String> = std::env::args().collect();
    let rad: f64 = std::env::var("VIC_R").map_or(150.0, |v| v.parse().unwrap()); let sz = (2.0 * rad + 100.0) as usize; let spec = RenderSpec { width: sz, height: sz, shape: Shape::Circle { cx: sz as f64 / 2.0 + 0.37, cy: sz as f64 / 2.0 - 0.29, r: rad }, kind: Kind::Silhouette,
        method: Method::Coverage, foreground: 0.8, background: 0.2, bits: Some(8), noise: std::env::var("VIC_NOISE").map_or(0.0, |v| v.parse().unwrap()), seed: 7, blur_sigma: args.get(2).map_or(0.0, |s| s.parse().unwrap()), ..RenderSpec::default() };
    let img = render(&spec).unwrap();
    let mut cfg = FitConfig::default();
    if std::env::var("VIC_BILINEAR").is_ok() { cfg.interpolation = vicurve::interp::Interpolation::Bilinear; }
    if let Some(s) = args.get(1) { if s != "default" { cfg.stages = Some(parse_stages(s).unwrap()); } }
    let m = measure(&img, &InitialCurve::Circle { cx: sz as f64 / 2.0 + 3.0, cy: sz as f64 / 2.0 - 2.0, r: rad - 5.0 }, &cfg).unwrap();
    for s in &m.stages { println!("{:?}", s); }
    let st = evaluate(&m.points(), &spec.shape).unwrap();
    println!("{:?} skipped {:?}", st, m.skipped);
}
