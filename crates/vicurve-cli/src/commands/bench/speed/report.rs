//! The speed benchmark's outputs: the table printed, `speed.md` (machine,
//! whole processes, parts, stages, profile, peers) and `speed.csv` (one
//! line per case and quantity: median, min, max).

use super::peers::Peers;
use super::CaseResult;
use std::fmt::Write as _;

/// Median, minimum and maximum of some timings.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Spread {
    /// Median (the mean of the two middle values for an even count).
    pub median: f64,
    /// Smallest.
    pub min: f64,
    /// Largest.
    pub max: f64,
}

impl Spread {
    /// Of `values` (NaN for none).
    pub fn of(values: &[f64]) -> Spread {
        let mut v: Vec<f64> = values.to_vec();
        v.sort_by(f64::total_cmp);
        let n = v.len();
        if n == 0 {
            return Spread {
                median: f64::NAN,
                min: f64::NAN,
                max: f64::NAN,
            };
        }
        let median = if n % 2 == 1 {
            v[n / 2]
        } else {
            0.5 * (v[n / 2 - 1] + v[n / 2])
        };
        Spread {
            median,
            min: v[0],
            max: v[n - 1],
        }
    }

    /// `median [min, max]` in milliseconds.
    fn ms(&self) -> String {
        format!(
            "{:.1} [{:.1}, {:.1}]",
            self.median * 1e3,
            self.min * 1e3,
            self.max * 1e3
        )
    }
}

/// Where and when the benchmark ran.
pub struct Machine {
    /// Logical CPUs available to this process.
    pub cpus: usize,
    /// `model name` of /proc/cpuinfo.
    pub model: String,
    /// The 1-minute load average at the start (/proc/loadavg).
    pub load: String,
    /// UTC date and time at the start, `YYYY-MM-DD HH:MM`.
    pub date: String,
}

impl Machine {
    /// This machine, now.
    pub fn now() -> Machine {
        let cpuinfo = std::fs::read_to_string("/proc/cpuinfo").unwrap_or_default();
        let model = cpuinfo
            .lines()
            .find(|l| l.starts_with("model name"))
            .and_then(|l| l.split_once(':'))
            .map_or("unknown".to_string(), |(_, m)| m.trim().to_string());
        let load = std::fs::read_to_string("/proc/loadavg")
            .ok()
            .and_then(|t| t.split_whitespace().next().map(str::to_string))
            .unwrap_or_else(|| "unknown".into());
        Machine {
            cpus: std::thread::available_parallelism().map_or(0, |n| n.get()),
            model,
            load,
            date: utc_now(),
        }
    }
}

/// The current UTC time, `YYYY-MM-DD HH:MM` (days to civil date: Howard
/// Hinnant's algorithm).
fn utc_now() -> String {
    let secs = std::time::SystemTime::now()
        .duration_since(std::time::UNIX_EPOCH)
        .map_or(0, |d| d.as_secs()) as i64;
    let (days, rem) = (secs.div_euclid(86_400), secs.rem_euclid(86_400));
    let z = days + 719_468;
    let era = z.div_euclid(146_097);
    let doe = z - era * 146_097;
    let yoe = (doe - doe / 1460 + doe / 36_524 - doe / 146_096) / 365;
    let doy = doe - (365 * yoe + yoe / 4 - yoe / 100);
    let mp = (5 * doy + 2) / 153;
    let d = doy - (153 * mp + 2) / 5 + 1;
    let m = if mp < 10 { mp + 3 } else { mp - 9 };
    let y = yoe + era * 400 + i64::from(m <= 2);
    format!(
        "{y:04}-{m:02}-{d:02} {:02}:{:02} UTC",
        rem / 3600,
        (rem % 3600) / 60
    )
}

