//! `vicurve track video.mkv`: a video decoded by FFmpeg tracks to the
//! curves of the same frames as PNG files (a lossless codec, FFV1 at 16
//! bits), its frames named by index; without FFmpeg, one line says what to
//! install.

use std::path::Path;
use std::process::Command;

use crate::common::{text, vicurve};

const FRAMES: usize = 5;

/// Whether FFmpeg's programs run here (the test that needs them is
/// skipped, saying so, when they do not).
fn ffmpeg_present() -> bool {
    ["ffmpeg", "ffprobe"].iter().all(|p| {
        Command::new(p)
            .arg("-version")
            .output()
            .is_ok_and(|o| o.status.success())
    })
}

fn track(input: &Path, out: &Path) -> std::process::Output {
    vicurve(&[
        "track",
        &input.display().to_string(),
        "--init",
        "circle:70,75,38",
        "--out-dir",
        &out.display().to_string(),
    ])
}

fn curve(dir: &Path, stem: &str) -> serde_json::Value {
    let t = std::fs::read_to_string(dir.join(format!("{stem}.json"))).unwrap();
    serde_json::from_str(&t).unwrap()
}

#[test]
fn a_lossless_video_tracks_as_its_frames_as_png_files() {
    if !ffmpeg_present() {
        eprintln!("skipped: ffmpeg and ffprobe are not on PATH");
        return;
    }
    let tmp = tempfile::tempdir().unwrap();
    let dir = tmp.path();
    for k in 0..FRAMES {
        let f = crate::stack::disc(k);
        vicurve::io::save_image(&dir.join(format!("f_{k:03}.png")), &f, 16).unwrap();
    }
    let video = dir.join("disc.mkv");
    let made = Command::new("ffmpeg")
        .args(["-v", "error", "-i"])
        .arg(dir.join("f_%03d.png"))
        .args(["-c:v", "ffv1", "-pix_fmt", "gray16le"])
        .arg(&video)
        .output()
        .unwrap();
    assert!(made.status.success(), "{}", text(&made.stderr));
    let o = track(&dir.join("f_*.png"), &dir.join("png"));
    assert!(o.status.success(), "{}", text(&o.stderr));
    let o = track(&video, &dir.join("video"));
    assert!(o.status.success(), "{}", text(&o.stderr));
    for k in 0..FRAMES {
        let a = curve(&dir.join("png"), &format!("f_{k:03}"));
        let b = curve(&dir.join("video"), &format!("disc_{k:04}"));
        assert_eq!(a["curve"], b["curve"], "frame {k}");
        let input = b["input"]["path"].as_str().unwrap();
        assert_eq!(input, format!("{}#{k}", video.display()));
    }
    // Run again from the third frame's files removed: frames are decoded
    // in order, the done ones skipped.
    std::fs::remove_file(dir.join("video").join("disc_0002.json")).unwrap();
    let o = track(&video, &dir.join("video"));
    assert!(o.status.success(), "{}", text(&o.stderr));
    let b = curve(&dir.join("video"), "disc_0002");
    assert_eq!(curve(&dir.join("png"), "f_002")["curve"], b["curve"]);
}

#[test]
fn without_ffmpeg_a_video_is_one_line_saying_what_to_install() {
    let tmp = tempfile::tempdir().unwrap();
    let video = tmp.path().join("clip.mp4");
    std::fs::write(&video, b"not looked at").unwrap();
    let o = Command::new(env!("CARGO_BIN_EXE_vicurve"))
        .args([
            "track",
            &video.display().to_string(),
            "--init",
            "circle:5,5,3",
        ])
        .args(["--out-dir", &tmp.path().join("o").display().to_string()])
        .env("PATH", tmp.path())
        .output()
        .unwrap();
    assert_eq!(o.status.code(), Some(1));
    let err = text(&o.stderr);
    assert_eq!(err.trim().lines().count(), 1, "{err}");
    assert!(
        err.contains("needs the ffmpeg and ffprobe programs on PATH"),
        "{err}"
    );
}
