//! Traversal of a binary BVH: closest hit, any hit and the all-hit cost, each over a fixed stack.

use core::mem::MaybeUninit;

use super::{Bvh, MAX_DEPTH};
use crate::geometry::{pad_far, Ray, Triangle};
use crate::heuristics::CostConstants;

/// The closest intersection along a ray.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Hit {
    /// Ray parameter of the hit.
    pub t: f32,
    /// Id of the triangle hit (its index in the scene's triangle array).
    pub triangle: u32,
    /// Barycentric weight of the triangle's `v1`.
    pub u: f32,
    /// Barycentric weight of the triangle's `v2`.
    pub v: f32,
}

impl Hit {
    /// True when `self` is closer than `other`; equal distances go to the lower triangle id, so
    /// every traversal order (and the brute-force oracle) picks the same triangle.
    #[inline]
    pub fn is_closer_than(&self, other: &Hit) -> bool {
        self.t < other.t || (self.t == other.t && self.triangle < other.triangle)
    }
}

/// What one closest-hit or any-hit query did.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub struct TraversalStats {
    /// Inner nodes visited (each tests both child boxes).
    pub inner_nodes: u32,
    /// Leaves visited.
    pub leaves: u32,
    /// Ray/triangle tests.
    pub triangles: u32,
}

impl TraversalStats {
    /// `C_trav * inner nodes + C_isect * triangles`.
    #[inline]
    pub fn cost(&self, k: CostConstants) -> f32 {
        k.traversal * self.inner_nodes as f32 + k.intersection * self.triangles as f32
    }
}

/// What the all-hit walk touched: every node whose box the ray segment touches, with no early exit.
/// This is what SAH and PAH estimate, and what the thesis called the real cost.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub struct AllHitStats {
    /// Inner nodes whose box the segment touches.
    pub inner_nodes: u32,
    /// Leaves whose box the segment touches.
    pub leaves: u32,
    /// Triangles in those leaves.
    pub triangles: u32,
    /// How many of those triangles the segment hits.
    pub hits: u32,
}

impl AllHitStats {
    /// `C_trav * inner nodes + C_isect * triangles`.
    #[inline]
    pub fn cost(&self, k: CostConstants) -> f32 {
        k.traversal * self.inner_nodes as f32 + k.intersection * self.triangles as f32
    }
}

/// A traversal stack with room for one entry per level plus one, which the builder's depth bound
/// guarantees is enough: every entry is the pending sibling of a node on the current root path,
/// plus at most the one child about to be popped.
const STACK_SIZE: usize = MAX_DEPTH as usize + 1;

/// The stack's storage is left uninitialised: filling a wide traversal's 196 entries cost every ray
/// a 2 KiB `memset` (8% of a camera-ray traversal on Sponza). Entries below `len` are always
/// initialised, since `push` is the only writer and `pop` reads only below `len`.
pub struct Stack<T: Copy, const N: usize = STACK_SIZE> {
    items: [MaybeUninit<T>; N],
    len: usize,
}

impl<T: Copy, const N: usize> Stack<T, N> {
    #[inline]
    pub(crate) fn new() -> Self {
        Self {
            items: [const { MaybeUninit::uninit() }; N],
            len: 0,
        }
    }
    #[inline]
    pub(crate) fn push(&mut self, item: T) {
        // Bounds-checked: a push past N (impossible under the depth bound) panics, never
        // writes out of bounds.
        self.items[self.len].write(item);
        self.len += 1;
    }
    #[inline]
    pub(crate) fn pop(&mut self) -> Option<T> {
        self.len = self.len.checked_sub(1)?;
        // SAFETY: `items[len]` (the new `len`) was written by the `push` that raised `len` above
        // it, and nothing else lowers `len` or writes `items`; `T: Copy`, so reading it out
        // leaves nothing to drop. Every traversal test exercises this path.
        Some(unsafe { self.items[self.len].assume_init() })
    }
}

/// Tests the triangles `ids` and keeps the closest hit in `best` (shared by the binary and wide
/// traversals, so both apply the same tie rule).
#[inline]
pub(crate) fn test_prims(
    ids: &[u32],
    ray: &Ray,
    tris: &[Triangle],
    best: &mut Option<Hit>,
    stats: &mut TraversalStats,
) {
    stats.leaves += 1;
    for &id in ids {
        let Some(tri) = tris.get(id as usize) else {
            continue;
        };
        stats.triangles += 1;
        let t_max = best.map_or(ray.t_max, |h| h.t);
        if let Some(h) = tri.intersect(ray, t_max) {
            let hit = Hit {
                t: h.t,
                triangle: id,
                u: h.u,
                v: h.v,
            };
            if best.is_none_or(|b| hit.is_closer_than(&b)) {
                *best = Some(hit);
            }
        }
    }
}

