//! The command line's integration tests: one binary, shared helpers in
//! `common`.

mod common;
mod golden;
