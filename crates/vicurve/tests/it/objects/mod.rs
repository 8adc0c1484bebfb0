//! Every object of an image (`vicurve::objects`): found completely, each
//! measured to the single-object accuracy, failures recorded with their
//! reason.

mod grid;
mod holes;
mod lines;
mod scene;
mod square_grid;
