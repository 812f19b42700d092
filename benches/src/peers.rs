//! One adapter per library: rdbvh and its Rust peers, behind one trait so that every benchmark and
//! the agreement check run the same code for all of them.
//!
//! Choices, and why each is the fair comparison:
//!
//! - **rdbvh**: `Builder::sah()` (binned SAH, all three axes, 16 bins, SAH termination with leaves
//!   up to 8), single-threaded; binary-node closest hit and any hit. `rdbvh-wide` is the same
//!   tree improved by reinsertion (as obvhs's build improves its own) and collapsed to 4-wide
//!   nodes: the tree for tracing many rays per build.
//! - **obvhs 0.4**: `BvhBuildParams::fast_build()`, its fast high-quality build, through the
//!   crate's own helpers. obvhs does not build with binned SAH: its builder is PLOC (agglomerative clustering
//!   over a Morton order) plus a little reinsertion, so "SAH build" here means "its fast
//!   high-quality build". It is measured twice: `obvhs-bvh2` (`build_bvh2_from_tris`, its binary
//!   tree, the same node kind as rdbvh) and `obvhs-cwbvh` (`build_cwbvh_from_tris`, its
//!   8-wide compressed tree with SIMD traversal, the structure obvhs is built for and its fastest
//!   traversal). Its `parallel` feature is on (for the threaded builds), so its single-threaded
//!   builds run inside a one-thread rayon pool. Triangle test: obvhs's own double-sided
//!   Moller-Trumbore (`Triangle::intersect`).
//! - **bvh 0.13**: `Bvh::build` (its binned SAH over the longest centroid axis, one shape per
//!   leaf; the serial executor). Traversal: `bvh` has no closest-hit query of its own, only
//!   iterators over the shapes whose boxes a ray crosses, so closest hit walks
//!   `nearest_traverse_iterator` (near-to-far, stopping once a leaf box starts beyond the best
//!   hit) and any hit walks `traverse_iterator` up to the first hit. Its own ray/triangle test
//!   culls back faces, which would change the answers, so the shapes use rdbvh's
//!   double-sided test: the comparison isolates the tree and its traversal.
//! - **parry3d 0.31**: `Bvh::from_leaves(BvhBuildStrategy::Binned, ..)` over the triangles' boxes
//!   (the binned SAH builder `TriMesh::new` runs; without the mesh's other bookkeeping), and
//!   `Bvh::cast_ray` with parry's own triangle ray cast per leaf, which is exactly the path
//!   `TriMesh::cast_local_ray` takes. Any hit uses `Bvh::traverse` with an early exit on the
//!   first triangle hit, since parry's composite any-hit query is a full closest-hit cast.
//!   Segments end at the ray's `t_max` (parry's `max_time_of_impact`).
//! - **Embree 3** and **tinybvh 1.6.8** (feature `cpp-peers`): see `embree` and `tinybvh`. Each
//!   is measured with its default build and beside it with its spatial-split build
//!   (`embree-high`, `tinybvh8-hq`): a spatial-split (SBVH) build of rdbvh is compared with
//!   those, not with trees built without splits.

use std::marker::PhantomData;

use glam::{Vec3, Vec3A};
use rdbvh_core::builder::{reinsert, Builder, ReinsertConfig};
use rdbvh_core::bvh::{Lanes, WideBvhN, Width};
use rdbvh_core::geometry::{Ray, Triangle};
use rdbvh_core::heuristics::Sah;

use crate::Answers;

#[cfg(feature = "cpp-peers")]
pub mod embree;
#[cfg(feature = "cpp-peers")]
pub use embree::{Embree, EmbreeHigh};
#[cfg(feature = "cpp-peers")]
pub mod tinybvh;
#[cfg(feature = "cpp-peers")]
pub use tinybvh::{TinybvhBvh4, TinybvhBvh8, TinybvhBvh8Hq};

/// A library under test: how it takes triangles and rays, builds, and answers the two queries.
pub trait Library {
    /// The name in benchmark ids and the results table.
    const NAME: &'static str;
    /// The triangles in the library's own format.
    type Scene;
    /// A ray in the library's own format.
    type Ray;
    /// The built acceleration structure.
    type Accel;

