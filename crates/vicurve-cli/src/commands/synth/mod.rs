//! `vicurve synth`: test images with exactly known geometry.

mod necking;
mod scene;

pub use crate::args::synth::Args;
use crate::args::synth::{check_bits, numbers, parse_size, ShapeName, DEFAULT_LEVELS};
use crate::failure::Failure;
use vicurve::render::Shading;
use vicurve::render::Truth;
use vicurve::render::{presets, render, Method, RenderSpec};
use vicurve::tone::Tone;
use vicurve::truth::Shape;
use vicurve::virtual_image::Kind;

pub fn run(args: Args) -> Result<(), Failure> {
    if args.shape == ShapeName::Necking {
        return necking::necking(&args);
    }
    if args.shape == ShapeName::SquareGrid {
        return scene::square(&args);
    }
    if matches!(args.shape, ShapeName::Scene | ShapeName::Grid) {
        return scene::scene(&args);
    }
    let spec = spec_from_args(&args)?;
    let image = render(&spec)?;
    let bits = args.bits.unwrap_or(8);
    vicurve::io::save_image(&args.out, &image, bits)?;
    if let Some(t) = &args.truth {
        Truth::from_spec(&spec).save(t)?;
    }
    eprintln!(
        "wrote {} ({}x{}, {}-bit{})",
        args.out.display(),
        spec.width,
        spec.height,
        bits,
        args.truth
            .as_ref()
            .map(|t| format!(", truth in {}", t.display()))
            .unwrap_or_default()
    );
    Ok(())
}

/// The render specification described by the arguments.
pub fn spec_from_args(a: &Args) -> Result<RenderSpec, Failure> {
    let bits = check_bits(a.bits.unwrap_or(8))?;
    let (w, h) = parse_size(a.size.as_deref().unwrap_or("512x512"))?;
    let (blur, noise) = (a.blur.unwrap_or(0.0), a.noise.unwrap_or(0.0));
    let levels = numbers("levels", &a.levels, ',', 2)?;
    let tone: Tone = a
        .tone
        .parse()
        .map_err(|e| Failure::Error(format!("--tone: {e}")))?;
    let shading: Shading = a
        .shading
        .parse()
        .map_err(|e| Failure::Error(format!("--shading: {e}")))?;
    if a.shape == ShapeName::PaperDisc {
        // The preset (512x512, levels 0 and 1 unless given), with the
        // user's radius, profile, blur, noise and depth on top.
        let mut spec = presets::paper_disc(a.profile.unwrap_or(10.0));
        if let Shape::Circle { r, .. } = &mut spec.shape {
            *r = a.radius.unwrap_or(*r);
        }
        if a.levels != DEFAULT_LEVELS {
            (spec.background, spec.foreground) = (levels[0], levels[1]);
        }
        spec.blur_sigma = blur;
        spec.blur_sigma_y = a.blur_y;
        spec.noise = noise;
        spec.seed = a.seed;
        spec.bits = Some(bits);
        spec.tone = tone;
        spec.shading = shading;
        spec.validate()?;
        return Ok(spec);
    }
    let small = w.min(h);
    let (cx, cy) = match &a.center {
        Some(c) => {
            let v = numbers("center", c, ',', 2)?;
            (v[0], v[1])
        }
        None => ((w - 1.0) / 2.0 + 0.3, (h - 1.0) / 2.0 - 0.2),
    };
    let radius = a.radius.unwrap_or(0.3 * small);
    let phase = a.phase.to_radians();
    let sine = || Shape::Sine {
        y0: a.y0.unwrap_or((h - 1.0) / 2.0 + 0.3),
        amplitude: a.amplitude.unwrap_or(0.1 * h),
        wavelength: a.wavelength.unwrap_or(0.5 * w),
        phase,
        x_min: 0.0,
        x_max: w - 1.0,
    };
    let shape = match a.shape {
        ShapeName::Disc | ShapeName::Ring | ShapeName::PaperDisc => {
            Shape::Circle { cx, cy, r: radius }
        }
        ShapeName::Ellipse => {
            let ab = match &a.axes {
                Some(t) => numbers("axes", t, ',', 2)?,
                None => vec![0.35 * small, 0.2 * small],
            };
            Shape::Ellipse {
                cx,
                cy,
                a: ab[0],
                b: ab[1],
                angle: a.angle.to_radians(),
            }
        }
        ShapeName::Star => Shape::Star {
            cx,
            cy,
            r0: radius,
            amplitude: a.amplitude.unwrap_or(0.2),
            lobes: a.lobes,
            phase,
        },
        ShapeName::SineEdge | ShapeName::SineLine => sine(),
        ShapeName::Necking => {
            return Err(Failure::Error(
                "necking is a sequence: see synth necking".into(),
            ));
        }
        ShapeName::Scene | ShapeName::Grid | ShapeName::SquareGrid => {
            return Err(Failure::Error(
                "scene and grid hold many shapes: see synth scene, synth grid".into(),
            ));
        }
    };
    let line = match a.shape {
        ShapeName::Ring | ShapeName::SineLine => Some(a.line.unwrap_or(3.0)),
        _ => a.line,
    };
    let profile = a.profile;
    let (background, foreground) = (levels[0], levels[1]);
    let spec = RenderSpec {
        width: w as usize,
        height: h as usize,
        shape,
        kind: if line.is_some() {
            Kind::Contour
        } else {
            Kind::Silhouette
        },
        line_width: line.unwrap_or(3.0),
        foreground,
        background,
        method: match profile {
            Some(half_width) => Method::Profile { half_width },
            None => Method::Coverage,
        },
        blur_sigma: blur,
        blur_sigma_y: a.blur_y,
        noise,
        seed: a.seed,
        bits: Some(bits),
        tone,
        shading,
    };
    spec.validate()?;
    Ok(spec)
}
