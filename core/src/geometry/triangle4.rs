//! Four triangles as structure-of-arrays lanes, precomputed for Moller-Trumbore: one 4-wide test
//! gives the same accept/reject decisions and the same `t`, `u`, `v`, bit for bit, as four calls
//! of [`Triangle::intersect`].

use bytemuck::{Pod, Zeroable};
use wide::f32x4;

use glam::Vec3;

use super::triangle::determinant_is_noise;
use super::{Ray, Triangle};

/// Four triangles, one per lane: `v0` and the edges `e1 = v1 - v0`, `e2 = v2 - v0` per axis (the
/// edges are computed once here, with the same single subtraction the scalar test does per ray),
/// and the triangle ids. An unused lane has all-zero geometry, hence a zero determinant, which the
/// test rejects like any degenerate triangle.
#[derive(Clone, Copy, Debug, PartialEq, Pod, Zeroable)]
#[repr(C, align(16))]
pub struct Triangle4 {
    /// First vertices, per axis.
    pub v0: [[f32; 4]; 3],
    /// `v1 - v0`, per axis.
    pub e1: [[f32; 4]; 3],
    /// `v2 - v0`, per axis.
    pub e2: [[f32; 4]; 3],
    /// Triangle ids; [`Triangle4::UNUSED_ID`] for an unused lane.
    pub id: [u32; 4],
}

static_assertions::assert_eq_size!(Triangle4, [u8; 160]);

/// One lane of a [`Triangle4`]: a triangle as the intersection test sees it, its first vertex and
/// the edges `e1 = v1 - v0`, `e2 = v2 - v0` (computed once by [`Triangle4::set`] with the scalar
/// test's subtractions, so bit for bit `tri.v1 - tri.v0` and `tri.v2 - tri.v0`). A hit's point
/// `v0 + e1 u + e2 v` and normal `e1 x e2` come from it without the scene's own triangle array,
/// whose entry for the hit is usually not in the caches when the leaf's block is.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct TriangleEdges {
    /// The first vertex.
    pub v0: Vec3,
    /// `v1 - v0`.
    pub e1: Vec3,
    /// `v2 - v0`.
    pub e2: Vec3,
}

/// The hits of a [`Triangle4`] test: the bitmask of lanes hit and their `t`, `u`, `v`.
#[derive(Clone, Copy, Debug)]
pub struct Hits4 {
    /// Bit `j` set when lane `j` is hit on the segment.
    pub mask: u32,
    /// Ray parameters (meaningful only in hit lanes).
    pub t: [f32; 4],
    /// Barycentric weights of `v1`.
    pub u: [f32; 4],
    /// Barycentric weights of `v2`.
    pub v: [f32; 4],
}

/// A ray's origin, anchor and direction splatted over four lanes, and its squared length for the
/// determinant check, prepared once per ray.
#[derive(Clone, Copy, Debug)]
pub struct RayTri4 {
    /// The ray's origin and anchor ([`Ray::anchor`]): the test measures from the one that errs
    /// less (`Ray::measures_from_anchor`).
    origin: [f32x4; 3],
    anchor: [f32x4; 3],
    anchor_t: f32x4,
    anchor_split: f32x4,
    dir: [f32x4; 3],
    dir_len_sq: f64,
    t_min: f32x4,
}

impl RayTri4 {
    /// Splats `ray`.
    #[inline(always)]
    pub fn new(ray: &Ray) -> Self {
        let s = f32x4::splat;
        Self {
            origin: [s(ray.origin.x), s(ray.origin.y), s(ray.origin.z)],
            anchor: [s(ray.anchor.x), s(ray.anchor.y), s(ray.anchor.z)],
            anchor_t: s(ray.anchor_t),
            anchor_split: s(ray.anchor_split),
            dir: [s(ray.dir.x), s(ray.dir.y), s(ray.dir.z)],
            dir_len_sq: ray.dir_len_sq,
            t_min: s(ray.t_min),
        }
    }
}

#[inline(always)]
fn load(a: &[[f32; 4]; 3]) -> [f32x4; 3] {
    [f32x4::from(a[0]), f32x4::from(a[1]), f32x4::from(a[2])]
}

