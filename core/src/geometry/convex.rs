//! Convex polytopes given by their planes, vertices, face normals and edge directions, and the
//! separating-axis test between them: exact overlap for boxes, triangles, oriented boxes and
//! frustums.

use glam::Vec3;

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

    /// True when `p` is inside (boundary included, with the same relative tolerance).
    #[inline]
    pub fn contains(&self, p: Vec3) -> bool {
        let tol = self.tolerance(p.abs().max_element());
        self.planes
            .iter()
            .all(|pl| pl.signed(p) <= tol * pl.normal.length())
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
