//! Square-grid strain analysis: the cells of a printed square grid (pitch
//! `P0` before forming), each measured as a closed curve; their centroids,
//! indexed on the lattice, give the local deformation gradient and from it
//! the principal true strains.
//!
//! 1. [`lattice_indices`] numbers the centroids `[column, row]` on the
//!    deformed lattice: from the centroid nearest the middle, whose nearest
//!    neighbours give the two lattice directions (the one closest to `+x`
//!    is the columns'), each neighbour is looked for where the last
//!    neighbour step predicts it (within 30 % of the step), so that a
//!    smoothly varying deformation is followed across the grid.
//! 2. [`cell_strains`]: the deformation gradient at a cell is
//!    `F = [dx/di, dx/dj] / P0` by central differences of the centroids
//!    (second-order accurate), or one-sided at the grid's edge (first
//!    order: [`GridStrain::central`] says which); `F F^T`'s eigenvalues are
//!    the squared principal stretches, `eps = ln(lambda)`, and its major
//!    eigenvector the major strain's direction. The rigid rotation of the
//!    grid and its reference orientation do not matter.
//!
//! A cell's strains are reported as the [`GridStrain`] of the ellipse that
//! a circle of diameter `P0` centred on the cell becomes under `F`
//! (`a = lambda1 P0 / 2`), so that circle and square grids share one
//! table, map and forming-limit plot.

use super::{find::find_objects, AllConfig, AllResult, GridStrain, ObjectPolarity, ObjectResult};
use crate::buckets::Buckets;
use crate::error::Result;
use crate::image::Image;
use std::collections::HashMap;

/// A neighbour must lie within this fraction of the predicted step of
/// where the step predicts it: a cell's pitch varies by a few per cent
/// from one cell to the next under a smooth forming strain, while the
/// nearest wrong candidate (a diagonal or second neighbour) lies 40 % or
/// more of the step away.
const NEIGHBOUR_TOLERANCE: f64 = 0.3;

/// The phase of a square grid's cells: `config.polarity` when given, else
/// (auto) the phase in which more objects are found, since the cells are
/// many enclosed regions and the lines one network (cut by the border), and
/// the cells may well be the majority phase that auto would not pick.
///
/// Errors: those of [`find_objects`] (no contrast, a bad region of
/// interest).
pub fn cell_polarity(image: &Image, config: &AllConfig) -> Result<ObjectPolarity> {
    if config.polarity != ObjectPolarity::Auto {
        return Ok(config.polarity);
    }
    let count = |polarity| {
        let c = AllConfig {
            polarity,
            ..config.clone()
        };
        find_objects(image, &c).map(|f| f.candidates.len())
    };
    let (bright, dark) = (count(ObjectPolarity::Bright)?, count(ObjectPolarity::Dark)?);
    Ok(if dark > bright {
        ObjectPolarity::Dark
    } else {
        ObjectPolarity::Bright
    })
}

