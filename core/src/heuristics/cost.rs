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

    /// Checks that both are finite, `C_trav >= 0` and `C_isect > 0` (what every builder needs
    /// to price a split against a leaf).
    pub(crate) fn validate(&self) -> Result<(), crate::BuildError> {
        let traversal_ok = self.traversal.is_finite() && self.traversal >= 0.0;
        let intersection_ok = self.intersection.is_finite() && self.intersection > 0.0;
        if traversal_ok && intersection_ok {
            Ok(())
        } else {
            Err(crate::BuildError::InvalidConfig(
                "cost constants must be finite, C_trav >= 0 and C_isect > 0",
            ))
        }
    }
}

/// A hit measure: `measure(child) / measure(parent)` is the probability that a ray of the modelled
/// distribution that hits the parent also hits the child. Only ratios matter, so any positive
/// scale is fine.
pub trait CostModel {
    /// The measure of box `b`: zero for an empty box, never negative or NaN for a valid one.
    fn measure(&self, b: &Aabb) -> f32;

    /// The measures of four boxes at once: the builder's sweeps price candidate splits four at a
    /// time through this. The default measures each lane with [`CostModel::measure`]; models with
    /// a closed form override it with one 4-wide evaluation. Each lane must be what `measure`
    /// gives that box alone, whatever the other lanes hold: the same node meets different
    /// neighbours in a threaded build's job and in the single-threaded build, and both must
    /// make the same tree.
    #[inline]
    fn measure4(&self, b: &Aabb4) -> f32x4 {
        f32x4::from([
            self.measure(&b.lane(0)),
            self.measure(&b.lane(1)),
            self.measure(&b.lane(2)),
            self.measure(&b.lane(3)),
        ])
    }

    /// What the model can settle once for every box inside `node`, before a sweep prices its
    /// candidates (all of which lie inside the node): say, that they all lie inside the light's
    /// window, so no lane needs the culling test. Opaque to the builder, which hands it back to
    /// [`CostModel::measure4_hinted`]. The default settles nothing (0).
    #[inline]
    fn hint(&self, node: &Aabb) -> u32 {
        let _ = node;
        0
    }

    /// [`CostModel::measure4`] for four boxes that lie inside a node whose [`CostModel::hint`]
    /// was `hint` (or that are empty). It must return what `measure4` returns for them; it may
    /// only skip work. The default is `measure4`.
    #[inline]
    fn measure4_hinted(&self, b: &Aabb4, hint: u32) -> f32x4 {
        let _ = hint;
        self.measure4(b)
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

    #[inline]
    fn hint(&self, node: &Aabb) -> u32 {
        (**self).hint(node)
    }

    #[inline]
    fn measure4_hinted(&self, b: &Aabb4, hint: u32) -> f32x4 {
        (**self).measure4_hinted(b, hint)
    }
}
