//! The Rust side of `bench/bench_measure.py`: the same measurements, timed
//! the same way (best and median of N calls after three warm-up calls), so
//! that the Python figures in docs/benchmarks.md compare like with like.
//!
//! ```sh
//! cargo run --release -p vicurve-py --example bench_measure -- [N]
//! ```

use std::time::Instant;
use vicurve::curve::InitialCurve;
use vicurve::fit::{measure, Elements, FitConfig, Stage};
use vicurve::render::{presets, render};

/// Print the best and median wall-clock time of `n` calls of `f`.
fn time(name: &str, n: usize, mut f: impl FnMut()) {
    for _ in 0..3 {
        f();
    }
    let mut t: Vec<f64> = (0..n)
        .map(|_| {
            let start = Instant::now();
            f();
            start.elapsed().as_secs_f64()
        })
        .collect();
    t.sort_by(f64::total_cmp);
    println!(
        "{name}: best {:.1} ms, median {:.1} ms (N = {n})",
        t[0] * 1e3,
        t[n / 2] * 1e3
    );
}

fn main() -> Result<(), Box<dyn std::error::Error>> {
    let n: usize = match std::env::args().nth(1) {
        Some(a) => a.parse()?,
        None => 50,
    };
    let n = n.max(1);
    // The paper's disc, one stage, as the criterion bench "paper disc, one
    // stage (from the image)".
    let disc = render(&presets::paper_disc(10.0))?;
    let disc_init = InitialCurve::Circle {
        cx: 255.0,
        cy: 257.0,
        r: 203.0,
    };
    let one_stage = FitConfig {
        stages: Some(vec![Stage {
            half_width: 10.0,
            elements: Elements::Count(25),
        }]),
        blur_correction: false,
        ..FitConfig::default()
    };
    time(
        "paper disc, one stage (R = 10, 25 elements), from the image",
        n,
        || {
            let _ = measure(&disc, &disc_init, &one_stage);
        },
    );
    let star = render(&presets::star_1024())?;
    let star_init = InitialCurve::Circle {
        cx: 522.3,
        cy: 511.6,
        r: 300.0,
    };
    let config = FitConfig::default();
    time(
        "1024^2 star, default schedule, from the image",
        (n / 5).max(5),
        || {
            let _ = measure(&star, &star_init, &config);
        },
    );
    Ok(())
}