/// The lattice index `[column, row]` of every point (`None` for a `None`
/// point or one not reached from the middle through neighbours), columns
/// along the lattice direction closest to `+x`, rows along the one closest
/// to `+y`, the smallest of each 0. Points are cell centroids, px.
///
/// Edge cases: fewer than two points, or a middle point without two
/// non-parallel neighbours, give no index at all; a point that would take
/// an index already taken is left without one.
pub fn lattice_indices(points: &[Option<[f64; 2]>]) -> Vec<Option<[i64; 2]>> {
    let mut out = vec![None; points.len()];
    let valid: Vec<(usize, [f64; 2])> = points
        .iter()
        .enumerate()
        .filter_map(|(k, p)| {
            p.filter(|p| p[0].is_finite() && p[1].is_finite())
                .map(|p| (k, p))
        })
        .collect();
    if valid.len() < 2 {
        return out;
    }
    let Some(spacing) = typical_spacing(&valid) else {
        return out;
    };
    let index = Buckets::new(valid.iter().map(|v| v.1), 1.5 * spacing);
    let Some((seed, a1, a2)) = seed_basis(&valid, &index, spacing) else {
        return out;
    };
    let mut taken: HashMap<[i64; 2], usize> = HashMap::new();
    let mut at: Vec<Option<[i64; 2]>> = vec![None; valid.len()];
    at[seed] = Some([0, 0]);
    taken.insert([0, 0], seed);
    let mut queue = std::collections::VecDeque::from([(seed, a1, a2)]);
    while let Some((k, a1, a2)) = queue.pop_front() {
        let Some(ij) = at[k] else { continue };
        let p = valid[k].1;
        for (step, along_columns, sign) in [
            (a1, true, 1.0),
            (a1, true, -1.0),
            (a2, false, 1.0),
            (a2, false, -1.0),
        ] {
            let q = [p[0] + sign * step[0], p[1] + sign * step[1]];
            let reach = NEIGHBOUR_TOLERANCE * norm(a1).min(norm(a2));
            let Some(n) = nearest(&index, &valid, q, reach) else {
                continue;
            };
            let d = if along_columns {
                [sign as i64, 0]
            } else {
                [0, sign as i64]
            };
            let nij = [ij[0] + d[0], ij[1] + d[1]];
            if at[n].is_some() || taken.contains_key(&nij) {
                continue;
            }
            at[n] = Some(nij);
            taken.insert(nij, n);
            let found = [sign * (valid[n].1[0] - p[0]), sign * (valid[n].1[1] - p[1])];
            let (b1, b2) = if along_columns {
                (found, a2)
            } else {
                (a1, found)
            };
            queue.push_back((n, b1, b2));
        }
    }
    let lo = |c: usize| at.iter().flatten().map(|ij| ij[c]).min().unwrap_or(0);
    let (i0, j0) = (lo(0), lo(1));
    for (v, ij) in valid.iter().zip(&at) {
        out[v.0] = ij.map(|ij| [ij[0] - i0, ij[1] - j0]);
    }
    out
}

/// The strains of every cell of `all` (measured closed curves of a square
/// grid of pitch `pitch` px before forming; module docs): `None` for a
/// failed object, one without a closed curve, one off the lattice, or one
/// without a neighbour in each direction. `pitch` must be positive (NaN
/// strains otherwise).
///
/// Each strain's deviation is propagated to first order from the
/// centroids' (taken as independent; each from its samples' sigma, the
/// samples correlated in groups as many as the displacement's degrees of
/// freedom).
pub fn cell_strains(all: &AllResult, pitch: f64) -> Vec<Option<GridStrain>> {
    let cells: Vec<Option<([f64; 2], [f64; 2])>> = all.objects.iter().map(centroid_of).collect();
    let points: Vec<Option<[f64; 2]>> = cells.iter().map(|c| c.map(|c| c.0)).collect();
    let idx = lattice_indices(&points);
    let by_index: HashMap<[i64; 2], usize> = idx
        .iter()
        .enumerate()
        .filter_map(|(k, ij)| ij.map(|ij| (ij, k)))
        .collect();
    (0..all.objects.len())
        .map(|k| {
            let ij = idx[k]?;
            let (centre, sigma) = cells[k]?;
            let stencil = Stencil::at(ij, &by_index)?;
            // Every cell of a stencil is on the lattice, so has a centroid.
            let around: Vec<([f64; 2], [f64; 2])> = stencil
                .cells
                .iter()
                .map(|&c| cells[c])
                .collect::<Option<_>>()?;
            let cell = Cell {
                id: all.objects[k].id,
                ij,
                centre,
                sigma,
            };
            Some(strain_at(&cell, &stencil, &around, pitch))
        })
        .collect()
}

