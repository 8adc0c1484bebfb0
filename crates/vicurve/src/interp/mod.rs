//! Image interpolation with gradients.
//!
//! The fit samples the image at about `10^5` sub-pixel points per iteration,
//! so [`Sampler::value`] and [`Sampler::value_gradient`] are inlined,
//! allocation-free and nearly branch-free: all preparation (copying the image
//! into a mirrored, padded buffer and, for cubic B-splines, the prefilter) is
//! done once in [`Sampler::new`]. A bilinear sampler, whose stencil never
//! leaves the image, shares the image's pixels instead (no copy: tracking
//! reads only pixel values, see [`crate::fit::measure_tracked`]).
//!
//! Coordinates are pixels with pixel centres at integers (see
//! [`crate::image`]); the interpolants are defined on
//! `[0, width - 1] x [0, height - 1]`, the rectangle of pixel centres.
//! Neighbours beyond the border are taken from the image mirrored about its
//! first and last pixel centres (`f(-k) = f(k)`, `f(w - 1 + k) = f(w - 1 -
//! k)`), so the whole rectangle is valid for every kind.

use rayon::prelude::*;
use std::fmt;
use std::str::FromStr;
use std::sync::Arc;

use crate::error::{Error, Result};
use crate::image::Image;
use crate::tone::Tone;

mod prefilter;

/// How gray levels between pixel centres are computed.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Default, serde::Serialize, serde::Deserialize)]
#[serde(rename_all = "snake_case")]
pub enum Interpolation {
    /// Bilinear: continuous, gradient discontinuous across pixel centre
    /// lines; reproduces `a x + b y + c x y + d` exactly. Fastest.
    #[default]
    Bilinear,
    /// Cubic B-spline interpolation (Unser 1993): the image is prefiltered
    /// so that the `C^2` cubic spline passes through every pixel value;
    /// smooth gradients, reproduces cubic polynomials away from the border.
    CubicBSpline,
    /// Keys cubic convolution with `a = -1/2` (Catmull-Rom): interpolating,
    /// `C^1`, no prefilter, reproduces quadratics away from the border.
    Keys,
}

impl Interpolation {
    /// Every kind, in declaration order.
    pub const ALL: [Interpolation; 3] = [
        Interpolation::Bilinear,
        Interpolation::CubicBSpline,
        Interpolation::Keys,
    ];

    /// The name used in configuration files and on the command line
    /// (`bilinear`, `cubic_b_spline`, `keys`), the same as its serde name.
    pub fn name(self) -> &'static str {
        match self {
            Interpolation::Bilinear => "bilinear",
            Interpolation::CubicBSpline => "cubic_b_spline",
            Interpolation::Keys => "keys",
        }
    }
}

impl fmt::Display for Interpolation {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        f.write_str(self.name())
    }
}

impl FromStr for Interpolation {
    type Err = Error;

    /// Parses [`Interpolation::name`] or the front ends' short names:
    /// `cubic` (and `cubic_bspline`) for the cubic B-spline, `linear` for
    /// bilinear; case is ignored and `-` is read as `_`. This is the one
    /// parser of the command line's `--interp` and Python's
    /// `interpolation=`. Errors: [`Error::InvalidParameter`] naming the
    /// accepted values.
    fn from_str(s: &str) -> Result<Self> {
        let norm = s.trim().to_ascii_lowercase().replace('-', "_");
        match norm.as_str() {
            "cubic" | "cubic_bspline" => return Ok(Interpolation::CubicBSpline),
            "linear" => return Ok(Interpolation::Bilinear),
            _ => {}
        }
        Interpolation::ALL
            .into_iter()
            .find(|k| k.name() == norm)
            .ok_or_else(|| {
                Error::invalid(
                    "interpolation",
                    format!("'{s}' (expected cubic, bilinear or keys)"),
                )
            })
    }
}

