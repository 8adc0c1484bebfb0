//! Synthetic scenes of many objects by exact coverage, with their truth:
//! a random scene of discs and ellipses (some specks, some cut by the
//! border, optionally a touching pair) and a circle grid deformed by a
//! known smooth strain field.
//!
//! Every shape is painted by the exact coverage of its dense polygon
//! ([`super::shapes`]); the shapes do not overlap (a hole lies wholly
//! inside its object, drawn the other way round), so the image is exact
//! everywhere; blurred before the pixels integrate, then noise and
//! quantisation, as [`super::render`].

use super::{blur, noise, shapes, Method, RenderSpec, Shading};
use crate::error::{Error, Result};
use crate::image::Image;
use crate::tone::Tone;
use crate::truth::{Kind, Shape};
use noise::Rng;
use serde::{Deserialize, Serialize};

/// What a shape of a scene is, for scoring a multi-object measurement.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Serialize, Deserialize)]
#[serde(rename_all = "snake_case")]
pub enum Role {
    /// A whole object: to be found and measured.
    Object,
    /// A speck (under the default least area): never to be reported.
    Speck,
    /// Cut by the image border: skipped unless asked.
    Border,
    /// One of a pair that touch: to be reported as failed.
    Touching,
    /// A hole inside an object (the background's level inside its shape):
    /// an object of the opposite polarity with `--holes`.
    Hole,
}

/// One shape of a scene.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub struct SceneItem {
    /// The exact shape, px.
    pub shape: Shape,
    /// Its role.
    pub role: Role,
    /// For grid circles: the exact major and minor true strains and the
    /// major axis direction `[eps1, eps2, angle]` (rad).
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub strain: Option<[f64; 3]>,
}

/// How a many-shape image is rendered after the exact coverage: its two
/// levels, blur, noise and quantisation. [`Rendering::standard`] is the
/// scenes' default.
#[derive(Clone, Copy, Debug, PartialEq, Serialize, Deserialize)]
pub struct Rendering {
    /// Gray level inside the shapes, in `[0, 1]`.
    pub foreground: f64,
    /// Gray level elsewhere, in `[0, 1]`.
    pub background: f64,
    /// Gaussian blur, px (along the rows when `blur_sigma_y` is given).
    pub blur_sigma: f64,
    /// The blur along the columns, px, when it differs (see
    /// [`super::RenderSpec::blur_sigma_y`]).
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub blur_sigma_y: Option<f64>,
    /// Noise as a fraction of the contrast.
    pub noise: f64,
    /// Seed of the noise.
    pub seed: u64,
    /// Quantisation, 8 or 16 bits, or none.
    pub bits: Option<u8>,
    /// The tone curve that encodes the light (see
    /// [`super::RenderSpec::tone`]); linear when absent.
    #[serde(default = "Tone::linear")]
    pub tone: Tone,
    /// Uneven light (see [`super::RenderSpec::shading`]); even when
    /// absent.
    #[serde(default, skip_serializing_if = "Shading::is_even")]
    pub shading: Shading,
}

impl Rendering {
    /// 0.8 on 0.2, blur 1 px, noise 1 % of the contrast (from `seed`),
    /// 8 bits.
    pub fn standard(seed: u64) -> Rendering {
        Rendering {
            foreground: 0.8,
            background: 0.2,
            blur_sigma: 1.0,
            blur_sigma_y: None,
            noise: 0.01,
            seed,
            bits: Some(8),
            tone: Tone::Linear,
            shading: Shading::default(),
        }
    }

    /// The levels, blur, noise and depth of `spec`.
    pub fn of(spec: &super::RenderSpec) -> Rendering {
        Rendering {
            foreground: spec.foreground,
            background: spec.background,
            blur_sigma: spec.blur_sigma,
            blur_sigma_y: spec.blur_sigma_y,
            noise: spec.noise,
            seed: spec.seed,
            bits: spec.bits,
            tone: spec.tone,
            shading: spec.shading,
        }
    }
}

/// A scene: its shapes and how it is rendered. It is its own truth file
/// (the rendering's fields at the top level).
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub struct Scene {
    /// Image width, px.
    pub width: usize,
    /// Image height, px.
    pub height: usize,
    /// The shapes.
    pub items: Vec<SceneItem>,
    /// Levels, blur, noise, quantisation.
    #[serde(flatten)]
    pub rendering: Rendering,
    /// Printed circles' diameter of a grid scene, px.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub d0: Option<f64>,
}

