//! Corners of a traced start ([`super::AllConfig::corners`]): the `n`
//! sharpest turns of a closed boundary, as break positions for the fit
//! (cells of a square grid, square holes, nuts), so that each side is
//! measured as its own smooth curve instead of a spline rounding the
//! corners.

/// Least turn (rad) for a corner: 30 degrees between the boundary's
/// chords before and after it. Over the window `h = L / (6 n)` a circle's
/// chords turn by `h / r = pi / (3 n)` whatever its radius (15 degrees for
/// `n = 4`), a square's corner by 90.
const MIN_TURN: f64 = 0.52;

/// Arc lengths (px, from the first point, in `[0, L)`) of the `n` sharpest
/// corners of the closed polyline `points` (about a pixel apart, as a
/// smoothed traced boundary), in increasing order; `None` when fewer than
/// `n` corners turn by `MIN_TURN` (30 degrees) or more, or the polyline is too short
/// for `n` corners (under 8 px a side).
///
/// The turn at a point is the angle between the chords to the points a
/// window `h` before and after it (`h = L / (6 n)`, 2 to 8 px: past the
/// rounding the smoothing and blur give a corner, within a side); corners
/// are taken greatest turn first, each at least `L / (2 n)` from the others.
pub fn corner_breaks(points: &[[f64; 2]], n: usize) -> Option<Vec<f64>> {
    let m = points.len();
    if n == 0 || m < 4 * n {
        return None;
    }
    let mut s = Vec::with_capacity(m + 1);
    s.push(0.0);
    for k in 0..m {
        let (p, q) = (points[k], points[(k + 1) % m]);
        s.push(s[k] + (q[0] - p[0]).hypot(q[1] - p[1]));
    }
    let length = s[m];
    if length.is_nan() || length < 8.0 * n as f64 {
        return None;
    }
    let h = (length / (6.0 * n as f64)).clamp(2.0, 8.0);
    // The point `h` px of arc before or after point k (to the nearest
    // vertex), by walking along the closed polyline.
    let offset = |k: usize, ahead: bool| {
        let (mut j, mut walked) = (k, 0.0);
        while walked < h {
            let next = if ahead { (j + 1) % m } else { (j + m - 1) % m };
            let (p, q) = (points[j], points[next]);
            walked += (q[0] - p[0]).hypot(q[1] - p[1]);
            j = next;
            if j == k {
                break;
            }
        }
        points[j]
    };
    let turn: Vec<f64> = (0..m)
        .map(|k| {
            let (a, p, b) = (offset(k, false), points[k], offset(k, true));
            let d1 = [p[0] - a[0], p[1] - a[1]];
            let d2 = [b[0] - p[0], b[1] - p[1]];
            let cross = d1[0] * d2[1] - d1[1] * d2[0];
            let dot = d1[0] * d2[0] + d1[1] * d2[1];
            cross.atan2(dot).abs()
        })
        .collect();
    let apart = length / (2.0 * n as f64);
    let mut order: Vec<usize> = (0..m).collect();
    order.sort_by(|&a, &b| turn[b].total_cmp(&turn[a]));
    let mut chosen: Vec<f64> = Vec::with_capacity(n);
    for k in order {
        if chosen.len() == n || turn[k] < MIN_TURN {
            break;
        }
        let far = chosen.iter().all(|&c| {
            let d = (s[k] - c).abs();
            d.min(length - d) >= apart
        });
        if far {
            chosen.push(s[k]);
        }
    }
    if chosen.len() < n {
        return None;
    }
    chosen.sort_by(f64::total_cmp);
    Some(chosen)
}
