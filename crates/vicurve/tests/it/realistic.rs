//! Synthesized realistic cases with exact truth (issue 4's "Tests to add"):
//! a textured bright region, JPEG compression at quality 75, and a disc
//! touching the image border. Each measured with default settings from the
//! automatic start. The bounds are about twice the figures measured; the
//! figures are printed (`cargo test --release -p vicurve --test realistic
//! -- --nocapture`) and recorded in docs/benchmarks.md ("Realistic images").

use vicurve::curve::InitialCurve;
use vicurve::fit::{measure, FitConfig, LevelModel, Measurement, Outcome};
use vicurve::render::blur::gaussian_blur;
use vicurve::render::noise::{add_gaussian_noise, quantise, Rng};
use vicurve::render::{render, Method, RenderSpec};
use vicurve::start::{find_silhouette, AutoStart, StartConfig};
use vicurve::truth::{evaluate, ErrorStats, Shape};
use vicurve::virtual_image::{Kind, Profile};
use vicurve::{Error, Image};

/// Gray levels of the scenes: a bright object (0.75) on a dark ground (0.2).
const BRIGHT: f64 = 0.75;
const DARK: f64 = 0.2;

/// How a scene is painted and degraded.
struct Scene {
    width: usize,
    height: usize,
    shape: Shape,
    /// Standard deviation of the texture inside the object, as a fraction of
    /// the contrast `BRIGHT - DARK`.
    texture_inside: f64,
    /// The same outside.
    texture_outside: f64,
    /// Correlation length of the texture (the deviation of the Gaussian that
    /// smooths white noise into it), px.
    texture_length: f64,
    /// Optical blur (Gaussian deviation), px.
    blur: f64,
    /// Additive Gaussian noise, as a fraction of the contrast.
    noise: f64,
    seed: u64,
}

/// The exact fraction of each pixel inside `shape`.
fn coverage(width: usize, height: usize, shape: &Shape) -> Image {
    render(&RenderSpec {
        width,
        height,
        shape: shape.clone(),
        kind: Kind::Silhouette,
        method: Method::Coverage,
        foreground: 1.0,
        background: 0.0,
        ..RenderSpec::default()
    })
    .expect("coverage")
}

/// A smooth random texture of zero mean and unit deviation: white Gaussian
/// noise (seeded) blurred by a Gaussian of deviation `length` px.
fn texture(width: usize, height: usize, length: f64, seed: u64) -> Vec<f64> {
    let mut rng = Rng::new(seed);
    let white: Vec<f64> = (0..width * height).map(|_| rng.normal()).collect();
    let smooth = gaussian_blur(&Image::new(width, height, white).unwrap(), length).unwrap();
    let d = smooth.data();
    let n = d.len() as f64;
    let mean = d.iter().sum::<f64>() / n;
    let sd = (d.iter().map(|v| (v - mean).powi(2)).sum::<f64>() / n).sqrt();
    d.iter().map(|v| (v - mean) / sd).collect()
}

/// The scene as an 8-bit camera records it: each pixel mixes the textured
/// inside and outside levels by its exact coverage (the texture, smooth
/// over several pixels, is taken at the pixel centre), then the optics blur
/// it, the sensor adds noise and the file stores 8 bits.
fn paint(s: &Scene) -> Image {
    let (w, h) = (s.width, s.height);
    let contrast = BRIGHT - DARK;
    let inside = texture(w, h, s.texture_length, s.seed);
    let outside = texture(w, h, s.texture_length, s.seed + 1);
    let data: Vec<f64> = coverage(w, h, &s.shape)
        .data()
        .iter()
        .zip(inside.iter().zip(&outside))
        .map(|(&f, (&ti, &to))| {
            let i = BRIGHT + s.texture_inside * contrast * ti;
            let o = DARK + s.texture_outside * contrast * to;
            o + f * (i - o)
        })
        .collect();
    let mut image = gaussian_blur(&Image::new(w, h, data).unwrap(), s.blur).unwrap();
    add_gaussian_noise(image.data_mut(), s.noise * contrast, s.seed + 2);
    quantise(image.data_mut(), 8);
    image
}

/// A five-lobed star, radius 95 +- 11.4 px (smallest radius of curvature
/// about 37 px, in its hollows), off the pixel grid.
const STAR: Shape = Shape::Star {
    cx: 150.3,
    cy: 149.6,
    r0: 95.0,
    amplitude: 0.12,
    lobes: 5,
    phase: 0.4,
};

