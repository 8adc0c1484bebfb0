//! The outer boundary of a region, traced pixel by pixel.

/// Neighbour offsets clockwise on screen (y down), starting west.
const RING: [(i64, i64); 8] = [
    (-1, 0),
    (-1, -1),
    (0, -1),
    (1, -1),
    (1, 0),
    (1, 1),
    (0, 1),
    (-1, 1),
];

fn ring_index(dx: i64, dy: i64) -> usize {
    RING.iter().position(|&o| o == (dx, dy)).unwrap_or(0)
}

/// The outer boundary of the region labelled `id` in `labels` (`w x h`),
/// as the closed chain of its boundary pixels `(column, row)` in clockwise
/// order on screen, by Moore-neighbour tracing from `first` (its first
/// pixel in raster order). A one-pixel region gives that pixel alone.
pub fn trace(
    labels: &[u32],
    w: usize,
    h: usize,
    id: u32,
    first: (usize, usize),
) -> Vec<(usize, usize)> {
    let inside = |x: i64, y: i64| {
        x >= 0
            && y >= 0
            && (x as usize) < w
            && (y as usize) < h
            && labels[y as usize * w + x as usize] == id
    };
    let start = (first.0 as i64, first.1 as i64);
    let mut chain = vec![first];
    // The first pixel's west neighbour is outside (raster order).
    let (mut cur, mut back) = (start, 0usize);
    let mut second: Option<(i64, i64)> = None;
    let limit = 4 * w * h + 16;
    for _ in 0..limit {
        let mut next = None;
        for k in 1..=8 {
            let d = (back + k) % 8;
            let n = (cur.0 + RING[d].0, cur.1 + RING[d].1);
            if inside(n.0, n.1) {
                // The last outside position scanned becomes the backtrack,
                // seen from the new pixel.
                let p = (back + k - 1) % 8;
                let b = (cur.0 + RING[p].0, cur.1 + RING[p].1);
                next = Some((n, ring_index(b.0 - n.0, b.1 - n.1)));
                break;
            }
        }
        let Some((n, b)) = next else {
            return chain; // an isolated pixel
        };
        if cur == start {
            match second {
                None => second = Some(n),
                // Back at the start and about to repeat the first step.
                Some(s) if s == n => return chain,
                Some(_) => {}
            }
        }
        if n != start || second.is_none() {
            chain.push((n.0 as usize, n.1 as usize));
        }
        (cur, back) = (n, b);
    }
    chain
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn square_and_single_pixel() {
        // A 3x3 square in a 5x5 grid: 8 boundary pixels.
        let labels: Vec<u32> = (0..25)
            .map(|k| {
                let (x, y) = (k % 5, k / 5);
                u32::from(!((1..4).contains(&x) && (1..4).contains(&y)))
            })
            .collect();
        let chain = trace(&labels, 5, 5, 0, (1, 1));
        assert_eq!(chain.len(), 8, "{chain:?}");
        assert_eq!(chain[0], (1, 1));
        assert_eq!(chain[1], (2, 1)); // clockwise on screen: east first
        assert!(!chain.contains(&(2, 2)));
        let one = [1, 1, 1, 1, 0, 1, 1, 1, 1];
        assert_eq!(trace(&one, 3, 3, 0, (1, 1)), vec![(1, 1)]);
    }

    #[test]
    fn a_plus_is_walked_through_its_tips() {
        // A plus-shaped region: its centre has all four side neighbours
        // inside, so it is not on the boundary; the trace steps diagonally
        // from tip to tip, clockwise on screen.
        let labels: Vec<u32> = (0..25)
            .map(|k| {
                let (x, y) = (k % 5, k / 5);
                u32::from(!(x == 2 && (1..4).contains(&y) || y == 2 && (1..4).contains(&x)))
            })
            .collect();
        let chain = trace(&labels, 5, 5, 0, (2, 1));
        assert_eq!(chain, vec![(2, 1), (3, 2), (2, 3), (1, 2)]);
    }
}
