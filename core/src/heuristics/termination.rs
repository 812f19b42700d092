//! Termination rules: when a node becomes a leaf.

/// Decides when a node stops splitting. The builder also stops on its own at its depth bound, and
/// splits at the object median when a node must split but no binned split separates it.
pub trait Termination {
    /// Called before any split is evaluated: `true` makes the node a leaf at once.
    fn must_stop(&self, count: u32, depth: u32) -> bool;
    /// Called with the cost of the node as a leaf and of its best split (both relative to the
    /// node): `true` makes it a leaf instead. A node that returns `false` here must split.
    fn prefer_leaf(&self, count: u32, leaf_cost: f32, split_cost: f32) -> bool;
}

/// SAH termination: split until one primitive remains, but keep a node of at most `max_leaf`
/// primitives as a leaf when splitting it would not be cheaper.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct SahTermination {
    /// Largest leaf the cost comparison may keep.
    pub max_leaf: u32,
}

impl Default for SahTermination {
    fn default() -> Self {
        Self { max_leaf: 8 }
    }
}

impl Termination for SahTermination {
    #[inline]
    fn must_stop(&self, count: u32, _depth: u32) -> bool {
        count <= 1
    }
    #[inline]
    fn prefer_leaf(&self, count: u32, leaf_cost: f32, split_cost: f32) -> bool {
        count <= self.max_leaf && leaf_cost <= split_cost
    }
}

/// Leaf by size alone: split while a node holds more than `max_leaf` primitives, with no cost-based
/// termination (the thesis used 2).
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct LeafSize {
    /// Largest leaf.
    pub max_leaf: u32,
}

impl Termination for LeafSize {
    #[inline]
    fn must_stop(&self, count: u32, _depth: u32) -> bool {
        count <= self.max_leaf.max(1)
    }
    #[inline]
    fn prefer_leaf(&self, _count: u32, _leaf_cost: f32, _split_cost: f32) -> bool {
        false
    }
}

/// Another rule, plus: a node of at most `min_leaf` primitives is a leaf at once, before any split
/// is priced (Embree's minimum leaf size). For trees that are collapsed afterwards, where what a
/// small node would split into is thrown away ([`crate::builder::Builder::for_wide`]).
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct MinLeaf<T> {
    /// The rule for every larger node.
    pub inner: T,
    /// Nodes of at most this many primitives are leaves.
    pub min_leaf: u32,
}

impl<T: Termination> Termination for MinLeaf<T> {
    #[inline]
    fn must_stop(&self, count: u32, depth: u32) -> bool {
        count <= self.min_leaf || self.inner.must_stop(count, depth)
    }
    #[inline]
    fn prefer_leaf(&self, count: u32, leaf_cost: f32, split_cost: f32) -> bool {
        self.inner.prefer_leaf(count, leaf_cost, split_cost)
    }
}
