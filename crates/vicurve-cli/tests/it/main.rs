//! The command line's integration tests: one binary, shared helpers in
//! `common`.

mod common;

mod cli;
mod conformance;
mod diagnostics;
mod export;
mod golden;
mod objects;
mod shard;
mod speed;
mod stack;
mod start;
mod track;
mod video;
