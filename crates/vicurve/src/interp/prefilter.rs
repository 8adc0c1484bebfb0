//! The cubic B-spline prefilter of the whole image, in place in the
//! sampler's padded buffer, and the mirrored border of that buffer.
//!
//! Each row, then each column, of samples `s` becomes the coefficients `c`
//! of the cubic B-spline that interpolates it under mirror boundaries: a
//! causal then an anti-causal first-order recursive filter with pole
//! `z = sqrt(3) - 2` and gain 6 (Unser, Aldroubi & Eden 1993; Thévenaz,
//! Blu & Unser 2000), [`prefilter_line`]. The rows are filtered by groups
//! of [`ROWS`], their recursions interleaved; the columns by strips of
//! [`STRIP`] adjacent columns, each strip's recursions run down the rows on
//! all its columns at once (contiguous in memory, no transpose). Every row
//! and column still goes through exactly the floating-point operations of
//! [`prefilter_line`], in the same order, so the coefficients are
//! bit-identical to filtering each line alone.

use rayon::prelude::*;

/// The pole of the cubic B-spline prefilter, `sqrt(3) - 2`.
const POLE: f64 = -0.267_949_192_431_122_7;

/// `|z|^40 < 1e-22`: beyond 40 terms the causal filter's first
/// coefficient no longer changes in f64.
const HORIZON: usize = 40;

/// Columns filtered together by one task (256 bytes of each row).
const STRIP: usize = 32;

/// Rows filtered together, their recursions interleaved: one row's
/// recursion is a chain of dependent multiply-adds, bound by their latency;
/// eight independent chains keep the arithmetic units busy.
const ROWS: usize = 8;

/// The gain of the two recursions, `(1 - z) (1 - 1/z)` (6).
fn gain(z: f64) -> f64 {
    (1.0 - z) * (1.0 - 1.0 / z)
}

/// Prefilter the `w x h` samples stored at rows `pad..pad + h`, columns
/// `pad..pad + w` of `buf` (rows of `stride` values), in place: rows, then
/// columns. The border (the `pad` rows and columns around) is not read
/// nor written.
pub(super) fn prefilter_2d_in(buf: &mut [f64], w: usize, h: usize, stride: usize, pad: usize) {
    let interior = &mut buf[pad * stride..(pad + h) * stride];
    interior.par_chunks_mut(ROWS * stride).for_each(|group| {
        let mut rows: Vec<&mut [f64]> = group
            .chunks_exact_mut(stride)
            .map(|row| &mut row[pad..pad + w])
            .collect();
        if rows.len() == ROWS && w > HORIZON {
            prefilter_rows(&mut rows);
        } else {
            rows.into_iter().for_each(prefilter_line);
        }
    });
    if h <= HORIZON {
        // Short columns: the exact mirrored sum of `initial_causal`, one
        // column at a time (small images only).
        let mut col = vec![0.0; h];
        for x in pad..pad + w {
            for (y, v) in col.iter_mut().enumerate() {
                *v = interior[y * stride + x];
            }
            prefilter_line(&mut col);
            for (y, v) in col.iter().enumerate() {
                interior[y * stride + x] = *v;
            }
        }
        return;
    }
    // Each strip: its row segments, top to bottom.
    let strips = w.div_ceil(STRIP);
    let mut segments: Vec<Vec<&mut [f64]>> = (0..strips).map(|_| Vec::with_capacity(h)).collect();
    for row in interior.chunks_exact_mut(stride) {
        for (strip, seg) in segments.iter_mut().zip(row[pad..pad + w].chunks_mut(STRIP)) {
            strip.push(seg);
        }
    }
    segments
        .into_par_iter()
        .for_each(|mut rows| prefilter_columns(&mut rows));
}

