//! The whole object's image: its region blurred and integrated over each
//! square pixel, by a line integral along its curve (module docs of
//! [`super`]).

use super::super::schedule::MIN_CLOSED_ELEMENTS;
use crate::curve::{polygon_contains, SplineCurve};
use crate::interp::Sampler;
use crate::spline::Basis;
use crate::virtual_image::pixel_edge::{normal_cdf_pdf, spread_variance};

/// Quadrature points along the curve at most this many spreads apart.
const STEP_SPREADS: f64 = 1.0 / 3.0;
/// ... and at most this many pixels.
const MAX_STEP: f64 = 0.5;

/// The whole spread (pixels) of a blur of `blur` px: the optics' and the
/// pixel's own in quadrature.
pub(super) fn spread(blur: f64) -> f64 {
    spread_variance(blur).sqrt()
}

/// The quadrature's longest piece along the curve under a blur of `blur`
/// px, pixels of parameter.
pub(super) fn quadrature_step(blur: f64) -> f64 {
    (STEP_SPREADS * spread(blur)).min(MAX_STEP)
}

/// The work of one rendering of a closed curve `length` px long under a
/// blur of `blur` px at `pixels` pixels: pixels times quadrature points
/// (three on each piece of [`quadrature_step`]).
pub(crate) fn rendering_work(length: f64, blur: f64, pixels: f64) -> f64 {
    pixels * 3.0 * length / quadrature_step(blur)
}

/// The share of each pixel's light that comes from the region `curve`
/// (closed) bounds, through a Gaussian blur of `blur` px (the rendering of
/// the module docs), at the centres of the `size[0] x size[1]` pixels
/// from `origin`, row after row: what a noiseless camera records of the
/// object, between 0 and 1. `None` for an open curve or one of no area.
pub(crate) fn region_light(
    curve: &SplineCurve,
    blur: f64,
    origin: [usize; 2],
    size: [usize; 2],
) -> Option<Vec<f64>> {
    if !(curve.is_closed() && blur.is_finite() && blur >= 0.0) {
        return None;
    }
    // A blur of 0 leaves the box's edges sharp; a hair of blur keeps the
    // quadrature's integrand smooth, far below a pixel's share of 1e-3.
    let blur = blur.max(0.05);
    let basis = Basis::new(3, MIN_CLOSED_ELEMENTS, curve.param_length(), true).ok()?;
    let quad = Quadrature::new(curve, &basis, quadrature_step(blur))?;
    let window = Window {
        origin,
        size,
        pixels: (0..size[0] * size[1])
            .map(|i| Pixel {
                col: i % size[0],
                row: i / size[0],
                g: 0.0,
            })
            .collect(),
    };
    let mut shape = Shape::default();
    quad.shape_into(&basis, &vec![0.0; basis.n_functions()], &mut shape);
    let mut tables = Tables::default();
    shape.tables_into(blur, &window, &mut tables);
    Some(
        window
            .pixels
            .iter()
            .map(|p| shape.render(p, &tables).w)
            .collect(),
    )
}

/// The pixels the whole-object fit compares, in a rectangle of the image.
pub(super) struct Window {
    /// The rectangle's first column and row.
    origin: [usize; 2],
    /// Its columns and rows.
    size: [usize; 2],
    /// The pixels.
    pub(super) pixels: Vec<Pixel>,
}

/// A window pixel: its column and row in the window's rectangle, and its
/// gray level.
#[derive(Clone, Copy)]
pub(super) struct Pixel {
    col: usize,
    row: usize,
    pub(super) g: f64,
}

/// Points equally spaced on the reference's parameter, with what the
/// rendering needs of them.
pub(super) struct Quadrature {
    /// The points' weights, pixels of parameter.
    weight: Vec<f64>,
    /// The reference's points.
    x0: Vec<[f64; 2]>,
    /// Its first derivatives.
    d0: Vec<[f64; 2]>,
    /// Its outward unit normals `n0`.
    n0: Vec<[f64; 2]>,
    /// The outward normal's rate of change along `x0'`: `n0' = turn x0'`.
    turn: Vec<f64>,
    /// The displacement basis: first function, values, derivatives.
    basis: Vec<(usize, [f64; 4], [f64; 4])>,
    /// `n0` in units of the reference frame's (left) normal: -1 when the
    /// region lies on the curve's left, 1 otherwise.
    pub(super) outward: f64,
}