/// The centroid of a measured closed object and its deviation `[sx, sy]`,
/// px.
fn centroid_of(o: &ObjectResult) -> Option<([f64; 2], [f64; 2])> {
    if o.failure.is_some() {
        return None;
    }
    let (m, closed) = (o.measurement.as_ref()?, o.closed.as_ref()?);
    let c = closed.centroid;
    let n = m.samples.len();
    if n < 3 {
        return None;
    }
    // A normal move dn of the curve over ds moves the centroid by
    // (p - c) dn ds / A; the samples are independent in groups of
    // samples / (the displacement's degrees of freedom: one per element,
    // and `degree` more at each break, where it is discontinuous).
    let ds = closed.length / n as f64;
    let breaks = (m.curve.corners().len() * m.curve.basis().degree()) as f64;
    let independent = m.stages.last().map_or(n as f64, |s| s.elements as f64) + breaks;
    let inflate = (n as f64 / independent.max(1.0)).max(1.0);
    let (mut vx, mut vy) = (0.0, 0.0);
    for s in &m.samples {
        let w = s.sigma * ds / closed.area;
        vx += ((s.x - c[0]) * w).powi(2);
        vy += ((s.y - c[1]) * w).powi(2);
    }
    Some((c, [(vx * inflate).sqrt(), (vy * inflate).sqrt()]))
}

/// The centroids a cell's gradient is taken from: `cells` (object
/// indices), and the gradient columns as weights on them.
struct Stencil {
    /// Object indices of the centroids used.
    cells: Vec<usize>,
    /// `dx/di = sum w1[k] x[cells[k]]`.
    w1: Vec<f64>,
    /// `dx/dj = sum w2[k] x[cells[k]]`.
    w2: Vec<f64>,
    /// Whether both directions are central differences.
    central: bool,
}

impl Stencil {
    /// The stencil of the cell at `ij`: central differences where both
    /// neighbours are there, one-sided where one is, `None` where neither
    /// is in some direction.
    fn at(ij: [i64; 2], by_index: &HashMap<[i64; 2], usize>) -> Option<Stencil> {
        let me = by_index.get(&ij).copied()?;
        let mut cells = Vec::new();
        let slot = |k: usize, cells: &mut Vec<usize>| match cells.iter().position(|&c| c == k) {
            Some(s) => s,
            None => {
                cells.push(k);
                cells.len() - 1
            }
        };
        let mut terms: [Vec<(usize, f64)>; 2] = [Vec::new(), Vec::new()];
        let mut central = true;
        for (dir, t) in terms.iter_mut().enumerate() {
            let off = |s: i64| {
                let mut n = ij;
                n[dir] += s;
                by_index.get(&n).copied()
            };
            match (off(1), off(-1)) {
                (Some(p), Some(m)) => {
                    t.push((slot(p, &mut cells), 0.5));
                    t.push((slot(m, &mut cells), -0.5));
                }
                (Some(p), None) => {
                    central = false;
                    t.push((slot(p, &mut cells), 1.0));
                    t.push((slot(me, &mut cells), -1.0));
                }
                (None, Some(m)) => {
                    central = false;
                    t.push((slot(me, &mut cells), 1.0));
                    t.push((slot(m, &mut cells), -1.0));
                }
                (None, None) => return None,
            }
        }
        let weights = |t: &[(usize, f64)]| {
            let mut w = vec![0.0; cells.len()];
            t.iter().for_each(|&(s, v)| w[s] += v);
            w
        };
        let (w1, w2) = (weights(&terms[0]), weights(&terms[1]));
        Some(Stencil {
            cells,
            w1,
            w2,
            central,
        })
    }

    /// `F = [dx/di, dx/dj] / pitch` from the stencil's centroids `x`.
    fn gradient(&self, x: &[[f64; 2]], pitch: f64) -> [[f64; 2]; 2] {
        let col = |w: &[f64]| {
            let mut g = [0.0; 2];
            for (p, &wk) in x.iter().zip(w) {
                g[0] += wk * p[0];
                g[1] += wk * p[1];
            }
            [g[0] / pitch, g[1] / pitch]
        };
        let (g1, g2) = (col(&self.w1), col(&self.w2));
        [[g1[0], g2[0]], [g1[1], g2[1]]]
    }
}