/// How far from a multiple of the step a pixel read through the cubic
/// prefilter may be (in steps) and still count as one
/// ([`Sampler::quantum`]): the prefilter's rounding is about `1e-12`.
const QUANTUM_TOLERANCE: f64 = 1e-6;
/// [`Sampler::pixel_noise`] keeps this share of the pixels' second
/// differences, the smallest.
const NOISE_KEPT: f64 = 0.9;
/// `E[Z^2 | |Z| < z]` for a standard normal `Z` and `P(|Z| < z) =
/// NOISE_KEPT` (`z = 1.6449`): `1 - 2 z phi(z) / NOISE_KEPT`.
const NOISE_TRIMMED_MOMENT: f64 = 0.623_015;

/// Padding (pixels) of the mirrored buffer on each side: the 4x4 cubic
/// stencil at a point of the last cell reaches two pixels beyond.
const PAD: usize = 2;

/// Pixels of the regular subsample the image-wide statistics read at most
/// (about: one every `width height / SUBSAMPLE`).
const SUBSAMPLE: usize = 65_536;

/// An image prepared for interpolation.
#[derive(Clone, Debug)]
pub struct Sampler {
    kind: Interpolation,
    width: usize,
    height: usize,
    /// `width - 1` and `height - 1`, the domain's upper bounds.
    x_max: f64,
    y_max: f64,
    /// Largest left/top cell index of the bilinear stencil, `max(w, 2) - 2`:
    /// the last pixel centre uses the cell on its left, so its gradient is
    /// that cell's, not the (mirrored, zero-mean) one beyond.
    cell_x_max: usize,
    cell_y_max: usize,
    /// Row length of `coef`: `width + 2 pad`.
    stride: usize,
    /// Padding of `coef` on each side: `PAD`, or 0 for a bilinear sampler
    /// (its stencil never leaves the image), which then shares the image's
    /// pixels.
    pad: usize,
    /// Pixel values (bilinear, Keys) or spline coefficients (cubic
    /// B-spline), mirrored into a `(width + 2 pad) x (height + 2 pad)`
    /// frame.
    coef: Arc<Vec<f64>>,
    /// The image's own pixels, row after row, shared with the image (not
    /// copied): what a binned level of the image is made of
    /// ([`Sampler::image_pixels`]); empty for a binned level itself.
    pixels: Arc<Vec<f64>>,
    /// [`Sampler::gray_range`], computed on first use and shared by clones.
    range: Arc<std::sync::OnceLock<f64>>,
    /// [`Sampler::quantum`], likewise.
    quantum: Arc<std::sync::OnceLock<Option<f64>>>,
    /// [`Sampler::pixel_noise`], likewise.
    pixel_noise: Arc<std::sync::OnceLock<f64>>,
    /// [`Sampler::clip_levels`], likewise (or set by the sampler a linear
    /// one was made from).
    clip: Arc<std::sync::OnceLock<Option<(f64, f64)>>>,
    /// [`Sampler::linear`]: the samplers of the image in linear light made
    /// so far, by tone curve, shared by clones.
    linear: Arc<std::sync::Mutex<LinearSamplers>>,
}

/// [`Sampler::linear`]'s list: each tone curve with its sampler.
type LinearSamplers = Vec<(Tone, Arc<Sampler>)>;

/// Samplers of an image in linear light [`Sampler::linear`] keeps at most
/// (each a copy of the image): one for an explicit tone curve, or the few
/// an image's objects read.
const LINEAR_KEPT: usize = 2;

impl Sampler {
    /// Prepares `image` for interpolation of the given kind: `O(w h)` time,
    /// one padded copy of the image in memory; bilinear interpolation
    /// instead shares the image's pixels (no copy, constant time). The
    /// sampler shares the image's pixels either way (a fit's coarse stages
    /// bin them), so they stay in memory as long as it does.
    pub fn new(image: &Image, kind: Interpolation) -> Self {
        Sampler::with_pixels(image, kind, true)
    }

