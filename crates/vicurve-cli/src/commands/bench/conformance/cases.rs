//! The cases of the conformance sweep: which images (shape, blur, noise,
//! depth, polarity) and which starts, with stable readable ids.
//!
//! Every geometric detail that is not a named parameter of the sweep (the
//! centre's sub-pixel offset, an ellipse's or polygon's orientation, a
//! star's or sine's phase, the side of an offset start, the noise seed)
//! comes from a generator seeded by the image id or the case id, never
//! chosen per case.

use vicurve::render::{Kind, Method, RenderSpec, Shading};
use vicurve::tone::Tone;
use vicurve::truth::Shape;

/// Side of the sweep's images, px.
pub const SIZE: usize = 512;

/// Blurs of the sweep (Gaussian sigma, px).
pub const BLURS: [f64; 4] = [0.0, 1.0, 2.0, 4.0];

/// Noise levels of the sweep (standard deviation, fraction of the contrast).
pub const NOISES: [f64; 4] = [0.0, 0.01, 0.02, 0.05];

/// Width of the thin lines (contours), px.
pub const LINE_WIDTH: f64 = 2.5;

/// The tone curves of the encoded images (JPEG files, renderers' sRGB
/// output): the light of the other images, encoded before the noise.
pub const TONES: [Tone; 2] = [Tone::Srgb, Tone::Gamma(2.2)];

/// The blurs along x and along y of the astigmatic images, px (a lens
/// blurring one axis more than the other).
pub const ASTIGMATIC: (f64, f64) = (1.0, 2.5);

/// The uneven light of the shaded images: a gradient across the field,
/// and vignetting with a weaker gradient (a lamp beside the specimen; a
/// backlight or lens darker towards the corners).
pub const SHADINGS: [Shading; 2] = [
    Shading {
        gradient: [0.12, -0.06],
        vignetting: 0.0,
    },
    Shading {
        gradient: [0.04, 0.03],
        vignetting: 0.3,
    },
];

/// The paper's three stages, used by half the far-start stars.
pub const PAPER_STAGES: &str = "20:25,10:50,5:100";

/// Which cases to run.
#[derive(Clone, Copy, Debug, PartialEq, Eq, clap::ValueEnum)]
pub enum Set {
    /// Every shape and start on a rotation of the image conditions (~60
    /// cases, a minute or two): what CI asserts.
    Ci,
    /// Every shape x start x blur x noise x depth x polarity, and every
    /// far-start star (minutes).
    Full,
}

/// The sweep's shapes.
#[derive(Clone, Copy, Debug, PartialEq)]
pub enum ShapeName {
    /// Disc of radius 150 px.
    Disc,
    /// Ellipse of semi-axes 180 and 110 px.
    Ellipse,
    /// Six-lobed star, mean radius 140 px, amplitude 0.1 (smallest radius
    /// of curvature 36 px, at the lobes).
    StarMild,
    /// Six-lobed star, mean radius 140 px, amplitude 0.2 (radius of
    /// curvature 24 px at the lobes, 14 px in the bays).
    StarSharp,
    /// Pentagon of circumradius 160 px, measured as a smooth curve.
    Polygon,
    /// The same pentagon measured with breaks at its corners.
    PolygonBreaks,
    /// Edge `y = y0 + 12 sin(2π x / 300 + φ)` crossing the whole image.
    SineEdge,
    /// Thin ring of radius 150 px (a contour).
    RingLine,
    /// Thin line along the sine of `SineEdge` (a contour).
    SineLine,
    /// The far-start star of the paper's showcase: 1704x2272, mean radius
    /// 600 px, blur 1.5 px, noise 1 %.
    FarStar {
        /// Number of lobes.
        lobes: u32,
        /// Relative amplitude.
        amplitude: f64,
    },
}

impl ShapeName {
    /// The 512x512 shapes, in report order.
    pub const SWEEP: [ShapeName; 9] = [
        ShapeName::Disc,
        ShapeName::Ellipse,
        ShapeName::StarMild,
        ShapeName::StarSharp,
        ShapeName::Polygon,
        ShapeName::PolygonBreaks,
        ShapeName::SineEdge,
        ShapeName::RingLine,
        ShapeName::SineLine,
    ];

