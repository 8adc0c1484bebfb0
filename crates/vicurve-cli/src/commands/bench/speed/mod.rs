//! `vicurve bench speed`: the time of one measurement from scratch (issue
//! 19). The three cases ([`cases`]) are rendered and saved as PNG; each is
//! measured by whole `vicurve measure` processes ([`process`]: wall clock,
//! peak resident set) and in this process part by part ([`inproc`]:
//! decode, prefilter, the fit's stages, the blur estimate, writing); with
//! `--profile`, one single-threaded process per case under `perf`
//! ([`profile`]); with `--peers`, the Python peers on the same images
//! ([`peers`]). [`report`] prints the table and writes `speed.md` and
//! `speed.csv`.

mod cases;
mod inproc;
mod peers;
pub(super) mod process;
mod profile;
pub(super) mod report;

use crate::failure::Failure;
use cases::SpeedCase;
use std::path::{Path, PathBuf};

/// Arguments of `vicurve bench speed`.
#[derive(clap::Args)]
pub struct SpeedArgs {
    /// Timed runs of each case (whole processes, and as many in-process
    /// measurements); medians, minima and maxima are reported.
    #[arg(long, default_value_t = 7)]
    repeats: usize,
    /// Output directory (created if needed): speed.md and speed.csv are
    /// replaced.
    #[arg(long, default_value = "speed")]
    out: PathBuf,
    /// Working directory (created if needed): the images (images/) and
    /// the runs' result files (runs/); default: vicurve-speed in the
    /// system's temporary directory.
    #[arg(long, value_name = "DIR")]
    work: Option<PathBuf>,
    /// Also time scikit-image `find_contours` and subpixel-edges on the
    /// same images (bench/peers/speed_peers.py, needs the packages of
    /// bench/peers/requirements.txt) and print the ratios.
    #[arg(long)]
    peers: bool,
    /// The Python interpreter of `--peers`.
    #[arg(long, default_value = "python3", value_name = "PATH")]
    python: String,
    /// Also profile one single-threaded process of each case with `perf`
    /// (when installed): the share of each phase.
    #[arg(long)]
    profile: bool,
    /// Small images (a smoke test of the command).
    #[arg(long, hide = true)]
    quick: bool,
}

/// Everything measured on one case.
pub struct CaseResult {
    /// The case (its image included).
    pub case: SpeedCase,
    /// The `measure` arguments timed.
    pub args: Vec<String>,
    /// The timed processes.
    pub runs: Vec<process::ProcessRun>,
    /// The in-process timings, one per repeat.
    pub parts: Vec<inproc::Parts>,
    /// The last in-process measurement.
    pub m: vicurve::fit::Measurement,
    /// Total Gauss–Newton iterations of the process's result file (to check
    /// that it measured what the in-process run did).
    pub process_iterations: Option<usize>,
    /// The perf profile, or why there is none.
    pub profile: Option<Result<profile::Profile, String>>,
    /// Peak resident set of one more process under `/usr/bin/time -v`,
    /// bytes (`None` without that program).
    pub peak_rss: Option<Result<u64, String>>,
}

/// Run the benchmark and write its outputs.
pub fn speed(args: &SpeedArgs) -> Result<(), Failure> {
    if args.repeats == 0 {
        return Err(Failure::Error("--repeats must be at least 1".into()));
    }
    let out = &args.out;
    let work = args
        .work
        .clone()
        .unwrap_or_else(|| std::env::temp_dir().join("vicurve-speed"));
    let images = work.join("images");
    let runs = work.join("runs");
    for d in [out, &images, &runs] {
        std::fs::create_dir_all(d)
            .map_err(|e| format!("cannot create the directory {}: {e}", d.display()))?;
    }
    let exe = std::env::current_exe().map_err(|e| format!("cannot find this program: {e}"))?;
    let machine = report::Machine::now();
    let profiling = args.profile && {
        let ok = profile::available();
        if !ok {
            eprintln!("vicurve: --profile: perf is not installed here; no profile");
        }
        ok
    };
    let mut results = Vec::new();
    for case in cases::cases(args.quick)? {
        eprintln!("{}: {} runs ...", case.name, args.repeats);
        results.push(run_case(
            case,
            &exe,
            &images,
            &runs,
            args.repeats,
            profiling,
        )?);
    }
    let peer_result = if args.peers {
        Some(run_peers(args, &results))
    } else {
        None
    };
    let command = command_line(args);
    let table = report::table(&results, peer_result.as_ref());
    print!("{table}");
    write(
        &out.join("speed.md"),
        &report::markdown(&results, peer_result.as_ref(), &machine, &command),
    )?;
    write(
        &out.join("speed.csv"),
        &report::csv(&results, peer_result.as_ref()),
    )?;
    println!(
        "wrote {} (speed.md, speed.csv); images and runs in {}",
        out.display(),
        work.display()
    );
    Ok(())
}

