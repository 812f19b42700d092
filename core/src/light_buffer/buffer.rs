//! The light buffer itself: the finest grid of cells over the cube map, each naming the tree of
//! the quadtree cell it lies in, and the query.

use alloc::vec::Vec;

use wide::f32x4;

use super::cell::{face_coords, FACES};
use super::source::LightSource;
use super::subdivide::LightBufferBuilder;
use crate::bvh::{ClosestHitEdges, Counters, Hit, TraversalStats, WideBvh8};
use crate::geometry::{Ray, Triangle, TriangleEdges};
use crate::BuildError;

/// A grid cell the light does not illuminate: its segments are not the buffer's to answer.
pub(crate) const DARK: u32 = u32::MAX;
/// A grid cell whose segments can reach no triangle.
pub(crate) const CLEAR: u32 = u32::MAX - 1;

/// How a light buffer subdivides its cube map.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct LightBufferOptions {
    /// The finest level: each face is a grid of `2^max_level` cells a side (at most 8).
    pub max_level: u32,
    /// A cell that reaches at most this many triangles is not subdivided.
    pub leaf_triangles: u32,
    /// A face stops subdividing once its cells hold this many triangle references per triangle
    /// the whole face reaches: a bound on memory and build time for scenes where every cell
    /// reaches much.
    pub reference_budget: f32,
}

/// The defaults (depth 4, 16 x 16 cells a face; leaves of 64 triangles) trade lookups for
/// memory: finer grids with smaller leaves cut a little more work per ray, for twice the
/// references, and lose on incoherent rays to cache misses in a larger forest.
impl Default for LightBufferOptions {
    fn default() -> Self {
        Self {
            max_level: 4,
            leaf_triangles: 64,
            reference_budget: 4.0,
        }
    }
}

/// What a light buffer holds.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub struct LightBufferStats {
    /// Quadtree leaves with a tree.
    pub trees: usize,
    /// Quadtree leaves the light illuminates that reach no triangle.
    pub clear_cells: usize,
    /// Quadtree leaves the light does not illuminate.
    pub dark_cells: usize,
    /// Triangles over all trees: the scene BVH leaves each tree points at, each leaf's
    /// triangles counted once per tree.
    pub references: usize,
    /// Bytes of the grid and the trees' nodes (the triangles stay the scene BVH's).
    pub memory_bytes: usize,
}

/// A light buffer: the shadow-ray structure of one light (see the module documentation).
///
/// ```
/// use rdbvh_core::bvh::{TraversalStats, WideBvh8};
/// use rdbvh_core::geometry::{Ray, Triangle};
/// use rdbvh_core::light_buffer::{LightBuffer, LightBufferOptions, LightSource};
/// use rdbvh_core::{BuildOptions, Preset, Vec3};
///
/// // A floor and a small occluder under a point light.
/// let tris = [
///     Triangle::new(Vec3::new(-9.0, 0.0, -9.0), Vec3::new(9.0, 0.0, -9.0), Vec3::new(0.0, 0.0, 9.0)),
///     Triangle::new(Vec3::new(-1.0, 2.0, -1.0), Vec3::new(1.0, 2.0, -1.0), Vec3::new(0.0, 2.0, 1.0)),
/// ];
/// // The scene's BVH, which the buffer's trees point into.
/// let scene = WideBvh8::from_binary(&BuildOptions::new(Preset::Sah).build(&tris, None)?, &tris);
/// let light = Vec3::new(0.0, 5.0, 0.0);
/// let source = LightSource::point(light)?;
/// let buffer = LightBuffer::build(&tris, &scene, source, &LightBufferOptions::default())?;
/// // Shadow segments from the floor to the light: under the occluder, and beside it.
/// let shadow = |p: Vec3| Ray::segment(p, light - p, 0.0, 1.0 - 1e-4).unwrap();
/// let mut stats = TraversalStats::default();
/// let under = shadow(Vec3::new(0.0, 0.01, 0.0));
/// assert_eq!(buffer.occluded_with_stats(&scene, &under, &mut stats), Some(true));
/// assert_eq!(buffer.occluded(&scene, &shadow(Vec3::new(6.0, 0.01, 0.0))), Some(false));
/// // A segment that does not end on the light is not the buffer's to answer.
/// let other = Ray::segment(Vec3::ZERO, Vec3::X, 0.0, 1.0)?;
/// assert_eq!(buffer.occluded(&scene, &other), None);
/// # Ok::<(), Box<dyn std::error::Error>>(())
/// ```
#[derive(Clone, Debug)]
pub struct LightBuffer {
    pub(crate) source: LightSource,
    /// Cells a side on each face of the finest grid: a power of two, `1 << max_level`.
    pub(crate) resolution: u32,
    /// Per finest cell, `face * r * r + v * r + u`: the root node of its tree in its face's
    /// forest, [`CLEAR`] or [`DARK`].
    pub(crate) grid: Vec<u32>,
    /// Per cube-map face, every cell's tree in one node array, in the order the quadtree's
    /// depth-first walk made them (neighbouring cells' trees lie side by side in memory). Each
    /// face keeps the array its build made: joined into one, the copy of a large buffer's nodes
    /// took a fifth of its build. It holds no triangles: each leaf names a leaf's blocks in the
    /// scene BVH, whose triangles the renderer's other rays keep in the caches.
    pub(crate) forests: Vec<WideBvh8>,
    /// The scene BVH's node and block counts, checked at each query.
    pub(crate) scene_size: (usize, usize),
    /// The length margin of every decision ([`super::source::MARGIN`] times the coordinate scale).
    pub(crate) margin: f32,
    /// Where the segments the buffer answers end ([`LightSource::end_box`]).
    pub(crate) end_box: (f32x4, f32x4),
    pub(crate) stats: LightBufferStats,
}

