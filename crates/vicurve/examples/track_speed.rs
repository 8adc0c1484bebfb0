//! Speed of tracking one contour of about 2000 px through 1-megapixel
//! frames, as `vicurve track` does it: each frame decoded from its PNG,
//! prepared for interpolation and measured from the previous frame's curve.
//!
//! ```sh
//! cargo run --release -p vicurve --example track_speed -- [FRAMES] [STAGES...]
//! ```
//!
//! The frames (1000x1000, 8-bit PNG, a five-lobed star of mean radius 318
//! px and perimeter about 2030 px, moving 0.3 px and turning 0.2 degree per
//! frame, blur 1, noise 1 %) are rendered once into the temporary folder.
//! For each schedule (`tracked`, the tracking schedule that `track` uses by
//! default: the pixel-edge stage alone from the previous frame's blur and
//! elements, [`vicurve::fit::measure_tracked_cached`] with the band the
//! previous frame left when it serves, on an image prepared
//! without interpolation, falling back to the default schedule when it
//! cannot measure; `default`, the full default schedule; or `R:N,...` as
//! `--stages`; optionally followed by `/bilinear` or `/keys` for another
//! interpolation than the cubic B-spline; default list: `tracked default
//! default/bilinear 2:auto 2:40px 2:40px/bilinear`) the frames are tracked
//! from the previous curve as `track` does it, and timed: decode,
//! preparation (the cubic prefilter, or the plain copy of the tracking
//! schedule), the fit; frames per second with and without the decode, and
//! the largest distance to the exact star over all samples of all frames.
//! `TRACK_SPEED_VERBOSE=1` prints every frame's stages and its errors
//! against the exact star (bias, RMS, largest);
//! `TRACK_SPEED_BLUR=0.5` and `TRACK_SPEED_BITS=16` render the frames with
//! another blur (pixels) or bit depth (into their own folder).

use std::time::Instant;
use vicurve::curve::{InitialCurve, SplineCurve};
use vicurve::fit::{
    measure, measure_from, measure_tracked_cached, parse_stages, FitConfig, TrackCache, TrackState,
};
use vicurve::interp::{Interpolation, Sampler};
use vicurve::render::{render, Method, RenderSpec};
use vicurve::truth::{evaluate, Kind, Shape};

fn star(k: usize) -> Shape {
    Shape::Star {
        cx: 500.3 + 0.3 * k as f64,
        cy: 499.6 - 0.1 * k as f64,
        r0: 318.0,
        amplitude: 0.05,
        lobes: 5,
        phase: (0.2 * k as f64).to_radians(),
    }
}

