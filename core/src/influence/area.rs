//! Either kind of influence area behind one type, for the scene structure and the host.

use glam::Vec3;

use super::{PlaneArea, PointArea};
use crate::geometry::{Aabb, Polytope, Ray, Triangle};

/// A plane or a point influence area.
#[derive(Clone, Copy, Debug, PartialEq)]
pub enum InfluenceArea {
    /// Parallel rays in an oriented box.
    Plane(PlaneArea),
    /// Radial rays in a frustum.
    Point(PointArea),
}

impl From<PlaneArea> for InfluenceArea {
    fn from(a: PlaneArea) -> Self {
        InfluenceArea::Plane(a)
    }
}

impl From<PointArea> for InfluenceArea {
    fn from(a: PointArea) -> Self {
        InfluenceArea::Point(a)
    }
}

impl InfluenceArea {
    /// The area's shape as a polytope.
    pub fn polytope(&self) -> &Polytope {
        match self {
            InfluenceArea::Plane(a) => a.polytope(),
            InfluenceArea::Point(a) => a.polytope(),
        }
    }

    /// The axis-aligned bounds of the area's shape.
    pub fn bounds(&self) -> Aabb {
        Aabb::from_points(&self.polytope().vertices)
    }

    /// True when `p` is inside.
    pub fn contains(&self, p: Vec3) -> bool {
        self.polytope().contains(p)
    }

    /// Exact overlap with a box.
    pub fn overlaps_aabb(&self, b: &Aabb) -> bool {
        self.polytope().overlaps_aabb(b)
    }

    /// Exact overlap with a triangle.
    pub fn overlaps_triangle(&self, t: &Triangle) -> bool {
        self.polytope().overlaps_triangle(t)
    }

    /// Where the segment leaves the area, if it is inside it somewhere.
    pub fn exit(&self, ray: &Ray) -> Option<f32> {
        self.polytope().clip_ray(ray).map(|(_, t1)| t1)
    }

    /// The ids of the triangles of `tris` this area's local BVH holds ([`crate::toplevel::TopLevel`]
    /// builds it over them): those [`InfluenceArea::takes_triangle`] takes, in id order.
    pub fn triangles_in<'a>(&'a self, tris: &'a [Triangle]) -> impl Iterator<Item = u32> + 'a {
        let bounds = self.bounds().padded();
        (0..tris.len() as u32).filter(move |&t| self.takes_triangle(&bounds, &tris[t as usize]))
    }

    /// Whether this area (whose `self.bounds().padded()` is `bounds`) takes triangle `tri` into
    /// its local BVH: a test of the padded boxes the BVH nodes use, then the separating-axis test
    /// ([`crate::geometry::Polytope::overlaps_triangle`], conservative by a relative 1e-5 of the
    /// larger coordinate magnitude). Neither drops a triangle the area touches; a very large area
    /// also takes triangles within that margin: more work, never a different answer. Every
    /// command and the experiment runner select an area's triangles by this one test.
    #[inline]
    pub fn takes_triangle(&self, bounds: &Aabb, tri: &Triangle) -> bool {
        !tri.bounds().padded().intersection(*bounds).is_empty() && self.overlaps_triangle(tri)
    }

    /// The affinity test of the area's kind.
    pub fn is_affine(&self, ray: &Ray) -> bool {
        match self {
            InfluenceArea::Plane(a) => a.is_affine(ray),
            InfluenceArea::Point(a) => a.is_affine(ray),
        }
    }

    /// The part of the segment inside the area, `[t0, t1]`, when the ray is affine; `None` when it
    /// is not or the segment misses the area. Equal to [`InfluenceArea::is_affine`] followed by
    /// the clip to the area's polytope, in one pass: the scene's per-ray test.
    #[inline]
    pub fn affine_clip(&self, ray: &Ray) -> Option<(f32, f32)> {
        match self {
            InfluenceArea::Plane(a) => a.affine_clip(ray),
            InfluenceArea::Point(a) => a.affine_clip(ray),
        }
    }

    /// The area's ray direction at `p` (unit): the normal, or eye to `p`.
    pub fn direction_at(&self, p: Vec3) -> Vec3 {
        match self {
            InfluenceArea::Plane(a) => a.frame.forward,
            InfluenceArea::Point(a) => a.direction_at(p),
        }
    }
}
