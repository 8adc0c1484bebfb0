//! `vicurve run job.toml`: the job file's sequence (see
//! [`crate::sequence::job`] for the format and [`crate::sequence`] for
//! what a run does).

use crate::failure::Failure;
use std::path::PathBuf;

/// Run a job file: images, curves, widths and outputs in TOML.
#[derive(clap::Args)]
pub struct Args {
    /// The job file (TOML; see the README's "Sequences" section).
    pub job: PathBuf,
    /// Measure every frame again, even those already done in the output
    /// folder (by default a re-run skips them).
    #[arg(long)]
    pub force: bool,
    /// Measure part K of N of the frames (`--shard 3/10`, K from 1): an
    /// untracked job's frames split evenly in order. The frames' files go
    /// to the job's output folder, the part's rows to
    /// `summary.shard-K-of-N.csv`; `vicurve merge` joins the parts.
    #[arg(long, value_name = "K/N")]
    pub shard: Option<String>,
}

pub fn run(args: Args) -> Result<(), Failure> {
    let mut job = crate::sequence::job::load(&args.job)?;
    if let Some(text) = &args.shard {
        let (k, n) = crate::sequence::job::parse_shard(text)?;
        crate::sequence::job::shard(&mut job, k, n)?;
    }
    crate::sequence::run(&job, args.force)
}
