//! The peers on the same images in the same run: `bench/peers/speed_peers.py`
//! (scikit-image `find_contours` and subpixel-edges, timed in-process in
//! Python), its JSON read back.

use std::path::{Path, PathBuf};
use std::process::{Command, Stdio};

/// One peer's timing on one image, seconds.
pub struct PeerTime {
    /// The image file.
    pub image: PathBuf,
    /// `skimage-find_contours`, `subpixel-edges-itersN`.
    pub tool: String,
    /// Median of the repeats.
    pub median: f64,
    /// Fastest repeat.
    pub min: f64,
    /// Slowest repeat.
    pub max: f64,
    /// Points it returned.
    pub points: usize,
}

/// What the peers' run gave.
pub struct Peers {
    /// The timings.
    pub times: Vec<PeerTime>,
    /// `tool on image: error` for the calls that failed.
    pub errors: Vec<String>,
    /// `name version` of Python and the packages.
    pub versions: String,
}

/// The script: `bench/peers/speed_peers.py` under the current directory,
/// else in the source tree this program was built from.
pub fn script() -> Option<PathBuf> {
    let here = PathBuf::from("bench/peers/speed_peers.py");
    if here.is_file() {
        return Some(here);
    }
    let built = Path::new(env!("CARGO_MANIFEST_DIR")).join("../../bench/peers/speed_peers.py");
    built.is_file().then_some(built)
}

/// Why the peers cannot run with `python` (the missing modules), or
/// `None` when they can.
pub fn missing(python: &str) -> Option<String> {
    let probe = "import skimage, cv2, scipy, numpy\nimport numpy as np\nnp.int = int\nimport subpixel_edges";
    match Command::new(python)
        .args(["-c", probe])
        .stdin(Stdio::null())
        .stdout(Stdio::null())
        .output()
    {
        Err(e) => Some(format!("cannot run {python}: {e}")),
        Ok(o) if !o.status.success() => {
            let err = String::from_utf8_lossy(&o.stderr);
            let last = err.lines().last().unwrap_or("import failed").trim();
            Some(format!(
                "{python} lacks the peers' packages ({last}); install bench/peers/requirements.txt \
                 (e.g. into a venv) and pass --python VENV/bin/python"
            ))
        }
        Ok(_) => None,
    }
}

/// Run the script on `images`, `repeats` timed calls each.
pub fn run(
    python: &str,
    script: &Path,
    images: &[PathBuf],
    repeats: usize,
) -> Result<Peers, String> {
    let out = Command::new(python)
        .arg(script)
        .arg("--repeats")
        .arg(repeats.to_string())
        .args(images)
        .stdin(Stdio::null())
        .output()
        .map_err(|e| format!("cannot run {python}: {e}"))?;
    if !out.status.success() {
        let err = String::from_utf8_lossy(&out.stderr);
        return Err(format!(
            "{} failed: {}",
            script.display(),
            err.lines().last().unwrap_or("").trim()
        ));
    }
    let v: serde_json::Value = serde_json::from_slice(&out.stdout)
        .map_err(|e| format!("{} printed no JSON: {e}", script.display()))?;
    let num = |r: &serde_json::Value, k: &str| r[k].as_f64().unwrap_or(f64::NAN);
    let text = |r: &serde_json::Value, k: &str| r[k].as_str().unwrap_or("").to_string();
    let times = v["results"]
        .as_array()
        .map(|a| {
            a.iter()
                .map(|r| PeerTime {
                    image: PathBuf::from(text(r, "image")),
                    tool: text(r, "tool"),
                    median: num(r, "median"),
                    min: num(r, "min"),
                    max: num(r, "max"),
                    points: r["points"].as_u64().unwrap_or(0) as usize,
                })
                .collect()
        })
        .unwrap_or_default();
    let errors = v["errors"]
        .as_array()
        .map(|a| {
            a.iter()
                .map(|r| {
                    format!(
                        "{} on {}: {}",
                        text(r, "tool"),
                        text(r, "image"),
                        text(r, "error")
                    )
                })
                .collect()
        })
        .unwrap_or_default();
    let versions = v["versions"]
        .as_object()
        .map(|o| {
            o.iter()
                .map(|(k, v)| format!("{k} {}", v.as_str().unwrap_or("?")))
                .collect::<Vec<_>>()
                .join(", ")
        })
        .unwrap_or_default();
    Ok(Peers {
        times,
        errors,
        versions,
    })
}
