//! Reinsertion: improving a built BVH by moving subtrees to where they cost least.
//!
//! A top-down build decides every split once, from centroids binned at the node; the tree it
//! leaves is good but not a local optimum of its own cost. Reinsertion (Bittner, Hapala and Havran,
//! "Fast insertion-based optimization of bounding volume hierarchies", 2013) takes the nodes of
//! largest measure, removes each from the tree (its sibling takes its parent's place) and puts it
//! back as the sibling of the node where it adds the least cost, found by branch and bound from
//! the root. It matters most on scenes of long, overlapping triangles.
//!
//! Leaves move whole: their primitives and boxes never change, so a tree's cost
//! (`C_trav * sum of inner measures + C_isect * sum of leaf measures x counts`, over the root's)
//! changes only through the inner nodes' measures. Inserting node `N` beside node `X` makes one
//! inner node of measure `m(X u N)` and grows every ancestor `A` of `X` by `m(A u N) - m(A)`; the
//! search keeps the `X` with the least such sum. The node's old place is priced first and a new
//! place must beat it by more than rounding could fake, so the cost never grows.

use alloc::collections::BinaryHeap;
use alloc::vec::Vec;
use bytemuck::Zeroable;
use core::cmp::Reverse;

use super::keys::{ordered, unordered};
use crate::bvh::{Bvh, BvhNode, MAX_DEPTH};
use crate::geometry::Aabb;
use crate::heuristics::CostModel;

/// No node: the root's parent, a leaf's children.
const NONE: u32 = u32::MAX;

/// The share of its old place's cost by which a node's new place must be cheaper.
const MIN_GAIN: f32 = 1e-5;

/// How much reinsertion to do.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct ReinsertConfig {
    /// Share of the nodes, the largest by the cost model's measure, that one pass tries to move.
    /// Large nodes gain most (a ray is likeliest to visit them) and are found soonest (their
    /// measure prunes the search early).
    pub fraction: f32,
    /// The most passes; each pass picks its candidates afresh.
    pub max_passes: u32,
    /// A pass that lowers the inner nodes' summed measure by less than this share of it is the
    /// last.
    pub min_gain: f32,
    /// The deepest the result may be, at most [`MAX_DEPTH`]: moves can deepen a tree, and a
    /// renderer may size its stacks for the depth its build was bounded to. A result deeper than
    /// this is dropped and the input kept.
    pub max_depth: u32,
}

impl Default for ReinsertConfig {
    /// 2% of the nodes per pass, at most 3 passes, stop below a 0.1% gain, depth up to
    /// [`MAX_DEPTH`]: the best 4-wide traversal cost of the settings compared (measured:
    /// benches/RESULTS.md, section Tree quality for traversal: reinsertion and the 4-wide
    /// collapse).
    fn default() -> Self {
        Self {
            fraction: 0.02,
            max_passes: 3,
            min_gain: 0.001,
            max_depth: MAX_DEPTH,
        }
    }
}

impl ReinsertConfig {
    /// True when the settings make sense: `fraction` in `(0, 1]`, `min_gain` finite and not
    /// negative, `max_depth` at most [`MAX_DEPTH`].
    pub fn is_valid(&self) -> bool {
        self.fraction > 0.0
            && self.fraction <= 1.0
            && self.min_gain.is_finite()
            && self.min_gain >= 0.0
            && self.max_depth <= MAX_DEPTH
    }
}

/// What a reinsertion run did.
#[derive(Clone, Copy, Debug, Default, PartialEq)]
pub struct ReinsertStats {
    /// Passes run.
    pub passes: u32,
    /// Nodes taken out and put back.
    pub tried: u32,
    /// Nodes put back somewhere else.
    pub moved: u32,
    /// The inner nodes' summed measure over the root's, before and after: the tree's cost under
    /// the model fell by about `C_trav` times the difference (the stored root keeps the build's
    /// box, a hair larger than its children's union).
    pub inner_before: f32,
    /// See [`ReinsertStats::inner_before`].
    pub inner_after: f32,
    /// True when the optimized tree would have been deeper than [`ReinsertConfig::max_depth`], so
    /// the input tree was kept unchanged.
    pub kept_for_depth: bool,
    /// True when the settings were not [valid](ReinsertConfig::is_valid), so nothing ran and the
    /// tree is unchanged.
    pub invalid_config: bool,
}

