//! Spatial splits (SBVH, Stich, Friedrich and Dietrich 2009): a binned SAH build that may also
//! cut a node with a plane through its triangles, putting a triangle that straddles the plane in
//! both children with its box clipped to each side.
//!
//! An object split can only group whole triangles, so a node holding long or diagonal triangles
//! (Sponza's walls and arches) gets children whose boxes overlap, and every ray through the
//! overlap visits both. A spatial split trades that overlap for duplicate references. Each node
//! prices its best object split (centroid bins, every axis) and, where that split's children
//! overlap by more than `alpha` of the root's area and that holds more than twice `max_leaf`
//! fragments, its best spatial split (bins over the node's box, each triangle's part in each bin
//! it crosses), then keeps the cheaper one, with
//! reference unsplitting: a straddling triangle goes to one side whole when that prices lower.
//!
//! References live in one buffer of `(1 + budget) n` slots. A node owns a slot range larger than
//! its references, and a split hands the spare slots to its children in proportion to their
//! references, so the budget bounds the duplicates without any allocation during the build. A
//! spatial split that would need more slots than the node owns is not considered.
//!
//! The tree is a [`Bvh`] like any other, whose leaves may name a triangle more than once across
//! the tree (never twice in one leaf). Its leaf boxes bound the clipped parts only: a traversal
//! that tests the whole triangle finds exactly the hits it finds in an ordinary BVH, since every
//! point of a triangle lies in one of its parts' boxes.

use alloc::vec::Vec;

use glam::Vec3A;

use super::config::MAX_BINS;
use crate::bvh::{Bvh, BvhNode, MAX_DEPTH};
use crate::geometry::{Aabb, Triangle};
use crate::heuristics::CostConstants;
use crate::BuildError;

/// The settings of a [`SpatialBuilder`].
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct SpatialSplits {
    /// Spatial splits are priced only in nodes whose best object split's children overlap by
    /// more than `alpha` times the root's surface area (Stich et al.: `1e-5`), and that hold
    /// more than twice `max_leaf` fragments. 0 prices them in every such node; 1 or more, in
    /// none.
    pub alpha: f32,
    /// Duplicate references allowed, as a fraction of the triangle count: `0.5` lets the tree
    /// hold up to `1.5 n` references. 0 gives a plain binned SAH tree.
    pub budget: f32,
    /// Object-split (centroid) bins per axis, 2 to 64.
    pub object_bins: u32,
    /// Spatial-split bins per axis, 2 to 64.
    pub spatial_bins: u32,
    /// The most triangles a leaf may hold: a node of more always splits.
    pub max_leaf: u32,
    /// The cost constants that price splits against leaves.
    pub constants: CostConstants,
}

impl Default for SpatialSplits {
    /// Stich et al.'s `alpha = 1e-5`, up to half as many references again, 16 object bins (the
    /// `sah` preset's) and 32 spatial bins, leaves of at most 8 (the `sah` preset's).
    fn default() -> Self {
        Self {
            alpha: 1e-5,
            budget: 0.5,
            object_bins: 16,
            spatial_bins: 32,
            max_leaf: 8,
            constants: CostConstants::default(),
        }
    }
}

impl SpatialSplits {
    /// Checks every value's range.
    pub fn validate(&self) -> Result<(), BuildError> {
        if !(self.alpha >= 0.0 && self.alpha.is_finite()) {
            return Err(BuildError::InvalidConfig(
                "spatial split alpha must be finite and >= 0",
            ));
        }
        if !(self.budget >= 0.0 && self.budget <= 16.0) {
            return Err(BuildError::InvalidConfig(
                "spatial split budget must be between 0 and 16",
            ));
        }
        if !(2..=MAX_BINS).contains(&self.object_bins)
            || !(2..=MAX_BINS).contains(&self.spatial_bins)
        {
            return Err(BuildError::InvalidConfig("bins must be between 2 and 64"));
        }
        if self.max_leaf == 0 {
            return Err(BuildError::InvalidConfig("max_leaf must be at least 1"));
        }
        self.constants.validate()
    }
}

/// Builds SBVHs (Stich, Friedrich and Dietrich 2009): binned SAH whose nodes may also be cut by a
/// plane through their triangles, a straddling triangle going to both children with its box
/// clipped to each side (or whole to one side where that prices lower). Spatial splits are
/// priced where the best object split's children overlap by more than
/// [`SpatialSplits::alpha`] of the root's area (in nodes of more than twice
/// [`SpatialSplits::max_leaf`] fragments), within a budget of duplicate references
/// ([`SpatialSplits::budget`]) handed down the tree as spare slots, so the build allocates
/// nothing once started. The result is a [`Bvh`] whose leaves may name a triangle more than once
/// across the tree (never twice in one leaf; [`Bvh::validate_split`]); every traversal finds the
/// same hits as in any BVH, since each leaf box bounds its part of a triangle and the triangle
/// test tests all of it.
///
/// ```
/// use rdbvh_core::builder::{SpatialBuilder, SpatialSplits};
/// use rdbvh_core::{Builder, Ray, Triangle, Vec3};
///
/// // Small triangles, crossed by a few long slivers from corner to corner (a wall's trim, a cable).
/// let mut tris: Vec<Triangle> = (0..400)
///     .map(|i| {
///         let o = Vec3::new((i % 20) as f32, (i / 20) as f32, (i % 7) as f32);
///         Triangle::new(o, o + Vec3::X * 0.5, o + Vec3::Y * 0.5)
///     })
///     .collect();
/// for i in 0..8 {
///     let a = Vec3::new(i as f32 * 2.0, 0.0, 0.0);
///     let b = Vec3::new(20.0 - a.x, 20.0, 7.0);
///     tris.push(Triangle::new(a, b, b + Vec3::X * 0.05));
/// }
/// let sbvh = SpatialBuilder::new(SpatialSplits::default()).build(&tris)?;
/// let sah = Builder::sah().build(&tris)?;
/// assert!(sbvh.prim_indices().len() > tris.len()); // some triangles were split
/// let ray = Ray::new(Vec3::new(6.2, 4.2, -1.0), Vec3::Z)?;
/// assert_eq!(sbvh.closest_hit(&ray, &tris), sah.closest_hit(&ray, &tris));
/// # Ok::<(), Box<dyn std::error::Error>>(())
/// ```
#[derive(Clone, Copy, Debug, Default, PartialEq)]
pub struct SpatialBuilder {
    /// Its settings.
    pub splits: SpatialSplits,
}

