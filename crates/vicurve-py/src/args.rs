//! Keyword arguments of the Python functions as the library's types.
//!
//! Pure Rust (no Python objects), so that it is unit-tested by `cargo
//! test`. The names accepted are those of the command-line tool, so that a
//! user can move between the two without a dictionary: `kind=`,
//! `polarity=`, `interpolation=` and `levels=` are parsed by the library's
//! `FromStr` (as the command line's flags are), `stages=` text by
//! [`parse_stages`].

use vicurve::fit::{parse_stages, Elements, Stage};
use vicurve::render::{presets, Method, RenderSpec};
use vicurve::truth::Shape;
use vicurve::virtual_image::Kind;

/// The element part of one stage as given in Python.
#[derive(Clone, Debug, PartialEq)]
pub enum ElementsArg {
    /// A number of elements.
    Count(i64),
    /// The command line's text: `"40px"` (element length) or `"auto"`.
    Text(String),
}

/// One stage `(R, elements)`; the schedule as a whole is checked by
/// `FitConfig::validate`.
pub fn stage(index: usize, half_width: f64, elements: &ElementsArg) -> Result<Stage, String> {
    let elements = match elements {
        ElementsArg::Count(n) if *n < 0 => {
            return Err(format!(
                "invalid stages: stage {index} has {n} elements (must be at least 1)"
            ))
        }
        ElementsArg::Count(n) => Elements::Count(*n as usize),
        ElementsArg::Text(t) => {
            // The command line's parser, on a stage with a dummy width.
            let parsed = parse_stages(&format!("1:{}", t.trim()))
                .map_err(|e| format!("invalid stages: stage {index}: {e}"))?;
            match parsed.as_slice() {
                [one] => one.elements,
                _ => {
                    return Err(format!(
                        "invalid stages: stage {index}: {t:?} is not a number of elements, \"Lpx\" or \"auto\""
                    ))
                }
            }
        }
    };
    Ok(Stage {
        half_width,
        elements,
    })
}

/// The shapes `synth` draws (those of `vicurve synth`).
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum ShapeName {
    /// A disc (silhouette).
    Disc,
    /// An ellipse (silhouette).
    Ellipse,
    /// A star (silhouette).
    Star,
    /// An open sinusoidal edge across the image.
    SineEdge,
    /// A thin circular line (contour).
    Ring,
    /// A thin sinusoidal line (contour).
    SineLine,
    /// The paper's test disc.
    PaperDisc,
}

impl ShapeName {
    /// From the command line's name (`sine-edge` or `sine_edge`).
    pub fn parse(s: &str) -> Result<Self, String> {
        Ok(
            match s.trim().to_ascii_lowercase().replace('_', "-").as_str() {
                "disc" => ShapeName::Disc,
                "ellipse" => ShapeName::Ellipse,
                "star" => ShapeName::Star,
                "sine-edge" => ShapeName::SineEdge,
                "ring" => ShapeName::Ring,
                "sine-line" => ShapeName::SineLine,
                "paper-disc" => ShapeName::PaperDisc,
                _ => return Err(format!(
                    "invalid shape: {s:?} (expected disc, ellipse, star, sine-edge, ring, sine-line or paper-disc)"
                )),
            },
        )
    }
}

/// The options of `synth`, with the defaults of `vicurve synth` (a `None`
/// is the command line's "not given").
#[derive(Clone, Debug, PartialEq)]
pub struct SynthArgs {
    /// What to draw.
    pub shape: ShapeName,
    /// Width, height, pixels.
    pub size: (i64, i64),
    /// Centre of closed shapes (default: image centre + (0.3, -0.2)).
    pub center: Option<(f64, f64)>,
    /// Radius (disc, ring) or mean radius (star) (default: 30 % of the
    /// smaller side).
    pub radius: Option<f64>,
    /// Ellipse semi-axes (default: 35 % and 20 % of the smaller side).
    pub axes: Option<(f64, f64)>,
    /// Ellipse rotation, degrees.
    pub angle: f64,
    /// Star: relative amplitude (0.2); sine: pixels (10 % of the height).
    pub amplitude: Option<f64>,
    /// Star lobes.
    pub lobes: u32,
    /// Phase, degrees.
    pub phase: f64,
    /// Sine wavelength (half the width).
    pub wavelength: Option<f64>,
    /// Sine mean ordinate (middle row + 0.3).
    pub y0: Option<f64>,
    /// Line width of a contour (ring and sine-line: 3 px).
    pub line: Option<f64>,
    /// Render with the virtual profile of this half-width.
    pub profile: Option<f64>,
    /// Gaussian blur, pixels (along the rows when `blur_y` is given).
    pub blur: f64,
    /// The blur along the columns when it differs, pixels.
    pub blur_y: Option<f64>,
    /// Noise, fraction of the contrast.
    pub noise: f64,
    /// Seed of the noise.
    pub seed: u64,
    /// 8, 16 or `None` (no quantisation).
    pub bits: Option<u8>,
    /// Background, foreground (default 0.2, 0.8; the paper disc's 0, 1).
    pub levels: Option<(f64, f64)>,
    /// Tone curve encoding the light (linear).
    pub tone: vicurve::tone::Tone,
    /// Uneven light (even).
    pub shading: vicurve::render::Shading,
}

