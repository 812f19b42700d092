//! Wide (4-child) BVHs: the children's boxes as SoA lanes, so one 4-wide slab test checks all four.

use alloc::vec::Vec;

use bytemuck::{Pod, Zeroable};
use glam::Vec3;
use wide::f32x4;

use super::collapse::{CollapsePlan, LEAF_BLOCK};
use super::{Bvh, BvhNode, MAX_DEPTH};
use crate::geometry::{Aabb, Triangle, Triangle4};

/// A wide node of `W` children (4 or 8), `32 W` bytes on a 64-byte boundary: the children's
/// boxes as `min`/`max` lanes per axis (one `W`-lane load each), then per child either an inner
/// node index (`count == 0`), a leaf's first [`Triangle4`] block (`count > 0` triangles, in
/// `ceil(count / 4)` blocks), or nothing (`child == EMPTY`, with an inverted box that no ray can
/// hit, so the slab test needs no mask).
#[derive(Clone, Copy, Debug, PartialEq)]
#[repr(C, align(64))]
pub struct WideNodeN<const W: usize> {
    /// Lower bounds of the children, per axis.
    pub min: [[f32; W]; 3],
    /// Upper bounds of the children, per axis.
    pub max: [[f32; W]; 3],
    /// Child node index, or first triangle block of a leaf child, or [`WideNodeN::EMPTY`].
    pub child: [u32; W],
    /// Triangles of a leaf child; zero for an inner child or an empty slot.
    pub count: [u32; W],
}

/// The 4-wide node: 128 bytes, its child boxes tested with one `f32x4` per plane.
pub type WideNode = WideNodeN<4>;

/// The 8-wide node: 256 bytes, its child boxes tested with one `f32x8` per plane (two 4-wide
/// halves without AVX).
pub type WideNode8 = WideNodeN<8>;

// SAFETY: every field is an array of `f32` or `u32` (any bit pattern valid, zero included), and
// `32 W` bytes of fields fill the 64-byte alignment exactly for W = 4 and 8: no padding.
unsafe impl Zeroable for WideNodeN<4> {}
// SAFETY: as above.
unsafe impl Pod for WideNodeN<4> {}
// SAFETY: as above.
unsafe impl Zeroable for WideNodeN<8> {}
// SAFETY: as above.
unsafe impl Pod for WideNodeN<8> {}

static_assertions::assert_eq_size!(WideNode, [u8; 128]);
static_assertions::const_assert_eq!(core::mem::align_of::<WideNode>(), 64);
static_assertions::const_assert_eq!(core::mem::offset_of!(WideNode, min), 0);
static_assertions::const_assert_eq!(core::mem::offset_of!(WideNode, max), 48);
static_assertions::assert_eq_size!(WideNode8, [u8; 256]);
static_assertions::const_assert_eq!(core::mem::offset_of!(WideNode8, max), 96);

impl<const W: usize> WideNodeN<W> {
    /// The `child` value of an unused slot.
    pub const EMPTY: u32 = u32::MAX;

