//! `vicurve track stack.tif`: a multi-page 16-bit TIFF tracks to the same
//! curves as the same frames as PNG files, its frames named by index, and
//! resumes like a folder of frames.

use std::path::Path;

use crate::common::{text, vicurve};
use vicurve::render::{render, Method, RenderSpec};
use vicurve::truth::Shape;
use vicurve::Image;

const FRAMES: usize = 6;

/// Frame `k` of a disc drifting by (0.7, 0.4) px and growing by 0.5 px per
/// frame: exact coverage, blur 1 px, 1 % noise, 16-bit.
pub fn disc(k: usize) -> Image {
    let t = k as f64;
    render(&RenderSpec {
        width: 160,
        height: 150,
        shape: Shape::Circle {
            cx: 70.3 + 0.7 * t,
            cy: 74.6 + 0.4 * t,
            r: 40.0 + 0.5 * t,
        },
        method: Method::Coverage,
        blur_sigma: 1.0,
        noise: 0.01,
        seed: k as u64,
        bits: Some(16),
        ..RenderSpec::default()
    })
    .unwrap()
}

/// The frames as one multi-page 16-bit TIFF (the `tiff` crate's encoder).
fn write_stack(path: &Path, frames: &[Image]) {
    use tiff::encoder::{colortype::Gray16, TiffEncoder};
    let mut file = std::io::BufWriter::new(std::fs::File::create(path).unwrap());
    let mut encoder = TiffEncoder::new(&mut file).unwrap();
    for f in frames {
        let data: Vec<u16> = f
            .data()
            .iter()
            .map(|v| (v * 65535.0).round() as u16)
            .collect();
        encoder
            .write_image::<Gray16>(f.width() as u32, f.height() as u32, &data)
            .unwrap();
    }
}

fn curve(dir: &Path, stem: &str) -> serde_json::Value {
    let t = std::fs::read_to_string(dir.join(format!("{stem}.json"))).unwrap();
    let v: serde_json::Value = serde_json::from_str(&t).unwrap();
    v
}

#[test]
fn a_16_bit_stack_tracks_as_its_frames_as_png_files() {
    let tmp = tempfile::tempdir().unwrap();
    let dir = tmp.path();
    let frames: Vec<Image> = (0..FRAMES).map(disc).collect();
    for (k, f) in frames.iter().enumerate() {
        vicurve::io::save_image(&dir.join(format!("f_{k:03}.png")), f, 16).unwrap();
    }
    let stack = dir.join("disc.tif");
    write_stack(&stack, &frames);

    let track = |input: &str, out: &str| {
        let out_dir = dir.join(out).display().to_string();
        let args = [
            "track",
            input,
            "--init",
            "circle:70,75,38",
            "--out-dir",
            &out_dir,
        ];
        let o = vicurve(&args);
        assert!(o.status.success(), "{}", text(&o.stderr));
        o
    };
    track(&dir.join("f_*.png").display().to_string(), "png");
    track(&stack.display().to_string(), "tif");
    let (png, tif) = (dir.join("png"), dir.join("tif"));
    for k in 0..FRAMES {
        let a = curve(&png, &format!("f_{k:03}"));
        let b = curve(&tif, &format!("disc_{k:04}"));
        assert_eq!(a["curve"], b["curve"], "frame {k}");
        assert_eq!(a["sequence"]["frame"], b["sequence"]["frame"]);
        let input = b["input"]["path"].as_str().unwrap();
        assert_eq!(input, format!("{}#{k}", stack.display()));
    }
    // Frames after the first started from the previous one, and the
    // summary names the pages.
    let b = curve(&tif, "disc_0003");
    assert_eq!(b["sequence"]["started_from"], "disc_0002");
    let summary = std::fs::read_to_string(tif.join("summary.csv")).unwrap();
    let firsts: Vec<&str> = summary
        .lines()
        .skip(1)
        .map(|l| l.split(',').next().unwrap())
        .collect();
    let expected: Vec<String> = (0..FRAMES).map(|k| format!("disc_{k:04}")).collect();
    assert_eq!(firsts, expected);

    // Run again: every page is already done.
    let o = track(&stack.display().to_string(), "tif");
    let err = text(&o.stderr);
    assert!(
        err.contains(&format!("{FRAMES} frame(s) already done")),
        "{err}"
    );
}

#[test]
fn a_truncated_stack_records_its_missing_pages() {
    let tmp = tempfile::tempdir().unwrap();
    let dir = tmp.path();
    let frames: Vec<Image> = (0..3).map(disc).collect();
    let stack = dir.join("disc.tif");
    write_stack(&stack, &frames);
    // Pixel data of the last page cut: its directory (written after the
    // data) is lost, so the stack has two pages.
    let bytes = std::fs::read(&stack).unwrap();
    std::fs::write(&stack, &bytes[..bytes.len() - 1000]).unwrap();
    let out_dir = dir.join("t").display().to_string();
    let o = vicurve(&[
        "track",
        &stack.display().to_string(),
        "--init",
        "circle:70,75,38",
        "--out-dir",
        &out_dir,
    ]);
    // Two pages measured, the third recorded as failed (exit 3).
    let err = text(&o.stderr);
    assert_eq!(o.status.code(), Some(3), "{err}");
    let summary = std::fs::read_to_string(dir.join("t").join("summary.csv")).unwrap();
    let rows: Vec<&str> = summary.lines().skip(1).collect();
    assert_eq!(rows.len(), 3, "{summary}");
    assert!(
        rows[0].starts_with("disc_0000,curve,converged"),
        "{}",
        rows[0]
    );
    assert!(
        rows[1].starts_with("disc_0001,curve,converged"),
        "{}",
        rows[1]
    );
    assert!(rows[2].starts_with("disc_0002,curve,failed"), "{}", rows[2]);
    assert!(rows[2].contains("page 2"), "{}", rows[2]);
}