fn stats(m: &Measurement, shape: &Shape) -> ErrorStats {
    evaluate(&m.points(), shape).expect("evaluate")
}

fn show(name: &str, m: &Measurement, e: &ErrorStats) {
    let last = m.stages.last().expect("a stage");
    println!(
        "{name}: {} bias {:+.2e} scatter {:.2e} max {:.2e} px ({} points; last stage R {} px, {} elements, {:?})",
        m.outcome, e.bias, e.scatter, e.max_abs, e.count, last.half_width, last.elements, last.profile
    );
}

fn auto_start(image: &Image) -> AutoStart {
    find_silhouette(image, &StartConfig::default()).expect("automatic start")
}

/// Measure from the automatic start with default settings (or `config`).
fn measure_auto(image: &Image, config: &FitConfig) -> Measurement {
    let start = auto_start(image);
    let m = measure(image, &start.curve, config).expect("measure");
    assert_eq!(m.outcome, Outcome::Converged);
    m
}

/// A star whose bright inside carries a smooth random texture (deviation
/// 10 % of the contrast, correlation length 3 px) on a background textured
/// at 5 %; blur 1 px, 1 % noise, 8 bits. From the automatic start and from a
/// circle, default settings.
///
/// The texture is not noise to the method: near the edge it changes the
/// local contrast, and a brighter patch just inside the edge looks, to any
/// fit of a step of constant contrast, like the edge moved outward. The
/// half-level crossing of a blurred step moves by about `1.25 s dC / C`
/// (`s` the edge's spread), 0.13 px for dC = 10 %: hence the scatter,
/// 1.75e-1 px here against 7.7e-3 px without texture. Nor is it symmetric:
/// the crossing moves as `1 / (C + dC)`, so darker patches move it in more
/// than brighter ones move it out, a mean inward shift of about
/// `1.25 s var(dC / C)` for the texture averaged over an element. The
/// automatic element length follows the texture down to the shortest
/// elements (5 px), which average little of it: over 8 other texture draws
/// the mean error is -1.6e-2 px (+-1.0e-2 from draw to draw; this draw's
/// -5.1e-2 is the worst seen), against -3.4e-3 px (+-1.4e-2) with elements
/// of 20 px or longer ([`textured_star_over_texture_draws`]). The global
/// gray-level pair does no better than the varying levels.
#[test]
fn textured_star() {
    let scene = |inside, outside| Scene {
        width: 300,
        height: 300,
        shape: STAR,
        texture_inside: inside,
        texture_outside: outside,
        texture_length: 3.0,
        blur: 1.0,
        noise: 0.01,
        seed: 11,
    };
    let shape = STAR;
    let textured = paint(&scene(0.1, 0.05));
    let clean = paint(&scene(0.0, 0.0));

    let m = measure_auto(&textured, &FitConfig::default());
    let e = stats(&m, &shape);
    show("textured star, automatic start", &m, &e);
    let circle = InitialCurve::Circle {
        cx: 153.0,
        cy: 148.0,
        r: 100.0,
    };
    let mc = measure(&textured, &circle, &FitConfig::default()).unwrap();
    let ec = stats(&mc, &shape);
    show("textured star, circle start", &mc, &ec);
    let global = FitConfig {
        levels: LevelModel::Global,
        ..FitConfig::default()
    };
    let mg = measure_auto(&textured, &global);
    let eg = stats(&mg, &shape);
    show("textured star, global gray levels", &mg, &eg);
    let m0 = measure_auto(&clean, &FitConfig::default());
    let e0 = stats(&m0, &shape);
    show("same star without texture", &m0, &e0);

    assert_eq!(mc.outcome, Outcome::Converged);
    for e in [&e, &ec, &eg] {
        assert!(e.bias.abs() <= 0.1, "{e:?}");
        assert!(e.max_abs <= 1.2, "{e:?}");
        assert!(e.scatter <= 0.35, "{e:?}");
    }
    // The two starts end on the same curve (the last stage's fixed point).
    assert!((e.bias - ec.bias).abs() <= 2e-3, "{e:?} vs {ec:?}");
    // Its elements (5 px) follow the texture: the residuals keep none of
    // it, and `sigma` (the white-noise one, `fit::correlated`) is 4.8 times
    // under the scatter. Not asserted: a known fault (see docs).
    println!(
        "  textured star: scatter / sigma {:.2}",
        e.scatter / crate::common::rms_sigma(&m)
    );
    // Without texture the same star is measured ten times better: the
    // figures above are the texture's.
    assert!(e0.max_abs <= 0.07 && e0.bias.abs() <= 4e-3, "{e0:?}");
}

