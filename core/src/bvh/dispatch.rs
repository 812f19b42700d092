//! Which instructions the wide traversals use, chosen at run time.
//!
//! `wide`'s vectors pick their instructions when the crate is compiled: for the default x86-64
//! target (SSE2) an `f32x8` is two SSE halves, and an 8-wide node test costs twice the
//! instructions it needs on a CPU with AVX. With the `std` feature (which the host crate and
//! `rayon` turn on), x86-64 builds therefore also carry the 8-wide traversals compiled for AVX2
//! (`super::avx2`), and the first query checks the CPU once and keeps the answer: from then on a
//! query pays one relaxed load and a predictable branch. Both paths compute the same answers bit
//! for bit. 4-wide trees keep the baseline: their lanes are one SSE register either way, and
//! AVX2 gained them nothing measurable.
//!
//! There is nothing to choose, and the traversals call the compiled path directly, when the crate
//! is built without `std` (no CPU detection on bare metal), for another architecture, under Miri
//! (no AVX intrinsics), or already for AVX2 (`-C target-cpu=native` on such a CPU, which lets the
//! rest of the crate use it too).

/// The instruction set of the wide traversals ([`simd_level`], [`set_simd_level`]).
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash)]
pub enum SimdLevel {
    /// The code compiled for the build's own target features (SSE2 on a default x86-64 target;
    /// whatever `-C target-cpu` or `-C target-feature` add).
    Baseline,
    /// The traversals compiled for AVX2 (with FMA, BMI1, BMI2, LZCNT and POPCNT present), chosen
    /// at run time; 8-wide nodes test their children in one 256-bit register.
    Avx2,
}

/// True when the build can choose at run time (see the module documentation).
#[cfg(target_arch = "x86_64")]
const DISPATCH: bool = cfg!(all(
    feature = "std",
    not(target_feature = "avx2"),
    not(miri)
));

/// The choice, once made: [`UNKNOWN`] until the first query or [`set_simd_level`].
#[cfg(target_arch = "x86_64")]
static LEVEL: core::sync::atomic::AtomicU8 = core::sync::atomic::AtomicU8::new(UNKNOWN);
#[cfg(target_arch = "x86_64")]
const UNKNOWN: u8 = 0;
#[cfg(target_arch = "x86_64")]
const BASELINE: u8 = 1;
#[cfg(target_arch = "x86_64")]
const AVX2: u8 = 2;

/// True when a `W`-wide query should take the AVX2 entry points (`super::avx2`): the build
/// dispatches, the width gains from it, and the CPU has AVX2 (unless forced to the baseline).
#[cfg(target_arch = "x86_64")]
#[inline(always)]
pub(crate) fn avx2_entry<const W: usize>() -> bool {
    use core::sync::atomic::Ordering::Relaxed;
    if !DISPATCH || !(W == 8 || super::avx2::WIDE4) {
        return false;
    }
    match LEVEL.load(Relaxed) {
        AVX2 => true,
        BASELINE => false,
        _ => detect() == SimdLevel::Avx2,
    }
}

/// Everything the AVX2 entry points are compiled for, on this CPU (never, without `std` to ask).
#[cfg(target_arch = "x86_64")]
pub(crate) fn cpu_has_avx2() -> bool {
    #[cfg(any(feature = "std", test))]
    {
        std::is_x86_feature_detected!("avx")
            && std::is_x86_feature_detected!("avx2")
            && std::is_x86_feature_detected!("fma")
            && std::is_x86_feature_detected!("bmi1")
            && std::is_x86_feature_detected!("bmi2")
            && std::is_x86_feature_detected!("lzcnt")
            && std::is_x86_feature_detected!("popcnt")
    }
    #[cfg(not(any(feature = "std", test)))]
    false
}

/// The first query's choice: AVX2 where the CPU has it, unless the environment variable
/// `RDBVH_SIMD` is `baseline`.
#[cfg(target_arch = "x86_64")]
#[cold]
#[inline(never)]
fn detect() -> SimdLevel {
    #[cfg(feature = "std")]
    let forced = std::env::var_os("RDBVH_SIMD").is_some_and(|v| v == "baseline");
    #[cfg(not(feature = "std"))]
    let forced = false;
    let level = if DISPATCH && cpu_has_avx2() && !forced {
        SimdLevel::Avx2
    } else {
        SimdLevel::Baseline
    };
    store(level);
    level
}

#[cfg(target_arch = "x86_64")]
fn store(level: SimdLevel) {
    let v = match level {
        SimdLevel::Baseline => BASELINE,
        SimdLevel::Avx2 => AVX2,
    };
    LEVEL.store(v, core::sync::atomic::Ordering::Relaxed);
}

/// The instruction set the wide traversals use: the run-time choice where the build makes one
/// (on the first call, AVX2 where the CPU has it, unless the environment variable `RDBVH_SIMD` is
/// `baseline`), else what the crate was compiled for.
pub fn simd_level() -> SimdLevel {
    if cfg!(target_feature = "avx2") {
        return SimdLevel::Avx2;
    }
    #[cfg(target_arch = "x86_64")]
    if DISPATCH {
        return match LEVEL.load(core::sync::atomic::Ordering::Relaxed) {
            AVX2 => SimdLevel::Avx2,
            BASELINE => SimdLevel::Baseline,
            _ => detect(),
        };
    }
    SimdLevel::Baseline
}

/// Chooses the wide traversals' instruction set for every later query, on every thread, and
/// returns the one in effect: AVX2 only where the build dispatches and the CPU has it, and a
/// build compiled for AVX2 keeps it. For A/B measurements and tests; the answers are the same
/// either way.
pub fn set_simd_level(level: SimdLevel) -> SimdLevel {
    #[cfg(target_arch = "x86_64")]
    if DISPATCH {
        let level = match level {
            SimdLevel::Avx2 if cpu_has_avx2() => SimdLevel::Avx2,
            _ => SimdLevel::Baseline,
        };
        store(level);
        return level;
    }
    let _ = level;
    simd_level()
}
