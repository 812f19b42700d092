//! Triangles and the Moller-Trumbore ray/triangle test.

use bytemuck::{Pod, Zeroable};
use glam::Vec3;

use super::{Aabb, Ray};

/// A triangle given by its three vertices.
#[derive(Clone, Copy, Debug, PartialEq, Pod, Zeroable)]
#[repr(C)]
pub struct Triangle {
    /// First vertex; barycentric `u` and `v` weigh `v1` and `v2` against it.
    pub v0: Vec3,
    /// Second vertex.
    pub v1: Vec3,
    /// Third vertex.
    pub v2: Vec3,
}

static_assertions::assert_eq_size!(Triangle, [f32; 9]);

/// `(8 eps)^2`: a determinant below `8 eps |d| |e1| |e2|` is rounding noise.
const DET_EPSILON_SQ: f64 = (8.0 * f32::EPSILON as f64) * (8.0 * f32::EPSILON as f64);

/// `(2^-123)^2`: the squared floor of [`determinant_is_noise`]'s precision test. Below the
/// smallest normal f32 (2^-126) results round to a fixed grid of 2^-149; eight such roundings
/// stay under one ulp (2^-23 relative) of `u`, `v` and of the hit point as long as the
/// determinant is at least `2^-149 * 8 / 2^-23 = 2^-123` times `max(1, |d|, |d| / |e|)`.
const PRECISION_FLOOR_SQ: f64 = 1.0 / (1u128 << 123) as f64 / (1u128 << 123) as f64;

/// True when Moller-Trumbore's f32 determinant `det` (for a direction `d` of squared length
/// `dir_len_sq`, [`Ray::dir_len_sq`], and edges `e1`, `e2`) cannot be trusted, so its `u`, `v`
/// and `t` are meaningless:
/// - within the rounding error of zero, `|det| <= 8 eps |d| |e1| |e2|` (a degenerate triangle,
///   or a ray in its plane);
/// - infinite (the products overflowed);
/// - so small that subnormal rounding would show: below `2^-123 max(1, |d|, |d| / |e|)` for the
///   longer edge `|e|`, or with `|d| |e2| < 2^-123` (the products that make `d x e2`). In f32
///   arithmetic this is where triangles under about 1e-12 units (seen along a unit direction)
///   stop being hit; above it the answers keep their precision.
///
/// Compared in f64, where the squared lengths of any finite f32 vectors neither overflow nor
/// underflow: in f32 they did past `|d| |e1| |e2|` of about 1.8e19 or below about 1e-23, and
/// rejected every hit on large triangles, along long or short directions, and on triangles
/// under about 1e-9 units. Shared by the scalar and the 4-wide test, so both decide alike. Runs
/// only for a hit that passed every other test.
#[inline]
pub(crate) fn determinant_is_noise(det: f32, dir_len_sq: f64, e1: Vec3, e2: Vec3) -> bool {
    let len_sq = |v: Vec3| {
        let (x, y, z) = (f64::from(v.x), f64::from(v.y), f64::from(v.z));
        x * x + y * y + z * z
    };
    if !det.is_finite() {
        return true;
    }
    let det_sq = f64::from(det) * f64::from(det);
    let (d, a, b) = (dir_len_sq, len_sq(e1), len_sq(e2));
    let floor = PRECISION_FLOOR_SQ * 1f64.max(d).max(d / a.max(b));
    det_sq <= DET_EPSILON_SQ * (d * a * b) || det_sq < floor || d * b < PRECISION_FLOOR_SQ
}

/// A ray/triangle intersection: the ray parameter and the barycentrics of `v1` and `v2`.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct TriangleHit {
    /// Ray parameter of the hit.
    pub t: f32,
    /// Barycentric weight of `v1`.
    pub u: f32,
    /// Barycentric weight of `v2`.
    pub v: f32,
}

impl Triangle {
    /// A triangle from three vertices.
    #[inline]
    pub const fn new(v0: Vec3, v1: Vec3, v2: Vec3) -> Self {
        Self { v0, v1, v2 }
    }

    /// The bounding box of the three vertices.
    #[inline]
    pub fn bounds(&self) -> Aabb {
        Aabb::new(
            self.v0.min(self.v1).min(self.v2),
            self.v0.max(self.v1).max(self.v2),
        )
    }

