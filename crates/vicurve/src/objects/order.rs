//! The objects' numbering: row-major by centroid.

use super::RegionInfo;

/// The id of each region of `infos`: sorted by centroid row, gathered into
/// rows (a region whose centroid is within half the median object height
/// of the row's first joins it), each row sorted by centroid column, rows
/// top to bottom. Two images of the same scene, slightly moved or deformed,
/// number their objects alike; a plain sort by `(y, x)` would interleave a
/// row whose centroids differ by a fraction of a pixel.
pub fn row_major(infos: &[RegionInfo]) -> Vec<usize> {
    let n = infos.len();
    if n == 0 {
        return Vec::new();
    }
    let mut heights: Vec<f64> = infos
        .iter()
        .map(|r| (r.bbox[3] - r.bbox[1] + 1) as f64)
        .collect();
    heights.sort_by(f64::total_cmp);
    let tol = 0.5 * heights[n / 2];
    let mut by_y: Vec<usize> = (0..n).collect();
    by_y.sort_by(|&a, &b| infos[a].centroid[1].total_cmp(&infos[b].centroid[1]));
    let mut ids = vec![0; n];
    let mut next = 0;
    let mut k = 0;
    while k < n {
        let y_first = infos[by_y[k]].centroid[1];
        let mut end = k;
        while end < n && infos[by_y[end]].centroid[1] - y_first <= tol {
            end += 1;
        }
        let mut row = by_y[k..end].to_vec();
        row.sort_by(|&a, &b| infos[a].centroid[0].total_cmp(&infos[b].centroid[0]));
        for r in row {
            ids[r] = next;
            next += 1;
        }
        k = end;
    }
    ids
}

#[cfg(test)]
mod tests {
    use super::*;

    fn info(x: f64, y: f64) -> RegionInfo {
        RegionInfo {
            centroid: [x, y],
            pixels: 100,
            boundary: 40,
            bbox: [0, 0, 10, 10],
            touches_border: false,
            gap: f64::INFINITY,
            parent: None,
        }
    }

    #[test]
    fn rows_with_jitter_are_read_left_to_right() {
        // Two rows; the right object of the top row sits 1 px higher.
        let infos = [
            info(50.0, 20.0),
            info(10.0, 21.0),
            info(30.0, 60.0),
            info(80.0, 59.0),
        ];
        assert_eq!(row_major(&infos), vec![1, 0, 2, 3]);
    }
}