/// A box as two SIMD lanes (glam's `Vec3A`): the build's loops grow, clip and intersect boxes in
/// every step, each then one `minps` or `maxps` per corner.
#[derive(Clone, Copy, Debug)]
struct Box3 {
    min: Vec3A,
    max: Vec3A,
}

impl Box3 {
    const EMPTY: Box3 = Box3 {
        min: Vec3A::INFINITY,
        max: Vec3A::NEG_INFINITY,
    };

    #[inline(always)]
    fn union(self, o: Box3) -> Box3 {
        Box3 {
            min: self.min.min(o.min),
            max: self.max.max(o.max),
        }
    }

    #[inline(always)]
    fn grown(self, p: Vec3A) -> Box3 {
        Box3 {
            min: self.min.min(p),
            max: self.max.max(p),
        }
    }

    #[inline(always)]
    fn intersection(self, o: Box3) -> Box3 {
        Box3 {
            min: self.min.max(o.min),
            max: self.max.min(o.max),
        }
    }

    #[inline(always)]
    fn is_empty(&self) -> bool {
        self.min.cmpgt(self.max).any()
    }

    /// Half the surface area, zero for an empty box (as [`Aabb::half_area`]).
    #[inline(always)]
    fn half_area(&self) -> f32 {
        let e = (self.max - self.min).max(Vec3A::ZERO);
        e.x * e.y + e.y * e.z + e.z * e.x
    }

    /// The axis of the largest extent, ties to the lower axis (as [`Aabb::largest_axis`]).
    #[inline(always)]
    fn largest_axis(&self) -> usize {
        Aabb::from(*self).largest_axis()
    }
}

impl From<Aabb> for Box3 {
    #[inline(always)]
    fn from(b: Aabb) -> Self {
        Box3 {
            min: b.min.into(),
            max: b.max.into(),
        }
    }
}

impl From<Box3> for Aabb {
    #[inline(always)]
    fn from(b: Box3) -> Self {
        Aabb::new(b.min.into(), b.max.into())
    }
}

/// One reference: a triangle, or the part of it a spatial split left in this node, by its box.
#[derive(Clone, Copy, Debug)]
struct Fragment {
    bounds: Box3,
    id: u32,
}

impl Fragment {
    const EMPTY: Fragment = Fragment {
        bounds: Box3::EMPTY,
        id: u32::MAX,
    };

    /// Twice the box centre along `axis`.
    #[inline(always)]
    fn centroid2(&self, axis: usize) -> f32 {
        self.bounds.min[axis] + self.bounds.max[axis]
    }
}

/// A node still to decide: fragments in slots `start..start + count`, spare slots up to `end`.
#[derive(Clone, Copy, Debug)]
struct Task {
    node: u32,
    start: u32,
    count: u32,
    end: u32,
    depth: u32,
}

/// A bin of either sweep: the box of what fell in it, and how many fragments start (`enter`) and
/// end (`exit`) in it (an object bin's fragments do both).
#[derive(Clone, Copy, Debug)]
struct SweepBin {
    bounds: Box3,
    enter: u32,
    exit: u32,
}

impl SweepBin {
    const EMPTY: SweepBin = SweepBin {
        bounds: Box3::EMPTY,
        enter: 0,
        exit: 0,
    };
}

/// The bins of one sweep and its suffix boxes, kept for the whole build: only the bins a node
/// uses are cleared, where fresh arrays of [`MAX_BINS`] would be mostly written for nothing in
/// every small node.
#[derive(Debug)]
struct Sweep {
    bins: [SweepBin; MAX_BINS as usize],
    right: [(Box3, u32); MAX_BINS as usize],
    /// One fragment's part in each spatial bin, before it is clipped to the fragment's box.
    parts: [Box3; MAX_BINS as usize],
}

/// The cheapest bin boundary of a sweep: `bin` splits the bins below it from the rest.
#[derive(Clone, Copy, Debug)]
struct Boundary {
    bin: usize,
    cost: f32,
    left: Box3,
    right: Box3,
    n_left: u32,
    n_right: u32,
}

impl Boundary {
    /// Makes this boundary, as `split`, the `best` split so far when it is cheaper.
    fn keep_if_cheaper(&self, split: Split, best: &mut Option<Priced>) {
        if best.is_none_or(|b| self.cost < b.cost) {
            *best = Some(Priced {
                split,
                cost: self.cost,
                left: self.left,
                right: self.right,
            });
        }
    }
}

impl Sweep {
    const NEW: Sweep = Sweep {
        bins: [SweepBin::EMPTY; MAX_BINS as usize],
        right: [(Box3::EMPTY, 0); MAX_BINS as usize],
        parts: [Box3::EMPTY; MAX_BINS as usize],
    };