/// `glam::Vec3::cross`, lane-wise, in its operation order.
#[inline(always)]
fn cross(a: [f32x4; 3], b: [f32x4; 3]) -> [f32x4; 3] {
    [
        a[1] * b[2] - b[1] * a[2],
        a[2] * b[0] - b[2] * a[0],
        a[0] * b[1] - b[0] * a[1],
    ]
}

/// `glam::Vec3::dot`, lane-wise, in its operation order: `(x x' + y y') + z z'`.
#[inline(always)]
fn dot(a: [f32x4; 3], b: [f32x4; 3]) -> f32x4 {
    a[0] * b[0] + a[1] * b[1] + a[2] * b[2]
}

impl Triangle4 {
    /// The id of an unused lane.
    pub const UNUSED_ID: u32 = u32::MAX;

    /// An all-unused block.
    pub const EMPTY: Triangle4 = Triangle4 {
        v0: [[0.0; 4]; 3],
        e1: [[0.0; 4]; 3],
        e2: [[0.0; 4]; 3],
        id: [Self::UNUSED_ID; 4],
    };

    /// Lane `j`'s first vertex and edges.
    #[inline]
    pub fn edges(&self, j: usize) -> TriangleEdges {
        let v = |rows: &[[f32; 4]; 3]| Vec3::new(rows[0][j], rows[1][j], rows[2][j]);
        TriangleEdges {
            v0: v(&self.v0),
            e1: v(&self.e1),
            e2: v(&self.e2),
        }
    }

    /// Puts triangle `tri` with id `id` in lane `j`.
    pub fn set(&mut self, j: usize, tri: &Triangle, id: u32) {
        // The same subtractions as `Triangle::intersect`, so the edges are bit-identical.
        let e1 = tri.v1 - tri.v0;
        let e2 = tri.v2 - tri.v0;
        for k in 0..3 {
            self.v0[k][j] = tri.v0[k];
            self.e1[k][j] = e1[k];
            self.e2[k][j] = e2[k];
        }
        self.id[j] = id;
    }

    /// Moller-Trumbore on the four lanes against the segment `[ray.t_min, t_max]`, under
    /// [`Triangle::intersect`]'s policy and with its exact arithmetic: every product, sum and
    /// comparison in the same order, so a lane is hit exactly when the scalar test hits its
    /// triangle, with the same `t`, `u` and `v`. The scalar test's early exits become masks; the
    /// determinant-noise check (the scalar test's own function, in f64) runs only for the lanes
    /// still hit.
    #[inline(always)]
    pub fn intersect(&self, ray: &RayTri4, t_max: f32) -> Hits4 {
        let e1 = load(&self.e1);
        let e2 = load(&self.e2);
        let v0 = load(&self.v0);
        let p = cross(ray.dir, e2);
        let det = dot(e1, p);
        let inv_det = f32x4::ONE / det;
        // `Ray::measures_from_anchor`, lane by lane.
        let anchored = dot(v0, ray.dir).simd_gt(ray.anchor_split);
        let s: [f32x4; 3] =
            core::array::from_fn(|k| anchored.select(ray.anchor[k], ray.origin[k]) - v0[k]);
        let t0 = anchored.select(ray.anchor_t, f32x4::ZERO);
        let u = dot(s, p) * inv_det;
        let q = cross(s, e1);
        let v = dot(ray.dir, q) * inv_det;
        let t = t0 + dot(e2, q) * inv_det;
        let zero = f32x4::ZERO;
        let one = f32x4::ONE;
        // Each comparison is false for NaN, as in the scalar test.
        let ok = !det.simd_eq(zero)
            & u.simd_ge(zero)
            & u.simd_le(one)
            & v.simd_ge(zero)
            & (u + v).simd_le(one)
            & t.simd_ge(ray.t_min)
            & t.simd_le(f32x4::splat(t_max))
            & t.abs().simd_lt(f32x4::splat(f32::INFINITY));
        let mut mask = ok.to_bitmask();
        if mask != 0 {
            let edge = |e: &[[f32; 4]; 3], j: usize| Vec3::new(e[0][j], e[1][j], e[2][j]);
            for (j, &det) in det.to_array().iter().enumerate() {
                if mask & (1 << j) != 0
                    && determinant_is_noise(
                        det,
                        ray.dir_len_sq,
                        edge(&self.e1, j),
                        edge(&self.e2, j),
                    )
                {
                    mask &= !(1 << j);
                }
            }
        }
        Hits4 {
            mask,
            t: t.to_array(),
            u: u.to_array(),
            v: v.to_array(),
        }
    }