    /// Converts triangles to the library's format (not timed).
    fn scene(tris: &[Triangle]) -> Self::Scene;
    /// Converts rays to the library's format (not timed).
    fn rays(rays: &[Ray]) -> Vec<Self::Ray>;
    /// How [`Library::build_mt`] uses threads, for reports; `None` when the library has no
    /// threaded build and `build_mt` is its single-threaded build.
    const PARALLEL_BUILD: Option<&'static str>;

    /// Builds the acceleration structure (the timed build). Mutable because `bvh` writes node
    /// indices into its shapes. Single-threaded for rdbvh, `bvh` and parry3d; obvhs (built with
    /// its `parallel` feature) uses the current rayon pool, so callers that want its
    /// single-threaded build run this inside a one-thread pool ([`crate::single_thread_pool`]).
    fn build(scene: &mut Self::Scene) -> Self::Accel;
    /// The library's threaded build, on the current rayon pool; [`Library::build`] when it has
    /// none.
    fn build_mt(scene: &mut Self::Scene) -> Self::Accel {
        Self::build(scene)
    }
    /// Why `accel` cannot be traced safely, if it cannot (checked after every build in the
    /// comparison, before any ray): a library whose traversal would overrun its own limits is
    /// left out rather than crash the process.
    fn unusable(_accel: &Self::Accel) -> Option<String> {
        None
    }
    /// The closest hit's distance along the ray, or `None`.
    fn closest(accel: &Self::Accel, scene: &Self::Scene, ray: &Self::Ray) -> Option<f32>;
    /// Whether anything is hit along the ray.
    fn any(accel: &Self::Accel, scene: &Self::Scene, ray: &Self::Ray) -> bool;
}

/// Everything one library needs to trace: its scene, its structure and its rays.
pub struct Prepared<L: Library> {
    /// The library's triangles.
    pub scene: L::Scene,
    /// The built structure.
    pub accel: L::Accel,
}

impl<L: Library> Prepared<L> {
    /// Converts `tris` and builds once.
    pub fn new(tris: &[Triangle]) -> Self {
        let mut scene = L::scene(tris);
        let accel = L::build(&mut scene);
        Self { scene, accel }
    }

    /// Traces every ray with closest hit; returns the number of hits, which the benchmark loop
    /// hands to `black_box` so no query can be optimised away.
    #[inline]
    pub fn closest_all(&self, rays: &[L::Ray]) -> usize {
        rays.iter()
            .filter(|r| L::closest(&self.accel, &self.scene, r).is_some())
            .count()
    }

    /// Traces every ray with any hit; returns the number of hits.
    #[inline]
    pub fn any_all(&self, rays: &[L::Ray]) -> usize {
        rays.iter()
            .filter(|r| L::any(&self.accel, &self.scene, r))
            .count()
    }

    /// Both answers for every ray, for [`crate::agreement`].
    pub fn answers(&self, rays: &[L::Ray]) -> Answers {
        Answers {
            closest: rays
                .iter()
                .map(|r| L::closest(&self.accel, &self.scene, r))
                .collect(),
            any: rays
                .iter()
                .map(|r| L::any(&self.accel, &self.scene, r))
                .collect(),
            floor: Vec::new(),
        }
    }
}

/// rdbvh: binned SAH over all axes, binary nodes.
pub struct Rdbvh;

impl Library for Rdbvh {
    const NAME: &'static str = "rdbvh";
    const PARALLEL_BUILD: Option<&'static str> = Some(
        "rdbvh_core::builder::parallel::build (rayon; the single-threaded tree, node for node)",
    );
    type Scene = Vec<Triangle>;
    type Ray = Ray;
    type Accel = rdbvh_core::bvh::Bvh;

    fn scene(tris: &[Triangle]) -> Self::Scene {
        tris.to_vec()
    }
    fn rays(rays: &[Ray]) -> Vec<Ray> {
        rays.to_vec()
    }
    fn build(scene: &mut Self::Scene) -> Self::Accel {
        BinnedSah::binary(scene)
    }
    fn build_mt(scene: &mut Self::Scene) -> Self::Accel {
        BinnedSah::binary_mt(scene)
    }
    #[inline]
    fn closest(accel: &Self::Accel, scene: &Self::Scene, ray: &Ray) -> Option<f32> {
        accel.closest_hit(ray, scene).map(|h| h.t)
    }
    #[inline]
    fn any(accel: &Self::Accel, scene: &Self::Scene, ray: &Ray) -> bool {
        accel.any_hit(ray, scene)
    }
}

