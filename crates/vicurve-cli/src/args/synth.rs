//! The options of `synth`, and the parsers of their values.

use crate::failure::Failure;
use std::path::PathBuf;

/// The shapes `synth` draws.
#[derive(Clone, Copy, Debug, PartialEq, Eq, clap::ValueEnum)]
pub enum ShapeName {
    /// A disc (silhouette).
    Disc,
    /// An ellipse (silhouette).
    Ellipse,
    /// A star r(θ) = R0 (1 + a cos kθ) (silhouette).
    Star,
    /// An open sinusoidal edge y = y0 + A sin(2πx/λ) across the image.
    SineEdge,
    /// A thin circular line (contour).
    Ring,
    /// A thin sinusoidal line across the image (contour).
    SineLine,
    /// The paper's test: 512x512 disc of radius 200, rendered with the
    /// silhouette profile of half-width 10 px at pixel centres, 8-bit
    /// (not a blurred step: measure it with `--no-blur-correction`).
    PaperDisc,
    /// A sequence: a bright bar (a tensile specimen) whose width narrows
    /// progressively at one section, `--frames` images in the folder
    /// `--out` with their truth (`truth.json`) and the job file that
    /// measures them (`job.toml`, for `vicurve run`). Defaults: 400x200,
    /// 8 frames, blur 1.5, noise 0.001, 16 bits.
    Necking,
    /// Many shapes in one image by exact coverage: 50 discs and ellipses
    /// (semi-axes 10 to 25 px) 8 px apart, 20 specks (radius 1 to 3 px), 5
    /// discs cut by the border; `--truth` lists each shape and its role.
    /// Defaults: 1024x768, blur 1, noise 0.01, 8 bits.
    Scene,
    /// A 10x10 grid of circles of diameter D = 2 x `--radius` (default 15
    /// px), their pitch the larger of 2 D and 1.3 D + 24 px (with
    /// `--size`, as far apart as the image allows, the grid centred; an
    /// error when they would come closer than 12 px),
    /// each deformed into an exact ellipse by a known smooth strain field;
    /// `--truth` gives every ellipse and its strains. Defaults: blur 1,
    /// noise 0.01, 8 bits.
    Grid,
    /// A printed square grid after forming: 8x8 bright square cells
    /// between dark lines `--line` px wide (default 10), the pitch as large
    /// as `--size` allows (default 640x640), every point moved by a known
    /// smooth deformation; `--truth` gives each cell's index, exact
    /// centroid, deformation gradient and strains (`vicurve grid --pitch`
    /// measures it). Defaults: blur 1, noise 0.01, 8 bits.
    SquareGrid,
}

/// Gray levels BACKGROUND,FOREGROUND when not given.
pub const DEFAULT_LEVELS: &str = "0.2,0.8";