/// Buckets of [`bucket`]: a positive finite float's exponent and its top three mantissa bits.
const BUCKETS: usize = 1 << 11;

/// The bucket of a positive finite measure: buckets are in the measures' order (a positive
/// float's bits are), so every measure in a higher bucket is larger.
#[inline(always)]
fn bucket(m: f32) -> usize {
    (m.to_bits() >> 20) as usize & (BUCKETS - 1)
}

/// A node waiting in the branch-and-bound search: its induced cost's [`ordered`] bits above its
/// index, so the min-heap pops the smallest induced cost first, ties to the lower index (the
/// search is a function of the tree alone), with one integer comparison.
#[inline(always)]
fn pending(induced: f32, node: u32) -> Reverse<u64> {
    Reverse(u64::from(ordered(induced)) << 32 | u64::from(node))
}

/// Reinsertion with its working memory: the tree as parent and child links (node indices are the
/// input's, and stay fixed while nodes move), the search heap, and the output arrays. Reuse one
/// across trees to allocate only when a tree, or a search's heap, needs more room than any before
/// (the output arrays trade places with the tree's, so their memory is reused too).
#[derive(Clone, Debug, Default)]
pub struct Reinserter {
    parent: Vec<u32>,
    children: Vec<[u32; 2]>,
    bounds: Vec<Aabb>,
    measure: Vec<f32>,
    /// Measure's [`ordered`] bits above the complemented index: descending order is the largest
    /// measure first, ties to the lower index.
    candidates: Vec<u64>,
    /// Nodes per [`bucket`] of measure, for [`Reinserter::pick`].
    histogram: Vec<u32>,
    heap: BinaryHeap<Reverse<u64>>,
    path: Vec<u32>,
    nodes: Vec<BvhNode>,
    prims: Vec<u32>,
    stack: Vec<(u32, u32, u32)>,
    root: u32,
}

impl Reinserter {
    /// A reinserter with no memory yet.
    pub fn new() -> Self {
        Self::default()
    }

    /// Optimizes `bvh` in place under `model`: at most `config.max_passes` passes, each trying the
    /// `config.fraction` largest nodes. The result holds the same leaves (primitives and boxes), is
    /// laid out as a builder lays it out (depth first, children adjacent, primitive runs in leaf
    /// order), and costs no more than the input under `model`. A tree of fewer than five nodes,
    /// a root of zero or non-finite measure, or an invalid `config` leave `bvh` as it was (the
    /// last says so in [`ReinsertStats::invalid_config`]).
    ///
    /// Nodes the model measures at zero (a PAH node outside the light's window) are not tried:
    /// every place costs them nothing, so they stay where the build put them.
    pub fn optimize<M: CostModel>(
        &mut self,
        bvh: &mut Bvh,
        model: &M,
        config: &ReinsertConfig,
    ) -> ReinsertStats {
        let mut stats = ReinsertStats {
            invalid_config: !config.is_valid(),
            ..ReinsertStats::default()
        };
        if bvh.nodes.len() < 5 || stats.invalid_config {
            return stats;
        }
        self.load(bvh, model);
        let root_measure = self.measure[0];
        if !(root_measure > 0.0 && root_measure.is_finite()) {
            return stats;
        }
        let mut inner = self.inner_sum();
        stats.inner_before = (inner / f64::from(root_measure)) as f32;
        for _ in 0..config.max_passes {
            self.pick(config.fraction);
            for k in 0..self.candidates.len() {
                let node = u32::MAX - self.candidates[k] as u32;
                stats.tried += 1;
                stats.moved += u32::from(self.reinsert(node, model));
            }
            stats.passes += 1;
            let now = self.inner_sum();
            let gain = inner - now;
            inner = now;
            if gain < f64::from(config.min_gain) * inner {
                break;
            }
        }
        stats.inner_after = (inner / f64::from(root_measure)) as f32;
        if stats.moved > 0 {
            if self.store(bvh, config.max_depth) {
                core::mem::swap(&mut bvh.nodes, &mut self.nodes);
                core::mem::swap(&mut bvh.prim_indices, &mut self.prims);
            } else {
                stats.kept_for_depth = true;
                stats.inner_after = stats.inner_before;
            }
        }
        stats
    }