/// The named in-process parts of a case, in report order.
fn parts(r: &CaseResult) -> Vec<(&'static str, Spread)> {
    let p = &r.parts;
    let of =
        |f: &dyn Fn(&super::inproc::Parts) -> f64| Spread::of(&p.iter().map(f).collect::<Vec<_>>());
    let sum = |q: &super::inproc::Parts| q.decode + q.prefilter + q.fit + q.output;
    vec![
        ("decode", of(&|q| q.decode)),
        ("prefilter", of(&|q| q.prefilter)),
        ("fit", of(&|q| q.fit)),
        ("stages", of(&|q| q.stages.iter().sum())),
        ("fit outside stages", of(&|q| q.fit_outside_stages())),
        ("output", of(&|q| q.output)),
        ("in-process total", of(&sum)),
        ("blur estimate (separate call)", of(&|q| q.blur_estimate)),
    ]
}

/// Process wall clock of a case.
fn process(r: &CaseResult) -> Spread {
    Spread::of(&r.runs.iter().map(|x| x.seconds).collect::<Vec<_>>())
}

/// Peak resident set of the case's process under `/usr/bin/time -v`, MiB
/// (NaN when not measured).
fn peak_mib(r: &CaseResult) -> f64 {
    match &r.peak_rss {
        Some(Ok(b)) => *b as f64 / (1024.0 * 1024.0),
        _ => f64::NAN,
    }
}

/// Why the peak resident set was not measured, if it was not.
fn rss_note(r: &CaseResult) -> Option<String> {
    match &r.peak_rss {
        Some(Ok(_)) => None,
        Some(Err(e)) => Some(e.clone()),
        None => Some("/usr/bin/time is not installed".into()),
    }
}

/// Median of each stage's seconds over the repeats.
fn stage_seconds(r: &CaseResult) -> Vec<Spread> {
    (0..r.m.stages.len())
        .map(|i| {
            Spread::of(
                &r.parts
                    .iter()
                    .filter_map(|p| p.stages.get(i).copied())
                    .collect::<Vec<_>>(),
            )
        })
        .collect()
}

/// vicurve's in-process time without decoding (prefilter, fit, output):
/// what a peer's in-process time (image in memory) compares with.
fn in_memory(r: &CaseResult) -> f64 {
    Spread::of(
        &r.parts
            .iter()
            .map(|q| q.prefilter + q.fit + q.output)
            .collect::<Vec<_>>(),
    )
    .median
}

/// The table printed at the end of a run.
pub fn table(results: &[CaseResult], peers: Option<&Result<Peers, String>>) -> String {
    let mut s = String::new();
    let _ = writeln!(
        s,
        "{:<20} {:>26} {:>9} {:>9} {:>9} {:>9} {:>9} {:>9}",
        "case",
        "process ms median [min,max]",
        "decode",
        "prefilt",
        "fit",
        "stages",
        "output",
        "RSS MiB"
    );
    for r in results {
        let p = parts(r);
        let get = |n: &str| {
            p.iter()
                .find(|x| x.0 == n)
                .map_or(f64::NAN, |x| x.1.median * 1e3)
        };
        let _ = writeln!(
            s,
            "{:<20} {:>26} {:>9.1} {:>9.1} {:>9.1} {:>9.1} {:>9.1} {:>9.1}",
            r.case.name,
            process(r).ms(),
            get("decode"),
            get("prefilter"),
            get("fit"),
            get("stages"),
            get("output"),
            peak_mib(r)
        );
        let stages: Vec<String> =
            r.m.stages
                .iter()
                .zip(stage_seconds(r))
                .map(|(st, t)| {
                    let binned = if st.binning > 1 {
                        format!("/{}", st.binning)
                    } else {
                        String::new()
                    };
                    format!(
                        "R{}{binned} {}it {:.1}ms",
                        st.half_width,
                        st.iterations,
                        t.median * 1e3
                    )
                })
                .collect();
        let _ = writeln!(
            s,
            "{:<20} stages: {} ({})",
            "",
            stages.join(", "),
            r.m.outcome
        );
    }
    match peers {
        None => {}
        Some(Err(why)) => {
            let _ = writeln!(s, "peers: not run: {why}");
        }
        Some(Ok(p)) => {
            let _ = writeln!(
                s,
                "{:<20} {:<24} {:>10} {:>16} {:>16}",
                "case", "peer", "median ms", "vicurve proc/peer", "in-memory/peer"
            );
            for r in results {
                for t in p.times.iter().filter(|t| t.image == super::image_path(r)) {
                    let _ = writeln!(
                        s,
                        "{:<20} {:<24} {:>10.1} {:>16.2} {:>16.2}",
                        r.case.name,
                        t.tool,
                        t.median * 1e3,
                        process(r).median / t.median,
                        in_memory(r) / t.median
                    );
                }
            }
            for e in &p.errors {
                let _ = writeln!(s, "peer failed: {e}");
            }
        }
    }
    s
}

