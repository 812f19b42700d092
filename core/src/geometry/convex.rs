//! Convex polytopes given by their planes, vertices, face normals and edge directions, and the
//! separating-axis test between them: exact overlap for boxes, triangles, oriented boxes and
//! frustums.

use glam::Vec3;
use wide::f32x4;

use super::{Aabb, Ray, Triangle};

/// A half-space `normal . p <= offset` (the outward normal need not be unit length).
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Plane {
    /// Outward normal.
    pub normal: Vec3,
    /// Offset: points with `normal . p <= offset` are inside.
    pub offset: f32,
}

impl Plane {
    /// The plane through `point` with outward normal `normal`.
    #[inline]
    pub fn through(point: Vec3, normal: Vec3) -> Self {
        Self {
            normal,
            offset: normal.dot(point),
        }
    }

    /// Signed distance scaled by `|normal|`: positive outside.
    #[inline]
    pub fn signed(&self, p: Vec3) -> f32 {
        self.normal.dot(p) - self.offset
    }
}

/// A convex polytope with at most 8 vertices and 6 faces: an oriented box or a frustum. The face
/// normals and edge directions are the separating-axis candidates it contributes.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Polytope {
    /// The six bounding planes, outward.
    pub planes: [Plane; 6],
    /// The eight corners.
    pub vertices: [Vec3; 8],
    /// Distinct face normals (`face_count` of them are used).
    pub face_normals: [Vec3; 5],
    /// How many of `face_normals` are used.
    pub face_count: usize,
    /// Distinct edge directions (`edge_count` of them are used).
    pub edges: [Vec3; 6],
    /// How many of `edges` are used.
    pub edge_count: usize,
    /// A length scale (the largest vertex coordinate magnitude) for tolerances.
    pub scale: f32,
    /// `|normal|` of each plane, for [`Polytope::contains`]'s tolerance: kept, not recomputed, so
    /// a containment test costs no square root.
    pub normal_lengths: [f32; 6],
    /// The planes again, four to a lane group, for [`Polytope::clip_ray_from_inside`].
    pub lanes: PlaneLanes,
}

/// Six planes as two groups of four lanes: normals' `x`, `y`, `z`, offsets and normal lengths.
/// The last two lanes are neutral (a zero normal and an infinite offset clip nothing and contain
/// everything), so every lane computes what the scalar loop computes for its plane.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct PlaneLanes {
    x: [[f32; 4]; 2],
    y: [[f32; 4]; 2],
    z: [[f32; 4]; 2],
    offset: [[f32; 4]; 2],
    len: [[f32; 4]; 2],
}

impl PlaneLanes {
    /// The lanes of `planes`, whose normals have the lengths `lengths`.
    pub fn new(planes: &[Plane; 6], lengths: &[f32; 6]) -> Self {
        let lane = |f: &dyn Fn(usize) -> f32, neutral: f32| {
            core::array::from_fn(|g| {
                core::array::from_fn(|k| {
                    let i = 4 * g + k;
                    if i < 6 {
                        f(i)
                    } else {
                        neutral
                    }
                })
            })
        };
        Self {
            x: lane(&|i| planes[i].normal.x, 0.0),
            y: lane(&|i| planes[i].normal.y, 0.0),
            z: lane(&|i| planes[i].normal.z, 0.0),
            offset: lane(&|i| planes[i].offset, f32::INFINITY),
            len: lane(&|i| lengths[i], 0.0),
        }
    }
}

/// The interval of `points` projected on `axis`.
#[inline]
fn project(points: &[Vec3], axis: Vec3) -> (f32, f32) {
    points
        .iter()
        .fold((f32::INFINITY, f32::NEG_INFINITY), |(lo, hi), p| {
            let d = p.dot(axis);
            (lo.min(d), hi.max(d))
        })
}

/// True when no axis in `axes` separates the two point sets by more than `tol` (relative to the
/// axis length). Near-zero axes (parallel edges) are skipped.
#[inline]
fn no_separating_axis(a: &[Vec3], b: &[Vec3], axes: impl Iterator<Item = Vec3>, tol: f32) -> bool {
    for axis in axes {
        let len2 = axis.length_squared();
        // Parallel edges give a zero axis; NaN axes are skipped too.
        if len2.is_nan() || len2 <= 1e-20 {
            continue;
        }
        let (a_lo, a_hi) = project(a, axis);
        let (b_lo, b_hi) = project(b, axis);
        let pad = tol * libm::sqrtf(len2);
        if a_hi < b_lo - pad || b_hi < a_lo - pad {
            return false;
        }
    }
    true
}