/// One of rdbvh's wide trees as a [`Library`]: a binary tree made by `R`, improved by
/// reinsertion ([`rdbvh_core::builder::reinsert`], default settings, under SAH) and collapsed into
/// `W`-wide nodes with its own copy of the triangles in 4-wide leaf blocks, as a renderer that
/// traces many rays per build would make it. Its build time includes all three steps; its
/// traversals use that copy, not the scene.
pub struct RdbvhWideOf<R, const W: usize>(PhantomData<R>);

/// What differs between rdbvh's wide trees: the binary build before the reinsertion and the
/// collapse.
pub trait BinaryRecipe {
    /// The wide tree's name in benchmark ids and the results table, per width.
    const NAMES: [&'static str; 2];
    /// How [`BinaryRecipe::binary_mt`] uses threads (see [`Library::PARALLEL_BUILD`]).
    const PARALLEL_BUILD: Option<&'static str>;
    /// The binary tree, on one thread.
    fn binary(tris: &[Triangle]) -> rdbvh_core::bvh::Bvh;
    /// The binary tree, threaded where the recipe has a threaded build.
    fn binary_mt(tris: &[Triangle]) -> rdbvh_core::bvh::Bvh {
        Self::binary(tris)
    }
}

/// rdbvh's binned SAH build, the tree of [`Rdbvh`].
pub struct BinnedSah;

impl BinaryRecipe for BinnedSah {
    const NAMES: [&'static str; 2] = ["rdbvh-wide", "rdbvh-wide8"];
    const PARALLEL_BUILD: Option<&'static str> = Some(
        "rdbvh_core::builder::parallel::build, then the single-threaded reinsertion and collapse",
    );
    fn binary(tris: &[Triangle]) -> rdbvh_core::bvh::Bvh {
        Builder::sah()
            .build(tris)
            .expect("scene triangles are finite")
    }
    fn binary_mt(tris: &[Triangle]) -> rdbvh_core::bvh::Bvh {
        rdbvh_core::builder::parallel::build(&Builder::sah(), tris)
            .expect("scene triangles are finite")
    }
}

/// rdbvh's SBVH ([`rdbvh_core::builder::SpatialBuilder`], default settings: spatial splits with
/// up to half as many references again), the counterpart of `embree-high` and `tinybvh8-hq`.
/// The spatial-split build runs on one thread.
pub struct Sbvh;

impl BinaryRecipe for Sbvh {
    const NAMES: [&'static str; 2] = ["rdbvh-wide-sbvh", "rdbvh-wide8-sbvh"];
    const PARALLEL_BUILD: Option<&'static str> = None;
    fn binary(tris: &[Triangle]) -> rdbvh_core::bvh::Bvh {
        rdbvh_core::builder::SpatialBuilder::default()
            .build(tris)
            .expect("scene triangles are finite")
    }
}

/// rdbvh's 4-wide tree over its binned SAH build.
pub type RdbvhWide = RdbvhWideOf<BinnedSah, 4>;

/// [`RdbvhWide`]'s binary tree collapsed to 8-wide nodes ([`rdbvh_core::bvh::WideBvh8`]): half
/// the levels, so half the dependent node fetches on a ray's path.
pub type RdbvhWide8 = RdbvhWideOf<BinnedSah, 8>;

/// [`RdbvhWide8`] over an SBVH: split triangles.
pub type RdbvhWide8Sbvh = RdbvhWideOf<Sbvh, 8>;

impl<R: BinaryRecipe, const W: usize> RdbvhWideOf<R, W>
where
    Width<W>: Lanes<W>,
{
    /// `bvh` improved by reinsertion under SAH, collapsed to `W`-wide nodes over `tris`.
    fn widen(mut bvh: rdbvh_core::bvh::Bvh, tris: &[Triangle]) -> WideBvhN<W> {
        reinsert(&mut bvh, &Sah, &ReinsertConfig::default());
        WideBvhN::from_binary(&bvh, tris)
    }
}

impl<R: BinaryRecipe, const W: usize> Library for RdbvhWideOf<R, W>
where
    Width<W>: Lanes<W>,
{
    const NAME: &'static str = R::NAMES[(W == 8) as usize];
    const PARALLEL_BUILD: Option<&'static str> = R::PARALLEL_BUILD;
    type Scene = Vec<Triangle>;
    type Ray = Ray;
    type Accel = WideBvhN<W>;

    fn scene(tris: &[Triangle]) -> Self::Scene {
        tris.to_vec()
    }
    fn rays(rays: &[Ray]) -> Vec<Ray> {
        rays.to_vec()
    }
    fn build(scene: &mut Self::Scene) -> Self::Accel {
        Self::widen(R::binary(scene), scene)
    }
    fn build_mt(scene: &mut Self::Scene) -> Self::Accel {
        Self::widen(R::binary_mt(scene), scene)
    }
    #[inline]
    fn closest(accel: &Self::Accel, _scene: &Self::Scene, ray: &Ray) -> Option<f32> {
        accel.closest_hit(ray).map(|h| h.t)
    }
    #[inline]
    fn any(accel: &Self::Accel, _scene: &Self::Scene, ray: &Ray) -> bool {
        accel.any_hit(ray)
    }
}

/// obvhs's two trees as far as the adapter uses them: the same methods on each, which obvhs
/// declares on each type rather than in a trait.
pub trait ObvhsTree: Sized {
    /// The tree's name in benchmark ids and the results table.
    const NAME: &'static str;
    /// Builds the tree with `fast_build` on the current rayon pool.
    fn build(scene: &mut [obvhs::triangle::Triangle]) -> Self;
    /// Triangle index of each primitive slot.
    fn primitive_indices(&self) -> &[u32];
    /// obvhs's closest-hit traversal with `intersect` as the leaf test.
    fn traverse(
        &self,
        ray: obvhs::ray::Ray,
        hit: &mut obvhs::ray::RayHit,
        intersect: impl FnMut(&obvhs::ray::Ray, usize) -> f32,
    ) -> bool;
    /// obvhs's any-hit traversal: true when nothing is hit.
    fn traverse_miss(
        &self,
        ray: obvhs::ray::Ray,
        intersect: impl FnMut(&obvhs::ray::Ray, usize) -> f32,
    ) -> bool;
}

/// [`ObvhsTree`] for one of obvhs's trees: `$tree` built by `$build`, named `$name`.
macro_rules! obvhs_tree {
    ($tree:ty, $name:literal, $build:path) => {
        impl ObvhsTree for $tree {
            const NAME: &'static str = $name;
            fn build(scene: &mut [obvhs::triangle::Triangle]) -> Self {
                $build(
                    scene,
                    obvhs::BvhBuildParams::fast_build(),
                    &mut Default::default(),
                )
            }
            fn primitive_indices(&self) -> &[u32] {
                &self.primitive_indices
            }
            #[inline]
            fn traverse(
                &self,
                ray: obvhs::ray::Ray,
                hit: &mut obvhs::ray::RayHit,
                intersect: impl FnMut(&obvhs::ray::Ray, usize) -> f32,
            ) -> bool {
                self.ray_traverse(ray, hit, intersect)
            }
            #[inline]
            fn traverse_miss(
                &self,
                ray: obvhs::ray::Ray,
                intersect: impl FnMut(&obvhs::ray::Ray, usize) -> f32,
            ) -> bool {
                self.ray_traverse_miss(ray, intersect)
            }
        }
    };
}

obvhs_tree!(
    obvhs::bvh2::Bvh2,
    "obvhs-bvh2",
    obvhs::bvh2::builder::build_bvh2_from_tris
);
obvhs_tree!(
    obvhs::cwbvh::CwBvh,
    "obvhs-cwbvh",
    obvhs::cwbvh::builder::build_cwbvh_from_tris
);

/// obvhs's tree `T` from `fast_build` (PLOC + reinsertion + leaf collapse), with obvhs's own
/// traversal and triangle test.
pub struct Obvhs<T>(PhantomData<T>);

/// obvhs's binary tree.
pub type ObvhsBvh2 = Obvhs<obvhs::bvh2::Bvh2>;

/// obvhs's 8-wide compressed tree, with its SIMD traversal.
pub type ObvhsCwbvh = Obvhs<obvhs::cwbvh::CwBvh>;

impl<T: ObvhsTree> Library for Obvhs<T> {
    const NAME: &'static str = T::NAME;
    const PARALLEL_BUILD: Option<&'static str> =
        Some("the same call with obvhs's `parallel` feature on the all-thread rayon pool");
    type Scene = Vec<obvhs::triangle::Triangle>;
    type Ray = obvhs::ray::Ray;
    type Accel = T;