    /// Reads the tree's links, boxes and measures.
    fn load<M: CostModel>(&mut self, bvh: &Bvh, model: &M) {
        let n = bvh.nodes.len();
        self.parent.clear();
        self.parent.resize(n, NONE);
        self.children.clear();
        self.children.resize(n, [NONE; 2]);
        // Reserved whole, not grown by doubling: the growth's copies are costly on large trees.
        self.bounds.clear();
        self.bounds.reserve(n);
        self.measure.clear();
        self.measure.reserve(n);
        for (i, node) in bvh.nodes.iter().enumerate() {
            let b = node.bounds();
            self.bounds.push(b);
            self.measure.push(model.measure(&b));
            if !node.is_leaf() {
                let l = node.left_first;
                self.children[i] = [l, l + 1];
                self.parent[l as usize] = i as u32;
                self.parent[l as usize + 1] = i as u32;
            }
        }
        self.root = 0;
    }

    /// The inner nodes' summed measure, in f64 so a pass's small gain is not lost in rounding.
    fn inner_sum(&self) -> f64 {
        self.children
            .iter()
            .zip(&self.measure)
            .filter(|(c, _)| c[0] != NONE)
            .map(|(_, &m)| f64::from(m))
            .sum()
    }

    /// The pass's candidates: the `fraction` largest nodes of positive measure (not the root),
    /// largest first, ties by index.
    ///
    /// A histogram of the measures' top bits finds the bucket the last candidate falls in, and
    /// only the nodes from that bucket up are collected and ordered: the same nodes, in the same
    /// order, as ordering them all, at a fraction of the cost on large trees.
    fn pick(&mut self, fraction: f32) {
        self.candidates.clear();
        let root = self.root as usize;
        // Positive and finite: the bits of (0, inf), one comparison.
        let valid = |m: f32| m.to_bits().wrapping_sub(1) < f32::INFINITY.to_bits() - 1;
        self.histogram.clear();
        self.histogram.resize(BUCKETS, 0);
        let mut count = 0usize;
        for &m in &self.measure {
            if valid(m) {
                self.histogram[bucket(m)] += 1;
                count += 1;
            }
        }
        if let Some(&m) = self.measure.get(root).filter(|&&m| valid(m)) {
            self.histogram[bucket(m)] -= 1;
            count -= 1;
        }
        let keep = (libm::ceil(count as f64 * f64::from(fraction)) as usize).min(count);
        if keep == 0 {
            return;
        }
        // The highest bucket whose nodes and those above number at least `keep`.
        let (mut lowest, mut above) = (BUCKETS - 1, 0usize);
        for (b, &n) in self.histogram.iter().enumerate().rev() {
            (lowest, above) = (b, above + n as usize);
            if above >= keep {
                break;
            }
        }
        self.candidates.extend(
            self.measure
                .iter()
                .enumerate()
                .filter(|&(i, &m)| valid(m) && bucket(m) >= lowest && i != root)
                .map(|(i, &m)| u64::from(ordered(m)) << 32 | u64::from(u32::MAX - i as u32)),
        );
        let order = |a: &u64, b: &u64| b.cmp(a);
        if keep < self.candidates.len() {
            self.candidates.select_nth_unstable_by(keep - 1, order);
            self.candidates.truncate(keep);
        }
        self.candidates.sort_unstable_by(order);
    }