/// Encode an image as a grayscale JPEG of the given quality and read it back
/// as a user would, through `vicurve::io::load_image`.
fn through_jpeg(image: &Image, quality: u8) -> Image {
    use image::codecs::jpeg::JpegEncoder;
    let bytes: Vec<u8> = image
        .data()
        .iter()
        .map(|v| (v.clamp(0.0, 1.0) * 255.0).round() as u8)
        .collect();
    let mut jpeg = Vec::new();
    JpegEncoder::new_with_quality(&mut jpeg, quality)
        .encode(
            &bytes,
            image.width() as u32,
            image.height() as u32,
            image::ExtendedColorType::L8,
        )
        .expect("JPEG encoding");
    let path = std::env::temp_dir().join(format!(
        "vicurve-realistic-{}-q{quality}.jpg",
        std::process::id()
    ));
    std::fs::write(&path, &jpeg).expect("write the JPEG");
    let read = vicurve::io::load_image(&path);
    std::fs::remove_file(&path).ok();
    read.expect("read the JPEG")
}

/// The star blurred by 1.2 px with 1.5 % noise, saved as a JPEG of quality
/// 75 (8x8 blocks of quantised cosines: ringing and block edges of a few
/// gray levels along the edge) and read back. Measured from the automatic
/// start with default settings, against the same 8-bit image before
/// compression.
#[test]
fn jpeg_quality_75_star() {
    let shape = STAR;
    let original = paint(&Scene {
        width: 300,
        height: 300,
        shape: shape.clone(),
        texture_inside: 0.0,
        texture_outside: 0.0,
        texture_length: 1.0,
        blur: 1.2,
        noise: 0.015,
        seed: 21,
    });
    let jpeg = through_jpeg(&original, 75);
    let n = original.data().len() as f64;
    let rms = (original
        .data()
        .iter()
        .zip(jpeg.data())
        .map(|(a, b)| (a - b).powi(2))
        .sum::<f64>()
        / n)
        .sqrt();
    println!(
        "JPEG q75: rms change of the gray levels {:.2} (of 255)",
        rms * 255.0
    );
    let m = measure_auto(&jpeg, &FitConfig::default());
    let e = stats(&m, &shape);
    show("JPEG q75 star", &m, &e);
    let m8 = measure_auto(&original, &FitConfig::default());
    let e8 = stats(&m8, &shape);
    show("same star before compression", &m8, &e8);
    assert!(e.bias.abs() <= 6e-3, "{e:?}");
    assert!(e.max_abs <= 0.16, "{e:?}");
    assert!(e.scatter <= 0.05, "{e:?}");
}

/// A disc cut by the left border of the image (19.7 px of its 160 px
/// width lie beyond it). The automatic start is an open curve along the visible part
/// of the edge, its ends kept 3 px from the border, and the measurement
/// along it is as accurate as on a whole disc. A circle drawn by the user
/// over the whole disc crosses the border: a typed error that says where
/// and what to do, not a partial result.
#[test]
fn disc_cut_by_the_image_border() {
    let shape = Shape::Circle {
        cx: 60.3,
        cy: 120.6,
        r: 80.0,
    };
    let image = paint(&Scene {
        width: 240,
        height: 240,
        shape: shape.clone(),
        texture_inside: 0.0,
        texture_outside: 0.0,
        texture_length: 1.0,
        blur: 1.0,
        noise: 0.01,
        seed: 31,
    });
    let start = auto_start(&image);
    // (Either side's region may be chosen: both touch the border and share
    // this edge; the polarity is found by the fit.)
    assert!(!start.closed, "{start:?}");
    let InitialCurve::Polyline { points, .. } = &start.curve else {
        panic!("{:?}", start.curve)
    };
    assert!(points.iter().all(|p| p[0] >= 3.0), "an end on the border");
    let m = measure(&image, &start.curve, &FitConfig::default()).unwrap();
    assert_eq!(m.outcome, Outcome::Converged);
    let e = stats(&m, &shape);
    show("disc cut by the border, automatic start", &m, &e);
    // The measured arc is the visible edge but for the ends' few pixels
    // (the start's 3 px, the trim where the last band leaves the image):
    // x = 60.3 + 80 cos(t) >= 8 is |t| <= 130.8 degrees.
    let turn = |p: &[f64; 2]| (p[1] - 120.6).atan2(p[0] - 60.3).to_degrees();
    let pts = m.points();
    let (lo, hi) = pts
        .iter()
        .map(turn)
        .fold((180.0f64, -180.0f64), |(lo, hi), t| (lo.min(t), hi.max(t)));
    println!("  arc measured: from {lo:.1} to {hi:.1} degrees (visible: +-138.9)");
    assert!(lo < -130.0 && hi > 130.0, "{lo} to {hi}");
    assert!(e.bias.abs() <= 2.5e-3 && e.max_abs <= 0.018, "{e:?}");

    let circle = InitialCurve::Circle {
        cx: 62.0,
        cy: 122.0,
        r: 82.0,
    };
    let err = measure(&image, &circle, &FitConfig::default()).unwrap_err();
    println!("  circle start over the border: {err}");
    assert!(
        matches!(err, Error::CurveOutsideImage { x, .. } if x < 0.0),
        "{err:?}"
    );
}

