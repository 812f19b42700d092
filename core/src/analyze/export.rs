//! One record per node, for exporting a whole tree (JSON) or chosen columns (CSV).

use alloc::vec::Vec;

use crate::bvh::Bvh;
use crate::heuristics::CostModel;

use super::{Analysis, NodeView};

/// Everything the analyzer knows about one node, flat, for serialisation by the host.
#[derive(Clone, Copy, Debug, Default, PartialEq)]
pub struct NodeRecord {
    /// Index in the node array.
    pub index: u32,
    /// Parent index (`u32::MAX` for the root).
    pub parent: u32,
    /// Depth (root 0).
    pub depth: u32,
    /// Lower corner.
    pub min: [f32; 3],
    /// Upper corner.
    pub max: [f32; 3],
    /// Primitives (0 for an inner node).
    pub count: u32,
    /// Left child (inner) or first primitive slot (leaf).
    pub left_first: u32,
    /// The node's measure under the chosen model (surface area / 2 for SAH).
    pub measure: f32,
    /// `measure / parent's measure`: the conditional hit probability (1 for the root, 0 under a
    /// parent of zero measure).
    pub hit_probability: f32,
}

/// Collects a [`NodeRecord`] per node, in walk order, with measures under `M`. The parent's
/// measure is handed down as per-node data.
#[derive(Clone, Debug)]
pub struct NodeRecords<M> {
    model: M,
    records: Vec<NodeRecord>,
}

impl<M: CostModel> NodeRecords<M> {
    /// Records with measures under `model`.
    pub fn new(model: M) -> Self {
        Self {
            model,
            records: Vec::new(),
        }
    }
}

impl<M: CostModel> Analysis for NodeRecords<M> {
    type NodeData = f32;
    type Output = Vec<NodeRecord>;

    fn visit(&mut self, v: &NodeView<'_>, parent: Option<&f32>) -> f32 {
        let measure = self.model.measure(&v.node.bounds());
        let hit_probability = match parent {
            None => 1.0,
            Some(&p) if p > 0.0 => measure / p,
            Some(_) => 0.0,
        };
        self.records.push(NodeRecord {
            index: v.index,
            parent: v.parent.unwrap_or(u32::MAX),
            depth: v.depth,
            min: v.node.min,
            max: v.node.max,
            count: v.node.count,
            left_first: v.node.left_first,
            measure,
            hit_probability,
        });
        measure
    }

    fn finish(self, _: &Bvh) -> Vec<NodeRecord> {
        self.records
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::analyze::analyze;
    use crate::analyze::analyzer::tests::small_tree;
    use crate::heuristics::Sah;

    #[test]
    fn records_by_hand() {
        let r = analyze(&small_tree(), NodeRecords::new(Sah));
        assert_eq!(r.len(), 5);
        assert_eq!(
            (r[0].index, r[0].parent, r[0].hit_probability),
            (0, u32::MAX, 1.0)
        );
        // Node 1 (half area 5) under the root (9); leaf 3 (3) under node 1 (5).
        assert_eq!(r[1].index, 1);
        assert!((r[1].hit_probability - 5.0 / 9.0).abs() < 1e-6);
        assert_eq!((r[2].index, r[2].parent, r[2].depth), (3, 1, 2));
        assert!((r[2].hit_probability - 0.6).abs() < 1e-6);
    }
}
