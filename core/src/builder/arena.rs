//! The build arena: every buffer a build needs, allocated once and reused.

use alloc::vec::Vec;
use core::ops::Range;

use glam::Vec3;
use wide::f32x4;

use super::config::MAX_BINS;
use super::exhaustive::SUBSETS;
use crate::bvh::MAX_DEPTH;
use crate::geometry::{Aabb, Triangle};
use crate::simd::Aabb4;
use crate::BuildError;

/// One primitive reference: its bounds as two 16-byte lanes `(x, y, z, half the id)`, 32 bytes.
///
/// Every loop of the build reads a primitive's whole box at once (binning grows three bins by it,
/// the partition moves it), so the six bounds and the id share one record: two aligned loads, one
/// 32-byte swap, where seven separate arrays would need scattered swaps and gathers.
///
/// Lane 3 of each corner holds 16 of the id's bits as the mantissa of a float in `[1, 2)`
/// ([`ID_LANE_ONE`]). The build's 4-wide arithmetic carries lane 3 along, and raw id bits would
/// be subnormal floats there, each operation on them a slow microcode assist (measured:
/// benches/RESULTS.md, section Build speed (single and multi thread)). Sums and differences of
/// two such floats are again normal or zero, so no garbage lane turns subnormal either.
#[derive(Clone, Copy, Debug, Default, PartialEq, bytemuck::Pod, bytemuck::Zeroable)]
#[repr(C, align(16))]
pub(crate) struct PrimRef {
    /// `min.x, min.y, min.z`, then the id's upper 16 bits (see [`ID_LANE_ONE`]).
    lo: [f32; 4],
    /// `max.x, max.y, max.z`, then the id's lower 16 bits.
    hi: [f32; 4],
}

/// The bits of `1.0f32`: lane 3 of a [`PrimRef`] corner is `ID_LANE_ONE | (16 id bits)`, a
/// normal float in `[1, 2)` whatever the id.
const ID_LANE_ONE: u32 = 0x3f80_0000;

impl PrimRef {
    /// All zero: the filler of fixed scratch arrays.
    pub const ZERO: PrimRef = PrimRef {
        lo: [0.0; 4],
        hi: [0.0; 4],
    };

    #[inline(always)]
    pub(crate) fn new(id: u32, b: &Aabb) -> Self {
        Self::from_corners(id, b.min.to_array(), b.max.to_array())
    }

    /// The reference of primitive `id` with corners `lo` and `hi`.
    #[inline(always)]
    fn from_corners(id: u32, lo: [f32; 3], hi: [f32; 3]) -> Self {
        Self {
            lo: [
                lo[0],
                lo[1],
                lo[2],
                f32::from_bits(ID_LANE_ONE | (id >> 16)),
            ],
            hi: [
                hi[0],
                hi[1],
                hi[2],
                f32::from_bits(ID_LANE_ONE | (id & 0xffff)),
            ],
        }
    }

    /// The lower corner as a lane; lane 3 holds half the id and must be ignored.
    #[inline(always)]
    pub fn lo4(&self) -> f32x4 {
        f32x4::from(self.lo)
    }

    /// The upper corner as a lane; lane 3 holds half the id and must be ignored.
    #[inline(always)]
    pub fn hi4(&self) -> f32x4 {
        f32x4::from(self.hi)
    }

    /// Twice the centroid along `axis` only.
    #[inline(always)]
    pub fn centroid2_axis(&self, axis: usize) -> f32 {
        self.lo[axis] + self.hi[axis]
    }

    /// Twice the centroid as a lane; lane 3 holds garbage (a normal float) and must be ignored.
    #[inline(always)]
    pub fn centroid2_4(&self) -> f32x4 {
        self.lo4() + self.hi4()
    }

    /// The primitive id.
    #[inline(always)]
    pub fn id(&self) -> u32 {
        ((self.lo[3].to_bits() & 0xffff) << 16) | (self.hi[3].to_bits() & 0xffff)
    }
}

/// The primitive references of a build, permuted in place into leaf order.
#[derive(Debug, Default)]
pub(crate) struct PrimRefs {
    refs: Vec<PrimRef>,
}