/// `speed.md`.
pub fn markdown(
    results: &[CaseResult],
    peers: Option<&Result<Peers, String>>,
    machine: &Machine,
    command: &str,
) -> String {
    let mut s = String::new();
    let repeats = results.first().map_or(0, |r| r.runs.len());
    let _ = writeln!(s, "# Speed of one measurement\n");
    let _ = writeln!(
        s,
        "Generated by `{command}` (vicurve {}); do not edit by hand. The numbers \
         are in `speed.csv` next to this file.\n",
        env!("CARGO_PKG_VERSION")
    );
    let _ = writeln!(
        s,
        "Machine: {} logical CPUs, {}; load average {} at the start; {}.\n",
        machine.cpus, machine.model, machine.load, machine.date
    );
    let _ = writeln!(
        s,
        "Cases (images rendered by the library, saved as 8-bit PNG in the working directory's `images/`):\n"
    );
    for r in results {
        let _ = writeln!(s, "- `{}`: {}.", r.case.name, r.case.what);
    }
    let _ = writeln!(
        s,
        "\n## Whole process\n\n`vicurve {{args}}` spawned {repeats} times after one untimed run \
         (decode to CSV and JSON); wall clock from spawn to exit, ms; peak resident set of \
         one more run under `/usr/bin/time -v`.\n"
    );
    let _ = writeln!(
        s,
        "| case | median ms | min | max | peak RSS MiB | outcome | iterations |\n|---|---|---|---|---|---|---|"
    );
    for r in results {
        let p = process(r);
        let its = match r.process_iterations {
            Some(n) if n == r.m.iterations() => format!("{n}"),
            Some(n) => format!("{n} (in-process {})", r.m.iterations()),
            None => format!("? (in-process {})", r.m.iterations()),
        };
        let rss = match rss_note(r) {
            None => format!("{:.1}", peak_mib(r)),
            Some(why) => format!("not measured: {why}"),
        };
        let _ = writeln!(
            s,
            "| {} | {:.1} | {:.1} | {:.1} | {rss} | {} | {its} |",
            r.case.name,
            p.median * 1e3,
            p.min * 1e3,
            p.max * 1e3,
            r.m.outcome
        );
    }
    let _ = writeln!(s, "\nThe commands:\n");
    for r in results {
        let _ = writeln!(s, "- `vicurve {}`", r.args.join(" "));
    }
    let _ = writeln!(
        s,
        "\n## Parts, in-process\n\nThe library called as `measure` calls it, {repeats} times: \
         `io::load_image`, `Sampler::new` (the cubic B-spline prefilter of the whole image), \
         `InitialCurve::to_curve` + `measure_from` (the fit: the stages' own `seconds`, and \
         the rest: the blur estimate, the samples with their sigma, the measured B-spline), \
         writing the JSON and CSV; \"blur estimate\" is a separate call of \
         `psf::edge_spread` (band 8 px) on the measured curve, what the fit's estimate costs. \
         Median [min, max], ms; the share of the process's median in brackets.\n"
    );
    let names: Vec<&str> = results
        .first()
        .map_or(Vec::new(), |r| parts(r).iter().map(|x| x.0).collect());
    let _ = writeln!(
        s,
        "| part | {} |",
        results
            .iter()
            .map(|r| r.case.name)
            .collect::<Vec<_>>()
            .join(" | ")
    );
    let _ = writeln!(s, "|---|{}", "---|".repeat(results.len()));
    for name in &names {
        let cells: Vec<String> = results
            .iter()
            .map(|r| {
                let sp = parts(r).into_iter().find(|x| x.0 == *name).map(|x| x.1);
                match sp {
                    Some(sp) => format!(
                        "{} ({:.0} %)",
                        sp.ms(),
                        100.0 * sp.median / process(r).median
                    ),
                    None => "-".into(),
                }
            })
            .collect();
        let _ = writeln!(s, "| {name} | {} |", cells.join(" | "));
    }
    let cells: Vec<String> = results
        .iter()
        .map(|r| {
            let inproc = parts(r)
                .iter()
                .find(|x| x.0 == "in-process total")
                .map_or(f64::NAN, |x| x.1.median);
            format!("{:.1}", (process(r).median - inproc) * 1e3)
        })
        .collect();
    let _ = writeln!(
        s,
        "| process - in-process total (start-up, parsing, exit) | {} |",
        cells.join(" | ")
    );
    let _ = writeln!(
        s,
        "\n## Stages, in-process\n\nA coarse stage of a closed curve runs on the image binned by `binning` (the means of its blocks, `fit/pyramid.rs`); its band pixels are the binned image's.\n"
    );
    for r in results {
        let _ = writeln!(s, "`{}` ({}):\n", r.case.name, r.m.outcome);
        let _ = writeln!(
            s,
            "| R px | binning | profile | elements | iterations | re-references | band pixels | ms median [min, max] | outcome |\n|---|---|---|---|---|---|---|---|---|"
        );
        for (st, t) in r.m.stages.iter().zip(stage_seconds(r)) {
            let _ = writeln!(
                s,
                "| {} | {} | {} | {} | {} | {} | {} | {} | {} |",
                st.half_width,
                st.binning,
                profile_name(&st.profile),
                st.elements,
                st.iterations,
                st.rereferences,
                st.band_pixels,
                t.ms(),
                st.outcome
            );
        }
        if !r.m.skipped.is_empty() {
            let _ = writeln!(s, "\nSkipped: {}.", r.m.skipped.join("; "));
        }
        let _ = writeln!(s);
    }
    profile_section(&mut s, results);
    peers_section(&mut s, results, peers);
    s
}