    /// [`Sampler::new`] for a binned level of an image (`fit::pyramid`) of
    /// `w x h` pixels, row `j` of which `row(j, out)` writes into `out`
    /// (`w` values, zero before), the rows in parallel: straight into the
    /// padded coefficients, with no image in between (a megapixel image's
    /// level by 2 x 2 blocks is 2 MB, and a fresh buffer costs a page
    /// fault per 4 KiB written). It keeps no pixels of its own to bin
    /// further (a bilinear level's coefficients are its pixels).
    pub(crate) fn binned_level(
        w: usize,
        h: usize,
        kind: Interpolation,
        row: impl Fn(usize, &mut [f64]) + Sync,
    ) -> Self {
        if kind == Interpolation::Bilinear && w >= 2 && h >= 2 {
            let mut data = vec![0.0; w * h];
            data.par_chunks_mut(w)
                .enumerate()
                .for_each(|(j, out)| row(j, out));
            return Sampler::with_coef(kind, w, h, 0, Arc::new(data), Arc::default());
        }
        Sampler::padded(w, h, kind, Arc::default(), |coef, stride| {
            coef[PAD * stride..(PAD + h) * stride]
                .par_chunks_mut(stride)
                .enumerate()
                .for_each(|(j, out)| row(j, &mut out[PAD..PAD + w]));
        })
    }

    /// [`Sampler::new`], keeping the image's pixels when `keep`.
    fn with_pixels(image: &Image, kind: Interpolation, keep: bool) -> Self {
        let pixels = || {
            if keep {
                image.shared_data()
            } else {
                Arc::default()
            }
        };
        let (w, h) = (image.width(), image.height());
        // The bilinear stencil of a point in the domain stays in the image
        // (`cell_x_max`, `cell_y_max`) when both sides have two pixels.
        if kind == Interpolation::Bilinear && w >= 2 && h >= 2 {
            return Sampler::with_coef(kind, w, h, 0, image.shared_data(), pixels());
        }
        // The image copied into the middle of the padded buffer.
        let data = image.data();
        Sampler::padded(w, h, kind, pixels(), |coef, stride| {
            for (y, row) in data.chunks_exact(w).enumerate() {
                coef[(y + PAD) * stride + PAD..][..w].copy_from_slice(row);
            }
        })
    }

    /// The sampler of `w x h` pixels that `fill(coef, stride)` writes
    /// into the middle of the padded buffer `coef` (rows of `stride`
    /// values, zero before): prefiltered there in place for a cubic
    /// B-spline, then its border mirrored.
    fn padded(
        w: usize,
        h: usize,
        kind: Interpolation,
        pixels: Arc<Vec<f64>>,
        fill: impl FnOnce(&mut [f64], usize),
    ) -> Self {
        let stride = w + 2 * PAD;
        let mut coef = crate::pages::with_capacity(stride * (h + 2 * PAD));
        coef.resize(stride * (h + 2 * PAD), 0.0);
        fill(&mut coef, stride);
        if kind == Interpolation::CubicBSpline {
            prefilter::prefilter_2d_in(&mut coef, w, h, stride, PAD);
        }
        prefilter::mirror_border(&mut coef, w, h, stride, PAD);
        Sampler::with_coef(kind, w, h, PAD, Arc::new(coef), pixels)
    }

    fn with_coef(
        kind: Interpolation,
        w: usize,
        h: usize,
        pad: usize,
        coef: Arc<Vec<f64>>,
        pixels: Arc<Vec<f64>>,
    ) -> Sampler {
        Sampler {
            kind,
            width: w,
            height: h,
            x_max: (w - 1) as f64,
            y_max: (h - 1) as f64,
            cell_x_max: w.max(2) - 2,
            cell_y_max: h.max(2) - 2,
            stride: w + 2 * pad,
            pad,
            coef,
            pixels,
            range: Arc::default(),
            quantum: Arc::default(),
            pixel_noise: Arc::default(),
            clip: Arc::default(),
            linear: Arc::default(),
        }
    }

    /// The sampler of this image in linear light by `tone`, made by `make`
    /// the first time and kept for this sampler and its clones (the
    /// objects of one image, a grown edge's steps measure on the same
    /// one), the last [`LINEAR_KEPT`] tone curves.
    ///
    /// Errors: those of `make`.
    pub(crate) fn linear(
        &self,
        tone: Tone,
        make: impl FnOnce() -> crate::error::Result<Sampler>,
    ) -> crate::error::Result<Arc<Sampler>> {
        // A panic elsewhere while holding the lock leaves a usable list.
        let mut kept = self.linear.lock().unwrap_or_else(|e| e.into_inner());
        if let Some((_, s)) = kept.iter().find(|(t, _)| *t == tone) {
            return Ok(Arc::clone(s));
        }
        let made = Arc::new(make()?);
        if kept.len() == LINEAR_KEPT {
            kept.remove(0);
        }
        kept.push((tone, Arc::clone(&made)));
        Ok(made)
    }

