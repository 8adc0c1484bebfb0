//! `vicurve merge DIR...`: join the parts of a job run with `run --shard
//! K/N` into one summary (see [`crate::sequence::merge`]).

use crate::failure::Failure;
use std::path::PathBuf;

/// Join the parts of a sharded run into one summary.csv.
#[derive(clap::Args)]
pub struct Args {
    /// Folders holding the parts (`summary.shard-K-of-N.csv` and
    /// `job.json`): the job's output folder, or one folder per part.
    #[arg(required = true)]
    pub dirs: Vec<PathBuf>,
    /// Where to write `summary.csv` (default: the first folder).
    #[arg(long)]
    pub out: Option<PathBuf>,
}

pub fn run(args: Args) -> Result<(), Failure> {
    let out = args.out.clone().unwrap_or_else(|| args.dirs[0].clone());
    crate::sequence::merge::merge(&args.dirs, &out)
}