/// `[eps1, eps2, eps3, angle]` of the deformation gradient `f`
/// (row-major): the principal true strains `ln(lambda)` from the
/// eigenvalues `lambda^2` of `F F^T`, `eps3 = -(eps1 + eps2)`, and the
/// major direction in the deformed image (rad, counterclockwise on screen
/// from `+x`, in `(-pi/2, pi/2]`; 0 when the stretches are equal).
pub fn principal_strains(f: [[f64; 2]; 2]) -> [f64; 4] {
    let b11 = f[0][0] * f[0][0] + f[0][1] * f[0][1];
    let b22 = f[1][0] * f[1][0] + f[1][1] * f[1][1];
    let b12 = f[0][0] * f[1][0] + f[0][1] * f[1][1];
    let mean = 0.5 * (b11 + b22);
    let half = (0.25 * (b11 - b22).powi(2) + b12 * b12).sqrt();
    let (mu1, mu2) = (mean + half, (mean - half).max(0.0));
    let (e1, e2) = (0.5 * mu1.ln(), 0.5 * mu2.ln());
    // The major direction (x, y) at theta = atan2(2 b12, b11 - b22) / 2;
    // on screen (y down) its angle is -theta.
    let mut angle = -0.5 * (2.0 * b12).atan2(b11 - b22);
    if angle <= -std::f64::consts::FRAC_PI_2 {
        angle += std::f64::consts::PI;
    }
    [e1, e2, -(e1 + e2), angle]
}

/// One cell: its object id, lattice index, centroid and the centroid's
/// deviation `[sx, sy]`, px.
struct Cell {
    id: usize,
    ij: [i64; 2],
    centre: [f64; 2],
    sigma: [f64; 2],
}

/// The [`GridStrain`] of `cell` from the centroids and deviations of its
/// stencil's cells (`around`, in the stencil's order), with first-order
/// deviations by finite differences over their coordinates.
fn strain_at(
    cell: &Cell,
    stencil: &Stencil,
    around: &[([f64; 2], [f64; 2])],
    pitch: f64,
) -> GridStrain {
    let mut x: Vec<[f64; 2]> = around.iter().map(|a| a.0).collect();
    let f = stencil.gradient(&x, pitch);
    let v = principal_strains(f);
    let mut var = [0.0; 4];
    // A step small against the coordinates' deviations' effect, large
    // against rounding.
    let h = 1e-4;
    for k in 0..x.len() {
        for c in 0..2 {
            let x0 = x[k][c];
            x[k][c] = x0 + h;
            let up = principal_strains(stencil.gradient(&x, pitch));
            x[k][c] = x0 - h;
            let down = principal_strains(stencil.gradient(&x, pitch));
            x[k][c] = x0;
            for q in 0..4 {
                let mut d = up[q] - down[q];
                if q == 3 {
                    // The angle wraps at +-pi/2.
                    d = (d + std::f64::consts::FRAC_PI_2).rem_euclid(std::f64::consts::PI)
                        - std::f64::consts::FRAC_PI_2;
                }
                var[q] += (d / (2.0 * h) * around[k].1[c]).powi(2);
            }
        }
    }
    GridStrain {
        id: cell.id,
        centre: cell.centre,
        a: 0.5 * pitch * v[0].exp(),
        b: 0.5 * pitch * v[1].exp(),
        eps1: v[0],
        sigma_eps1: var[0].sqrt(),
        eps2: v[1],
        sigma_eps2: var[1].sqrt(),
        eps3: v[2],
        sigma_eps3: var[2].sqrt(),
        angle: v[3],
        sigma_angle: var[3].sqrt(),
        sigma_centre: Some(cell.sigma),
        cell: Some(cell.ij),
        gradient: Some(f),
        central: Some(stencil.central),
    }
}

fn norm(v: [f64; 2]) -> f64 {
    v[0].hypot(v[1])
}

