//! The automatic element length (`fit/refine.rs`): a last step onto the
//! shortest elements judged on references of its own.

use vicurve::curve::InitialCurve;
use vicurve::fit::{FitConfig, Outcome};

use super::run;
use crate::common::disc;

/// A small disc (radius 10 px: a hole, a circle grid's dot), blurred by 1
/// px, noiseless, 16 bits, from a circle 0.5 px off. Its 63 px of outline
/// start on the 8 elements a closed curve needs at least (7.9 px), whose
/// best cubic spline is 4.0e-3 px (RMS) off a circle, and so was the
/// measurement (measured before): the pixel-edge stage's last step onto 5
/// px elements was judged on the coarse reference, which holds that error
/// at the coarse elements' period, beyond the finer elements' reach. On
/// references of their own the step is taken: 13 elements, scatter 5e-4
/// px (measured).
#[test]
fn a_small_disc_refines_on_its_own_reference() {
    let spec = disc(64, (32.27, 31.64, 10.0), 1.0, 0.0, 7, Some(16));
    let init = InitialCurve::Circle {
        cx: 32.6,
        cy: 31.3,
        r: 10.0,
    };
    let (m, s) = run(&spec, init, FitConfig::default());
    let elements = m.stages.last().unwrap().elements;
    println!(
        "disc r = 10, blur 1: {elements} elements, bias {:+.2e} scatter {:.2e} max {:.2e}",
        s.bias, s.scatter, s.max_abs
    );
    assert_eq!(m.outcome, Outcome::Converged);
    assert!(elements >= 12, "{elements} elements");
    assert!(s.scatter <= 1.5e-3, "scatter {}", s.scatter);
    assert!(s.bias.abs() <= 1e-3, "bias {}", s.bias);
}

/// A smooth closed curve with one tight bay (radius of curvature 4.4 px)
/// and gentle bends elsewhere: a mean radius of 59.8 px with harmonics 4,
/// 5 and 6, darker than its background (111 on 188 of 255), its pixel
/// coverage (16 x 16 points a pixel) blurred by 1.31 px on the pixel grid
/// (as `bench/probes/shapes.py` rendered its seed 1110 before it took
/// exact coverage), noiseless, 8 bits, measured from the automatic start.
/// The pixel-edge stage keeps elements of 4.8 px (the finer fit's noise
/// would cost more than the bay's shape error, summed over the whole
/// curve), which cut the bay by up to 0.044 px, 4.2 `sigma` (measured
/// before). The rejected finer fit's difference says where: the samples
/// near the bay are now within 3 `sigma` of the curve (2.3, measured), and
/// flagged.
#[test]
fn a_bay_the_kept_elements_cut_is_charged_where_it_lies() {
    use vicurve::render::blur::gaussian_blur;
    use vicurve::render::noise::quantise;
    let (size, cx, cy) = (202usize, 102.73662016190723, 98.3095556303287);
    let radius = |t: f64| {
        59.791118599831606
            * (1.0
                + 0.14101341 * (6.0 * t + 4.0485384).cos()
                + 0.17212107 * (4.0 * t + 4.76927401).cos()
                + 0.04577118 * (5.0 * t + 0.35121078).cos())
    };
    let n = 8000;
    let ring: Vec<[f64; 2]> = (0..n)
        .map(|k| {
            let t = std::f64::consts::TAU * k as f64 / n as f64;
            [cx + radius(t) * t.cos(), cy + radius(t) * t.sin()]
        })
        .collect();
    // The coverage of 16 x 16 points in each pixel, as the probe's.
    let k = 16;
    let cover: Vec<f64> = (0..size * size)
        .map(|i| {
            let (col, row) = ((i % size) as f64, (i / size) as f64);
            let mut inside = 0;
            for a in 0..k {
                for b in 0..k {
                    let u = col + (b as f64 + 0.5) / k as f64 - 0.5 - cx;
                    let w = row + (a as f64 + 0.5) / k as f64 - 0.5 - cy;
                    inside += usize::from(u.hypot(w) <= radius(w.atan2(u)));
                }
            }
            inside as f64 / (k * k) as f64
        })
        .collect();
    let (outside, inside) = (188.2549626734435 / 255.0, 111.3499740718311 / 255.0);
    let light: Vec<f64> = cover
        .iter()
        .map(|c| outside + (inside - outside) * c)
        .collect();
    let image = vicurve::image::Image::new(size, size, light).expect("image");
    let mut light = gaussian_blur(&image, 1.31).expect("blur").data().to_vec();
    quantise(&mut light, 8);
    let image = vicurve::image::Image::new(size, size, light).expect("image");
    let init = vicurve::start::find_silhouette(&image, &vicurve::start::StartConfig::default())
        .expect("start")
        .curve;
    let m = vicurve::fit::measure(&image, &init, &FitConfig::default()).expect("measure");
    assert_eq!(m.outcome, Outcome::Converged);
    // Signed distance to the dense polygon (outside positive).
    let inside_of = |p: [f64; 2]| {
        let (u, w) = (p[0] - cx, p[1] - cy);
        u.hypot(w) < radius(w.atan2(u))
    };
    let error = |p: [f64; 2]| {
        let d = ring
            .iter()
            .zip(ring.iter().cycle().skip(1))
            .map(|(a, b)| {
                let (dx, dy) = (b[0] - a[0], b[1] - a[1]);
                let t = (((p[0] - a[0]) * dx + (p[1] - a[1]) * dy) / (dx * dx + dy * dy))
                    .clamp(0.0, 1.0);
                (p[0] - a[0] - t * dx).hypot(p[1] - a[1] - t * dy)
            })
            .fold(f64::INFINITY, f64::min);
        if inside_of(p) {
            -d
        } else {
            d
        }
    };
    // The bay: where the curvature (of the circle through points 1 px
    // apart on each side) is largest.
    let bay = (0..n)
        .map(|k| {
            let (a, p, b) = (ring[(k + n - 20) % n], ring[k], ring[(k + 20) % n]);
            let (u, v) = ([p[0] - a[0], p[1] - a[1]], [b[0] - p[0], b[1] - p[1]]);
            let cross = (u[0] * v[1] - u[1] * v[0]).abs();
            let c = 2.0 * cross
                / (u[0].hypot(u[1]) * v[0].hypot(v[1]) * (b[0] - a[0]).hypot(b[1] - a[1]));
            (c, p)
        })
        .fold(
            (0.0, [0.0; 2]),
            |best, c| if c.0 > best.0 { c } else { best },
        )
        .1;
    let (mut worst, mut largest, mut flagged) = (0.0f64, 0.0f64, 0);
    for s in m
        .samples
        .iter()
        .filter(|s| (s.x - bay[0]).hypot(s.y - bay[1]) <= 8.0)
    {
        let e = error([s.x, s.y]).abs();
        worst = worst.max(e / s.sigma);
        largest = largest.max(e);
        flagged += usize::from(s.misfit);
    }
    let elements = m.stages.last().unwrap().elements;
    println!(
        "one tight bay at ({:.1}, {:.1}): {elements} elements; within 8 px of it max error \
         {largest:.3} px, largest error / sigma {worst:.1}, {flagged} samples flagged",
        bay[0], bay[1]
    );
    assert!(largest > 0.02, "{largest:.3} px: the bay is no test");
    assert!(worst <= 3.0, "{worst:.1} sigma");
    assert!(flagged > 0);
}
