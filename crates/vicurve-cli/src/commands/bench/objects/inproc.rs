//! `measure --all` timed in this process, part by part, and its result
//! checked against the truth.

use super::Case;
use std::time::Instant;
use vicurve::interp::Sampler;
use vicurve::objects::find::find_objects;
use vicurve::objects::{measure_all, AllConfig, AllResult};
use vicurve::truth::Shape;
use vicurve::virtual_image::Profile;

/// Band half-width of the fit's blur estimate, pixels (`fit::blur`'s first
/// search band), for the separate call.
const EDGE_SPREAD_BAND: f64 = 8.0;

/// What the in-process runs measured.
pub struct Inproc {
    /// Threads of rayon's pool.
    pub threads: usize,
    /// `find_objects` alone, seconds, per repeat.
    pub find: Vec<f64>,
    /// `Sampler::new` alone (the cubic prefilter of the image), seconds.
    pub sampler: Vec<f64>,
    /// `measure_all` (search, interpolant, every object), seconds.
    pub all: Vec<f64>,
    /// `measure_all` in a pool of one thread, seconds.
    pub one_thread: Vec<f64>,
    /// Each stage summed over the objects, in schedule order (of the last
    /// one-thread run: stage times are not shared with other work there).
    pub stages: Vec<StageSum>,
    /// Separate calls of the blur estimate (`psf::edge_spread`, band 8 px)
    /// on every measured curve, one thread, seconds in all.
    pub blur_estimate: f64,
    /// The result against the truth.
    pub accuracy: Accuracy,
}

/// One stage of the schedule, over all objects.
pub struct StageSum {
    /// `R = 5 px, silhouette`, `R = 1.5 px, pixel edge`, ...
    pub label: String,
    /// Objects that ran it.
    pub objects: usize,
    /// Gauss–Newton iterations, all objects.
    pub iterations: usize,
    /// Re-references, all objects.
    pub rereferences: usize,
    /// Wall-clock seconds, all objects.
    pub seconds: f64,
}

/// The measured objects matched to the truth's circles (nearest centre
/// within a radius).
pub struct Accuracy {
    /// Circles in the truth.
    pub truth: usize,
    /// Objects reported.
    pub reported: usize,
    /// Objects measured (not failed).
    pub measured: usize,
    /// Truth circles matched by a measured object.
    pub matched: usize,
    /// Largest centre error of a matched object (best-fit circle), px.
    pub centre_max: f64,
    /// Largest radius error of a matched object, px.
    pub radius_max: f64,
}

/// `repeats` runs of each part on `case`.
pub fn run(case: &Case, repeats: usize) -> Result<Inproc, String> {
    let config = AllConfig::default();
    let image = &case.image;
    let err = |e: vicurve::Error| e.to_string();
    let one = rayon::ThreadPoolBuilder::new()
        .num_threads(1)
        .build()
        .map_err(|e| format!("cannot make a thread pool: {e}"))?;
    let mut out = Inproc {
        threads: rayon::current_num_threads(),
        find: Vec::new(),
        sampler: Vec::new(),
        all: Vec::new(),
        one_thread: Vec::new(),
        stages: Vec::new(),
        blur_estimate: 0.0,
        accuracy: score(case, None),
    };
    let mut last = None;
    for _ in 0..repeats {
        out.find.push(timed(|| find_objects(image, &config)).1);
        out.sampler
            .push(timed(|| Sampler::new(image, config.fit.interpolation)).1);
        let (all, t) = timed(|| measure_all(image, &config));
        all.map_err(err)?;
        out.all.push(t);
        let (all, t) = timed(|| one.install(|| measure_all(image, &config)));
        out.one_thread.push(t);
        last = Some(all.map_err(err)?);
    }
    if let Some(all) = last {
        out.stages = stage_sums(&all);
        out.blur_estimate = one.install(|| blur_estimates(image, &config, &all));
        out.accuracy = score(case, Some(&all));
    }
    Ok(out)
}

/// `f()` and its wall-clock seconds.
fn timed<T>(f: impl FnOnce() -> T) -> (T, f64) {
    let t = Instant::now();
    let v = f();
    (v, t.elapsed().as_secs_f64())
}

/// The stages of every object summed by position in the schedule.
fn stage_sums(all: &AllResult) -> Vec<StageSum> {
    let mut sums: Vec<StageSum> = Vec::new();
    for m in all.objects.iter().filter_map(|o| o.measurement.as_ref()) {
        for (k, s) in m.stages.iter().enumerate() {
            let profile = match s.profile {
                Profile::PixelEdge { .. } => "pixel edge".to_string(),
                Profile::PixelLine { .. } => "pixel line".to_string(),
                p => p.to_string(),
            };
            let label = format!("{}. R = {} px, {profile}", k + 1, s.half_width);
            let at = match sums.iter().position(|x| x.label == label) {
                Some(i) => i,
                None => {
                    sums.push(StageSum {
                        label,
                        objects: 0,
                        iterations: 0,
                        rereferences: 0,
                        seconds: 0.0,
                    });
                    sums.len() - 1
                }
            };
            let x = &mut sums[at];
            x.objects += 1;
            x.iterations += s.iterations;
            x.rereferences += s.rereferences;
            x.seconds += s.seconds;
        }
    }
    sums.sort_by(|a, b| a.label.cmp(&b.label));
    sums
}

/// Seconds of one blur estimate per measured curve, all together.
fn blur_estimates(image: &vicurve::Image, config: &AllConfig, all: &AllResult) -> f64 {
    let sampler = Sampler::new(image, config.fit.interpolation);
    let curves: Vec<_> = all
        .objects
        .iter()
        .filter_map(|o| o.measurement.as_ref())
        .collect();
    timed(|| {
        for m in &curves {
            let _ = vicurve::psf::edge_spread(&sampler, &m.curve, EDGE_SPREAD_BAND);
        }
    })
    .1
}

/// Match `all` (when given) to the truth's circles.
fn score(case: &Case, all: Option<&AllResult>) -> Accuracy {
    let circles: Vec<[f64; 3]> = case
        .scene
        .items
        .iter()
        .filter_map(|i| match i.shape {
            Shape::Circle { cx, cy, r } => Some([cx, cy, r]),
            _ => None,
        })
        .collect();
    let mut acc = Accuracy {
        truth: circles.len(),
        reported: 0,
        measured: 0,
        matched: 0,
        centre_max: f64::NAN,
        radius_max: f64::NAN,
    };
    let Some(all) = all else { return acc };
    acc.reported = all.objects.len();
    acc.measured = all.objects.len() - all.failed();
    let (mut centre, mut radius) = (0.0f64, 0.0f64);
    for t in &circles {
        let fit = all
            .objects
            .iter()
            .filter(|o| o.failure.is_none())
            .filter_map(|o| o.closed.as_ref().map(|c| c.circle))
            .find(|c| (c.cx - t[0]).hypot(c.cy - t[1]) < t[2]);
        if let Some(c) = fit {
            acc.matched += 1;
            centre = centre.max((c.cx - t[0]).hypot(c.cy - t[1]));
            radius = radius.max((c.r - t[2]).abs());
        }
    }
    if acc.matched > 0 {
        (acc.centre_max, acc.radius_max) = (centre, radius);
    }
    acc
}