impl LightBuffer {
    /// Builds the buffer of `source` over the scene `tris` (the triangles every other structure
    /// sees, in the same order) and `scene`, an 8-wide BVH over exactly those triangles, whose
    /// leaves the buffer's trees name. Fails on a triangle with a NaN or infinite coordinate, a
    /// `scene` over other triangles, or options out of range.
    pub fn build(
        tris: &[Triangle],
        scene: &WideBvh8,
        source: LightSource,
        options: &LightBufferOptions,
    ) -> Result<Self, BuildError> {
        let build = LightBufferBuilder::new(tris, scene, source, options)?;
        let faces = (0..LightBufferBuilder::FACES)
            .map(|face| build.face(face))
            .collect::<Result<Vec<_>, _>>()?;
        build.finish(faces)
    }

    /// The light this buffer was built for.
    pub fn source(&self) -> &LightSource {
        &self.source
    }

    /// What the buffer holds.
    pub fn stats(&self) -> LightBufferStats {
        self.stats
    }

    /// Cells a side on each face of the finest grid.
    pub fn resolution(&self) -> u32 {
        self.resolution
    }

    /// [`LightBuffer::occluded_with_stats`] without counting.
    #[inline]
    pub fn occluded(&self, scene: &WideBvh8, ray: &Ray) -> Option<bool> {
        self.query(scene, ray, &mut ())
    }

    /// Whether a triangle blocks the shadow segment `ray` (any hit on `[t_min, t_max]`), exactly
    /// as a BVH over the whole scene answers: `Some(answer)` for a segment that ends on the light
    /// (`origin + dir` on its surface, as a renderer's light sample gives) and starts where the
    /// light sends light; `None` for any other, which the caller answers elsewhere. `scene` is
    /// the BVH the buffer was built with, whose blocks its leaves name; given a BVH of another
    /// size the buffer answers `None` too.
    ///
    /// The cell lookup counts as one inner node in `stats` (it costs less than one 8-wide box
    /// test), the cell's tree as a [`WideBvh8`] traversal does.
    #[inline]
    pub fn occluded_with_stats(
        &self,
        scene: &WideBvh8,
        ray: &Ray,
        stats: &mut TraversalStats,
    ) -> Option<bool> {
        self.query(scene, ray, stats)
    }

    /// The finest grid cell that answers the shadow segment `ray` (an index below
    /// [`LightBuffer::cells`]), or `None` for a segment that is not the buffer's to answer (see
    /// [`LightBuffer::occluded_with_stats`]). A renderer that answers many segments at once can
    /// take them cell by cell ([`LightBuffer::occluded_in_cell`]): segments of one cell walk one
    /// small tree, which then stays in the caches.
    #[inline]
    pub fn cell_of(&self, scene: &WideBvh8, ray: &Ray) -> Option<u32> {
        if (scene.nodes.len(), scene.tris.len()) != self.scene_size
            || !self.source.ends_on_light(ray, self.end_box, self.margin)
        {
            return None;
        }
        Some(self.cell(-ray.dir) as u32)
    }

    /// Cells in the finest grid: `6 * resolution^2`.
    pub fn cells(&self) -> usize {
        self.grid.len()
    }

    /// [`LightBuffer::occluded_with_stats`] for a segment whose cell [`LightBuffer::cell_of`]
    /// gave, without counting. Given another cell the answer is that cell's tree's, which need
    /// not be the segment's.
    #[inline]
    pub fn occluded_in_cell(&self, cell: u32, scene: &WideBvh8, ray: &Ray) -> Option<bool> {
        self.answer(cell, scene, ray, &mut ())
    }

    /// [`LightBuffer::occluded_with_stats`] for a segment whose cell [`LightBuffer::cell_of`]
    /// gave: the same answer and the same counts.
    #[inline]
    pub fn occluded_in_cell_with_stats(
        &self,
        cell: u32,
        scene: &WideBvh8,
        ray: &Ray,
        stats: &mut TraversalStats,
    ) -> Option<bool> {
        self.answer(cell, scene, ray, stats)
    }

