//! The start of `measure`: the curve given with `--init`, or the one
//! found automatically (with a line saying what was found), and a grown
//! start (`--grow`), measured.

use crate::args::{CurveArgs, StartArgs};
use crate::failure::Failure;
use vicurve::curve::InitialCurve;
use vicurve::fit::grow::{grow, EndReason, GrowConfig, Grown};
use vicurve::fit::FitConfig;
use vicurve::interp::Sampler;
use vicurve::virtual_image::Kind;
use vicurve::Image;

/// The starting curve: `explicit` (the parsed `--init`) or, without it,
/// the automatic start found in `image` (`--pick`, `--roi` in `auto`).
pub fn initial_curve(
    explicit: Option<InitialCurve>,
    auto: &vicurve::start::StartConfig,
    kind: Kind,
    image: &Image,
) -> Result<InitialCurve, Failure> {
    if let Some(init) = explicit {
        return Ok(init);
    }
    if kind == Kind::Contour {
        let found = vicurve::start::ridge::find_line(image, auto).map_err(|e| match e {
            // Its reasons already say what to try.
            vicurve::Error::NoLine { .. } => e.to_string(),
            _ => format!("{e}; or give a starting curve with --init"),
        })?;
        eprintln!(
            "vicurve: automatic start: {} line followed from the picked point over {:.0} px (scale {} px), {} curve",
            if found.bright { "bright" } else { "dark" },
            found.length,
            found.scale,
            if found.closed { "closed" } else { "open" }
        );
        return Ok(found.curve);
    }
    let found = vicurve::start::find_silhouette(image, auto).map_err(|e| {
        format!("{e}; give a starting curve with --init, or point at the object with --pick X,Y")
    })?;
    eprintln!(
        "vicurve: automatic start: {} {} region of {} pixels (threshold {:.4}), {} curve",
        if found.bright { "bright" } else { "dark" },
        if auto.pick.is_some() {
            "picked"
        } else {
            "main"
        },
        found.region_pixels,
        found.threshold,
        if found.closed { "closed" } else { "open" }
    );
    Ok(found.curve)
}

/// `--init`, parsed with `--closed` (before the image is read, so that a
/// bad start is reported first).
pub fn explicit(start: &StartArgs, curve: &CurveArgs) -> Result<Option<InitialCurve>, Failure> {
    start
        .init
        .as_deref()
        .map(|spec| curve.init(spec))
        .transpose()
}

/// `--grow [LEN]`: grow the open start segment by segment, then measure.
pub fn grow_from(
    image: &Image,
    init: &InitialCurve,
    config: &FitConfig,
    length: Option<f64>,
) -> Result<Grown, Failure> {
    if init.is_closed() {
        return Err(Failure::Error(
            "--grow extends the two ends of an open start: give --init segment:X0,Y0,X1,Y1 or an open polyline".into(),
        ));
    }
    let sampler = Sampler::new(image, config.interpolation);
    let settings = GrowConfig {
        max_length: length,
        ..GrowConfig::default()
    };
    let g = grow(&sampler, init.to_curve()?, config, &settings)?;
    let kept = g.report.steps.iter().filter(|s| s.kept).count();
    let why = |e: EndReason| match e {
        EndReason::Border => "the image border",
        EndReason::EdgeEnds => "the end of the edge",
        EndReason::Length => "the length asked",
        EndReason::Closed => "closure",
        EndReason::MetUnclosed => "the other end (the loop did not converge)",
        EndReason::StepLimit => "the step limit",
        EndReason::StartFailed => "a start that did not converge",
    };
    let [a, b] = g.report.ends;
    if a == EndReason::Closed {
        eprintln!("vicurve: grown in {kept} step(s) into a closed curve");
    } else {
        eprintln!(
            "vicurve: grown in {kept} step(s); the start stopped at {}, the end at {}",
            why(a),
            why(b)
        );
    }
    Ok(g)
}