impl SynthArgs {
    /// The command line's defaults for `shape`.
    pub fn new(shape: ShapeName) -> Self {
        SynthArgs {
            shape,
            size: (512, 512),
            center: None,
            radius: None,
            axes: None,
            angle: 20.0,
            amplitude: None,
            lobes: 5,
            phase: 0.0,
            wavelength: None,
            y0: None,
            line: None,
            profile: None,
            blur: 0.0,
            blur_y: None,
            noise: 0.0,
            seed: 1,
            bits: Some(8),
            levels: None,
            tone: vicurve::tone::Tone::Linear,
            shading: vicurve::render::Shading::default(),
        }
    }
}

/// Gray levels when none are given (`vicurve synth --levels`).
const DEFAULT_LEVELS: (f64, f64) = (0.2, 0.8);

/// The render specification `vicurve synth` builds from the same options,
/// validated.
pub fn synth_spec(a: &SynthArgs) -> Result<RenderSpec, vicurve::Error> {
    if let Some(bits) = a.bits {
        if bits != 8 && bits != 16 {
            return Err(vicurve::Error::invalid(
                "bits",
                format!("{bits} (expected 8, 16 or None)"),
            ));
        }
    }
    let (w, h) = a.size;
    if w < 1 || h < 1 {
        return Err(vicurve::Error::invalid(
            "size",
            format!("({w}, {h}): expected (width, height) of at least one pixel each"),
        ));
    }
    let (w, h) = (w as f64, h as f64);
    if a.shape == ShapeName::PaperDisc {
        let mut spec = presets::paper_disc(a.profile.unwrap_or(10.0));
        if let Shape::Circle { r, .. } = &mut spec.shape {
            *r = a.radius.unwrap_or(*r);
        }
        if let Some((bg, fg)) = a.levels {
            (spec.background, spec.foreground) = (bg, fg);
        }
        spec.blur_sigma = a.blur;
        spec.blur_sigma_y = a.blur_y;
        spec.noise = a.noise;
        spec.seed = a.seed;
        spec.bits = a.bits;
        spec.tone = a.tone;
        spec.shading = a.shading;
        spec.validate()?;
        return Ok(spec);
    }
    let small = w.min(h);
    let (cx, cy) = a
        .center
        .unwrap_or(((w - 1.0) / 2.0 + 0.3, (h - 1.0) / 2.0 - 0.2));
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
            let (sa, sb) = a.axes.unwrap_or((0.35 * small, 0.2 * small));
            Shape::Ellipse {
                cx,
                cy,
                a: sa,
                b: sb,
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
    };
    let line = match a.shape {
        ShapeName::Ring | ShapeName::SineLine => Some(a.line.unwrap_or(3.0)),
        _ => a.line,
    };
    let (background, foreground) = a.levels.unwrap_or(DEFAULT_LEVELS);
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
        method: match a.profile {
            Some(half_width) => Method::Profile { half_width },
            None => Method::Coverage,
        },
        blur_sigma: a.blur,
        blur_sigma_y: a.blur_y,
        noise: a.noise,
        seed: a.seed,
        bits: a.bits,
        tone: a.tone,
        shading: a.shading,
    };
    spec.validate()?;
    Ok(spec)
}

