//! The three cases of issue 19: the image each is measured on (rendered
//! by the library) and the `measure` options it is measured with.

use super::super::conformance::cases::{self as conf, ShapeName, Start, PAPER_STAGES};
use super::super::conformance::run::initial_curve;
use vicurve::curve::InitialCurve;
use vicurve::render::{presets, render, RenderSpec};
use vicurve::Image;

/// One timed case.
pub struct SpeedCase {
    /// Short name (file names, tables): `disc-512`, `star-1024`,
    /// `far-star-1704x2272`.
    pub name: &'static str,
    /// What it is, in words.
    pub what: String,
    /// The image (rendered, 8-bit levels).
    pub image: Image,
    /// `--init` value: `circle:CX,CY,R` (numbers in Rust's shortest
    /// round-trip form, so that the process and the in-process timing start
    /// from the same bits).
    pub init: String,
    /// `--stages` value, `None` for the default schedule.
    pub stages: Option<&'static str>,
}

impl SpeedCase {
    /// The start, parsed as `measure` parses `--init`.
    pub fn initial_curve(&self) -> Result<InitialCurve, String> {
        self.init.parse::<InitialCurve>().map_err(|e| e.to_string())
    }
}

/// `circle:CX,CY,R` of a circle start.
fn circle_text(c: &InitialCurve) -> Result<String, String> {
    match *c {
        InitialCurve::Circle { cx, cy, r } => Ok(format!("circle:{cx},{cy},{r}")),
        _ => Err("the speed cases start from circles".into()),
    }
}

fn rendered(spec: &RenderSpec) -> Result<Image, String> {
    render(spec).map_err(|e| format!("rendering: {e}"))
}

/// The three cases; `quick` makes them small (a smoke test of the
/// command: same shapes and starts, images of a few hundred pixels).
pub fn cases(quick: bool) -> Result<Vec<SpeedCase>, String> {
    if quick {
        return quick_cases();
    }
    // The conformance sweep's disc and start (same ids, same seeds).
    let disc = conf::image_case(ShapeName::Disc, 1.0, 0.0, 8, true);
    let disc_case = conf::case(&disc, Start::Circle1_5, None);
    let disc_image = rendered(&disc.spec)?;
    let disc_init = circle_text(&initial_curve(&disc_case, &disc_image)?)?;

    let star = presets::star_1024();
    let star_init = match star.shape {
        vicurve::truth::Shape::Star { cx, cy, r0, .. } => {
            circle_text(&InitialCurve::Circle { cx, cy, r: r0 })?
        }
        _ => return Err("star_1024 is not a star".into()),
    };

    let far = conf::image_case(
        ShapeName::FarStar {
            lobes: 6,
            amplitude: 0.2,
        },
        1.5,
        0.01,
        8,
        true,
    );
    let (fcx, fcy) = conf::centre(&far.spec.shape);
    let far_init = circle_text(&InitialCurve::Circle {
        cx: fcx,
        cy: fcy,
        r: 500.0,
    })?;

    Ok(vec![
        SpeedCase {
            name: "disc-512",
            what: format!(
                "512x512 8-bit disc r = 150, blur 1, noiseless (conformance image {}), \
                 from a circle 1.5 px off (its case {}), default schedule",
                disc.id, disc_case.id
            ),
            image: disc_image,
            init: disc_init,
            stages: None,
        },
        SpeedCase {
            name: "star-1024",
            what: "1024x1024 8-bit star r = 300 (1 + 0.2 cos 5 theta), blur 1, noise 1 % \
                   (render::presets::star_1024), from the circle of radius 300 at its \
                   centre, default schedule"
                .into(),
            image: rendered(&star)?,
            init: star_init,
            stages: None,
        },
        SpeedCase {
            name: "far-star-1704x2272",
            what: format!(
                "the paper's 1704x2272 8-bit star r = 600 (1 + 0.2 cos 6 theta), blur 1.5, \
                 noise 1 % (conformance image {}), from the circle of radius 500 at its \
                 centre, stages {PAPER_STAGES}",
                far.id
            ),
            image: rendered(&far.spec)?,
            init: far_init,
            stages: Some(PAPER_STAGES),
        },
    ])
}

/// The same three shapes at a quarter of the size or less.
fn quick_cases() -> Result<Vec<SpeedCase>, String> {
    use vicurve::truth::Shape;
    let base = |width, height, shape, blur, noise| RenderSpec {
        width,
        height,
        shape,
        blur_sigma: blur,
        noise,
        seed: 1,
        bits: Some(8),
        ..RenderSpec::default()
    };
    let star = |cx, cy, r0, lobes| Shape::Star {
        cx,
        cy,
        r0,
        amplitude: 0.2,
        lobes,
        phase: 0.0,
    };
    let disc = base(
        128,
        128,
        Shape::Circle {
            cx: 63.8,
            cy: 64.3,
            r: 40.0,
        },
        1.0,
        0.0,
    );
    let small = base(256, 256, star(128.3, 127.6, 75.0, 5), 1.0, 0.01);
    let far = base(426, 568, star(213.2, 283.7, 150.0, 6), 1.5, 0.01);
    Ok(vec![
        SpeedCase {
            name: "disc-512",
            what: "quick: 128x128 disc r = 40, from a circle 1.5 px off".into(),
            image: rendered(&disc)?,
            init: "circle:65.3,64.3,40".into(),
            stages: None,
        },
        SpeedCase {
            name: "star-1024",
            what: "quick: 256x256 star r = 75, from the circle of radius 75".into(),
            image: rendered(&small)?,
            init: "circle:128.3,127.6,75".into(),
            stages: None,
        },
        SpeedCase {
            name: "far-star-1704x2272",
            what: "quick: 426x568 star r = 150, from the circle of radius 125".into(),
            image: rendered(&far)?,
            init: "circle:213.2,283.7,125".into(),
            stages: Some("10:25,5:50,2.5:100"),
        },
    ])
}