impl Quadrature {
    /// The quadrature of `curve`: three Gauss–Legendre points on each
    /// piece between the knots of `curve` and of `basis` (where the
    /// integrands are smooth), pieces at most `step` pixels of parameter
    /// long; `None` for a curve of no area.
    pub(super) fn new(curve: &SplineCurve, basis: &Basis, step: f64) -> Option<Quadrature> {
        let nodes = gauss_nodes(&knots(curve, basis), step);
        let area = curve.area()?;
        // The signed area (Green's theorem), for the orientation.
        let signed: f64 = nodes
            .iter()
            .map(|&(t, w)| {
                let [p, d, _] = curve.derivatives(t);
                0.5 * (p[0] * d[1] - p[1] * d[0]) * w
            })
            .sum();
        if area.is_nan() || area <= 0.0 || signed == 0.0 {
            return None;
        }
        // Left normal `(-y', x') / |x'|`; the outward normal is `-left`
        // when the region is on the left (positive signed area).
        let outward = -signed.signum();
        let count = nodes.len();
        let mut q = Quadrature {
            weight: Vec::with_capacity(count),
            x0: Vec::with_capacity(count),
            d0: Vec::with_capacity(count),
            n0: Vec::with_capacity(count),
            turn: Vec::with_capacity(count),
            basis: Vec::with_capacity(count),
            outward,
        };
        for &(t, w) in &nodes {
            let [p, d, dd] = curve.derivatives(t);
            let f = crate::curve::frame_from(p, d, dd);
            q.weight.push(w);
            q.x0.push(p);
            q.d0.push(d);
            q.n0.push([outward * f.normal[0], outward * f.normal[1]]);
            // left' = -kappa |x'| T = -kappa x'; n0 = outward * left.
            q.turn.push(-outward * f.curvature);
            let b = basis.eval_derivs(t);
            let mut v = [0.0; 4];
            let mut d1 = [0.0; 4];
            v.copy_from_slice(&b.value[..4]);
            d1.copy_from_slice(&b.d1[..4]);
            q.basis.push((b.first, v, d1));
        }
        Some(q)
    }

    /// The curve `x0 + U n0` of the coefficients `lambda` at the
    /// quadrature points, into `shape` (its storage reused).
    pub(super) fn shape_into(&self, basis: &Basis, lambda: &[f64], shape: &mut Shape) {
        shape.x.clear();
        shape.dy.clear();
        shape.rate.clear();
        shape.region_left = self.outward < 0.0;
        for i in 0..self.x0.len() {
            let (first, v, d1) = &self.basis[i];
            let (mut u, mut du) = (0.0, 0.0);
            for k in 0..4 {
                let c = lambda[basis.index(*first, k)];
                u += c * v[k];
                du += c * d1[k];
            }
            let (p, d, n) = (self.x0[i], self.d0[i], self.n0[i]);
            let stretch = 1.0 + self.turn[i] * u;
            let dx = [d[0] * stretch + du * n[0], d[1] * stretch + du * n[1]];
            shape.x.push([p[0] + u * n[0], p[1] + u * n[1]]);
            shape.dy.push(dx[1] * self.weight[i]);
            // The outward normal times |x'|, dotted with n0, times the
            // weight: the area swept per unit of U.
            let outward = if shape.region_left {
                [dx[1], -dx[0]]
            } else {
                [-dx[1], dx[0]]
            };
            shape
                .rate
                .push((outward[0] * n[0] + outward[1] * n[1]) * self.weight[i]);
        }
    }
}

/// The current curve at the quadrature points.
#[derive(Default)]
pub(super) struct Shape {
    x: Vec<[f64; 2]>,
    /// `y'` times the point's weight.
    dy: Vec<f64>,
    /// Area swept per unit of `U`: `(outward |x'|) . n0` times the weight.
    rate: Vec<f64>,
    /// Whether the region lies on the curve's left.
    region_left: bool,
}

