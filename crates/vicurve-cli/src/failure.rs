//! How a command fails, and the exit status of a measurement's outcome.

use vicurve::fit::{Measurement, Outcome};

/// How a command failed.
pub enum Failure {
    /// Bad input or files: exit 1.
    Error(String),
    /// The fit diverged (outputs written): exit 3.
    Diverged(String),
}

impl From<vicurve::Error> for Failure {
    fn from(e: vicurve::Error) -> Self {
        Failure::Error(e.to_string())
    }
}

impl From<String> for Failure {
    fn from(e: String) -> Self {
        Failure::Error(e)
    }
}

impl Failure {
    /// The message, whatever the kind of failure.
    pub fn message(self) -> String {
        match self {
            Failure::Error(m) | Failure::Diverged(m) => m,
        }
    }
}

/// Map a measurement's outcome to the exit status: diverged is a failure,
/// an iteration limit a warning.
pub fn finish(m: &Measurement) -> Result<(), Failure> {
    match m.outcome {
        Outcome::Converged => Ok(()),
        Outcome::IterationLimit => {
            eprintln!(
                "vicurve: warning: the iteration limit was reached before convergence; raise --max-iter or start closer to the curve"
            );
            Ok(())
        }
        Outcome::Diverged { divergence } => Err(Failure::Diverged(format!(
            "the fit diverged: {divergence}; start from a curve closer to the edge, or use a narrower band (--stages)"
        ))),
    }
}

/// Messages are printed on one line whatever their source.
pub fn one_line(msg: &str) -> String {
    msg.split_whitespace().collect::<Vec<_>>().join(" ")
}
