//! The thesis's break-even rule: when a local BVH pays for itself.

/// Measured costs of one area's rays with and without its local BVH.
///
/// With the structure a ray costs `cost_local` plus, when the local BVH misses, the fallback; the
/// fallback alone costs `cost_global`. So the local BVH pays off when its hit rate exceeds
/// `cost_local / cost_global` (the thesis's threshold on the share of rays that must not fall
/// back).
#[derive(Clone, Copy, Debug, Default, PartialEq)]
pub struct BreakEven {
    /// Rays sampled.
    pub rays: u32,
    /// Share of affine rays answered by the local BVH.
    pub hit_rate: f32,
    /// Mean closest-hit cost of the local traversal per ray.
    pub cost_local: f32,
    /// Mean closest-hit cost of the fallback BVH alone for the same rays.
    pub cost_global: f32,
    /// Mean cost per ray through the structure (local, then fallback when it misses).
    pub cost_structure: f32,
}

impl BreakEven {
    /// `cost_local / cost_global`: the hit rate the local BVH must exceed.
    pub fn threshold(&self) -> f32 {
        if self.cost_global > 0.0 {
            self.cost_local / self.cost_global
        } else {
            f32::INFINITY
        }
    }

    /// True when the hit rate exceeds the threshold.
    pub fn pays_off(&self) -> bool {
        self.hit_rate > self.threshold()
    }
}