/// A pixel's rendering.
pub(super) struct Rendered {
    /// `W(p)`, the region's share of the pixel's light.
    pub(super) w: f64,
    /// `dW / dblur`.
    pub(super) dw_dblur: f64,
}

impl Shape {
    /// The kernels of every quadrature point at every column and row of
    /// `window` under a blur of `blur`, into `tables` (its storage
    /// reused): the kernel is separable, so a pixel's rendering reads
    /// them instead of evaluating its own.
    pub(super) fn tables_into(&self, blur: f64, window: &Window, tables: &mut Tables) {
        tables.nodes = self.x.len();
        tables.columns.clear();
        tables.rows.clear();
        let [x0, y0] = window.origin.map(|v| v as f64);
        let [width, height] = window.size;
        for col in 0..width {
            let x = x0 + col as f64;
            let kernels = self.x.iter().map(|q| Kernel::at(x - q[0], blur));
            tables.columns.extend(kernels);
        }
        // A row's kernel beyond `cut` is below 1e-15: zero, and skipped.
        let cut = 0.5 + 8.0 * blur;
        for row in 0..height {
            let y = y0 + row as f64;
            tables.rows.extend(self.x.iter().map(|q| {
                let v = y - q[1];
                if v.abs() > cut {
                    Kernel::ZERO
                } else {
                    Kernel::at(v, blur)
                }
            }));
        }
    }

    /// `W(p)` and its derivative in the blur, from `tables`.
    pub(super) fn render(&self, p: &Pixel, tables: &Tables) -> Rendered {
        let (columns, rows) = tables.at(p);
        let (mut w, mut dw) = (0.0, 0.0);
        for ((ku, kv), &dy) in columns.iter().zip(rows).zip(&self.dy) {
            if kv.k == 0.0 && kv.dk == 0.0 {
                continue;
            }
            w += ku.big * kv.k * dy;
            dw += (ku.dbig * kv.k + ku.big * kv.dk) * dy;
        }
        let sign = if self.region_left { -1.0 } else { 1.0 };
        Rendered {
            w: sign * w,
            dw_dblur: sign * dw,
        }
    }

    /// [`Shape::render`], and `dW / dlambda_j` added into `grad`.
    pub(super) fn render_with_gradient(
        &self,
        p: &Pixel,
        tables: &Tables,
        quad: &Quadrature,
        grad: &mut [f64],
    ) -> Rendered {
        let (columns, rows) = tables.at(p);
        let n = grad.len();
        let (mut w, mut dw) = (0.0, 0.0);
        for (i, (ku, kv)) in columns.iter().zip(rows).enumerate() {
            if kv.k == 0.0 && kv.dk == 0.0 {
                continue;
            }
            let dy = self.dy[i];
            w += ku.big * kv.k * dy;
            dw += (ku.dbig * kv.k + ku.big * kv.dk) * dy;
            let density = ku.k * kv.k * self.rate[i];
            if density != 0.0 {
                let (first, values, _) = &quad.basis[i];
                for (k, &b) in values.iter().enumerate() {
                    let j = first + k;
                    grad[if j >= n { j - n } else { j }] += density * b;
                }
            }
        }
        let sign = if self.region_left { -1.0 } else { 1.0 };
        Rendered {
            w: sign * w,
            dw_dblur: sign * dw,
        }
    }
}

/// [`Shape::tables_into`]: the kernels, node by node, of each column and
/// row.
#[derive(Default)]
pub(super) struct Tables {
    nodes: usize,
    columns: Vec<Kernel>,
    rows: Vec<Kernel>,
}

impl Tables {
    /// The kernels of `p`'s column and of its row.
    fn at(&self, p: &Pixel) -> (&[Kernel], &[Kernel]) {
        let n = self.nodes;
        (
            &self.columns[p.col * n..(p.col + 1) * n],
            &self.rows[p.row * n..(p.row + 1) * n],
        )
    }
}

