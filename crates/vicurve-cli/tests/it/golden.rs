//! Golden runs: whole measurements through the command line whose result
//! files must not change unless a change means them to (see
//! `common::golden`). They cover every path through the fit: silhouettes
//! and contours, open and closed, global and varying levels, levelset
//! coordinates, clutter, breaks, growing, the ridge and automatic starts,
//! every `--model`, diagnostics, sequences (`run`, `track`, resume).

use crate::common::golden::check;
use crate::common::ok_in;
use std::path::Path;
use vicurve::image::Image;
use vicurve::io::save_image;
use vicurve::render::coverage::polygon_coverage;

/// A scratch folder holding the inputs the cases are made of.
fn scratch() -> tempfile::TempDir {
    tempfile::tempdir().unwrap()
}

/// `vicurve synth SHAPE --out NAME.png ARGS` in `dir`.
fn synth(dir: &Path, shape: &str, name: &str, args: &[&str]) {
    let out = format!("{name}.png");
    let mut all = vec!["synth", shape, "--out", out.as_str()];
    all.extend_from_slice(args);
    ok_in(dir, &all);
}

/// The blurred, noisy disc most cases measure (200x200, radius 60).
fn disc(dir: &Path) {
    synth(
        dir,
        "disc",
        "disc",
        &[
            "--size", "200x200", "--radius", "60", "--blur", "1", "--noise", "0.01",
        ],
    );
}

/// Measure `args` in a fresh folder made by `setup`, and check `files`.
fn case(name: &str, setup: impl Fn(&Path), args: &[&str], files: &[&str]) {
    let tmp = scratch();
    let dir = tmp.path();
    setup(dir);
    ok_in(dir, args);
    check(name, dir, files);
}

/// The result file and the points of a `measure`.
const OUT: [&str; 4] = ["--out", "r.json", "--points", "p.csv"];
const FILES: [&str; 2] = ["r.json", "p.csv"];

fn measure(name: &str, setup: impl Fn(&Path), args: &[&str]) {
    let mut all = vec!["measure"];
    all.extend_from_slice(args);
    all.extend_from_slice(&OUT);
    case(name, setup, &all, &FILES);
}

#[test]
fn disc_from_a_circle() {
    measure(
        "disc_circle",
        disc,
        &["disc.png", "--init", "circle:101,98,64"],
    );
}

#[test]
fn disc_with_global_levels() {
    measure(
        "disc_global_levels",
        disc,
        &[
            "disc.png",
            "--init",
            "circle:101,98,64",
            "--levels",
            "global",
        ],
    );
}

#[test]
fn disc_on_levelset_coordinates() {
    measure(
        "disc_levelset",
        disc,
        &[
            "disc.png",
            "--init",
            "circle:101,98,64",
            "--coords",
            "levelset",
        ],
    );
}

#[test]
fn disc_bilinear_quadratic_given_stages() {
    measure(
        "disc_bilinear_stages",
        disc,
        &[
            "disc.png",
            "--init",
            "circle:99,101,57",
            "--interp",
            "bilinear",
            "--degree",
            "2",
            "--stages",
            "10:16,4:32",
        ],
    );
}

#[test]
fn disc_from_the_automatic_start() {
    measure("disc_auto", disc, &["disc.png"]);
}

#[test]
fn star_from_a_crossing_circle() {
    measure(
        "star_circle",
        |d| {
            synth(
                d,
                "star",
                "star",
                &[
                    "--size",
                    "320x320",
                    "--radius",
                    "100",
                    "--amplitude",
                    "0.15",
                    "--blur",
                    "1",
                    "--noise",
                    "0.01",
                ],
            )
        },
        &["star.png", "--init", "circle:160,159,100"],
    );
}

/// A sine edge across a 240x160 image (y0 = 80.3, amplitude 16 px,
/// wavelength 120 px).
fn sine_edge(dir: &Path) {
    synth(
        dir,
        "sine-edge",
        "edge",
        &["--size", "240x160", "--blur", "1", "--noise", "0.01"],
    );
}