    /// True when a lane is hit on `[ray.t_min, t_max]` (the same decisions as
    /// [`Triangle4::intersect`]).
    #[inline(always)]
    pub fn any_hit(&self, ray: &RayTri4, t_max: f32) -> bool {
        self.intersect(ray, t_max).mask != 0
    }
}

#[cfg(test)]
mod tests {
    use alloc::vec::Vec;

    use glam::Vec3;

    use super::*;
    use crate::random::Pcg32;

    /// Every lane agrees with the scalar test bit for bit, on random and adversarial triangles
    /// (degenerate, tiny, huge, axis-aligned) and rays (in the plane, through vertices, along
    /// axes), and unused lanes never hit.
    #[test]
    fn lanes_match_the_scalar_test_bit_for_bit() {
        let mut rng = Pcg32::new(4);
        let mut v = |s: f32| Vec3::new(rng.range(-s, s), rng.range(-s, s), rng.range(-s, s));
        // Miri runs a tenth of the cases (the CI's Miri pass covers geometry::).
        let cases = if cfg!(miri) { 40 } else { 400 };
        let mut tris = Vec::new();
        for i in 0..cases {
            let a = v(4.0);
            let (b, c) = match i % 8 {
                // Degenerate: a segment and a point.
                0 => (a + Vec3::X, a + Vec3::X * 2.0),
                1 => (a, a),
                // Axis-aligned, in the plane z = a.z.
                2 => (a + Vec3::new(3.0, 0.0, 0.0), a + Vec3::new(0.0, 3.0, 0.0)),
                // Tiny.
                3 => (a + v(1e-6), a + v(1e-6)),
                // Huge.
                4 => (a + v(1e6), a + v(1e6)),
                _ => (a + v(3.0), a + v(3.0)),
            };
            tris.push(Triangle::new(a, b, c));
        }
        let mut rays = Vec::new();
        for i in 0..cases {
            let o = v(6.0);
            let t = &tris[i % tris.len()];
            let d = match i % 6 {
                // Towards a vertex, the centroid, along the triangle's plane.
                0 => t.v0 - o,
                1 => t.centroid() - o,
                2 => t.v1 - t.v0,
                3 => Vec3::new(0.0, 0.0, 1.0),
                _ => v(1.0),
            };
            let (t_min, t_max) = match i % 5 {
                0 => (0.5, 2.0),
                1 => (-1.0, f32::INFINITY),
                _ => (0.0, f32::INFINITY),
            };
            if let Ok(r) = Ray::segment(o, d, t_min, t_max) {
                rays.push(r);
            }
            // A ray in the axis-aligned triangles' planes.
            if let Ok(r) = Ray::new(Vec3::new(o.x, o.y, t.v0.z), Vec3::new(d.x, d.y, 0.0)) {
                rays.push(r);
            }
        }
        let mut hits = 0;
        for chunk in tris.chunks(3) {
            // Three triangles and one unused lane per block.
            let mut block = Triangle4::EMPTY;
            for (j, t) in chunk.iter().enumerate() {
                block.set(j, t, j as u32);
            }
            for ray in &rays {
                for t_max in [ray.t_max, 1.0] {
                    let h = block.intersect(&RayTri4::new(ray), t_max);
                    assert_eq!(h.mask & !((1 << chunk.len()) - 1), 0, "unused lane hit");
                    for (j, t) in chunk.iter().enumerate() {
                        let scalar = t.intersect(ray, t_max);
                        assert_eq!(h.mask & (1 << j) != 0, scalar.is_some(), "{t:?} {ray:?}");
                        if let Some(s) = scalar {
                            hits += 1;
                            assert_eq!(s.t.to_bits(), h.t[j].to_bits());
                            assert_eq!(s.u.to_bits(), h.u[j].to_bits());
                            assert_eq!(s.v.to_bits(), h.v[j].to_bits());
                            assert!(h.t[j].is_finite());
                        }
                    }
                    assert_eq!(block.any_hit(&RayTri4::new(ray), t_max), h.mask != 0);
                }
            }
        }
        assert!(hits > cases / 4, "too few hits ({hits}) to mean anything");
    }
}
