//! A cache hint for data a caller reads after a query: a renderer's per-triangle materials,
//! indexed by the hit's triangle id, are the next load after a closest hit, and usually a miss.

/// Hints the cache to fetch the line holding `value`, so that a read of it later (after other
/// work, such as tracing a shadow segment) does not wait on memory. A hint only: nothing is read
/// into the program, nothing can fault, no result changes. Does nothing off x86-64.
#[inline(always)]
pub fn prefetch<T>(value: &T) {
    prefetch_line((value as *const T).cast());
}

/// [`prefetch`] for every cache line `value` spans: for a value larger than a line, or one that
/// may straddle two (an 80-byte shadow segment in an array).
#[inline(always)]
pub fn prefetch_all<T>(value: &T) {
    let start = (value as *const T).cast::<u8>();
    let size = core::mem::size_of::<T>();
    let mut offset = 0;
    while offset < size {
        prefetch_line(start.wrapping_add(offset));
        offset += 64;
    }
    // The last line, when the value does not start on a line.
    prefetch_line(start.wrapping_add(size.saturating_sub(1)));
}

/// Hints the cache to fetch the line holding `address`.
#[inline(always)]
fn prefetch_line(address: *const u8) {
    #[cfg(target_arch = "x86_64")]
    // SAFETY: a prefetch has no memory access semantics (it cannot fault, and it reads nothing
    // into the program), whatever the address; SSE is part of the x86-64 baseline.
    unsafe {
        use core::arch::x86_64::{_mm_prefetch, _MM_HINT_T0};
        _mm_prefetch::<_MM_HINT_T0>(address.cast::<i8>());
    }
    #[cfg(not(target_arch = "x86_64"))]
    let _ = address;
}
