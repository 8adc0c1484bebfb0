//! Starts far from the edge (issue 18, failure 2.5): a start that cannot
//! be measured as one simple curve is reported as diverged, never as a
//! success.

use vicurve::curve::InitialCurve;
use vicurve::fit::{measure, Divergence, FitConfig, Outcome};
use vicurve::render::render;

use crate::common::disc;

/// A start that crosses itself (a figure of eight over a disc) cannot be
/// measured as the disc's edge, nor as any simple curve: the curve it
/// moves to crosses itself as well, a divergence, not a result.
#[test]
fn a_start_that_crosses_itself_diverges() {
    let spec = disc(200, (100.3, 99.8, 60.0), 1.5, 0.01, 1, Some(8));
    let image = render(&spec).expect("render");
    let points: Vec<[f64; 2]> = (0..64)
        .map(|i| {
            let t = std::f64::consts::TAU * i as f64 / 64.0;
            [100.0 + 62.0 * t.sin(), 100.0 + 45.0 * (2.0 * t).sin()]
        })
        .collect();
    let init = InitialCurve::Polyline {
        points,
        closed: true,
    };
    let m = measure(&image, &init, &FitConfig::default()).expect("measure");
    println!("a figure of eight over a disc: {}", m.outcome);
    assert!(
        matches!(
            m.outcome,
            Outcome::Diverged {
                divergence: Divergence::SelfIntersecting { .. } | Divergence::FoldedBack { .. }
            }
        ),
        "{}",
        m.outcome
    );
}