    /// The first `count` bins, cleared.
    fn reset(&mut self, count: usize) -> &mut [SweepBin] {
        let bins = &mut self.bins[..count];
        bins.fill(SweepBin::EMPTY);
        bins
    }

    /// The cheapest boundary of the first `count` bins for a node of area `area`, among those
    /// whose children counts `fits` admits (both non-empty): left of boundary `i` is what
    /// enters below it, right what exits at or above it.
    fn cheapest(
        &mut self,
        count: usize,
        area: f32,
        k: CostConstants,
        fits: impl Fn(u32, u32) -> bool,
    ) -> Option<Boundary> {
        let (mut acc, mut acc_n) = (Box3::EMPTY, 0);
        for i in (1..count).rev() {
            acc = acc.union(self.bins[i].bounds);
            acc_n += self.bins[i].exit;
            self.right[i] = (acc, acc_n);
        }
        let (mut acc, mut acc_n) = (Box3::EMPTY, 0);
        let mut best: Option<Boundary> = None;
        for i in 1..count {
            acc = acc.union(self.bins[i - 1].bounds);
            acc_n += self.bins[i - 1].enter;
            let (right, n_right) = self.right[i];
            if acc_n == 0 || n_right == 0 || !fits(acc_n, n_right) {
                continue;
            }
            let cost = k.traversal
                + k.intersection
                    * (acc.half_area() * acc_n as f32 + right.half_area() * n_right as f32)
                    / area;
            if best.is_none_or(|b| cost < b.cost) {
                best = Some(Boundary {
                    bin: i,
                    cost,
                    left: acc,
                    right,
                    n_left: acc_n,
                    n_right,
                });
            }
        }
        best
    }
}

/// The chosen way to split a node.
#[derive(Clone, Copy, Debug)]
enum Split {
    /// Centroids in bins below `bin` go left; `scale` and `offset` map a doubled centroid to its
    /// bin.
    Object {
        axis: usize,
        bin: usize,
        offset: f32,
        scale: f32,
    },
    /// Boundary `bin` of the node's spatial bins `grid` along `axis`; the sweep's children
    /// boxes and counts, which reference unsplitting starts from.
    Spatial {
        axis: usize,
        bin: usize,
        grid: SpatialBins,
        n_left: u32,
        n_right: u32,
    },
    /// The node's object median along `axis` (its widest centroid axis).
    Median { axis: usize },
}

/// A priced split: its cost relative to the node's area (`C_trav + C_isect (a_L n_L + a_R n_R) /
/// a`) and its children's boxes as the sweep saw them (the children's nodes are boxed again from
/// the fragments they get).
#[derive(Clone, Copy, Debug)]
struct Priced {
    split: Split,
    cost: f32,
    left: Box3,
    right: Box3,
}

/// The spatial bins of one axis of a node's box: bin `i` spans `[plane(i), plane(i + 1)]`.
#[derive(Clone, Copy, Debug)]
struct SpatialBins {
    lo: f32,
    width: f32,
    inv_width: f32,
    count: usize,
}

impl SpatialBins {
    #[inline(always)]
    fn bin(&self, x: f32) -> usize {
        // NaN-free inputs; the clamp keeps rounding at either end inside.
        let b = ((x - self.lo) * self.inv_width) as i64;
        b.clamp(0, self.count as i64 - 1) as usize
    }

    #[inline(always)]
    fn plane(&self, i: usize) -> f32 {
        self.lo + self.width * i as f32
    }
}

/// The parts of `tri` on either side of the plane `axis = position`, each bounded by its side of
/// the plane and by `within` (the box of the fragment being split); either may be empty.
fn split_fragment(tri: &Triangle, within: &Box3, axis: usize, position: f32) -> (Box3, Box3) {
    let v = [
        Vec3A::from(tri.v0),
        Vec3A::from(tri.v1),
        Vec3A::from(tri.v2),
    ];
    let (mut left, mut right) = (Box3::EMPTY, Box3::EMPTY);
    for i in 0..3 {
        let (a, b) = (v[i], v[(i + 1) % 3]);
        let (pa, pb) = (a[axis], b[axis]);
        if pa <= position {
            left = left.grown(a);
        }
        if pa >= position {
            right = right.grown(a);
        }
        if (pa < position && position < pb) || (pb < position && position < pa) {
            let t = ((position - pa) / (pb - pa)).clamp(0.0, 1.0);
            let p = on_plane(a + (b - a) * t, axis, position);
            left = left.grown(p);
            right = right.grown(p);
        }
    }
    let mut l = left.intersection(*within);
    let mut r = right.intersection(*within);
    // The plane bounds each side exactly, whatever the rounding of the crossing points.
    l.max = l.max.min(on_plane(l.max, axis, position));
    r.min = r.min.max(on_plane(r.min, axis, position));
    (l, r)
}

/// `p` with its coordinate on `axis` set to `position`, by a lane select: writing one lane
/// through memory and reading the vector back stalls store forwarding, which took over a quarter
/// of the SBVH build's time.
#[inline(always)]
fn on_plane(p: Vec3A, axis: usize, position: f32) -> Vec3A {
    const LANES: [[bool; 3]; 3] = [
        [true, false, false],
        [false, true, false],
        [false, false, true],
    ];
    let [x, y, z] = LANES[axis];
    Vec3A::select(glam::BVec3A::new(x, y, z), Vec3A::splat(position), p)
}