impl PrimRefs {
    fn clear(&mut self) {
        self.refs.clear();
    }

    #[inline(always)]
    pub fn len(&self) -> usize {
        self.refs.len()
    }

    #[inline(always)]
    pub fn get(&self, i: usize) -> &PrimRef {
        &self.refs[i]
    }

    /// Slots `start..start + count`.
    #[inline(always)]
    pub fn slots(&self, start: usize, count: usize) -> &[PrimRef] {
        &self.refs[start..start + count]
    }

    /// Slots `start..start + count`, to reorder.
    #[inline(always)]
    pub fn slots_mut(&mut self, start: usize, count: usize) -> &mut [PrimRef] {
        &mut self.refs[start..start + count]
    }

    /// The ids in slot order.
    pub fn ids(&self) -> impl Iterator<Item = u32> + '_ {
        self.refs.iter().map(PrimRef::id)
    }

    /// Twice the centroid of slot `i` along `axis` only.
    #[inline(always)]
    pub fn centroid2_axis(&self, i: usize, axis: usize) -> f32 {
        self.refs[i].centroid2_axis(axis)
    }

    /// The bounds of slot `i`.
    #[inline(always)]
    pub fn bounds(&self, i: usize) -> Aabb {
        let r = &self.refs[i];
        Aabb::new(
            Vec3::new(r.lo[0], r.lo[1], r.lo[2]),
            Vec3::new(r.hi[0], r.hi[1], r.hi[2]),
        )
    }

    #[inline(always)]
    pub fn swap(&mut self, i: usize, j: usize) {
        self.refs.swap(i, j);
    }
}

/// One bin of a sweep: how many centroids fell in it and the bounds of their primitives, kept as
/// 4-wide lanes `(x, y, z, 0)` so growing it by a primitive is one `minps` and one `maxps`.
///
/// Padded to 64 bytes: the binning loop addresses a bin by its index shifted left by 6, one
/// instruction per axis where 48 bytes took two (see [`super::binning::BinOffsets`]).
#[derive(Clone, Copy, Debug)]
#[repr(align(64))]
pub(crate) struct Bin {
    pub min: f32x4,
    pub max: f32x4,
    pub count: u32,
}

impl Bin {
    pub const EMPTY: Bin = Bin {
        min: f32x4::splat(f32::INFINITY),
        max: f32x4::splat(f32::NEG_INFINITY),
        count: 0,
    };

    /// Adds a primitive's bounds (finite lanes, so the NaN-unaware min/max are exact).
    #[inline(always)]
    pub fn grow(&mut self, lo: f32x4, hi: f32x4) {
        self.min = self.min.fast_min(lo);
        self.max = self.max.fast_max(hi);
        self.count += 1;
    }

    /// Adds another bin.
    #[inline(always)]
    pub fn merge(&mut self, other: &Bin) {
        self.min = self.min.fast_min(other.min);
        self.max = self.max.fast_max(other.max);
        self.count += other.count;
    }
}

/// One side of every bin boundary of a sweep: boundary `i`'s box as `(x, y, z, _)` lanes and its
/// count. Padded by three entries so the last group of four can always be loaded; four boxes are
/// transposed into SoA lanes for pricing.
#[derive(Debug)]
pub(crate) struct SweepSide {
    min: [f32x4; SWEEP_LANES],
    max: [f32x4; SWEEP_LANES],
    pub count: [u32; SWEEP_LANES],
}

const SWEEP_LANES: usize = MAX_BINS as usize + 4;

impl SweepSide {
    const fn new() -> Self {
        Self {
            min: [f32x4::splat(f32::INFINITY); SWEEP_LANES],
            max: [f32x4::splat(f32::NEG_INFINITY); SWEEP_LANES],
            count: [0; SWEEP_LANES],
        }
    }

    #[inline(always)]
    pub fn set(&mut self, i: usize, bin: &Bin) {
        self.min[i] = bin.min;
        self.max[i] = bin.max;
        self.count[i] = bin.count;
    }

    #[inline(always)]
    pub fn bounds(&self, i: usize) -> Aabb {
        let (lo, hi) = (self.min[i].to_array(), self.max[i].to_array());
        Aabb::new(
            Vec3::new(lo[0], lo[1], lo[2]),
            Vec3::new(hi[0], hi[1], hi[2]),
        )
    }

