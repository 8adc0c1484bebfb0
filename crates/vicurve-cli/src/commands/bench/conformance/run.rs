//! Running one case: its start built as a user's would be, the fit
//! configured as `measure` configures it, the measurement timed.

use super::cases::{centre, Case, Rng, ShapeName, Start};
use std::panic::{catch_unwind, AssertUnwindSafe};
use std::time::Instant;
use vicurve::curve::InitialCurve;
use vicurve::fit::{measure, parse_stages, FitConfig, Measurement};
use vicurve::render::Kind;
use vicurve::start::StartConfig;
use vicurve::truth::Shape;
use vicurve::Image;

/// What running a case gave.
pub enum Ran {
    /// The fit returned (whatever its outcome), in `seconds` (start search
    /// included for the automatic start).
    Measured {
        /// The measurement.
        m: Box<Measurement>,
        /// Wall-clock seconds.
        seconds: f64,
    },
    /// The fit, or building its start, refused or panicked: the message.
    Failed {
        /// Why.
        message: String,
        /// Wall-clock seconds until then.
        seconds: f64,
    },
}

/// Run `case` on its rendered `image`; a panic is caught and reported as a
/// failure of this case only.
pub fn run_case(case: &Case, image: &Image) -> Ran {
    let started = Instant::now();
    let result = catch_unwind(AssertUnwindSafe(|| fit(case, image)));
    let seconds = started.elapsed().as_secs_f64();
    match result {
        Ok(Ok(m)) => Ran::Measured {
            m: Box::new(m),
            seconds,
        },
        Ok(Err(message)) => Ran::Failed { message, seconds },
        Err(panic) => Ran::Failed {
            message: format!("panic: {}", panic_text(&panic)),
            seconds,
        },
    }
}

fn panic_text(panic: &Box<dyn std::any::Any + Send>) -> String {
    if let Some(s) = panic.downcast_ref::<&str>() {
        (*s).to_string()
    } else if let Some(s) = panic.downcast_ref::<String>() {
        s.clone()
    } else {
        "(no message)".into()
    }
}

/// The start, the configuration and the measurement.
fn fit(case: &Case, image: &Image) -> Result<Measurement, String> {
    let init = initial_curve(case, image)?;
    let config = config(case, &init)?;
    measure(image, &init, &config).map_err(|e| e.to_string())
}

/// The configuration `measure` would use: the defaults, `--kind contour`
/// for lines, `--stages` when the case has them, `--break` at the
/// polygon's corners.
fn config(case: &Case, init: &InitialCurve) -> Result<FitConfig, String> {
    let mut config = FitConfig {
        kind: case.image.shape.kind(),
        ..FitConfig::default()
    };
    if let Some(s) = case.stages {
        config.stages = Some(parse_stages(s).map_err(|e| e.to_string())?);
    }
    if case.image.shape == ShapeName::PolygonBreaks {
        config.breaks = break_positions(init, &case.image.spec.shape.corners())?;
    }
    config.validate().map_err(|e| e.to_string())?;
    Ok(config)
}

/// Arc lengths along the start of the points of it nearest to each corner
/// (what a user reads off the start to give `--break`), sorted.
fn break_positions(init: &InitialCurve, corners: &[[f64; 2]]) -> Result<Vec<f64>, String> {
    let pts = init.dense_points(0.25).map_err(|e| e.to_string())?;
    let mut cum = Vec::with_capacity(pts.len());
    let mut total = 0.0;
    for (i, p) in pts.iter().enumerate() {
        if i > 0 {
            total += (p[0] - pts[i - 1][0]).hypot(p[1] - pts[i - 1][1]);
        }
        cum.push(total);
    }
    let nearest = |c: &[f64; 2]| {
        let d = |p: &[f64; 2]| (p[0] - c[0]).hypot(p[1] - c[1]);
        (0..pts.len()).min_by(|&a, &b| d(&pts[a]).total_cmp(&d(&pts[b])))
    };
    let mut s: Vec<f64> = corners
        .iter()
        .filter_map(|c| nearest(c).map(|i| cum[i]))
        .collect();
    s.sort_by(f64::total_cmp);
    Ok(s)
}

/// The start of `case`, built from the truth (explicit starts) or found in
/// the image (the automatic start, with the library calls `measure`
/// makes).
pub fn initial_curve(case: &Case, image: &Image) -> Result<InitialCurve, String> {
    let shape = &case.image.spec.shape;
    let mut rng = Rng::new(&case.id);
    match case.start {
        Start::Circle1_5 => Ok(shifted_circle(shape, 1.5, &mut rng)),
        Start::Circle10pct => Ok(shifted_circle(shape, 0.1 * mean_radius(shape), &mut rng)),
        Start::Circle085 => {
            let (cx, cy) = centre(shape);
            Ok(InitialCurve::Circle {
                cx,
                cy,
                r: 0.85 * mean_radius(shape),
            })
        }
        Start::Polyline1_5 => offset_polyline(shape, 1.5 * rng.sign(), image.width()),
        Start::Segment => Ok(segment(shape, 1.5 * rng.sign(), image.width())),
        Start::Auto => automatic(case, image, &mut rng),
    }
}

