//! How the error on a sharp (exact-coverage, noiseless, 8-bit) disc depends
//! on its sub-pixel position, default settings (docs/benchmarks.md; under
//! the sine profile alone a sharp edge aliases with the pixel grid, the
//! pixel-edge stage removes that).
//!
//! `cargo run --release -p vicurve --example coverage_positions`

use vicurve::curve::InitialCurve;
use vicurve::fit::{measure, FitConfig};
use vicurve::render::{render, Method, RenderSpec};
use vicurve::truth::{evaluate, Shape};
use vicurve::virtual_image::Kind;

fn main() {
    println!("| centre offset (px) | radius (px) | bias (px) | scatter (px) |");
    println!("|---|---|---|---|");
    let (mut lo, mut hi, mut smin, mut smax): (f64, f64, f64, f64) =
        (f64::MAX, f64::MIN, f64::MAX, f64::MIN);
    for dx in [0.0, 0.13, 0.37, 0.5, 0.71] {
        for r in [149.6, 150.0, 150.3] {
            let spec = RenderSpec {
                width: 400,
                height: 400,
                shape: Shape::Circle {
                    cx: 200.0 + dx,
                    cy: 199.71,
                    r,
                },
                kind: Kind::Silhouette,
                method: Method::Coverage,
                foreground: 0.8,
                background: 0.2,
                bits: Some(8),
                ..RenderSpec::default()
            };
            let image = render(&spec).expect("render");
            let init = InitialCurve::Circle {
                cx: 203.0,
                cy: 198.0,
                r: r - 5.0,
            };
            let m = measure(&image, &init, &FitConfig::default()).expect("measure");
            let s = evaluate(&m.points(), &spec.shape).expect("evaluate");
            println!("| {dx} | {r} | {:+.2e} | {:.2e} |", s.bias, s.scatter);
            lo = lo.min(s.bias);
            hi = hi.max(s.bias);
            smin = smin.min(s.scatter);
            smax = smax.max(s.scatter);
        }
    }
    println!("\nbias from {lo:+.2e} to {hi:+.2e} px, scatter from {smin:.2e} to {smax:.2e} px");
}