    /// The interpolation kind.
    pub fn kind(&self) -> Interpolation {
        self.kind
    }

    /// Image width in pixels.
    pub fn width(&self) -> usize {
        self.width
    }

    /// Image height in pixels.
    pub fn height(&self) -> usize {
        self.height
    }

    /// The image's pixels as recorded, row after row (`width x height`);
    /// empty for a binned level ([`Sampler::binned_level`]).
    pub(crate) fn image_pixels(&self) -> &[f64] {
        &self.pixels
    }

    /// Whether `(x, y)` lies in the domain `[0, width - 1] x [0, height - 1]`
    /// (false for NaN).
    #[inline]
    pub fn in_domain(&self, x: f64, y: f64) -> bool {
        x >= 0.0 && x <= self.x_max && y >= 0.0 && y <= self.y_max
    }

    /// Interpolated gray level at `(x, y)` (pixels, pixel centres at
    /// integers). `None` outside `[0, width - 1] x [0, height - 1]` or for a
    /// NaN coordinate.
    #[inline]
    pub fn value(&self, x: f64, y: f64) -> Option<f64> {
        if !self.in_domain(x, y) {
            return None;
        }
        Some(match self.kind {
            Interpolation::Bilinear => self.bilinear(x, y).0,
            Interpolation::CubicBSpline => self.cubic_value(x, y, bspline_weights),
            Interpolation::Keys => self.cubic_value(x, y, keys_weights),
        })
    }

    /// [`Sampler::value`] at the point of the domain nearest `(x, y)`: the
    /// image extended beyond its border by its border's values. `None` for
    /// a NaN coordinate.
    pub fn value_clamped(&self, x: f64, y: f64) -> Option<f64> {
        self.value(x.clamp(0.0, self.x_max), y.clamp(0.0, self.y_max))
    }

    /// The recorded gray level of the pixel whose centre is `(x, y)`
    /// (integers; the same as [`Sampler::value`] there, which every
    /// interpolation kind reproduces): read from the image's own pixels
    /// when the sampler keeps them (all but a binned level), else from
    /// the bilinear or Keys coefficients (the pixels themselves) or, for a
    /// binned cubic level, the spline (equal to rounding). `None` outside
    /// the image.
    #[inline]
    pub fn pixel(&self, x: usize, y: usize) -> Option<f64> {
        if x >= self.width || y >= self.height {
            return None;
        }
        if let Some(&v) = self.pixels.get(y * self.width + x) {
            return Some(v);
        }
        Some(match self.kind {
            Interpolation::Bilinear | Interpolation::Keys => {
                self.coef[(y + self.pad) * self.stride + x + self.pad]
            }
            Interpolation::CubicBSpline => self.cubic_node(x, y),
        })
    }

    /// The image's gray-level range: the 99.5th minus the 0.5th percentile
    /// of a regular subsample of at most about 65,536 pixels (robust to hot
    /// pixels and specks); 0 for an empty image. Computed once per image and
    /// kept (every fit of the image's objects asks for it).
    pub fn gray_range(&self) -> f64 {
        *self.range.get_or_init(|| {
            let mut values = self.subsample();
            if values.is_empty() {
                return 0.0;
            }
            // The two order statistics, as a sort would place them.
            let rank = |q: f64| ((values.len() - 1) as f64 * q).round() as usize;
            let (lo, hi) = (rank(0.005), rank(0.995));
            let (below, &mut top, _) = values.select_nth_unstable_by(hi, f64::total_cmp);
            let bottom = match below.len() {
                n if lo < n => *below.select_nth_unstable_by(lo, f64::total_cmp).1,
                _ => top,
            };
            top - bottom
        })
    }

