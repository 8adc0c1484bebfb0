use std::time::Instant;
use vicurve::band::Band;
use vicurve::curve::InitialCurve;
use vicurve::fit::{measure_from, Elements, FitConfig, Stage};
use vicurve::interp::{Interpolation, Sampler};
use vicurve::spline::Basis;
use vicurve::virtual_image::Kind;
use vicurve::Image;
fn main() {
    let (cx, cy, r0, rf) = (256.3, 255.7, 200.0, 10.0);
    let img = Image::from_fn(512, 512, |x, y| {
        let d = ((x as f64 - cx).hypot(y as f64 - cy)) - r0;
        (Kind::Silhouette.gamma(d / rf) * 255.0).round() / 255.0
    });
    for _ in 0..3 {
        let t = Instant::now();
        let s = Sampler::new(&img, Interpolation::CubicBSpline);
        let t1 = t.elapsed();
        let c = InitialCurve::Circle {
            cx: 256.0,
            cy: 256.0,
            r: 203.0,
        }
        .to_curve()
        .unwrap();
        let t2 = t.elapsed();
        let b = Basis::new(3, 25, c.param_length(), true).unwrap();
        let band = Band::build(&c, &b, 10.0, Kind::Silhouette, 512, 512).unwrap();
        let t3 = t.elapsed();
        let cfg = FitConfig {
            stages: Some(vec![Stage {
                half_width: 10.0,
                elements: Elements::Count(25),
            }]),
            ..Default::default()
        };
        let m = measure_from(&s, c.clone(), &cfg).unwrap();
        let t4 = t.elapsed();
        println!(
            "sampler {:?} curve {:?} band {:?} ({} px) measure_from {:?} it {}",
            t1,
            t2 - t1,
            t3 - t2,
            band.len(),
            t4 - t3,
            m.iterations()
        );
    }
}
