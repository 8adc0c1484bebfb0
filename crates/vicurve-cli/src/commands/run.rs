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
}

pub fn run(args: Args) -> Result<(), Failure> {
    let job = crate::sequence::job::load(&args.job)?;
    crate::sequence::run(&job, args.force)
}