    /// Name in ids and tables.
    pub fn name(&self) -> String {
        match self {
            ShapeName::Disc => "disc".into(),
            ShapeName::Ellipse => "ellipse".into(),
            ShapeName::StarMild => "star-a0.1".into(),
            ShapeName::StarSharp => "star-a0.2".into(),
            ShapeName::Polygon => "polygon".into(),
            ShapeName::PolygonBreaks => "polygon-breaks".into(),
            ShapeName::SineEdge => "sine-edge".into(),
            ShapeName::RingLine => "ring-line".into(),
            ShapeName::SineLine => "sine-line".into(),
            ShapeName::FarStar { lobes, amplitude } => {
                format!("far-star-l{lobes}-a{amplitude:.2}")
            }
        }
    }

    /// Edge (silhouette) or thin line (contour).
    pub fn kind(&self) -> Kind {
        match self {
            ShapeName::RingLine | ShapeName::SineLine => Kind::Contour,
            _ => Kind::Silhouette,
        }
    }

    /// The starts measured on this shape.
    pub fn starts(&self) -> &'static [Start] {
        use Start::*;
        match self {
            ShapeName::Disc | ShapeName::RingLine => &[Circle1_5, Circle10pct, Auto],
            ShapeName::Ellipse | ShapeName::Polygon | ShapeName::PolygonBreaks => {
                &[Polyline1_5, Circle10pct, Auto]
            }
            ShapeName::StarMild | ShapeName::StarSharp => {
                &[Polyline1_5, Circle10pct, Circle085, Auto]
            }
            ShapeName::SineEdge | ShapeName::SineLine => &[Polyline1_5, Segment, Auto],
            ShapeName::FarStar { .. } => &[Circle085],
        }
    }
}

/// How a case starts (what a user would give).
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Start {
    /// A circle of the true radius whose centre is 1.5 px off (circles).
    Circle1_5,
    /// A circle of the mean radius whose centre is 10 % of it off.
    Circle10pct,
    /// A polyline 1.5 px off the truth (to one side), vertices ~4 px apart;
    /// for open curves from border to border, its ends on the outermost
    /// pixel centres.
    Polyline1_5,
    /// The straight segment from border to border along the sine's mean
    /// line, 1.5 px off it (open curves).
    Segment,
    /// The automatic start (`measure` without `--init`; for lines, with
    /// `--pick` 1 px beside the line).
    Auto,
    /// A circle at the centre, 0.85 of the mean radius (stars).
    Circle085,
}

impl Start {
    /// Name in ids and tables.
    pub fn name(&self) -> &'static str {
        match self {
            Start::Circle1_5 => "circle-1.5px",
            Start::Circle10pct => "circle-10pct",
            Start::Polyline1_5 => "polyline-1.5px",
            Start::Segment => "segment",
            Start::Auto => "auto",
            Start::Circle085 => "circle-0.85r",
        }
    }
}

/// One image of the sweep.
#[derive(Clone, Debug)]
pub struct ImageCase {
    /// `shape/blurB/noiseN/Dbit/polarity`.
    pub id: String,
    /// The shape.
    pub shape: ShapeName,
    /// Bright object (or line) on a dark ground, or the reverse.
    pub bright: bool,
    /// Quantisation depth.
    pub bits: u8,
    /// Blur sigma, px.
    pub blur: f64,
    /// Noise, fraction of the contrast.
    pub noise: f64,
    /// The tone curve encoding the light (linear for most).
    pub tone: Tone,
    /// Astigmatic images: the blur along y, px (`blur` is along x).
    pub blur_y: Option<f64>,
    /// The light across the field (even for most).
    pub shading: Shading,
    /// The image to render (its shape is the truth).
    pub spec: RenderSpec,
}

/// One measurement: an image and a start.
#[derive(Clone, Debug)]
pub struct Case {
    /// `image id/start[/paper-stages]`, stable and readable.
    pub id: String,
    /// The image.
    pub image: ImageCase,
    /// The start.
    pub start: Start,
    /// Explicit stages (`R:N,...`), `None` for the default schedule.
    pub stages: Option<&'static str>,
}

/// FNV-1a hash of `text`: the seed of everything random about a case.
pub fn seed_of(text: &str) -> u64 {
    text.bytes().fold(0xcbf2_9ce4_8422_2325, |h, b| {
        (h ^ u64::from(b)).wrapping_mul(0x0100_0000_01b3)
    })
}

/// A small deterministic generator (splitmix64) of uniform numbers.
pub struct Rng(u64);

