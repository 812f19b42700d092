//! The build arena: every buffer a build needs, allocated once and reused.

use alloc::vec::Vec;

use glam::Vec3;
use wide::f32x4;

use super::config::MAX_BINS;
use crate::bvh::MAX_DEPTH;
use crate::geometry::{Aabb, Triangle};
use crate::simd::Aabb4;
use crate::BuildError;

/// Primitive references as a structure of arrays: the binning loop streams through the bounds, and
/// the partition swaps entries in place, so the working set of a node is always contiguous.
#[derive(Debug, Default)]
pub(crate) struct PrimRefs {
    /// Primitive ids, permuted into leaf order by the build.
    pub ids: Vec<u32>,
    /// Lower corners per axis.
    pub lo: [Vec<f32>; 3],
    /// Upper corners per axis.
    pub hi: [Vec<f32>; 3],
}

impl PrimRefs {
    fn with_capacity(n: usize) -> Self {
        let v = || Vec::<f32>::with_capacity(n);
        Self {
            ids: Vec::with_capacity(n),
            lo: [v(), v(), v()],
            hi: [v(), v(), v()],
        }
    }

    fn clear(&mut self) {
        self.ids.clear();
        for a in 0..3 {
            self.lo[a].clear();
            self.hi[a].clear();
        }
    }

    /// Twice the centroid of primitive slot `i` (the factor 1/2 cancels in every use).
    #[inline(always)]
    pub fn centroid2(&self, i: usize) -> Vec3 {
        Vec3::new(
            self.lo[0][i] + self.hi[0][i],
            self.lo[1][i] + self.hi[1][i],
            self.lo[2][i] + self.hi[2][i],
        )
    }

    /// Twice the centroid of slot `i` along `axis` only.
    #[inline(always)]
    pub fn centroid2_axis(&self, i: usize, axis: usize) -> f32 {
        self.lo[axis][i] + self.hi[axis][i]
    }

    /// The bounds of slot `i`.
    #[inline(always)]
    pub fn bounds(&self, i: usize) -> Aabb {
        Aabb::new(
            Vec3::new(self.lo[0][i], self.lo[1][i], self.lo[2][i]),
            Vec3::new(self.hi[0][i], self.hi[1][i], self.hi[2][i]),
        )
    }

    #[inline(always)]
    pub fn swap(&mut self, i: usize, j: usize) {
        self.ids.swap(i, j);
        for a in 0..3 {
            self.lo[a].swap(i, j);
            self.hi[a].swap(i, j);
        }
    }
}

/// One bin of a sweep: how many centroids fell in it and the bounds of their primitives, kept as
/// 4-wide lanes `(x, y, z, 0)` so growing it by a primitive is one `minps` and one `maxps`.
#[derive(Clone, Copy, Debug)]
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

/// One side of every bin boundary of a sweep, as SoA lanes: boundary `i`'s box and count. Padded
/// by three lanes so the last group of four can always be loaded.
#[derive(Debug)]
pub(crate) struct SweepSide {
    min: [[f32; SWEEP_LANES]; 3],
    max: [[f32; SWEEP_LANES]; 3],
    pub count: [u32; SWEEP_LANES],
}

const SWEEP_LANES: usize = MAX_BINS as usize + 4;

impl SweepSide {
    const fn new() -> Self {
        Self {
            min: [[0.0; SWEEP_LANES]; 3],
            max: [[0.0; SWEEP_LANES]; 3],
            count: [0; SWEEP_LANES],
        }
    }

    #[inline(always)]
    pub fn set(&mut self, i: usize, bin: &Bin) {
        let (lo, hi) = (bin.min.to_array(), bin.max.to_array());
        for k in 0..3 {
            self.min[k][i] = lo[k];
            self.max[k][i] = hi[k];
        }
        self.count[i] = bin.count;
    }

    #[inline(always)]
    pub fn bounds(&self, i: usize) -> Aabb {
        Aabb::new(
            Vec3::new(self.min[0][i], self.min[1][i], self.min[2][i]),
            Vec3::new(self.max[0][i], self.max[1][i], self.max[2][i]),
        )
    }