/// Render a synthetic image and its truth file.
#[derive(clap::Args)]
pub struct Args {
    /// What to draw.
    pub shape: ShapeName,
    /// Output image (.png or .tif); for `necking`, the output folder.
    #[arg(long)]
    pub out: PathBuf,
    /// Output truth file (JSON): the exact curve and how the image was made.
    #[arg(long)]
    pub truth: Option<PathBuf>,
    /// Image size WIDTHxHEIGHT, pixels (default 512x512; necking 400x200).
    #[arg(long)]
    pub size: Option<String>,
    /// Centre X,Y of closed shapes, pixels (default: the image centre, moved
    /// off the pixel grid by (0.3, -0.2)).
    #[arg(long)]
    pub center: Option<String>,
    /// Radius (disc, ring) or mean radius (star), pixels (default: 30 % of
    /// the smaller side).
    #[arg(long)]
    pub radius: Option<f64>,
    /// Ellipse semi-axes A,B, pixels (default: 35 % and 20 % of the smaller side).
    #[arg(long)]
    pub axes: Option<String>,
    /// Rotation of the ellipse's first axis, degrees counterclockwise on screen.
    #[arg(long, default_value_t = 20.0)]
    pub angle: f64,
    /// Star: relative amplitude a; sine: amplitude in pixels (defaults 0.2
    /// and 10 % of the height).
    #[arg(long)]
    pub amplitude: Option<f64>,
    /// Star: number of lobes k.
    #[arg(long, default_value_t = 5)]
    pub lobes: u32,
    /// Phase, degrees (star and sine).
    #[arg(long, default_value_t = 0.0)]
    pub phase: f64,
    /// Sine: wavelength, pixels (default: half the width).
    #[arg(long)]
    pub wavelength: Option<f64>,
    /// Sine: mean ordinate y0, pixels (default: the middle row + 0.3).
    #[arg(long)]
    pub y0: Option<f64>,
    /// Draw a thin line of this full width along the curve (contour) instead
    /// of an edge; `ring` and `sine-line` imply it (default width 3 px).
    #[arg(long)]
    pub line: Option<f64>,
    /// Render with the virtual image's own profile of this half-width at
    /// pixel centres (the paper's method) instead of exact pixel coverage.
    #[arg(long)]
    pub profile: Option<f64>,
    /// Gaussian blur, standard deviation in pixels (default 0; necking 1.5).
    #[arg(long)]
    pub blur: Option<f64>,
    /// The blur along the columns (y) when it differs from `--blur`, which
    /// is then the blur along the rows (x): an astigmatic lens. Exact
    /// coverage only (not with `--profile`).
    #[arg(long, value_name = "SIGMA")]
    pub blur_y: Option<f64>,
    /// Additive Gaussian noise, standard deviation as a fraction of the
    /// contrast (0.01 = 1 %; default 0, necking 0.001).
    #[arg(long)]
    pub noise: Option<f64>,
    /// Seed of the noise.
    #[arg(long, default_value_t = 1)]
    pub seed: u64,
    /// Bits per pixel of the saved image: 8 or 16 (default 8; necking 16).
    #[arg(long)]
    pub bits: Option<u8>,
    /// Tone curve that encodes the light in the saved gray levels, as a
    /// camera writing JPEG files does: `linear` (the default), `srgb`, or a
    /// gamma such as `2.2`; the levels are light, the noise is added after
    /// the encoding.
    #[arg(long, default_value = "linear", value_name = "CURVE")]
    pub tone: String,
    /// Uneven light, multiplying the levels before the tone curve:
    /// `GX,GY` a gradient (the light changes by GX, a fraction, from the
    /// first column to the last, by GY down the rows), `GX,GY,V` and
    /// vignetting (corners darker by V); `even` (the default).
    #[arg(long, default_value = "even", value_name = "GX,GY[,V]")]
    pub shading: String,
    /// Necking: number of frames.
    #[arg(long, default_value_t = 8)]
    pub frames: usize,
    /// Gray levels BACKGROUND,FOREGROUND in [0, 1] (foreground: inside
    /// closed shapes, above a sine edge, the line of a contour).
    #[arg(long, default_value = DEFAULT_LEVELS)]
    pub levels: String,
}

/// `COUNT` finite numbers separated by `sep`, the value of `--WHAT`.
pub fn numbers(what: &str, text: &str, sep: char, count: usize) -> Result<Vec<f64>, Failure> {
    let v: Result<Vec<f64>, _> = text.split(sep).map(|t| t.trim().parse::<f64>()).collect();
    match v {
        Ok(v) if v.len() == count && v.iter().all(|x| x.is_finite()) => Ok(v),
        _ => Err(Failure::Error(format!(
            "--{what} '{text}': expected {count} numbers separated by '{sep}'"
        ))),
    }
}

/// `8` or `16`.
pub fn check_bits(bits: u8) -> Result<u8, Failure> {
    if bits != 8 && bits != 16 {
        return Err(Failure::Error(format!("--bits {bits} (expected 8 or 16)")));
    }
    Ok(bits)
}

/// `WIDTHxHEIGHT` in whole pixels.
pub fn parse_size(text: &str) -> Result<(f64, f64), Failure> {
    let size = numbers("size", text, 'x', 2)?;
    if size.iter().any(|v| *v < 1.0 || v.fract() != 0.0) {
        return Err(Failure::Error(format!(
            "--size '{text}': expected WIDTHxHEIGHT in whole pixels"
        )));
    }
    Ok((size[0], size[1]))
}