fn main() {
    let args: Vec<String> = std::env::args().skip(1).collect();
    let verbose = std::env::var_os("TRACK_SPEED_VERBOSE").is_some();
    let frames: usize = args.first().and_then(|a| a.parse().ok()).unwrap_or(40);
    let schedules: Vec<String> = if args.len() > 1 {
        args[1..].to_vec()
    } else {
        [
            "tracked",
            "default",
            "default/bilinear",
            "2:auto",
            "2:40px",
            "2:40px/bilinear",
        ]
        .iter()
        .map(|s| s.to_string())
        .collect()
    };
    let env = |name: &str| std::env::var(name).ok();
    let blur: f64 = env("TRACK_SPEED_BLUR")
        .and_then(|v| v.parse().ok())
        .unwrap_or(1.0);
    let bits: u8 = env("TRACK_SPEED_BITS")
        .and_then(|v| v.parse().ok())
        .unwrap_or(8);
    // The default frames keep their folder (and `vicurve track`'s command
    // in docs/benchmarks.md); others get their own.
    let dir = match (blur, bits) {
        (1.0, 8) => std::env::temp_dir().join("vicurve-track-speed"),
        _ => std::env::temp_dir().join(format!("vicurve-track-speed-{blur}-{bits}")),
    };
    std::fs::create_dir_all(&dir).unwrap();
    let path = |k: usize| dir.join(format!("frame_{k:04}.png"));
    let t = Instant::now();
    for k in 0..=frames {
        if path(k).is_file() {
            continue;
        }
        let spec = RenderSpec {
            width: 1000,
            height: 1000,
            shape: star(k),
            kind: Kind::Silhouette,
            method: Method::Coverage,
            foreground: 0.8,
            background: 0.2,
            blur_sigma: blur,
            noise: 0.01,
            seed: k as u64 + 1,
            bits: Some(bits),
            ..RenderSpec::default()
        };
        let img = render(&spec).unwrap();
        vicurve::io::save_image(&path(k), &img, bits).unwrap();
    }
    println!(
        "{} frames of 1000x1000 in {} (made in {:.1} s), perimeter {:.0} px; {} threads",
        frames + 1,
        dir.display(),
        t.elapsed().as_secs_f64(),
        star(0).length(),
        rayon::current_num_threads()
    );
    // Frame 0 from a circle, with the default schedule (not timed).
    let first = vicurve::io::load_image(&path(0)).unwrap();
    let init = InitialCurve::Circle {
        cx: 500.0,
        cy: 500.0,
        r: 318.0,
    };
    let m0 = measure(&first, &init, &FitConfig::default()).unwrap();
    println!("frame 0: {}, {} iterations", m0.outcome, m0.iterations());
    println!(
        "| schedule | decode ms | prepare ms | fit ms | iterations | frames/s without decode | frames/s with decode | max error px |"
    );
    println!("|---|---|---|---|---|---|---|---|");
    for sched in &schedules {
        let mut config = FitConfig::default();
        let (sched_text, interp) = match sched.split_once('/') {
            Some((a, b)) => (a, Some(b)),
            None => (sched.as_str(), None),
        };
        let tracked = sched_text == "tracked";
        if sched_text != "default" && !tracked {
            config.stages = Some(parse_stages(sched_text).unwrap());
        }
        if let Some(i) = interp {
            config.interpolation = i.parse().unwrap();
        }
        let (mut decode, mut prepare, mut fit) = (0.0, 0.0, 0.0);
        let mut iterations = 0;
        let mut worst: f64 = 0.0;
        let mut curve = m0.curve.clone();
        let mut state = TrackState::from_measurement(&m0);
        let mut fallbacks = 0;
        // What each tracked frame leaves for the next (its band).
        let mut cache = TrackCache::default();
        for k in 1..=frames {
            let t = Instant::now();
            let img = vicurve::io::load_image(&path(k)).unwrap();
            decode += t.elapsed().as_secs_f64();
            let t = Instant::now();
            // The tracking schedule reads pixel values only: no prefilter.
            let kind = match (tracked, state) {
                (true, Some(_)) => Interpolation::Bilinear,
                _ => config.interpolation,
            };
            let sampler = Sampler::new(&img, kind);
            prepare += t.elapsed().as_secs_f64();
            let t = Instant::now();
            // The start as `vicurve track` makes it: the tracking schedule
            // takes the previous curve as it is (it refits it itself), the
            // others the previous curve refitted with control points 10 px
            // apart.
            let smoothed = |curve: &SplineCurve| {
                let n = (curve.param_length() / 0.5).ceil() as usize;
                let pts: Vec<[f64; 2]> = curve
                    .sample_params(n)
                    .into_iter()
                    .map(|u| curve.point(u))
                    .collect();
                let spacing = (curve.param_length() / 16.0).clamp(2.0, 10.0);
                SplineCurve::fit(&pts, true, 3, spacing).unwrap()
            };
            let attempt = match (tracked, &state) {
                (true, Some(st)) => {
                    measure_tracked_cached(&sampler, curve.clone(), st, &config, &mut cache)
                        .unwrap()
                }
                _ => None,
            };
            let m = match attempt {
                Some(m) => m,
                None if kind != config.interpolation => {
                    fallbacks += 1;
                    let full = Sampler::new(&img, config.interpolation);
                    measure_from(&full, smoothed(&curve), &config).unwrap()
                }
                None => measure_from(&sampler, smoothed(&curve), &config).unwrap(),
            };
            fit += t.elapsed().as_secs_f64();
            iterations += m.iterations();
            let e = evaluate(&m.points(), &star(k)).unwrap();
            worst = worst.max(e.max_abs);
            if verbose {
                let stages: Vec<String> = m
                    .stages
                    .iter()
                    .map(|s| {
                        format!(
                            "R {} x {} el: {} it, {} rr, {} px, {:.1} ms",
                            s.half_width,
                            s.elements,
                            s.iterations,
                            s.rereferences,
                            s.band_pixels,
                            s.seconds * 1e3
                        )
                    })
                    .collect();
                println!(
                    "  {sched} frame {k}: max error {:.4} px bias {:+.5} rms {:.5}; {}",
                    e.max_abs,
                    e.bias,
                    e.rms,
                    stages.join("; ")
                );
            }
            assert!(m.outcome.is_converged(), "frame {k}: {}", m.outcome);
            state = TrackState::from_measurement(&m);
            curve = m.curve;
        }
        if fallbacks > 0 {
            println!("  ({fallbacks} frames measured again with the default schedule)");
        }
        let n = frames as f64;
        println!(
            "| `{sched}` | {:.1} | {:.1} | {:.1} | {:.1} | {:.1} | {:.1} | {:.4} |",
            1e3 * decode / n,
            1e3 * prepare / n,
            1e3 * fit / n,
            iterations as f64 / n,
            n / (prepare + fit),
            n / (decode + prepare + fit),
            worst
        );
    }
}
