//! Traversal of 4-wide BVHs: one loop ([`super::WideBvh::traverse`]) with one 4-wide slab test per node,
//! and a leaf callback ([`LeafVisitor`]) that makes it closest hit, any hit or the all-hit count.

use core::mem::MaybeUninit;
use core::ops::{Add, Mul, Sub};

use wide::{f32x4, f32x8};

use super::wide::{WideBvhN, WideNodeN};
use super::{AllHitStats, Hit, TraversalStats, MAX_DEPTH};
use crate::geometry::{pad_far, Ray, RayTri4, Triangle4, TriangleEdges};

/// The pending entries of a `W`-wide traversal: each visited node pops one entry and pushes at
/// most `W`, so they grow by at most `W - 1` per level of the (at most [`MAX_DEPTH`] deep) tree.
pub(crate) const fn wide_stack(w: usize) -> usize {
    (w - 1) * MAX_DEPTH as usize + w
}

/// The storage of a traversal's pending entries, sized per width ([`Lanes::Pending`]), left
/// uninitialised (only the used part is ever written). The walk counts the entries in a local of
/// its own: a count in one struct with the dynamically indexed array stayed in
/// memory, a store and a reload on every push and pop.
pub trait Pending {
    /// Empty storage.
    fn new() -> Self;
    /// Writes `entry` to slot `i` (panics past the depth bound's size, which a valid tree never
    /// reaches).
    fn put(&mut self, i: usize, entry: Entry);
    /// The entry in slot `i`.
    ///
    /// # Safety
    ///
    /// Slot `i` was written by [`Pending::put`].
    unsafe fn get(&self, i: usize) -> Entry;
}

/// Storage for `N` pending entries.
pub struct PendingArray<const N: usize>([MaybeUninit<Entry>; N]);

impl<const N: usize> Pending for PendingArray<N> {
    #[inline(always)]
    fn new() -> Self {
        Self([const { MaybeUninit::uninit() }; N])
    }
    #[inline(always)]
    fn put(&mut self, i: usize, entry: Entry) {
        // Bounds-checked: never writes out of bounds.
        self.0[i].write(entry);
    }
    #[inline(always)]
    unsafe fn get(&self, i: usize) -> Entry {
        // SAFETY: the caller says slot `i` was written; `Entry: Copy`, nothing to drop.
        unsafe { self.0.get_unchecked(i).assume_init() }
    }
}

/// A stack over [`Pending`] storage with its count beside it: the walk's pending subtrees.
struct PendingStack<'a, P> {
    items: &'a mut P,
    len: usize,
}

impl<P: Pending> PendingStack<'_, P> {
    #[inline(always)]
    fn push(&mut self, entry: Entry) {
        self.items.put(self.len, entry);
        self.len += 1;
    }
    #[inline(always)]
    fn pop(&mut self) -> Option<Entry> {
        self.len = self.len.checked_sub(1)?;
        // SAFETY: slot `len` (the new `len`) was written by the push that raised `len` above it;
        // only `push` writes and only `pop` lowers `len`.
        Some(unsafe { self.items.get(self.len) })
    }
}

/// The slab test's relative padding (see `Aabb::slab_interval`), as a vector.
const PAD: f32 = 2.0 * (3.0 * f32::EPSILON * 0.5) / (1.0 - 3.0 * f32::EPSILON * 0.5);

/// The SIMD vector of a node's `W` child lanes: what the slab test needs of it.
pub trait ChildLanes<const W: usize>:
    Copy + Add<Output = Self> + Sub<Output = Self> + Mul<Output = Self>
{
    /// Every lane `v`.
    fn splat(v: f32) -> Self;
    /// The lanes of one row of a node.
    fn load(row: [f32; W]) -> Self;
    /// `max(self, t)` per lane, keeping `self` where `t` is NaN.
    fn keep_max(self, t: Self) -> Self;
    /// `min(self, t)` per lane, keeping `self` where `t` is NaN.
    fn keep_min(self, t: Self) -> Self;
    /// `|self|` per lane.
    fn abs(self) -> Self;
    /// Bit `i` set when lane `i` of `self` is at most that of `other` (false for NaN).
    fn le_bitmask(self, other: Self) -> u32;
    /// The lanes.
    fn to_array(self) -> [f32; W];
}

impl ChildLanes<4> for f32x4 {
    #[inline(always)]
    fn splat(v: f32) -> Self {
        f32x4::splat(v)
    }
    #[inline(always)]
    fn load(row: [f32; 4]) -> Self {
        f32x4::from(row)
    }
    #[inline(always)]
    fn keep_max(self, t: Self) -> Self {
        keep_max(self, t)
    }
    #[inline(always)]
    fn keep_min(self, t: Self) -> Self {
        keep_min(self, t)
    }
    #[inline(always)]
    fn abs(self) -> Self {
        f32x4::abs(self)
    }
    #[inline(always)]
    fn le_bitmask(self, other: Self) -> u32 {
        self.simd_le(other).to_bitmask()
    }
    #[inline(always)]
    fn to_array(self) -> [f32; 4] {
        f32x4::to_array(self)
    }
}