    /// A node with every slot unused.
    pub(crate) const UNUSED: Self = Self {
        min: [[f32::INFINITY; W]; 3],
        max: [[f32::NEG_INFINITY; W]; 3],
        child: [Self::EMPTY; W],
        count: [0; W],
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

    /// Fills slot `i`: `child` is a node index (`count` 0) or a leaf's first block.
    pub(crate) fn set(&mut self, i: usize, bounds: Aabb, child: u32, count: u32) {
        for k in 0..3 {
            self.min[k][i] = bounds.min[k];
            self.max[k][i] = bounds.max[k];
        }
        self.child[i] = child;
        self.count[i] = count;
    }
}

/// A wide BVH of `W` children per node (4: [`WideBvh`], 8: [`WideBvh8`]) with its own copy of the
/// triangles, in leaf order and laid out for the 4-wide triangle test ([`Triangle4`] blocks: a leaf tests four triangles per step, with no indirection
/// through a primitive-index array). The root is node 0; a BVH whose binary root becomes a leaf
/// (see [`WideBvh::from_binary`]) gets a root with that leaf as its only child.
///
/// ```
/// use rdbvh_core::{BuildOptions, Preset, Ray, Triangle, Vec3, WideBvh};
///
/// let tris: Vec<Triangle> = (0..50)
///     .map(|i| {
///         let o = Vec3::new(i as f32, 0.0, 4.0);
///         Triangle::new(o, o + Vec3::X, o + Vec3::Y)
///     })
///     .collect();
/// // A tree only to be collapsed can skip what the collapse throws away.
/// let options = BuildOptions { for_wide: true, ..BuildOptions::new(Preset::Sah) };
/// let wide = WideBvh::from_binary(&options.build(&tris, None)?, &tris);
/// let ray = Ray::new(Vec3::new(7.1, 0.1, 0.0), Vec3::Z)?;
/// assert_eq!(wide.closest_hit(&ray).map(|h| h.triangle), Some(7));
/// // A shadow segment that stops short of the triangles.
/// let shadow = Ray::segment(Vec3::new(7.1, 0.1, 0.0), Vec3::Z, 0.0, 3.9)?;
/// assert!(!wide.any_hit(&shadow));
/// # Ok::<(), Box<dyn std::error::Error>>(())
/// ```
#[derive(Clone, Debug, Default, PartialEq)]
pub struct WideBvhN<const W: usize> {
    pub(crate) nodes: Vec<WideNodeN<W>>,
    pub(crate) tris: Vec<Triangle4>,
    pub(crate) max_depth: u32,
    bounds: Aabb,
    /// The union of the root's children's boxes as `(x, y, z, _)` lanes, lane 3 spanning
    /// `-inf..inf` (empty for an empty tree): the traversals' first, set-up-free test
    /// ([`WideBvh::misses_root`](crate::bvh::WideBvh)).
    pub(crate) root_min: f32x4,
    pub(crate) root_max: f32x4,
}

/// The 4-wide BVH: the width whose node and triangle-test counts the renderer's and the CLI's
/// counters compare structures at.
pub type WideBvh = WideBvhN<4>;

/// The 8-wide BVH: half the levels of the 4-wide tree's, so half the dependent node fetches on a
/// ray's path, for the same triangle blocks.
pub type WideBvh8 = WideBvhN<8>;

impl<const W: usize> WideBvhN<W> {
    /// A binary subtree of at most this many triangles always becomes one leaf of the wide tree,
    /// in one [`Triangle4`] block, whatever its shape: one 4-wide test replaces the subtree's box
    /// tests and its one or two scalar leaf tests. So a binary build meant only for the collapse
    /// need not split such nodes ([`crate::builder::Builder::for_wide`]).
    pub const ONE_BLOCK: u32 = 4;

    /// Collapses a binary BVH built over `tris` into the `W`-wide tree of least SAH cost that keeps
    /// its subtrees (node and block tests priced alike; `core/src/bvh/collapse.rs`): each wide
    /// node stands for a binary node and takes two to four of its descendants as slots, chosen by
    /// dynamic programming over the binary tree. A binary subtree of at most four triangles
    /// becomes one leaf of one [`Triangle4`] block, one of five to eight a leaf of two blocks when
    /// that costs less than opening it, and a larger binary leaf a leaf of consecutive blocks.
    /// Depth never grows. Ids missing from `tris` are dropped, as the binary traversal skips them.
    ///
    /// Each node's children come fewest triangles first, a leaf before an inner child of as
    /// many, so that an any-hit query tries the cheap subtrees before a large one.
    pub fn from_binary(bvh: &Bvh, tris: &[Triangle]) -> Self {
        let mut out = Self::collapse(bvh, tris);
        out.order_fewest_first();
        let root = out.nodes.first().map_or(Aabb::EMPTY, |root| {
            (0..W).fold(Aabb::EMPTY, |b, i| b.union(root.child_bounds(i)))
        });
        let (lo, hi) = (root.min, root.max);
        out.root_min = f32x4::from([lo.x, lo.y, lo.z, f32::NEG_INFINITY]);
        out.root_max = f32x4::from([hi.x, hi.y, hi.z, f32::INFINITY]);
        out
    }