/// Bounds the part of `tri` in each slab of `grid` along `axis` from bin `first` on, one box per
/// entry of `parts` (which it overwrites). A triangle's part in a slab is a convex polygon whose
/// corners lie on its edges inside the slab, so walking each edge across the planes it crosses
/// bounds every part with one crossing point per plane, where clipping the whole triangle at each
/// plane ([`split_fragment`]) did three edges' work per plane. These boxes only price the spatial
/// split; the partition clips the fragments it moves with [`split_fragment`].
fn slab_parts(tri: &Triangle, axis: usize, grid: &SpatialBins, first: usize, parts: &mut [Box3]) {
    parts.fill(Box3::EMPTY);
    let last = first + parts.len() - 1;
    let v = [
        Vec3A::from(tri.v0),
        Vec3A::from(tri.v1),
        Vec3A::from(tri.v2),
    ];
    for i in 0..3 {
        let (mut a, mut b) = (v[i], v[(i + 1) % 3]);
        if a[axis] > b[axis] {
            core::mem::swap(&mut a, &mut b);
        }
        let (ea, eb) = (grid.bin(a[axis]), grid.bin(b[axis]));
        let (lo, hi) = (ea.max(first), eb.min(last));
        if lo > hi {
            continue;
        }
        // Only called for planes strictly between the edge's ends, so `a` and `b` differ there.
        let crossing = |j: usize| {
            let p = grid.plane(j);
            let t = ((p - a[axis]) / (b[axis] - a[axis])).clamp(0.0, 1.0);
            on_plane(a + (b - a) * t, axis, p)
        };
        let mut from = if ea < lo { crossing(lo) } else { a };
        for j in lo + 1..=hi {
            let q = crossing(j);
            parts[j - 1 - first] = parts[j - 1 - first].grown(from).grown(q);
            from = q;
        }
        let to = if eb > hi { crossing(hi + 1) } else { b };
        parts[hi - first] = parts[hi - first].grown(from).grown(to);
    }
}

/// `ceil(log2 n)` for `n >= 1`.
fn ceil_log2(n: u32) -> u32 {
    32 - (n.max(1) - 1).leading_zeros()
}

impl SpatialBuilder {
    /// A builder with `splits`.
    pub fn new(splits: SpatialSplits) -> Self {
        Self { splits }
    }

    /// Builds an SBVH over `tris` (triangle `i` gets id `i`). Allocates its buffers once, before
    /// the build; an empty slice gives an empty BVH. A triangle with a NaN or infinite
    /// coordinate is an error.
    pub fn build(&self, tris: &[Triangle]) -> Result<Bvh, BuildError> {
        self.build_ids(tris, 0..tris.len() as u64, tris.len())
    }

    /// Builds an SBVH over the triangles of `tris` that `ids` names (a scene's subset: the
    /// triangles near a light, say), each keeping its id. An id that names no triangle is an
    /// error, as in [`crate::builder::BuildArena::load_triangle_subset`].
    pub fn build_subset(&self, tris: &[Triangle], ids: &[u32]) -> Result<Bvh, BuildError> {
        self.build_ids(tris, ids.iter().map(|&i| u64::from(i)), ids.len())
    }

    fn build_ids(
        &self,
        tris: &[Triangle],
        ids: impl Iterator<Item = u64>,
        n: usize,
    ) -> Result<Bvh, BuildError> {
        self.splits.validate()?;
        // Slots must stay `u32`, duplicates included.
        let slots = n as u64 + (n as f64 * f64::from(self.splits.budget)) as u64;
        if slots > u64::from(u32::MAX / 2) {
            return Err(BuildError::TooManyPrimitives);
        }
        let slots = slots as usize;
        let mut refs = Vec::with_capacity(slots);
        for id in ids {
            let tri = tris.get(id as usize).ok_or(BuildError::NoSuchPrimitive {
                index: u32::try_from(id).ok(),
                count: tris.len(),
            })?;
            if !tri.is_finite() {
                return Err(BuildError::InvalidPrimitive { index: id as u32 });
            }
            refs.push(Fragment {
                bounds: Box3::from(tri.bounds()),
                id: id as u32,
            });
        }
        let mut bvh = Bvh::default();
        if n == 0 {
            return Ok(bvh);
        }
        refs.resize(slots, Fragment::EMPTY);
        let mut scratch = alloc::vec![Fragment::EMPTY; slots];
        bvh.nodes.reserve(2 * slots - 1);
        bvh.prim_indices.reserve(slots);
        let root = bounds_of(&refs[..n]);
        let mut run = Run {
            splits: &self.splits,
            tris,
            refs: &mut refs,
            scratch: &mut scratch,
            out: &mut bvh,
            root_area: root.half_area(),
            sweep: Sweep::NEW,
        };
        run.build(root, n as u32, slots as u32);
        Ok(bvh)
    }
}

/// The box of `frags`.
fn bounds_of(frags: &[Fragment]) -> Box3 {
    frags.iter().fold(Box3::EMPTY, |b, f| b.union(f.bounds))
}

/// One build's state.
struct Run<'a> {
    splits: &'a SpatialSplits,
    tris: &'a [Triangle],
    refs: &'a mut [Fragment],
    scratch: &'a mut [Fragment],
    out: &'a mut Bvh,
    root_area: f32,
    sweep: Sweep,
}