    fn scene(tris: &[Triangle]) -> Self::Scene {
        tris.iter()
            .map(|t| obvhs::triangle::Triangle {
                v0: Vec3A::from(t.v0),
                v1: Vec3A::from(t.v1),
                v2: Vec3A::from(t.v2),
            })
            .collect()
    }
    fn rays(rays: &[Ray]) -> Vec<Self::Ray> {
        rays.iter()
            .map(|r| {
                obvhs::ray::Ray::new(Vec3A::from(r.origin), Vec3A::from(r.dir), r.t_min, r.t_max)
            })
            .collect()
    }
    fn build(scene: &mut Self::Scene) -> Self::Accel {
        T::build(scene)
    }
    #[inline]
    fn closest(accel: &Self::Accel, scene: &Self::Scene, ray: &Self::Ray) -> Option<f32> {
        let mut hit = obvhs::ray::RayHit::none();
        let ids = accel.primitive_indices();
        accel
            .traverse(*ray, &mut hit, |r, id| scene[ids[id] as usize].intersect(r))
            .then_some(hit.t)
    }
    #[inline]
    fn any(accel: &Self::Accel, scene: &Self::Scene, ray: &Self::Ray) -> bool {
        let ids = accel.primitive_indices();
        !accel.traverse_miss(*ray, |r, id| scene[ids[id] as usize].intersect(r))
    }
}

/// A triangle as a `bvh` shape: its box comes from the triangle, and the crate writes the index
/// of the leaf that holds it.
#[derive(Clone, Copy, Debug)]
pub struct BvhShape {
    tri: Triangle,
    node: usize,
}

fn point(v: Vec3) -> nalgebra::Point3<f32> {
    nalgebra::Point3::new(v.x, v.y, v.z)
}

impl bvh::aabb::Bounded<f32, 3> for BvhShape {
    #[inline]
    fn aabb(&self) -> bvh::aabb::Aabb<f32, 3> {
        let b = self.tri.bounds();
        bvh::aabb::Aabb::with_bounds(point(b.min), point(b.max))
    }
}

impl bvh::bounding_hierarchy::BHShape<f32, 3> for BvhShape {
    fn set_bh_node_index(&mut self, index: usize) {
        self.node = index;
    }
    fn bh_node_index(&self) -> usize {
        self.node
    }
}

/// A ray for the `bvh` adapter: the crate's ray for the tree, rdbvh's for the shared triangle
/// test (the same origin; `bvh` normalises the direction, see `dir_len`).
#[derive(Clone, Copy, Debug)]
pub struct BvhRay {
    tree: bvh::ray::Ray<f32, 3>,
    tri: Ray,
    /// `|dir|`: `bvh` normalises its rays' directions, so its box distances are this many
    /// times rdbvh's `t` (1 for the unit camera and random rays, not for shadow segments).
    dir_len: f32,
}

/// `bvh` 0.13's binned SAH tree, one triangle per leaf.
pub struct BvhCrate;

impl Library for BvhCrate {
    const NAME: &'static str = "bvh";
    const PARALLEL_BUILD: Option<&'static str> =
        Some("Bvh::build_par (rayon::join over subtrees of 64 nodes and more)");
    type Scene = Vec<BvhShape>;
    type Ray = BvhRay;
    type Accel = bvh::bvh::Bvh<f32, 3>;