    /// The centroid `(v0 + v1 + v2) / 3`.
    #[inline]
    pub fn centroid(&self) -> Vec3 {
        (self.v0 + self.v1 + self.v2) * (1.0 / 3.0)
    }

    /// The triangle's area. Where the cross product's square leaves f32's normal range (edges
    /// past about 4e9 or below 3e-10 units), its length is taken in f64, so the area is right
    /// (or infinite past f32's range) instead of infinite or zero.
    #[inline]
    pub fn area(&self) -> f32 {
        let c = (self.v1 - self.v0).cross(self.v2 - self.v0);
        let squared = c.length_squared();
        if squared.is_finite() && squared >= f32::MIN_POSITIVE {
            0.5 * c.length()
        } else {
            (0.5 * c.as_dvec3().length()) as f32
        }
    }

    /// True when every vertex coordinate is finite.
    #[inline]
    pub fn is_finite(&self) -> bool {
        self.v0.is_finite() && self.v1.is_finite() && self.v2.is_finite()
    }

    /// Moller-Trumbore intersection with the segment `[ray.t_min, t_max]`.
    ///
    /// Policy, shared by the BVH traversals and the brute-force oracle so both give the same answer:
    /// - both faces are hit (no back-face culling);
    /// - edges and vertices belong to the triangle (`u >= 0`, `v >= 0`, `u + v <= 1`), so a ray
    ///   through a shared edge hits both neighbours and the closest-hit tie rule picks one;
    /// - the segment is closed: hits at exactly `t_min` or `t_max` count;
    /// - degenerate triangles (zero area, so a zero determinant) and rays in the triangle's plane
    ///   never hit, also when rounding makes the determinant a few ulps from zero (below
    ///   `8 eps |d| |e1| |e2|`, rays within about 1e-6 radians of the plane of a well-shaped
    ///   triangle), or so small that f32's subnormal rounding would show in the answer (triangles
    ///   under about 1e-12 units seen along a unit direction);
    ///   every comparison rejects NaN, and the determinant and `t` must be finite, so overflow
    ///   cannot produce a hit either.
    ///
    /// The arithmetic is f32, measured from the ray's origin or its anchor ([`Ray::anchor`]),
    /// whichever errs less at the triangle's first vertex: `u` and `v` carry an absolute error of
    /// about 2^-24 times the distance from the origin, or from the anchor plus the anchor's
    /// distance from the world origin, over the triangle's size. The anchor is never farther
    /// from the world origin than a hit ahead of the origin, so the error is at most a few
    /// times 2^-24 the hit's own distance from the world origin, wherever the ray starts; the
    /// README's Known limits give the numbers.
    #[inline]
    pub fn intersect(&self, ray: &Ray, t_max: f32) -> Option<TriangleHit> {
        let e1 = self.v1 - self.v0;
        let e2 = self.v2 - self.v0;
        let p = ray.dir.cross(e2);
        let det = e1.dot(p);
        if det == 0.0 {
            return None;
        }
        let inv_det = 1.0 / det;
        // Measured from the ray's origin or its anchor (see `Ray::anchor`), whichever errs less
        // at the triangle's first vertex: the edge decisions' error grows with the distance.
        let (from, t0) = if ray.measures_from_anchor(self.v0) {
            (ray.anchor, ray.anchor_t)
        } else {
            (ray.origin, 0.0)
        };
        let s = from - self.v0;
        let u = s.dot(p) * inv_det;
        if !(0.0..=1.0).contains(&u) {
            return None;
        }
        let q = s.cross(e1);
        let v = ray.dir.dot(q) * inv_det;
        if !(v >= 0.0 && u + v <= 1.0) {
            return None;
        }
        let t = t0 + e2.dot(q) * inv_det;
        if !(t >= ray.t_min && t <= t_max && t.is_finite()) {
            return None;
        }
        // A determinant within the rounding error of zero (a degenerate triangle whose edges are
        // parallel, or a ray in the triangle's plane) gives meaningless u, v and t: the computed
        // "hit" can lie anywhere, far from the triangle. |det| <= |d| |e1| |e2| always, and its
        // rounding error is a few ulps of that bound, so such hits are rejected. Checked only
        // after everything else passed: hits are rare, misses pay nothing.
        if determinant_is_noise(det, ray.dir_len_sq, e1, e2) {
            return None;
        }
        Some(TriangleHit { t, u, v })
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn tri() -> Triangle {
        Triangle::new(
            Vec3::new(0.0, 0.0, 1.0),
            Vec3::new(1.0, 0.0, 1.0),
            Vec3::new(0.0, 1.0, 1.0),
        )
    }

    /// Half a unit square at any scale f32 holds its area at: 2^-60 to 2^60 units a side.
    #[test]
    fn area_at_any_scale() {
        assert_eq!(tri().area(), 0.5);
        for k in [-60, -20, 20, 60] {
            let s = 2f32.powi(k);
            let t = Triangle::new(tri().v0 * s, tri().v1 * s, tri().v2 * s);
            assert_eq!(t.area(), 0.5 * s * s, "2^{k}");
        }
    }

    #[test]
    fn hit_with_barycentrics() {
        let r = Ray::new(Vec3::new(0.25, 0.5, 0.0), Vec3::Z).unwrap();
        let h = tri().intersect(&r, f32::INFINITY).unwrap();
        assert!((h.t - 1.0).abs() < 1e-6);
        assert!((h.u - 0.25).abs() < 1e-6);
        assert!((h.v - 0.5).abs() < 1e-6);
    }

    #[test]
    fn back_face_and_edges_hit() {
        let r = Ray::new(Vec3::new(0.25, 0.25, 2.0), -Vec3::Z).unwrap();
        assert!(tri().intersect(&r, f32::INFINITY).is_some());
        let r = Ray::new(Vec3::new(0.5, 0.0, 0.0), Vec3::Z).unwrap();
        assert!(tri().intersect(&r, f32::INFINITY).is_some(), "edge");
        let r = Ray::new(Vec3::new(0.0, 0.0, 0.0), Vec3::Z).unwrap();
        assert!(tri().intersect(&r, f32::INFINITY).is_some(), "vertex");
    }

    #[test]
    fn misses() {
        let r = Ray::new(Vec3::new(0.75, 0.75, 0.0), Vec3::Z).unwrap();
        assert!(tri().intersect(&r, f32::INFINITY).is_none(), "outside");
        let r = Ray::new(Vec3::new(0.25, 0.25, 0.0), Vec3::Z).unwrap();
        assert!(tri().intersect(&r, 0.5).is_none(), "beyond t_max");
        let r = Ray::new(Vec3::new(0.25, 0.25, 2.0), Vec3::Z).unwrap();
        assert!(tri().intersect(&r, f32::INFINITY).is_none(), "behind");
        let r = Ray::new(Vec3::new(-1.0, 0.25, 1.0), Vec3::X).unwrap();
        assert!(tri().intersect(&r, f32::INFINITY).is_none(), "in plane");
    }

    #[test]
    fn hits_at_every_scale_and_direction_length() {
        // Found by black-box testing of `rdbvh trace`: the noise check's squared lengths
        // overflowed or underflowed in f32 and rejected these hits. Scalar and 4-wide agree.
        use crate::geometry::{RayTri4, Triangle4};
        let hit = |t: Triangle, r: Ray| {
            let h = t.intersect(&r, f32::INFINITY);
            let mut block = Triangle4::EMPTY;
            block.set(0, &t, 0);
            let four = block.intersect(&RayTri4::new(&r), f32::INFINITY);
            assert_eq!(four.mask == 1, h.is_some(), "{t:?} {r:?}");
            if let Some(h) = h {
                assert_eq!(four.t[0].to_bits(), h.t.to_bits());
            }
            h
        };
        let check = |t: Triangle, r: Ray, expect_t: f32| {
            let h = hit(t, r).unwrap_or_else(|| panic!("{t:?} {r:?}: no hit"));
            assert!(
                (h.t - expect_t).abs() <= 1e-5 * expect_t,
                "{t:?} {r:?}: {h:?}"
            );
            assert!(
                (h.u - 0.25).abs() < 1e-5 && (h.v - 0.5).abs() < 1e-5,
                "{h:?}"
            );
        };
        let scaled =
            |scale: f32| Triangle::new(tri().v0 * scale, tri().v1 * scale, tri().v2 * scale);
        let from = |scale: f32| Vec3::new(0.25, 0.5, 0.0) * scale;
        for scale in [1e-11f32, 1e-6, 1.0, 1e6, 1e10, 1e12] {
            check(
                scaled(scale),
                Ray::new(from(scale), Vec3::Z).unwrap(),
                scale,
            );
        }
        // The direction as long as the triangle: the determinant scales with it.
        for scale in [1e-12f32, 1e-6, 1.0, 1e6, 1e10] {
            check(
                scaled(scale),
                Ray::new(from(scale), Vec3::Z * scale).unwrap(),
                1.0,
            );
        }
        for len in [1e-30f32, 1e-23, 2e19, 1e20, 1e30] {
            let r = Ray::new(Vec3::new(0.25, 0.5, 0.0), Vec3::Z * len).unwrap();
            check(tri(), r, 1.0 / len);
        }
        // Past what f32 can compute, no hit rather than a wrong one: a 1e-15 triangle seen along
        // a unit direction from 1e-15 away gets its `t` numerator on the subnormal grid (it
        // came out 1.4e-15 for a true 1e-15), and a 1e15 triangle along a 1e15 direction
        // overflows the determinant.
        assert_eq!(
            hit(scaled(1e-15), Ray::new(from(1e-15), Vec3::Z).unwrap()),
            None
        );
        assert_eq!(
            hit(scaled(1e15), Ray::new(from(1e15), Vec3::Z * 1e15).unwrap()),
            None
        );
    }

    #[test]
    fn degenerate_triangles_never_hit() {
        let line = Triangle::new(Vec3::ZERO, Vec3::X, Vec3::X * 2.0);
        let point = Triangle::new(Vec3::ONE, Vec3::ONE, Vec3::ONE);
        for d in [Vec3::Y, Vec3::Z, Vec3::new(1.0, 1.0, 1.0)] {
            let r = Ray::new(Vec3::new(0.5, -1.0, -1.0), d).unwrap();
            assert!(line.intersect(&r, f32::INFINITY).is_none());
            assert!(point.intersect(&r, f32::INFINITY).is_none());
        }
    }

    #[test]
    fn rounding_noise_determinants_never_hit() {
        // Found by the scene fuzz target: a segment-shaped triangle (v1 == v2) whose determinant
        // rounds to a tiny non-zero value "hit" a ray nowhere near it.
        let seg = Triangle::new(
            Vec3::splat(10000.0),
            Vec3::splat(-7500.0),
            Vec3::splat(-7500.0),
        );
        let r = Ray::new(
            Vec3::new(-4.946_645_7, -7.766_198, -3.721_115),
            Vec3::new(-0.460_257_14, -0.836_773_75, -0.296_602_6),
        )
        .unwrap();
        assert!(seg.intersect(&r, f32::INFINITY).is_none());
        // A ray in a triangle's plane, aimed at its own vertex.
        let t = Triangle::new(
            Vec3::ZERO,
            Vec3::new(1.0, 0.0, 0.3),
            Vec3::new(0.2, 1.0, 0.7),
        );
        let inside = (t.v0 + t.v1 + t.v2) / 3.0;
        let r = Ray::new(inside, t.v0 - inside).unwrap();
        assert!(t.intersect(&r, f32::INFINITY).is_none());
        // A ray about 0.01 radians off the plane, aimed at the centroid, still hits.
        let n = (t.v1 - t.v0).cross(t.v2 - t.v0).normalize();
        let origin = inside + (inside - t.v0) - n * 0.01 * (inside - t.v0).length();
        let r = Ray::new(origin, inside - origin).unwrap();
        let hit = t.intersect(&r, f32::INFINITY).unwrap();
        assert!((hit.t - 1.0).abs() < 1e-4);
    }

    /// Found by black-box testing: measured from the origin, a ray from 1e8 units away hit a
    /// 12-unit triangle at `u = v = 0` while passing 3 units beside it. Rays from 1e3 to 1e10
    /// units away (measured from the anchor; further out the f64 reference itself loses 1e-4),
    /// and rays started within a few units of 1-unit triangles 4e5 units from the world origin
    /// (measured from the origin, also when they cross the scene sideways and the anchor lies
    /// nearer), decide like exact arithmetic on their own f32 values, except within 1e-4 of the
    /// triangle's size of an edge; scalar and 4-wide alike.
    #[test]
    fn far_origins_and_far_scenes_decide_like_exact_arithmetic() {
        use crate::geometry::{RayTri4, Triangle4};
        use crate::random::Pcg32;
        let mut rng = Pcg32::new(7);
        let (mut hits, mut misses) = (0, 0);
        let cases = if cfg!(miri) { 50 } else { 4000 };
        let far_scene = Vec3::new(3e5, -2e5, 1e5);
        for i in 0..cases {
            // Even cases: a 12-unit triangle at the world origin, rays from far away. Odd: a
            // 1-unit triangle far out, rays from 0.5 to 4 units away.
            let (centre, size, distance) = match i % 2 {
                0 => (Vec3::ZERO, 12.0, [1e3f32, 1e5, 1e7, 1e8, 1e10][i / 2 % 5]),
                _ => (far_scene, 1.0, rng.range(0.5, 4.0)),
            };
            let mut point = |half: f32| {
                centre
                    + Vec3::new(
                        rng.range(-half, half),
                        rng.range(-half, half),
                        rng.range(-half, half),
                    )
            };
            let tri = Triangle::new(point(size / 2.0), point(size / 2.0), point(size / 2.0));
            let (a, b) = (rng.range(-0.3, 1.3), rng.range(-0.3, 1.3));
            let aim = tri.v0 + (tri.v1 - tri.v0) * a + (tri.v2 - tri.v0) * b;
            let w = Vec3::new(
                rng.range(-1.0, 1.0),
                rng.range(-1.0, 1.0),
                rng.range(-1.0, 1.0),
            );
            // Every other far-scene ray crosses it sideways, at right angles to its position:
            // then the line's point nearest the world origin lies beside the triangle, nearer it
            // than the origin, but is rounded by half an ulp of 1e5 (found by black-box
            // testing: measured from that anchor, 23 in 20,000 such rays flipped hit and miss).
            let w = if i % 4 == 3 {
                let out = far_scene.normalize();
                w - out * w.dot(out)
            } else {
                w
            };
            let origin = aim + w.normalize_or(Vec3::X) * distance;
            let Ok(r) = Ray::new(origin, aim - origin) else {
                continue;
            };
            let e = (tri.v1 - tri.v0).cross(tri.v2 - tri.v0);
            // Well-shaped triangles and rays well off their planes only: the rest is the noise
            // check's business, tested above.
            if e.length() < 0.01 * size * size || e.normalize().dot(r.dir.normalize()).abs() < 0.05
            {
                continue;
            }
            let (t, u, v) = crate::test_scenes::exact_intersection(&tri, &r);
            let margin = 1e-4;
            if [u, v, 1.0 - u - v].iter().any(|x| x.abs() < margin) {
                continue;
            }
            let inside = u > 0.0 && v > 0.0 && u + v < 1.0;
            let got = tri.intersect(&r, f32::INFINITY);
            let mut block = Triangle4::EMPTY;
            block.set(0, &tri, 0);
            let four = block.intersect(&RayTri4::new(&r), f32::INFINITY);
            assert_eq!(four.mask == 1, got.is_some(), "{tri:?} {r:?}");
            assert_eq!(
                got.is_some(),
                inside,
                "{tri:?} {r:?}: exact ({t}, {u}, {v}), got {got:?}"
            );
            if let Some(h) = got {
                assert_eq!(four.t[0].to_bits(), h.t.to_bits());
                assert!(
                    (f64::from(h.t) - t).abs() <= 1e-6 * t,
                    "{h:?} against t {t}"
                );
                assert!(
                    (f64::from(h.u) - u).abs() < margin && (f64::from(h.v) - v).abs() < margin,
                    "{tri:?} {r:?} {h:?} exact {t} {u} {v}"
                );
                hits += 1;
            } else {
                misses += 1;
            }
        }
        assert!(
            hits > cases / 10 && misses > cases / 10,
            "{hits} hits, {misses} misses"
        );
    }

    #[test]
    fn segment_is_closed() {
        let r = Ray::segment(Vec3::new(0.25, 0.25, 0.0), Vec3::Z, 1.0, 1.0).unwrap();
        assert!(tri().intersect(&r, r.t_max).is_some());
    }
}
