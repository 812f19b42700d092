//! The analyzer itself: the [`Analysis`] trait, one explicit-stack walk, and tuples of analyses.

use alloc::vec::Vec;

use crate::bvh::{Bvh, BvhNode};

/// What an analysis sees of one node during the walk.
#[derive(Clone, Copy, Debug)]
pub struct NodeView<'a> {
    /// The tree being walked.
    pub bvh: &'a Bvh,
    /// The node.
    pub node: &'a BvhNode,
    /// Its index in [`Bvh::nodes`].
    pub index: u32,
    /// Its depth (the root has depth 0).
    pub depth: u32,
    /// Its parent's index (`None` for the root).
    pub parent: Option<u32>,
}

/// One analysis of a BVH: a per-node action that may read its parent's per-node data and keeps
/// its own accumulators in `self`, and a final action producing the output.
///
/// Nodes are visited parent before children (depth first, left child first), each exactly once.
pub trait Analysis {
    /// What the per-node action hands down to the node's children (`()` when nothing).
    type NodeData: Clone;
    /// What the final action produces.
    type Output;

    /// The per-node action: `parent` is the data this analysis returned for the parent (`None`
    /// at the root).
    fn visit(&mut self, view: &NodeView<'_>, parent: Option<&Self::NodeData>) -> Self::NodeData;

    /// The final action, after every node has been visited.
    fn finish(self, bvh: &Bvh) -> Self::Output;
}

/// `(index, depth, parent index, parent data)` of a node waiting on the walk's stack.
type Pending<D> = (u32, u32, Option<u32>, Option<D>);

/// Runs `analysis` (one analysis or a tuple of them) over `bvh` in one walk with an explicit stack
/// and returns its output. An empty BVH visits no node.
pub fn analyze<A: Analysis>(bvh: &Bvh, mut analysis: A) -> A::Output {
    let nodes = bvh.nodes();
    // A pending node and what its parent handed down.
    let mut stack: Vec<Pending<A::NodeData>> = Vec::new();
    if !nodes.is_empty() {
        stack.push((0, 0, None, None));
    }
    while let Some((index, depth, parent, data)) = stack.pop() {
        let Some(node) = nodes.get(index as usize) else {
            continue;
        };
        let view = NodeView {
            bvh,
            node,
            index,
            depth,
            parent,
        };
        let mine = analysis.visit(&view, data.as_ref());
        if !node.is_leaf() {
            let left = node.left_first;
            // Children always follow their parent; anything else would not be a tree.
            if left > index && (left as usize + 1) < nodes.len() {
                stack.push((left + 1, depth + 1, Some(index), Some(mine.clone())));
                stack.push((left, depth + 1, Some(index), Some(mine)));
            }
        }
    }
    analysis.finish(bvh)
}

macro_rules! tuple_analysis {
    ($($name:ident $idx:tt),+) => {
        impl<$($name: Analysis),+> Analysis for ($($name,)+) {
            type NodeData = ($($name::NodeData,)+);
            type Output = ($($name::Output,)+);

            #[inline]
            fn visit(
                &mut self,
                view: &NodeView<'_>,
                parent: Option<&Self::NodeData>,
            ) -> Self::NodeData {
                ($(self.$idx.visit(view, parent.map(|p| &p.$idx)),)+)
            }

            fn finish(self, bvh: &Bvh) -> Self::Output {
                ($(self.$idx.finish(bvh),)+)
            }
        }
    };
}

tuple_analysis!(A 0);
tuple_analysis!(A 0, B 1);
tuple_analysis!(A 0, B 1, C 2);
tuple_analysis!(A 0, B 1, C 2, D 3);
tuple_analysis!(A 0, B 1, C 2, D 3, E 4);
tuple_analysis!(A 0, B 1, C 2, D 3, E 4, F 5);
tuple_analysis!(A 0, B 1, C 2, D 3, E 4, F 5, G 6);
tuple_analysis!(A 0, B 1, C 2, D 3, E 4, F 5, G 6, H 7);

#[cfg(test)]
pub(crate) mod tests {
    use super::*;
    use crate::geometry::Aabb;
    use alloc::vec;
    use glam::Vec3;

    /// A hand-made tree: root 0 over inner 1 (leaves 3, 4) and leaf 2. Boxes:
    /// root [0,4]x[0,1]x[0,1], node 1 [0,2]x..., leaf 2 [3,4]x..., leaves 3 [0,1], 4 [1,2].
    pub(crate) fn small_tree() -> Bvh {
        let b = |x0: f32, x1: f32| Aabb::new(Vec3::new(x0, 0.0, 0.0), Vec3::new(x1, 1.0, 1.0));
        let raw = |bounds: Aabb, left_first: u32, count: u32| BvhNode {
            min: bounds.min.to_array(),
            left_first,
            max: bounds.max.to_array(),
            count,
        };
        Bvh {
            nodes: vec![
                raw(b(0.0, 4.0), 1, 0),
                raw(b(0.0, 2.0), 3, 0),
                raw(b(3.0, 4.0), 0, 1),
                raw(b(0.0, 1.0), 1, 1),
                raw(b(1.0, 2.0), 2, 1),
            ],
            prim_indices: vec![2, 0, 1],
            max_depth: 2,
        }
    }

    struct Order(Vec<(u32, u32, Option<u32>, Option<u32>)>);
    impl Analysis for Order {
        type NodeData = u32;
        type Output = Vec<(u32, u32, Option<u32>, Option<u32>)>;
        fn visit(&mut self, v: &NodeView<'_>, parent: Option<&u32>) -> u32 {
            self.0.push((v.index, v.depth, v.parent, parent.copied()));
            v.index * 10
        }
        fn finish(self, _: &Bvh) -> Self::Output {
            self.0
        }
    }

    #[test]
    fn walk_visits_each_node_once_parent_first_with_parent_data() {
        let bvh = small_tree();
        let order = analyze(&bvh, Order(Vec::new()));
        assert_eq!(
            order,
            vec![
                (0, 0, None, None),
                (1, 1, Some(0), Some(0)),
                (3, 2, Some(1), Some(10)),
                (4, 2, Some(1), Some(10)),
                (2, 1, Some(0), Some(0)),
            ]
        );
        // A tuple runs both in one walk and gives the same answers.
        let (a, b) = analyze(&bvh, (Order(Vec::new()), Order(Vec::new())));
        assert_eq!(a, order);
        assert_eq!(b, order);
    }

    #[test]
    fn empty_tree_visits_nothing() {
        assert!(analyze(&Bvh::default(), Order(Vec::new())).is_empty());
    }
}
