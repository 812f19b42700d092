//! A light-buffer cell's tree: an 8-wide BVH over the scene BVH's leaves that hold a triangle
//! the cell's segments can reach, each boxed by the clipped parts of those triangles. Its leaves
//! name the scene BVH's blocks instead of copying triangles, so a buffer adds only nodes to
//! memory, and its shadow segments test the very blocks the renderer's camera and bounce rays
//! keep in the caches. An any-hit query over a scene leaf tests the leaf's other triangles too;
//! any of them that the segment hits is one the scene BVH would report as well, so the answer is
//! still the scene BVH's.

use alloc::vec;
use alloc::vec::Vec;

use crate::builder::{BuildArena, Builder};
use crate::bvh::{Bvh, WideBvh8, WideNodeN};
use crate::geometry::{Aabb, Triangle4};
use crate::heuristics::LeafSize;
use crate::BuildError;

/// The scene BVH's leaves, `(first block, triangle count)`, and the leaf of each triangle.
#[derive(Clone, Debug)]
pub(crate) struct SceneLeaves {
    leaves: Vec<(u32, u32)>,
    of_triangle: Vec<u32>,
    /// The scene BVH's node and block counts, which a query checks against the BVH it is given.
    pub(crate) size: (usize, usize),
}

impl SceneLeaves {
    /// The leaves of `scene`, which must hold each of `triangles` triangles exactly once.
    pub(crate) fn new(scene: &WideBvh8, triangles: usize) -> Result<Self, BuildError> {
        const OTHER: BuildError =
            BuildError::InvalidConfig("light buffer scene BVH is not over these triangles");
        let mut leaves = Vec::new();
        let mut of_triangle = vec![u32::MAX; triangles];
        for node in &scene.nodes {
            for (&first, &count) in node.child.iter().zip(&node.count) {
                if first == WideNodeN::<8>::EMPTY || count == 0 {
                    continue;
                }
                let leaf = leaves.len() as u32;
                leaves.push((first, count));
                let end = first as usize + count.div_ceil(4) as usize;
                let blocks = scene.tris.get(first as usize..end).ok_or(OTHER)?;
                for &id in blocks.iter().flat_map(|b| &b.id) {
                    if id == Triangle4::UNUSED_ID {
                        continue;
                    }
                    let slot = of_triangle.get_mut(id as usize).ok_or(OTHER)?;
                    if *slot != u32::MAX {
                        return Err(OTHER);
                    }
                    *slot = leaf;
                }
            }
        }
        if of_triangle.contains(&u32::MAX) {
            return Err(OTHER);
        }
        Ok(Self {
            leaves,
            of_triangle,
            size: (scene.nodes.len(), scene.tris.len()),
        })
    }
}

/// What every cell's tree build reuses: the arena, the binary tree, and the items of the cell
/// being built (a scene leaf and the box of its reached parts) with each leaf's item index.
pub(crate) struct CellTreeBuilder {
    arena: BuildArena,
    bvh: Bvh,
    items: Vec<(u32, Aabb)>,
    item_of: Vec<u32>,
    /// The collapse's pending wide nodes: index, binary node, depth.
    pending: Vec<(usize, u32, u32)>,
}

impl CellTreeBuilder {
    pub(crate) fn new() -> Self {
        Self {
            arena: BuildArena::with_capacity(0),
            bvh: Bvh::default(),
            items: Vec::new(),
            item_of: Vec::new(),
            pending: Vec::new(),
        }
    }

