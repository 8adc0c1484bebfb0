//! `vicurve eval` of a multi-object result: the points of `measure --all
//! --points` (an `object` column) against a scene's truth (`synth
//! scene|grid --truth`), object by object.

use crate::failure::Failure;
use serde::Serialize;
use std::path::Path;
use vicurve::render::scene::{Role, Scene};
use vicurve::truth::{evaluate, ErrorStats, Shape};

/// One measured object against the truth shape it matched.
#[derive(Serialize)]
pub struct ObjectScore {
    /// The object's id.
    pub object: usize,
    /// The index of the matched shape in the scene's items (`None`: none
    /// within 1 px RMS).
    pub item: Option<usize>,
    /// The matched shape's role.
    pub role: Option<Role>,
    /// Distances of the object's points to the matched shape.
    pub stats: Option<ErrorStats>,
}

/// The whole comparison.
#[derive(Serialize)]
pub struct SceneScore {
    /// Every measured object.
    pub objects: Vec<ObjectScore>,
    /// Items to be measured (objects, holes) that no object matched.
    pub missed: Vec<usize>,
    /// Objects that matched nothing to be measured (no shape, a speck, a
    /// border object).
    pub extra: Vec<usize>,
}

/// The centre of a scene's shape (circles and ellipses).
fn centre(s: &Shape) -> Option<([f64; 2], f64)> {
    match *s {
        Shape::Circle { cx, cy, r } => Some(([cx, cy], r)),
        Shape::Ellipse { cx, cy, a, b, .. } => Some(([cx, cy], a.max(b))),
        _ => None,
    }
}

/// An object's id and its points `[x, y]`, px.
pub type ObjectPoints = (usize, Vec<[f64; 2]>);

/// The points of each object of an `object,...,x,y,...` CSV, by id.
pub fn read_object_points(path: &Path) -> Result<Vec<ObjectPoints>, Failure> {
    let fail = |what: String| Failure::Error(format!("{}: {what}", path.display()));
    let text = std::fs::read_to_string(path).map_err(|e| fail(e.to_string()))?;
    let mut lines = text.lines();
    let header: Vec<&str> = lines.next().unwrap_or("").split(',').collect();
    let col = |n: &str| {
        header.iter().position(|c| c.trim() == n).ok_or_else(|| {
            fail(format!(
                "no `{n}` column (write it with measure --all --points)"
            ))
        })
    };
    let (io, ix, iy) = (col("object")?, col("x")?, col("y")?);
    let mut out: Vec<ObjectPoints> = Vec::new();
    for (n, line) in lines.enumerate().filter(|(_, l)| !l.trim().is_empty()) {
        let cells: Vec<&str> = line.split(',').collect();
        let num = |k: usize| cells.get(k).and_then(|c| c.trim().parse::<f64>().ok());
        let (Some(o), Some(x), Some(y)) = (num(io), num(ix), num(iy)) else {
            return Err(fail(format!(
                "row {}: object, x and y must be numbers",
                n + 2
            )));
        };
        let id = o as usize;
        match out.last_mut() {
            Some((last, pts)) if *last == id => pts.push([x, y]),
            _ => out.push((id, vec![[x, y]])),
        }
    }
    Ok(out)
}

/// Match each object to the scene's shape its points fit best (RMS
/// distance under 1 px, among the shapes whose centre is within their
/// reach of the points' mean) and score it.
pub fn score(objects: &[ObjectPoints], scene: &Scene) -> SceneScore {
    let mut used = vec![false; scene.items.len()];
    let mut scores = Vec::new();
    for (id, pts) in objects {
        let n = pts.len().max(1) as f64;
        let mean = pts
            .iter()
            .fold([0.0, 0.0], |m, p| [m[0] + p[0] / n, m[1] + p[1] / n]);
        let best = scene
            .items
            .iter()
            .enumerate()
            .filter_map(|(k, item)| {
                let (c, reach) = centre(&item.shape)?;
                ((c[0] - mean[0]).hypot(c[1] - mean[1]) < reach).then_some(k)
            })
            .filter_map(|k| evaluate(pts, &scene.items[k].shape).ok().map(|s| (k, s)))
            .filter(|(_, s)| s.rms < 1.0)
            .min_by(|a, b| a.1.rms.total_cmp(&b.1.rms));
        if let Some((k, _)) = &best {
            used[*k] = true;
        }
        scores.push(ObjectScore {
            object: *id,
            item: best.as_ref().map(|b| b.0),
            role: best.as_ref().map(|b| scene.items[b.0].role),
            stats: best.map(|b| b.1),
        });
    }
    let wanted = |r: Role| matches!(r, Role::Object | Role::Hole);
    SceneScore {
        missed: (0..scene.items.len())
            .filter(|&k| wanted(scene.items[k].role) && !used[k])
            .collect(),
        extra: scores
            .iter()
            .filter(|s| !s.role.is_some_and(wanted))
            .map(|s| s.object)
            .collect(),
        objects: scores,
    }
}

/// Print the per-object table and the summary.
pub fn print(s: &SceneScore) {
    println!("object  item  role      points  bias (px)   scatter (px)  max (px)");
    for o in &s.objects {
        match (&o.item, &o.role, &o.stats) {
            (Some(k), Some(r), Some(st)) => println!(
                "{:6}  {k:4}  {:8}  {:6}  {:+.3e}  {:.3e}     {:.3e}",
                o.object,
                format!("{r:?}").to_lowercase(),
                st.count,
                st.bias,
                st.scatter,
                st.max_abs
            ),
            _ => println!("{:6}  none", o.object),
        }
    }
    let matched: Vec<&ErrorStats> = s
        .objects
        .iter()
        .filter(|o| matches!(o.role, Some(Role::Object | Role::Hole)))
        .filter_map(|o| o.stats.as_ref())
        .collect();
    let worst = |f: fn(&ErrorStats) -> f64| matched.iter().map(|s| f(s)).fold(0.0, f64::max);
    println!(
        "matched: {} object(s); missed: {:?}; extra: {:?}; worst |bias| {:.3e} px, worst max {:.3e} px",
        matched.len(),
        s.missed,
        s.extra,
        worst(|s| s.bias.abs()),
        worst(|s| s.max_abs)
    );
}