/// A stage's profile in a few words.
fn profile_name(p: &vicurve::virtual_image::Profile) -> String {
    let text = format!("{p:?}");
    text.split([' ', '{', '(']).next().unwrap_or("").to_string()
}

fn profile_section(s: &mut String, results: &[CaseResult]) {
    let profiled: Vec<&CaseResult> = results.iter().filter(|r| r.profile.is_some()).collect();
    if profiled.is_empty() {
        return;
    }
    let _ = writeln!(
        s,
        "## Profile\n\nOne process of each case under `perf record --call-graph dwarf` (500 to 10,000 Hz, \
         about 4000 samples) \
         with `RAYON_NUM_THREADS=1` (one thread, so that every sample's call chain reaches \
         its phase); each sample goes to the first phase below one of whose functions is on \
         its chain (a band built inside the blur estimate counts as blur estimate). Shares of \
         the CPU time, %.\n"
    );
    let _ = writeln!(
        s,
        "| phase | {} |",
        profiled
            .iter()
            .map(|r| r.case.name)
            .collect::<Vec<_>>()
            .join(" | ")
    );
    let _ = writeln!(s, "|---|{}", "---|".repeat(profiled.len()));
    let names: Vec<String> = super::profile::PHASES
        .iter()
        .map(|p| p.0.to_string())
        .chain(std::iter::once(super::profile::OTHER.to_string()))
        .collect();
    for name in &names {
        let cells: Vec<String> = profiled
            .iter()
            .map(|r| match &r.profile {
                Some(Ok(p)) => p
                    .shares
                    .iter()
                    .find(|x| &x.0 == name)
                    .map_or("-".into(), |x| format!("{:.1}", 100.0 * x.1)),
                _ => "-".into(),
            })
            .collect();
        let _ = writeln!(s, "| {name} | {} |", cells.join(" | "));
    }
    let cells: Vec<String> = profiled
        .iter()
        .map(|r| match &r.profile {
            Some(Ok(p)) => format!("{}", p.samples),
            Some(Err(e)) => format!("failed: {e}"),
            None => "-".into(),
        })
        .collect();
    let _ = writeln!(s, "| samples | {} |\n", cells.join(" | "));
}

