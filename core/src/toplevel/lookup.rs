//! Area lookup: which influence areas may contain a point.

use alloc::vec::Vec;

use glam::Vec3;

use crate::influence::InfluenceArea;

/// Answers "which areas may contain this point": a conservative candidate list (it may name areas
/// that do not contain the point, never omit one that does), in area order.
pub trait AreaLookup {
    /// Candidate area indices for `p`.
    fn candidates(&self, p: Vec3) -> &[u32];

    /// The same kind of lookup (same settings) over other areas.
    fn rebuilt(&self, areas: &[InfluenceArea]) -> Self
    where
        Self: Sized;

    /// Bytes held.
    fn memory_bytes(&self) -> usize;
}

/// The naive lookup: every area is a candidate, and the scene tests each in turn. The baseline the
/// octree is measured against.
#[derive(Clone, Debug, Default, PartialEq, Eq)]
pub struct AreaList {
    all: Vec<u32>,
}

impl AreaList {
    /// A list over `count` areas.
    pub fn new(count: usize) -> Self {
        Self {
            all: (0..count as u32).collect(),
        }
    }
}

impl AreaLookup for AreaList {
    #[inline]
    fn candidates(&self, _p: Vec3) -> &[u32] {
        &self.all
    }

    fn rebuilt(&self, areas: &[InfluenceArea]) -> Self {
        AreaList::new(areas.len())
    }

    fn memory_bytes(&self) -> usize {
        self.all.len() * 4
    }
}
