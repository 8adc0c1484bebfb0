//! Every option of the command line, declared once.
//!
//! The subcommands are made of these structs (`#[command(flatten)]`): a
//! flag that two commands share comes from the same field, with the same
//! help. Option values that name a library type are parsed by that type's
//! `FromStr` only (the parser Python's bindings use too), when the options
//! are turned into the library's configuration: a wrong value is then one
//! line, `vicurve: error: ...`, exit 1, as any other input error.
//!
//! - [`curve`]: the options of one curve to measure ([`CurveArgs`], shared
//!   by `measure`, `track` and job files) and those only `measure` has
//!   ([`BandArgs`]), turned into [`vicurve::fit::FitConfig`];
//! - [`start`]: `measure`'s start (`--init`, `--pick`, `--roi`, `--grow`);
//! - [`files`]: the output files of a measurement and its CAD exports;
//! - [`synth`]: the options of `synth`;
//! - [`all`]: `measure --all` and `grid`.

pub mod all;
pub mod curve;
pub mod files;
pub mod start;
pub mod synth;

pub use all::AllArgs;
pub use curve::{BandArgs, CurveArgs};
pub use files::{CurveFiles, Outputs};
pub use start::StartArgs;