    /// The measures and counts of boundaries `i..i + 4`.
    #[inline(always)]
    pub fn lanes<M: crate::heuristics::CostModel>(&self, i: usize, model: &M) -> (f32x4, f32x4) {
        let lane = |a: &[f32; SWEEP_LANES]| -> [f32; 4] { [a[i], a[i + 1], a[i + 2], a[i + 3]] };
        let b4 = Aabb4::load(
            &[lane(&self.min[0]), lane(&self.min[1]), lane(&self.min[2])],
            &[lane(&self.max[0]), lane(&self.max[1]), lane(&self.max[2])],
        );
        let c = &self.count;
        let n = f32x4::from([
            c[i] as f32,
            c[i + 1] as f32,
            c[i + 2] as f32,
            c[i + 3] as f32,
        ]);
        (model.measure4(&b4), n)
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
}

/// Every buffer a build uses, sized for at most `capacity` primitives when it is made. Load the
/// primitives with [`BuildArena::load_triangles`] or [`BuildArena::push`], then hand the arena to
/// [`super::Builder::build_into`]. One arena serves any number of builds (over many influence
/// areas, say): loading clears it without freeing its memory.
#[derive(Debug)]
pub struct BuildArena {
    pub(crate) refs: PrimRefs,
    pub(crate) bins: [[Bin; MAX_BINS as usize]; 3],
    pub(crate) sweep: Sweep,
    pub(crate) tasks: Vec<Task>,
    pub(crate) bounds: Aabb,
    pub(crate) centroids: Aabb,
    capacity: usize,
}

impl BuildArena {
    /// An arena for builds over up to `capacity` primitives.
    pub fn with_capacity(capacity: usize) -> Self {
        Self {
            refs: PrimRefs::with_capacity(capacity),
            bins: [[Bin::EMPTY; MAX_BINS as usize]; 3],
            sweep: Sweep {
                left: SweepSide::new(),
                right: SweepSide::new(),
            },
            // The builder descends into one child and defers the other, so pending tasks are at
            // most one per level.
            tasks: Vec::with_capacity(MAX_DEPTH as usize + 2),
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
        self.refs.ids.len()
    }

    /// True when no primitive is loaded.
    pub fn is_empty(&self) -> bool {
        self.refs.ids.is_empty()
    }

    /// The id and bounds in primitive slot `slot` (in the order a build left them), or `None`
    /// past the loaded primitives.
    pub fn prim(&self, slot: usize) -> Option<(u32, Aabb)> {
        (slot < self.len()).then(|| (self.refs.ids[slot], self.refs.bounds(slot)))
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
        if self.refs.ids.len() >= self.capacity {
            return Err(BuildError::ArenaFull {
                capacity: self.capacity,
            });
        }
        if !bounds.is_valid() {
            return Err(BuildError::InvalidPrimitive { index: id });
        }
        self.refs.ids.push(id);
        for a in 0..3 {
            self.refs.lo[a].push(bounds.min[a]);
            self.refs.hi[a].push(bounds.max[a]);
        }
        self.bounds = self.bounds.union(bounds);
        self.centroids = self.centroids.grown(bounds.min + bounds.max);
        Ok(())
    }

    /// Clears the arena and loads `tris`, triangle `i` with id `i`.
    pub fn load_triangles(&mut self, tris: &[Triangle]) -> Result<(), BuildError> {
        self.load_triangle_subset(tris, 0..tris.len() as u64)
    }

    /// Clears the arena and loads the triangles whose ids `ids` yields (a local BVH's subset).
    pub fn load_triangle_subset<I>(&mut self, tris: &[Triangle], ids: I) -> Result<(), BuildError>
    where
        I: IntoIterator,
        I::Item: TryInto<u32>,
    {
        self.clear();
        if tris.len() > u32::MAX as usize {
            return Err(BuildError::TooManyPrimitives);
        }
        for id in ids {
            let id: u32 = id.try_into().map_err(|_| BuildError::TooManyPrimitives)?;
            let tri = tris
                .get(id as usize)
                .ok_or(BuildError::InvalidPrimitive { index: id })?;
            // `Vec3::min`/`max` drop a NaN operand, so the bounds alone could hide one.
            if !tri.is_finite() {
                return Err(BuildError::InvalidPrimitive { index: id });
            }
            self.push(id, tri.bounds())?;
        }
        Ok(())
    }
}
