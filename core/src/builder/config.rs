//! Builder settings shared by every heuristic.

use crate::bvh::MAX_DEPTH;
use crate::heuristics::CostConstants;
use crate::BuildError;

/// The most bins a sweep may use; bins live in fixed arrays, so this bounds the arena's size.
pub const MAX_BINS: u32 = 64;

/// The most primitives [`BuildConfig::exhaustive_max`] may name: a node of six has 31
/// bipartitions, about what three sweeps of sixteen bins price.
pub const MAX_EXHAUSTIVE: u32 = 6;

/// Where the candidate planes of a node lie.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub enum BinSpace {
    /// Uniformly over the bounds of the node's primitive centroids (Wald 2007): no empty end bins.
    #[default]
    Centroids,
    /// Uniformly over the node's box, as the thesis placed its 40 candidate planes.
    NodeBox,
}

/// The thesis's cut evaluation: how picky the builder is before accepting a split.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct ThesisCut {
    /// Stop trying axes once `(m(L) + m(R)) / m(parent)` is at most this (thesis: 0.9).
    pub excellent_ratio: f32,
    /// When the next axis is of too low a quality, accept the best split so far if its ratio is at
    /// most this (thesis: 1.3); otherwise take SAH on the longest axis.
    pub acceptable_ratio: f32,
    /// Axes after the first are tried only while their quality is at least this (thesis: 0.4
    /// for SPFH, 0.99 for LSPH).
    pub quality_threshold: f32,
}

impl ThesisCut {
    /// The thesis's values for a chooser with the given quality threshold.
    pub const fn with_threshold(quality_threshold: f32) -> Self {
        Self {
            excellent_ratio: 0.9,
            acceptable_ratio: 1.3,
            quality_threshold,
        }
    }

    /// The thesis's values for SPFH (threshold 0.4).
    pub const SPFH: ThesisCut = ThesisCut::with_threshold(0.4);
    /// The thesis's values for LSPH (threshold 0.99).
    pub const LSPH: ThesisCut = ThesisCut::with_threshold(0.99);
}

/// Which of the chooser's axes a node evaluates, and which split it keeps.
#[derive(Clone, Copy, Debug, Default, PartialEq)]
pub enum CutEvaluation {
    /// Evaluate every axis the chooser names and keep the cheapest split.
    #[default]
    BestOfAxes,
    /// Evaluate the chooser's first axis only.
    FirstAxis,
    /// The thesis's cut evaluation: axes in quality order, early acceptance, SAH on the longest axis as the last resort.
    Thesis(ThesisCut),
}

/// Settings of the build skeleton.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct BuildConfig {
    /// Centroid bins per axis, 2 to [`MAX_BINS`]; each bin boundary is a candidate plane. With
    /// [`BinSpace::Centroids`], a node of fewer than `2 * bins` primitives uses half as many bins
    /// as it has primitives, at least 4 (and never more than `bins`).
    pub bins: u32,
    /// The cost constants used to price splits against leaves.
    pub constants: CostConstants,
    /// Hard depth bound, 1 to [`MAX_DEPTH`]: a node at this depth is a leaf whatever its size.
    pub max_depth: u32,
    /// Which axes a node evaluates and which split it keeps.
    pub cut: CutEvaluation,
    /// Where the candidate planes lie.
    pub bin_space: BinSpace,
    /// Nodes of at most this many primitives (0 to [`MAX_EXHAUSTIVE`]) price every bipartition
    /// of their primitives instead of binning: the cheapest split of all, at a fraction of a
    /// binned node's fixed costs, which dominate the many tiny nodes near the leaves. Only with
    /// [`CutEvaluation::BestOfAxes`] (the other evaluations are about which axes a node tries)
    /// and [`BinSpace::Centroids`] (node-box planes reproduce the thesis's builder). 0 bins every
    /// node.
    pub exhaustive_max: u32,
}

impl Default for BuildConfig {
    fn default() -> Self {
        Self {
            bins: 16,
            constants: CostConstants::default(),
            max_depth: MAX_DEPTH,
            cut: CutEvaluation::BestOfAxes,
            bin_space: BinSpace::Centroids,
            exhaustive_max: 4,
        }
    }
}

impl BuildConfig {
    /// Checks every value's range.
    pub fn validate(&self) -> Result<(), BuildError> {
        if !(2..=MAX_BINS).contains(&self.bins) {
            return Err(BuildError::InvalidConfig("bins must be between 2 and 64"));
        }
        if self.exhaustive_max > MAX_EXHAUSTIVE {
            return Err(BuildError::InvalidConfig(
                "exhaustive_max must be at most 6",
            ));
        }
        if !(1..=MAX_DEPTH).contains(&self.max_depth) {
            return Err(BuildError::InvalidConfig(
                "max_depth must be between 1 and 64",
            ));
        }
        if let CutEvaluation::Thesis(c) = self.cut {
            let ok = |x: f32| x.is_finite() && x >= 0.0;
            if !(ok(c.excellent_ratio) && ok(c.acceptable_ratio) && ok(c.quality_threshold)) {
                return Err(BuildError::InvalidConfig(
                    "cut ratios and thresholds must be finite and >= 0",
                ));
            }
        }
        self.constants.validate()
    }
}