/// With AVX one 8-lane instruction per step, else two 4-lane halves (`wide` picks at compile
/// time); `fast_max`/`fast_min` keep the accumulator on NaN either way (`maxps`, `vmaxps` and the
/// halves' `keep_max` all return their second operand then).
impl ChildLanes<8> for f32x8 {
    #[inline(always)]
    fn splat(v: f32) -> Self {
        f32x8::splat(v)
    }
    #[inline(always)]
    fn load(row: [f32; 8]) -> Self {
        f32x8::from(row)
    }
    #[inline(always)]
    fn keep_max(self, t: Self) -> Self {
        #[cfg(target_feature = "sse")]
        {
            t.fast_max(self)
        }
        #[cfg(not(target_feature = "sse"))]
        {
            self.max(t)
        }
    }
    #[inline(always)]
    fn keep_min(self, t: Self) -> Self {
        #[cfg(target_feature = "sse")]
        {
            t.fast_min(self)
        }
        #[cfg(not(target_feature = "sse"))]
        {
            self.min(t)
        }
    }
    #[inline(always)]
    fn abs(self) -> Self {
        f32x8::abs(self)
    }
    #[inline(always)]
    fn le_bitmask(self, other: Self) -> u32 {
        self.simd_le(other).to_bitmask()
    }
    #[inline(always)]
    fn to_array(self) -> [f32; 8] {
        f32x8::to_array(self)
    }
}

/// A node width with a SIMD vector for its lanes: 4 (`f32x4`) and 8 (`f32x8`).
pub struct Width<const W: usize>;

/// The vector type of width `W` ([`Width`]), and the stack its traversal needs.
pub trait Lanes<const W: usize> {
    /// One lane per child.
    type V: ChildLanes<W>;
    /// The pending entries (left uninitialised: only the used part is ever written).
    #[doc(hidden)]
    type Pending: Pending;
}

impl Lanes<4> for Width<4> {
    type V = f32x4;
    type Pending = PendingArray<{ wide_stack(4) }>;
}

impl Lanes<8> for Width<8> {
    type V = f32x8;
    type Pending = PendingArray<{ wide_stack(8) }>;
}

/// A ray prepared for `W`-wide box tests, once per query: splatted origin and inverse direction,
/// and per axis the row of the node's bounds (see [`planes`]) holding the near and the far
/// planes, chosen from the direction's signs.
struct RayN<V> {
    origin: [V; 3],
    inv: [V; 3],
    near: [usize; 3],
    far: [usize; 3],
    t_min: V,
    /// `t_min >= 0`, as for nearly every ray: every entry distance is then at least zero, and
    /// the padding one product each way (see [`RayN::intersect`]).
    forward: bool,
}

/// A node's bounds as rows: `min` of axes 0 to 2, then `max` of axes 0 to 2 (then `child` and
/// `count`, which the slab test never reads).
#[inline(always)]
fn planes<const W: usize>(node: &WideNodeN<W>) -> &[[f32; W]; 8] {
    // SAFETY: `WideNodeN` is `repr(C)`: eight arrays of `W` four-byte values, `32 W` bytes with
    // no padding (see its `Pod` impls), so it is eight rows of `W` floats; every bit pattern is
    // a valid `f32`, and the borrow lives as long as the node's.
    unsafe { &*(node as *const WideNodeN<W>).cast::<[[f32; W]; 8]>() }
}

impl<V> RayN<V> {
    #[inline(always)]
    fn new<const W: usize>(ray: &Ray) -> Self
    where
        V: ChildLanes<W>,
    {
        let s = |v: f32| V::splat(v);
        Self {
            origin: [s(ray.origin.x), s(ray.origin.y), s(ray.origin.z)],
            inv: [s(ray.inv_dir.x), s(ray.inv_dir.y), s(ray.inv_dir.z)],
            near: core::array::from_fn(|k| if ray.inv_dir[k] >= 0.0 { k } else { k + 3 }),
            far: core::array::from_fn(|k| if ray.inv_dir[k] >= 0.0 { k + 3 } else { k }),
            t_min: s(ray.t_min),
            forward: ray.t_min >= 0.0,
        }
    }

    /// Entry distances of the children and the bitmask of those the segment up to `t_max`
    /// touches. The slab values and their reduction are the scalar `Aabb::slab_interval`'s: the
    /// reduction keeps its accumulator where a slab value is NaN (a zero direction component
    /// with the origin on a slab plane). The interval is padded after Ize by the same relative
    /// margin, but for a segment with `t_min >= 0` as Ize writes it, `t_near (1 - pad)` and
    /// `t_far (1 + pad)`: one multiply each instead of an absolute value, a multiply and an add,
    /// on the path from a node's load to the next node's address (up to 4% faster; see
    /// `benches/RESULTS.md`). `t_near` is then at least zero, so the product shrinks it as the
    /// general form does; a negative `t_far` stays below it either way, so the box is missed
    /// either way.
    #[inline(always)]
    fn intersect<const W: usize>(&self, node: &WideNodeN<W>, t_max: f32) -> (V, u32)
    where
        V: ChildLanes<W>,
    {
        let mut t_near = self.t_min;
        let mut t_far = V::splat(t_max);
        let rows = planes(node);
        for k in 0..3 {
            // Rows are below 6; the mask only spares the bounds check.
            let (near, far) = (rows[self.near[k] & 7], rows[self.far[k] & 7]);
            t_near = t_near.keep_max((V::load(near) - self.origin[k]) * self.inv[k]);
            t_far = t_far.keep_min((V::load(far) - self.origin[k]) * self.inv[k]);
        }
        let (t_near, t_far) = if self.forward {
            (t_near * V::splat(1.0 - PAD), t_far * V::splat(1.0 + PAD))
        } else {
            let pad = V::splat(PAD);
            (t_near - t_near.abs() * pad, t_far + t_far.abs() * pad)
        };
        (t_near, t_near.le_bitmask(t_far))
    }
}

/// `max(acc, t)` per lane, keeping `acc` where `t` is NaN. With SSE, `maxps(t, acc)` returns its
/// second operand when either is NaN: one instruction. Elsewhere `wide`'s NaN-ignoring `max`.
#[inline(always)]
fn keep_max(acc: f32x4, t: f32x4) -> f32x4 {
    #[cfg(target_feature = "sse")]
    {
        t.fast_max(acc)
    }
    #[cfg(not(target_feature = "sse"))]
    {
        acc.max(t)
    }
}