/// [`prefilter_line`] on each of the [`ROWS`] rows of `rows` (all of one
/// length, more than [`HORIZON`]), the rows' recursions interleaved: the
/// same operations on each row, in the same order.
fn prefilter_rows(rows: &mut [&mut [f64]]) {
    let z = POLE;
    let g = gain(z);
    let n = rows[0].len();
    let mut prev = [0.0; ROWS];
    for (r, row) in rows.iter_mut().enumerate() {
        // `initial_causal`'s sum over the gained samples 0..=HORIZON.
        let mut zk = 1.0;
        let mut sum = 0.0;
        for v in &row[..=HORIZON] {
            sum += zk * (*v * g);
            zk *= z;
        }
        row[0] = sum;
        prev[r] = sum;
    }
    // Causal: c[k] = g s[k] + z c[k - 1].
    for k in 1..n {
        for (row, p) in rows.iter_mut().zip(prev.iter_mut()) {
            let c = row[k] * g + z * *p;
            row[k] = c;
            *p = c;
        }
    }
    // The last anti-causal coefficient, then the anti-causal recursion.
    let last = z / (z * z - 1.0);
    let mut next = [0.0; ROWS];
    for (row, q) in rows.iter_mut().zip(next.iter_mut()) {
        let c = last * (z * row[n - 2] + row[n - 1]);
        row[n - 1] = c;
        *q = c;
    }
    for k in (0..n - 1).rev() {
        for (row, q) in rows.iter_mut().zip(next.iter_mut()) {
            let c = z * (*q - row[k]);
            row[k] = c;
            *q = c;
        }
    }
}

/// [`prefilter_line`] on every column of `rows` (the row segments of a
/// strip, top to bottom, all of one length; more than [`HORIZON`] rows),
/// the recursions run row after row.
fn prefilter_columns(rows: &mut [&mut [f64]]) {
    let z = POLE;
    let g = gain(z);
    let n = rows.len();
    let width = rows[0].len();
    // The first causal coefficient from the gained samples 0..=HORIZON:
    // `initial_causal`'s sum, term by term in the same order.
    let mut sum = vec![0.0; width];
    let mut zk = 1.0;
    for row in rows.iter().take(HORIZON + 1) {
        for (acc, v) in sum.iter_mut().zip(row.iter()) {
            *acc += zk * (*v * g);
        }
        zk *= z;
    }
    rows[0].copy_from_slice(&sum);
    // Causal: c[k] = g s[k] + z c[k - 1].
    for k in 1..n {
        let (done, rest) = rows.split_at_mut(k);
        let prev = &done[k - 1];
        for (c, p) in rest[0].iter_mut().zip(prev.iter()) {
            *c = *c * g + z * p;
        }
    }
    // The last anti-causal coefficient, then the anti-causal recursion.
    let last = z / (z * z - 1.0);
    {
        let (head, tail) = rows.split_at_mut(n - 1);
        for (c, p) in tail[0].iter_mut().zip(head[n - 2].iter()) {
            *c = last * (z * p + *c);
        }
    }
    for k in (0..n - 1).rev() {
        let (head, tail) = rows.split_at_mut(k + 1);
        for (c, next) in head[k].iter_mut().zip(tail[0].iter()) {
            *c = z * (next - *c);
        }
    }
}

/// Fill the `pad` rows and columns around the `w x h` interior of `buf`
/// (rows of `stride` values) with the interior mirrored about its first
/// and last pixel centres (see [`super::mirror`]).
pub(super) fn mirror_border(buf: &mut [f64], w: usize, h: usize, stride: usize, pad: usize) {
    let left: Vec<usize> = (0..pad)
        .map(|px| super::mirror(px as isize - pad as isize, w))
        .collect();
    let right: Vec<usize> = (0..pad)
        .map(|k| super::mirror((w + k) as isize, w))
        .collect();
    for row in buf[pad * stride..(pad + h) * stride].chunks_exact_mut(stride) {
        for (px, &j) in left.iter().enumerate() {
            row[px] = row[pad + j];
        }
        for (k, &j) in right.iter().enumerate() {
            row[pad + w + k] = row[pad + j];
        }
    }
    for py in (0..pad).chain(pad + h..h + 2 * pad) {
        let from = pad + super::mirror(py as isize - pad as isize, h);
        buf.copy_within(from * stride..(from + 1) * stride, py * stride);
    }
}

