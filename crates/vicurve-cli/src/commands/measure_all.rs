//! `vicurve measure IMAGE --all`: every object of the image.

use super::measure::Args;
use crate::args::all::object_polarity;
use crate::failure::Failure;
use crate::output::objects;
use vicurve::objects::{measure_all, AllConfig, AllResult};
use vicurve::virtual_image::Kind;

/// The configuration of `--all` from `measure`'s flags: `--polarity` is the
/// objects' phase; the fit's polarity is set per object.
pub fn config(args: &Args) -> Result<AllConfig, Failure> {
    if args.start.init.is_some() || args.start.pick.is_some() || args.start.grow.is_some() {
        return Err(Failure::Error(
            "--all finds every object itself: drop --init, --pick and --grow".into(),
        ));
    }
    let mut curve = args.curve.clone();
    let polarity = object_polarity(&curve.polarity)?;
    curve.polarity = "auto".into();
    let mut fit = curve.config()?;
    args.band.apply(&mut fit)?;
    Ok(AllConfig {
        polarity,
        min_length: args.all.min_length,
        min_area: args.all.min_area,
        roi: args.start.automatic()?.roi,
        include_border: args.all.include_border,
        holes: args.all.holes,
        corners: args.all.corners,
        min_strength: args.all.min_strength,
        model: args.model,
        fit,
        ..AllConfig::default()
    })
}

pub fn run(args: Args) -> Result<(), Failure> {
    let config = config(&args)?;
    config.validate()?;
    if args.diagnostics.is_some() || args.cad.any() {
        return Err(Failure::Error(
            "--all writes --out, --points, --table, --svg and --png; --diagnostics and the CAD files are for one curve".into(),
        ));
    }
    let image = vicurve::io::load_image(&args.image)?;
    let all = measure_all(&image, &config)?;
    let input = args.image.display().to_string();
    objects::write(
        &all,
        &config,
        &input,
        &image,
        &args.outputs,
        args.all.table.as_deref(),
    )?;
    summary(&all, config.fit.kind);
    finish(&all)
}

/// One line on what was found (objects, or lines with `kind` contour), one
/// per failed object.
pub fn summary(all: &AllResult, kind: Kind) {
    let f = &all.found;
    if kind == Kind::Contour {
        eprintln!(
            "vicurve: {} {} line(s) found (least strength {:.4}, strength noise {:.4}); left out: {} short, {} not followed",
            all.objects.len(),
            if f.bright { "bright" } else { "dark" },
            f.threshold,
            f.noise,
            f.small,
            f.faint
        );
    } else {
        eprintln!(
            "vicurve: {} {} object(s) found (threshold {:.4}, noise {:.4}); left out: {} small{}, {} faint, {} cut by the border",
            all.objects.len(),
            if f.bright { "bright" } else { "dark" },
            f.threshold,
            f.noise,
            f.small,
            small_limits(f),
            f.faint,
            f.border
        );
    }
    for o in all.objects.iter() {
        if let Some(e) = &o.failure {
            let c = o.region.centroid;
            eprintln!(
                "vicurve: object {} at ({:.1}, {:.1}) failed: {e}",
                o.id, c[0], c[1]
            );
        }
    }
}

/// The least area and length the small regions were under, and the
/// options that lower them (empty without small regions).
fn small_limits(f: &vicurve::objects::Found) -> String {
    if f.small == 0 {
        return String::new();
    }
    format!(
        " (under {:.0} px^2 or a {:.0} px boundary: --min-area, --min-length)",
        f.min_area, f.min_length
    )
}

/// Exit 3 when some object failed (the others are written); exit 1 when
/// no object was found but some were left out as small (nothing was
/// measured, and the user should lower the limits).
pub fn finish(all: &AllResult) -> Result<(), Failure> {
    let f = &all.found;
    if all.objects.is_empty() && f.small > 0 {
        return Err(Failure::Error(format!(
            "no object measured: {} left out as too small (least area {:.0} px^2, least length {:.0} px); lower --min-area or --min-length to measure them",
            f.small, f.min_area, f.min_length
        )));
    }
    match all.failed() {
        0 => Ok(()),
        n => Err(Failure::Diverged(format!(
            "{n} of {} objects failed (the others are measured and written; the table's outcome says why each failed)",
            all.objects.len()
        ))),
    }
}