/// The straight start crosses the sine and lies up to 16 px off it, at
/// the limit of the default schedule's reach: from `segment:30,80,210,80`
/// the fit diverges (exit 3) on 5 noise seeds of 5 of this image, from
/// 2 px higher or lower on 1 or 2 of 5; from this one on none.
#[test]
fn open_edge_from_a_segment() {
    measure(
        "edge_segment",
        sine_edge,
        &[
            "edge.png",
            "--init",
            "segment:20,80,220,80",
            "--polarity",
            "bright-left",
        ],
    );
}

/// The 10.8 px start does not converge (its steps are longer than the
/// band), nothing grows, and its curve crosses itself: a divergence, exit
/// 3 (the outputs are written all the same).
#[test]
fn open_edge_grown_from_a_short_segment() {
    let tmp = scratch();
    let dir = tmp.path();
    sine_edge(dir);
    let mut all = vec![
        "measure",
        "edge.png",
        "--init",
        "segment:118,79,128,75",
        "--grow",
    ];
    all.extend_from_slice(&OUT);
    let out = crate::common::vicurve_in(dir, &all);
    assert_eq!(
        out.status.code(),
        Some(3),
        "{}",
        crate::common::text(&out.stderr)
    );
    check("edge_grow", dir, &FILES);
}

#[test]
fn thin_line_from_its_ridge() {
    measure(
        "line_ridge",
        |d| {
            synth(
                d,
                "sine-line",
                "line",
                &["--size", "240x160", "--blur", "1", "--noise", "0.01"],
            )
        },
        &["line.png", "--kind", "contour", "--pick", "120,80"],
    );
}

#[test]
fn ring_line_from_a_circle() {
    measure(
        "ring_circle",
        |d| {
            synth(
                d,
                "ring",
                "ring",
                &[
                    "--size", "200x200", "--radius", "60", "--blur", "0.8", "--noise", "0.01",
                ],
            )
        },
        &[
            "ring.png",
            "--kind",
            "contour",
            "--init",
            "circle:100,100,63",
        ],
    );
}

/// A square of half-diagonal 60 px about (100.3, 99.6), turned by 0.3
/// rad, gray 0.8 on 0.2, exact coverage, 8-bit; and a start polyline
/// 1.5 px outside it from its first vertex.
fn square(dir: &Path) {
    let vertex = |k: usize, r: f64| {
        let t = 0.3 + std::f64::consts::FRAC_PI_2 * k as f64;
        [100.3 + r * t.cos(), 99.6 - r * t.sin()]
    };
    let ring: Vec<[f64; 2]> = (0..4).map(|k| vertex(k, 60.0)).collect();
    let mut data = polygon_coverage(200, 200, &[ring]).unwrap();
    data.iter_mut().for_each(|c| *c = 0.2 + 0.6 * *c);
    let image = Image::new(200, 200, data).unwrap();
    save_image(&dir.join("square.png"), &image, 8).unwrap();
    let start: String = (0..4)
        .map(|k| vertex(k, 62.0))
        .map(|[x, y]| format!("{x:.6},{y:.6}\n"))
        .collect();
    std::fs::write(dir.join("square.csv"), format!("x,y\n{start}")).unwrap();
}

#[test]
fn square_with_breaks_at_its_corners() {
    // Sides of sqrt(2) * 62 = 87.68 px.
    measure(
        "square_breaks",
        square,
        &[
            "square.png",
            "--init",
            "polyline:square.csv",
            "--closed",
            "--break",
            "0,87.681,175.362,263.044",
        ],
    );
}

/// A disc crossed by two dark lines 3 px wide (robust weights).
fn cluttered(dir: &Path) {
    synth(
        dir,
        "disc",
        "clean",
        &[
            "--size", "200x200", "--radius", "60", "--blur", "1", "--noise", "0.01", "--bits", "16",
        ],
    );
    let clean = vicurve::io::load_image(&dir.join("clean.png")).unwrap();
    let lines = |x: f64, y: f64| {
        [
            (0.3 * x - y + 40.0).abs() / 1.09f64.sqrt(),
            (x - 0.1 * y - 140.0).abs() / 1.01f64.sqrt(),
        ]
    };
    let crossed = Image::from_fn(200, 200, |x, y| {
        let k = lines(x as f64, y as f64)
            .iter()
            .map(|d| (1.5 - d).clamp(0.0, 1.0))
            .fold(0.0, f64::max);
        clean.get(x, y) * (1.0 - k) + 0.05 * k
    });
    save_image(&dir.join("crossed.png"), &crossed, 8).unwrap();
}

