//! The automatic element length (`fit/refine.rs`): a last step onto the
//! shortest elements judged on references of its own.

use vicurve::curve::InitialCurve;
use vicurve::fit::{FitConfig, Outcome};

use super::run;
use crate::common::disc;

/// A small disc (radius 10 px: a hole, a circle grid's dot), blurred by 1
/// px, noiseless, 16 bits, from a circle 0.5 px off. Its 63 px of outline
/// start on the 8 elements a closed curve needs at least (7.9 px), whose
/// best cubic spline is 4.0e-3 px (RMS) off a circle, and so was the
/// measurement (measured before): the pixel-edge stage's last step onto 5
/// px elements was judged on the coarse reference, which holds that error
/// at the coarse elements' period, beyond the finer elements' reach. On
/// references of their own the step is taken: 13 elements, scatter 5e-4
/// px (measured).
#[test]
fn a_small_disc_refines_on_its_own_reference() {
    let spec = disc(64, (32.27, 31.64, 10.0), 1.0, 0.0, 7, Some(16));
    let init = InitialCurve::Circle {
        cx: 32.6,
        cy: 31.3,
        r: 10.0,
    };
    let (m, s) = run(&spec, init, FitConfig::default());
    let elements = m.stages.last().unwrap().elements;
    println!(
        "disc r = 10, blur 1: {elements} elements, bias {:+.2e} scatter {:.2e} max {:.2e}",
        s.bias, s.scatter, s.max_abs
    );
    assert_eq!(m.outcome, Outcome::Converged);
    assert!(elements >= 12, "{elements} elements");
    assert!(s.scatter <= 1.5e-3, "scatter {}", s.scatter);
    assert!(s.bias.abs() <= 1e-3, "bias {}", s.bias);
}
