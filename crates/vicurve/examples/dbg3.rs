use vicurve::curve::InitialCurve;
use vicurve::fit::{measure, FitConfig, parse_stages};
use vicurve::render::{render, Method, RenderSpec};
use vicurve::truth::{evaluate, Shape};
use vicurve::virtual_image::Kind;
fn main() {
    let args: Vec<String> = std::env::args().collect();
    let shape = Shape::Sine { y0: 150.2, amplitude: 12.0, wavelength: 150.0, phase: 0.3, x_min: 30.0, x_max: 270.0 };
    let spec = RenderSpec { width: 300, height: 300, shape, kind: Kind::Silhouette, method: Method::Coverage, foreground: 0.8, background: 0.2, blur_sigma: 1.0, bits: Some(8), ..RenderSpec::default() };
    let img = render(&spec).unwrap();
    let mut cfg = FitConfig::default();
    if let Some(s) = args.get(1) { cfg.stages = Some(parse_stages(s).unwrap()); }
    let init = InitialCurve::Segment { x0: 30.0, y0: 150.0, x1: 270.0, y1: 150.0 };
    let m = measure(&img, &init, &cfg).unwrap();
    for s in &m.stages { println!("R {} el {} it {} reref {} {:?} a {:.3} c {:.3}", s.half_width, s.elements, s.iterations, s.rereferences, s.outcome, s.a, s.c); }
    let d: Vec<f64> = m.points().iter().map(|p| spec.shape.signed_distance(p[0], p[1])).collect();
    let n = d.len();
    for i in (0..n).step_by(n / 24) { print!("{:.0}:{:+.3} ", m.samples[i].x, d[i]); }
    println!("\n{:?} skipped {:?}", evaluate(&m.points(), &spec.shape).unwrap(), m.skipped);
}
