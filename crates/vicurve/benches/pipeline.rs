//! Criterion benches of the pipeline, one group per stage of the method:
//! B-spline basis, band construction, matrix assembly and factorisation,
//! one Gauss–Newton iteration, whole measurements (the paper's disc, one
//! stage; the 1024x1024 star, default schedule), image decode.
//!
//! `cargo bench -p vicurve --bench pipeline`; figures in docs/benchmarks.md.

use criterion::{criterion_group, criterion_main, Criterion};
use std::hint::black_box;
use vicurve::band::Band;
use vicurve::curve::InitialCurve;
use vicurve::fit::{measure, measure_from, Coords, Elements, FitConfig, Stage};
use vicurve::interp::{Interpolation, Sampler};
use vicurve::render::{presets, render, RenderSpec};
use vicurve::solver::{BandCholesky, SymBandMatrix};
use vicurve::spline::Basis;
use vicurve::truth::Shape;
use vicurve::virtual_image::Kind;
use vicurve::Image;

fn paper_disc() -> Image {
    render(&presets::paper_disc(10.0)).unwrap()
}

fn star() -> Image {
    render(&presets::star_1024()).unwrap()
}

fn paper_config() -> FitConfig {
    FitConfig {
        stages: Some(vec![Stage {
            half_width: 10.0,
            elements: Elements::Count(25),
        }]),
        blur_correction: false,
        ..FitConfig::default()
    }
}

fn basis(c: &mut Criterion) {
    let b = Basis::new(3, 100, 1000.0, true).unwrap();
    c.bench_function("basis/eval cubic", |bench| {
        let mut v = [0.0; 6];
        let mut s = 0.0;
        bench.iter(|| {
            s = (s + 0.731) % 1000.0;
            black_box(b.eval(black_box(s), &mut v));
        })
    });
}

fn band(c: &mut Criterion) {
    let curve = InitialCurve::Circle {
        cx: 256.3,
        cy: 255.6,
        r: 203.0,
    }
    .to_curve()
    .unwrap();
    let b = Basis::new(3, 25, curve.param_length(), true).unwrap();
    c.bench_function("band/build R=10 (paper disc, 25k px)", |bench| {
        bench.iter(|| Band::build(&curve, &b, 10.0, Kind::Silhouette, 512, 512).unwrap())
    });
    c.bench_function("band/build levelset R=10 (paper disc)", |bench| {
        let coords = Coords::Levelset { mesh_size: 10.0 };
        bench.iter(|| {
            Band::build_with(&curve, &b, 10.0, Kind::Silhouette, 512, 512, 1, coords).unwrap()
        })
    });
}

fn assembly(c: &mut Criterion) {
    // The normal matrix pattern of 100 cubic periodic elements, assembled
    // from 25k pixels and factorised.
    let b = Basis::new(3, 100, 1256.0, true).unwrap();
    c.bench_function(
        "solver/assemble+factor 100 cubic periodic (25k px)",
        |bench| {
            let mut v = [0.0; 6];
            bench.iter(|| {
                let mut m = SymBandMatrix::zeros(100, 3, true).unwrap();
                for k in 0..25_000 {
                    let s = k as f64 * 0.05;
                    let first = b.eval(s, &mut v);
                    for i in 0..4 {
                        for j in i..4 {
                            m.add(b.index(first, i), b.index(first, j), v[i] * v[j]);
                        }
                    }
                }
                BandCholesky::factor(&m).unwrap()
            })
        },
    );
}