    /// The measures and counts of boundaries `i..i + 4`, all inside a node whose
    /// [`CostModel::hint`](crate::heuristics::CostModel::hint) is `hint`.
    #[inline(always)]
    pub fn lanes<M: crate::heuristics::CostModel>(
        &self,
        i: usize,
        model: &M,
        hint: u32,
    ) -> (f32x4, f32x4) {
        let lanes = |v: &[f32x4; SWEEP_LANES]| [v[i], v[i + 1], v[i + 2], v[i + 3]];
        let b4 = soa(lanes(&self.min), lanes(&self.max));
        let c = &self.count;
        let n = f32x4::from([
            c[i] as f32,
            c[i + 1] as f32,
            c[i + 2] as f32,
            c[i + 3] as f32,
        ]);
        (model.measure4_hinted(&b4, hint), n)
    }
}

/// Four boxes given as `(x, y, z, _)` corner lanes, transposed into SoA lanes for pricing.
#[inline(always)]
pub(crate) fn soa(mins: [f32x4; 4], maxs: [f32x4; 4]) -> Aabb4 {
    let [min_x, min_y, min_z, _] = f32x4::transpose(mins);
    let [max_x, max_y, max_z, _] = f32x4::transpose(maxs);
    Aabb4 {
        min: [min_x, min_y, min_z],
        max: [max_x, max_y, max_z],
    }
}

/// Scratch of one axis's sweep: both sides of every boundary.
#[derive(Debug)]
pub(crate) struct Sweep {
    pub left: SweepSide,
    pub right: SweepSide,
}

/// A node waiting to be processed: its exact bounds, slot range, depth and centroid bounds
/// (doubled, like [`PrimRefs::centroid2`]).
#[derive(Clone, Copy, Debug)]
pub(crate) struct Task {
    pub node: u32,
    /// The node's exact bounds (nodes store them padded).
    pub bounds: Aabb,
    pub start: u32,
    pub count: u32,
    pub depth: u32,
    pub centroids: Aabb,
    /// The node's measure under the builder's cost model when its parent's split already took it
    /// (see [`super::Subtree::measure`]); `None` makes the node take it.
    pub measure: Option<f32>,
}

/// Pending tasks of a build: the builder descends into one child and defers the other, so they are
/// at most one per level.
const MAX_TASKS: usize = MAX_DEPTH as usize + 2;

/// Every buffer a build uses, sized for at most `capacity` primitives when it is made. Load the
/// primitives with [`BuildArena::load_triangles`] or [`BuildArena::push`], then hand the arena to
/// [`super::Builder::build_into`]. One arena serves any number of builds (over many influence
/// areas, say): loading clears it without freeing its memory.
#[derive(Debug)]
pub struct BuildArena {
    pub(crate) refs: PrimRefs,
    pub(crate) bins: [[Bin; MAX_BINS as usize]; 3],
    /// A second set of bins, for large nodes binned in two interleaved halves.
    pub(crate) bins2: [[Bin; MAX_BINS as usize]; 3],
    pub(crate) sweep: Sweep,
    /// The boxes of every subset of a node priced exhaustively.
    pub(crate) subsets: [Bin; SUBSETS],
    pub(crate) tasks: Vec<Task>,
    pub(crate) bounds: Aabb,
    pub(crate) centroids: Aabb,
    capacity: usize,
}

impl BuildArena {
    /// An arena for builds over up to `capacity` primitives: 32 bytes per primitive, plus about
    /// 4.75 KiB of bins and scratch. Like `Vec::with_capacity`, it panics past `isize::MAX` bytes
    /// and aborts when the allocation fails; [`BuildArena::try_with_capacity`] reports both.
    pub fn with_capacity(capacity: usize) -> Self {
        Self::from_buffers(
            Vec::with_capacity(capacity),
            Vec::with_capacity(MAX_TASKS),
            capacity,
        )
    }

