//! Geometric primitives: boxes, rays, triangles, oriented boxes and frustums, with the
//! intersection and separating-axis tests the BVHs and influence areas need.

mod aabb;
mod convex;
mod frame;
mod frustum;
mod obb;
mod polygon;
mod projection;
mod ray;
mod solid_angle;
mod triangle;
mod triangle4;

pub(crate) use aabb::pad_far;
pub use aabb::Aabb;
pub use convex::{Plane, PlaneLanes, Polytope};
pub use frame::Frame;
pub use frustum::Frustum;
pub use obb::Obb;
pub(crate) use polygon::clip_convex;
pub use polygon::{ConvexPolygon, MAX_POLY};
pub use projection::{
    box_corner, orthographic_silhouette, orthographic_slab_silhouette, perspective_silhouette,
    perspective_window_silhouette, windowed_silhouette, MIN_RELATIVE_DEPTH, PRECISE_SPAN,
};
pub use ray::{Ray, RayError};
#[cfg(test)]
pub(crate) use solid_angle::tests::{front_faces_f64, reference as box_solid_angle_f64};
pub use solid_angle::{box_solid_angle4, box_solid_angle_far4, far_field4, FarFace, FAR_FIELD};
pub use triangle::{Triangle, TriangleHit};
pub use triangle4::{Hits4, RayTri4, Triangle4, TriangleEdges};
