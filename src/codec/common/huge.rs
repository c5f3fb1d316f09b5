//! Large read-mostly arrays on transparent huge pages.
//!
//! A traversal touches nodes and leaves all over arrays of tens of
//! megabytes. With 4 KiB pages nearly every node on a new page is also a
//! TLB miss (a second-level TLB covers a few megabytes); with 2 MiB pages
//! the whole tree is a few dozen entries. Linux hands out huge pages to
//! anonymous memory only where asked (`/sys/kernel/mm/transparent_hugepage/
//! enabled` is `madvise` on most distributions), so Embree asks, and so does
//! this module: [`huge`] collects a large array into fresh memory advised
//! with `madvise(MADV_HUGEPAGE)` *before* it is written, so that its pages
//! fault in huge.
//!
//! What it buys depends on the machine's memory virtualisation. `peers`
//! (1 M statue, 512² camera rays, one thread), on two of this project's
//! 2-core virtual machines: on one, forcing huge pages on system-wide took
//! CLBVH from 5.5 to 9.2 M rays/s and plain from 3.0 to 4.8, Embree
//! (which asks) unchanged; on another, binaries with and without this
//! module, run alternately, gave CLBVH 12.1–12.4 against 11.9–12.1 and
//! plain 6.2–6.3 against 6.1–6.15.
//!
//! Elsewhere (other systems, small arrays, or when the kernel says no) the
//! vector is returned as it is: the advice changes speed, never contents.

/// Vectors smaller than this stay where they are (a huge page is 2 MiB).
const MIN_BYTES: usize = 4 << 20;

/// `items` collected into memory advised for transparent huge pages when
/// they are large and the system supports the advice (see the module
/// docs); the same elements either way. Taking an iterator of known
/// length, not a vector, lets callers copy or decode straight into that
/// memory: a mesh's arrays are copied once, a file's sections decoded
/// once. A vector passed in is reused as it is when it is small.
pub fn huge<T: Copy>(items: impl IntoIterator<Item = T, IntoIter: ExactSizeIterator>) -> Vec<T> {
    let items = items.into_iter();
    #[cfg(target_os = "linux")]
    if items.len().saturating_mul(size_of::<T>()) >= MIN_BYTES {
        let mut w: Vec<T> = Vec::with_capacity(items.len());
        let start = w.as_ptr() as usize;
        let end = start + w.capacity() * size_of::<T>();
        const PAGE: usize = 2 << 20;
        let (lo, hi) = (start.next_multiple_of(PAGE), end / PAGE * PAGE);
        if lo < hi {
            // SAFETY: `lo..hi` lies inside `w`'s allocation (`start..end`
            // is its capacity), which this function owns; MADV_HUGEPAGE
            // only advises the kernel how to back those pages and never
            // changes their contents or the mapping's validity. A failure
            // (an old kernel, THP disabled) is harmless and ignored.
            unsafe {
                libc::madvise(lo as *mut libc::c_void, hi - lo, libc::MADV_HUGEPAGE);
            }
        }
        w.extend(items);
        return w;
    }
    items.collect()
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn huge_keeps_every_element() {
        for n in [0usize, 3, 1 << 20, (5 << 20) / 4 + 7] {
            let v: Vec<u32> = (0..n as u32)
                .map(|x| x.wrapping_mul(2_654_435_761))
                .collect();
            assert_eq!(huge(v.clone()), v);
            assert_eq!(huge(v.iter().copied()), v);
        }
    }
}