    /// [`BuildArena::with_capacity`], returning the allocation's failure instead of panicking or
    /// aborting: for a host that sizes the arena from untrusted scene data.
    pub fn try_with_capacity(capacity: usize) -> Result<Self, alloc::collections::TryReserveError> {
        let mut refs = Vec::new();
        refs.try_reserve_exact(capacity)?;
        let mut tasks = Vec::new();
        tasks.try_reserve_exact(MAX_TASKS)?;
        Ok(Self::from_buffers(refs, tasks, capacity))
    }

    fn from_buffers(refs: Vec<PrimRef>, tasks: Vec<Task>, capacity: usize) -> Self {
        Self {
            refs: PrimRefs { refs },
            bins: [[Bin::EMPTY; MAX_BINS as usize]; 3],
            bins2: [[Bin::EMPTY; MAX_BINS as usize]; 3],
            sweep: Sweep {
                left: SweepSide::new(),
                right: SweepSide::new(),
            },
            subsets: [Bin::EMPTY; SUBSETS],
            tasks,
            bounds: Aabb::EMPTY,
            centroids: Aabb::EMPTY,
            capacity,
        }
    }

    /// How many primitives the arena holds room for.
    pub fn capacity(&self) -> usize {
        self.capacity
    }

    /// How many primitives are loaded.
    pub fn len(&self) -> usize {
        self.refs.len()
    }

    /// True when no primitive is loaded.
    pub fn is_empty(&self) -> bool {
        self.refs.len() == 0
    }

    /// The id and bounds in primitive slot `slot` (in the order a build left them), or `None`
    /// past the loaded primitives.
    pub fn prim(&self, slot: usize) -> Option<(u32, Aabb)> {
        (slot < self.len()).then(|| (self.refs.get(slot).id(), self.refs.bounds(slot)))
    }

    /// Forgets the loaded primitives, keeping the memory.
    pub fn clear(&mut self) {
        self.refs.clear();
        self.bounds = Aabb::EMPTY;
        self.centroids = Aabb::EMPTY;
    }

    /// Adds a primitive with id `id` and bounds `bounds`. Fails when the arena is full or the
    /// bounds are empty or not finite (a NaN or infinite vertex).
    pub fn push(&mut self, id: u32, bounds: Aabb) -> Result<(), BuildError> {
        if self.refs.len() >= self.capacity {
            return Err(BuildError::ArenaFull {
                capacity: self.capacity,
            });
        }
        if !bounds.is_valid() {
            return Err(BuildError::InvalidPrimitive { index: id });
        }
        self.refs.refs.push(PrimRef::new(id, &bounds));
        self.bounds = self.bounds.union(bounds);
        self.centroids = self.centroids.grown(bounds.min + bounds.max);
        Ok(())
    }

    /// Clears the arena and loads the primitives in `other`'s slots `slots` (ids and bounds, in
    /// slot order): a threaded build's subtree job copies its primitives this way, one block
    /// copy and one 4-wide bounds pass instead of a checked push per primitive. Fails when they
    /// do not fit or `slots` lies outside `other`'s primitives.
    pub fn load_slots(
        &mut self,
        other: &BuildArena,
        slots: Range<usize>,
    ) -> Result<(), BuildError> {
        self.clear();
        let refs = other
            .refs
            .refs
            .get(slots)
            .ok_or(BuildError::InvalidConfig("slots outside the source arena"))?;
        if refs.len() > self.capacity {
            return Err(BuildError::ArenaFull {
                capacity: self.capacity,
            });
        }
        self.refs.refs.extend_from_slice(refs);
        let mut acc = LoadedBounds::EMPTY;
        // The source validated these bounds. Lane 3 (the id's halves) is dropped by lanes_to_aabb.
        for r in refs {
            let (lo, hi) = (r.lo4(), r.hi4());
            let centroid = lo + hi;
            acc.min = acc.min.fast_min(lo);
            acc.max = acc.max.fast_max(hi);
            acc.centroid_min = acc.centroid_min.fast_min(centroid);
            acc.centroid_max = acc.centroid_max.fast_max(centroid);
        }
        self.bounds = lanes_to_aabb(acc.min, acc.max);
        self.centroids = lanes_to_aabb(acc.centroid_min, acc.centroid_max);
        Ok(())
    }