    /// The step between the image's recorded gray levels when they are
    /// those of an integer format: 1 (integer counts), 1/255 (8-bit files)
    /// or 1/65535 (16-bit files), the coarsest of which every pixel of
    /// [`Sampler::gray_range`]'s subsample is a multiple of; `None` for
    /// other data (floating-point images, or levels rescaled after
    /// reading). Computed once per image and kept.
    ///
    /// Why: rounding to these steps adds a noise of variance `q^2 / 12`
    /// wherever the gray level varies from pixel to pixel by more than a
    /// step (an edge's pixels), even in an image without any other noise.
    pub fn quantum(&self) -> Option<f64> {
        *self.quantum.get_or_init(|| {
            let values = self.subsample();
            [1.0, 1.0 / 255.0, 1.0 / 65535.0].into_iter().find(|q| {
                values.iter().all(|v| {
                    let n = v / q;
                    (n - n.round()).abs() < QUANTUM_TOLERANCE
                })
            })
        })
    }

    /// The standard deviation of the noise of the image's pixels (gray
    /// levels), from the second differences `d = p(x-1) - 2 p(x) + p(x+1)`
    /// along the rows, at a regular subsample of at most about 65,536
    /// pixels: the mean of `d^2` over the smallest 90 % of them,
    /// over `6 E[Z^2 | |Z| < z]` for a standard normal `Z` trimmed to the
    /// same share. Shading and the tails of blurred edges, nearly linear
    /// over three pixels, cancel; edges and specks change few pixels,
    /// which the trimming leaves out; texture counts as noise, and so does
    /// rounding to integer levels once the noise dithers it (`q^2 / 12`).
    /// 0 for a noiseless image of flat regions, and for an image less than
    /// 3 pixels wide. Computed once per image and kept.
    pub fn pixel_noise(&self) -> f64 {
        *self.pixel_noise.get_or_init(|| {
            let w = self.width;
            if w < 3 {
                return 0.0;
            }
            let mut squares: Vec<f64> = self
                .subsample_cells()
                .filter(|&(x, _)| (1..w - 1).contains(&x))
                .filter_map(|(x, y)| {
                    let d =
                        self.pixel(x - 1, y)? - 2.0 * self.pixel(x, y)? + self.pixel(x + 1, y)?;
                    Some(d * d)
                })
                .collect();
            let kept = (squares.len() as f64 * NOISE_KEPT) as usize;
            if kept == 0 {
                return 0.0;
            }
            squares.select_nth_unstable_by(kept - 1, f64::total_cmp);
            let mean = squares[..kept].iter().sum::<f64>() / kept as f64;
            (mean / (6.0 * NOISE_TRIMMED_MOMENT)).sqrt()
        })
    }

    /// The recorded levels of a regular subsample of at most about 65,536
    /// pixels, in raster order ([`Sampler::gray_range`], [`Sampler::quantum`]).
    fn subsample(&self) -> Vec<f64> {
        self.subsample_cells()
            .filter_map(|(x, y)| self.pixel(x, y))
            .collect()
    }

    /// The pixels `(x, y)` of the regular subsample the image-wide
    /// statistics read: raster indices `0`, `k`, `2 k`... below `width x
    /// height`, `k = max(1, width height / SUBSAMPLE)`.
    ///
    /// In parallel, in raster order (collected, they are the sequential
    /// loop's): on a large image each read is a cache miss, and the reads
    /// are the statistics' cost.
    fn subsample_cells(&self) -> impl IndexedParallelIterator<Item = (usize, usize)> {
        let (w, h) = (self.width.max(1), self.height);
        let stride = ((w * h) / SUBSAMPLE).max(1);
        (0..(w * h).div_ceil(stride))
            .into_par_iter()
            .map(move |i| (i * stride % w, i * stride / w))
    }

