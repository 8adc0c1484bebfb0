//! Points in square buckets: the points within a distance of a query
//! point, for distances up to the buckets' size, by looking only in the
//! query's bucket and its eight neighbours. For point sets the queries
//! would otherwise scan whole (a grid's dots, a curve's dense points).

use std::collections::HashMap;

/// Indices of points in square buckets of a given size, pixels.
pub(crate) struct Buckets {
    size: f64,
    map: HashMap<(i64, i64), Vec<usize>>,
}

impl Buckets {
    /// The `points` (indexed in their order) in buckets of `size` pixels.
    pub(crate) fn new(points: impl IntoIterator<Item = [f64; 2]>, size: f64) -> Buckets {
        let mut map: HashMap<(i64, i64), Vec<usize>> = HashMap::new();
        for (k, p) in points.into_iter().enumerate() {
            map.entry(Self::key(p, size)).or_default().push(k);
        }
        Buckets { size, map }
    }

    fn key(p: [f64; 2], size: f64) -> (i64, i64) {
        ((p[0] / size).floor() as i64, (p[1] / size).floor() as i64)
    }

    /// The indices of the points within `r` (at most the buckets' size)
    /// of `q`, lazily (bucket by bucket, in no particular order); `point(k)`
    /// is point `k` as given to [`Buckets::new`]. `.next().is_some()` asks
    /// whether there is any.
    pub(crate) fn within<'a>(
        &'a self,
        point: impl Fn(usize) -> [f64; 2] + 'a,
        q: [f64; 2],
        r: f64,
    ) -> impl Iterator<Item = usize> + 'a {
        let (bx, by) = Self::key(q, self.size);
        (-1..=1)
            .flat_map(move |dx| (-1..=1).map(move |dy| (bx + dx, by + dy)))
            .filter_map(|key| self.map.get(&key))
            .flatten()
            .copied()
            .filter(move |&k| {
                let p = point(k);
                (p[0] - q[0]).hypot(p[1] - q[1]) <= r
            })
    }
}

#[cfg(test)]
mod tests {
    use super::Buckets;

    /// The points within a distance, as a scan of all of them finds them.
    #[test]
    fn within_finds_what_a_scan_finds() {
        let points: Vec<[f64; 2]> = (0..400)
            .map(|k| {
                let t = k as f64 * 0.37;
                [
                    50.0 + 30.0 * t.cos() + (k % 7) as f64,
                    40.0 + 20.0 * t.sin() - (k % 5) as f64,
                ]
            })
            .collect();
        let buckets = Buckets::new(points.iter().copied(), 3.0);
        for q in [[50.0, 40.0], [80.2, 41.3], [20.0, 20.0], [-5.0, 0.0]] {
            for r in [0.5, 1.7, 3.0] {
                let mut found: Vec<usize> = buckets.within(|k| points[k], q, r).collect();
                found.sort_unstable();
                let scan: Vec<usize> = (0..points.len())
                    .filter(|&k| (points[k][0] - q[0]).hypot(points[k][1] - q[1]) <= r)
                    .collect();
                assert_eq!(found, scan, "{q:?} {r}");
                assert_eq!(
                    buckets.within(|k| points[k], q, r).next().is_some(),
                    !scan.is_empty()
                );
            }
        }
    }
}