/// Render `scene` (module docs). Errors: those of [`RenderSpec::validate`]
/// for any shape or setting.
pub fn render_scene(scene: &Scene) -> Result<Image> {
    let mut rings = Vec::new();
    for item in &scene.items {
        let spec = RenderSpec {
            width: scene.width,
            height: scene.height,
            shape: item.shape.clone(),
            kind: Kind::Silhouette,
            foreground: scene.rendering.foreground,
            background: scene.rendering.background,
            method: Method::Coverage,
            blur_sigma: scene.rendering.blur_sigma,
            blur_sigma_y: scene.rendering.blur_sigma_y,
            noise: scene.rendering.noise,
            seed: scene.rendering.seed,
            bits: scene.rendering.bits,
            shading: scene.rendering.shading,
            ..RenderSpec::default()
        };
        spec.validate()?;
        let mut these = shapes::region_rings(&spec)?;
        if item.role == Role::Hole {
            // Drawn the other way round: the coverage subtracts it.
            these.iter_mut().for_each(|r| r.reverse());
        }
        rings.extend(these);
    }
    paint(&rings, (scene.width, scene.height), &scene.rendering)
}

/// The `width x height` image of the region bounded by `rings` rendered
/// by `r` (the blur before the pixels integrate:
/// [`blur::blurred_coverage`]). Errors: those of that function.
pub(super) fn paint(
    rings: &[Vec<[f64; 2]>],
    (width, height): (usize, usize),
    r: &Rendering,
) -> Result<Image> {
    let (fg, bg) = (r.foreground, r.background);
    let sigmas = (r.blur_sigma, r.blur_sigma_y.unwrap_or(r.blur_sigma));
    let mut cov = blur::blurred_coverage_xy(width, height, rings, sigmas)?;
    cov.iter_mut().for_each(|c| *c = bg + (fg - bg) * *c);
    Ok(finish(Image::new(width, height, cov)?, r))
}

/// `image` (light, its blur already in it) with the shading, tone, noise
/// and quantisation of `r`. The noise is a fraction of the contrast of
/// the levels as encoded, whatever the shading.
pub(super) fn finish(mut image: Image, r: &Rendering) -> Image {
    let size = (image.width(), image.height());
    r.shading.apply(image.data_mut(), size);
    let mut contrast = (r.foreground - r.background).abs();
    if !r.tone.is_identity() {
        for v in image.data_mut() {
            *v = r.tone.from_linear(*v);
        }
        contrast = (r.tone.from_linear(r.foreground) - r.tone.from_linear(r.background)).abs();
    }
    noise::add_gaussian_noise(image.data_mut(), r.noise * contrast, r.seed);
    if let Some(bits) = r.bits {
        noise::quantise(image.data_mut(), bits);
    }
    image
}

/// Draws a shape: the shape, its centre, its reach (px) and the margin it
/// keeps from the border.
type Maker<'a> = dyn Fn(&mut Rng) -> (Shape, [f64; 2], f64, f64) + 'a;

