//! The BVH invariants, checked in one walk: what tests and fuzz targets assert after every build.

use alloc::vec;
use core::fmt;

use super::{Bvh, MAX_DEPTH};

/// A broken BVH invariant.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum InvariantError {
    /// A child index points outside the node array, or a node is reached twice.
    BadChild {
        /// The parent node.
        node: u32,
    },
    /// A node was never reached from the root.
    Unreachable {
        /// The node.
        node: u32,
    },
    /// A leaf's primitive run leaves the index array.
    BadLeafRange {
        /// The leaf.
        node: u32,
    },
    /// A primitive id is missing from the leaves, or appears in more than one place (for
    /// [`Bvh::validate_split`]: twice in one leaf).
    PrimitiveCount {
        /// The primitive id.
        prim: u32,
    },
    /// A child's box is not inside its parent's.
    ChildOutsideParent {
        /// The child node.
        node: u32,
    },
    /// A leaf's box does not hold one of its primitives' boxes.
    PrimitiveOutsideLeaf {
        /// The leaf.
        node: u32,
    },
    /// A node is deeper than the recorded maximum depth or [`MAX_DEPTH`].
    TooDeep {
        /// The node.
        node: u32,
    },
}

impl fmt::Display for InvariantError {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        match self {
            InvariantError::BadChild { node } => write!(f, "node {node} has a bad child index"),
            InvariantError::Unreachable { node } => write!(f, "node {node} is unreachable"),
            InvariantError::BadLeafRange { node } => {
                write!(f, "leaf {node} refers outside the primitive indices")
            }
            InvariantError::PrimitiveCount { prim } => {
                write!(
                    f,
                    "primitive {prim} is missing from the leaves or named too often"
                )
            }
            InvariantError::ChildOutsideParent { node } => {
                write!(f, "node {node}'s box is not inside its parent's")
            }
            InvariantError::PrimitiveOutsideLeaf { node } => {
                write!(f, "leaf {node}'s box does not hold its primitives")
            }
            InvariantError::TooDeep { node } => write!(f, "node {node} is deeper than recorded"),
        }
    }
}

impl core::error::Error for InvariantError {}

/// How often a leaf may name a primitive, and what its box must do with the primitive's.
#[derive(Clone, Copy, PartialEq, Eq)]
enum References {
    /// Each id in exactly one leaf, its box inside the leaf's (object splits).
    WholeOnce,
    /// Each id in at least one leaf and at most once per leaf, its box overlapping the leaf's
    /// (spatial splits: a leaf bounds only its part of the triangle).
    Parts,
}

impl Bvh {
    /// Checks every invariant for a BVH built over primitive ids `0..prim_count` whose boxes
    /// `prim_bounds(id)` returns: each id in exactly one leaf, children in range and reached once,
    /// every child box inside its parent's, every primitive box inside its leaf's, depth within the
    /// recorded maximum and [`MAX_DEPTH`].
    pub fn validate(
        &self,
        prim_count: usize,
        prim_bounds: impl Fn(u32) -> crate::geometry::Aabb,
    ) -> Result<(), InvariantError> {
        self.walk(prim_count, prim_bounds, References::WholeOnce)
    }

    /// [`Bvh::validate`] for a tree whose primitives may be split across leaves
    /// ([`crate::builder::SpatialBuilder`]): each id in at least one leaf and at most once in
    /// any leaf, every primitive box overlapping its leaf's box, and the same structural
    /// invariants.
    pub fn validate_split(
        &self,
        prim_count: usize,
        prim_bounds: impl Fn(u32) -> crate::geometry::Aabb,
    ) -> Result<(), InvariantError> {
        self.walk(prim_count, prim_bounds, References::Parts)
    }

    fn walk(
        &self,
        prim_count: usize,
        prim_bounds: impl Fn(u32) -> crate::geometry::Aabb,
        references: References,
    ) -> Result<(), InvariantError> {
        if self.nodes.is_empty() {
            return match prim_count {
                0 => Ok(()),
                _ => Err(InvariantError::PrimitiveCount { prim: 0 }),
            };
        }
        let mut seen_node = vec![false; self.nodes.len()];
        let mut seen_prim = vec![0u32; prim_count];
        let mut stack = vec![(0u32, 0u32)];
        seen_node[0] = true;
        while let Some((index, depth)) = stack.pop() {
            let node = &self.nodes[index as usize];
            if depth > self.max_depth || depth > MAX_DEPTH {
                return Err(InvariantError::TooDeep { node: index });
            }
            let bounds = node.bounds();
            if node.is_leaf() {
                let first = node.left_first as usize;
                let run = self
                    .prim_indices
                    .get(first..first + node.count as usize)
                    .ok_or(InvariantError::BadLeafRange { node: index })?;
                for (i, &prim) in run.iter().enumerate() {
                    let slot = seen_prim
                        .get_mut(prim as usize)
                        .ok_or(InvariantError::PrimitiveCount { prim })?;
                    *slot += 1;
                    let b = prim_bounds(prim);
                    let inside = match references {
                        References::WholeOnce => bounds.contains_box(&b),
                        References::Parts => !bounds.intersection(b).is_empty(),
                    };
                    if !inside {
                        return Err(InvariantError::PrimitiveOutsideLeaf { node: index });
                    }
                    if references == References::Parts && run[..i].contains(&prim) {
                        return Err(InvariantError::PrimitiveCount { prim });
                    }
                }
            } else {
                let l = node.left_first as usize;
                if l == 0 || l + 1 >= self.nodes.len() {
                    return Err(InvariantError::BadChild { node: index });
                }
                for child in [l, l + 1] {
                    if core::mem::replace(&mut seen_node[child], true) {
                        return Err(InvariantError::BadChild { node: index });
                    }
                    if !bounds.contains_box(&self.nodes[child].bounds()) {
                        return Err(InvariantError::ChildOutsideParent { node: child as u32 });
                    }
                    stack.push((child as u32, depth + 1));
                }
            }
        }
        if let Some(node) = seen_node.iter().position(|&s| !s) {
            return Err(InvariantError::Unreachable { node: node as u32 });
        }
        let miscounted = |c: u32| match references {
            References::WholeOnce => c != 1,
            References::Parts => c == 0,
        };
        if let Some(prim) = seen_prim.iter().position(|&c| miscounted(c)) {
            return Err(InvariantError::PrimitiveCount { prim: prim as u32 });
        }
        if references == References::WholeOnce && self.prim_indices.len() != prim_count {
            return Err(InvariantError::PrimitiveCount {
                prim: prim_count as u32,
            });
        }
        Ok(())
    }
}
