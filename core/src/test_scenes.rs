//! Seeded random scenes for the unit tests, so every module tests on the same kind of data.

use alloc::vec::Vec;

use glam::Vec3;

use crate::geometry::{Aabb, Ray, Triangle};
use crate::influence::{InfluenceArea, RaySampler};
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

/// Moller-Trumbore in f64 on the ray's and the triangle's own f32 values, measured from the
/// ray's origin: `(t, u, v)`, the reference the f32 test is held to.
pub(crate) fn exact_intersection(tri: &Triangle, r: &Ray) -> (f64, f64, f64) {
    let f = |v: Vec3| v.to_array().map(f64::from);
    let sub = |a: [f64; 3], b: [f64; 3]| [a[0] - b[0], a[1] - b[1], a[2] - b[2]];
    let dot = |a: [f64; 3], b: [f64; 3]| a[0] * b[0] + a[1] * b[1] + a[2] * b[2];
    let cross = |a: [f64; 3], b: [f64; 3]| {
        [
            a[1] * b[2] - a[2] * b[1],
            a[2] * b[0] - a[0] * b[2],
            a[0] * b[1] - a[1] * b[0],
        ]
    };
    let (v0, d) = (f(tri.v0), f(r.dir));
    let (e1, e2) = (sub(f(tri.v1), v0), sub(f(tri.v2), v0));
    let p = cross(d, e2);
    let det = dot(e1, p);
    let s = sub(f(r.origin), v0);
    let q = cross(s, e1);
    (dot(e2, q) / det, dot(s, p) / det, dot(d, q) / det)
}

/// The fraction of `n` rays from `rays` that meet `b` before they leave `area`, theirs: a
/// sampled hit probability for checking a PAH measure (the measure over the window's is its
/// exact value).
pub(crate) fn hit_fraction(rays: &mut RaySampler, area: &InfluenceArea, b: &Aabb, n: u32) -> f32 {
    let hits = (0..n)
        .filter(|_| {
            let r = rays.sample();
            area.exit(&r)
                .is_some_and(|exit| b.intersect(&r, exit).is_some())
        })
        .count();
    hits as f32 / n as f32
}