const BOX_AXES: [Vec3; 3] = [Vec3::X, Vec3::Y, Vec3::Z];

fn box_corners(b: &Aabb) -> [Vec3; 8] {
    core::array::from_fn(|i| {
        Vec3::new(
            if i & 1 == 0 { b.min.x } else { b.max.x },
            if i & 2 == 0 { b.min.y } else { b.max.y },
            if i & 4 == 0 { b.min.z } else { b.max.z },
        )
    })
}

impl Polytope {
    fn faces(&self) -> &[Vec3] {
        &self.face_normals[..self.face_count]
    }

    fn edge_dirs(&self) -> &[Vec3] {
        &self.edges[..self.edge_count]
    }

    /// The separation tolerance: a relative `1e-5` of the larger of the two scales, so rounding
    /// can only make the test say "overlap", never miss one. A triangle wrongly kept in a local
    /// BVH costs a little time; a triangle wrongly dropped would cost a wrong answer.
    #[inline]
    fn tolerance(&self, other_scale: f32) -> f32 {
        1e-5 * self.scale.max(other_scale).max(1e-30)
    }

    /// A box holding every point [`Polytope::contains`] accepts: the corners' box grown by the
    /// containment tolerance (twice over, for the tolerance's own growth with `|p|` and for
    /// rounding). The corners' box alone can lose a face's points to rounding: an area's light
    /// face, where its rays start, can round a few ulps outside it.
    pub fn containment_bounds(&self) -> Aabb {
        let b = Aabb::from_points(&self.vertices);
        let scale = self.scale.max(b.min.abs().max(b.max.abs()).max_element());
        let margin = Vec3::splat(2.0 * self.tolerance(scale));
        Aabb::new(b.min - margin, b.max + margin)
    }

    /// True when every corner, plane and axis is finite (inputs near `f32::MAX` can overflow).
    pub fn is_finite(&self) -> bool {
        self.vertices.iter().all(|v| v.is_finite())
            && self
                .planes
                .iter()
                .all(|p| p.normal.is_finite() && p.offset.is_finite())
            && self.scale.is_finite()
    }

    /// The lengths of `planes`' normals, as [`Polytope::normal_lengths`] keeps them.
    pub fn lengths_of(planes: &[Plane; 6]) -> [f32; 6] {
        core::array::from_fn(|i| planes[i].normal.length())
    }

    /// True when `p` is inside (boundary included, with the same relative tolerance).
    #[inline]
    pub fn contains(&self, p: Vec3) -> bool {
        let tol = self.tolerance(p.abs().max_element());
        self.planes
            .iter()
            .zip(&self.normal_lengths)
            .all(|(pl, &len)| pl.signed(p) <= tol * len)
    }

    /// Exact (conservative by a relative `1e-5`) overlap with an axis-aligned box.
    pub fn overlaps_aabb(&self, b: &Aabb) -> bool {
        let corners = box_corners(b);
        let scale = b.min.abs().max(b.max.abs()).max_element();
        let tol = self.tolerance(scale);
        let crosses = self
            .edge_dirs()
            .iter()
            .flat_map(|&e| BOX_AXES.iter().map(move |&a| e.cross(a)));
        no_separating_axis(
            &self.vertices,
            &corners,
            self.faces()
                .iter()
                .copied()
                .chain(BOX_AXES.iter().copied())
                .chain(crosses),
            tol,
        )
    }