    /// Clears the arena and loads `tris`, triangle `i` with id `i`.
    pub fn load_triangles(&mut self, tris: &[Triangle]) -> Result<(), BuildError> {
        self.load_triangles_with(tris, |load| load.run())
    }

    /// [`BuildArena::load_triangles`] with the work handed to `run`, for threaded hosts: `run`
    /// gets the whole load as one [`TriangleLoad`], may cut it into disjoint parts with
    /// [`TriangleLoad::split_at`], runs each part ([`TriangleLoad::run`]) on any thread and
    /// merges their [`LoadedBounds`] ([`LoadedBounds::merge`]). Every part must run: the arena
    /// holds what they wrote. Any cut gives the same arena as the serial load, and the same error
    /// (the first invalid triangle's).
    pub fn load_triangles_with<R>(&mut self, tris: &[Triangle], run: R) -> Result<(), BuildError>
    where
        R: FnOnce(TriangleLoad<'_>) -> Result<LoadedBounds, BuildError>,
    {
        if tris.len() > self.capacity || tris.len() > u32::MAX as usize {
            // The error path: report exactly what loading one triangle at a time reports.
            return self.load_triangle_subset(tris, 0..tris.len() as u64);
        }
        self.clear();
        // Zeroed slots, overwritten by the parts; within capacity, so no allocation.
        self.refs.refs.resize(tris.len(), PrimRef::default());
        let loaded = run(TriangleLoad {
            tris,
            first_id: 0,
            slots: &mut self.refs.refs,
        });
        match loaded {
            Ok(b) => {
                (self.bounds, self.centroids) = (
                    lanes_to_aabb(b.min, b.max),
                    lanes_to_aabb(b.centroid_min, b.centroid_max),
                );
                Ok(())
            }
            Err(e) => {
                self.clear();
                Err(e)
            }
        }
    }

    /// Clears the arena and loads the triangles whose ids `ids` yields (a local BVH's subset).
    /// On an error the arena is left empty, as after [`BuildArena::clear`], never with the
    /// triangles before the bad one.
    ///
    /// Each id should appear once: a repeated id loads its triangle twice, and the tree then
    /// holds it in two leaves (queries still answer right, and [`crate::bvh::Bvh::validate`]
    /// reports `PrimitiveCount`). The check would need a set as large as `tris`, which the arena
    /// does not keep.
    pub fn load_triangle_subset<I>(&mut self, tris: &[Triangle], ids: I) -> Result<(), BuildError>
    where
        I: IntoIterator,
        I::Item: TryInto<u32>,
    {
        self.clear();
        let loaded = self.push_subset(tris, ids);
        if loaded.is_err() {
            self.clear();
        }
        loaded
    }

    /// [`BuildArena::load_triangle_subset`]'s loop, stopping at the first error.
    fn push_subset<I>(&mut self, tris: &[Triangle], ids: I) -> Result<(), BuildError>
    where
        I: IntoIterator,
        I::Item: TryInto<u32>,
    {
        if tris.len() > u32::MAX as usize {
            return Err(BuildError::TooManyPrimitives);
        }
        let missing = |index| BuildError::NoSuchPrimitive {
            index,
            count: tris.len(),
        };
        for id in ids {
            let id: u32 = id.try_into().map_err(|_| missing(None))?;
            let tri = tris.get(id as usize).ok_or(missing(Some(id)))?;
            // `Vec3::min`/`max` drop a NaN operand, so the bounds alone could hide one.
            if !tri.is_finite() {
                return Err(BuildError::InvalidPrimitive { index: id });
            }
            self.push(id, tri.bounds())?;
        }
        Ok(())
    }
}

/// A part of a triangle load ([`BuildArena::load_triangles_with`]): triangles and the arena slots
/// they fill, starting at id `first_id`.
#[derive(Debug)]
pub struct TriangleLoad<'a> {
    tris: &'a [Triangle],
    first_id: u32,
    slots: &'a mut [PrimRef],
}

impl<'a> TriangleLoad<'a> {
    /// Triangles in this part.
    pub fn len(&self) -> usize {
        self.tris.len()
    }

    /// True when the part holds no triangle.
    pub fn is_empty(&self) -> bool {
        self.tris.is_empty()
    }

