//! Geometric primitives: boxes, rays and triangles, with the intersection tests the BVH needs.

mod aabb;
mod ray;
mod triangle;

pub use aabb::Aabb;
pub use ray::{Ray, RayError};
pub use triangle::{Triangle, TriangleHit};