/// `min(acc, t)` per lane, keeping `acc` where `t` is NaN (see [`keep_max`]).
#[inline(always)]
fn keep_min(acc: f32x4, t: f32x4) -> f32x4 {
    #[cfg(target_feature = "sse")]
    {
        t.fast_min(acc)
    }
    #[cfg(not(target_feature = "sse"))]
    {
        acc.min(t)
    }
}

/// A pending child: node index or first triangle block, triangle count (0 for a node), entry
/// distance (kept only by ordered traversals).
pub type Entry = (u32, u32, f32);

/// What a traversal counts: [`TraversalStats`] for the `_with_stats` queries, nothing at all for
/// the plain ones, whose loops then carry no counter updates.
pub(crate) trait Counters {
    fn node(&mut self);
    fn leaf(&mut self, triangles: u32);
}

impl Counters for TraversalStats {
    #[inline(always)]
    fn node(&mut self) {
        self.inner_nodes += 1;
    }
    #[inline(always)]
    fn leaf(&mut self, triangles: u32) {
        self.leaves += 1;
        self.triangles += triangles;
    }
}

impl Counters for () {
    #[inline(always)]
    fn node(&mut self) {}
    #[inline(always)]
    fn leaf(&mut self, _: u32) {}
}

/// The leaf callback of the one 4-wide traversal ([`super::WideBvh::traverse`]): closest hit, any hit
/// and the all-hit count are each a visitor over the same loop, which is monomorphised per
/// visitor, so each query compiles to its own loop with nothing of the others in it.
pub trait LeafVisitor {
    /// True: children are visited nearest first and a pending subtree is dropped once it starts
    /// beyond [`LeafVisitor::t_max`] (closest hit). False: children in slot order, no distances
    /// kept (queries whose segment never shortens).
    const ORDERED: bool;

    /// The end of the segment still searched: the closest hit so far for a closest-hit query,
    /// the ray's `t_max` otherwise. Nodes and pending subtrees beyond it are skipped.
    fn t_max(&self) -> f32;

    /// Visits one leaf: `count` triangles in `blocks` (`ceil(count / 4)` blocks, unused lanes
    /// after the last). Returns true to end the traversal (an any-hit query's first hit).
    fn leaf(&mut self, blocks: &[Triangle4], count: u32) -> bool;
}

/// Closest hit: keeps the closest hit under [`Hit::is_closer_than`] and shortens the segment to it.
pub struct ClosestHit {
    ray: RayTri4,
    /// The closest hit so far.
    pub best: Option<Hit>,
    t_max: f32,
}

impl ClosestHit {
    /// A query along `ray`, nothing hit yet.
    #[inline(always)]
    pub fn new(ray: &Ray) -> Self {
        Self {
            ray: RayTri4::new(ray),
            best: None,
            t_max: ray.t_max,
        }
    }
}

impl LeafVisitor for ClosestHit {
    const ORDERED: bool = true;

    #[inline(always)]
    fn t_max(&self) -> f32 {
        self.t_max
    }

    /// Every lane hit in a block lies within the segment as it was before the block, so the
    /// closest of them under the tie rule, compared with `best`, is what the scalar loop (which
    /// shortens the segment after each hit) finds.
    #[inline(always)]
    fn leaf(&mut self, blocks: &[Triangle4], _count: u32) -> bool {
        for block in blocks {
            self.take(block);
        }
        false
    }
}

impl ClosestHit {
    /// Tests `block` and keeps the closest of its hits under the tie rule; returns the lane that
    /// became the closest hit last, if any did.
    #[inline(always)]
    fn take(&mut self, block: &Triangle4) -> Option<usize> {
        let h = block.intersect(&self.ray, self.t_max);
        let mut m = h.mask;
        let mut taken = None;
        while m != 0 {
            let j = m.trailing_zeros() as usize;
            m &= m - 1;
            let hit = Hit {
                t: h.t[j],
                triangle: block.id[j],
                u: h.u[j],
                v: h.v[j],
            };
            if self.best.is_none_or(|b| hit.is_closer_than(&b)) {
                self.best = Some(hit);
                self.t_max = hit.t;
                taken = Some(j);
            }
        }
        taken
    }
}

/// Closest hit that also keeps the hit triangle's first vertex and edges from its leaf block
/// ([`TriangleEdges`]), for a renderer that shades the hit: the block was just read, the scene's
/// triangle array usually was not.
pub struct ClosestHitEdges {
    closest: ClosestHit,
    /// The closest hit so far and its triangle.
    pub best: Option<(Hit, TriangleEdges)>,
}

impl ClosestHitEdges {
    /// A query along `ray`, nothing hit yet.
    #[inline(always)]
    pub fn new(ray: &Ray) -> Self {
        Self {
            closest: ClosestHit::new(ray),
            best: None,
        }
    }
}

impl LeafVisitor for ClosestHitEdges {
    const ORDERED: bool = true;

    #[inline(always)]
    fn t_max(&self) -> f32 {
        self.closest.t_max
    }

    #[inline(always)]
    fn leaf(&mut self, blocks: &[Triangle4], _count: u32) -> bool {
        for block in blocks {
            // `take` returns a lane only when it set `best`.
            if let (Some(j), Some(hit)) = (self.closest.take(block), self.closest.best) {
                self.best = Some((hit, block.edges(j)));
            }
        }
        false
    }
}

/// Any hit: ends the traversal at the first triangle hit on the segment.
pub struct AnyHit {
    ray: RayTri4,
    t_max: f32,
}

impl AnyHit {
    /// A query along `ray`.
    #[inline(always)]
    pub fn new(ray: &Ray) -> Self {
        Self {
            ray: RayTri4::new(ray),
            t_max: ray.t_max,
        }
    }
}

