use vicurve::curve::InitialCurve;
use vicurve::fit::{measure, Elements, FitConfig, Stage};
use vicurve::virtual_image::Kind;
use vicurve::Image;
fn main() {
    let (cx, cy, r0, rf) = (256.3, 255.7, 200.0, 10.0);
    let img = Image::from_fn(512, 512, |x, y| {
        let d = ((x as f64 - cx).hypot(y as f64 - cy)) - r0;
        let v = Kind::Silhouette.gamma(d / rf);
        (v * 255.0).round() / 255.0
    });
    for n_el in [12usize, 25, 50, 100] {
        let cfg = FitConfig { stages: Some(vec![Stage { half_width: 10.0, elements: Elements::Count(n_el) }]), ..Default::default() };
        let t = std::time::Instant::now();
        let m = measure(&img, &InitialCurve::Circle { cx: 256.0, cy: 256.0, r: 203.0 }, &cfg).unwrap();
        let el = t.elapsed();
        let d: Vec<f64> = m.samples.iter().map(|s| (s.x - cx).hypot(s.y - cy) - r0).collect();
        let mean = d.iter().sum::<f64>() / d.len() as f64;
        let sc = (d.iter().map(|v| (v - mean).powi(2)).sum::<f64>() / d.len() as f64).sqrt();
        println!("n_el {n_el}: {} it {} mean {mean:.2e} scatter {sc:.2e} fiterr {:.1e} sigma {:.1e} {:?} a {:.4} c {:.4} t {:?}", m.outcome, m.iterations(), m.curve_fit_error, m.samples[0].sigma, m.stages[0].band_pixels, m.stages[0].a, m.stages[0].c, el);
    }
}
