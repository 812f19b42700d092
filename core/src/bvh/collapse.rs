//! Where a binary BVH's nodes go in its 4-wide collapse: the slots of every wide node chosen by
//! dynamic programming over the binary tree to minimise the wide tree's SAH cost (the scheme of
//! Ylitie, Karras and Laine, "Efficient incoherent ray traversal on GPUs through compressed wide
//! BVHs", HPG 2017, for four slots and leaves of one or two [`crate::geometry::Triangle4`]
//! blocks).
//!
//! A wide node standing for binary node `n` tests four boxes, at cost [`C_NODE`] per ray that
//! enters `n`; a leaf tests its blocks, [`C_BLOCK`] each, per ray that enters its box. Rays enter
//! a box with probability proportional to its surface area, so the wide tree's cost is the sum of
//! `area x cost` over its nodes and leaves, and the cheapest tree is found bottom-up: for each
//! binary node `n` and each `i` in 1..=4, the cheapest way to put `n`'s subtree in at most `i`
//! slots of the wide node above it.

use alloc::vec::Vec;

use super::{Bvh, MAX_DEPTH};

/// Relative cost of a wide node's 4-wide box test, per ray that enters the node.
const C_NODE: f32 = 1.0;

/// Relative cost of one 4-triangle block test, per ray that enters the leaf. By instructions a
/// block test costs about three node tests (callgrind: 140 against 50), but both mostly wait on
/// memory (160 and 128 bytes per block or node). Against the greedy collapse this replaced
/// (callgrind, `profile_traverse`, instructions per pass; bunny and Crytek Sponza, camera and
/// random rays), 1.0 lowers all four by 3.5-5.5% with about as many nodes; 2.0 lowers them by
/// 4.5-11% but makes 13-25% more nodes, and timed, its random rays were no faster; 0.7 makes
/// fewer nodes and keeps less of the gain. `benches/RESULTS.md` has the numbers.
const C_BLOCK: f32 = 1.0;

/// Largest binary subtree the collapse may turn into one leaf (two blocks). A binary subtree of at
/// most [`super::WideBvh::ONE_BLOCK`] triangles is always one leaf (so a build that does not split
/// such nodes collapses to the same wide nodes); one of five to eight becomes a leaf when that is
/// cheaper than opening it.
pub(crate) const LEAF_BLOCK: usize = 8;

/// Subtree sizes saturate here: "more than a leaf's two blocks".
const MORE: u8 = LEAF_BLOCK as u8 + 1;

/// The choices for one binary node, for a wide node of `W` slots.
#[derive(Clone, Copy, Debug)]
struct Choice<const W: usize> {
    /// In one slot, the node is a wide leaf (else a wide node of its own).
    leaf: bool,
    /// For `i` = 2 to `W` slots (index `i - 2`): the node takes one slot (else its children
    /// share the `i`).
    single: [bool; W],
    /// For `j` = 2 to `W` slots shared by the children (index `j - 2`): how many the left takes.
    left: [u8; W],
}

/// The collapse's decisions for every node of a binary BVH.
pub(crate) struct CollapsePlan<const W: usize> {
    choice: Vec<Choice<W>>,
    /// The binary root is a leaf or holds at most [`super::WideBvh::ONE_BLOCK`] triangles.
    root_forced: bool,
}