    /// Cuts the part into its first `mid` triangles and the rest (`mid` is clamped to the length).
    pub fn split_at(self, mid: usize) -> (TriangleLoad<'a>, TriangleLoad<'a>) {
        let mid = mid.min(self.tris.len());
        let (ta, tb) = self.tris.split_at(mid);
        let (sa, sb) = self.slots.split_at_mut(mid);
        (
            TriangleLoad {
                tris: ta,
                first_id: self.first_id,
                slots: sa,
            },
            TriangleLoad {
                tris: tb,
                first_id: self.first_id + mid as u32,
                slots: sb,
            },
        )
    }

    /// Loads the part: each triangle's bounds and id into its slot. Fails on the part's first
    /// triangle with a NaN or infinite coordinate.
    pub fn run(self) -> Result<LoadedBounds, BuildError> {
        let mut acc = LoadedBounds::EMPTY;
        let v = |p: Vec3| f32x4::from([p.x, p.y, p.z, 0.0]);
        for (k, (t, slot)) in self.tris.iter().zip(self.slots.iter_mut()).enumerate() {
            let (a, b, c) = (v(t.v0), v(t.v1), v(t.v2));
            // `0 * x` is (signed) 0 for a finite `x` and NaN otherwise, and NaN survives the
            // sums: one test for all nine coordinates. Finite lanes make the NaN-unaware
            // min/max exact.
            let zero = f32x4::ZERO;
            if (zero * a + zero * b + zero * c).simd_ne(zero).any() {
                return Err(BuildError::InvalidPrimitive {
                    index: self.first_id + k as u32,
                });
            }
            let lo = a.fast_min(b).fast_min(c);
            let hi = a.fast_max(b).fast_max(c);
            let (l, h) = (lo.to_array(), hi.to_array());
            *slot = PrimRef::from_corners(
                self.first_id + k as u32,
                [l[0], l[1], l[2]],
                [h[0], h[1], h[2]],
            );
            let centroid = lo + hi;
            acc.min = acc.min.fast_min(lo);
            acc.max = acc.max.fast_max(hi);
            acc.centroid_min = acc.centroid_min.fast_min(centroid);
            acc.centroid_max = acc.centroid_max.fast_max(centroid);
        }
        Ok(acc)
    }
}

/// The bounds and (doubled) centroid bounds of the triangles a [`TriangleLoad`] part loaded, as
/// `(x, y, z, 0)` lanes. Min and max are exact in any order, so merged parts give the serial
/// load's bounds bit for bit.
#[derive(Clone, Copy, Debug)]
pub struct LoadedBounds {
    min: f32x4,
    max: f32x4,
    centroid_min: f32x4,
    centroid_max: f32x4,
}

impl LoadedBounds {
    const EMPTY: LoadedBounds = LoadedBounds {
        min: f32x4::splat(f32::INFINITY),
        max: f32x4::splat(f32::NEG_INFINITY),
        centroid_min: f32x4::splat(f32::INFINITY),
        centroid_max: f32x4::splat(f32::NEG_INFINITY),
    };

    /// The bounds of two parts together; of two failures, the one at the lower index (the one a
    /// serial load reports).
    pub fn merge(
        a: Result<LoadedBounds, BuildError>,
        b: Result<LoadedBounds, BuildError>,
    ) -> Result<LoadedBounds, BuildError> {
        match (a, b) {
            (Ok(a), Ok(b)) => Ok(LoadedBounds {
                min: a.min.fast_min(b.min),
                max: a.max.fast_max(b.max),
                centroid_min: a.centroid_min.fast_min(b.centroid_min),
                centroid_max: a.centroid_max.fast_max(b.centroid_max),
            }),
            (
                Err(BuildError::InvalidPrimitive { index: i }),
                Err(BuildError::InvalidPrimitive { index: j }),
            ) => Err(BuildError::InvalidPrimitive { index: i.min(j) }),
            (Err(e), _) | (Ok(_), Err(e)) => Err(e),
        }
    }
}