/// A dark object on textured cloth, cut by the image border, with two
/// specks of about 150 pixels seen whole: a dark one on the cloth and a
/// bright one on the object. Both specks are regions that do not touch the
/// border; the object's edge is long and as sharp. The automatic start must
/// take the object's edge (its score, contrast times length, is some ten
/// times a speck's), and the measurement from it must find that edge.
#[test]
fn dark_object_on_cloth_beats_the_specks() {
    let shape = Shape::Circle {
        cx: 40.3,
        cy: 150.6,
        r: 110.0,
    };
    let mut image = paint(&Scene {
        width: 300,
        height: 300,
        shape: shape.clone(),
        texture_inside: 0.03,
        texture_outside: 0.12,
        texture_length: 2.0,
        blur: 1.0,
        noise: 0.01,
        seed: 51,
    });
    // The object dark, the cloth bright; then the specks (radius 7 px).
    let speck = |d: &mut [f64], cx: f64, cy: f64, v: f64| {
        for j in 0..300 {
            for i in 0..300 {
                if (i as f64 - cx).hypot(j as f64 - cy) < 7.0 {
                    d[j * 300 + i] = v;
                }
            }
        }
    };
    let d = image.data_mut();
    d.iter_mut().for_each(|v| *v = 1.0 - *v);
    speck(d, 240.0, 60.0, 1.0 - BRIGHT);
    speck(d, 60.0, 150.0, 1.0 - DARK);
    let start = auto_start(&image);
    assert!(!start.closed, "a speck was taken: {start:?}");
    let InitialCurve::Polyline { points, .. } = &start.curve else {
        panic!("{:?}", start.curve)
    };
    let on_edge = points
        .iter()
        .all(|p| ((p[0] - 40.3).hypot(p[1] - 150.6) - 110.0).abs() < 2.0);
    assert!(on_edge && points.len() > 200, "{} points", points.len());
    let m = measure(&image, &start.curve, &FitConfig::default()).unwrap();
    assert_eq!(m.outcome, Outcome::Converged);
    let e = stats(&m, &shape);
    show("dark object on cloth, automatic start", &m, &e);
    // The cloth's texture (12 % of the contrast) dominates the error, as in
    // `textured_star`.
    assert!(
        e.bias.abs() <= 0.08 && e.scatter <= 0.3 && e.max_abs <= 1.0,
        "{e:?}"
    );
}

/// A whole disc whose edge passes `gap` px from the left border: the
/// border cuts its bands, which keep their pixels in the image, so the
/// edge's blur is measured and the pixel edge takes over, even half a
/// pixel from the border. (When a closed curve's band had to fit in the
/// image, the coarse stages were skipped, the blur could not be estimated
/// on its 8-px band and the result kept the blur's curvature shift, about
/// -6e-3 px here; at 0.5 px the edge was refused.)
#[test]
fn disc_grazing_the_image_border() {
    let disc = |gap: f64| Shape::Circle {
        cx: 80.3 + gap,
        cy: 100.6,
        r: 80.0,
    };
    let scene = |gap| Scene {
        width: 240,
        height: 200,
        shape: disc(gap),
        texture_inside: 0.0,
        texture_outside: 0.0,
        texture_length: 1.0,
        blur: 1.0,
        noise: 0.01,
        seed: 41,
    };
    for gap in [0.5, 3.0, 6.0] {
        let image = paint(&scene(gap));
        let start = auto_start(&image);
        assert!(start.closed);
        let m = measure(&image, &start.curve, &FitConfig::default()).unwrap();
        assert_eq!(m.outcome, Outcome::Converged);
        let e = stats(&m, &disc(gap));
        show(&format!("disc {gap} px from the border"), &m, &e);
        let last = m.stages.last().map(|s| s.profile);
        assert!(matches!(last, Some(Profile::PixelEdge { .. })), "{last:?}");
        assert!(e.bias.abs() <= 3e-3 && e.max_abs <= 2e-2, "{e:?}");
    }
}