/// True when one of the triangles `ids` is hit on the segment.
#[inline]
pub(crate) fn any_prim(
    ids: &[u32],
    ray: &Ray,
    tris: &[Triangle],
    stats: &mut TraversalStats,
) -> bool {
    stats.leaves += 1;
    for &id in ids {
        let Some(tri) = tris.get(id as usize) else {
            continue;
        };
        stats.triangles += 1;
        if tri.intersect(ray, ray.t_max).is_some() {
            return true;
        }
    }
    false
}

/// What one traversal of a binary BVH does at its leaves: the one part in which closest hit, any
/// hit and the all-hit walk differ. [`Bvh::traverse`] is the loop they share.
trait LeafQuery {
    /// Visit the nearer child first and skip subtrees that enter beyond [`LeafQuery::t_max`]
    /// (closest hit); unordered queries visit left before right.
    const ORDERED: bool;
    /// Where the segment effectively ends now: child boxes are tested up to here.
    fn t_max(&self) -> f32;
    /// True when a subtree entered at `t_entry` may still hold what the query wants: always,
    /// for a query that does not shorten the segment.
    #[inline(always)]
    fn wants(&self, _t_entry: f32) -> bool {
        true
    }
    /// Tests a leaf's primitives; `true` ends the traversal.
    fn leaf(&mut self, ids: &[u32]) -> bool;
    /// An inner node was visited (both child boxes tested).
    fn inner(&mut self);
}

/// The closest hit so far.
struct Closest<'a> {
    ray: &'a Ray,
    tris: &'a [Triangle],
    best: Option<Hit>,
    stats: &'a mut TraversalStats,
}

impl LeafQuery for Closest<'_> {
    const ORDERED: bool = true;
    #[inline(always)]
    fn t_max(&self) -> f32 {
        self.best.map_or(self.ray.t_max, |h| h.t)
    }
    #[inline(always)]
    fn wants(&self, t_entry: f32) -> bool {
        // The same padded bound the box test used when it admitted the subtree.
        self.best.is_none_or(|b| t_entry <= pad_far(b.t))
    }
    #[inline(always)]
    fn leaf(&mut self, ids: &[u32]) -> bool {
        test_prims(ids, self.ray, self.tris, &mut self.best, self.stats);
        false
    }
    #[inline(always)]
    fn inner(&mut self) {
        self.stats.inner_nodes += 1;
    }
}

/// Any hit: the shadow-ray query, done at the first hit.
struct Any<'a> {
    ray: &'a Ray,
    tris: &'a [Triangle],
    stats: &'a mut TraversalStats,
}

impl LeafQuery for Any<'_> {
    const ORDERED: bool = false;
    #[inline(always)]
    fn t_max(&self) -> f32 {
        self.ray.t_max
    }
    #[inline(always)]
    fn leaf(&mut self, ids: &[u32]) -> bool {
        any_prim(ids, self.ray, self.tris, self.stats)
    }
    #[inline(always)]
    fn inner(&mut self) {
        self.stats.inner_nodes += 1;
    }
}

/// Every node and triangle the segment touches, with no early exit.
struct AllHit<'a> {
    ray: &'a Ray,
    tris: &'a [Triangle],
    stats: AllHitStats,
}

impl LeafQuery for AllHit<'_> {
    const ORDERED: bool = false;
    #[inline(always)]
    fn t_max(&self) -> f32 {
        self.ray.t_max
    }
    #[inline(always)]
    fn leaf(&mut self, ids: &[u32]) -> bool {
        self.stats.leaves += 1;
        for &id in ids {
            self.stats.triangles += 1;
            let hit = self.tris.get(id as usize);
            if hit.is_some_and(|t| t.intersect(self.ray, self.ray.t_max).is_some()) {
                self.stats.hits += 1;
            }
        }
        false
    }
    #[inline(always)]
    fn inner(&mut self) {
        self.stats.inner_nodes += 1;
    }
}

impl Bvh {
    /// The closest hit on `[ray.t_min, ray.t_max]`, or `None`. `tris` are the triangles the BVH
    /// was built over, indexed by primitive id (ids missing from `tris` are skipped).
    #[inline]
    pub fn closest_hit(&self, ray: &Ray, tris: &[Triangle]) -> Option<Hit> {
        self.closest_hit_with_stats(ray, tris, &mut TraversalStats::default())
    }

