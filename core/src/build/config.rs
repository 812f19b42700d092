//! Builder settings shared by every heuristic.

use crate::bvh::MAX_DEPTH;
use crate::heuristics::CostConstants;
use crate::BuildError;

/// The most bins a sweep may use; bins live in fixed arrays, so this bounds the arena's size.
pub const MAX_BINS: u32 = 64;

/// Settings of the build skeleton.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct BuildConfig {
    /// Centroid bins per axis, 2 to [`MAX_BINS`]; each bin boundary is a candidate plane.
    pub bins: u32,
    /// The cost constants used to price splits against leaves.
    pub constants: CostConstants,
    /// Hard depth bound, 1 to [`MAX_DEPTH`]: a node at this depth is a leaf whatever its size.
    pub max_depth: u32,
}

impl Default for BuildConfig {
    fn default() -> Self {
        Self {
            bins: 16,
            constants: CostConstants::default(),
            max_depth: MAX_DEPTH,
        }
    }
}

impl BuildConfig {
    /// Checks every value's range.
    pub fn validate(&self) -> Result<(), BuildError> {
        if !(2..=MAX_BINS).contains(&self.bins) {
            return Err(BuildError::InvalidConfig("bins must be between 2 and 64"));
        }
        if !(1..=MAX_DEPTH).contains(&self.max_depth) {
            return Err(BuildError::InvalidConfig(
                "max_depth must be between 1 and 64",
            ));
        }
        let k = self.constants;
        if !(k.traversal.is_finite() && k.traversal >= 0.0)
            || !(k.intersection.is_finite() && k.intersection > 0.0)
        {
            return Err(BuildError::InvalidConfig(
                "cost constants must be finite, C_trav >= 0 and C_isect > 0",
            ));
        }
        Ok(())
    }
}
