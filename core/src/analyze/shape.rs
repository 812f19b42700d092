//! The tree's shape: node counts, depth, leaf sizes and memory.

use alloc::vec::Vec;

use crate::bvh::Bvh;

use super::{Analysis, NodeView};

/// Counts nodes and leaves, the deepest level, the leaf-size histogram and the tree's memory.
#[derive(Clone, Debug, Default)]
pub struct TreeShape {
    report: ShapeReport,
    leaf_depth_sum: u64,
}

/// What [`TreeShape`] found.
#[derive(Clone, Debug, Default, PartialEq)]
pub struct ShapeReport {
    /// Nodes visited.
    pub nodes: u32,
    /// Inner nodes.
    pub inner: u32,
    /// Leaves.
    pub leaves: u32,
    /// Primitive references in leaves.
    pub primitives: u32,
    /// Depth of the deepest node (the root has depth 0).
    pub max_depth: u32,
    /// Mean depth of the leaves.
    pub mean_leaf_depth: f32,
    /// `leaf_sizes[n]` leaves hold `n` primitives (index 0 is always 0).
    pub leaf_sizes: Vec<u32>,
    /// Bytes of the node and primitive-index arrays.
    pub memory_bytes: usize,
}

impl ShapeReport {
    /// Levels of the tree, counting the root's as level 1 (the thesis's "Max level").
    pub fn levels(&self) -> u32 {
        if self.nodes == 0 {
            0
        } else {
            self.max_depth + 1
        }
    }

    /// The largest leaf.
    pub fn max_leaf_size(&self) -> u32 {
        self.leaf_sizes.iter().rposition(|&c| c > 0).unwrap_or(0) as u32
    }
}

impl Analysis for TreeShape {
    type NodeData = ();
    type Output = ShapeReport;

    fn visit(&mut self, v: &NodeView<'_>, _: Option<&()>) {
        let r = &mut self.report;
        r.nodes += 1;
        r.max_depth = r.max_depth.max(v.depth);
        if v.node.is_leaf() {
            r.leaves += 1;
            r.primitives += v.node.count;
            self.leaf_depth_sum += u64::from(v.depth);
            let size = v.node.count as usize;
            if r.leaf_sizes.len() <= size {
                r.leaf_sizes.resize(size + 1, 0);
            }
            r.leaf_sizes[size] += 1;
        } else {
            r.inner += 1;
        }
    }

    fn finish(mut self, bvh: &Bvh) -> ShapeReport {
        self.report.memory_bytes = bvh.memory_bytes();
        if self.report.leaves > 0 {
            self.report.mean_leaf_depth =
                (self.leaf_depth_sum as f64 / f64::from(self.report.leaves)) as f32;
        }
        self.report
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::analyze::analyze;
    use crate::analyze::analyzer::tests::small_tree;
    use alloc::vec;

    #[test]
    fn shape_by_hand() {
        let r = analyze(&small_tree(), TreeShape::default());
        assert_eq!((r.nodes, r.inner, r.leaves, r.primitives), (5, 2, 3, 3));
        assert_eq!(r.max_depth, 2);
        assert_eq!(r.levels(), 3);
        assert_eq!(r.leaf_sizes, vec![0, 3]);
        assert_eq!(r.max_leaf_size(), 1);
        assert!((r.mean_leaf_depth - 5.0 / 3.0).abs() < 1e-6);
        assert_eq!(r.memory_bytes, 5 * 32 + 3 * 4);
    }
}