    /// Takes `node` out and puts it back where it costs least; true when that is a new place.
    fn reinsert<M: CostModel>(&mut self, node: u32, model: &M) -> bool {
        let p = self.parent[node as usize];
        if p == NONE {
            return false;
        }
        let old = self.children[p as usize];
        let sibling = if old[0] == node { old[1] } else { old[0] };
        // Out: the sibling takes the parent's place, and the ancestors shrink.
        let g = self.parent[p as usize];
        self.replace(g, p, sibling);
        self.refit(g, model);

        let (nb, nm) = (self.bounds[node as usize], self.measure[node as usize]);
        // A new place must beat the old one by more than f32 rounding could fake: sums of
        // rounded measures, compared strictly, would otherwise take moves that cost a hair more.
        let stay = self.cost_beside(sibling, &nb, model);
        let (mut best, mut best_cost) = (sibling, stay - stay * MIN_GAIN);
        self.heap.clear();
        self.heap.push(pending(0.0, self.root));
        while let Some(Reverse(key)) = self.heap.pop() {
            let (induced, x) = (unordered((key >> 32) as u32), key as u32);
            // Every place below costs at least the induced cost plus the new node's own measure.
            if induced + nm >= best_cost {
                break;
            }
            let joined = model.measure(&self.bounds[x as usize].union(nb));
            let cost = induced + joined;
            if cost < best_cost {
                (best, best_cost) = (x, cost);
            }
            let [l, r] = self.children[x as usize];
            if l != NONE {
                let induced = induced + (joined - self.measure[x as usize]);
                if induced + nm < best_cost {
                    self.heap.push(pending(induced, l));
                    self.heap.push(pending(induced, r));
                }
            }
        }

        // In: the parent, reused, joins `node` and `best` where `best` was.
        let gb = self.parent[best as usize];
        self.replace(gb, best, p);
        self.children[p as usize] = if best == sibling { old } else { [best, node] };
        self.parent[best as usize] = p;
        self.parent[node as usize] = p;
        let b = self.bounds[best as usize].union(nb);
        self.bounds[p as usize] = b;
        self.measure[p as usize] = model.measure(&b);
        self.refit(gb, model);
        best != sibling
    }

    /// What putting a node of box `nb` beside `x` costs, summed from the root down exactly as the
    /// search sums it, so the search's price of the same place compares equal.
    fn cost_beside<M: CostModel>(&mut self, x: u32, nb: &Aabb, model: &M) -> f32 {
        self.path.clear();
        let mut a = self.parent[x as usize];
        while a != NONE {
            self.path.push(a);
            a = self.parent[a as usize];
        }
        let mut induced = 0.0f32;
        for &a in self.path.iter().rev() {
            let a = a as usize;
            induced += model.measure(&self.bounds[a].union(*nb)) - self.measure[a];
        }
        induced + model.measure(&self.bounds[x as usize].union(*nb))
    }

    /// Makes `new` the child of `parent` that `old` was (or the root, when `parent` is none).
    fn replace(&mut self, parent: u32, old: u32, new: u32) {
        if parent == NONE {
            self.root = new;
        } else {
            let c = &mut self.children[parent as usize];
            let k = usize::from(c[0] != old);
            c[k] = new;
        }
        self.parent[new as usize] = parent;
    }

    /// Recomputes the boxes from `node` up to the root; stops where a box did not change, since
    /// then none above it does.
    fn refit<M: CostModel>(&mut self, mut node: u32, model: &M) {
        while node != NONE {
            let [l, r] = self.children[node as usize];
            let b = self.bounds[l as usize].union(self.bounds[r as usize]);
            if b == self.bounds[node as usize] {
                break;
            }
            self.bounds[node as usize] = b;
            self.measure[node as usize] = model.measure(&b);
            node = self.parent[node as usize];
        }
    }

    /// Lays the tree out as a builder does (depth first, left child next, children adjacent,
    /// primitive runs in leaf order) in `self.nodes` and `self.prims`, and sets `bvh`'s depth.
    /// False, with `bvh` untouched, when the tree is deeper than `depth_limit`.
    fn store(&mut self, bvh: &mut Bvh, depth_limit: u32) -> bool {
        self.nodes.clear();
        self.nodes.reserve(bvh.nodes.len());
        self.prims.clear();
        self.prims.reserve(bvh.prim_indices.len());
        self.stack.clear();
        let mut max_depth = 0;
        // (input node, output slot, depth)
        self.nodes.push(<BvhNode as Zeroable>::zeroed());
        self.stack.push((self.root, 0, 0));
        // The root keeps the build's (padded) box: the same primitives are under it, and a tree's
        // cost is relative to the root's measure, which would otherwise shrink to the union of
        // its children and raise every ratio.
        let root_box = bvh.nodes[0].bounds();
        while let Some((node, slot, depth)) = self.stack.pop() {
            if depth > depth_limit {
                return false;
            }
            max_depth = max_depth.max(depth);
            let b = if slot == 0 {
                root_box
            } else {
                self.bounds[node as usize]
            };
            let [l, r] = self.children[node as usize];
            // Written directly, not by `BvhNode::leaf`/`inner`: those pad, and these boxes are
            // already the padded leaves' or unions of them.
            let out = if l == NONE {
                let leaf = &bvh.nodes[node as usize];
                let first = self.prims.len() as u32;
                self.prims.extend_from_slice(bvh.leaf_prims(leaf));
                BvhNode {
                    min: b.min.to_array(),
                    left_first: first,
                    max: b.max.to_array(),
                    count: leaf.count,
                }
            } else {
                let left = self.nodes.len() as u32;
                self.nodes.push(<BvhNode as Zeroable>::zeroed());
                self.nodes.push(<BvhNode as Zeroable>::zeroed());
                self.stack.push((r, left + 1, depth + 1));
                self.stack.push((l, left, depth + 1));
                BvhNode {
                    min: b.min.to_array(),
                    left_first: left,
                    max: b.max.to_array(),
                    count: 0,
                }
            };
            self.nodes[slot as usize] = out;
        }
        bvh.max_depth = max_depth;
        true
    }
}