/// In place, samples `s` become the coefficients `c` of the cubic B-spline
/// with `(c[k-1] + 4 c[k] + c[k+1]) / 6 = s[k]` under mirror boundaries
/// (`c[-1] = c[1]`, `c[n] = c[n-2]`): a causal then an anti-causal
/// first-order recursive filter with pole `z = sqrt(3) - 2` and gain 6.
pub(super) fn prefilter_line(c: &mut [f64]) {
    let n = c.len();
    if n < 2 {
        return; // One sample: the constant spline, c = s.
    }
    let z = POLE;
    for v in c.iter_mut() {
        *v *= gain(z);
    }
    c[0] = initial_causal(c, z);
    for k in 1..n {
        c[k] += z * c[k - 1];
    }
    c[n - 1] = (z / (z * z - 1.0)) * (z * c[n - 2] + c[n - 1]);
    for k in (0..n - 1).rev() {
        c[k] = z * (c[k + 1] - c[k]);
    }
}

/// First causal coefficient `sum_{k >= 0} z^k s[k]` over the mirrored,
/// infinitely extended sequence.
fn initial_causal(c: &[f64], z: f64) -> f64 {
    let n = c.len();
    if n > HORIZON {
        let mut zk = 1.0;
        let mut sum = 0.0;
        for v in &c[..=HORIZON] {
            sum += zk * v;
            zk *= z;
        }
        return sum;
    }
    // Exact sum over one period 2n - 2 of the mirrored sequence, divided by
    // 1 - z^(2n-2) for the geometric repetition.
    let iz = 1.0 / z;
    let mut zk = z;
    let z_last = z.powi(n as i32 - 1);
    let mut sum = c[0] + z_last * c[n - 1];
    // Sample k also appears at 2n - 2 - k in the period.
    let mut z2k = z_last * z_last * iz;
    for v in &c[1..n - 1] {
        sum += (zk + z2k) * v;
        zk *= z;
        z2k *= iz;
    }
    sum / (1.0 - zk * zk)
}

#[cfg(test)]
mod tests {
    use super::*;

    /// The former prefilter: rows, a transpose, the columns as rows, the
    /// transpose back; then the padded, mirrored copy.
    fn reference(values: &[f64], w: usize, h: usize, pad: usize) -> Vec<f64> {
        let mut v = values.to_vec();
        v.chunks_exact_mut(w).for_each(prefilter_line);
        let mut t = vec![0.0; w * h];
        for y in 0..h {
            for x in 0..w {
                t[x * h + y] = v[y * w + x];
            }
        }
        t.chunks_exact_mut(h).for_each(prefilter_line);
        for x in 0..w {
            for y in 0..h {
                v[y * w + x] = t[x * h + y];
            }
        }
        let stride = w + 2 * pad;
        let mut coef = Vec::new();
        for py in 0..h + 2 * pad {
            let row = &v[super::super::mirror(py as isize - pad as isize, h) * w..][..w];
            for px in 0..pad {
                coef.push(row[super::super::mirror(px as isize - pad as isize, w)]);
            }
            coef.extend_from_slice(row);
            for k in 0..pad {
                coef.push(row[super::super::mirror((w + k) as isize, w)]);
            }
        }
        assert_eq!(coef.len(), stride * (h + 2 * pad));
        coef
    }

    #[test]
    fn bit_identical_to_filtering_each_line_alone() {
        let mut seed = 7u64;
        let mut next = || {
            seed = seed
                .wrapping_mul(6_364_136_223_846_793_005)
                .wrapping_add(1_442_695_040_888_963_407);
            (seed >> 11) as f64 / (1u64 << 53) as f64
        };
        let pad = 2;
        for (w, h) in [
            (1, 1),
            (1, 60),
            (60, 1),
            (2, 2),
            (7, 41),
            (41, 7),
            (40, 40),
            (33, 45),
            (100, 97),
            (64, 130),
            (45, 8),
            (45, 17),
        ] {
            let values: Vec<f64> = (0..w * h).map(|_| next()).collect();
            let stride = w + 2 * pad;
            let mut buf = vec![f64::NAN; stride * (h + 2 * pad)];
            for y in 0..h {
                buf[(y + pad) * stride + pad..][..w].copy_from_slice(&values[y * w..][..w]);
            }
            prefilter_2d_in(&mut buf, w, h, stride, pad);
            mirror_border(&mut buf, w, h, stride, pad);
            let want = reference(&values, w, h, pad);
            let same = buf
                .iter()
                .zip(&want)
                .all(|(a, b)| a.to_bits() == b.to_bits());
            assert!(same, "{w}x{h}");
        }
    }
}