impl Run<'_> {
    /// The build loop: depth first, left child first, nodes written as they are decided.
    fn build(&mut self, root: Box3, n: u32, slots: u32) {
        self.out.nodes.push(BvhNode::leaf(root.into(), 0, n));
        // Each level pushes two tasks and pops one, and depth is at most MAX_DEPTH.
        let mut stack: [Option<Task>; MAX_DEPTH as usize + 2] = [None; MAX_DEPTH as usize + 2];
        let mut top = 1;
        stack[0] = Some(Task {
            node: 0,
            start: 0,
            count: n,
            end: slots,
            depth: 0,
        });
        while top > 0 {
            top -= 1;
            let Some(task) = stack[top].take() else {
                break;
            };
            self.out.max_depth = self.out.max_depth.max(task.depth);
            let range = task.start as usize..(task.start + task.count) as usize;
            let bounds = bounds_of(&self.refs[range.clone()]);
            let Some(priced) = self.choose(&task, &bounds) else {
                let first = self.out.prim_indices.len() as u32;
                self.out
                    .prim_indices
                    .extend(self.refs[range].iter().map(|f| f.id));
                self.out.nodes[task.node as usize] =
                    BvhNode::leaf(bounds.into(), first, task.count);
                continue;
            };
            let (left, right) = self.apply(&task, &priced);
            let child = self.out.nodes.len() as u32;
            self.out.nodes[task.node as usize] = BvhNode::inner(bounds.into(), child);
            // Placeholders until the children are decided.
            self.out.nodes.push(BvhNode::leaf(Aabb::EMPTY, 0, 0));
            self.out.nodes.push(BvhNode::leaf(Aabb::EMPTY, 0, 0));
            let depth = task.depth + 1;
            stack[top] = Some(Task {
                node: child + 1,
                depth,
                ..right
            });
            stack[top + 1] = Some(Task {
                node: child,
                depth,
                ..left
            });
            top += 2;
        }
    }

    /// The split of the node `task` (box `bounds`), or `None` for a leaf.
    fn choose(&mut self, task: &Task, bounds: &Box3) -> Option<Priced> {
        let n = task.count;
        if n <= 1 {
            return None;
        }
        let area = bounds.half_area();
        // Near the depth bound, halve: `ceil(log2 n)` more levels always reach single
        // fragments. A box of no area gives the heuristic nothing to price.
        let deep = task.depth + ceil_log2(n) >= MAX_DEPTH;
        if deep || area.partial_cmp(&0.0) != Some(core::cmp::Ordering::Greater) {
            return (deep || n > self.splits.max_leaf).then(|| self.median(task));
        }
        let k = self.splits.constants;
        let object = self.best_object_split(task, area);
        let overlap = object.map_or(f32::INFINITY, |o| o.left.intersection(o.right).half_area());
        let slack = task.end - task.start - n;
        // Small nodes price no spatial split: their children are mostly leaves, where a
        // duplicate costs a triangle test as the overlap would, and they are most of the nodes.
        let small = n <= 2 * self.splits.max_leaf;
        let spatial = if slack > 0 && !small && overlap > self.splits.alpha * self.root_area {
            self.best_spatial_split(task, bounds, area)
        } else {
            None
        };
        let best = match (object, spatial) {
            (Some(o), Some(s)) if s.cost < o.cost => Some(s),
            (Some(o), _) => Some(o),
            (None, s) => s,
        };
        let leaf_cost = k.intersection * n as f32;
        match best {
            Some(b) if n <= self.splits.max_leaf && leaf_cost <= b.cost => None,
            Some(b) => Some(b),
            None => (n > self.splits.max_leaf).then(|| self.median(task)),
        }
    }

    /// The widest axis of `task`'s fragment centroids.
    fn median_axis(&self, task: &Task) -> usize {
        let start = task.start as usize;
        let frags = &self.refs[start..start + task.count as usize];
        let centroids = frags
            .iter()
            .fold(Box3::EMPTY, |b, f| b.grown(f.bounds.min + f.bounds.max));
        centroids.largest_axis()
    }

    /// The object median split of `task` along its widest centroid axis.
    fn median(&self, task: &Task) -> Priced {
        Priced {
            split: Split::Median {
                axis: self.median_axis(task),
            },
            cost: 0.0,
            left: Box3::EMPTY,
            right: Box3::EMPTY,
        }
    }

    /// Moves the fragments of `task` into the children's slot ranges and returns the children's
    /// tasks (node and depth still to set).
    fn apply(&mut self, task: &Task, priced: &Priced) -> (Task, Task) {
        let (start, n) = (task.start as usize, task.count as usize);
        let (n_left, n_right, moved) = match priced.split {
            Split::Object {
                axis,
                bin,
                offset,
                scale,
            } => {
                let frags = &mut self.refs[start..start + n];
                let mut i = 0;
                let mut j = n;
                while i < j {
                    let b = object_bin(frags[i].centroid2(axis), offset, scale, usize::MAX);
                    if b < bin {
                        i += 1;
                    } else {
                        j -= 1;
                        frags.swap(i, j);
                    }
                }
                (i, n - i, false)
            }
            Split::Median { axis } => self.partition_median(task, axis),
            Split::Spatial {
                axis,
                bin,
                grid,
                n_left,
                n_right,
            } => {
                let sweep = (priced.left, priced.right, n_left, n_right);
                match self.partition_spatial(task, axis, bin, &grid, sweep) {
                    Some((l, r)) => (l, r, true),
                    // Rounding emptied a side: halve instead.
                    None => self.partition_median(task, self.median_axis(task)),
                }
            }
        };
        // Spare slots go to the children in proportion to their fragments.
        let spare = task.end as usize - start - n_left - n_right;
        let left_spare = (spare as u64 * n_left as u64 / (n_left + n_right) as u64) as usize;
        let right_start = start + n_left + left_spare;
        if moved {
            // Left fragments at the front of the scratch range, right ones from its back.
            let end = task.end as usize;
            self.refs[start..start + n_left].copy_from_slice(&self.scratch[start..start + n_left]);
            self.refs[right_start..right_start + n_right]
                .copy_from_slice(&self.scratch[end - n_right..end]);
        } else if left_spare > 0 {
            self.refs
                .copy_within(start + n_left..start + n, right_start);
        }
        let left = Task {
            node: 0,
            start: start as u32,
            count: n_left as u32,
            end: right_start as u32,
            depth: 0,
        };
        let right = Task {
            node: 0,
            start: right_start as u32,
            count: n_right as u32,
            end: task.end,
            depth: 0,
        };
        (left, right)
    }

    /// Splits `task`'s fragments at their object median along `axis`, in place.
    fn partition_median(&mut self, task: &Task, axis: usize) -> (usize, usize, bool) {
        let (start, n) = (task.start as usize, task.count as usize);
        self.refs[start..start + n].select_nth_unstable_by(n / 2, |a, b| {
            a.centroid2(axis).total_cmp(&b.centroid2(axis))
        });
        (n / 2, n - n / 2, false)
    }

    /// Writes the spatial split's left fragments to the front of `task`'s scratch range and its
    /// right ones to the back, unsplitting a straddling triangle where one side alone prices
    /// lower. Sides are decided by the sweep's bins, so no more fragments come out than the
    /// sweep counted (which fit the slots). Returns the counts, or `None` when rounding left a
    /// side empty (the fragments in `refs` are untouched).
    fn partition_spatial(
        &mut self,
        task: &Task,
        axis: usize,
        bin: usize,
        grid: &SpatialBins,
        (mut left, mut right, mut n_left, mut n_right): (Box3, Box3, u32, u32),
    ) -> Option<(usize, usize)> {
        let (start, end) = (task.start as usize, task.end as usize);
        let position = grid.plane(bin);
        let (mut l, mut r) = (0, 0);
        for i in start..start + task.count as usize {
            let f = self.refs[i];
            let b0 = grid.bin(f.bounds.min[axis]);
            let b1 = grid.bin(f.bounds.max[axis]);
            let (to_left, to_right) = if b1 < bin {
                (Some(f.bounds), None)
            } else if b0 >= bin {
                (None, Some(f.bounds))
            } else {
                let (a_l, a_r) = (left.half_area(), right.half_area());
                let (nl, nr) = (n_left as f32, n_right as f32);
                let split = a_l * nl + a_r * nr;
                let whole_left = left.union(f.bounds).half_area() * nl + a_r * (nr - 1.0);
                let whole_right = a_l * (nl - 1.0) + right.union(f.bounds).half_area() * nr;
                if n_right > 1 && whole_left < split && whole_left <= whole_right {
                    left = left.union(f.bounds);
                    n_right -= 1;
                    (Some(f.bounds), None)
                } else if n_left > 1 && whole_right < split {
                    right = right.union(f.bounds);
                    n_left -= 1;
                    (None, Some(f.bounds))
                } else {
                    let tri = &self.tris[f.id as usize];
                    match split_fragment(tri, &f.bounds, axis, position) {
                        // Only rounding empties both: keep the fragment whole.
                        (bl, br) if bl.is_empty() && br.is_empty() => (Some(f.bounds), None),
                        (bl, br) => (
                            (!bl.is_empty()).then_some(bl),
                            (!br.is_empty()).then_some(br),
                        ),
                    }
                }
            };
            if let Some(b) = to_left {
                self.scratch[start + l] = Fragment {
                    bounds: b,
                    id: f.id,
                };
                l += 1;
            }
            if let Some(b) = to_right {
                r += 1;
                self.scratch[end - r] = Fragment {
                    bounds: b,
                    id: f.id,
                };
            }
        }
        (l > 0 && r > 0).then_some((l, r))
    }

    /// The cheapest spatial split of the node, or `None` when no plane separates it within its
    /// `slack` spare slots.
    fn best_spatial_split(&mut self, task: &Task, bounds: &Box3, area: f32) -> Option<Priced> {
        let (start, n) = (task.start as usize, task.count);
        let slack = task.end - task.start - n;
        let frags = &self.refs[start..start + n as usize];
        let count = bins_for(self.splits.spatial_bins, n);
        let mut best: Option<Priced> = None;
        for axis in 0..3 {
            let extent = bounds.max[axis] - bounds.min[axis];
            if extent.partial_cmp(&0.0) != Some(core::cmp::Ordering::Greater) {
                continue;
            }
            let width = extent / count as f32;
            let grid = SpatialBins {
                lo: bounds.min[axis],
                width,
                inv_width: 1.0 / width,
                count,
            };
            self.sweep.reset(count);
            let Sweep { bins, parts, .. } = &mut self.sweep;
            for f in frags {
                let b0 = grid.bin(f.bounds.min[axis]);
                let b1 = grid.bin(f.bounds.max[axis]);
                bins[b0].enter += 1;
                bins[b1].exit += 1;
                if b0 == b1 {
                    bins[b0].bounds = bins[b0].bounds.union(f.bounds);
                    continue;
                }
                let tri = &self.tris[f.id as usize];
                let parts = &mut parts[b0..=b1];
                slab_parts(tri, axis, &grid, b0, parts);
                for (bin, part) in bins[b0..=b1].iter_mut().zip(parts.iter()) {
                    bin.bounds = bin.bounds.union(part.intersection(f.bounds));
                }
            }
            // Both children smaller than the node, and their duplicates within the slack.
            let fits = |l: u32, r: u32| l < n && r < n && l + r - n <= slack;
            let Some(c) = self
                .sweep
                .cheapest(count, area, self.splits.constants, fits)
            else {
                continue;
            };
            let split = Split::Spatial {
                axis,
                bin: c.bin,
                grid,
                n_left: c.n_left,
                n_right: c.n_right,
            };
            c.keep_if_cheaper(split, &mut best);
        }
        best
    }

    /// The cheapest object split of the node (box area `area`), or `None` when every centroid
    /// is the same.
    fn best_object_split(&mut self, task: &Task, area: f32) -> Option<Priced> {
        let (start, n) = (task.start as usize, task.count);
        let frags = &self.refs[start..start + n as usize];
        let count = bins_for(self.splits.object_bins, n);
        let centroids = frags
            .iter()
            .fold(Box3::EMPTY, |b, f| b.grown(f.bounds.min + f.bounds.max));
        let mut best: Option<Priced> = None;
        for axis in 0..3 {
            let extent = centroids.max[axis] - centroids.min[axis];
            if extent.partial_cmp(&0.0) != Some(core::cmp::Ordering::Greater) {
                continue;
            }
            // Slightly under `count / extent`, so the largest centroid lands in the last bin.
            let scale = count as f32 * (1.0 - 1e-6) / extent;
            let offset = centroids.min[axis];
            let bins = self.sweep.reset(count);
            for f in frags {
                let b = object_bin(f.centroid2(axis), offset, scale, count - 1);
                bins[b].bounds = bins[b].bounds.union(f.bounds);
                // A whole triangle enters and leaves in its centroid's bin.
                bins[b].enter += 1;
                bins[b].exit += 1;
            }
            let Some(c) = self
                .sweep
                .cheapest(count, area, self.splits.constants, |_, _| true)
            else {
                continue;
            };
            let split = Split::Object {
                axis,
                bin: c.bin,
                offset,
                scale,
            };
            c.keep_if_cheaper(split, &mut best);
        }
        best
    }
}