    /// The gray levels at which the image's encoding clips the light, `(0,
    /// 1)`: those of an 8- or 16-bit image (a [`Sampler::quantum`] of 1/255
    /// or 1/65535), and of its linear-light samplers, whose tone curves map
    /// 0 and 1 to themselves. A pixel at one of them may have received
    /// more light (a saturated backlight) or less; the pixel-edge fit takes
    /// it as censored (`correlation`). `None` for other images (floating
    /// point, or integer counts beyond 1), whose range says nothing of a
    /// clip.
    pub fn clip_levels(&self) -> Option<(f64, f64)> {
        *self.clip.get_or_init(|| match self.quantum() {
            Some(q) if q < 1.0 => Some((0.0, 1.0)),
            _ => None,
        })
    }

    /// Set [`Sampler::clip_levels`] (a linear-light sampler takes those of
    /// the image it was made from); no effect once they are known.
    pub(crate) fn set_clip_levels(&self, clip: Option<(f64, f64)>) {
        let _ = self.clip.set(clip);
    }

    /// The variance of the rounding to [`Sampler::quantum`]'s steps `q`,
    /// `q^2 / 12` (gray levels squared; 0 without steps): the least noise
    /// an edge's pixels carry.
    pub fn rounding_variance(&self) -> f64 {
        self.quantum().map_or(0.0, |q| q * q / 12.0)
    }

    /// Interpolated gray level and its gradient `[d/dx, d/dy]` (gray levels
    /// per pixel) at `(x, y)`; same domain as [`Sampler::value`]. For
    /// bilinear interpolation, on a pixel centre line where the gradient
    /// jumps, it is the one of the cell on the right/below (on the left/above
    /// for the last line).
    #[inline]
    pub fn value_gradient(&self, x: f64, y: f64) -> Option<(f64, [f64; 2])> {
        if !self.in_domain(x, y) {
            return None;
        }
        Some(match self.kind {
            Interpolation::Bilinear => self.bilinear(x, y),
            Interpolation::CubicBSpline => self.cubic_value_gradient(x, y, bspline_weights),
            Interpolation::Keys => self.cubic_value_gradient(x, y, keys_weights),
        })
    }

    /// Bilinear value and gradient; `(x, y)` in the domain.
    #[inline(always)]
    fn bilinear(&self, x: f64, y: f64) -> (f64, [f64; 2]) {
        // Non-negative, so `as` truncation is the floor.
        let ix = (x as usize).min(self.cell_x_max);
        let iy = (y as usize).min(self.cell_y_max);
        let (tx, ty) = (x - ix as f64, y - iy as f64);
        let k = (iy + self.pad) * self.stride + ix + self.pad;
        let top = &self.coef[k..k + 2];
        let bottom = &self.coef[k + self.stride..k + self.stride + 2];
        let (dtop, dbottom) = (top[1] - top[0], bottom[1] - bottom[0]);
        let a = top[0] + tx * dtop;
        let b = bottom[0] + tx * dbottom;
        (a + ty * (b - a), [dtop + ty * (dbottom - dtop), b - a])
    }

    /// The 4x4 stencil's first index: the point lies in the cell whose
    /// top-left centre is `(ix, iy)`, neighbours `ix - 1 ..= ix + 2`.
    #[inline(always)]
    fn stencil(&self, x: f64, y: f64) -> (usize, f64, f64) {
        let ix = x as usize;
        let iy = y as usize;
        let k = (iy + PAD - 1) * self.stride + ix + PAD - 1;
        (k, x - ix as f64, y - iy as f64)
    }

    /// The cubic B-spline interpolant at the pixel centre `(x, y)` (in the
    /// image): at a node the basis weights are 1/6, 4/6, 1/6 and 0, so three
    /// rows of three taps, summed in [`Sampler::cubic_value`]'s order (the
    /// same value to the last bit, for a third of the work: the image's
    /// noise, range and quantum read every pixel of a subsample).
    #[inline(always)]
    fn cubic_node(&self, x: usize, y: usize) -> f64 {
        const W: [f64; 3] = [1.0 / 6.0, 4.0 / 6.0, 1.0 / 6.0];
        let k = (y + PAD - 1) * self.stride + x + PAD - 1;
        let mut v = 0.0;
        for (r, wr) in W.iter().enumerate() {
            let row = &self.coef[k + r * self.stride..k + r * self.stride + 3];
            v += wr * (W[0] * row[0] + W[1] * row[1] + W[2] * row[2]);
        }
        v
    }

