//! One row per object: what `--table` and Python's `measure_all` give.

use super::{AllResult, ObjectResult};

/// A table of the objects: numeric columns (NaN where a value does not
/// exist: a failed object, an open curve) and the outcome of each.
#[derive(Clone, Debug, PartialEq)]
pub struct Table {
    /// `(name, values)`, one value per object, in the objects' order.
    pub columns: Vec<(String, Vec<f64>)>,
    /// `measured` or the failure's reason tag, per object.
    pub outcome: Vec<String>,
    /// The failure's message (empty for a measured object).
    pub message: Vec<String>,
}

/// The values of one object's row, named.
fn row(o: &ObjectResult) -> Vec<(String, f64)> {
    let nan = f64::NAN;
    let mut r: Vec<(String, f64)> = Vec::new();
    let mut put = |name: &str, v: f64| r.push((name.to_string(), v));
    put("id", o.id as f64);
    let c = o.closed.as_ref().filter(|_| o.failure.is_none());
    let centroid = c.map_or([nan, nan], |c| c.centroid);
    put("centroid_x", centroid[0]);
    put("centroid_y", centroid[1]);
    put("region_x", o.region.centroid[0]);
    put("region_y", o.region.centroid[1]);
    put("region_pixels", o.region.pixels as f64);
    if let Some(p) = o.region.parent {
        put("parent", p as f64);
    }
    put("area", c.map_or(nan, |c| c.area));
    put(
        "equivalent_diameter",
        c.map_or(nan, |c| c.equivalent_diameter),
    );
    let ci = c.map(|c| &c.circle);
    for (n, v) in [
        ("circle_cx", ci.map(|c| c.cx)),
        ("circle_cy", ci.map(|c| c.cy)),
        ("circle_r", ci.map(|c| c.r)),
        ("circle_sigma_cx", ci.map(|c| c.sigma_cx)),
        ("circle_sigma_cy", ci.map(|c| c.sigma_cy)),
        ("circle_sigma_r", ci.map(|c| c.sigma_r)),
        ("circle_rms", ci.map(|c| c.rms)),
    ] {
        put(n, v.unwrap_or(nan));
    }
    let e = c.map(|c| &c.ellipse);
    for (n, v) in [
        ("ellipse_cx", e.map(|e| e.cx)),
        ("ellipse_cy", e.map(|e| e.cy)),
        ("ellipse_a", e.map(|e| e.a)),
        ("ellipse_b", e.map(|e| e.b)),
        ("ellipse_angle", e.map(|e| e.angle)),
        ("ellipse_sigma_cx", e.map(|e| e.sigma_cx)),
        ("ellipse_sigma_cy", e.map(|e| e.sigma_cy)),
        ("ellipse_sigma_a", e.map(|e| e.sigma_a)),
        ("ellipse_sigma_b", e.map(|e| e.sigma_b)),
        ("ellipse_sigma_angle", e.map(|e| e.sigma_angle)),
        ("ellipse_rms", e.map(|e| e.rms)),
    ] {
        put(n, v.unwrap_or(nan));
    }
    let m = o.measurement.as_ref().filter(|_| o.failure.is_none());
    put("residual_rms", m.map_or(nan, |m| m.residual_rms()));
    put("length", m.map_or(nan, |m| m.length()));
    if let Some(f) = &o.model {
        let ok = o.failure.is_none();
        for p in &f.parameters {
            put(&format!("model_{}", p.name), if ok { p.value } else { nan });
            put(
                &format!("model_sigma_{}", p.name),
                if ok { p.sigma } else { nan },
            );
        }
        put("model_residual_rms", if ok { f.residual_rms } else { nan });
    }
    r
}

/// The table of `all` (module docs). The model's columns (`model_<name>`,
/// `model_sigma_<name>`, `model_residual_rms`) are there when a model was
/// fitted to some object; objects without it have NaN.
pub fn object_table(all: &AllResult) -> Table {
    let rows: Vec<Vec<(String, f64)>> = all.objects.iter().map(row).collect();
    let mut names: Vec<String> = Vec::new();
    for r in &rows {
        for (n, _) in r {
            if !names.contains(n) {
                names.push(n.clone());
            }
        }
    }
    let columns = names
        .into_iter()
        .map(|n| {
            let values = rows
                .iter()
                .map(|r| r.iter().find(|(m, _)| *m == n).map_or(f64::NAN, |p| p.1))
                .collect();
            (n, values)
        })
        .collect();
    Table {
        columns,
        outcome: all.objects.iter().map(|o| o.outcome()).collect(),
        message: all
            .objects
            .iter()
            .map(|o| o.failure.as_ref().map_or(String::new(), |f| f.to_string()))
            .collect(),
    }
}
