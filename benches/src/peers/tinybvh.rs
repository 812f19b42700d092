//! tinybvh 1.6.8 (the single header shipped in the `tinybvh-rs` crate, compiled by `build.rs`
//! with `benches/cpp/tinybvh_peer.cpp` at `-O3 -march=native`): the other C++ anchor.
//!
//! The crate's own bindings expose neither an occlusion query nor the 4-wide CPU layout, and
//! gate the 8-wide traversal on the *Rust* target having AVX2 (which would change how rdbvh is
//! compiled too), so the adapter calls tinybvh through its own small C ABI instead.
//!
//! - **Layouts**: tinybvh's two CPU-traversal layouts, `BVH8_CPU` (8-wide, AVX2 kernels, its
//!   fastest on x86) and `BVH4_CPU` (4-wide, SSE), measured as `tinybvh-bvh8` and
//!   `tinybvh-bvh4`; under `tinybvh` each measure reports the faster of the two, which the text
//!   output names. Both are built by the layout's `Build` (tinybvh's default binned SAH builder,
//!   `BuildAVX` on AVX machines, then leaves regrouped to at most 4 triangles and the tree
//!   collapsed into the layout): the default, what a renderer gets without asking.
//! - **Spatial splits**: `tinybvh8-hq` is `BVH8_CPU` built by its `BuildHQ`, tinybvh's SBVH
//!   builder (binned SAH that may also split triangles, up to half again as many references),
//!   then the same regrouping and collapse: the like of a spatial-split build of rdbvh.
//!   Only the 8-wide layout: it is the faster one on every traversal.
//! - **One thread**: `BVH::threadedBuild` is cleared before a one-thread build; `build_mt` leaves
//!   it set, and tinybvh's builder then runs its own job system (`hardware_concurrency` threads)
//!   for meshes of 50,000 triangles and more, and one thread below that.
//! - **Queries**: `Intersect` for closest hit, `IsOccluded` for any hit, one prepared
//!   `tinybvh::Ray` at a time (copied per query, as Embree's and every Rust peer's are).
//! - **Semantics**: tinybvh's triangles are two-sided. Its rays have unit directions (its `Ray`
//!   constructor normalises) and no `tnear`: every ray here starts at `t_min = 0`, and a segment
//!   ends at `t_max |dir|` along the unit direction; hit distances are divided by `|dir|` back
//!   into rdbvh's units.

use std::ffi::c_void;

use rdbvh_core::geometry::{Ray, Triangle};

use super::Library;

extern "C" {
    fn rdbvh_tinybvh_ray_size() -> u32;
    fn rdbvh_tinybvh_ray_align() -> u32;
    fn rdbvh_tinybvh_ray(o: *const f32, d: *const f32, t: f32, out: *mut c_void);
    fn rdbvh_tinybvh8_build(verts: *const f32, tris: u32, threaded: bool, hq: bool) -> *mut c_void;
    fn rdbvh_tinybvh8_free(b: *mut c_void);
    fn rdbvh_tinybvh8_closest(b: *const c_void, ray: *const c_void) -> f32;
    fn rdbvh_tinybvh8_occluded(b: *const c_void, ray: *const c_void) -> bool;
    fn rdbvh_tinybvh8_stack_need(b: *const c_void) -> u32;
    fn rdbvh_tinybvh4_build(verts: *const f32, tris: u32, threaded: bool, hq: bool) -> *mut c_void;
    fn rdbvh_tinybvh4_free(b: *mut c_void);
    fn rdbvh_tinybvh4_closest(b: *const c_void, ray: *const c_void) -> f32;
    fn rdbvh_tinybvh4_occluded(b: *const c_void, ray: *const c_void) -> bool;
    fn rdbvh_tinybvh4_stack_need(b: *const c_void) -> u32;
}

/// The entries of tinybvh's traversal stacks (fixed arrays in `Intersect` and `IsOccluded`, not
/// checked while pushing).
const STACK: u32 = 256;

/// tinybvh's `BVH_FAR`: its "no end" for a ray.
const FAR: f32 = 1e30;

/// Room for one `tinybvh::Ray` (128 bytes, 64-byte aligned, in tinybvh 1.6.8 as compiled here; checked
/// by [`available`]).
#[repr(C, align(64))]
#[derive(Clone, Copy)]
struct RayBlob([u8; 128]);

/// Whether the compiled tinybvh matches this adapter: its ray fits the adapter's 128-byte copy, and the scene
/// size fits its 32-bit triangle count (checked per scene in `compare::run`).
pub fn available() -> Result<(), String> {
    // SAFETY: plain functions without arguments.
    let (size, align) = unsafe { (rdbvh_tinybvh_ray_size(), rdbvh_tinybvh_ray_align()) };
    if size as usize > std::mem::size_of::<RayBlob>()
        || align as usize > std::mem::align_of::<RayBlob>()
    {
        return Err(format!(
            "tinybvh's Ray is {size} bytes aligned to {align}; the adapter holds 128 aligned to 64"
        ));
    }
    Ok(())
}