    /// Exact (conservative by a relative `1e-5`) overlap with a triangle. Degenerate triangles are
    /// tested as the segment or point they are: their zero normal is skipped, and the polytope's
    /// face normals with the edge cross products are a complete axis set for those.
    pub fn overlaps_triangle(&self, t: &Triangle) -> bool {
        let verts = [t.v0, t.v1, t.v2];
        let scale = t.v0.abs().max(t.v1.abs()).max(t.v2.abs()).max_element();
        let tol = self.tolerance(scale);
        let tri_edges = [t.v1 - t.v0, t.v2 - t.v1, t.v0 - t.v2];
        let normal = tri_edges[0].cross(tri_edges[1]);
        let crosses = self
            .edge_dirs()
            .iter()
            .flat_map(|&e| tri_edges.iter().map(move |&a| e.cross(a)));
        no_separating_axis(
            &self.vertices,
            &verts,
            self.faces()
                .iter()
                .copied()
                .chain(core::iter::once(normal))
                .chain(crosses),
            tol,
        )
    }

    /// The parameter interval `(t_enter, t_exit)` where the ray's line is inside the polytope,
    /// clipped to `[ray.t_min, ray.t_max]`; `None` when it misses (Cyrus-Beck clipping).
    pub fn clip_ray(&self, ray: &Ray) -> Option<(f32, f32)> {
        let (mut t0, mut t1) = (ray.t_min, ray.t_max);
        for pl in &self.planes {
            let denom = pl.normal.dot(ray.dir);
            let num = pl.offset - pl.normal.dot(ray.origin);
            if denom > 0.0 {
                t1 = t1.min(num / denom);
            } else if denom < 0.0 {
                t0 = t0.max(num / denom);
            } else if num < 0.0 {
                return None;
            }
        }
        (t0 <= t1).then_some((t0, t1))
    }