/// A random scene: `objects` discs and ellipses (semi-axes 10 to 25 px,
/// random orientation) at least `gap` px apart and from the border,
/// `specks` discs of radius 1 to 3 px, `border` discs cut by the border,
/// and, when `touching`, one pair of discs 0.5 px apart. Placed by
/// rejection from `seed` (the same seed gives the same scene).
///
/// Errors: [`Error::InvalidParameter`] when the shapes do not fit in the
/// image (after many tries).
#[allow(clippy::too_many_arguments)]
pub fn random_scene(
    width: usize,
    height: usize,
    objects: usize,
    specks: usize,
    border: usize,
    touching: bool,
    gap: f64,
    seed: u64,
) -> Result<Scene> {
    let mut rng = Rng::new(seed ^ 0x5ce9e);
    let (w, h) = (width as f64, height as f64);
    let mut items: Vec<SceneItem> = Vec::new();
    // Placed shapes as (centre, reach) for the spacing test.
    let mut placed: Vec<([f64; 2], f64)> = Vec::new();
    if touching {
        // Two discs of radius 16, 0.5 px apart, near the centre.
        let (cx, cy) = (0.5 * w - 16.25 + 0.37, 0.5 * h + 0.21);
        for dx in [0.0, 32.5] {
            items.push(SceneItem {
                shape: Shape::Circle {
                    cx: cx + dx,
                    cy,
                    r: 16.0,
                },
                role: Role::Touching,
                strain: None,
            });
        }
        placed.push(([cx + 16.25, cy], 33.0));
    }
    let mut tries = 0usize;
    let mut place =
        |items: &mut Vec<SceneItem>, rng: &mut Rng, role: Role, make: &Maker<'_>| -> Result<()> {
            loop {
                tries += 1;
                if tries > 200_000 {
                    return Err(Error::invalid(
                        "scene",
                        "the shapes do not fit in the image: fewer objects or a larger image",
                    ));
                }
                let (shape, c, reach, margin) = make(rng);
                let inside = c[0] - reach >= margin
                    && c[1] - reach >= margin
                    && c[0] + reach <= w - 1.0 - margin
                    && c[1] + reach <= h - 1.0 - margin;
                let clear = placed
                    .iter()
                    .all(|(p, r)| (p[0] - c[0]).hypot(p[1] - c[1]) >= r + reach + gap);
                if (inside || role == Role::Border) && clear {
                    placed.push((c, reach));
                    items.push(SceneItem {
                        shape,
                        role,
                        strain: None,
                    });
                    return Ok(());
                }
            }
        };
    for _ in 0..border {
        place(&mut items, &mut rng, Role::Border, &|rng| {
            let r = 12.0 + 10.0 * rng.uniform();
            let t = rng.uniform();
            let side = (rng.uniform() * 4.0) as usize;
            let c = match side {
                0 => [t * w, 0.3 * r],
                1 => [t * w, h - 1.0 - 0.3 * r],
                2 => [0.3 * r, t * h],
                _ => [w - 1.0 - 0.3 * r, t * h],
            };
            (
                Shape::Circle {
                    cx: c[0],
                    cy: c[1],
                    r,
                },
                c,
                r,
                0.0,
            )
        })?;
    }
    for _ in 0..objects {
        place(&mut items, &mut rng, Role::Object, &|rng| {
            let a = 10.0 + 15.0 * rng.uniform();
            let b = a * (0.6 + 0.4 * rng.uniform());
            let c = [w * rng.uniform(), h * rng.uniform()];
            let shape = if rng.uniform() < 0.5 {
                Shape::Circle {
                    cx: c[0],
                    cy: c[1],
                    r: a,
                }
            } else {
                Shape::Ellipse {
                    cx: c[0],
                    cy: c[1],
                    a,
                    b,
                    angle: std::f64::consts::PI * (rng.uniform() - 0.5),
                }
            };
            (shape, c, a, gap)
        })?;
    }
    for _ in 0..specks {
        place(&mut items, &mut rng, Role::Speck, &|rng| {
            let r = 1.0 + 2.0 * rng.uniform();
            let c = [w * rng.uniform(), h * rng.uniform()];
            (
                Shape::Circle {
                    cx: c[0],
                    cy: c[1],
                    r,
                },
                c,
                r,
                gap,
            )
        })?;
    }
    Ok(scene_of(width, height, items, seed, None))
}

/// A scene of `items` with the [`Rendering::standard`] rendering.
fn scene_of(
    width: usize,
    height: usize,
    items: Vec<SceneItem>,
    seed: u64,
    d0: Option<f64>,
) -> Scene {
    Scene {
        width,
        height,
        items,
        rendering: Rendering::standard(seed),
        d0,
    }
}

/// Largest principal stretch of [`strained_grid`]'s field.
const MAX_STRETCH: f64 = 1.3;
/// Least gap (px) between two circles of a grid: more than twice the
/// default schedule's last bands, so that each is measured alone.
const GRID_MIN_GAP: f64 = 12.0;