/// The radius a user would give a circle for the shape: the radius,
/// `sqrt(a b)`, the star's mean radius, a polygon's mean of circumradius
/// and inradius.
fn mean_radius(shape: &Shape) -> f64 {
    match *shape {
        Shape::Circle { r, .. } => r,
        Shape::Ellipse { a, b, .. } => (a * b).sqrt(),
        Shape::Star { r0, .. } => r0,
        Shape::Polygon { r, sides, .. } => {
            0.5 * r * (1.0 + (std::f64::consts::PI / f64::from(sides)).cos())
        }
        Shape::Sine { .. } => f64::NAN,
    }
}

/// A circle of the mean radius, its centre `off` px away from the shape's
/// in a seeded direction.
fn shifted_circle(shape: &Shape, off: f64, rng: &mut Rng) -> InitialCurve {
    let (cx, cy) = centre(shape);
    let dir = rng.uniform(0.0, std::f64::consts::TAU);
    InitialCurve::Circle {
        cx: cx + off * dir.cos(),
        cy: cy + off * dir.sin(),
        r: mean_radius(shape),
    }
}

/// The truth moved by `off` px along its normal: vertices every ~4 px of a
/// closed shape; for the sine, vertices every ~8 px in x from the first
/// pixel column to the last (both included), moved by `off` in y.
fn offset_polyline(shape: &Shape, off: f64, width: usize) -> Result<InitialCurve, String> {
    if let Shape::Sine { .. } = shape {
        let last = width as f64 - 1.0;
        let n = (last / 8.0).ceil() as usize;
        let points = (0..=n)
            .map(|i| {
                let x = last * i as f64 / n as f64;
                [x, sine_y(shape, x) + off]
            })
            .collect();
        return Ok(InitialCurve::Polyline {
            points,
            closed: false,
        });
    }
    let points = shape
        .polyline(4.0)
        .map_err(|e| e.to_string())?
        .into_iter()
        .map(|p| {
            let (_, n) = shape.closest_point(p[0], p[1]);
            [p[0] + off * n[0], p[1] + off * n[1]]
        })
        .collect();
    Ok(InitialCurve::Polyline {
        points,
        closed: true,
    })
}

/// `y(x)` of a sine.
fn sine_y(shape: &Shape, x: f64) -> f64 {
    match *shape {
        Shape::Sine {
            y0,
            amplitude,
            wavelength,
            phase,
            ..
        } => y0 + amplitude * (std::f64::consts::TAU * x / wavelength + phase).sin(),
        _ => f64::NAN,
    }
}

/// The segment from the first pixel column to the last along the sine's
/// mean line, `off` px below it.
fn segment(shape: &Shape, off: f64, width: usize) -> InitialCurve {
    let y = match *shape {
        Shape::Sine { y0, .. } => y0 + off,
        _ => f64::NAN,
    };
    InitialCurve::Segment {
        x0: 0.0,
        y0: y,
        x1: width as f64 - 1.0,
        y1: y,
    }
}

/// The automatic start: the main silhouette, or for a line the ridge
/// followed from a point 1 px beside it (`--pick`), at a seeded place.
fn automatic(case: &Case, image: &Image, rng: &mut Rng) -> Result<InitialCurve, String> {
    if case.image.shape.kind() == Kind::Silhouette {
        let found = vicurve::start::find_silhouette(image, &StartConfig::default())
            .map_err(|e| e.to_string())?;
        return Ok(found.curve);
    }
    let shape = &case.image.spec.shape;
    let guess = match *shape {
        Shape::Sine { .. } => {
            let x = rng.uniform(0.2, 0.8) * image.width() as f64;
            [x, sine_y(shape, x)]
        }
        _ => {
            let (cx, cy) = centre(shape);
            let (r, th) = (mean_radius(shape), rng.uniform(0.0, std::f64::consts::TAU));
            [cx + r * th.cos(), cy + r * th.sin()]
        }
    };
    let (p, n) = shape.closest_point(guess[0], guess[1]);
    let side = rng.sign();
    let config = StartConfig {
        pick: Some([p[0] + side * n[0], p[1] + side * n[1]]),
        roi: None,
    };
    let found = vicurve::start::ridge::find_line(image, &config).map_err(|e| e.to_string())?;
    Ok(found.curve)
}