/// [`Reinserter::optimize`] with fresh working memory.
///
/// A renderer that traces many rays per build builds, reinserts, then collapses to 4-wide nodes:
///
/// ```
/// use rdbvh_core::builder::{reinsert, Builder, ReinsertConfig};
/// use rdbvh_core::bvh::WideBvh;
/// use rdbvh_core::geometry::{Ray, Triangle};
/// use rdbvh_core::heuristics::{CostConstants, Sah};
/// use rdbvh_core::Vec3;
///
/// // A row of long thin triangles crossed by small ones.
/// let mut tris: Vec<Triangle> = (0..64)
///     .map(|i| {
///         let o = Vec3::new((i % 8) as f32, (i / 8) as f32, 0.0);
///         Triangle::new(o, o + Vec3::X * 0.3, o + Vec3::Y * 0.3)
///     })
///     .collect();
/// tris.extend((0..8).map(|i| {
///     let y = i as f32;
///     Triangle::new(Vec3::new(-1.0, y, 0.5), Vec3::new(9.0, y, 0.5), Vec3::new(-1.0, y + 0.1, 0.6))
/// }));
/// let mut bvh = Builder::sah().build(&tris)?;
/// let before = bvh.estimated_cost(&Sah, CostConstants::default());
/// let stats = reinsert(&mut bvh, &Sah, &ReinsertConfig::default());
/// assert!(bvh.estimated_cost(&Sah, CostConstants::default()) <= before);
/// assert!(stats.tried > 0);
///
/// let wide = WideBvh::from_binary(&bvh, &tris);
/// let ray = Ray::new(Vec3::new(2.1, 3.1, -1.0), Vec3::Z)?;
/// assert_eq!(wide.closest_hit(&ray), bvh.closest_hit(&ray, &tris));
/// # Ok::<(), Box<dyn core::error::Error>>(())
/// ```
pub fn reinsert<M: CostModel>(bvh: &mut Bvh, model: &M, config: &ReinsertConfig) -> ReinsertStats {
    Reinserter::new().optimize(bvh, model, config)
}

#[cfg(test)]
mod tests {
    use glam::Vec3;

    use super::*;
    use crate::brute_force;
    use crate::builder::Builder;
    use crate::geometry::{Ray, Triangle};
    use crate::heuristics::{CostConstants, Sah};
    use crate::random::Pcg32;

    /// Small triangles among long ones crossing the scene, as in an architectural model: a
    /// binned build leaves room for reinsertion there.
    fn small_among_long() -> Vec<Triangle> {
        let mut tris = crate::test_scenes::soup(3000, 5, -10.0, 10.0, 0.5);
        tris.extend(crate::test_scenes::soup(150, 6, -10.0, 10.0, 10.0));
        tris
    }

    fn check(bvh: &Bvh, tris: &[Triangle]) {
        bvh.validate(tris.len(), |i| tris[i as usize].bounds())
            .unwrap();
    }

