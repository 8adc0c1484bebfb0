//! Where a `vicurve measure` process spends its time: `perf record` with
//! DWARF call graphs (at a rate aiming at [`TARGET_SAMPLES`]) on one
//! single-threaded run (`RAYON_NUM_THREADS=1`,
//! so that every sample's call chain reaches the phase that made it: the
//! worker threads of a parallel run lose it), each sample put in the
//! first phase of [`PHASES`] one of whose functions is on its chain.

use std::path::Path;
use std::process::{Command, Stdio};

/// The phases, in the order a sample is tested against them, with the
/// function-name fragments that mark them. The command line's own crate is
/// also named `vicurve`: its modules (`output`, `commands`) are not the
/// library's.
pub const PHASES: &[(&str, &[&str])] = &[
    ("decode", &["vicurve::io::load_image"]),
    ("prefilter", &["vicurve::interp::Sampler::new"]),
    ("blur estimate", &["vicurve::fit::blur::estimate_spread"]),
    (
        "writing files",
        &["vicurve::output::", "vicurve::commands::measure::run"],
    ),
    (
        "band building",
        &[
            "vicurve::band::Band>::new_in",
            "vicurve::band::Band::new",
            "vicurve::band::exact::",
            "vicurve::band::levelset",
        ],
    ),
    ("samples and sigma", &["vicurve::fit::output::"]),
    (
        "GN system (Correlation::new)",
        &["vicurve::correlation::Correlation::new"],
    ),
    (
        "GN iterations (Correlation::iterate)",
        &["vicurve::correlation::Correlation::iterate"],
    ),
    (
        "GN other (line search, noise, levels)",
        &["vicurve::correlation::"],
    ),
    ("fit other", &["vicurve::fit::", "vicurve::band::"]),
    (
        "start and curve",
        &["vicurve::curve::", "vicurve::measure_start"],
    ),
];

/// Name of the samples no phase claims (loading the program, the
/// allocator's page faults outside any phase, exit).
pub const OTHER: &str = "startup, exit, other";

/// The share of each phase in one profiled run.
pub struct Profile {
    /// `(phase, fraction of the samples' periods)`, in [`PHASES`] order
    /// then [`OTHER`].
    pub shares: Vec<(String, f64)>,
    /// Samples recorded.
    pub samples: usize,
}

/// Whether `perf` runs here.
pub fn available() -> bool {
    Command::new("perf")
        .arg("--version")
        .stdout(Stdio::null())
        .stderr(Stdio::null())
        .status()
        .map(|s| s.success())
        .unwrap_or(false)
}

/// Samples aimed at per profile: enough for shares to about a percent,
/// few enough that perf's file (32 KiB of stack a sample) stays small.
const TARGET_SAMPLES: f64 = 4000.0;

/// Record `exe args` under perf into `data`, then read and classify it;
/// `seconds` is about how long the run takes on all threads (the
/// single-threaded one takes up to twice as long): the sampling rate is
/// chosen from it, 500 to 10,000 Hz.
pub fn profile(exe: &Path, args: &[String], data: &Path, seconds: f64) -> Result<Profile, String> {
    let rate = (TARGET_SAMPLES / (2.0 * seconds))
        .clamp(500.0, 10_000.0)
        .round();
    let status = Command::new("perf")
        .args(["record", "-q", "-F"])
        .arg(format!("{rate}"))
        .args(["--call-graph", "dwarf,32768", "-o"])
        .arg(data)
        .arg("--")
        .arg(exe)
        .args(args)
        .env("RAYON_NUM_THREADS", "1")
        .stdin(Stdio::null())
        .stdout(Stdio::null())
        .stderr(Stdio::null())
        .status()
        .map_err(|e| format!("cannot run perf: {e}"))?;
    // The measurement's own exit code (3 for a divergence) passes through.
    if status.code().is_none() {
        return Err("perf record was killed".into());
    }
    let out = Command::new("perf")
        .args(["script", "-F", "period,ip,sym", "--no-inline", "-i"])
        .arg(data)
        .stdin(Stdio::null())
        .stderr(Stdio::null())
        .output()
        .map_err(|e| format!("cannot run perf script: {e}"))?;
    if !out.status.success() {
        return Err("perf script failed".into());
    }
    Ok(classify(&String::from_utf8_lossy(&out.stdout)))
}

/// Classify `perf script -F period,ip,sym` output: blocks separated by a
/// blank line, a period line then one `ADDRESS SYMBOL` line per frame.
pub fn classify(text: &str) -> Profile {
    let mut totals = vec![0.0; PHASES.len() + 1];
    let mut samples = 0;
    for block in text.split("\n\n") {
        let mut lines = block.lines().filter(|l| !l.trim().is_empty());
        let Some(head) = lines.next() else { continue };
        let Ok(period) = head.trim().parse::<f64>() else {
            continue;
        };
        let frames: Vec<&str> = lines
            .map(|l| l.trim().split_once(' ').map_or("", |(_, sym)| sym))
            .collect();
        let phase = PHASES
            .iter()
            .position(|(_, marks)| frames.iter().any(|f| marks.iter().any(|m| f.contains(m))))
            .unwrap_or(PHASES.len());
        totals[phase] += period;
        samples += 1;
    }
    let sum: f64 = totals.iter().sum();
    let shares = PHASES
        .iter()
        .map(|(name, _)| *name)
        .chain(std::iter::once(OTHER))
        .zip(&totals)
        .map(|(name, t)| (name.to_string(), if sum > 0.0 { t / sum } else { 0.0 }))
        .collect();
    Profile { shares, samples }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn samples_go_to_their_first_phase() {
        let text = "\
    300 \n\t  1 vicurve::correlation::Correlation::iterate\n\t  2 vicurve::band::Band::new\n\n\
    100 \n\t  1 libm::exp\n\t  2 vicurve::correlation::Correlation::iterate\n\n\
    100 \n\t  1 _dl_start\n";
        let p = classify(text);
        assert_eq!(p.samples, 3);
        let share = |n: &str| p.shares.iter().find(|s| s.0 == n).map(|s| s.1);
        assert_eq!(share("band building"), Some(0.6));
        assert_eq!(share("GN iterations (Correlation::iterate)"), Some(0.2));
        assert_eq!(share(OTHER), Some(0.2));
    }
}