impl LeafVisitor for AnyHit {
    const ORDERED: bool = false;

    #[inline(always)]
    fn t_max(&self) -> f32 {
        self.t_max
    }

    #[inline(always)]
    fn leaf(&mut self, blocks: &[Triangle4], _count: u32) -> bool {
        // A plain loop: `Iterator::any` here was left out of line.
        for block in blocks {
            if block.any_hit(&self.ray, self.t_max) {
                return true;
            }
        }
        false
    }
}

/// The all-hit count: every triangle hit on the segment, no early exit and no pruning.
pub struct HitCount {
    ray: RayTri4,
    t_max: f32,
    /// Triangles hit so far.
    pub hits: u32,
}

impl HitCount {
    /// A count along `ray`, at zero.
    #[inline(always)]
    pub fn new(ray: &Ray) -> Self {
        Self {
            ray: RayTri4::new(ray),
            t_max: ray.t_max,
            hits: 0,
        }
    }
}

impl LeafVisitor for HitCount {
    const ORDERED: bool = false;

    #[inline(always)]
    fn t_max(&self) -> f32 {
        self.t_max
    }

    #[inline(always)]
    fn leaf(&mut self, blocks: &[Triangle4], _count: u32) -> bool {
        for block in blocks {
            self.hits += block.intersect(&self.ray, self.t_max).mask.count_ones();
        }
        false
    }
}

