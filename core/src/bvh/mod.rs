//! Flat binary BVHs: node arrays with adjacent children, a primitive-index array, and the maximum
//! depth recorded at build time so that traversal stacks are provably large enough.

#[cfg(target_arch = "x86_64")]
mod avx2;
mod collapse;
mod dispatch;
mod node;
mod traversable;
mod traverse;
mod validate;
mod wide;
mod wide_traverse;

use alloc::vec::Vec;

pub use dispatch::{set_simd_level, simd_level, SimdLevel};
pub use node::BvhNode;
pub use traversable::Traversable;
pub use traverse::{AllHitStats, Hit, TraversalStats};
pub use validate::InvariantError;
pub use wide::{WideBvh, WideBvh8, WideBvhN, WideNode, WideNode8, WideNodeN};
pub(crate) use wide_traverse::Counters;
pub use wide_traverse::{
    AnyHit, ChildLanes, ClosestHit, ClosestHitEdges, HitCount, Lanes, LeafVisitor, Width,
};

use crate::geometry::Aabb;
use crate::heuristics::{CostConstants, CostModel};

/// The deepest a BVH may be: no builder splits a node at this depth, and the traversals' fixed
/// stacks are sized from it (`MAX_DEPTH + 1` entries for the binary tree, `3 MAX_DEPTH + 4` for the
/// 4-wide one). Once `depth + ceil(log2 n)` reaches the bound, a node is split at its object
/// median (which halves it), so adversarial inputs can reach depth 64 but never pass it, and since
/// `log2(u32::MAX) = 32` the halving splits always have room to bring any node down to one
/// primitive.
pub const MAX_DEPTH: u32 = 64;

/// A binary BVH over primitives identified by `u32` ids (for triangles, their index in the
/// scene's triangle array).
///
/// Only the builders make one, so its invariants hold by construction and the traversals can rely
/// on them: children in range and adjacent, depth at most [`MAX_DEPTH`], every leaf's run inside
/// [`Bvh::prim_indices`]. [`Bvh::validate`] checks them all.
///
/// A renderer that rebuilds every frame sizes the arena and the tree once and builds into them
/// without allocating:
///
/// ```
/// use rdbvh_core::builder::BuildArena;
/// use rdbvh_core::{BuildOptions, Bvh, Preset, Ray, Triangle, Vec3};
///
/// let mut tris: Vec<Triangle> = (0..32)
///     .map(|i| {
///         let o = Vec3::new(i as f32, 0.0, 2.0);
///         Triangle::new(o, o + Vec3::X, o + Vec3::Y)
///     })
///     .collect();
/// let options = BuildOptions::new(Preset::Sah);
/// let mut arena = BuildArena::with_capacity(tris.len());
/// let mut bvh = Bvh::with_capacity(tris.len());
/// for frame in 0..3 {
///     for t in &mut tris {
///         *t = Triangle::new(t.v0 + Vec3::Z, t.v1 + Vec3::Z, t.v2 + Vec3::Z); // the scene moves
///     }
///     arena.load_triangles(&tris)?;
///     options.build_into(&mut arena, None, &mut bvh)?;
///     let ray = Ray::new(Vec3::new(3.1, 0.1, 0.0), Vec3::Z)?;
///     let hit = bvh.closest_hit(&ray, &tris).unwrap();
///     assert_eq!((hit.triangle, hit.t), (3, 3.0 + frame as f32));
///     assert!(bvh.any_hit(&ray, &tris));
/// }
/// # Ok::<(), Box<dyn std::error::Error>>(())
/// ```
#[derive(Clone, Debug, Default, PartialEq)]
pub struct Bvh {
    pub(crate) nodes: Vec<BvhNode>,
    pub(crate) prim_indices: Vec<u32>,
    pub(crate) max_depth: u32,
}

impl Bvh {
    /// An empty BVH with room for a build over `prims` primitives (at most `2 prims - 1` nodes), so
    /// that [`crate::builder::Builder::build_into`] does not allocate: 68 bytes per primitive (two
    /// 32-byte nodes and a 4-byte index). Like `Vec::with_capacity`, it panics past `isize::MAX`
    /// bytes and aborts when the allocation fails; [`Bvh::try_with_capacity`] reports both.
    pub fn with_capacity(prims: usize) -> Self {
        Self {
            nodes: Vec::with_capacity(Self::node_capacity(prims)),
            prim_indices: Vec::with_capacity(prims),
            max_depth: 0,
        }
    }