    /// [`Polytope::clip_ray`] for a ray whose origin [`Polytope::contains`], `None` otherwise:
    /// both in one pass over the planes, four at a time, which share the origin's side of each.
    /// The same answer as the two calls: each lane does the scalar arithmetic (`offset - n.o` is
    /// exactly `-(n.o - offset)`), and min and max do not depend on the order.
    #[inline]
    pub fn clip_ray_from_inside(&self, ray: &Ray) -> Option<(f32, f32)> {
        let tol = f32x4::splat(self.tolerance(ray.origin.abs().max_element()));
        let l = &self.lanes;
        let s = f32x4::splat;
        let (o, d) = (ray.origin, ray.dir);
        let (mut t0, mut t1) = (s(ray.t_min), s(ray.t_max));
        for g in 0..2 {
            let (x, y, z) = (
                f32x4::from(l.x[g]),
                f32x4::from(l.y[g]),
                f32x4::from(l.z[g]),
            );
            let denom = x * s(d.x) + y * s(d.y) + z * s(d.z);
            let num = f32x4::from(l.offset[g]) - (x * s(o.x) + y * s(o.y) + z * s(o.z));
            let zero = f32x4::ZERO;
            let inside = (-num).simd_le(tol * f32x4::from(l.len[g]));
            let parallel_outside = denom.simd_eq(zero) & num.simd_lt(zero);
            if !inside.all() || parallel_outside.any() {
                return None;
            }
            let t = num / denom;
            t1 = denom.simd_gt(zero).bitselect(t1.min(t), t1);
            t0 = denom.simd_lt(zero).bitselect(t0.max(t), t0);
        }
        let [a, b, c, e] = t0.to_array();
        let [f, g, h, i] = t1.to_array();
        let (t0, t1) = (a.max(b).max(c.max(e)), f.min(g).min(h.min(i)));
        (t0 <= t1).then_some((t0, t1))
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::geometry::Frame;
    use crate::geometry::Obb;

    fn cube() -> Polytope {
        Obb::new(Vec3::ZERO, Frame::look_at(Vec3::Z).unwrap(), Vec3::ONE)
            .unwrap()
            .polytope()
    }

    #[test]
    fn clip_from_inside_equals_contains_then_clip() {
        use crate::geometry::Frustum;
        use crate::random::Pcg32;
        let frame = Frame::look_at(Vec3::new(0.3, -1.0, 0.2)).unwrap();
        let shapes = [
            cube(),
            Obb::new(Vec3::new(1.0, 2.0, -3.0), frame, Vec3::new(0.5, 2.0, 4.0))
                .unwrap()
                .polytope(),
            Frustum::new(Vec3::new(0.0, 3.0, 0.0), frame, 0.7, 1.3, 0.0, 6.0)
                .unwrap()
                .polytope(),
            Frustum::new(Vec3::ZERO, frame, 2.0, 0.4, 0.5, 3.0)
                .unwrap()
                .polytope(),
        ];
        let mut rng = Pcg32::new(17);
        let mut v = |s: f32| Vec3::new(rng.range(-s, s), rng.range(-s, s), rng.range(-s, s));
        // Miri interprets every instruction: a few hundred rays a shape there.
        let rays = if cfg!(miri) { 300 } else { 20_000 };
        let mut inside = 0;
        for shape in &shapes {
            for i in 0..rays {
                // Axis-parallel directions (zero components) and origins on faces included.
                let mut dir = v(1.0);
                if i % 7 == 0 {
                    dir.x = 0.0;
                }
                if i % 11 == 0 {
                    dir = Vec3::Z;
                }
                let origin = if i % 13 == 0 {
                    shape.vertices[i % 8]
                } else {
                    v(4.0)
                };
                let Ok(ray) = Ray::segment(origin, dir, -1.0 + (i % 3) as f32, 10.0) else {
                    continue;
                };
                let expected = shape
                    .contains(ray.origin)
                    .then(|| shape.clip_ray(&ray))
                    .flatten();
                assert_eq!(shape.clip_ray_from_inside(&ray), expected, "{ray:?}");
                inside += usize::from(expected.is_some());
            }
        }
        assert!(inside > rays / 4, "{inside}");
    }

    #[test]
    fn box_overlap() {
        let c = cube();
        assert!(c.overlaps_aabb(&Aabb::new(Vec3::splat(0.5), Vec3::splat(2.0))));
        assert!(
            c.overlaps_aabb(&Aabb::new(Vec3::splat(1.0), Vec3::splat(2.0))),
            "touching"
        );
        assert!(!c.overlaps_aabb(&Aabb::new(Vec3::splat(1.1), Vec3::splat(2.0))));
    }

    #[test]
    fn large_triangle_crossing_without_vertex_inside() {
        let c = cube();
        let t = Triangle::new(
            Vec3::new(-10.0, -10.0, 0.0),
            Vec3::new(10.0, -10.0, 0.0),
            Vec3::new(0.0, 10.0, 0.0),
        );
        assert!(c.overlaps_triangle(&t));
        // The same triangle moved past the cube's corner along x + y.
        let off = Vec3::new(0.0, 0.0, 1.5);
        let t2 = Triangle::new(t.v0 + off, t.v1 + off, t.v2 + off);
        assert!(!c.overlaps_triangle(&t2));
        // A triangle in the plane x + y = 2.2, just past the cube's edge at x = y = 1: its box
        // overlaps the cube, only its normal separates them. In the plane x + y = 1.6 it cuts the
        // cube's corner without a vertex inside.
        let sliver = |k: f32| {
            Triangle::new(
                Vec3::new(k, 0.0, -5.0),
                Vec3::new(0.0, k, -5.0),
                Vec3::new(0.0, k, 5.0),
            )
        };
        assert!(!c.overlaps_triangle(&sliver(2.2)));
        assert!(c.overlaps_triangle(&sliver(1.6)));
    }

    #[test]
    fn degenerate_triangle_as_segment() {
        let c = cube();
        let seg = Triangle::new(
            Vec3::new(-3.0, 0.0, 0.0),
            Vec3::new(3.0, 0.0, 0.0),
            Vec3::new(3.0, 0.0, 0.0),
        );
        assert!(c.overlaps_triangle(&seg));
        let off = Triangle::new(
            Vec3::new(-3.0, 1.8, 0.0),
            Vec3::new(0.0, 1.8, 3.0),
            Vec3::new(0.0, 1.8, 3.0),
        );
        assert!(!c.overlaps_triangle(&off));
    }

    #[test]
    fn clip_and_contain() {
        let c = cube();
        assert!(c.contains(Vec3::splat(0.999)));
        assert!(!c.contains(Vec3::splat(1.01)));
        let r = Ray::new(Vec3::ZERO, Vec3::X).unwrap();
        let (t0, t1) = c.clip_ray(&r).unwrap();
        assert_eq!(t0, 0.0);
        assert!((t1 - 1.0).abs() < 1e-6);
        let r = Ray::new(Vec3::new(0.0, 2.0, 0.0), Vec3::X).unwrap();
        assert!(c.clip_ray(&r).is_none());
    }
}