impl<const W: usize> WideBvhN<W>
where
    Width<W>: Lanes<W>,
{
    /// The one wide traversal: every node whose box the segment up to `visitor.t_max()` touches,
    /// nearest first when the visitor is ordered, with `visitor` called at each leaf until it
    /// returns true (then this returns true). Closest hit, any hit and the all-hit count are
    /// visitors over it; so can a caller's own leaf test be. With the `std` feature, an 8-wide
    /// tree runs the loop, the visitor inlined into it, compiled for AVX2 where the CPU has it
    /// ([`crate::bvh::simd_level`]).
    pub fn traverse<V: LeafVisitor>(&self, ray: &Ray, visitor: &mut V) -> bool {
        if self.nodes.is_empty() || self.misses_root(ray) {
            return false;
        }
        self.walk_dispatched(ray, visitor, &mut ())
    }

    /// [`super::WideBvh::traverse`], adding what it did to `stats` (see
    /// [`super::WideBvh::closest_hit_with_stats`] for what counts).
    pub fn traverse_with_stats<V: LeafVisitor>(
        &self,
        ray: &Ray,
        visitor: &mut V,
        stats: &mut TraversalStats,
    ) -> bool {
        if self.nodes.is_empty() || self.misses_root(ray) {
            return false;
        }
        self.walk_dispatched(ray, visitor, stats)
    }

    /// [`WideBvhN::walk`] from the root, through the AVX2 entry point where the CPU has it
    /// ([`super::dispatch`]).
    #[inline(always)]
    fn walk_dispatched<V: LeafVisitor>(
        &self,
        ray: &Ray,
        visitor: &mut V,
        stats: &mut impl Counters,
    ) -> bool {
        self.traverse_in(0, &self.tris, ray, visitor, stats)
    }

    /// [`WideBvhN::traverse`] from node `root` of a forest whose leaves name blocks of `tris`
    /// (see [`WideBvhN::any_hit_from`]), with no root-box test, through the AVX2 entry point
    /// where the CPU has it.
    #[inline(always)]
    pub(crate) fn traverse_in<V: LeafVisitor>(
        &self,
        root: u32,
        tris: &[Triangle4],
        ray: &Ray,
        visitor: &mut V,
        stats: &mut impl Counters,
    ) -> bool {
        #[cfg(target_arch = "x86_64")]
        if super::dispatch::avx2_entry::<W>() {
            // SAFETY: `avx2_entry` is true only once the CPU was seen to have what the entry
            // points are compiled for.
            return unsafe { super::avx2::traverse(self, root, tris, ray, visitor, stats) };
        }
        self.walk_in::<Width<W>, V>(root, tris, ray, visitor, stats)
    }

    /// The closest hit on `[ray.t_min, ray.t_max]`, exactly as the binary BVH and brute force
    /// find it over the triangles the tree was collapsed with.
    pub fn closest_hit(&self, ray: &Ray) -> Option<Hit> {
        self.closest(ray, &mut ())
    }

    /// [`super::WideBvh::closest_hit`], adding what it did to `stats` (a wide node counts as one inner
    /// node, a leaf's triangles as tested whatever their lanes decide; a ray that passes the
    /// root's box by visits none: see `WideBvh::misses_root`).
    pub fn closest_hit_with_stats(&self, ray: &Ray, stats: &mut TraversalStats) -> Option<Hit> {
        self.closest(ray, stats)
    }

    /// [`WideBvhN::closest_hit`] with the hit triangle's first vertex and edges from its leaf
    /// block (see [`TriangleEdges`]): the same hit, and what a renderer needs to shade it without
    /// another trip to memory.
    pub fn closest_hit_edges(&self, ray: &Ray) -> Option<(Hit, TriangleEdges)> {
        let mut visitor = ClosestHitEdges::new(ray);
        self.traverse(ray, &mut visitor);
        visitor.best
    }

    /// True when the ray surely misses every child of the root, decided before any set-up.
    /// Primary rays often do (65% of the `peers` camera's on Crytek Sponza, 44% on the bunny, go
    /// past the scene's box), and for them the set-up and the frame of the traversal loop were
    /// most of the cost. A ray from inside the box pays only the containment test.
    ///
    /// Never stricter than the root's own 4-wide test: the box is the union of the children's,
    /// and the test is that test's arithmetic on planes no farther out (per axis the near value
    /// is at least, the far value at most, a child's; a zero direction component's NaN plane is
    /// one the box's value would not restrict either), so a ray it sends past the box, the root's
    /// test sends past every child.
    #[inline(always)]
    fn misses_root(&self, ray: &Ray) -> bool {
        let (lo, hi) = (self.root_min, self.root_max);
        let o = f32x4::from([ray.origin.x, ray.origin.y, ray.origin.z, 0.0]);
        if (lo.simd_le(o) & o.simd_le(hi)).all() {
            return false;
        }
        // Lane 3 measures 1 along -inf..inf: -inf near, +inf far, neither restricts.
        let inv = f32x4::from([ray.inv_dir.x, ray.inv_dir.y, ray.inv_dir.z, 1.0]);
        let (t_lo, t_hi) = ((lo - o) * inv, (hi - o) * inv);
        let negative = inv.simd_lt(f32x4::ZERO);
        let near = keep_max(f32x4::splat(ray.t_min), negative.select(t_hi, t_lo)).to_array();
        let far = keep_min(f32x4::splat(ray.t_max), negative.select(t_lo, t_hi)).to_array();
        // Lanes hold no NaN now (each kept its accumulator), so plain comparisons reduce them.
        let max = |a: f32, b: f32| if a > b { a } else { b };
        let min = |a: f32, b: f32| if a < b { a } else { b };
        let t_near = max(max(near[0], near[1]), max(near[2], near[3]));
        let t_far = min(min(far[0], far[1]), min(far[2], far[3]));
        let touches = t_near - t_near.abs() * PAD <= t_far + t_far.abs() * PAD;
        !touches
    }

    #[inline(always)]
    fn closest(&self, ray: &Ray, stats: &mut impl Counters) -> Option<Hit> {
        if self.nodes.is_empty() || self.misses_root(ray) {
            return None;
        }
        #[cfg(target_arch = "x86_64")]
        if super::dispatch::avx2_entry::<W>() {
            // SAFETY: as in `walk_dispatched`.
            return unsafe { super::avx2::closest(self, ray, stats) };
        }
        self.closest_from_root(ray, stats)
    }

    /// The closest-hit traversal proper, out of line: its frame (saved registers, the stack of
    /// pending entries) is set up only for rays that get past [`WideBvh::misses_root`].
    #[inline(never)]
    pub(crate) fn closest_from_root(&self, ray: &Ray, stats: &mut impl Counters) -> Option<Hit> {
        self.closest_walk::<Width<W>>(ray, stats)
    }

    /// The closest-hit walk on lanes `L`, for [`WideBvh::closest_from_root`] and its AVX2 twin.
    #[inline(always)]
    pub(crate) fn closest_walk<L: Lanes<W>>(
        &self,
        ray: &Ray,
        stats: &mut impl Counters,
    ) -> Option<Hit> {
        let mut visitor = ClosestHit::new(ray);
        self.walk::<L, _>(0, ray, &mut visitor, stats);
        visitor.best
    }

    /// True when any triangle is hit on the segment; stops at the first hit.
    pub fn any_hit(&self, ray: &Ray) -> bool {
        self.any(ray, &mut ())
    }

    /// [`super::WideBvh::any_hit`], adding what it did to `stats`.
    pub fn any_hit_with_stats(&self, ray: &Ray, stats: &mut TraversalStats) -> bool {
        self.any(ray, stats)
    }

    #[inline(always)]
    fn any(&self, ray: &Ray, stats: &mut impl Counters) -> bool {
        if self.nodes.is_empty() || self.misses_root(ray) {
            return false;
        }
        self.any_hit_from(0, &self.tris, ray, stats)
    }

    /// [`WideBvh::any_hit_with_stats`] from node `root` of a forest (one node array holding
    /// several trees) whose leaves name blocks of `tris` (its own, or another tree's: a light
    /// buffer's cell trees point into the scene BVH's blocks), with no root-box test: a tree the
    /// caller chose for the ray. Runs [`WideBvh::any_from_root`], through the AVX2 entry point
    /// where the CPU has it.
    #[inline(always)]
    pub(crate) fn any_hit_from(
        &self,
        root: u32,
        tris: &[Triangle4],
        ray: &Ray,
        stats: &mut impl Counters,
    ) -> bool {
        #[cfg(target_arch = "x86_64")]
        if super::dispatch::avx2_entry::<W>() {
            // SAFETY: as in `walk_dispatched`.
            return unsafe { super::avx2::any(self, root, tris, ray, stats) };
        }
        self.any_from_root(root, tris, ray, stats)
    }

    /// The any-hit traversal proper from node `root`, out of line (see
    /// [`WideBvh::closest_from_root`]).
    #[inline(never)]
    pub(crate) fn any_from_root(
        &self,
        root: u32,
        tris: &[Triangle4],
        ray: &Ray,
        stats: &mut impl Counters,
    ) -> bool {
        self.any_walk::<Width<W>>(root, tris, ray, stats)
    }

    /// The any-hit walk on lanes `L`, for [`WideBvh::any_from_root`] and its AVX2 twin.
    #[inline(always)]
    pub(crate) fn any_walk<L: Lanes<W>>(
        &self,
        root: u32,
        tris: &[Triangle4],
        ray: &Ray,
        stats: &mut impl Counters,
    ) -> bool {
        self.walk_in::<L, _>(root, tris, ray, &mut AnyHit::new(ray), stats)
    }

    /// The all-hit walk: every wide node whose box the segment touches (`inner_nodes`), every
    /// leaf and triangle in those boxes, and how many of those triangles the segment hits, with
    /// no early exit. The 4-wide counterpart of [`crate::bvh::Bvh::all_hit`].
    pub fn all_hit(&self, ray: &Ray) -> AllHitStats {
        let mut count = HitCount::new(ray);
        let mut stats = TraversalStats::default();
        self.traverse_with_stats(ray, &mut count, &mut stats);
        AllHitStats {
            inner_nodes: stats.inner_nodes,
            leaves: stats.leaves,
            triangles: stats.triangles,
            hits: count.hits,
        }
    }

    /// The loop every query shares, from node `root` (the root box test done or skipped by the
    /// caller). It keeps the node it is in rather than pushing and popping it: a node with one
    /// child hit goes straight on to it, and one with several pushes all but the one it goes to
    /// (for an ordered visitor the nearest, the rest pushed farthest first; for an unordered
    /// one the lowest slot, the rest pushed highest first, so that they are visited in slot
    /// order). Generic over the lanes `L` so that the AVX2 entry points ([`super::dispatch`])
    /// instantiate the same loop.
    #[inline(always)]
    pub(crate) fn walk<L: Lanes<W>, V: LeafVisitor>(
        &self,
        root: u32,
        ray: &Ray,
        visitor: &mut V,
        stats: &mut impl Counters,
    ) -> bool {
        self.walk_in::<L, V>(root, &self.tris, ray, visitor, stats)
    }

    /// [`WideBvhN::walk`] over this tree's nodes with leaves in `tris`: its own blocks, or the
    /// blocks of the tree its leaves point into ([`WideBvhN::any_hit_from`]).
    #[inline(always)]
    pub(crate) fn walk_in<L: Lanes<W>, V: LeafVisitor>(
        &self,
        root: u32,
        tris: &[Triangle4],
        ray: &Ray,
        visitor: &mut V,
        stats: &mut impl Counters,
    ) -> bool {
        let r = RayN::<L::V>::new(ray);
        let mut storage = L::Pending::new();
        let mut stack = PendingStack {
            items: &mut storage,
            len: 0,
        };
        let (mut child, mut count) = (root, 0u32);
        loop {
            if count == 0 {
                stats.node();
                let node = &self.nodes[child as usize];
                let (t_near, mask) = r.intersect(node, visitor.t_max());
                if mask != 0 {
                    let first = mask.trailing_zeros() as usize;
                    let rest = mask & (mask - 1);
                    let next = if rest == 0 {
                        first
                    } else {
                        // Several children hit: start fetching them all now, so their cache
                        // misses overlap the work on the first (the loop is bound by them).
                        Self::prefetch(&self.nodes, tris, node, mask);
                        if V::ORDERED {
                            push_ordered(&mut stack, node, t_near, first, rest)
                        } else {
                            // Highest slot first, so that the pops come in slot order.
                            let mut m = rest;
                            while m != 0 {
                                let i = 31 - m.leading_zeros() as usize;
                                m &= !(1 << i);
                                stack.push((node.child[i], node.count[i], 0.0));
                            }
                            first
                        }
                    };
                    child = node.child[next];
                    count = node.count[next];
                    continue;
                }
            } else {
                stats.leaf(count);
                let first = child as usize;
                let blocks = &tris[first..first + count.div_ceil(4) as usize];
                if visitor.leaf(blocks, count) {
                    return true;
                }
            }
            // Pop the next subtree that can still hold a closer hit: the same padded bound the
            // box test used when it admitted the subtree.
            loop {
                let Some((c, n, t_entry)) = stack.pop() else {
                    return false;
                };
                if !V::ORDERED || t_entry <= pad_far(visitor.t_max()) {
                    child = c;
                    count = n;
                    break;
                }
            }
        }
    }
}