    /// [`WideBvh::from_binary`] but for the root's box.
    fn collapse(bvh: &Bvh, tris: &[Triangle]) -> Self {
        let mut out = Self {
            nodes: Vec::with_capacity(bvh.nodes.len() / 4 + 1),
            tris: Vec::with_capacity(bvh.prim_indices.len() / 2 + 1),
            max_depth: 0,
            bounds: bvh.bounds(),
            root_min: f32x4::ZERO,
            root_max: f32x4::ZERO,
        };
        if bvh.nodes.is_empty() {
            return out;
        }
        out.nodes.push(WideNodeN::UNUSED);
        let plan = CollapsePlan::<W>::new(bvh);
        if plan.root_is_leaf() {
            out.push_leaf(0, 0, bvh, 0, tris);
            return out;
        }
        // (wide node to fill, binary inner node whose subtree it stands for, depth)
        let mut stack: Vec<(u32, u32, u32)> = Vec::with_capacity(MAX_DEPTH as usize * (W - 1) + 1);
        stack.push((0, 0, 0));
        while let Some((wide, binary, depth)) = stack.pop() {
            out.max_depth = out.max_depth.max(depth);
            let mut slots = [(0u32, false); W];
            let n = plan.slots(bvh, binary, &mut slots);
            for (slot, &(b, leaf)) in slots[..n].iter().enumerate() {
                if leaf {
                    out.push_leaf(wide, slot, bvh, b, tris);
                } else {
                    let child: &BvhNode = &bvh.nodes[b as usize];
                    let index = out.nodes.len() as u32;
                    out.nodes.push(WideNodeN::UNUSED);
                    out.nodes[wide as usize].set(slot, child.bounds(), index, 0);
                    stack.push((index, b, depth + 1));
                }
            }
        }
        out
    }

    /// Makes slot `slot` of wide node `wide` a leaf holding the triangles of binary subtree `b`
    /// (a leaf or a small subtree), appended as blocks; a leaf left with no triangle (every id
    /// missing from `tris`) leaves the slot unused.
    fn push_leaf(&mut self, wide: u32, slot: usize, bvh: &Bvh, b: u32, tris: &[Triangle]) {
        let first = self.tris.len();
        let mut count = 0usize;
        let mut add = |out: &mut Vec<Triangle4>, id: u32| {
            let Some(tri) = tris.get(id as usize) else {
                return;
            };
            if count.is_multiple_of(4) {
                out.push(Triangle4::EMPTY);
            }
            let last = out.len() - 1;
            out[last].set(count % 4, tri, id);
            count += 1;
        };
        let node = &bvh.nodes[b as usize];
        if node.is_leaf() {
            for &id in bvh.leaf_prims(node) {
                add(&mut self.tris, id);
            }
        } else {
            let (ids, n) = small_subtree(bvh, b).unwrap_or(([0; LEAF_BLOCK], 0));
            for &id in &ids[..n] {
                add(&mut self.tris, id);
            }
        }
        if count > 0 {
            self.nodes[wide as usize].set(slot, node.bounds(), first as u32, count as u32);
        }
    }
    /// The nodes, root first.
    pub fn nodes(&self) -> &[WideNodeN<W>] {
        &self.nodes
    }

    /// The leaves' triangles in leaf order, four per block (a leaf child's `child` is its first
    /// block, its `count` the number of triangles).
    pub fn triangles(&self) -> &[Triangle4] {
        &self.tris
    }

    /// Depth of the deepest wide node (the root has depth 0).
    pub fn max_depth(&self) -> u32 {
        self.max_depth
    }

    /// The root's box.
    pub fn bounds(&self) -> Aabb {
        self.bounds
    }

    /// Bytes of the node and triangle arrays.
    pub fn memory_bytes(&self) -> usize {
        self.nodes.len() * core::mem::size_of::<WideNodeN<W>>()
            + self.tris.len() * core::mem::size_of::<Triangle4>()
    }

    /// Reorders the children of every node from node `first` on (the last tree of a forest, a
    /// node array holding several trees) by `key` of their boxes, largest first, the unused
    /// slots last.
    /// Unordered traversals (any hit, the all-hit count) visit the children a ray hits in slot
    /// order, so for rays of a known direction this sends an any-hit query first into the child
    /// likeliest to end it; answers do not change, only the work before them.
    pub(crate) fn order_children(&mut self, first: usize, key: impl Fn(&Aabb) -> f32) {
        self.sort_slots(first, |node, i| -f64::from(key(&node.child_bounds(i))));
    }

    /// Reorders every node's children so that the one holding the fewest triangles comes first,
    /// a leaf before an inner child of as many, ties in their collapse order. An any-hit query
    /// visits the children it hits in slot order, and a small subtree is cheap to search, so a
    /// shadow ray tries the cheap children before it commits to a large one: on the
    /// benches' any-hit rays this cut Sponza's node visits by a tenth to a quarter
    /// (benches/RESULTS.md). Closest-hit queries order by distance; no answer changes.
    pub(crate) fn order_fewest_first(&mut self) {
        // The collapse pushes every node before its children, so one backward pass over `nodes`
        // sizes every subtree.
        let mut triangles = alloc::vec![0u64; self.nodes.len()];
        for (i, node) in self.nodes.iter().enumerate().rev() {
            triangles[i] = (0..W)
                .filter(|&k| node.child[k] != WideNodeN::<W>::EMPTY)
                .map(|k| match node.count[k] {
                    0 => triangles[node.child[k] as usize],
                    n => u64::from(n),
                })
                .sum();
        }
        let inner_after_leaf = 0.5;
        self.sort_slots(0, |node, k| match node.count[k] {
            0 => triangles[node.child[k] as usize] as f64 + inner_after_leaf,
            n => f64::from(n),
        });
    }