/// Bins for a node of `n` fragments: `configured`, or half as many as it has fragments when
/// that is fewer, at least 4 (as the binned [`super::Builder`] does). Small nodes are most of a
/// tree, and more bins than fragments only price the same partitions again.
fn bins_for(configured: u32, n: u32) -> usize {
    configured.min((n / 2).max(4)) as usize
}

/// The bin of a doubled centroid `c2` under `offset` and `scale`, at most `last`.
#[inline(always)]
fn object_bin(c2: f32, offset: f32, scale: f32, last: usize) -> usize {
    (((c2 - offset) * scale) as usize).min(last)
}

#[cfg(test)]
mod tests {
    use alloc::vec::Vec;

    use glam::Vec3;

    use super::*;
    use crate::brute_force;
    use crate::builder::Builder;
    use crate::bvh::{Hit, WideBvh8};
    use crate::geometry::Ray;
    use crate::heuristics::Sah;
    use crate::random::Pcg32;
    use crate::test_scenes::soup;

    /// Rays from anywhere in `[-2, 12]^3` in random directions, a third of them short segments.
    fn rays(n: usize, seed: u64) -> Vec<Ray> {
        let mut rng = Pcg32::new(seed);
        let mut v = |a: f32, b: f32| Vec3::new(rng.range(a, b), rng.range(a, b), rng.range(a, b));
        (0..n)
            .filter_map(|i| {
                let (o, d) = (v(-2.0, 12.0), v(-1.0, 1.0));
                let t_max = if i % 3 == 0 { 2.0 } else { f32::INFINITY };
                Ray::segment(o, d, 0.0, t_max).ok()
            })
            .collect()
    }