    /// [`Bvh::closest_hit`], adding what it did to `stats`. Ordered: at each inner node the nearer
    /// child is visited first and the farther one is skipped once a hit closer than its entry is
    /// known.
    pub fn closest_hit_with_stats(
        &self,
        ray: &Ray,
        tris: &[Triangle],
        stats: &mut TraversalStats,
    ) -> Option<Hit> {
        let mut query = Closest {
            ray,
            tris,
            best: None,
            stats,
        };
        self.traverse(ray, &mut query);
        query.best
    }

    /// True when any triangle is hit on `[ray.t_min, ray.t_max]`: the shadow-ray query. Stops at
    /// the first hit found.
    #[inline]
    pub fn any_hit(&self, ray: &Ray, tris: &[Triangle]) -> bool {
        self.any_hit_with_stats(ray, tris, &mut TraversalStats::default())
    }

    /// [`Bvh::any_hit`], adding what it did to `stats`.
    pub fn any_hit_with_stats(
        &self,
        ray: &Ray,
        tris: &[Triangle],
        stats: &mut TraversalStats,
    ) -> bool {
        self.traverse(ray, &mut Any { ray, tris, stats })
    }

    /// The all-hit walk: every node whose box the segment `[ray.t_min, ray.t_max]` touches and
    /// every triangle in those leaves, with no early exit.
    pub fn all_hit(&self, ray: &Ray, tris: &[Triangle]) -> AllHitStats {
        let mut query = AllHit {
            ray,
            tris,
            stats: AllHitStats::default(),
        };
        self.traverse(ray, &mut query);
        query.stats
    }

    /// The one traversal loop: from the root, test both children of each inner node, go on to
    /// one and keep the other on a fixed stack, and hand every leaf reached to `query`. Returns
    /// true when the query ended it early. The loop keeps the node it is in rather than pushing
    /// and popping it.
    #[inline(always)]
    fn traverse<Q: LeafQuery>(&self, ray: &Ray, query: &mut Q) -> bool {
        let Some(root) = self.nodes.first() else {
            return false;
        };
        if root.bounds().intersect(ray, ray.t_max).is_none() {
            return false;
        }
        let mut stack: Stack<(u32, f32)> = Stack::new();
        let mut index = 0u32;
        loop {
            let node = &self.nodes[index as usize];
            if node.is_leaf() {
                let first = node.left_first as usize;
                if query.leaf(&self.prim_indices[first..first + node.count as usize]) {
                    return true;
                }
            } else {
                query.inner();
                let t_max = query.t_max();
                let l = node.left_first;
                let tl = self.nodes[l as usize].bounds().intersect(ray, t_max);
                let tr = self.nodes[l as usize + 1].bounds().intersect(ray, t_max);
                match (tl, tr) {
                    (Some(a), Some(b)) => {
                        let (near, far, t_far) = if !Q::ORDERED || a <= b {
                            (l, l + 1, b)
                        } else {
                            (l + 1, l, a)
                        };
                        stack.push((far, t_far));
                        index = near;
                        continue;
                    }
                    (Some(_), None) => {
                        index = l;
                        continue;
                    }
                    (None, Some(_)) => {
                        index = l + 1;
                        continue;
                    }
                    (None, None) => {}
                }
            }
            // Pop the next subtree that can still hold what the query wants.
            loop {
                let Some((next, t_entry)) = stack.pop() else {
                    return false;
                };
                if query.wants(t_entry) {
                    index = next;
                    break;
                }
            }
        }
    }
}

#[cfg(test)]
mod tests {
    use glam::Vec3;

    use super::*;
    use crate::brute_force;
    use crate::builder::Builder;

    /// The stack's one unsafe read: pops return exactly what was pushed, in reverse, and an
    /// empty stack pops nothing (small enough for Miri, which the test command runs on it).
    #[test]
    fn stack_returns_what_was_pushed() {
        let mut s: Stack<(u32, f32), 4> = Stack::new();
        assert_eq!(s.pop(), None);
        for i in 0..4 {
            s.push((i, i as f32 * 0.5));
        }
        for i in (0..4).rev() {
            assert_eq!(s.pop(), Some((i, i as f32 * 0.5)));
        }
        assert_eq!(s.pop(), None);
        s.push((9, 1.0));
        assert_eq!(s.pop(), Some((9, 1.0)));
    }