impl<const W: usize> CollapsePlan<W> {
    /// Prices every node of `bvh` (a valid tree with at least one node) in one post-order pass.
    pub(crate) fn new(bvh: &Bvh) -> Self {
        let n = bvh.nodes.len();
        let unset = Choice {
            leaf: false,
            single: [false; W],
            left: [0; W],
        };
        let mut choice = alloc::vec![unset; n];
        let mut size = alloc::vec![0u8; n];
        // cost[b][i - 1]: the cheapest cost of binary subtree `b` in at most `i` slots.
        let mut cost = alloc::vec![[0f32; W]; n];
        // (node, whether its children are done); a valid tree's depth bounds the stack.
        let mut stack: Vec<(u32, bool)> = Vec::with_capacity(2 * MAX_DEPTH as usize + 2);
        stack.push((0, false));
        while let Some((b, done)) = stack.pop() {
            let node = &bvh.nodes[b as usize];
            if node.is_leaf() {
                let area = node.bounds().half_area();
                // A binary leaf is a wide leaf, in as many blocks as it needs.
                size[b as usize] = node.count.min(u32::from(MORE)) as u8;
                cost[b as usize] = [area * C_BLOCK * node.count.div_ceil(4) as f32; W];
                choice[b as usize] = Choice {
                    leaf: true,
                    single: [true; W],
                    left: [1; W],
                };
                continue;
            }
            let l = node.left_first as usize;
            if !done {
                stack.push((b, true));
                stack.push((l as u32 + 1, false));
                stack.push((l as u32, false));
                continue;
            }
            let area = node.bounds().half_area();
            let s = (size[l] + size[l + 1]).min(MORE);
            size[b as usize] = s;
            // shared[j - 2]: the children's cheapest split of `j` slots, and the left's share.
            let mut shared = [(f32::INFINITY, 1u8); W];
            for (j, best) in (2..=W).zip(&mut shared) {
                for k in 1..j {
                    let c = cost[l][k - 1] + cost[l + 1][j - k - 1];
                    if c < best.0 {
                        *best = (c, k as u8);
                    }
                }
            }
            // At most four triangles: always one leaf (see `LEAF_BLOCK`).
            let forced = u32::from(s) <= super::WideBvh::ONE_BLOCK;
            let leaf_cost = area * C_BLOCK * u32::from(s).div_ceil(4) as f32;
            let node_cost = area * C_NODE + shared[W - 2].0;
            // Ties go to the leaf and to one slot: fewer nodes. (Boxes of a valid tree are
            // finite, so costs are never NaN; an overflow to infinity ties too.)
            let leaf = forced || (usize::from(s) <= LEAF_BLOCK && leaf_cost <= node_cost);
            let one = if leaf { leaf_cost } else { node_cost };
            let mut c = [one; W];
            let mut single = [true; W];
            if !forced {
                for (j, &(shared_cost, _)) in shared[..W - 1].iter().enumerate() {
                    if shared_cost < one {
                        c[j + 1] = shared_cost;
                        single[j] = false;
                    }
                }
            }
            cost[b as usize] = c;
            choice[b as usize] = Choice {
                leaf,
                single,
                left: shared.map(|(_, k)| k),
            };
        }
        let root_forced = bvh.nodes[0].is_leaf() || u32::from(size[0]) <= super::WideBvh::ONE_BLOCK;
        Self {
            choice,
            root_forced,
        }
    }

    /// True when the binary root becomes the wide root's only child, a leaf: when it is a binary
    /// leaf or holds at most [`super::WideBvh::ONE_BLOCK`] triangles. A root of five to eight
    /// opens, whatever it would cost as a leaf in a slot: the wide root is entered anyway, and
    /// its children's leaves cost at most the two blocks of one leaf over the root's box.
    pub(crate) fn root_is_leaf(&self) -> bool {
        self.root_forced
    }

    /// The slots of the wide node standing for binary inner node `b` (one that is not a leaf):
    /// the binary nodes they hold, in left-to-right order, with whether each is a wide leaf.
    /// Returns how many of `slots` it filled (two to `W`).
    pub(crate) fn slots(&self, bvh: &Bvh, b: u32, slots: &mut [(u32, bool); W]) -> usize {
        let mut n = 0;
        let l = bvh.nodes[b as usize].left_first;
        let k = self.choice[b as usize].left[W - 2];
        self.gather(bvh, l, usize::from(k), slots, &mut n);
        self.gather(bvh, l + 1, W - usize::from(k), slots, &mut n);
        n
    }

    /// Appends the slots binary node `b` takes when given at most `i` of them.
    fn gather(&self, bvh: &Bvh, b: u32, i: usize, slots: &mut [(u32, bool); W], n: &mut usize) {
        let choice = &self.choice[b as usize];
        if i == 1 || choice.single[i - 2] {
            slots[*n] = (b, choice.leaf);
            *n += 1;
            return;
        }
        // `i` is at most `W` and each share at least one less, so this recursion is shallow.
        let l = bvh.nodes[b as usize].left_first;
        let k = usize::from(choice.left[i - 2]);
        self.gather(bvh, l, k, slots, n);
        self.gather(bvh, l + 1, i - k, slots, n);
    }
}

#[cfg(test)]
mod tests {
    use alloc::vec::Vec;

    use super::*;
    use crate::builder::Builder;
    use crate::bvh::{WideBvh, WideNode};
    use crate::geometry::Triangle;
    use crate::heuristics::LeafSize;
    use crate::test_scenes::soup;

    /// The SAH cost of a wide tree as built: every wide node's box times [`C_NODE`], every leaf's
    /// box times its blocks times [`C_BLOCK`].
    fn wide_cost(wide: &WideBvh) -> f32 {
        let mut cost = wide.bounds().half_area() * C_NODE;
        for node in wide.nodes() {
            for slot in 0..4 {
                if node.child[slot] == WideNode::EMPTY {
                    continue;
                }
                let area = node.child_bounds(slot).half_area();
                cost += match node.count[slot] {
                    0 => area * C_NODE,
                    n => area * C_BLOCK * n.div_ceil(4) as f32,
                };
            }
        }
        cost
    }

    /// Subtree sizes, exactly.
    fn sizes(bvh: &Bvh, b: u32) -> u32 {
        let node = &bvh.nodes[b as usize];
        if node.is_leaf() {
            node.count
        } else {
            sizes(bvh, node.left_first) + sizes(bvh, node.left_first + 1)
        }
    }

