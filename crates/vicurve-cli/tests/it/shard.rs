//! `vicurve run job.toml --shard K/N` and `vicurve merge`: the parts of an
//! untracked job joined give the single run's summary, byte for byte, and
//! the same frame files.

use std::path::Path;

use crate::common::{text, vicurve};
use vicurve::render::{render, Method, RenderSpec};
use vicurve::truth::Shape;

const FRAMES: usize = 7;

fn frames(dir: &Path) {
    for k in 0..FRAMES {
        let t = k as f64;
        let image = render(&RenderSpec {
            width: 120,
            height: 110,
            shape: Shape::Circle {
                cx: 58.3 + 0.9 * t,
                cy: 54.6 - 0.5 * t,
                r: 30.0 + 0.4 * t,
            },
            method: Method::Coverage,
            blur_sigma: 1.0,
            noise: 0.01,
            seed: k as u64,
            bits: Some(16),
            ..RenderSpec::default()
        })
        .unwrap();
        vicurve::io::save_image(&dir.join(format!("f_{k:02}.png")), &image, 16).unwrap();
    }
}

fn job(dir: &Path, name: &str, out: &str, track: bool) -> String {
    let text = format!(
        "images = \"f_*.png\"\nout_dir = \"{out}\"\ntrack = {track}\n\n[[curve]]\nname = \"disc\"\ninit = \"circle:60,54,29\"\n"
    );
    let p = dir.join(name);
    std::fs::write(&p, text).unwrap();
    p.display().to_string()
}

#[test]
fn merged_parts_equal_the_single_run() {
    let tmp = tempfile::tempdir().unwrap();
    let dir = tmp.path();
    frames(dir);
    let single = job(dir, "single.toml", "single", false);
    let o = vicurve(&["run", &single]);
    assert!(o.status.success(), "{}", text(&o.stderr));
    let parts = job(dir, "parts.toml", "parts", false);
    // The parts in any order (as a job array's tasks end).
    for k in [3, 1, 2] {
        let o = vicurve(&["run", &parts, "--shard", &format!("{k}/3")]);
        assert!(o.status.success(), "{k}: {}", text(&o.stderr));
    }
    let read = |p: &Path| std::fs::read_to_string(p).unwrap();
    let sharded = dir.join("parts");
    assert!(!sharded.join("summary.csv").exists());
    let part2 = read(&sharded.join("summary.shard-2-of-3.csv"));
    assert_eq!(part2.lines().count(), 1 + 2, "{part2}"); // frames 2 and 3 of 0..7
    let o = vicurve(&["merge", &sharded.display().to_string()]);
    assert!(o.status.success(), "{}", text(&o.stderr));
    assert_eq!(
        read(&sharded.join("summary.csv")),
        read(&dir.join("single").join("summary.csv"))
    );
    for k in 0..FRAMES {
        let f = format!("f_{k:02}.json");
        let a: serde_json::Value =
            serde_json::from_str(&read(&dir.join("single").join(&f))).unwrap();
        let b: serde_json::Value = serde_json::from_str(&read(&sharded.join(&f))).unwrap();
        assert_eq!(a["curve"], b["curve"], "{f}");
        assert_eq!(a["sequence"], b["sequence"], "{f}");
    }

    // A part missing: merge says which.
    std::fs::remove_file(sharded.join("summary.shard-2-of-3.csv")).unwrap();
    let o = vicurve(&["merge", &sharded.display().to_string()]);
    assert_eq!(o.status.code(), Some(1));
    assert!(
        text(&o.stderr).contains("part 2 of 3: none found"),
        "{}",
        text(&o.stderr)
    );
}

#[test]
fn a_tracked_job_is_not_split() {
    let tmp = tempfile::tempdir().unwrap();
    let dir = tmp.path();
    frames(dir);
    let tracked = job(dir, "t.toml", "t", true);
    let o = vicurve(&["run", &tracked, "--shard", "1/2"]);
    assert_eq!(o.status.code(), Some(1));
    assert!(
        text(&o.stderr).contains("cannot be split"),
        "{}",
        text(&o.stderr)
    );
    for bad in ["0/2", "3/2", "2", "a/b"] {
        let o = vicurve(&["run", &tracked, "--shard", bad]);
        assert_eq!(o.status.code(), Some(1), "{bad}");
        assert!(
            text(&o.stderr).contains("expected K/N"),
            "{bad}: {}",
            text(&o.stderr)
        );
    }
}