/// An [`Aabb`] from `(x, y, z, _)` lanes.
#[inline(always)]
pub(crate) fn lanes_to_aabb(lo: f32x4, hi: f32x4) -> Aabb {
    let (lo, hi) = (lo.to_array(), hi.to_array());
    Aabb::new(
        Vec3::new(lo[0], lo[1], lo[2]),
        Vec3::new(hi[0], hi[1], hi[2]),
    )
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::bvh::Bvh;

    /// A load that fails leaves the arena empty: a later build must not quietly run over the
    /// triangles loaded before the error.
    #[test]
    fn sizes_beyond_memory_are_errors_when_asked_for() {
        assert!(BuildArena::try_with_capacity(usize::MAX / 4).is_err());
        assert!(Bvh::try_with_capacity(usize::MAX / 4).is_err());
        let tris = crate::test_scenes::soup(50, 3, -5.0, 5.0, 1.0);
        let (mut arena, mut out) = (
            BuildArena::try_with_capacity(tris.len()).unwrap(),
            Bvh::try_with_capacity(tris.len()).unwrap(),
        );
        assert_eq!(arena.capacity(), tris.len());
        arena.load_triangles(&tris).unwrap();
        crate::builder::Builder::sah()
            .build_into(&mut arena, &mut out)
            .unwrap();
        assert_eq!(out, crate::builder::Builder::sah().build(&tris).unwrap());
    }

    #[test]
    fn a_failed_load_leaves_the_arena_empty() {
        let t = |x: f32| {
            Triangle::new(
                Vec3::new(x, 0.0, 0.0),
                Vec3::new(x + 1.0, 0.0, 0.0),
                Vec3::new(x, 1.0, 0.0),
            )
        };
        let mut bad = [t(0.0), t(2.0), t(4.0)];
        let mut arena = BuildArena::with_capacity(2);
        assert!(matches!(
            arena.load_triangles(&bad),
            Err(BuildError::ArenaFull { .. })
        ));
        assert!(arena.is_empty());
        bad[1].v1.x = f32::NAN;
        let mut arena = BuildArena::with_capacity(3);
        assert_eq!(
            arena.load_triangles(&bad),
            Err(BuildError::InvalidPrimitive { index: 1 })
        );
        assert!(arena.is_empty());
        assert!(arena.load_triangle_subset(&bad, [0u32, 1]).is_err());
        assert!(arena.is_empty());
        // An id past the slice, or one that is no u32, names no triangle (not a bad one).
        let missing = |index| BuildError::NoSuchPrimitive { index, count: 3 };
        assert_eq!(
            arena.load_triangle_subset(&bad, [0u32, 7]),
            Err(missing(Some(7)))
        );
        assert!(arena.is_empty() && arena.bounds.is_empty());
        assert_eq!(
            arena.load_triangle_subset(&bad, [0i64, -1]),
            Err(missing(None))
        );
        let shown = alloc::format!("{}", missing(Some(7)));
        assert!(
            shown.contains("id 7 names no triangle (the slice holds 3, ids 0 to 2)"),
            "{shown}"
        );
        let none = BuildError::NoSuchPrimitive {
            index: Some(0),
            count: 0,
        };
        let shown = alloc::format!("{none}");
        assert!(
            shown.ends_with("names no triangle (the slice is empty)"),
            "{shown}"
        );
        arena.load_triangle_subset(&bad, [2u32, 0]).unwrap();
        assert_eq!(arena.len(), 2);
    }

    /// Every id comes back, and lane 3 of both corners and of the centroid is a normal float
    /// (no subnormal for the 4-wide arithmetic to trip on).
    #[test]
    fn prim_ref_ids_round_trip_through_normal_lanes() {
        let b = Aabb::new(Vec3::new(-1.0, 0.0, 2.0), Vec3::new(1.0, 3.0, 4.0));
        for id in [
            0,
            1,
            2,
            0xffff,
            0x1_0000,
            0x12_3456,
            0x7f80_0001,
            u32::MAX - 1,
            u32::MAX,
        ] {
            let r = PrimRef::new(id, &b);
            assert_eq!(r.id(), id);
            for lane in [r.lo4(), r.hi4(), r.centroid2_4()] {
                assert!(lane.to_array()[3].is_normal(), "id {id:#x}: {lane:?}");
            }
            assert_eq!(lanes_to_aabb(r.lo4(), r.hi4()), b);
        }
    }
}
