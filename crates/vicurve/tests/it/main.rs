//! The library's integration tests: one binary, one module per part of
//! `src/` (`fit/`, `model/`, `start/` as folders, like the library), and
//! the helpers they share in `common`. `cargo test -p vicurve --test it
//! fit::breaks` runs one module.

mod common;

mod band;
mod curve;
mod derived;
mod diagnostics;
mod error;
mod export;
mod fit;
mod interp;
mod io;
mod levelset;
mod model;
mod nurbs;
mod objects;
mod psf;
mod realistic;
mod render;
mod solver;
mod spline;
mod stack;
mod start;
mod truth;
