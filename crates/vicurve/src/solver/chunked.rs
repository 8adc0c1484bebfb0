//! Deterministic parallel sums over band pixels.
//!
//! Rayon's `fold`/`reduce` splits the work as the threads steal it, so the
//! order in which floating-point partial sums are added, and with it the
//! last bits of the result, can change from run to run. A fit that
//! compares such sums (a golden-section search, a significance test) could
//! then take a different branch on the same input. Here the chunks are
//! fixed by the number of items alone, computed in parallel, and added in
//! chunk order: the same bits on every run and with any number of threads.

use rayon::prelude::*;
use std::ops::Range;

/// Items per chunk: large enough that a chunk's partial result (a copy of
/// the system being assembled: a few kilobytes for a banded matrix, up to a
/// few hundred for the varying levels' coupling block) costs little next
/// to summing its items. All partial results are held until they are
/// added, one per 2048 items.
pub(crate) const CHUNK: usize = 2048;

/// `map` applied to the consecutive ranges of `CHUNK` items of `0..len` in
/// parallel, then the partial results folded with `add` in range order.
/// `None` when `len` is 0.
pub(crate) fn chunked_sum<A: Send>(
    len: usize,
    map: impl Fn(Range<usize>) -> A + Sync,
    mut add: impl FnMut(&mut A, A),
) -> Option<A> {
    let parts: Vec<A> = (0..len.div_ceil(CHUNK))
        .into_par_iter()
        .map(|k| map(k * CHUNK..((k + 1) * CHUNK).min(len)))
        .collect();
    let mut parts = parts.into_iter();
    let mut total = parts.next()?;
    for part in parts {
        add(&mut total, part);
    }
    Some(total)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn sums_every_item_once_in_chunk_order() {
        for len in [0, 1, CHUNK - 1, CHUNK, CHUNK + 1, 5 * CHUNK + 17] {
            let ranges = chunked_sum(len, |r| vec![(r.start, r.end)], |a, mut b| a.append(&mut b))
                .unwrap_or_default();
            let mut next = 0;
            for (start, end) in ranges {
                assert_eq!(start, next);
                assert!(end > start && end - start <= CHUNK);
                next = end;
            }
            assert_eq!(next, len);
        }
    }

    #[test]
    fn the_same_bits_with_any_number_of_threads() {
        // Terms of very different sizes: any change of order shows.
        let x: Vec<f64> = (0..20_000)
            .map(|i| ((i * 7919) % 1000) as f64 * 10f64.powi(i % 17 - 8))
            .collect();
        let sum = || chunked_sum(x.len(), |r| x[r].iter().sum::<f64>(), |a, b| *a += b);
        let reference = sum();
        for threads in [1, 2, 3, 8] {
            let pool = rayon::ThreadPoolBuilder::new()
                .num_threads(threads)
                .build()
                .unwrap();
            for _ in 0..5 {
                assert_eq!(
                    pool.install(sum).map(f64::to_bits),
                    reference.map(f64::to_bits)
                );
            }
        }
    }
}