fn measurements(c: &mut Criterion) {
    let disc = paper_disc();
    let disc_init = InitialCurve::Circle {
        cx: 255.0,
        cy: 257.0,
        r: 203.0,
    };
    let sampler = Sampler::new(&disc, Interpolation::CubicBSpline);
    let reference = disc_init.to_curve().unwrap();
    let config = paper_config();
    let mut group = c.benchmark_group("measure");
    group.sample_size(20);
    group.bench_function("paper disc, one stage (sampler prepared)", |bench| {
        bench.iter(|| measure_from(&sampler, reference.clone(), &config).unwrap())
    });
    group.bench_function("paper disc, one stage (from the image)", |bench| {
        bench.iter(|| measure(&disc, &disc_init, &config).unwrap())
    });
    let s = star();
    let star_init = InitialCurve::Circle {
        cx: 522.3,
        cy: 511.6,
        r: 300.0,
    };
    group.sample_size(10);
    group.bench_function(
        "star 1024x1024, default schedule (from the image)",
        |bench| bench.iter(|| measure(&s, &star_init, &FitConfig::default()).unwrap()),
    );
    let three = FitConfig {
        stages: Some(vicurve::fit::parse_stages("20:25,10:50,5:100").unwrap()),
        ..FitConfig::default()
    };
    group.bench_function(
        "star 1024x1024, stages 20:25,10:50,5:100 (from the image)",
        |bench| bench.iter(|| measure(&s, &star_init, &three).unwrap()),
    );
    let dir = std::env::temp_dir().join(format!("vicurve-bench-{}", std::process::id()));
    std::fs::create_dir_all(&dir).unwrap();
    let path = dir.join("star.png");
    vicurve::io::save_image(&path, &s, 8).unwrap();
    group.bench_function(
        "star 1024x1024, default schedule (PNG decode included)",
        |bench| {
            bench.iter(|| {
                let image = vicurve::io::load_image(&path).unwrap();
                measure(&image, &star_init, &FitConfig::default()).unwrap()
            })
        },
    );
    group.bench_function("decode 1024x1024 8-bit PNG", |bench| {
        bench.iter(|| vicurve::io::load_image(&path).unwrap())
    });
    // The paper's real-image setting (its section 8): a 1704x2272 star,
    // three stages from a circle of radius 500.
    let big = render(&RenderSpec {
        width: 1704,
        height: 2272,
        shape: Shape::Star {
            cx: 852.3,
            cy: 1136.6,
            r0: 560.0,
            amplitude: 0.2,
            lobes: 5,
            phase: 0.0,
        },
        ..presets::star_1024()
    })
    .unwrap();
    let big_init = InitialCurve::Circle {
        cx: 852.0,
        cy: 1136.0,
        r: 500.0,
    };
    group.bench_function(
        "star 1704x2272, stages 20:25,10:50,5:100 from a circle of radius 500 (from the image)",
        |bench| bench.iter(|| measure(&big, &big_init, &three).unwrap()),
    );
    let big_sampler = Sampler::new(&big, Interpolation::CubicBSpline);
    let big_reference = big_init.to_curve().unwrap();
    group.bench_function(
        "star 1704x2272, stages 20:25,10:50,5:100 from a circle of radius 500 (sampler prepared)",
        |bench| bench.iter(|| measure_from(&big_sampler, big_reference.clone(), &three).unwrap()),
    );
    group.bench_function("cubic B-spline prefilter, 1704x2272", |bench| {
        bench.iter(|| Sampler::new(&big, Interpolation::CubicBSpline))
    });
    group.finish();
    let _ = std::fs::remove_dir_all(&dir);
}

fn iteration(c: &mut Criterion) {
    // One Gauss–Newton iteration is the measurement minus its fixed costs;
    // time a fixed number of iterations on a converged start instead.
    let disc = paper_disc();
    let sampler = Sampler::new(&disc, Interpolation::CubicBSpline);
    let exact = InitialCurve::Circle {
        cx: 256.3,
        cy: 255.6,
        r: 200.0,
    }
    .to_curve()
    .unwrap();
    let config = FitConfig {
        max_iterations: 1,
        tolerance: 1e-300,
        ..paper_config()
    };
    c.bench_function(
        "measure/one stage, one iteration (band + matrix + 1 GN step)",
        |bench| bench.iter(|| measure_from(&sampler, exact.clone(), &config).unwrap()),
    );
    // The same with eleven iterations: the difference over ten is the cost
    // of one Gauss–Newton iteration (interpolation of the band, right-hand
    // side, banded solve).
    let eleven = FitConfig {
        max_iterations: 11,
        ..config.clone()
    };
    c.bench_function(
        "measure/one stage, eleven iterations (band + matrix + 11 GN steps)",
        |bench| bench.iter(|| measure_from(&sampler, exact.clone(), &eleven).unwrap()),
    );
}

criterion_group!(benches, basis, band, assembly, iteration, measurements);
criterion_main!(benches);