    /// The tree over the scene leaves of `reached` (triangle ids with the boxes of their parts
    /// in the cell), appended to `forest` (whose leaves name the scene's blocks, as its own):
    /// its root and the triangles of those leaves; `None` when nothing is reached.
    pub(crate) fn build(
        &mut self,
        reached: impl Iterator<Item = (u32, Aabb)>,
        scene: &SceneLeaves,
        forest: &mut WideBvh8,
    ) -> Result<Option<(u32, usize)>, BuildError> {
        if self.item_of.len() != scene.leaves.len() {
            self.item_of = vec![u32::MAX; scene.leaves.len()];
        }
        self.items.clear();
        for (id, bounds) in reached {
            let leaf = scene.of_triangle[id as usize];
            let item = &mut self.item_of[leaf as usize];
            if *item == u32::MAX {
                *item = self.items.len() as u32;
                self.items.push((leaf, bounds));
            } else {
                let it = &mut self.items[*item as usize];
                it.1 = it.1.union(bounds);
            }
        }
        for &(leaf, _) in &self.items {
            self.item_of[leaf as usize] = u32::MAX;
        }
        if self.items.is_empty() {
            return Ok(None);
        }
        if self.arena.capacity() < self.items.len() {
            self.arena = BuildArena::with_capacity(self.items.len());
        } else {
            self.arena.clear();
        }
        for (i, &(_, bounds)) in self.items.iter().enumerate() {
            self.arena.push(i as u32, bounds)?;
        }
        // One item a leaf: a wide leaf names one contiguous run of the scene's blocks.
        Builder::sah()
            .with_termination(LeafSize { max_leaf: 1 })
            .build_into(&mut self.arena, &mut self.bvh)?;
        let triangles = self
            .items
            .iter()
            .map(|&(leaf, _)| scene.leaves[leaf as usize].1 as usize)
            .sum();
        Ok(Some((self.collapse(scene, forest)?, triangles)))
    }

    /// The binary tree as 8-wide nodes appended to `out`, and its root: each wide node takes its
    /// binary node's children and opens the inner one of largest area while it has room, as
    /// `WideBvh8::from_binary` does without its leaf blocks; each binary leaf becomes the slot of
    /// its scene leaf. Written in place: collapsed into a tree of its own and then appended, the
    /// nodes were copied once more, and a large buffer's build spent a fifth of its time on it.
    fn collapse(&mut self, scene: &SceneLeaves, out: &mut WideBvh8) -> Result<u32, BuildError> {
        let nodes = &self.bvh.nodes;
        let root = out.nodes.len();
        out.nodes.push(WideNodeN::UNUSED);
        let pending = &mut self.pending;
        pending.clear();
        pending.push((root, 0u32, 0u32));
        // The binary nodes a wide node takes, at most 8: on the stack, no allocation per node.
        let mut open = [0u32; 8];
        while let Some((wide, binary, depth)) = pending.pop() {
            out.max_depth = out.max_depth.max(depth);
            let node = &nodes[binary as usize];
            let mut len = if node.count > 0 {
                open[0] = binary;
                1
            } else {
                open[..2].copy_from_slice(&[node.left_first, node.left_first + 1]);
                2
            };
            while len < 8 {
                let widest = (0..len)
                    .filter(|&i| nodes[open[i] as usize].count == 0)
                    .max_by(|&a, &b| {
                        let area = |i: usize| nodes[open[i] as usize].bounds().surface_area();
                        area(a).total_cmp(&area(b))
                    });
                let Some(i) = widest else { break };
                let left = nodes[open[i] as usize].left_first;
                open[i] = left;
                open[len] = left + 1;
                len += 1;
            }
            for (slot, &n) in open[..len].iter().enumerate() {
                let node = &nodes[n as usize];
                if node.count == 0 {
                    let child = out.nodes.len();
                    out.nodes.push(WideNodeN::UNUSED);
                    out.nodes[wide].set(slot, node.bounds(), child as u32, 0);
                    pending.push((child, n, depth + 1));
                } else if node.count == 1 {
                    let item = self.bvh.prim_indices[node.left_first as usize];
                    let (first, count) = scene.leaves[self.items[item as usize].0 as usize];
                    out.nodes[wide].set(slot, node.bounds(), first, count);
                } else {
                    return Err(BuildError::InvalidConfig(
                        "light buffer cell tree leaf with several scene leaves",
                    ));
                }
            }
        }
        Ok(root as u32)
    }
}