    /// Reorders the children of every node from node `first` on by `key(node, slot)`, smallest
    /// first (a stable sort), the unused slots last.
    fn sort_slots(&mut self, first: usize, key: impl Fn(&WideNodeN<W>, usize) -> f64) {
        for node in &mut self.nodes[first..] {
            let mut slots: [usize; W] = core::array::from_fn(|i| i);
            let keys: [f64; W] = core::array::from_fn(|i| {
                if node.child[i] == WideNodeN::<W>::EMPTY {
                    f64::INFINITY
                } else {
                    key(node, i)
                }
            });
            slots.sort_by(|&a, &b| keys[a].total_cmp(&keys[b]));
            let old = *node;
            for (i, &from) in slots.iter().enumerate() {
                node.set(i, old.child_bounds(from), old.child[from], old.count[from]);
            }
        }
    }
}

/// The primitive ids of binary subtree `b` when it is a leaf of at most [`LEAF_BLOCK`] primitives
/// or an inner node whose subtree holds at most that many; `None` otherwise (a larger binary leaf
/// is not "small": it becomes a leaf of several blocks, but only at the subtree's own node).
fn small_subtree(bvh: &Bvh, b: u32) -> Option<([u32; LEAF_BLOCK], usize)> {
    let mut ids = [0u32; LEAF_BLOCK];
    let mut n = 0usize;
    // A subtree of at most LEAF_BLOCK primitives has at most LEAF_BLOCK leaves, so its walk never
    // holds more than LEAF_BLOCK pending nodes; a larger one is abandoned as soon as it shows.
    let mut pending = [0u32; LEAF_BLOCK + 1];
    let mut top = 1;
    pending[0] = b;
    while top > 0 {
        top -= 1;
        let node = &bvh.nodes[pending[top] as usize];
        if node.is_leaf() {
            let prims = bvh.leaf_prims(node);
            if n + prims.len() > LEAF_BLOCK {
                return None;
            }
            ids[n..n + prims.len()].copy_from_slice(prims);
            n += prims.len();
        } else {
            if top + 2 > pending.len() {
                return None;
            }
            pending[top] = node.left_first + 1;
            pending[top + 1] = node.left_first;
            top += 2;
        }
    }
    Some((ids, n))
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::builder::{BinSpace, BuildConfig, Builder, CutEvaluation, ThesisCut};
    use crate::heuristics::{AxisChooser, CostModel, LeafSize, Termination};
    use crate::test_scenes::soup;

    /// The ids of each leaf slot's blocks, sorted: what a leaf holds, whatever its grouping.
    fn leaf_sets(wide: &WideBvh) -> Vec<Vec<u32>> {
        let mut sets = Vec::new();
        for node in wide.nodes() {
            for slot in 0..4 {
                let (first, count) = (node.child[slot] as usize, node.count[slot] as usize);
                if count == 0 {
                    continue;
                }
                let blocks = &wide.triangles()[first..first + count.div_ceil(4)];
                let mut ids: Vec<u32> = blocks.iter().flat_map(|b| b.id).collect();
                ids.truncate(count);
                ids.sort_unstable();
                sets.push(ids);
            }
        }
        sets
    }

    fn same_collapse<A, C, T>(builder: Builder<A, C, T>, tris: &[Triangle])
    where
        A: AxisChooser + Clone,
        C: CostModel + Clone,
        T: Termination + Clone,
    {
        let full = builder.clone().build(tris).unwrap();
        let pruned = builder.for_wide().build(tris).unwrap();
        let (a, b) = (
            WideBvh::from_binary(&full, tris),
            WideBvh::from_binary(&pruned, tris),
        );
        assert_eq!(a.nodes(), b.nodes(), "{} triangles", tris.len());
        assert_eq!(a.max_depth(), b.max_depth());
        assert_eq!(leaf_sets(&a), leaf_sets(&b));
        if tris.len() > 4 {
            assert!(pruned.nodes().len() < full.nodes().len());
        }
    }

    #[test]
    fn a_tree_built_for_wide_collapses_to_the_same_wide_tree() {
        let thesis = BuildConfig {
            cut: CutEvaluation::Thesis(ThesisCut::SPFH),
            bin_space: BinSpace::NodeBox,
            ..BuildConfig::default()
        };
        for (n, seed) in [(1, 1), (3, 2), (4, 3), (5, 4), (9, 5), (200, 6), (3000, 7)] {
            for spread in [0.05, 2.0] {
                let tris = soup(n, seed, -10.0, 10.0, spread);
                same_collapse(Builder::sah(), &tris);
                same_collapse(Builder::lsph(), &tris);
                same_collapse(
                    Builder::sah().with_termination(LeafSize { max_leaf: 2 }),
                    &tris,
                );
                same_collapse(Builder::sah().with_config(thesis), &tris);
            }
        }
    }

    /// `from_binary` puts each node's children fewest triangles first (a leaf before an inner
    /// child of as many), unused slots last, and only permutes the collapse's slots.
    #[test]
    fn children_come_fewest_triangles_first() {
        fn triangles<const W: usize>(tree: &WideBvhN<W>, node: u32, slot: usize) -> u32 {
            let n = &tree.nodes[node as usize];
            match n.count[slot] {
                0 => {
                    let inner = &tree.nodes[n.child[slot] as usize];
                    (0..W)
                        .filter(|&k| inner.child[k] != WideNodeN::<W>::EMPTY)
                        .map(|k| triangles(tree, n.child[slot], k))
                        .sum()
                }
                c => c,
            }
        }
        fn check<const W: usize>(tris: &[Triangle]) {
            let bvh = Builder::sah().build(tris).unwrap();
            let tree = WideBvhN::<W>::from_binary(&bvh, tris);
            let plain = WideBvhN::<W>::collapse(&bvh, tris);
            assert_eq!(tree.nodes.len(), plain.nodes.len());
            assert_eq!(tree.tris, plain.tris);
            for (i, (node, old)) in tree.nodes.iter().zip(&plain.nodes).enumerate() {
                let slots = |n: &WideNodeN<W>| {
                    let mut v: Vec<(u32, u32)> = (0..W).map(|k| (n.child[k], n.count[k])).collect();
                    v.sort_unstable();
                    v
                };
                assert_eq!(slots(node), slots(old), "node {i} holds other children");
                let used = node.arity();
                assert!(node.child[used..]
                    .iter()
                    .all(|&c| c == WideNodeN::<W>::EMPTY));
                // A leaf of `n` triangles sorts as `2 n`, an inner child of `n` as `2 n + 1`.
                let key = |k: usize| {
                    let n = triangles(&tree, i as u32, k);
                    2 * n + u32::from(node.count[k] == 0)
                };
                for k in 1..used {
                    assert!(key(k - 1) <= key(k), "node {i}: slot {k} comes too late");
                }
            }
        }
        let tris = soup(900, 5, 0.0, 10.0, 1.0);
        check::<4>(&tris);
        check::<8>(&tris);
    }

    /// Ordered children come largest key first with the unused slots last, and every query
    /// answers as before: the any-hit answer and the all-hit count of random rays.
    #[test]
    fn ordered_children_keep_the_answers() {
        let tris = soup(500, 11, 0.0, 10.0, 1.0);
        let bvh = Builder::sah().build(&tris).unwrap();
        let wide = WideBvh8::from_binary(&bvh, &tris);
        let mut ordered = wide.clone();
        let key = |b: &Aabb| b.center().x - b.center().y;
        ordered.order_children(0, key);
        for node in &ordered.nodes {
            let used = node.arity();
            assert!(node.child[used..]
                .iter()
                .all(|&c| c == WideNodeN::<8>::EMPTY));
            for i in 1..used {
                assert!(key(&node.child_bounds(i - 1)) >= key(&node.child_bounds(i)));
            }
        }
        let mut rng = crate::random::Pcg32::new(3);
        for _ in 0..2000 {
            let p = |rng: &mut crate::random::Pcg32| {
                Vec3::new(
                    rng.range(-1.0, 11.0),
                    rng.range(-1.0, 11.0),
                    rng.range(-1.0, 11.0),
                )
            };
            let (a, b) = (p(&mut rng), p(&mut rng));
            let ray = crate::geometry::Ray::segment(a, b - a, 0.0, 1.0).unwrap();
            assert_eq!(ordered.any_hit(&ray), wide.any_hit(&ray));
            assert_eq!(ordered.all_hit(&ray).hits, wide.all_hit(&ray).hits);
            assert_eq!(ordered.closest_hit(&ray), wide.closest_hit(&ray));
        }
    }
}
