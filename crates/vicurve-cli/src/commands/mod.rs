//! One module per subcommand: its own arguments (made of the structs of
//! [`crate::args`]) and `run`, which calls the layers below.

pub mod bench;
pub mod demo;
pub mod eval;
pub mod eval_objects;
pub mod export;
pub mod grid;
pub mod measure;
pub mod measure_all;
pub mod merge;
pub mod mesh;
pub mod run;
pub mod synth;
pub mod track;
