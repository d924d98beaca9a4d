//! Two hardware hints for the explorer's large arrays, the only unsafe code
//! of the crate: a software prefetch of a table slot, and transparent huge
//! pages (`madvise(MADV_HUGEPAGE)`) for the table and the state arrays, so
//! that random lookups in a table of hundreds of megabytes do not miss the
//! TLB on every access. Both are hints: elsewhere (other architectures, other
//! systems, THP disabled) they do nothing and the results are the same.
#![allow(unsafe_code)]

/// Asks the CPU to bring the cache line holding `x` into the cache.
#[inline(always)]
pub(super) fn prefetch<T>(x: &T) {
    #[cfg(target_arch = "x86_64")]
    // SAFETY: a prefetch never faults and has no effect on memory; the
    // pointer comes from a reference, and SSE is part of x86_64.
    unsafe {
        core::arch::x86_64::_mm_prefetch::<{ core::arch::x86_64::_MM_HINT_T0 }>((x as *const T).cast::<i8>());
    }
    #[cfg(not(target_arch = "x86_64"))]
    let _ = x;
}

/// Below this size huge pages do not pay (and the range may hold no aligned
/// 2 MiB page at all).
const HUGE_MIN_BYTES: usize = 4 << 20;
const HUGE_PAGE: usize = 2 << 20;

/// Advises the kernel to back the allocated buffer of `v` (its capacity,
/// spare part included) with transparent huge pages. Call it before the
/// memory is first written, so that page faults take 2 MiB at a time.
pub(super) fn advise_huge<T>(v: &mut Vec<T>) {
    let bytes = v.capacity() * std::mem::size_of::<T>();
    if bytes < HUGE_MIN_BYTES {
        return;
    }
    let start = v.as_mut_ptr() as usize;
    let lo = start.next_multiple_of(HUGE_PAGE);
    let hi = (start + bytes) / HUGE_PAGE * HUGE_PAGE;
    if hi <= lo {
        return;
    }
    #[cfg(target_os = "linux")]
    // SAFETY: `lo..hi` lies inside the allocation of `v`, which this function
    // borrows mutably; MADV_HUGEPAGE changes how the pages are backed, never
    // their contents, and a failure (THP off, old kernel) is ignored.
    unsafe {
        libc::madvise(lo as *mut libc::c_void, hi - lo, libc::MADV_HUGEPAGE);
    }
}

/// A vector of `n` copies of `x`, with huge pages when it is large.
pub(super) fn huge_vec<T: Copy>(n: usize, x: T) -> Vec<T> {
    let mut v = Vec::with_capacity(n);
    advise_huge(&mut v);
    v.resize(n, x);
    v
}
