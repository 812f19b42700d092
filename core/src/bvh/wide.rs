//! Wide (4-child) BVHs: the children's boxes as SoA lanes, so one 4-wide slab test checks all four.

use alloc::vec::Vec;

use bytemuck::{Pod, Zeroable};
use glam::Vec3;

use super::{Bvh, BvhNode, MAX_DEPTH};
use crate::geometry::Aabb;

/// A 4-wide node, 128 bytes on a 64-byte boundary: the four child boxes as `min`/`max` lanes per
/// axis (one `f32x4` load each), then per child either an inner node index (`count == 0`), a leaf's
/// first primitive slot (`count > 0`), or nothing (`child == EMPTY`, with an inverted box that no
/// ray can hit, so the slab test needs no mask).
#[derive(Clone, Copy, Debug, PartialEq, Pod, Zeroable)]
#[repr(C, align(64))]
pub struct WideNode {
    /// Lower bounds of the four children, per axis.
    pub min: [[f32; 4]; 3],
    /// Upper bounds of the four children, per axis.
    pub max: [[f32; 4]; 3],
    /// Child node index, or first primitive slot of a leaf child, or [`WideNode::EMPTY`].
    pub child: [u32; 4],
    /// Primitives of a leaf child; zero for an inner child or an empty slot.
    pub count: [u32; 4],
}

static_assertions::assert_eq_size!(WideNode, [u8; 128]);
static_assertions::const_assert_eq!(core::mem::align_of::<WideNode>(), 64);

impl WideNode {
    /// The `child` value of an unused slot.
    pub const EMPTY: u32 = u32::MAX;

    const UNUSED: WideNode = WideNode {
        min: [[f32::INFINITY; 4]; 3],
        max: [[f32::NEG_INFINITY; 4]; 3],
        child: [Self::EMPTY; 4],
        count: [0; 4],
    };

    /// The box of slot `i` (empty for an unused slot).
    pub fn child_bounds(&self, i: usize) -> Aabb {
        Aabb::new(
            Vec3::new(self.min[0][i], self.min[1][i], self.min[2][i]),
            Vec3::new(self.max[0][i], self.max[1][i], self.max[2][i]),
        )
    }

    /// Number of used slots.
    pub fn arity(&self) -> usize {
        self.child.iter().filter(|&&c| c != Self::EMPTY).count()
    }

    fn set(&mut self, i: usize, bounds: Aabb, child: u32, count: u32) {
        for k in 0..3 {
            self.min[k][i] = bounds.min[k];
            self.max[k][i] = bounds.max[k];
        }
        self.child[i] = child;
        self.count[i] = count;
    }
}

/// A 4-wide BVH over the same primitive ids as the binary BVH it was collapsed from. The root is
/// node 0; a BVH whose binary root is a leaf gets a root with that leaf as its only child.
#[derive(Clone, Debug, Default, PartialEq)]
pub struct WideBvh {
    pub(crate) nodes: Vec<WideNode>,
    pub(crate) prim_indices: Vec<u32>,
    pub(crate) max_depth: u32,
    bounds: Aabb,
}

impl WideBvh {
    /// Collapses a binary BVH: each wide node takes a binary node's children and keeps opening the
    /// inner child of largest surface area (the one a ray is likeliest to enter) until it has four.
    /// Leaves and primitive order are shared with the binary tree; depth never grows.
    pub fn from_binary(bvh: &Bvh) -> Self {
        let mut out = WideBvh {
            nodes: Vec::with_capacity(bvh.nodes.len() / 2 + 1),
            prim_indices: bvh.prim_indices.clone(),
            max_depth: 0,
            bounds: bvh.bounds(),
        };
        let Some(root) = bvh.nodes.first() else {
            return out;
        };
        out.nodes.push(WideNode::UNUSED);
        if root.is_leaf() {
            out.nodes[0].set(0, root.bounds(), root.left_first, root.count);
            return out;
        }
        // (wide node to fill, binary inner node whose subtree it stands for, depth)
        let mut stack: Vec<(u32, u32, u32)> = Vec::with_capacity(MAX_DEPTH as usize * 3 + 1);
        stack.push((0, 0, 0));
        while let Some((wide, binary, depth)) = stack.pop() {
            out.max_depth = out.max_depth.max(depth);
            let mut open: [u32; 4] = [0; 4];
            let node = &bvh.nodes[binary as usize];
            open[0] = node.left_first;
            open[1] = node.left_first + 1;
            let mut n = 2;
            while n < 4 {
                let pick = (0..n)
                    .filter(|&i| !bvh.nodes[open[i] as usize].is_leaf())
                    .max_by(|&a, &b| {
                        let area = |i: usize| bvh.nodes[open[i] as usize].bounds().half_area();
                        area(a).total_cmp(&area(b))
                    });
                let Some(i) = pick else { break };
                let l = bvh.nodes[open[i] as usize].left_first;
                open[i] = l;
                open[n] = l + 1;
                n += 1;
            }
            for (slot, &b) in open[..n].iter().enumerate() {
                let child: &BvhNode = &bvh.nodes[b as usize];
                if child.is_leaf() {
                    out.nodes[wide as usize].set(
                        slot,
                        child.bounds(),
                        child.left_first,
                        child.count,
                    );
                } else {
                    let index = out.nodes.len() as u32;
                    out.nodes.push(WideNode::UNUSED);
                    out.nodes[wide as usize].set(slot, child.bounds(), index, 0);
                    stack.push((index, b, depth + 1));
                }
            }
        }
        out
    }

    /// The nodes, root first.
    pub fn nodes(&self) -> &[WideNode] {
        &self.nodes
    }

    /// Primitive ids in leaf order.
    pub fn prim_indices(&self) -> &[u32] {
        &self.prim_indices
    }

    /// Depth of the deepest wide node (the root has depth 0).
    pub fn max_depth(&self) -> u32 {
        self.max_depth
    }

    /// The root's box.
    pub fn bounds(&self) -> Aabb {
        self.bounds
    }

    /// Bytes of the node and index arrays.
    pub fn memory_bytes(&self) -> usize {
        self.nodes.len() * core::mem::size_of::<WideNode>() + self.prim_indices.len() * 4
    }
}