impl<const W: usize> WideBvhN<W> {
    /// Hints the cache to fetch the children in `mask`: a node's two lines, or a leaf's first
    /// block's three. A hint only: no fault, no effect on any answer.
    #[inline(always)]
    fn prefetch(nodes: &[WideNodeN<W>], tris: &[Triangle4], node: &WideNodeN<W>, mask: u32) {
        #[cfg(target_arch = "x86_64")]
        {
            use core::arch::x86_64::{_mm_prefetch, _MM_HINT_T0};
            let mut m = mask;
            while m != 0 {
                let i = m.trailing_zeros() as usize;
                m &= m - 1;
                let (child, count) = (node.child[i] as usize, node.count[i]);
                // `wrapping_add`: the address is only a hint, never dereferenced here.
                let (p, lines) = if count == 0 {
                    (nodes.as_ptr().wrapping_add(child).cast::<i8>(), 2)
                } else {
                    (tris.as_ptr().wrapping_add(child).cast::<i8>(), 3)
                };
                for l in 0..lines {
                    // SAFETY: prefetching is a hint with no memory access semantics; any
                    // address is allowed.
                    unsafe { _mm_prefetch::<_MM_HINT_T0>(p.wrapping_add(64 * l)) };
                }
            }
        }
        #[cfg(not(target_arch = "x86_64"))]
        let _ = (nodes, tris, node, mask);
    }
}

/// Pushes the children hit in `first` and `rest` (a mask of at least one more) but the nearest,
/// farthest first, and returns the nearest.
#[inline(always)]
fn push_ordered<const W: usize, V: ChildLanes<W>>(
    stack: &mut PendingStack<'_, impl Pending>,
    node: &WideNodeN<W>,
    t_near: V,
    first: usize,
    rest: u32,
) -> usize {
    let t_near = t_near.to_array();
    let second = rest.trailing_zeros() as usize;
    let (near, far) = if t_near[second] < t_near[first] {
        (second, first)
    } else {
        (first, second)
    };
    if rest & (rest - 1) == 0 {
        // Two children hit, the commonest case after one: push the farther.
        stack.push((node.child[far], node.count[far], t_near[far]));
        return near;
    }
    // Three or more: sorted by entry, nearest last.
    let mut hits = [(0, 0.0); W];
    hits[0] = (far, t_near[far]);
    hits[1] = (near, t_near[near]);
    let mut n = 2;
    let mut m = rest & (rest - 1);
    while m != 0 {
        let i = m.trailing_zeros() as usize;
        m &= m - 1;
        let mut j = n;
        while j > 0 && hits[j - 1].1 < t_near[i] {
            hits[j] = hits[j - 1];
            j -= 1;
        }
        hits[j] = (i, t_near[i]);
        n += 1;
    }
    for &(i, t) in &hits[..n - 1] {
        stack.push((node.child[i], node.count[i], t));
    }
    hits[n - 1].0
}

