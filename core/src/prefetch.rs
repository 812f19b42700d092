//! A cache hint for data a caller reads after a query: a renderer's per-triangle materials,
//! indexed by the hit's triangle id, are the next load after a closest hit, and usually a miss.

/// Hints the cache to fetch the line holding `value`, so that a read of it later (after other
/// work, such as tracing a shadow segment) does not wait on memory. A hint only: nothing is read
/// into the program, nothing can fault, no result changes. Does nothing off x86-64.
#[inline(always)]
pub fn prefetch<T>(value: &T) {
    #[cfg(target_arch = "x86_64")]
    // SAFETY: a prefetch has no memory access semantics (it cannot fault, and it reads nothing
    // into the program); `value` is a valid reference anyway, and SSE is part of the x86-64
    // baseline.
    unsafe {
        use core::arch::x86_64::{_mm_prefetch, _MM_HINT_T0};
        _mm_prefetch::<_MM_HINT_T0>((value as *const T).cast::<i8>());
    }
    #[cfg(not(target_arch = "x86_64"))]
    let _ = value;
}