    /// [`Bvh::with_capacity`], returning the allocation's failure instead of panicking or
    /// aborting.
    pub fn try_with_capacity(prims: usize) -> Result<Self, alloc::collections::TryReserveError> {
        let mut nodes = Vec::new();
        nodes.try_reserve_exact(Self::node_capacity(prims))?;
        let mut prim_indices = Vec::new();
        prim_indices.try_reserve_exact(prims)?;
        Ok(Self {
            nodes,
            prim_indices,
            max_depth: 0,
        })
    }

    /// Nodes of a build over `prims` primitives, at most: `2 prims - 1` (at least one).
    fn node_capacity(prims: usize) -> usize {
        prims.saturating_mul(2).saturating_sub(1).max(1)
    }

    /// Nodes, root first, children adjacent; an empty BVH has no nodes.
    #[inline]
    pub fn nodes(&self) -> &[BvhNode] {
        &self.nodes
    }

    /// Primitive ids in leaf order: a leaf refers to a contiguous run of this array.
    #[inline]
    pub fn prim_indices(&self) -> &[u32] {
        &self.prim_indices
    }

    /// Depth of the deepest node (the root has depth 0), at most [`MAX_DEPTH`].
    #[inline]
    pub fn max_depth(&self) -> u32 {
        self.max_depth
    }

    /// The primitive ids of a leaf (empty for an inner node).
    #[inline]
    pub fn leaf_prims(&self, node: &BvhNode) -> &[u32] {
        let first = node.left_first as usize;
        self.prim_indices
            .get(first..first + node.count as usize)
            .unwrap_or(&[])
    }

    /// True when the BVH holds no primitive.
    pub fn is_empty(&self) -> bool {
        self.prim_indices.is_empty()
    }

    /// The root's box ([`Aabb::EMPTY`] for an empty BVH).
    pub fn bounds(&self) -> Aabb {
        self.nodes.first().map_or(Aabb::EMPTY, BvhNode::bounds)
    }

    /// Number of leaves.
    pub fn leaf_count(&self) -> usize {
        self.nodes.iter().filter(|n| n.is_leaf()).count()
    }

    /// Bytes held by the node and index arrays.
    pub fn memory_bytes(&self) -> usize {
        self.nodes.len() * core::mem::size_of::<BvhNode>() + self.prim_indices.len() * 4
    }

    /// The expected cost of a ray that hits the root, under the hit measure `model`:
    /// `sum over inner nodes of C_trav * m(n) / m(root) + sum over leaves of C_isect * count *
    /// m(leaf) / m(root)`. With [`crate::heuristics::Sah`] this is the SAH cost. Zero for an empty
    /// BVH or a root of zero measure.
    pub fn estimated_cost(&self, model: &impl CostModel, k: CostConstants) -> f32 {
        self.estimated_cost_over(model, k, model.measure(&self.bounds()))
    }

    /// The expected cost of a ray drawn from a distribution of total measure `total` (for an
    /// influence area, its window's measure): the same sum as [`Bvh::estimated_cost`] over `total`
    /// instead of the root's measure, so rays that miss the root count as costing nothing, as they
    /// do when rays are traced. Zero for an empty BVH or a non-positive `total`.
    pub fn estimated_cost_over(&self, model: &impl CostModel, k: CostConstants, total: f32) -> f32 {
        // NaN fails `total > 0.0` too.
        if self.nodes.is_empty() || total.partial_cmp(&0.0) != Some(core::cmp::Ordering::Greater) {
            return 0.0;
        }
        let sum: f64 = self
            .nodes
            .iter()
            .map(|n| {
                let m = f64::from(model.measure(&n.bounds()));
                if n.is_leaf() {
                    m * f64::from(k.intersection) * f64::from(n.count)
                } else {
                    m * f64::from(k.traversal)
                }
            })
            .sum();
        (sum / f64::from(total)) as f32
    }
}