    /// Separable 4x4 interpolation value; `(x, y)` in the domain.
    #[inline(always)]
    fn cubic_value(&self, x: f64, y: f64, weights: impl Fn(f64) -> Weights) -> f64 {
        let (k, tx, ty) = self.stencil(x, y);
        let wx = weights(tx).w;
        let wy = weights(ty).w;
        let mut v = 0.0;
        for (r, wyr) in wy.iter().enumerate() {
            let row = &self.coef[k + r * self.stride..k + r * self.stride + 4];
            v += wyr * (wx[0] * row[0] + wx[1] * row[1] + wx[2] * row[2] + wx[3] * row[3]);
        }
        v
    }

    /// Separable 4x4 interpolation value and gradient; `(x, y)` in the domain.
    #[inline(always)]
    fn cubic_value_gradient(
        &self,
        x: f64,
        y: f64,
        weights: impl Fn(f64) -> Weights,
    ) -> (f64, [f64; 2]) {
        let (k, tx, ty) = self.stencil(x, y);
        let (wx, wy) = (weights(tx), weights(ty));
        let (mut v, mut gx, mut gy) = (0.0, 0.0, 0.0);
        for r in 0..4 {
            let row = &self.coef[k + r * self.stride..k + r * self.stride + 4];
            let along = wx.w[0] * row[0] + wx.w[1] * row[1] + wx.w[2] * row[2] + wx.w[3] * row[3];
            let slope = wx.d[0] * row[0] + wx.d[1] * row[1] + wx.d[2] * row[2] + wx.d[3] * row[3];
            v += wy.w[r] * along;
            gx += wy.w[r] * slope;
            gy += wy.d[r] * along;
        }
        (v, [gx, gy])
    }
}

/// Weights of the four neighbours `-1, 0, 1, 2` of a cell at fractional
/// position `t in [0, 1]`, and their derivatives with respect to `t`.
struct Weights {
    w: [f64; 4],
    d: [f64; 4],
}

/// Cubic B-spline basis at distances `1 + t, t, 1 - t, 2 - t`.
#[inline(always)]
fn bspline_weights(t: f64) -> Weights {
    let s = 1.0 - t;
    let t2 = t * t;
    let t3 = t2 * t;
    Weights {
        w: [
            s * s * s / 6.0,
            (3.0 * t3 - 6.0 * t2 + 4.0) / 6.0,
            (-3.0 * t3 + 3.0 * t2 + 3.0 * t + 1.0) / 6.0,
            t3 / 6.0,
        ],
        d: [
            -0.5 * s * s,
            1.5 * t2 - 2.0 * t,
            -1.5 * t2 + t + 0.5,
            0.5 * t2,
        ],
    }
}

/// Keys cubic convolution kernel (`a = -1/2`) at distances `1 + t, t,
/// 1 - t, 2 - t`.
#[inline(always)]
fn keys_weights(t: f64) -> Weights {
    let t2 = t * t;
    let t3 = t2 * t;
    Weights {
        w: [
            0.5 * (-t3 + 2.0 * t2 - t),
            0.5 * (3.0 * t3 - 5.0 * t2 + 2.0),
            0.5 * (-3.0 * t3 + 4.0 * t2 + t),
            0.5 * (t3 - t2),
        ],
        d: [
            0.5 * (-3.0 * t2 + 4.0 * t - 1.0),
            0.5 * (9.0 * t2 - 10.0 * t),
            0.5 * (-9.0 * t2 + 8.0 * t + 1.0),
            0.5 * (3.0 * t2 - 2.0 * t),
        ],
    }
}

/// Index in `0..n` of index `k` of the sequence mirrored about its first and
/// last samples (period `2 n - 2`; constant when `n == 1`).
fn mirror(k: isize, n: usize) -> usize {
    if n == 1 {
        return 0;
    }
    let period = 2 * (n as isize - 1);
    let r = k.rem_euclid(period) as usize;
    if r < n {
        r
    } else {
        period as usize - r
    }
}