/// A vertex as tinybvh reads it: 16 bytes, 16-byte aligned.
#[repr(C, align(16))]
#[derive(Clone, Copy)]
struct Vertex([f32; 4]);

/// The scene in tinybvh's format: three vertices per triangle.
pub struct TinybvhScene {
    vertices: Vec<Vertex>,
}

/// A prepared tinybvh ray, its segment end along the unit direction, and `1 / |dir|` to bring
/// hit distances back into rdbvh's units.
#[derive(Clone, Copy)]
pub struct TinybvhRay {
    ray: RayBlob,
    t_end: f32,
    inv_len: f32,
}

/// One of tinybvh's CPU layouts: its build, release and queries through the C ABI.
pub trait Layout {
    /// The adapter's name, for the tree of `Build`.
    const NAME: &'static str;
    /// The adapter's name, for the tree of `BuildHQ`.
    const NAME_HQ: &'static str;
    /// Builds over `tris` triangles at `verts` with `BuildHQ` if `hq`, else `Build` (null when
    /// out of memory).
    ///
    /// # Safety
    /// `verts` holds `3 * tris` 16-byte-aligned vertices of 4 floats.
    unsafe fn build(verts: *const f32, tris: u32, threaded: bool, hq: bool) -> *mut c_void;
    /// Releases a tree from [`Layout::build`].
    ///
    /// # Safety
    /// `b` came from [`Layout::build`] and is released once.
    unsafe fn free(b: *mut c_void);
    /// The closest hit's distance along the unit direction, or the ray's end on a miss.
    ///
    /// # Safety
    /// `b` is a live tree from [`Layout::build`], `ray` a ray from `rdbvh_tinybvh_ray`.
    unsafe fn closest(b: *const c_void, ray: *const c_void) -> f32;
    /// Whether anything is hit before the ray's end.
    ///
    /// # Safety
    /// As [`Layout::closest`].
    unsafe fn occluded(b: *const c_void, ray: *const c_void) -> bool;
    /// The traversal stack entries the tree can need, whatever the ray.
    ///
    /// # Safety
    /// `b` is a live tree from [`Layout::build`].
    unsafe fn stack_need(b: *const c_void) -> u32;
}

/// `BVH8_CPU`: 8-wide nodes, AVX2 traversal.
pub struct Bvh8Cpu;

impl Layout for Bvh8Cpu {
    const NAME: &'static str = "tinybvh-bvh8";
    const NAME_HQ: &'static str = "tinybvh8-hq";
    unsafe fn build(verts: *const f32, tris: u32, threaded: bool, hq: bool) -> *mut c_void {
        rdbvh_tinybvh8_build(verts, tris, threaded, hq)
    }
    unsafe fn free(b: *mut c_void) {
        rdbvh_tinybvh8_free(b)
    }
    #[inline]
    unsafe fn closest(b: *const c_void, ray: *const c_void) -> f32 {
        rdbvh_tinybvh8_closest(b, ray)
    }
    #[inline]
    unsafe fn occluded(b: *const c_void, ray: *const c_void) -> bool {
        rdbvh_tinybvh8_occluded(b, ray)
    }
    unsafe fn stack_need(b: *const c_void) -> u32 {
        rdbvh_tinybvh8_stack_need(b)
    }
}

/// `BVH4_CPU`: 4-wide nodes, SSE traversal.
pub struct Bvh4Cpu;

impl Layout for Bvh4Cpu {
    const NAME: &'static str = "tinybvh-bvh4";
    const NAME_HQ: &'static str = "tinybvh4-hq";
    unsafe fn build(verts: *const f32, tris: u32, threaded: bool, hq: bool) -> *mut c_void {
        rdbvh_tinybvh4_build(verts, tris, threaded, hq)
    }
    unsafe fn free(b: *mut c_void) {
        rdbvh_tinybvh4_free(b)
    }
    #[inline]
    unsafe fn closest(b: *const c_void, ray: *const c_void) -> f32 {
        rdbvh_tinybvh4_closest(b, ray)
    }
    #[inline]
    unsafe fn occluded(b: *const c_void, ray: *const c_void) -> bool {
        rdbvh_tinybvh4_occluded(b, ray)
    }
    unsafe fn stack_need(b: *const c_void) -> u32 {
        rdbvh_tinybvh4_stack_need(b)
    }
}

/// A built tinybvh tree of layout `L`, released on drop.
pub struct TinybvhAccel<L: Layout> {
    tree: *mut c_void,
    layout: std::marker::PhantomData<L>,
}

// SAFETY: a built tinybvh tree is plain memory owned by this handle; tinybvh's queries only
// read it, from whichever thread.
unsafe impl<L: Layout> Send for TinybvhAccel<L> {}