#[cfg(test)]
mod tests {
    use alloc::vec::Vec;

    use glam::Vec3;

    use super::*;
    use crate::brute_force;
    use crate::builder::Builder;
    use crate::bvh::{Bvh, WideBvh};
    use crate::geometry::Triangle;
    use crate::random::Pcg32;

    #[test]
    fn wide_agrees_with_brute_force() {
        let mut tris = crate::test_scenes::soup(700, 21, -10.0, 10.0, 1.0);
        let mut rng = Pcg32::new(22);
        let mut v = |s: f32| Vec3::new(rng.range(-s, s), rng.range(-s, s), rng.range(-s, s));
        // Axis-aligned walls: rays along their faces exercise the NaN lanes.
        tris.push(Triangle::new(
            Vec3::new(-20.0, -20.0, 0.0),
            Vec3::new(20.0, -20.0, 0.0),
            Vec3::new(0.0, 20.0, 0.0),
        ));
        for n in [1usize, 2, 5, tris.len()] {
            let tris = &tris[..n];
            let bvh = Builder::sah().build(tris).unwrap();
            let wide = WideBvh::from_binary(&bvh, tris);
            let wide8 = crate::bvh::WideBvh8::from_binary(&bvh, tris);
            assert!(wide.max_depth() <= bvh.max_depth());
            assert!(wide8.max_depth() <= wide.max_depth());
            for i in 0..2000 {
                let o = v(12.0);
                let mut d = v(1.0);
                if i % 4 == 0 {
                    d = Vec3::new(d.x, 0.0, -0.0);
                }
                if i % 8 == 1 {
                    // Along the wall's plane.
                    let o = Vec3::new(o.x, o.y, 0.0);
                    let Ok(r) = Ray::new(o, Vec3::new(d.x, d.y, 0.0)) else {
                        continue;
                    };
                    assert_eq!(wide.closest_hit(&r), brute_force::closest_hit(&r, tris));
                    assert_eq!(wide8.closest_hit(&r), brute_force::closest_hit(&r, tris));
                    continue;
                }
                let Ok(r) = Ray::new(o, d) else { continue };
                let expect = brute_force::closest_hit(&r, tris);
                assert_eq!(wide.closest_hit(&r), expect, "ray {i}");
                assert_eq!(wide.any_hit(&r), expect.is_some());
                assert_eq!(wide.all_hit(&r).hits, brute_force::hit_count(&r, tris));
                assert_eq!(wide8.closest_hit(&r), expect, "ray {i}");
                assert_eq!(wide8.any_hit(&r), expect.is_some());
                assert_eq!(wide8.all_hit(&r).hits, brute_force::hit_count(&r, tris));
            }
        }
    }

    /// Records the leaves an unordered walk visits (by their first triangle id), never stopping.
    struct LeafOrder {
        t_max: f32,
        leaves: Vec<u32>,
    }

    impl LeafVisitor for LeafOrder {
        const ORDERED: bool = false;
        fn t_max(&self) -> f32 {
            self.t_max
        }
        fn leaf(&mut self, blocks: &[Triangle4], _count: u32) -> bool {
            self.leaves.push(blocks[0].id[0]);
            false
        }
    }

    /// The leaves below `node` whose boxes the ray touches, depth first in slot order.
    fn slot_order(wide: &crate::bvh::WideBvh8, r: &RayN<f32x8>, node: u32, out: &mut Vec<u32>) {
        let node = &wide.nodes[node as usize];
        let (_, mask) = r.intersect(node, f32::INFINITY);
        for i in (0..8).filter(|i| mask & (1 << i) != 0) {
            match node.count[i] {
                0 => slot_order(wide, r, node.child[i], out),
                _ => out.push(wide.triangles()[node.child[i] as usize].id[0]),
            }
        }
    }

    /// An unordered walk (any hit, the all-hit count) visits the children a ray hits in slot
    /// order, so that the order `order_fewest_first` and the light buffers' cell trees set up is
    /// the order an any-hit query tries them in.
    #[test]
    fn unordered_walks_visit_children_in_slot_order() {
        let tris = crate::test_scenes::soup(3000, 41, -10.0, 10.0, 1.0);
        let bvh = Builder::sah().build(&tris).unwrap();
        let wide8 = crate::bvh::WideBvh8::from_binary(&bvh, &tris);
        let mut rng = Pcg32::new(42);
        let mut several = 0;
        for _ in 0..500 {
            let mut v = |s: f32| Vec3::new(rng.range(-s, s), rng.range(-s, s), rng.range(-s, s));
            let Ok(ray) = Ray::new(v(12.0), v(1.0)) else {
                continue;
            };
            let mut expect = Vec::new();
            slot_order(&wide8, &RayN::new::<8>(&ray), 0, &mut expect);
            let mut seen = LeafOrder {
                t_max: ray.t_max,
                leaves: Vec::new(),
            };
            wide8.walk::<Width<8>, _>(0, &ray, &mut seen, &mut TraversalStats::default());
            assert_eq!(seen.leaves, expect);
            several += usize::from(expect.len() > 2);
        }
        assert!(several > 100, "{several} rays reach three leaves or more");
    }