fn peers_section(s: &mut String, results: &[CaseResult], peers: Option<&Result<Peers, String>>) {
    let Some(peers) = peers else { return };
    let _ = writeln!(s, "## Peers\n");
    let p = match peers {
        Err(why) => {
            let _ = writeln!(s, "Not run: {why}.\n");
            return;
        }
        Ok(p) => p,
    };
    let _ = writeln!(
        s,
        "`bench/peers/speed_peers.py` on the same images in the same run ({}): each peer \
         called as `run_peers.py` calls it, image in memory (decoding not timed), one warm-up \
         call then the same number of timed calls. Ratios: vicurve's whole-process median, \
         and vicurve's in-process time without decoding (prefilter, fit, output), over the \
         peer's median.\n",
        p.versions
    );
    let _ = writeln!(
        s,
        "| case | peer | median ms | min | max | points | vicurve process / peer | vicurve in-memory / peer |\n|---|---|---|---|---|---|---|---|"
    );
    for r in results {
        for t in p.times.iter().filter(|t| t.image == super::image_path(r)) {
            let _ = writeln!(
                s,
                "| {} | {} | {:.1} | {:.1} | {:.1} | {} | {:.2} | {:.2} |",
                r.case.name,
                t.tool,
                t.median * 1e3,
                t.min * 1e3,
                t.max * 1e3,
                t.points,
                process(r).median / t.median,
                in_memory(r) / t.median
            );
        }
    }
    for e in &p.errors {
        let _ = writeln!(s, "\nFailed: {e}.");
    }
    let _ = writeln!(s);
}

/// `speed.csv`: `case,quantity,median_s,min_s,max_s` (peak RSS in bytes,
/// profile shares as fractions, in the median column).
pub fn csv(results: &[CaseResult], peers: Option<&Result<Peers, String>>) -> String {
    let mut s = String::from("case,quantity,median,min,max\n");
    let mut line = |case: &str, q: &str, sp: Spread| {
        let _ = writeln!(
            s,
            "{case},{q},{:.6e},{:.6e},{:.6e}",
            sp.median, sp.min, sp.max
        );
    };
    for r in results {
        let name = r.case.name;
        line(name, "process_s", process(r));
        for (part, sp) in parts(r) {
            line(
                name,
                &format!("{}_s", part.replace(' ', "_").replace(['(', ')'], "")),
                sp,
            );
        }
        for (i, sp) in stage_seconds(r).into_iter().enumerate() {
            let st = &r.m.stages[i];
            line(name, &format!("stage{}_R{}_s", i + 1, st.half_width), sp);
        }
        let rss = peak_mib(r) * 1024.0 * 1024.0;
        line(
            name,
            "peak_rss_bytes",
            Spread {
                median: rss,
                min: rss,
                max: rss,
            },
        );
        if let Some(Ok(p)) = &r.profile {
            for (phase, share) in &p.shares {
                let q = format!("profile_share:{}", phase.replace(',', ";"));
                line(
                    name,
                    &q,
                    Spread {
                        median: *share,
                        min: *share,
                        max: *share,
                    },
                );
            }
        }
        if let Some(Ok(p)) = peers {
            for t in p.times.iter().filter(|t| t.image == super::image_path(r)) {
                line(
                    name,
                    &format!("peer:{}_s", t.tool),
                    Spread {
                        median: t.median,
                        min: t.min,
                        max: t.max,
                    },
                );
            }
        }
    }
    s
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn spread_of_odd_even_and_none() {
        let s = Spread::of(&[3.0, 1.0, 2.0]);
        assert_eq!((s.median, s.min, s.max), (2.0, 1.0, 3.0));
        assert_eq!(Spread::of(&[4.0, 1.0, 2.0, 3.0]).median, 2.5);
        assert!(Spread::of(&[]).median.is_nan());
    }

    #[test]
    fn the_date_is_civil() {
        let d = utc_now();
        assert_eq!(d.len(), "2026-01-01 00:00 UTC".len());
        assert!(d.starts_with("20"));
    }
}