impl<L: Layout> Drop for TinybvhAccel<L> {
    fn drop(&mut self) {
        // SAFETY: the tree came from `L::build` and is released once.
        unsafe { L::free(self.tree) }
    }
}

/// tinybvh with layout `L`, built by `Build`, or with `HQ` by `BuildHQ`.
pub struct Tinybvh<L: Layout, const HQ: bool = false>(std::marker::PhantomData<L>);

/// The 8-wide adapter.
pub type TinybvhBvh8 = Tinybvh<Bvh8Cpu>;
/// The 4-wide adapter.
pub type TinybvhBvh4 = Tinybvh<Bvh4Cpu>;
/// The 8-wide adapter with spatial splits.
pub type TinybvhBvh8Hq = Tinybvh<Bvh8Cpu, true>;

impl<L: Layout, const HQ: bool> Tinybvh<L, HQ> {
    fn build_with(scene: &TinybvhScene, threaded: bool) -> TinybvhAccel<L> {
        // `compare::run` checks the count fits u32 before any adapter is made.
        let tris = (scene.vertices.len() / 3) as u32;
        // SAFETY: the buffer holds 3 * tris aligned 4-float vertices.
        let tree = unsafe { L::build(scene.vertices.as_ptr().cast(), tris, threaded, HQ) };
        assert!(
            !tree.is_null(),
            "{}: out of memory building",
            <Self as Library>::NAME
        );
        TinybvhAccel {
            tree,
            layout: std::marker::PhantomData,
        }
    }
}

impl<L: Layout, const HQ: bool> Library for Tinybvh<L, HQ> {
    const NAME: &'static str = if HQ { L::NAME_HQ } else { L::NAME };
    const PARALLEL_BUILD: Option<&'static str> = Some(if HQ {
        "the same BuildHQ with BVH::threadedBuild set: tinybvh's job system on every hardware \
         thread (for 50,000 triangles and more)"
    } else {
        "the same Build with BVH::threadedBuild set: tinybvh's job system on every hardware \
         thread (for 50,000 triangles and more)"
    });
    type Scene = TinybvhScene;
    type Ray = TinybvhRay;
    type Accel = TinybvhAccel<L>;

    fn scene(tris: &[Triangle]) -> Self::Scene {
        let vertices = tris
            .iter()
            .flat_map(|t| [t.v0, t.v1, t.v2])
            .map(|v| Vertex([v.x, v.y, v.z, 0.0]))
            .collect();
        TinybvhScene { vertices }
    }

    fn rays(rays: &[Ray]) -> Vec<Self::Ray> {
        rays.iter()
            .map(|r| {
                let len = r.dir.length();
                let t_end = if r.t_max.is_finite() {
                    (r.t_max * len).min(FAR)
                } else {
                    FAR
                };
                let mut ray = RayBlob([0; 128]);
                let (o, d) = (r.origin.to_array(), r.dir.to_array());
                // SAFETY: `o` and `d` hold 3 floats; `ray` has the room and alignment
                // `available` checked.
                unsafe {
                    rdbvh_tinybvh_ray(
                        o.as_ptr(),
                        d.as_ptr(),
                        t_end,
                        (&mut ray as *mut RayBlob).cast(),
                    )
                };
                TinybvhRay {
                    ray,
                    t_end,
                    inv_len: 1.0 / len,
                }
            })
            .collect()
    }

    fn build(scene: &mut Self::Scene) -> Self::Accel {
        Self::build_with(scene, false)
    }

    fn build_mt(scene: &mut Self::Scene) -> Self::Accel {
        Self::build_with(scene, true)
    }

    /// A tree deeper than tinybvh's traversal stack holds (a degenerate build, as over a scene
    /// of 1e-20 units, where its binning cannot split) would overrun the stack, which tinybvh
    /// does not check: refused before any ray.
    fn unusable(accel: &Self::Accel) -> Option<String> {
        // SAFETY: a live tree.
        let need = unsafe { L::stack_need(accel.tree) };
        (need > STACK).then(|| {
            format!(
                "its tree can need {need} traversal stack entries, and its traversals hold \
                 {STACK} unchecked"
            )
        })
    }

    #[inline]
    fn closest(accel: &Self::Accel, _scene: &Self::Scene, ray: &Self::Ray) -> Option<f32> {
        // SAFETY: a live tree and a ray made by `rdbvh_tinybvh_ray`.
        let t = unsafe { L::closest(accel.tree, (&ray.ray as *const RayBlob).cast()) };
        (t < ray.t_end).then_some(t * ray.inv_len)
    }

    #[inline]
    fn any(accel: &Self::Accel, _scene: &Self::Scene, ray: &Self::Ray) -> bool {
        // SAFETY: as in `closest`.
        unsafe { L::occluded(accel.tree, (&ray.ray as *const RayBlob).cast()) }
    }
}
