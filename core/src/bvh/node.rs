//! The binary BVH node: 32 bytes, one per half cache line.

use bytemuck::{Pod, Zeroable};
use glam::Vec3;

use crate::geometry::Aabb;

/// A binary BVH node. The traversal loop reads a node's box and its child (or primitive) index
/// together, so they share one 32-byte, 32-aligned record; an inner node's two children are
/// adjacent (`left_first` and `left_first + 1`), so one index addresses both.
///
/// - inner node: `count == 0`, `left_first` = index of the left child;
/// - leaf: `count > 0` primitives at `prim_indices[left_first..left_first + count]`.
#[derive(Clone, Copy, Debug, PartialEq, Pod, Zeroable)]
#[repr(C, align(32))]
pub struct BvhNode {
    /// Lower corner of the node's box.
    pub min: [f32; 3],
    /// Left child (inner node) or first primitive slot (leaf).
    pub left_first: u32,
    /// Upper corner of the node's box.
    pub max: [f32; 3],
    /// Number of primitives; zero for an inner node.
    pub count: u32,
}

static_assertions::assert_eq_size!(BvhNode, [u8; 32]);
static_assertions::const_assert_eq!(core::mem::align_of::<BvhNode>(), 32);

impl BvhNode {
    /// A leaf over `count` primitive slots starting at `first`. The box is stored
    /// [`Aabb::padded`], so box tests stay conservative under the triangle test's rounding.
    #[inline]
    pub fn leaf(bounds: Aabb, first: u32, count: u32) -> Self {
        let bounds = bounds.padded();
        Self {
            min: bounds.min.to_array(),
            left_first: first,
            max: bounds.max.to_array(),
            count,
        }
    }

    /// An inner node whose children sit at `left` and `left + 1`; its box is stored padded.
    #[inline]
    pub fn inner(bounds: Aabb, left: u32) -> Self {
        let bounds = bounds.padded();
        Self {
            min: bounds.min.to_array(),
            left_first: left,
            max: bounds.max.to_array(),
            count: 0,
        }
    }

    /// True for a leaf.
    #[inline]
    pub fn is_leaf(&self) -> bool {
        self.count > 0
    }

    /// The node's box.
    #[inline]
    pub fn bounds(&self) -> Aabb {
        Aabb::new(Vec3::from_array(self.min), Vec3::from_array(self.max))
    }
}