    fn build(tris: &[Triangle], splits: SpatialSplits) -> Bvh {
        let bvh = SpatialBuilder::new(splits).build(tris).unwrap();
        bvh.validate_split(tris.len(), |i| tris[i as usize].bounds())
            .unwrap();
        bvh
    }

    /// Closest and any hit, binary and 8-wide, agree with brute force bit for bit on scenes of
    /// small triangles crossed by slivers (many split), long crossing triangles, small separate
    /// ones, and one in a plane.
    #[test]
    fn answers_match_brute_force() {
        let mut flat = soup(300, 7, 0.0, 10.0, 2.0);
        for t in &mut flat {
            (t.v0.z, t.v1.z, t.v2.z) = (5.0, 5.0, 5.0);
        }
        let scenes = [
            slivers(),
            soup(400, 1, 0.0, 10.0, 6.0),
            soup(1500, 2, 0.0, 10.0, 1.5),
            flat,
        ];
        let rays = rays(if cfg!(miri) { 20 } else { 400 }, 3);
        for (s, tris) in scenes.iter().enumerate() {
            let bvh = build(tris, SpatialSplits::default());
            if s == 0 {
                assert!(
                    bvh.prim_indices().len() > tris.len(),
                    "no triangle was split"
                );
            }
            assert!(bvh.prim_indices().len() <= tris.len() * 3 / 2);
            let wide = WideBvh8::from_binary(&bvh, tris);
            let mut hits = 0;
            for ray in &rays {
                let expected = brute_force::closest_hit(ray, tris);
                hits += usize::from(expected.is_some());
                assert_eq!(bvh.closest_hit(ray, tris), expected, "scene {s}, {ray:?}");
                assert_eq!(wide.closest_hit(ray), expected, "scene {s}, {ray:?}");
                let any = brute_force::any_hit(ray, tris);
                assert_eq!(bvh.any_hit(ray, tris), any, "scene {s}, {ray:?}");
                assert_eq!(wide.any_hit(ray), any, "scene {s}, {ray:?}");
            }
            assert!(hits > rays.len() / 10, "scene {s}: too few hits ({hits})");
        }
    }