/// A `rows x cols` grid of circles of diameter `d0` px, `pitch` px apart
/// before deformation, each deformed by the local deformation gradient of
/// a smooth field (so each becomes an exact ellipse): at the node's
/// position `(u, v)` in `[0, 1]^2` across the grid, principal stretches
/// `1 + 0.3 u` and `0.85 + 0.1 v`, major axis at `0.3 + 0.5 (u - v)` rad.
/// The exact strains are in each item's `strain`. The grid is centred in
/// an image `pitch` px wider than it on each side.
pub fn strained_grid(rows: usize, cols: usize, d0: f64, pitch: f64, seed: u64) -> Scene {
    let width = ((cols as f64 + 1.0) * pitch).ceil() as usize;
    let height = ((rows as f64 + 1.0) * pitch).ceil() as usize;
    let layout = GridLayout {
        rows,
        cols,
        d0,
        pitch,
        origin: [0.0, 0.0],
        strained: true,
    };
    grid_scene(width, height, &layout, seed)
}

/// A `rows x cols` grid of circles of diameter `d0` px in a `width x
/// height` image: the largest pitch that leaves a pitch of margin on each
/// side, the grid centred; deformed as in [`strained_grid`] when
/// `strained`, else circles (strains 0).
///
/// Errors: [`Error::InvalidParameter`] when the circles would come closer
/// than `GRID_MIN_GAP` px (12) to each other: a larger image or smaller
/// circles.
pub fn circle_grid(
    width: usize,
    height: usize,
    rows: usize,
    cols: usize,
    d0: f64,
    strained: bool,
    seed: u64,
) -> Result<Scene> {
    let pitch = (width as f64 / (cols as f64 + 1.0)).min(height as f64 / (rows as f64 + 1.0));
    let reach = d0 * if strained { MAX_STRETCH } else { 1.0 };
    if !(d0 > 0.0 && rows > 0 && cols > 0) || pitch - reach < GRID_MIN_GAP {
        return Err(Error::invalid(
            "size",
            format!(
                "a {rows}x{cols} grid of circles of diameter {d0} px in {width}x{height} px puts them {pitch:.1} px apart; at least {:.1} needed (a larger image or smaller circles)",
                reach + GRID_MIN_GAP
            ),
        ));
    }
    let origin = [
        0.5 * (width as f64 - (cols as f64 + 1.0) * pitch),
        0.5 * (height as f64 - (rows as f64 + 1.0) * pitch),
    ];
    let layout = GridLayout {
        rows,
        cols,
        d0,
        pitch,
        origin,
        strained,
    };
    Ok(grid_scene(width, height, &layout, seed))
}

/// Where a grid's circles are: node `(i, j)` at `origin + ((j + 1) pitch,
/// (i + 1) pitch)`, moved off the pixel grid by up to half a pixel.
struct GridLayout {
    rows: usize,
    cols: usize,
    d0: f64,
    pitch: f64,
    origin: [f64; 2],
    strained: bool,
}

/// The scene of `layout` in a `width x height` image (blur 1, noise 1 %,
/// 8 bits).
fn grid_scene(width: usize, height: usize, g: &GridLayout, seed: u64) -> Scene {
    let mut rng = Rng::new(seed ^ 0x671d);
    let mut items = Vec::new();
    for i in 0..g.rows {
        for j in 0..g.cols {
            let u = j as f64 / (g.cols.max(2) - 1) as f64;
            let v = i as f64 / (g.rows.max(2) - 1) as f64;
            let (l1, l2, angle) = if g.strained {
                (1.0 + 0.3 * u, 0.85 + 0.1 * v, 0.3 + 0.5 * (u - v))
            } else {
                (1.0, 1.0, 0.0)
            };
            // Off-grid centres: sub-pixel positions vary from circle to circle.
            let jitter = |rng: &mut Rng| rng.uniform() - 0.5;
            let cx = g.origin[0] + (j as f64 + 1.0) * g.pitch + jitter(&mut rng);
            let cy = g.origin[1] + (i as f64 + 1.0) * g.pitch + jitter(&mut rng);
            let shape = if g.strained {
                Shape::Ellipse {
                    cx,
                    cy,
                    a: 0.5 * g.d0 * l1,
                    b: 0.5 * g.d0 * l2,
                    angle,
                }
            } else {
                Shape::Circle {
                    cx,
                    cy,
                    r: 0.5 * g.d0,
                }
            };
            items.push(SceneItem {
                shape,
                role: Role::Object,
                strain: Some([l1.ln(), l2.ln(), angle]),
            });
        }
    }
    scene_of(width, height, items, seed, Some(g.d0))
}