    /// The cheapest cost of binary inner node `b` as a wide node, by brute force: every frontier
    /// of two to four descendants reached by opening nodes one at a time, each descendant priced
    /// as a leaf (when it may be one) or, recursively, as a wide node of its own.
    fn brute_node(bvh: &Bvh, b: u32) -> f32 {
        let area = |b: u32| bvh.nodes[b as usize].bounds().half_area();
        let l = bvh.nodes[b as usize].left_first;
        let mut best = f32::INFINITY;
        let mut frontiers: Vec<Vec<u32>> = alloc::vec![alloc::vec![l, l + 1]];
        while let Some(f) = frontiers.pop() {
            best = best.min(f.iter().map(|&c| brute_slot(bvh, c)).sum());
            if f.len() < 4 {
                for (i, &c) in f.iter().enumerate() {
                    if !forced_leaf(bvh, c) {
                        let cl = bvh.nodes[c as usize].left_first;
                        let mut g = f.clone();
                        g[i] = cl;
                        g.insert(i + 1, cl + 1);
                        frontiers.push(g);
                    }
                }
            }
        }
        area(b) * C_NODE + best
    }

    fn forced_leaf(bvh: &Bvh, b: u32) -> bool {
        bvh.nodes[b as usize].is_leaf() || sizes(bvh, b) <= WideBvh::ONE_BLOCK
    }

    /// The cheapest cost of binary node `b` in one slot.
    fn brute_slot(bvh: &Bvh, b: u32) -> f32 {
        let area = bvh.nodes[b as usize].bounds().half_area();
        let n = sizes(bvh, b);
        let leaf = area * C_BLOCK * n.div_ceil(4) as f32;
        if forced_leaf(bvh, b) {
            leaf
        } else if n as usize <= LEAF_BLOCK {
            leaf.min(brute_node(bvh, b))
        } else {
            brute_node(bvh, b)
        }
    }

    /// The collapse builds the cheapest wide tree there is: its cost equals the minimum over
    /// every wide tree the binary tree allows, found by enumerating them. Soups of several
    /// sizes, spreads (long triangles make subtrees whose children overlap, where a leaf can
    /// beat opening) and binary leaf sizes.
    #[test]
    fn the_collapse_is_the_cheapest_wide_tree() {
        let mut checked = 0;
        for (n, seed) in [(5, 1), (8, 2), (9, 3), (13, 4), (21, 5), (34, 6), (60, 7)] {
            for spread in [0.3, 4.0, 20.0] {
                let tris = soup(n, seed, -10.0, 10.0, spread);
                for max_leaf in [1, 2, 4] {
                    let bvh = Builder::sah()
                        .with_termination(LeafSize { max_leaf })
                        .build(&tris)
                        .unwrap();
                    let wide = WideBvh::from_binary(&bvh, &tris);
                    let root = if forced_leaf(&bvh, 0) {
                        bvh.bounds().half_area() * C_NODE + brute_slot(&bvh, 0)
                    } else {
                        brute_node(&bvh, 0)
                    };
                    let cost = wide_cost(&wide);
                    assert!(
                        (cost - root).abs() <= 1e-5 * root,
                        "{n} triangles, spread {spread}, leaves of {max_leaf}: {cost} against {root}"
                    );
                    checked += 1;
                }
            }
        }
        assert_eq!(checked, 63);
    }

    /// Identical degenerate triangles (one point, boxes only the build's padding wide) make
    /// every box the same and leave the choices tied: still a valid tree that holds every
    /// triangle once.
    #[test]
    fn ties_give_a_valid_tree() {
        let p = glam::Vec3::new(1.0, 2.0, 3.0);
        for n in [1, 4, 5, 9, 40] {
            let tris: Vec<Triangle> = (0..n).map(|_| Triangle::new(p, p, p)).collect();
            let bvh = Builder::sah()
                .with_termination(LeafSize { max_leaf: 1 })
                .build(&tris)
                .unwrap();
            let wide = WideBvh::from_binary(&bvh, &tris);
            let mut ids: Vec<u32> = Vec::new();
            for node in wide.nodes() {
                assert!(node.arity() >= 1);
                for slot in 0..4 {
                    let (first, count) = (node.child[slot] as usize, node.count[slot] as usize);
                    if count > 0 {
                        let blocks = &wide.triangles()[first..first + count.div_ceil(4)];
                        ids.extend(blocks.iter().flat_map(|b| b.id).take(count));
                        assert!(node.child_bounds(slot).contains_point(p));
                    }
                }
            }
            ids.sort_unstable();
            assert_eq!(ids, (0..n).collect::<Vec<u32>>());
            assert!(wide.max_depth() <= bvh.max_depth());
        }
    }
}