    /// Small triangles crossed by long diagonal slivers (a wall's trim, a cable): splitting the
    /// slivers lowers the SAH cost well below the binned SAH build's; with no budget the tree
    /// names each triangle exactly once.
    #[test]
    fn spatial_splits_lower_the_sah_cost() {
        let tris = slivers();
        let k = CostConstants::default();
        let sah = Builder::sah().build(&tris).unwrap().estimated_cost(&Sah, k);
        let sbvh = build(&tris, SpatialSplits::default());
        let cost = sbvh.estimated_cost(&Sah, k);
        std::eprintln!(
            "SBVH {cost} ({} references) against SAH {sah}",
            sbvh.prim_indices().len()
        );
        assert!(cost < 0.8 * sah, "SBVH {cost} against SAH {sah}");
        let none = SpatialSplits {
            budget: 0.0,
            ..SpatialSplits::default()
        };
        let plain = SpatialBuilder::new(none).build(&tris).unwrap();
        plain
            .validate(tris.len(), |i| tris[i as usize].bounds())
            .unwrap();
    }

    /// 1000 small triangles in `[0, 10]^3` and 40 slivers from corner to corner.
    fn slivers() -> Vec<Triangle> {
        let mut tris = soup(1000, 4, 0.0, 10.0, 1.0);
        let mut rng = Pcg32::new(9);
        for _ in 0..40 {
            let a = Vec3::new(rng.range(0.0, 10.0), rng.range(0.0, 10.0), 0.0);
            let b = Vec3::new(10.0 - a.x, 10.0 - a.y, 10.0);
            tris.push(Triangle::new(a, b, b + Vec3::new(0.05, 0.0, 0.0)));
        }
        tris
    }

    /// A subset keeps its ids, and reinsertion (which moves subtrees, not references) keeps
    /// the answers of a tree with split triangles.
    #[test]
    fn subsets_and_reinsertion_keep_the_answers() {
        let tris = slivers();
        let ids: Vec<u32> = (0..tris.len() as u32).filter(|i| i % 3 != 0).collect();
        let subset: Vec<Triangle> = ids.iter().map(|&i| tris[i as usize]).collect();
        let mut bvh = SpatialBuilder::default().build_subset(&tris, &ids).unwrap();
        assert!(bvh.prim_indices().iter().all(|i| i % 3 != 0));
        crate::builder::reinsert(&mut bvh, &Sah, &Default::default());
        for ray in &rays(300, 10) {
            // `ids` is increasing, so the tie rule (the lower id) picks the same triangle.
            let expected = brute_force::closest_hit(ray, &subset).map(|h| Hit {
                triangle: ids[h.triangle as usize],
                ..h
            });
            assert_eq!(bvh.closest_hit(ray, &tris), expected, "{ray:?}");
        }
        let err = SpatialBuilder::default()
            .build_subset(&tris, &[3, tris.len() as u32])
            .unwrap_err();
        assert!(matches!(err, BuildError::NoSuchPrimitive { .. }), "{err}");
    }

    /// Degenerate scenes end in valid trees: one triangle repeated, points, a single triangle,
    /// nothing; and spatial splits priced everywhere (`alpha = 0`) with a large budget.
    #[test]
    fn degenerate_scenes_build() {
        let t = Triangle::new(Vec3::ZERO, Vec3::X, Vec3::Y);
        let p = Triangle::new(Vec3::ONE, Vec3::ONE, Vec3::ONE);
        let every = SpatialSplits {
            alpha: 0.0,
            budget: 4.0,
            ..SpatialSplits::default()
        };
        for tris in [
            alloc::vec![t; 100],
            alloc::vec![p; 50],
            alloc::vec![t],
            Vec::new(),
        ] {
            for splits in [SpatialSplits::default(), every] {
                let bvh = build(&tris, splits);
                assert_eq!(bvh.is_empty(), tris.is_empty());
                assert!(bvh.max_depth() <= MAX_DEPTH);
            }
        }
        let tris = soup(200, 5, 0.0, 10.0, 8.0);
        let bvh = build(&tris, every);
        for ray in &rays(100, 6) {
            assert_eq!(
                bvh.closest_hit(ray, &tris),
                brute_force::closest_hit(ray, &tris)
            );
        }
    }

    /// Bad triangles and settings are errors naming what is wrong.
    #[test]
    fn bad_input_is_an_error() {
        let mut tris = soup(10, 8, 0.0, 1.0, 0.5);
        tris[6].v1.y = f32::NAN;
        let err = SpatialBuilder::default().build(&tris).unwrap_err();
        assert_eq!(err, BuildError::InvalidPrimitive { index: 6 });
        let bad = [
            SpatialSplits {
                alpha: f32::NAN,
                ..SpatialSplits::default()
            },
            SpatialSplits {
                budget: -0.5,
                ..SpatialSplits::default()
            },
            SpatialSplits {
                spatial_bins: 1,
                ..SpatialSplits::default()
            },
            SpatialSplits {
                max_leaf: 0,
                ..SpatialSplits::default()
            },
        ];
        for splits in bad {
            let err = SpatialBuilder::new(splits).build(&tris[..3]).unwrap_err();
            assert!(
                matches!(err, BuildError::InvalidConfig(_)),
                "{splits:?}: {err}"
            );
        }
    }
}