    /// Every traversal over a small tree, against brute force: the stacks' whole life cycle.
    #[test]
    fn traversals_of_a_small_tree() {
        let tris = crate::test_scenes::soup(24, 5, 0.0, 4.0, 1.0);
        let bvh = Builder::sah().build(&tris).unwrap();
        let wide = crate::bvh::WideBvh::from_binary(&bvh, &tris);
        for i in 0..16 {
            let o = Vec3::new(-1.0, (i % 4) as f32, (i / 4) as f32);
            let ray = Ray::new(o, Vec3::new(1.0, 0.1, 0.05)).unwrap();
            let expect = brute_force::closest_hit(&ray, &tris);
            assert_eq!(bvh.closest_hit(&ray, &tris), expect);
            assert_eq!(wide.closest_hit(&ray), expect);
            assert_eq!(bvh.any_hit(&ray, &tris), expect.is_some());
            assert_eq!(wide.any_hit(&ray), expect.is_some());
            assert_eq!(
                bvh.all_hit(&ray, &tris).hits,
                brute_force::hit_count(&ray, &tris)
            );
        }
    }

    /// Rays from 1e3 to 1e10 units away, aimed at triangles (in f32 a ray from 1e10 units can
    /// only aim to within about 600 units, so most of those miss): where exact arithmetic on the
    /// rays' own values leaves no hit within 1e-4 of an edge, the closest hit is exact
    /// arithmetic's (to `t`'s resolution), and the binary and the 4-wide tree give brute force's
    /// answer, so their box tests from far origins cull nothing the triangle test, measured from
    /// the ray's anchor there (`Ray::anchor`), hits.
    #[test]
    fn far_rays_answer_as_exact_arithmetic() {
        // Miri runs a small scene and a few rays.
        let n = if cfg!(miri) { 40 } else { 300 };
        let tris = crate::test_scenes::soup(n, 11, -10.0, 10.0, 2.0);
        let bvh = Builder::sah().build(&tris).unwrap();
        let wide = crate::bvh::WideBvh::from_binary(&bvh, &tris);
        let mut rng = crate::random::Pcg32::new(12);
        let (mut hits, mut decided) = (0, 0);
        let rays = if cfg!(miri) { 8 } else { 800 };
        for i in 0..rays {
            let aim = tris[i % tris.len()].centroid();
            let w = Vec3::new(
                rng.range(-1.0, 1.0),
                rng.range(-1.0, 1.0),
                rng.range(-1.0, 1.0),
            );
            let distance = [1e3f32, 1e5, 1e8, 1e10][i % 4];
            let origin = aim + w.normalize_or(Vec3::Y) * distance;
            let Ok(ray) = Ray::new(origin, aim - origin) else {
                continue;
            };
            let expect = brute_force::closest_hit(&ray, &tris);
            assert_eq!(bvh.closest_hit(&ray, &tris), expect, "{ray:?}");
            assert_eq!(wide.closest_hit(&ray), expect, "{ray:?}");
            assert_eq!(bvh.any_hit(&ray, &tris), expect.is_some());
            assert_eq!(wide.any_hit(&ray), expect.is_some());
            // Exact arithmetic's closest hit, unless some triangle's decision is too close to call.
            let mut exact: Option<(f64, usize)> = None;
            let mut close_call = false;
            for (k, tri) in tris.iter().enumerate() {
                let n = (tri.v1 - tri.v0).cross(tri.v2 - tri.v0);
                if n.length() < 1e-2 || n.normalize().dot(ray.dir.normalize()).abs() < 0.05 {
                    // Slivers and grazing rays are the noise check's business.
                    close_call |=
                        brute_force::closest_hit(&ray, core::slice::from_ref(tri)).is_some();
                    continue;
                }
                let (t, u, v) = crate::test_scenes::exact_intersection(tri, &ray);
                close_call |= t > 0.0 && [u, v, 1.0 - u - v].iter().any(|x| x.abs() < 1e-4);
                if t > 0.0 && u > 0.0 && v > 0.0 && u + v < 1.0 && exact.is_none_or(|(b, _)| t < b)
                {
                    exact = Some((t, k));
                }
            }
            if close_call {
                continue;
            }
            decided += 1;
            assert_eq!(expect.is_some(), exact.is_some(), "{ray:?}: {expect:?}");
            if let (Some(h), Some((t, _))) = (expect, exact) {
                // Closest to `t`'s own resolution: from 1e10 units one ulp of `t` is 600 units,
                // and triangles closer together than that along the ray tie (lower id wins).
                assert!((f64::from(h.t) - t).abs() <= 4.0 * f64::EPSILON.max(t * 2f64.powi(-23)));
                hits += 1;
            }
        }
        assert!(
            decided > rays / 2 && hits > rays / 8,
            "{decided} decided, {hits} hits"
        );
    }
}