impl Rng {
    /// Seeded by `text` (see [`seed_of`]).
    pub fn new(text: &str) -> Rng {
        Rng(seed_of(text))
    }

    /// Uniform in `[lo, hi)`.
    pub fn uniform(&mut self, lo: f64, hi: f64) -> f64 {
        self.0 = self.0.wrapping_add(0x9e37_79b9_7f4a_7c15);
        let mut z = self.0;
        z = (z ^ (z >> 30)).wrapping_mul(0xbf58_476d_1ce4_e5b9);
        z = (z ^ (z >> 27)).wrapping_mul(0x94d0_49bb_1331_11eb);
        z ^= z >> 31;
        lo + (hi - lo) * ((z >> 11) as f64 / (1u64 << 53) as f64)
    }

    /// `+1` or `-1`.
    pub fn sign(&mut self) -> f64 {
        if self.uniform(0.0, 1.0) < 0.5 {
            -1.0
        } else {
            1.0
        }
    }
}

/// `blur1`, `blur1.5`: a number without a useless `.0`.
fn num(v: f64) -> String {
    format!("{v}")
}

/// The id of an image; an encoded one's ends in its tone curve.
fn image_id(shape: ShapeName, blur: f64, noise: f64, bits: u8, bright: bool, tone: Tone) -> String {
    let mut id = format!(
        "{}/blur{}/noise{}/{bits}bit/{}",
        shape.name(),
        num(blur),
        num((noise * 100.0 * 1e6).round() / 1e6),
        if bright { "bright" } else { "dark" }
    );
    if !tone.is_identity() {
        id.push_str(&format!("/{tone}"));
    }
    id
}

/// The true curve of `shape`, its centre moved off the grid by the
/// generator seeded with the image id.
fn true_shape(shape: ShapeName, rng: &mut Rng, width: usize, height: usize) -> Shape {
    let cx = (width as f64 - 1.0) / 2.0 + rng.uniform(-0.5, 0.5);
    let cy = (height as f64 - 1.0) / 2.0 + rng.uniform(-0.5, 0.5);
    let turn = rng.uniform(0.0, std::f64::consts::TAU);
    let star = |r0: f64, amplitude: f64, lobes: u32| Shape::Star {
        cx,
        cy,
        r0,
        amplitude,
        lobes,
        phase: turn,
    };
    match shape {
        ShapeName::Disc | ShapeName::RingLine => Shape::Circle { cx, cy, r: 150.0 },
        ShapeName::Ellipse => Shape::Ellipse {
            cx,
            cy,
            a: 180.0,
            b: 110.0,
            angle: turn,
        },
        ShapeName::StarMild => star(140.0, 0.1, 6),
        ShapeName::StarSharp => star(140.0, 0.2, 6),
        ShapeName::Polygon | ShapeName::PolygonBreaks => Shape::Polygon {
            cx,
            cy,
            r: 160.0,
            sides: 5,
            angle: turn,
        },
        ShapeName::SineEdge | ShapeName::SineLine => Shape::Sine {
            y0: cy,
            amplitude: 12.0,
            wavelength: 300.0,
            phase: turn,
            x_min: 0.0,
            x_max: width as f64 - 1.0,
        },
        ShapeName::FarStar { lobes, amplitude } => star(600.0, amplitude, lobes),
    }
}

/// The image of `shape` under the given conditions.
pub fn image_case(shape: ShapeName, blur: f64, noise: f64, bits: u8, bright: bool) -> ImageCase {
    encoded_case(shape, blur, noise, bits, bright, Tone::Linear)
}

/// [`image_case`] with its light encoded by `tone`.
pub fn encoded_case(
    shape: ShapeName,
    blur: f64,
    noise: f64,
    bits: u8,
    bright: bool,
    tone: Tone,
) -> ImageCase {
    let id = image_id(shape, blur, noise, bits, bright, tone);
    let (width, height) = match shape {
        ShapeName::FarStar { .. } => (1704, 2272),
        _ => (SIZE, SIZE),
    };
    let mut rng = Rng::new(&id);
    let truth = true_shape(shape, &mut rng, width, height);
    let (fg, bg) = if bright { (0.8, 0.2) } else { (0.2, 0.8) };
    let spec = RenderSpec {
        width,
        height,
        shape: truth,
        kind: shape.kind(),
        line_width: LINE_WIDTH,
        foreground: fg,
        background: bg,
        method: Method::Coverage,
        blur_sigma: blur,
        blur_sigma_y: None,
        noise,
        seed: seed_of(&id),
        bits: Some(bits),
        tone,
        shading: Shading::default(),
    };
    ImageCase {
        id,
        shape,
        bright,
        bits,
        blur,
        noise,
        tone,
        blur_y: None,
        shading: Shading::default(),
        spec,
    }
}