/// The peers, or the one line that says why they did not run.
fn run_peers(args: &SpeedArgs, results: &[CaseResult]) -> Result<peers::Peers, String> {
    let Some(script) = peers::script() else {
        return Err("bench/peers/speed_peers.py not found (run from the repository)".into());
    };
    if let Some(why) = peers::missing(&args.python) {
        return Err(why);
    }
    eprintln!(
        "peers: {} runs of each (numba compiles first) ...",
        args.repeats
    );
    let images: Vec<PathBuf> = results.iter().map(image_path).collect();
    peers::run(&args.python, &script, &images, args.repeats)
}

/// The image file of a case's result.
fn image_path(r: &CaseResult) -> PathBuf {
    PathBuf::from(&r.args[1])
}

/// Save the case's image, time its processes and its parts in-process.
fn run_case(
    case: SpeedCase,
    exe: &Path,
    images: &Path,
    runs: &Path,
    repeats: usize,
    profiling: bool,
) -> Result<CaseResult, Failure> {
    let image = images.join(format!("{}.png", case.name));
    vicurve::io::save_image(&image, &case.image, 8)?;
    let json = runs.join(format!("{}.json", case.name));
    let mut args = vec![
        "measure".to_string(),
        image.display().to_string(),
        "--init".into(),
        case.init.clone(),
    ];
    if let Some(s) = case.stages {
        args.extend(["--stages".into(), s.to_string()]);
    }
    args.extend([
        "--out".into(),
        json.display().to_string(),
        "--points".into(),
        runs.join(format!("{}.csv", case.name))
            .display()
            .to_string(),
    ]);
    // One run untimed: the program and the image in the page cache.
    process::run(exe, &args)?;
    let mut timed = Vec::with_capacity(repeats);
    for _ in 0..repeats {
        let r = process::run(exe, &args)?;
        // 0 converged or iteration limit, 3 diverged (outputs written).
        if !matches!(r.code, Some(0) | Some(3)) {
            return Err(Failure::Error(format!(
                "{}: vicurve {} exited with {:?}",
                case.name,
                args.join(" "),
                r.code
            )));
        }
        timed.push(r);
    }
    let process_iterations = iterations_of(&json);
    let peak_rss = process::peak_rss_time_v(exe, &args);
    let mut parts = Vec::with_capacity(repeats);
    let mut last = None;
    for _ in 0..repeats {
        let (p, m) = inproc::run(&case, &image, runs)?;
        parts.push(p);
        last = Some(m);
    }
    let m = last.ok_or_else(|| Failure::Error("no in-process run".into()))?;
    let profile = profiling.then(|| {
        let data = runs.join(format!("{}.perf.data", case.name));
        let seconds = timed.iter().map(|r| r.seconds).fold(0.0, f64::max);
        let p = profile::profile(exe, &args, &data, seconds);
        // perf's file is large and only this run reads it.
        let _ = std::fs::remove_file(&data);
        p
    });
    Ok(CaseResult {
        case,
        args,
        runs: timed,
        parts,
        m,
        process_iterations,
        profile,
        peak_rss,
    })
}

/// Total iterations over the stages of a result file.
fn iterations_of(json: &Path) -> Option<usize> {
    let text = std::fs::read_to_string(json).ok()?;
    let v: serde_json::Value = serde_json::from_str(&text).ok()?;
    v["stages"].as_array().map(|stages| {
        stages
            .iter()
            .map(|s| s["iterations"].as_u64().unwrap_or(0) as usize)
            .sum()
    })
}

fn write(path: &Path, text: &str) -> Result<(), String> {
    std::fs::write(path, text).map_err(|e| format!("cannot write {}: {e}", path.display()))
}

/// The command that reproduces the outputs.
fn command_line(args: &SpeedArgs) -> String {
    let mut c = format!(
        "vicurve bench speed --repeats {} --out {}",
        args.repeats,
        args.out.display()
    );
    if args.peers {
        c.push_str(" --peers");
        if args.python != "python3" {
            c.push_str(" --python PYTHON");
        }
    }
    if args.profile {
        c.push_str(" --profile");
    }
    if let Some(w) = &args.work {
        c.push_str(&format!(" --work {}", w.display()));
    }
    if args.quick {
        c.push_str(" --quick");
    }
    c
}
