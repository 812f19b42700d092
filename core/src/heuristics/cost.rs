//! Cost models: the measure of a box that stands for the probability that a ray hits it.

use wide::f32x4;

use crate::geometry::Aabb;
use crate::simd::Aabb4;

/// The constants of the cost model `cost = C_trav * (inner nodes visited) + C_isect * (triangles
/// tested)`.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct CostConstants {
    /// Cost of visiting an inner node (`C_trav`).
    pub traversal: f32,
    /// Cost of testing one triangle (`C_isect`).
    pub intersection: f32,
}

impl Default for CostConstants {
    /// `C_trav = 1`, `C_isect = 1`, as Embree and tinybvh use.
    fn default() -> Self {
        Self {
            traversal: 1.0,
            intersection: 1.0,
        }
    }
}

impl CostConstants {
    /// The thesis's constants: 1.0 per inner node counted twice per visit (one per child box
    /// test), 1.2 per triangle.
    pub const THESIS: CostConstants = CostConstants {
        traversal: 2.0,
        intersection: 1.2,
    };
}

/// A hit measure: `measure(child) / measure(parent)` is the probability that a ray of the modelled
/// distribution that hits the parent also hits the child. Only ratios matter, so any positive
/// scale is fine.
pub trait CostModel {
    /// The measure of box `b`: zero for an empty box, never negative or NaN for a valid one.
    fn measure(&self, b: &Aabb) -> f32;

    /// The measures of four boxes at once: the builder's sweeps price candidate splits four at a
    /// time through this. The default measures each lane with [`CostModel::measure`]; models with
    /// a closed form override it with one 4-wide evaluation.
    #[inline]
    fn measure4(&self, b: &Aabb4) -> f32x4 {
        f32x4::from([
            self.measure(&b.lane(0)),
            self.measure(&b.lane(1)),
            self.measure(&b.lane(2)),
            self.measure(&b.lane(3)),
        ])
    }
}

/// The surface area heuristic (MacDonald and Booth 1990): uniformly distributed rays hit a convex
/// body with probability proportional to its surface area.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub struct Sah;

impl CostModel for Sah {
    #[inline]
    fn measure(&self, b: &Aabb) -> f32 {
        b.half_area()
    }

    #[inline(always)]
    fn measure4(&self, b: &Aabb4) -> f32x4 {
        b.half_area()
    }
}

impl<C: CostModel + ?Sized> CostModel for &C {
    #[inline]
    fn measure(&self, b: &Aabb) -> f32 {
        (**self).measure(b)
    }

    #[inline]
    fn measure4(&self, b: &Aabb4) -> f32x4 {
        (**self).measure4(b)
    }
}
