use vicurve::curve::InitialCurve;
use vicurve::fit::{measure, FitConfig, parse_stages};
use vicurve::render::{render, Method, RenderSpec};
use vicurve::truth::{evaluate, Shape};
use vicurve::virtual_image::Kind;
fn main() {
    let args: Vec<String> = std::env::args().collect();
    let (cx, cy) = (512.3, 511.6);
    let spec = RenderSpec { width: 1024, height: 1024, shape: Shape::Star { cx, cy, r0: 300.0, amplitude: 0.2, lobes: 5, phase: 0.0 }, kind: Kind::Silhouette, method: Method::Coverage, foreground: 0.8, background: 0.2, blur_sigma: 1.0, noise: std::env::var("VIC_NOISE").map_or(0.01, |v| v.parse().unwrap()), seed: 3, bits: Some(8), ..RenderSpec::default() };
    let t = std::time::Instant::now();
    let img = render(&spec).unwrap();
    println!("render {:?}", t.elapsed());
    let mut cfg = FitConfig::default();
    if let Some(s) = args.get(1) { cfg.stages = Some(parse_stages(s).unwrap()); }
    if let Ok(p) = std::env::var("VIC_P") { cfg.degree = p.parse().unwrap(); }
    let init = InitialCurve::Circle { cx: cx + 10.0, cy, r: 300.0 };
    let t = std::time::Instant::now();
    let m = measure(&img, &init, &cfg).unwrap();
    println!("measure {:?}", t.elapsed());
    for s in &m.stages { println!("R {} el {} it {} reref {} {:?} a {:.3} c {:.3} {:.1}ms", s.half_width, s.elements, s.iterations, s.rereferences, s.outcome, s.a, s.c, s.seconds * 1e3); }
    let d: Vec<f64> = m.points().iter().map(|p| spec.shape.signed_distance(p[0], p[1])).collect();
    let n = d.len();
    for i in (0..n).step_by(n / 60) { print!("{:+.4} ", d[i]); }
    println!("\n{:?} skipped {:?}", evaluate(&m.points(), &spec.shape).unwrap(), m.skipped);
}