/// The pixel's kernel along one axis at offset `u` (pixels) under a blur
/// of `blur`: `k = box * gauss`, its integral `K` from `-inf`, and their
/// derivatives in the blur.
pub(super) struct Kernel {
    k: f64,
    big: f64,
    dk: f64,
    dbig: f64,
}

impl Kernel {
    /// The kernel far from the pixel, where every term is zero.
    const ZERO: Kernel = Kernel {
        k: 0.0,
        big: 0.0,
        dk: 0.0,
        dbig: 0.0,
    };

    #[inline]
    fn at(u: f64, blur: f64) -> Kernel {
        let (a, b) = ((u + 0.5) / blur, (u - 0.5) / blur);
        let (pa, da) = normal_cdf_pdf(a);
        let (pb, db) = normal_cdf_pdf(b);
        // psi(x) = x Phi(x) + phi(x), psi' = Phi.
        let psi = |x: f64, p: f64, d: f64| x * p + d;
        Kernel {
            k: pa - pb,
            big: blur * (psi(a, pa, da) - psi(b, pb, db)),
            dk: -(a * da - b * db) / blur,
            dbig: da - db,
        }
    }
}

/// The knots of `curve` and of `basis` in `[0, L]`, increasing, each once
/// (both bases are periodic on the same `[0, L)`).
fn knots(curve: &SplineCurve, basis: &Basis) -> Vec<f64> {
    let l = curve.param_length();
    let reference = curve.basis();
    let mut knots: Vec<f64> = (0..reference.n_elements())
        .map(|e| reference.element_bounds(e).0)
        .chain((0..basis.n_elements()).map(|e| basis.element_bounds(e).0))
        .filter(|&t| (0.0..l).contains(&t))
        .chain([0.0, l])
        .collect();
    knots.sort_by(f64::total_cmp);
    knots.dedup_by(|a, b| (*a - *b).abs() <= 1e-9 * l);
    knots
}

/// Three-point Gauss–Legendre nodes `(t, weight)` on each piece between
/// consecutive `knots`, the pieces cut into parts at most `step` long.
fn gauss_nodes(knots: &[f64], step: f64) -> Vec<(f64, f64)> {
    const X: f64 = 0.774_596_669_241_483_4; // sqrt(3/5)
    const W: [f64; 3] = [5.0 / 9.0, 8.0 / 9.0, 5.0 / 9.0];
    let mut nodes = Vec::new();
    for k in knots.windows(2) {
        let parts = ((k[1] - k[0]) / step).ceil().max(1.0) as usize;
        let h = (k[1] - k[0]) / parts as f64;
        for i in 0..parts {
            let c = k[0] + (i as f64 + 0.5) * h;
            for (x, w) in [-X, 0.0, X].into_iter().zip(W) {
                nodes.push((c + 0.5 * h * x, 0.5 * h * w));
            }
        }
    }
    nodes
}

/// The window's pixels: inside the closed polygon `points` or within
/// `margin` pixels of it, in the image.
pub(super) fn window(sampler: &Sampler, points: &[[f64; 2]], margin: f64) -> Window {
    let (w, h) = (sampler.width(), sampler.height());
    let [x0, y0, x1, y1] = points_box(points);
    let clamp = |v: f64, hi: usize| v.max(0.0).min(hi as f64 - 1.0) as usize;
    let (i0, i1) = (
        clamp((x0 - margin).ceil(), w),
        clamp((x1 + margin).floor(), w),
    );
    let (j0, j1) = (
        clamp((y0 - margin).ceil(), h),
        clamp((y1 + margin).floor(), h),
    );
    let mut pixels = Vec::new();
    for j in j0..=j1 {
        for i in i0..=i1 {
            let (x, y) = (i as f64, j as f64);
            if !(polygon_contains(points, [x, y]) || near(points, [x, y], margin)) {
                continue;
            }
            if let Some(g) = sampler.pixel(i, j) {
                pixels.push(Pixel {
                    col: i - i0,
                    row: j - j0,
                    g,
                });
            }
        }
    }
    Window {
        origin: [i0, j0],
        size: [i1 + 1 - i0, j1 + 1 - j0],
        pixels,
    }
}