    /// The hit with edges is the closest hit, and its edges are the scene triangle's first
    /// vertex and `v1 - v0`, `v2 - v0` bit for bit, on 4- and 8-wide trees.
    #[test]
    fn closest_hit_edges_are_the_hit_triangles() {
        let tris = crate::test_scenes::soup(900, 31, -10.0, 10.0, 1.5);
        let bvh = Builder::sah().build(&tris).unwrap();
        let wide = WideBvh::from_binary(&bvh, &tris);
        let wide8 = crate::bvh::WideBvh8::from_binary(&bvh, &tris);
        let mut rng = Pcg32::new(32);
        let mut hits = 0;
        for _ in 0..3000 {
            let mut v = |s: f32| Vec3::new(rng.range(-s, s), rng.range(-s, s), rng.range(-s, s));
            let Ok(r) = Ray::new(v(12.0), v(1.0)) else {
                continue;
            };
            for found in [wide.closest_hit_edges(&r), wide8.closest_hit_edges(&r)] {
                assert_eq!(found.map(|(h, _)| h), wide.closest_hit(&r));
                if let Some((h, e)) = found {
                    let t = &tris[h.triangle as usize];
                    let bits = |v: Vec3| v.to_array().map(f32::to_bits);
                    assert_eq!(bits(e.v0), bits(t.v0));
                    assert_eq!(bits(e.e1), bits(t.v1 - t.v0));
                    assert_eq!(bits(e.e2), bits(t.v2 - t.v0));
                    hits += 1;
                }
            }
        }
        assert!(hits > 500, "{hits} hits");
    }

    #[test]
    fn rays_past_the_root_box_skip_the_traversal_and_lose_no_hit() {
        // A soup, and triangles whose edges and faces lie on the scene box's planes, so rays
        // that graze the box (along a face, through an edge or a corner, with zero direction
        // components whose slab values are NaN) can still hit something.
        let mut tris = crate::test_scenes::soup(300, 5, -8.0, 8.0, 1.5);
        let (lo, hi) = (Vec3::splat(-10.0), Vec3::splat(10.0));
        tris.push(Triangle::new(
            lo,
            Vec3::new(hi.x, lo.y, 0.0),
            Vec3::new(0.0, 0.0, hi.z),
        ));
        tris.push(Triangle::new(
            hi,
            Vec3::new(lo.x, hi.y, 0.0),
            Vec3::new(0.0, hi.y, lo.z),
        ));
        tris.push(Triangle::new(
            Vec3::new(hi.x, -5.0, -5.0),
            Vec3::new(hi.x, 5.0, -5.0),
            Vec3::new(0.0, 0.0, 5.0),
        ));
        let bvh = Builder::sah().build(&tris).unwrap();
        let wide = WideBvh::from_binary(&bvh, &tris);
        let b = bvh.bounds();
        let mut rng = Pcg32::new(41);
        let mut skipped = 0;
        for i in 0..6000 {
            // A target on, just inside or just outside the box's surface, some coordinates
            // exactly on its planes.
            let mut target = Vec3::new(
                rng.range(b.min.x - 1.0, b.max.x + 1.0),
                rng.range(b.min.y - 1.0, b.max.y + 1.0),
                rng.range(b.min.z - 1.0, b.max.z + 1.0),
            );
            for k in 0..3 {
                match rng.next_u32() % 4 {
                    0 => target[k] = b.min[k],
                    1 => target[k] = b.max[k],
                    _ => {}
                }
            }
            // From outside the box, sometimes within a face's plane with that component zero.
            let mut dir = Vec3::new(
                rng.range(-1.0, 1.0),
                rng.range(-1.0, 1.0),
                rng.range(-1.0, 1.0),
            );
            if i % 3 == 0 {
                let k = (rng.next_u32() % 3) as usize;
                dir[k] = 0.0;
            }
            let Ok(probe) = Ray::new(target, -dir) else {
                continue;
            };
            let origin = probe.at(rng.range(12.0, 60.0));
            let Ok(ray) = Ray::segment(origin, dir, 0.0, [f32::INFINITY, 30.0, 5.0][i % 3]) else {
                continue;
            };
            let expect = brute_force::closest_hit(&ray, &tris);
            let mut stats = TraversalStats::default();
            assert_eq!(
                wide.closest_hit_with_stats(&ray, &mut stats),
                expect,
                "ray {i}"
            );
            assert_eq!(wide.any_hit(&ray), expect.is_some(), "ray {i}");
            if stats.inner_nodes == 0 {
                skipped += 1;
                assert!(!b.contains_point(ray.origin) && expect.is_none(), "ray {i}");
            }
        }
        // Rays that pass the box by far are answered without visiting the root; rays from
        // inside always visit it.
        assert!(skipped > 1000, "{skipped} rays skipped the traversal");
        let inside = Ray::new(Vec3::ZERO, Vec3::X).unwrap();
        let mut stats = TraversalStats::default();
        wide.closest_hit_with_stats(&inside, &mut stats);
        assert!(stats.inner_nodes >= 1);
    }

    #[test]
    fn empty_and_single_leaf() {
        let wide = WideBvh::from_binary(&Bvh::default(), &[]);
        let r = Ray::new(Vec3::ZERO, Vec3::Z).unwrap();
        assert!(wide.closest_hit(&r).is_none());
        let t = [Triangle::new(
            Vec3::new(-1.0, -1.0, 1.0),
            Vec3::new(1.0, -1.0, 1.0),
            Vec3::new(0.0, 1.0, 1.0),
        )];
        let wide = WideBvh::from_binary(&Builder::sah().build(&t).unwrap(), &t);
        assert_eq!(wide.closest_hit(&r).unwrap().triangle, 0);
        assert!(wide.any_hit(&r));
    }
}