    fn scene(tris: &[Triangle]) -> Self::Scene {
        tris.iter().map(|&tri| BvhShape { tri, node: 0 }).collect()
    }
    fn rays(rays: &[Ray]) -> Vec<Self::Ray> {
        rays.iter()
            .map(|r| BvhRay {
                tree: bvh::ray::Ray::new(
                    point(r.origin),
                    nalgebra::Vector3::new(r.dir.x, r.dir.y, r.dir.z),
                ),
                tri: *r,
                dir_len: r.dir.length(),
            })
            .collect()
    }
    fn build(scene: &mut Self::Scene) -> Self::Accel {
        bvh::bvh::Bvh::build(scene)
    }
    fn build_mt(scene: &mut Self::Scene) -> Self::Accel {
        use bvh::bounding_hierarchy::BoundingHierarchy;
        bvh::bvh::Bvh::build_par(scene)
    }
    #[inline]
    fn closest(accel: &Self::Accel, scene: &Self::Scene, ray: &Self::Ray) -> Option<f32> {
        use bvh::aabb::Bounded;
        let mut best = ray.tri.t_max;
        let mut found = false;
        for shape in accel.nearest_traverse_iterator(&ray.tree, scene) {
            // Leaves come out in order of their boxes' entry distance: once one starts beyond
            // the best hit, so do all the rest.
            match ray.tree.intersection_slice_for_aabb(&shape.aabb()) {
                Some((entry, _)) if entry > best * ray.dir_len => break,
                _ => {}
            }
            if let Some(h) = shape.tri.intersect(&ray.tri, best) {
                best = h.t;
                found = true;
            }
        }
        found.then_some(best)
    }
    #[inline]
    fn any(accel: &Self::Accel, scene: &Self::Scene, ray: &Self::Ray) -> bool {
        accel
            .traverse_iterator(&ray.tree, scene)
            .any(|shape| shape.tri.intersect(&ray.tri, ray.tri.t_max).is_some())
    }
}

/// parry3d's binned BVH over the triangles' boxes, traced with parry's triangle ray cast.
pub struct Parry;

/// parry's triangles (with its own ray cast) and the boxes its builder takes.
pub struct ParryScene {
    tris: Vec<parry3d::shape::Triangle>,
    boxes: Vec<parry3d::bounding_volume::Aabb>,
}

/// A ray for the parry3d adapter: parry's ray has no segment end of its own, its queries take
/// one (`max_time_of_impact`), in units of the same unnormalised direction as rdbvh's `t`.
#[derive(Clone, Copy, Debug)]
pub struct ParryRay {
    ray: parry3d::query::Ray,
    t_max: f32,
}

fn pv(v: Vec3) -> parry3d::math::Vector {
    parry3d::math::Vector::new(v.x, v.y, v.z)
}

impl Library for Parry {
    const NAME: &'static str = "parry3d";
    /// parry3d 0.31 builds on one thread ("neither strategy is currently parallelized").
    const PARALLEL_BUILD: Option<&'static str> = None;
    type Scene = ParryScene;
    type Ray = ParryRay;
    type Accel = parry3d::partitioning::Bvh;