/// A gray level in `[0, 1]` as a sample of `max` (255 or 65535): clamped
/// and rounded like `vicurve::io::save_image`, so that the array equals
/// the file `vicurve synth` writes.
pub fn quantised_sample(v: f64, max: f64) -> u32 {
    let level = if v.is_nan() {
        0.0
    } else {
        v.clamp(0.0, 1.0) * max
    };
    level.round() as u32
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn names_of_the_command_line_are_accepted() {
        // The words Python documents, read by the library's parsers.
        use vicurve::fit::Polarity;
        use vicurve::interp::Interpolation;
        assert_eq!("Contour".parse::<Kind>().ok(), Some(Kind::Contour));
        assert!("edge".parse::<Kind>().is_err());
        let polarity = |s: &str| s.parse::<Polarity>().ok();
        assert_eq!(polarity("dark-inside"), Some(Polarity::Negative));
        assert_eq!(polarity("bright_line"), Some(Polarity::Positive));
        assert_eq!(polarity("auto"), Some(Polarity::Auto));
        assert_eq!(polarity("Positive"), Some(Polarity::Positive));
        assert!(polarity("bright").is_none());
        let interpolation = |s: &str| s.parse::<Interpolation>().ok();
        assert_eq!(interpolation("cubic"), Some(Interpolation::CubicBSpline));
        assert_eq!(
            interpolation("cubic_b_spline"),
            Some(Interpolation::CubicBSpline)
        );
        assert_eq!(interpolation("linear"), Some(Interpolation::Bilinear));
        assert_eq!(interpolation("bilinear"), Some(Interpolation::Bilinear));
        assert_eq!(interpolation("keys"), Some(Interpolation::Keys));
        assert!(interpolation("nearest").is_none());
        for (text, message) in [
            ("edge".parse::<Kind>().map(|_| ()), "invalid kind"),
            ("bright".parse::<Polarity>().map(|_| ()), "invalid polarity"),
            (
                "quintic".parse::<Interpolation>().map(|_| ()),
                "invalid interpolation",
            ),
        ] {
            let e = text.unwrap_err().to_string();
            assert!(e.starts_with(message), "{e}");
        }
    }

    #[test]
    fn stages_take_counts_lengths_and_auto() {
        assert_eq!(
            stage(0, 10.0, &ElementsArg::Count(25)),
            Ok(Stage {
                half_width: 10.0,
                elements: Elements::Count(25)
            })
        );
        assert_eq!(
            stage(1, 2.0, &ElementsArg::Text("40px".into()))
                .unwrap()
                .elements,
            Elements::Length(40.0)
        );
        assert!(matches!(
            stage(1, 2.0, &ElementsArg::Text("auto".into()))
                .unwrap()
                .elements,
            Elements::Auto { .. }
        ));
        let negative = stage(3, 10.0, &ElementsArg::Count(-2)).unwrap_err();
        assert!(negative.contains("stage 3"), "{negative}");
        assert!(stage(0, 10.0, &ElementsArg::Text("many".into())).is_err());
        assert!(stage(0, 10.0, &ElementsArg::Text("5,6".into())).is_err());
    }

    #[test]
    fn synth_defaults_are_the_command_line_ones() {
        let spec = synth_spec(&SynthArgs::new(ShapeName::Disc)).unwrap();
        assert_eq!((spec.width, spec.height), (512, 512));
        assert_eq!(
            spec.shape,
            Shape::Circle {
                cx: 511.0 / 2.0 + 0.3,
                cy: 511.0 / 2.0 - 0.2,
                r: 0.3 * 512.0
            }
        );
        assert_eq!((spec.background, spec.foreground), (0.2, 0.8));
        assert_eq!(spec.bits, Some(8));
        assert_eq!(spec.seed, 1);
        let ring = synth_spec(&SynthArgs::new(ShapeName::Ring)).unwrap();
        assert_eq!((ring.kind, ring.line_width), (Kind::Contour, 3.0));
        let paper = synth_spec(&SynthArgs::new(ShapeName::PaperDisc)).unwrap();
        assert_eq!(paper, {
            let mut p = presets::paper_disc(10.0);
            p.seed = 1;
            p
        });
        let mut bad = SynthArgs::new(ShapeName::Disc);
        bad.bits = Some(12);
        assert!(synth_spec(&bad).is_err());
        bad.bits = None;
        bad.size = (0, 10);
        assert!(synth_spec(&bad).is_err());
    }

    #[test]
    fn the_benchmark_star_is_the_rust_preset() {
        // crates/vicurve-py/bench/bench_measure.py draws it with these.
        let mut a = SynthArgs::new(ShapeName::Star);
        a.size = (1024, 1024);
        a.center = Some((512.3, 511.6));
        a.radius = Some(300.0);
        a.amplitude = Some(0.2);
        a.lobes = 5;
        a.blur = 1.0;
        a.noise = 0.01;
        a.seed = 3;
        assert_eq!(synth_spec(&a).unwrap(), presets::star_1024());
    }

    #[test]
    fn quantisation_matches_the_file_writer() {
        assert_eq!(quantised_sample(0.5, 255.0), 128);
        assert_eq!(quantised_sample(-1.0, 255.0), 0);
        assert_eq!(quantised_sample(2.0, 65535.0), 65535);
        assert_eq!(quantised_sample(f64::NAN, 255.0), 0);
        for k in 0..=255u32 {
            assert_eq!(quantised_sample(k as f64 / 255.0, 255.0), k);
        }
    }
}
