//! Influence areas: the regions where next event estimation makes rays coherent.
//!
//! A [`PlaneArea`] (an oriented box in front of a planar area light) holds parallel rays; a
//! [`PointArea`] (a frustum in front of a point or spot light) holds radial rays. Each offers point
//! containment, exact separating-axis overlap with boxes and triangles, the exit distance of a ray
//! segment, and the affinity test that decides whether a ray may use the area's local BVH. A
//! [`RaySampler`] draws the rays each area models.

mod area;
mod error;
mod plane;
mod point;
mod sampler;

pub use area::InfluenceArea;
pub use error::{AreaError, MAX_AREA_COORDINATE, MIN_WINDOW_MEASURE};
pub use plane::PlaneArea;
pub use point::PointArea;
pub use sampler::{PointDistribution, RaySampler};

/// The default angular tolerance of the affinity test, in degrees.
pub const DEFAULT_AFFINITY_DEG: f32 = 1.0;
