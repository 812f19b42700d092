//! Seeded random scenes for the unit tests, so every module tests on the same kind of data.

use alloc::vec::Vec;

use glam::Vec3;

use crate::geometry::Triangle;
use crate::random::Pcg32;

/// `n` triangles: the first vertex uniform in `[lo, hi)^3`, the other two within `spread` of it
/// on every axis. Small `spread` against the range gives a soup of separate triangles; large
/// `spread` gives long overlapping ones.
pub(crate) fn soup(n: usize, seed: u64, lo: f32, hi: f32, spread: f32) -> Vec<Triangle> {
    let mut rng = Pcg32::new(seed);
    let mut v = |a: f32, b: f32| Vec3::new(rng.range(a, b), rng.range(a, b), rng.range(a, b));
    (0..n)
        .map(|_| {
            let a = v(lo, hi);
            Triangle::new(a, a + v(-spread, spread), a + v(-spread, spread))
        })
        .collect()
}