/// The image of `shape` through the astigmatic blur `(blur_x, blur_y)`
/// px (the shape of [`image_case`]'s image with `blur_x`; its id ends in
/// `astig` and the blur along y).
pub fn astigmatic_case(
    shape: ShapeName,
    (blur_x, blur_y): (f64, f64),
    noise: f64,
    bits: u8,
    bright: bool,
) -> ImageCase {
    let mut image = image_case(shape, blur_x, noise, bits, bright);
    image.id.push_str(&format!("/astig{}", num(blur_y)));
    image.blur_y = Some(blur_y);
    image.spec.blur_sigma_y = Some(blur_y);
    image.spec.seed = seed_of(&image.id);
    image
}

/// The image of `shape` under the uneven light `shading` (the shape of
/// [`image_case`]'s image; its id ends in `shaded` and the shading's
/// words).
pub fn shaded_case(
    shape: ShapeName,
    shading: Shading,
    (blur, noise, bits): (f64, f64, u8),
    bright: bool,
) -> ImageCase {
    let mut image = image_case(shape, blur, noise, bits, bright);
    image.id.push_str(&format!("/shaded{shading}"));
    image.shading = shading;
    image.spec.shading = shading;
    image.spec.seed = seed_of(&image.id);
    image
}

/// Every case of `set`, grouped by image (each image is rendered once).
pub fn cases(set: Set) -> Vec<Case> {
    let mut out = match set {
        Set::Full => full_sweep(),
        Set::Ci => ci_sweep(),
    };
    out.extend(far_stars(set));
    out
}

/// Every start of every shape on every image condition.
fn full_sweep() -> Vec<Case> {
    let mut out = Vec::new();
    for shape in ShapeName::SWEEP {
        for blur in BLURS {
            for noise in NOISES {
                for bits in [8, 16] {
                    for bright in [true, false] {
                        let image = image_case(shape, blur, noise, bits, bright);
                        out.extend(with_starts(&image, None));
                    }
                }
            }
        }
    }
    out.extend(encoded_sweep());
    out.extend(astigmatic_sweep());
    out.extend(shaded_sweep());
    out
}

/// Every shape under each of [`SHADINGS`], at the blurs of an ordinary
/// camera (1 and 2 px) and 1 % noise, 8 bits, both polarities, with every
/// start.
fn shaded_sweep() -> Vec<Case> {
    let mut out = Vec::new();
    for shape in ShapeName::SWEEP {
        for shading in SHADINGS {
            for blur in [1.0, 2.0] {
                for bright in [true, false] {
                    let image = shaded_case(shape, shading, (blur, 0.01, 8), bright);
                    out.extend(with_starts(&image, None));
                }
            }
        }
    }
    out
}

/// The silhouettes through the [`ASTIGMATIC`] blur, 1 % noise, 8 bits,
/// both polarities, with every start.
fn astigmatic_sweep() -> Vec<Case> {
    let mut out = Vec::new();
    for shape in ShapeName::SWEEP {
        if shape.kind() != Kind::Silhouette {
            continue;
        }
        for bright in [true, false] {
            let image = astigmatic_case(shape, ASTIGMATIC, 0.01, 8, bright);
            out.extend(with_starts(&image, None));
        }
    }
    out
}

/// The silhouettes' images encoded by each of [`TONES`], at the blurs of
/// an ordinary camera (1 and 2 px) and 1 % noise, 8 bits, both
/// polarities, with every start.
fn encoded_sweep() -> Vec<Case> {
    let mut out = Vec::new();
    for shape in ShapeName::SWEEP {
        if shape.kind() != Kind::Silhouette {
            continue;
        }
        for tone in TONES {
            for blur in [1.0, 2.0] {
                for bright in [true, false] {
                    let image = encoded_case(shape, blur, 0.01, 8, bright, tone);
                    out.extend(with_starts(&image, None));
                }
            }
        }
    }
    out
}