/// The smallest box `[x0, y0, x1, y1]` holding `points`.
pub(super) fn points_box(points: &[[f64; 2]]) -> [f64; 4] {
    points.iter().fold(
        [f64::MAX, f64::MAX, f64::MIN, f64::MIN],
        |[x0, y0, x1, y1], p| [x0.min(p[0]), y0.min(p[1]), x1.max(p[0]), y1.max(p[1])],
    )
}

/// Points of `curve` at most `step` pixels of parameter apart.
pub(super) fn dense_points(curve: &SplineCurve, step: f64) -> Vec<[f64; 2]> {
    let count = ((curve.param_length() / step).ceil() as usize).max(16);
    curve
        .sample_params(count)
        .into_iter()
        .map(|u| curve.point(u))
        .collect()
}

/// Whether `p` lies within `margin` px of one of `points`.
pub(super) fn near(points: &[[f64; 2]], p: [f64; 2], margin: f64) -> bool {
    let m2 = margin * margin;
    points
        .iter()
        .any(|q| (q[0] - p[0]).powi(2) + (q[1] - p[1]).powi(2) <= m2)
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::render::blur::blurred_coverage;

    /// An ellipse of semi-axes 9 x 5 at (20.3, 18.6), 0.4 rad, as dense
    /// points (counterclockwise on screen when `reversed`).
    fn ellipse(reversed: bool) -> Vec<[f64; 2]> {
        let (c, s) = (0.4_f64.cos(), 0.4_f64.sin());
        let mut pts: Vec<[f64; 2]> = (0..2000)
            .map(|i| {
                let t = i as f64 / 2000.0 * std::f64::consts::TAU;
                let (u, w) = (9.0 * t.cos(), 5.0 * t.sin());
                [20.3 + c * u - s * w, 18.6 + s * u + c * w]
            })
            .collect();
        if reversed {
            pts.reverse();
        }
        pts
    }

    impl Quadrature {
        fn shape(&self, basis: &Basis, lambda: &[f64]) -> Shape {
            let mut shape = Shape::default();
            self.shape_into(basis, lambda, &mut shape);
            shape
        }
    }

    impl Shape {
        fn tables(&self, blur: f64, window: &Window) -> Tables {
            let mut tables = Tables::default();
            self.tables_into(blur, window, &mut tables);
            tables
        }
    }

    /// Every pixel of the `size x size` square from the image's corner,
    /// row after row.
    fn square(size: usize) -> Window {
        Window {
            origin: [0, 0],
            size: [size, size],
            pixels: (0..size * size)
                .map(|i| Pixel {
                    col: i % size,
                    row: i / size,
                    g: 0.0,
                })
                .collect(),
        }
    }

    /// The quadrature of the ellipse's spline and a basis of 10 elements.
    fn quadrature(reversed: bool, blur: f64) -> (Basis, Quadrature) {
        let curve = SplineCurve::fit(&ellipse(reversed), true, 3, 0.5).unwrap();
        let basis = Basis::new(3, 10, curve.param_length(), true).unwrap();
        let step = quadrature_step(blur);
        let quad = Quadrature::new(&curve, &basis, step).unwrap();
        (basis, quad)
    }

    /// `W` is the region's blurred coverage as the library's renderer
    /// makes it (to its own accuracy), either way round the curve.
    #[test]
    fn the_rendering_is_the_blurred_region() {
        for blur in [0.8, 1.5, 2.5] {
            let rendered = blurred_coverage(40, 40, &[ellipse(false)], blur).unwrap();
            for reversed in [false, true] {
                let (basis, quad) = quadrature(reversed, blur);
                let shape = quad.shape(&basis, &vec![0.0; basis.n_functions()]);
                let window = square(40);
                let tables = shape.tables(blur, &window);
                let worst = window
                    .pixels
                    .iter()
                    .zip(&rendered)
                    .map(|(p, r)| (shape.render(p, &tables).w - r).abs())
                    .fold(0.0, f64::max);
                assert!(worst < 1e-3, "blur {blur} reversed {reversed}: {worst:e}");
            }
        }
    }

    /// The quadrature's pieces (a third of the spread, half a pixel at
    /// most) give `W` as a quadrature ten times finer does, to 1e-8 of
    /// the contrast: far below any image's noise.
    #[test]
    fn the_quadrature_is_converged() {
        for blur in [0.8_f64, 1.5, 2.5] {
            let curve = SplineCurve::fit(&ellipse(false), true, 3, 0.5).unwrap();
            let basis = Basis::new(3, 10, curve.param_length(), true).unwrap();
            let lambda: Vec<f64> = (0..10).map(|j| 0.3 * (j as f64 * 0.7).cos()).collect();
            let step = quadrature_step(blur);
            let coarse = Quadrature::new(&curve, &basis, step).unwrap();
            let fine = Quadrature::new(&curve, &basis, 0.1 * step).unwrap();
            let window = square(40);
            let (a, b) = (coarse.shape(&basis, &lambda), fine.shape(&basis, &lambda));
            let (ta, tb) = (a.tables(blur, &window), b.tables(blur, &window));
            let worst = window
                .pixels
                .iter()
                .map(|p| (a.render(p, &ta).w - b.render(p, &tb).w).abs())
                .fold(0.0, f64::max);
            assert!(worst < 1e-8, "blur {blur}: {worst:e}");
        }
    }

    /// The derivatives in `U`'s coefficients and in the blur are those of
    /// `W`.
    #[test]
    fn the_gradient_is_the_rendering_s() {
        let blur = 1.7;
        for reversed in [false, true] {
            let (basis, quad) = quadrature(reversed, blur);
            let n = basis.n_functions();
            let lambda: Vec<f64> = (0..n).map(|j| 0.4 * (j as f64 * 1.3).sin()).collect();
            let shape = quad.shape(&basis, &lambda);
            let window = square(40);
            let tables = shape.tables(blur, &window);
            let e = 1e-6;
            let render = |shape: &Shape, blur: f64, p: &Pixel| {
                shape.render(p, &shape.tables(blur, &window)).w
            };
            for [col, row] in [[20, 18], [28, 22], [13, 15], [21, 24]] {
                let p = Pixel { col, row, g: 0.0 };
                let mut grad = vec![0.0; n];
                let r = shape.render_with_gradient(&p, &tables, &quad, &mut grad);
                let db = (render(&shape, blur + e, &p) - render(&shape, blur - e, &p)) / (2.0 * e);
                assert!((db - r.dw_dblur).abs() < 1e-7, "{db} {}", r.dw_dblur);
                for (j, &gj) in grad.iter().enumerate() {
                    let mut l = lambda.clone();
                    l[j] += e;
                    let up = render(&quad.shape(&basis, &l), blur, &p);
                    l[j] -= 2.0 * e;
                    let down = render(&quad.shape(&basis, &l), blur, &p);
                    let fd = (up - down) / (2.0 * e);
                    assert!(
                        (fd - gj).abs() < 1e-6,
                        "reversed {reversed} j {j}: {fd} {gj}"
                    );
                }
            }
        }
    }

    /// The kernel integrates to 1 and `K` is its integral.
    #[test]
    fn the_kernel_is_a_unit_box_blurred() {
        for blur in [0.4, 1.0, 2.5] {
            let h = 1e-3;
            let mut total = 0.0;
            let mut u = -20.0;
            while u < 20.0 {
                let k = Kernel::at(u + 0.5 * h, blur);
                total += k.k * h;
                let kk = Kernel::at(u + h, blur);
                let k0 = Kernel::at(u, blur);
                assert!(((kk.big - k0.big) / h - k.k).abs() < 1e-5);
                let e = 1e-6;
                let (p, m) = (Kernel::at(u, blur + e), Kernel::at(u, blur - e));
                assert!(((p.k - m.k) / (2.0 * e) - k0.dk).abs() < 1e-6);
                assert!(((p.big - m.big) / (2.0 * e) - k0.dbig).abs() < 1e-6);
                u += h;
            }
            assert!((total - 1.0).abs() < 1e-9, "{total}");
            assert!((Kernel::at(30.0, blur).big - 1.0).abs() < 1e-12);
        }
    }
}
