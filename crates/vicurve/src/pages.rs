//! Whole-image buffers on huge pages: a megapixel image's levels and its
//! interpolation coefficients (8 bytes a pixel each) are written once, in
//! full, right after they are allocated. On 4 KiB pages every page of
//! them costs a fault on that first write; on Linux the kernel is asked
//! (`madvise(MADV_HUGEPAGE)`) to back them with 2 MiB pages instead, 512
//! times fewer faults. Elsewhere, or when the kernel declines, the buffers
//! are ordinary ones: this changes no value, only how the memory is
//! mapped.
//!
//! Only for buffers written in full: a huge page is resident as soon as one
//! byte of it is touched, so a sparse one (the band's grids, which a curve
//! touches only along itself) would take far more memory than it uses.

/// Buffers smaller than this (bytes) stay on ordinary pages: they span at
/// most one huge page, which would save a few hundred faults at best.
#[cfg_attr(not(target_os = "linux"), allow(dead_code))]
const HUGE_MIN_BYTES: usize = 4 << 20;

/// Size of a huge page on the platforms asked for them, bytes.
#[cfg(target_os = "linux")]
const HUGE_PAGE: usize = 2 << 20;

/// An empty vector with room for `n` values, its storage (when at least
/// [`HUGE_MIN_BYTES`]) advised as huge pages before anything is written to
/// it. Fill it with `extend` or `resize`.
pub(crate) fn with_capacity<T>(n: usize) -> Vec<T> {
    let v = Vec::with_capacity(n);
    #[cfg(target_os = "linux")]
    advise(&v);
    v
}

/// `iter` collected (`n` values expected) into a [`with_capacity`] vector.
pub(crate) fn collect<T>(n: usize, iter: impl IntoIterator<Item = T>) -> Vec<T> {
    let mut v = with_capacity(n);
    v.extend(iter);
    v
}

/// Ask the kernel to back the whole huge pages within `v`'s allocation by
/// huge pages (a hint: an error, or a kernel that does not do it, leaves
/// them ordinary).
#[cfg(target_os = "linux")]
fn advise<T>(v: &Vec<T>) {
    let bytes = v.capacity() * std::mem::size_of::<T>();
    if bytes < HUGE_MIN_BYTES {
        return;
    }
    let start = v.as_ptr() as usize;
    let first = start.next_multiple_of(HUGE_PAGE);
    let end = (start + bytes) / HUGE_PAGE * HUGE_PAGE;
    if end > first {
        // SAFETY: the range lies within `v`'s own allocation, which lives
        // on; MADV_HUGEPAGE changes how it is mapped, never its contents
        // or its validity, and its result is only a hint taken or not.
        unsafe {
            libc::madvise(first as *mut libc::c_void, end - first, libc::MADV_HUGEPAGE);
        }
    }
}

#[cfg(test)]
mod tests {
    /// A buffer large enough to be advised holds what was written to it,
    /// like an ordinary one (the advice changes the mapping only).
    #[test]
    fn an_advised_buffer_holds_its_values() {
        let n = (3 * super::HUGE_MIN_BYTES) / 8 + 12_345;
        let v = super::collect(n, (0..n).map(|k| k as f64 * 0.5));
        assert_eq!(v.len(), n);
        assert!(v.iter().enumerate().all(|(k, &x)| x == k as f64 * 0.5));
        let mut z: Vec<f64> = super::with_capacity(n);
        z.resize(n, 0.0);
        assert!(z.iter().all(|&x| x == 0.0));
    }
}