    #[test]
    fn lowers_the_cost_and_keeps_every_answer() {
        let tris = small_among_long();
        let built = Builder::sah().build(&tris).unwrap();
        let mut bvh = built.clone();
        let stats = reinsert(&mut bvh, &Sah, &ReinsertConfig::default());
        check(&bvh, &tris);
        let k = CostConstants::default();
        let (before, after) = (built.estimated_cost(&Sah, k), bvh.estimated_cost(&Sah, k));
        assert!(
            stats.moved > 0 && after < 0.98 * before,
            "{stats:?}: {before} -> {after}"
        );
        assert!(stats.inner_after < stats.inner_before);
        // The leaves are the build's, laid out in the new leaf order.
        let leaves = |b: &Bvh| {
            let mut l: Vec<Vec<u32>> = b
                .nodes()
                .iter()
                .filter(|n| n.is_leaf())
                .map(|n| b.leaf_prims(n).to_vec())
                .collect();
            l.sort();
            l
        };
        assert_eq!(leaves(&built), leaves(&bvh));
        let mut rng = Pcg32::new(9);
        let mut v = |s: f32| Vec3::new(rng.range(-s, s), rng.range(-s, s), rng.range(-s, s));
        for _ in 0..2000 {
            let Ok(r) = Ray::new(v(15.0), v(1.0)) else {
                continue;
            };
            let expect = brute_force::closest_hit(&r, &tris);
            assert_eq!(bvh.closest_hit(&r, &tris), expect);
            assert_eq!(bvh.any_hit(&r, &tris), expect.is_some());
        }
    }

    #[test]
    fn is_deterministic_and_a_second_run_keeps_the_cost() {
        let tris = crate::test_scenes::soup(1500, 8, -5.0, 5.0, 2.0);
        let built = Builder::sah().build(&tris).unwrap();
        let (mut a, mut b) = (built.clone(), built.clone());
        let config = ReinsertConfig::default();
        reinsert(&mut a, &Sah, &config);
        let mut reused = Reinserter::new();
        reused.optimize(&mut b, &Sah, &config);
        assert_eq!(a, b);
        let k = CostConstants::default();
        let once = a.estimated_cost(&Sah, k);
        reused.optimize(&mut a, &Sah, &config);
        check(&a, &tris);
        assert!(a.estimated_cost(&Sah, k) <= once * (1.0 + 1e-6));
    }

    #[test]
    fn small_trees_and_bad_settings_are_left_alone() {
        let tris = crate::test_scenes::soup(200, 3, -5.0, 5.0, 3.0);
        let built = Builder::sah().build(&tris).unwrap();
        for config in [
            ReinsertConfig {
                fraction: 0.0,
                ..ReinsertConfig::default()
            },
            ReinsertConfig {
                fraction: f32::NAN,
                ..ReinsertConfig::default()
            },
            ReinsertConfig {
                min_gain: -1.0,
                ..ReinsertConfig::default()
            },
            ReinsertConfig {
                max_passes: 0,
                ..ReinsertConfig::default()
            },
            ReinsertConfig {
                max_depth: MAX_DEPTH + 1,
                ..ReinsertConfig::default()
            },
        ] {
            let mut bvh = built.clone();
            let stats = reinsert(&mut bvh, &Sah, &config);
            assert_eq!(bvh, built, "{config:?}");
            assert_eq!(stats.moved, 0);
            // Zero passes is a valid request for nothing; the rest are refused, and say so.
            assert_eq!(stats.invalid_config, config.max_passes != 0, "{config:?}");
        }
        let mut bvh = built.clone();
        assert!(!reinsert(&mut bvh, &Sah, &ReinsertConfig::default()).invalid_config);
        for n in [0, 1, 2] {
            let tris = &tris[..n];
            let built = Builder::sah().build(tris).unwrap();
            let mut bvh = built.clone();
            reinsert(&mut bvh, &Sah, &ReinsertConfig::default());
            assert_eq!(bvh, built);
        }
    }

    #[test]
    fn every_node_tried_reaches_the_same_answers() {
        // All nodes, many passes: every removal and insertion path, root children included.
        let tris = crate::test_scenes::soup(400, 17, -3.0, 3.0, 3.0);
        let mut bvh = Builder::sah().build(&tris).unwrap();
        let config = ReinsertConfig {
            fraction: 1.0,
            max_passes: 6,
            min_gain: 0.0,
            ..ReinsertConfig::default()
        };
        let stats = reinsert(&mut bvh, &Sah, &config);
        assert!(stats.tried as usize >= bvh.nodes().len() - 1);
        check(&bvh, &tris);
        let mut rng = Pcg32::new(4);
        let mut v = |s: f32| Vec3::new(rng.range(-s, s), rng.range(-s, s), rng.range(-s, s));
        for _ in 0..1000 {
            let Ok(r) = Ray::new(v(8.0), v(1.0)) else {
                continue;
            };
            assert_eq!(
                bvh.closest_hit(&r, &tris),
                brute_force::closest_hit(&r, &tris)
            );
        }
    }

