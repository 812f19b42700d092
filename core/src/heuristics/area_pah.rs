//! PAH for an influence area, whichever its kind: the one cost model that estimates any local
//! BVH's cost (the builders themselves are monomorphised per kind of area).

use wide::f32x4;

use super::{CostModel, PahOrtho, PahPerspective, PerspectiveMeasure};
use crate::geometry::Aabb;
use crate::influence::InfluenceArea;
use crate::simd::Aabb4;

/// PAH for an influence area: orthographic for a plane area, perspective for a point area. For
/// estimating a built tree's cost (the builders themselves are monomorphised per kind).
// The perspective model carries its 4-wide constants (about 600 bytes): one value per build or
// estimate lives on the stack, and boxing it would allocate where builds promise not to.
#[allow(clippy::large_enum_variant)]
#[derive(Clone, Copy, Debug, PartialEq)]
pub enum AreaPah {
    /// Parallel rays.
    Ortho(PahOrtho),
    /// Radial rays.
    Perspective(PahPerspective),
}

impl AreaPah {
    /// The PAH of `area`, culled to its window.
    pub fn new(area: &InfluenceArea, perspective: PerspectiveMeasure) -> Self {
        match area {
            InfluenceArea::Plane(a) => AreaPah::Ortho(PahOrtho::for_area(a)),
            InfluenceArea::Point(a) => {
                AreaPah::Perspective(PahPerspective::for_area(a, perspective))
            }
        }
    }

    /// The measure of the whole window: every sampled ray starts in it, so a box's measure over
    /// this is its hit probability.
    pub fn window_measure(&self) -> f32 {
        match self {
            AreaPah::Ortho(p) => p.window_measure().unwrap_or(0.0),
            AreaPah::Perspective(p) => p.window_measure(),
        }
    }
}

impl CostModel for AreaPah {
    fn measure(&self, b: &Aabb) -> f32 {
        match self {
            AreaPah::Ortho(p) => p.measure(b),
            AreaPah::Perspective(p) => p.measure(b),
        }
    }

    /// Forwarded so the sweeps get each model's 4-wide evaluation, not four scalar calls.
    #[inline]
    fn measure4(&self, b: &Aabb4) -> f32x4 {
        match self {
            AreaPah::Ortho(p) => p.measure4(b),
            AreaPah::Perspective(p) => p.measure4(b),
        }
    }

    #[inline]
    fn hint(&self, node: &Aabb) -> u32 {
        match self {
            AreaPah::Ortho(p) => p.hint(node),
            AreaPah::Perspective(p) => p.hint(node),
        }
    }

    #[inline]
    fn measure4_hinted(&self, b: &Aabb4, hint: u32) -> f32x4 {
        match self {
            AreaPah::Ortho(p) => p.measure4_hinted(b, hint),
            AreaPah::Perspective(p) => p.measure4_hinted(b, hint),
        }
    }
}