    fn scene(tris: &[Triangle]) -> Self::Scene {
        let tris: Vec<_> = tris
            .iter()
            .map(|t| parry3d::shape::Triangle::new(pv(t.v0), pv(t.v1), pv(t.v2)))
            .collect();
        let boxes = Vec::with_capacity(tris.len());
        ParryScene { tris, boxes }
    }
    fn rays(rays: &[Ray]) -> Vec<Self::Ray> {
        rays.iter()
            .map(|r| ParryRay {
                ray: parry3d::query::Ray::new(pv(r.origin), pv(r.dir)),
                t_max: r.t_max.min(f32::MAX),
            })
            .collect()
    }
    fn build(scene: &mut Self::Scene) -> Self::Accel {
        // The boxes are part of the build, as in rdbvh's (which bounds each triangle as it loads
        // its arena) and in `TriMesh::new`.
        scene.boxes.clear();
        scene
            .boxes
            .extend(scene.tris.iter().map(|t| t.local_aabb()));
        parry3d::partitioning::Bvh::from_leaves(
            parry3d::partitioning::BvhBuildStrategy::Binned,
            &scene.boxes,
        )
    }
    #[inline]
    fn closest(accel: &Self::Accel, scene: &Self::Scene, ray: &Self::Ray) -> Option<f32> {
        use parry3d::query::RayCast;
        accel
            .cast_ray(&ray.ray, ray.t_max, |i, best| {
                scene.tris[i as usize].cast_local_ray(&ray.ray, best, true)
            })
            .map(|(_, t)| t)
    }
    #[inline]
    fn any(accel: &Self::Accel, scene: &Self::Scene, ray: &Self::Ray) -> bool {
        use parry3d::partitioning::TraversalAction;
        use parry3d::query::RayCast;
        let mut hit = false;
        accel.traverse(|node| {
            if node.cast_ray(&ray.ray, ray.t_max) == f32::MAX {
                return TraversalAction::Prune;
            }
            if let Some(i) = node.leaf_data() {
                if scene.tris[i as usize].intersects_local_ray(&ray.ray, ray.t_max) {
                    hit = true;
                    return TraversalAction::EarlyExit;
                }
            }
            TraversalAction::Continue
        });
        hit
    }
}