    #[test]
    fn a_tree_past_the_depth_bound_is_not_kept() {
        // A bound below any tree over these triangles.
        let tris = small_among_long();
        let built = Builder::sah().build(&tris).unwrap();
        let mut bvh = built.clone();
        let config = ReinsertConfig {
            max_depth: 4,
            ..ReinsertConfig::default()
        };
        let stats = reinsert(&mut bvh, &Sah, &config);
        assert!(stats.moved > 0 && stats.kept_for_depth, "{stats:?}");
        assert_eq!(stats.inner_after, stats.inner_before);
        assert_eq!(bvh, built);
    }

    #[test]
    fn padding_and_rounding_never_raise_the_cost() {
        // A node's padding is relative to its largest coordinate: one triangle far along x gives
        // the root a padding that its children near the origin lack, so a root refitted to
        // their union would shrink and raise every cost ratio
        // (`fuzz/regressions/build_query/crash-cf4ce86c...`).
        let mut tris = crate::test_scenes::soup(300, 12, -0.5, 0.5, 0.2);
        let x = Vec3::new(300.0, 0.0, 0.0);
        tris.push(Triangle::new(x, x + Vec3::Y * 0.1, x + Vec3::Z * 0.1));
        let built = Builder::sah().build(&tris).unwrap();
        let k = CostConstants::default();
        for fraction in [0.1, 1.0] {
            let mut bvh = built.clone();
            let config = ReinsertConfig {
                fraction,
                max_passes: 4,
                min_gain: 0.0,
                ..ReinsertConfig::default()
            };
            let stats = reinsert(&mut bvh, &Sah, &config);
            check(&bvh, &tris);
            assert_eq!(bvh.bounds(), built.bounds());
            let (before, after) = (built.estimated_cost(&Sah, k), bvh.estimated_cost(&Sah, k));
            assert!(after <= before, "{stats:?}: {before} -> {after}");
        }
    }

    #[test]
    fn candidates_are_the_largest_nodes_in_order() {
        // The order `pick` must give: every node of positive finite measure but the root, by
        // measure descending, ties by index, the first `ceil(fraction * count)`.
        fn reference(measure: &[f32], root: u32, fraction: f32) -> Vec<u32> {
            let mut all: Vec<u32> = (0..measure.len() as u32)
                .filter(|&i| i != root && measure[i as usize] > 0.0)
                .filter(|&i| measure[i as usize].is_finite())
                .collect();
            all.sort_by(|&a, &b| {
                let (ma, mb) = (measure[a as usize], measure[b as usize]);
                mb.total_cmp(&ma).then(a.cmp(&b))
            });
            let keep = libm::ceil(all.len() as f64 * f64::from(fraction)) as usize;
            all.truncate(keep);
            all
        }
        let mut rng = Pcg32::new(9);
        let mut r = Reinserter::new();
        for round in 0..60 {
            let n = [1, 2, 7, 100, 3000][round % 5];
            r.measure = (0..n)
                .map(|k| match (round / 5) % 4 {
                    // Spread over many buckets, with a few repeats.
                    0 => libm::powf(10.0, rng.range(-30.0, 30.0)),
                    // All in one or two buckets: ties and a bucket holding everything.
                    1 => 1.0 + (k % 3) as f32 * f32::EPSILON,
                    2 => [0.0, f32::NAN, f32::INFINITY, 5.0, -1.0, 1e-42][k % 6],
                    _ => rng.range(0.0, 2.0),
                })
                .collect();
            r.root = (round as u32 * 7) % n as u32;
            for fraction in [1e-6, 0.02, 0.3, 1.0] {
                r.pick(fraction);
                let got: Vec<u32> = r.candidates.iter().map(|&c| u32::MAX - c as u32).collect();
                assert_eq!(
                    got,
                    reference(&r.measure, r.root, fraction),
                    "{round} {fraction}"
                );
            }
        }
    }
}