/// Each shape x start twice, on conditions taken in turn from a rotation
/// of blur x noise (stride 5 over the 16 pairs, so that any 16 consecutive
/// cases see every pair), depth (every fourth 16-bit) and polarity
/// (alternating).
fn ci_sweep() -> Vec<Case> {
    let mut out = Vec::new();
    let mut k = 0usize;
    for round in 0..2 {
        for shape in ShapeName::SWEEP {
            for &start in shape.starts() {
                let pair = (k * 5 + round) % 16;
                let (blur, noise) = (BLURS[pair / 4], NOISES[pair % 4]);
                let bits = if k % 4 == 3 { 16 } else { 8 };
                let image = image_case(shape, blur, noise, bits, k.is_multiple_of(2));
                out.push(case(&image, start, None));
                k += 1;
            }
        }
    }
    // An encoded edge of each kind: a closed one and one crossing the
    // image.
    for (shape, tone, blur, bright, start) in [
        (ShapeName::Disc, Tone::Srgb, 1.0, true, Start::Circle1_5),
        (
            ShapeName::SineEdge,
            Tone::Gamma(2.2),
            2.0,
            false,
            Start::Polyline1_5,
        ),
    ] {
        let image = encoded_case(shape, blur, 0.01, 8, bright, tone);
        out.push(case(&image, start, None));
    }
    // An astigmatic star.
    let image = astigmatic_case(ShapeName::StarSharp, ASTIGMATIC, 0.01, 8, true);
    out.push(case(&image, Start::Auto, None));
    // Uneven light: a gradient across an ellipse, vignetting along an
    // edge crossing the image.
    for (shape, shading, start) in [
        (ShapeName::Ellipse, SHADINGS[0], Start::Auto),
        (ShapeName::SineEdge, SHADINGS[1], Start::Polyline1_5),
    ] {
        let image = shaded_case(shape, shading, (1.0, 0.01, 8), false);
        out.push(case(&image, start, None));
    }
    out
}

/// The far-start stars of the paper's showcase: every lobe count and
/// amplitude with the paper's stages and the default schedule (full), or
/// one of them (CI: they are big).
fn far_stars(set: Set) -> Vec<Case> {
    let picks: Vec<(u32, f64, Option<&'static str>)> = match set {
        Set::Ci => vec![(5, 0.3, Some(PAPER_STAGES))],
        Set::Full => {
            let mut v = Vec::new();
            for lobes in [4, 5, 6] {
                for amplitude in [0.2, 0.25, 0.3] {
                    v.push((lobes, amplitude, Some(PAPER_STAGES)));
                    v.push((lobes, amplitude, None));
                }
            }
            v
        }
    };
    picks
        .into_iter()
        .map(|(lobes, amplitude, stages)| {
            let image = image_case(ShapeName::FarStar { lobes, amplitude }, 1.5, 0.01, 8, true);
            case(&image, Start::Circle085, stages)
        })
        .collect()
}

/// The cases of every start of the image's shape.
fn with_starts(image: &ImageCase, stages: Option<&'static str>) -> Vec<Case> {
    image
        .shape
        .starts()
        .iter()
        .map(|&s| case(image, s, stages))
        .collect()
}

/// The case of `start` on `image`, with explicit `stages` if any (its id
/// then ends in `/paper-stages`).
pub fn case(image: &ImageCase, start: Start, stages: Option<&'static str>) -> Case {
    let mut id = format!("{}/{}", image.id, start.name());
    if stages.is_some() {
        id.push_str("/paper-stages");
    }
    Case {
        id,
        image: image.clone(),
        start,
        stages,
    }
}

/// Centre of a closed shape (the sine has none: `(NaN, NaN)`).
pub fn centre(shape: &Shape) -> (f64, f64) {
    match *shape {
        Shape::Circle { cx, cy, .. }
        | Shape::Ellipse { cx, cy, .. }
        | Shape::Star { cx, cy, .. }
        | Shape::Polygon { cx, cy, .. } => (cx, cy),
        Shape::Sine { .. } => (f64::NAN, f64::NAN),
    }
}

/// Keep the cases whose id contains `filter`.
pub fn filtered(cases: Vec<Case>, filter: Option<&str>) -> Vec<Case> {
    match filter {
        Some(f) => cases.into_iter().filter(|c| c.id.contains(f)).collect(),
        None => cases,
    }
}
