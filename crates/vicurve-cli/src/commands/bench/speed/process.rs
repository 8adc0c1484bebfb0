//! One whole `vicurve measure` process: spawned and timed by the wall
//! clock from spawn to exit; its peak resident set from one more run under
//! `/usr/bin/time -v`.

use std::path::Path;
use std::process::{Command, Stdio};
use std::time::Instant;

/// What one process run gave.
pub struct ProcessRun {
    /// Wall-clock seconds from spawn to exit.
    pub seconds: f64,
    /// Exit code (`None`: killed by a signal).
    pub code: Option<i32>,
}

/// Run `exe` with `args`, its output discarded, and time it.
pub fn run(exe: &Path, args: &[String]) -> Result<ProcessRun, String> {
    let started = Instant::now();
    let status = Command::new(exe)
        .args(args)
        .stdin(Stdio::null())
        .stdout(Stdio::null())
        .stderr(Stdio::null())
        .status()
        .map_err(|e| format!("cannot run {}: {e}", exe.display()))?;
    Ok(ProcessRun {
        seconds: started.elapsed().as_secs_f64(),
        code: status.code(),
    })
}

/// `/usr/bin/time`, whose `-v` report gives the peak resident set of the
/// measurement alone: the `ru_maxrss` of a child spawned from this process
/// (`wait4`, `getrusage(RUSAGE_CHILDREN)`) would count the resident set
/// this process had when it spawned it, since Linux carries the peak
/// across `exec`; `time` is small.
const TIME: &str = "/usr/bin/time";

/// The peak resident set (bytes) of one run of `exe args` under
/// `/usr/bin/time -v`, or `None` when that program is not installed.
pub fn peak_rss_time_v(exe: &Path, args: &[String]) -> Option<Result<u64, String>> {
    if !Path::new(TIME).is_file() {
        return None;
    }
    let out = Command::new(TIME)
        .arg("-v")
        .arg(exe)
        .args(args)
        .stdin(Stdio::null())
        .stdout(Stdio::null())
        .output();
    Some(match out {
        Err(e) => Err(format!("cannot run {TIME}: {e}")),
        Ok(o) => String::from_utf8_lossy(&o.stderr)
            .lines()
            .find_map(|l| {
                l.trim()
                    .strip_prefix("Maximum resident set size (kbytes):")
                    .and_then(|v| v.trim().parse::<u64>().ok())
            })
            .map(|kb| kb * 1024)
            .ok_or_else(|| format!("{TIME} -v printed no maximum resident set size")),
    })
}
