//! The progress bar of a sequence: frames per second and the time left,
//! on a terminal only (elsewhere, one log line per frame).

use crate::failure::Failure;
use indicatif::{ProgressBar, ProgressDrawTarget, ProgressStyle};
use std::io::IsTerminal;

/// A bar of `len` frames on stderr, hidden when stderr is not a terminal.
pub fn bar(len: u64) -> Result<ProgressBar, Failure> {
    let bar = ProgressBar::with_draw_target(Some(len), ProgressDrawTarget::stderr());
    if !std::io::stderr().is_terminal() {
        bar.set_draw_target(ProgressDrawTarget::hidden());
    }
    bar.set_style(
        ProgressStyle::with_template(
            "{bar:40} {pos}/{len} frames, {per_sec}, {elapsed} elapsed, ETA {eta}",
        )
        .map_err(|e| e.to_string())?,
    );
    Ok(bar)
}