/// The median nearest-neighbour distance of the points, px.
fn typical_spacing(valid: &[(usize, [f64; 2])]) -> Option<f64> {
    let (mut x0, mut y0, mut x1, mut y1) = (
        f64::INFINITY,
        f64::INFINITY,
        f64::NEG_INFINITY,
        f64::NEG_INFINITY,
    );
    for (_, p) in valid {
        x0 = x0.min(p[0]);
        y0 = y0.min(p[1]);
        x1 = x1.max(p[0]);
        y1 = y1.max(p[1]);
    }
    // Buckets about one spacing wide for a full lattice; grown until most
    // points find a neighbour within them.
    let mut size = (((x1 - x0).max(1.0) * (y1 - y0).max(1.0)) / valid.len() as f64)
        .sqrt()
        .max(1.0);
    for _ in 0..8 {
        let b = Buckets::new(valid.iter().map(|v| v.1), size);
        let mut d: Vec<f64> = (0..valid.len())
            .filter_map(|k| nearest_other(&b, valid, k, size))
            .collect();
        if 2 * d.len() >= valid.len() {
            d.sort_unstable_by(f64::total_cmp);
            return Some(d[d.len() / 2]);
        }
        size *= 2.0;
    }
    None
}

/// The point nearest the points' middle with a neighbour direction closest
/// to `+x` and another, not parallel to it, closest to `+y`: its index and
/// the two steps.
fn seed_basis(
    valid: &[(usize, [f64; 2])],
    index: &Buckets,
    spacing: f64,
) -> Option<(usize, [f64; 2], [f64; 2])> {
    let n = valid.len() as f64;
    let mid = valid
        .iter()
        .fold([0.0, 0.0], |m, (_, p)| [m[0] + p[0] / n, m[1] + p[1] / n]);
    let mut order: Vec<usize> = (0..valid.len()).collect();
    let dist = |k: usize| (valid[k].1[0] - mid[0]).hypot(valid[k].1[1] - mid[1]);
    order.sort_by(|&a, &b| dist(a).total_cmp(&dist(b)));
    for &k in order.iter().take(16) {
        let p = valid[k].1;
        let near: Vec<[f64; 2]> = index
            .within(|j| valid[j].1, p, 1.4 * spacing)
            .filter(|&j| j != k)
            .map(|j| [valid[j].1[0] - p[0], valid[j].1[1] - p[1]])
            .collect();
        let best = |dir: [f64; 2], not: Option<[f64; 2]>| {
            near.iter()
                .copied()
                .filter(|v| {
                    not.is_none_or(|a| (v[0] * a[0] + v[1] * a[1]).abs() < 0.5 * norm(*v) * norm(a))
                })
                .map(|v| ((v[0] * dir[0] + v[1] * dir[1]) / norm(v), v))
                .filter(|(c, _)| *c > 0.5)
                .max_by(|a, b| a.0.total_cmp(&b.0))
                .map(|(_, v)| v)
        };
        if let Some(a1) = best([1.0, 0.0], None) {
            if let Some(a2) = best([0.0, 1.0], Some(a1)) {
                return Some((k, a1, a2));
            }
        }
    }
    None
}

/// The point of `valid` nearest `q` within `r` (at most the buckets'
/// size).
fn nearest(index: &Buckets, valid: &[(usize, [f64; 2])], q: [f64; 2], r: f64) -> Option<usize> {
    let d = |k: usize| (valid[k].1[0] - q[0]).hypot(valid[k].1[1] - q[1]);
    index
        .within(|k| valid[k].1, q, r)
        .min_by(|&a, &b| d(a).total_cmp(&d(b)))
}

/// Distance from point `k` of `valid` to its nearest other point within
/// `r` (at most the buckets' size).
fn nearest_other(index: &Buckets, valid: &[(usize, [f64; 2])], k: usize, r: f64) -> Option<f64> {
    let q = valid[k].1;
    index
        .within(|j| valid[j].1, q, r)
        .filter(|&j| j != k)
        .map(|j| (valid[j].1[0] - q[0]).hypot(valid[j].1[1] - q[1]))
        .min_by(f64::total_cmp)
}