/// The spread of the textured star's errors over texture draws (slow: run
/// with `--ignored`). Also with the last stage's elements kept at 20 px or
/// longer (explicit stages: no pixel-edge stage, the sine profile's blur
/// correction instead), to show how much of the scatter comes from the
/// automatic element length following the texture.
#[test]
#[ignore]
fn textured_star_over_texture_draws() {
    use vicurve::fit::{Elements, Stage};
    let stage = |half_width, elements| Stage {
        half_width,
        elements,
    };
    let long = FitConfig {
        stages: Some(vec![
            stage(20.0, Elements::Length(80.0)),
            stage(10.0, Elements::Length(40.0)),
            stage(5.0, Elements::Length(40.0)),
            stage(
                2.0,
                Elements::Auto {
                    longest: 40.0,
                    shortest: 20.0,
                },
            ),
        ]),
        ..FitConfig::default()
    };
    let shape = STAR;
    for (name, config) in [
        ("default", FitConfig::default()),
        ("elements >= 20 px", long),
    ] {
        let mut all = Vec::new();
        for seed in 100..108 {
            let image = paint(&Scene {
                width: 300,
                height: 300,
                shape: shape.clone(),
                texture_inside: 0.1,
                texture_outside: 0.05,
                texture_length: 3.0,
                blur: 1.0,
                noise: 0.01,
                seed,
            });
            let m = measure_auto(&image, &config);
            all.push((stats(&m, &shape), m.stages.last().unwrap().elements));
        }
        let n = all.len() as f64;
        let mean = |f: &dyn Fn(&ErrorStats) -> f64| all.iter().map(|(e, _)| f(e)).sum::<f64>() / n;
        let bias = mean(&|e| e.bias);
        let sd = (all
            .iter()
            .map(|(e, _)| (e.bias - bias).powi(2))
            .sum::<f64>()
            / (n - 1.0))
            .sqrt();
        let worst = all.iter().map(|(e, _)| e.max_abs).fold(0.0, f64::max);
        let elements: Vec<usize> = all.iter().map(|(_, k)| *k).collect();
        println!(
            "textured star, {name}, {n} draws: mean bias {bias:+.2e} (draw-to-draw deviation {sd:.1e}), mean scatter {:.2e}, largest error {worst:.2e} px; elements {elements:?}",
            mean(&|e| e.scatter)
        );
        assert!(bias.abs() < 3.5e-2 && worst < 1.2, "{bias} {worst}");
    }
}

/// A 1212x1212 disc whose surface carries a strong fine texture (deviation
/// half the contrast, correlation length 1.5 px) on a lightly textured
/// ground, from the automatic start. The last stage's settles chase the
/// texture until the iteration budget is spent; whatever the outcome, every
/// sample has a finite `sigma` (a run started with no budget left used to
/// leave a system that never iterated: `sigma` NaN on every sample), and
/// `sigma` counts the texture's correlation along the edge
/// (`fit::correlated`): the observed scatter stays within 2.5 times it.
#[test]
fn strongly_textured_disc_keeps_an_honest_sigma() {
    let shape = Shape::Circle {
        cx: 606.3,
        cy: 605.8,
        r: 424.2,
    };
    let image = paint(&Scene {
        width: 1212,
        height: 1212,
        shape: shape.clone(),
        texture_inside: 0.5,
        texture_outside: 0.1,
        texture_length: 1.5,
        blur: 1.2,
        noise: 0.01,
        seed: 7,
    });
    let start = auto_start(&image);
    let m = measure(&image, &start.curve, &FitConfig::default()).unwrap();
    let e = stats(&m, &shape);
    show("strongly textured disc", &m, &e);
    assert!(
        matches!(m.outcome, Outcome::Converged | Outcome::IterationLimit),
        "{}",
        m.outcome
    );
    assert!(
        m.samples
            .iter()
            .all(|s| s.sigma.is_finite() && s.sigma > 0.0),
        "a sample without sigma"
    );
    let ratio = e.scatter / crate::common::rms_sigma(&m);
    println!("  scatter / sigma {ratio:.2}");
    assert!((0.5..2.5).contains(&ratio), "{ratio}");
    assert!(e.bias.abs() < 0.3 && e.scatter < 1.0, "{e:?}");
}