    /// The query, counting into `stats` or (with `()`) not at all.
    #[inline(always)]
    fn query(&self, scene: &WideBvh8, ray: &Ray, stats: &mut impl Counters) -> Option<bool> {
        let cell = self.cell_of(scene, ray)?;
        self.answer(cell, scene, ray, stats)
    }

    /// Cell `cell`'s answer for `ray`: the lookup counts as one inner node. A cell out of range
    /// answers `None`, as a segment that is not the buffer's.
    #[inline(always)]
    fn answer(
        &self,
        cell: u32,
        scene: &WideBvh8,
        ray: &Ray,
        stats: &mut impl Counters,
    ) -> Option<bool> {
        Some(match self.tree(cell, stats)? {
            None => false,
            Some((forest, root)) => forest.any_hit_from(root, &scene.tris, ray, stats),
        })
    }

    /// Cell `cell`'s tree, the lookup counted as one inner node: its face's forest and its root,
    /// `Some(None)` for a cell that reaches no triangle, `None` for a dark cell or one out of
    /// range (not the buffer's to answer).
    #[inline(always)]
    fn tree(&self, cell: u32, stats: &mut impl Counters) -> Option<Option<(&WideBvh8, u32)>> {
        stats.node();
        match *self.grid.get(cell as usize)? {
            DARK => None,
            CLEAR => Some(None),
            root => {
                // The cell's face: its index over `r * r`, a power of two.
                let face = cell >> (2 * self.resolution.trailing_zeros());
                Some(Some((&self.forests[face as usize], root)))
            }
        }
    }

    /// The finest grid cell that answers `ray` as a ray leaving the source: it starts on the
    /// light (its origin within the light's box grown by the buffer's margin, where the shadow
    /// segments it answers may end), and the cell is that of its direction. `None` for any
    /// other ray, or a `scene` of another size. A cell's tree holds every triangle a segment of
    /// its directions can cross from anywhere on the light, so it holds every triangle such a
    /// ray can hit, however far: the buffer of a point light placed at a pinhole camera's eye
    /// answers the camera's rays (the item buffer of Weghorst, Hooper and Greenberg 1984, made
    /// exact).
    #[inline]
    pub fn cell_leaving(&self, scene: &WideBvh8, ray: &Ray) -> Option<u32> {
        let (lo, hi) = self.end_box;
        let o = f32x4::from([ray.origin.x, ray.origin.y, ray.origin.z, 0.0]);
        if (scene.nodes.len(), scene.tris.len()) != self.scene_size
            || !(lo.simd_le(o) & o.simd_le(hi)).all()
        {
            return None;
        }
        Some(self.cell(ray.dir) as u32)
    }

    /// The closest hit of `ray`, a ray leaving the source, with its triangle's edges from the
    /// scene BVH's block: exactly what [`WideBvh8::closest_hit_edges`] on `scene` finds,
    /// through one cell's tree. `None` for a ray that is not the buffer's (see
    /// [`LightBuffer::cell_leaving`]) or that leaves the light where it sends no light; then
    /// `Some(None)` means no hit at all. The lookup counts as one inner node in `stats`.
    #[inline]
    pub fn closest_hit_leaving_with_stats(
        &self,
        scene: &WideBvh8,
        ray: &Ray,
        stats: &mut TraversalStats,
    ) -> Option<Option<(Hit, TriangleEdges)>> {
        self.closest_leaving(scene, ray, stats)
    }

    /// [`LightBuffer::closest_hit_leaving_with_stats`] without counting.
    #[inline]
    pub fn closest_hit_leaving(
        &self,
        scene: &WideBvh8,
        ray: &Ray,
    ) -> Option<Option<(Hit, TriangleEdges)>> {
        self.closest_leaving(scene, ray, &mut ())
    }

    #[inline(always)]
    fn closest_leaving(
        &self,
        scene: &WideBvh8,
        ray: &Ray,
        stats: &mut impl Counters,
    ) -> Option<Option<(Hit, TriangleEdges)>> {
        let cell = self.cell_leaving(scene, ray)?;
        Some(match self.tree(cell, stats)? {
            None => None,
            Some((forest, root)) => {
                let mut visitor = ClosestHitEdges::new(ray);
                forest.traverse_in(root, &scene.tris, ray, &mut visitor, stats);
                visitor.best
            }
        })
    }

    /// The finest grid cell of direction `d` (finite and non-zero, as a ray's direction is).
    #[inline(always)]
    fn cell(&self, d: glam::Vec3) -> usize {
        let (face, u, v) = face_coords(d);
        let r = self.resolution;
        let half = 0.5 * r as f32;
        // `as` saturates: a coordinate rounded just below -1 gives cell 0.
        let i = (((u + 1.0) * half) as u32).min(r - 1) as usize;
        let j = (((v + 1.0) * half) as u32).min(r - 1) as usize;
        debug_assert!(face < FACES);
        (face * r as usize + j) * r as usize + i
    }
}