#[test]
fn disc_crossed_by_clutter() {
    measure(
        "clutter",
        cluttered,
        &["crossed.png", "--init", "circle:101,98,63"],
    );
}

#[test]
fn paper_disc_with_the_papers_schedule() {
    measure(
        "paper_disc",
        |d| synth(d, "paper-disc", "paper", &[]),
        &[
            "paper.png",
            "--init",
            "circle:256,256,203",
            "--no-blur-correction",
            "--levels",
            "global",
            "--stages",
            "20:25,10:50",
        ],
    );
}

#[test]
fn model_circle() {
    measure(
        "model_circle",
        disc,
        &[
            "disc.png",
            "--init",
            "circle:101,98,64",
            "--model",
            "circle",
        ],
    );
}

#[test]
fn model_ellipse() {
    measure(
        "model_ellipse",
        |d| {
            synth(
                d,
                "ellipse",
                "ellipse",
                &[
                    "--size", "200x200", "--axes", "70,45", "--blur", "1", "--noise", "0.01",
                ],
            )
        },
        &[
            "ellipse.png",
            "--init",
            "circle:100,100,60",
            "--model",
            "ellipse",
        ],
    );
}

#[test]
fn model_line() {
    measure(
        "model_line",
        |d| {
            synth(
                d,
                "sine-edge",
                "straight",
                &[
                    "--size",
                    "200x120",
                    "--amplitude",
                    "0",
                    "--blur",
                    "1",
                    "--noise",
                    "0.01",
                ],
            )
        },
        &[
            "straight.png",
            "--init",
            "segment:20,58,180,62",
            "--model",
            "line",
        ],
    );
}

#[test]
fn model_polygon() {
    measure(
        "model_polygon",
        square,
        &[
            "square.png",
            "--init",
            "polyline:square.csv",
            "--closed",
            "--model",
            "polygon:4",
        ],
    );
}

#[test]
fn model_bspline_curve() {
    measure(
        "model_bspline",
        disc,
        &[
            "disc.png",
            "--init",
            "circle:101,98,64",
            "--model",
            "bspline-curve",
        ],
    );
}

#[test]
fn diagnostics() {
    case(
        "diagnostics",
        disc,
        &[
            "measure",
            "disc.png",
            "--init",
            "circle:101,98,64",
            "--diagnostics",
            "diag",
            "--out",
            "r.json",
        ],
        &["r.json", "diag/diagnostics.json"],
    );
}

/// The JSON and CSV files of `dir`, sorted, as paths under `prefix`.
fn outputs(dir: &Path, prefix: &str) -> Vec<String> {
    let mut names: Vec<String> = std::fs::read_dir(dir.join(prefix))
        .unwrap()
        .map(|e| e.unwrap().file_name().to_string_lossy().into_owned())
        .filter(|n| n.ends_with(".json") || n.ends_with(".csv"))
        .map(|n| format!("{prefix}/{n}"))
        .collect();
    names.sort();
    names
}

/// Four frames of the necking specimen in `seq/` (job file included).
fn necking(dir: &Path) {
    ok_in(
        dir,
        &[
            "synth", "necking", "--out", "seq", "--frames", "4", "--size", "240x100",
        ],
    );
}

#[test]
fn job_file_run_and_resumed() {
    let tmp = scratch();
    let dir = tmp.path();
    necking(dir);
    ok_in(dir, &["run", "seq/job.toml"]);
    let files = outputs(dir, "seq/results");
    let files: Vec<&str> = files.iter().map(String::as_str).collect();
    check("job_run", dir, &files);
    // Resumed: nothing to do, the same files.
    ok_in(dir, &["run", "seq/job.toml"]);
    check("job_run", dir, &files);
}

#[test]
fn tracked_sequence() {
    let tmp = scratch();
    let dir = tmp.path();
    necking(dir);
    ok_in(
        dir,
        &[
            "track",
            "seq/frame_000.png",
            "seq/frame_001.png",
            "seq/frame_002.png",
            "seq/frame_003.png",
            "--init",
            "segment:10,30,230,30",
            "--out-dir",
            "trk",
        ],
    );
    let files = outputs(dir, "trk");
    let files: Vec<&str> = files.iter().map(String::as_str).collect();
    check("track", dir, &files);
}
