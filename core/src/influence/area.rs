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

    /// The affinity test of the area's kind.
    pub fn is_affine(&self, ray: &Ray) -> bool {
        match self {
            InfluenceArea::Plane(a) => a.is_affine(ray),
            InfluenceArea::Point(a) => a.is_affine(ray),
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
