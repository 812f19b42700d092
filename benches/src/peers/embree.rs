//! Embree 3 (the system's `libembree3`, through the `embree` crate's raw bindings): the C++
//! anchor renderers measure against.
//!
//! - **Build**: one triangle mesh over the scene's vertices (shared with Embree, not copied: a
//!   renderer hands Embree its own buffers) and default flags (not `ROBUST`, not `COMPACT`).
//!   Embree picks its widest kernels at run time (AVX-512 where the CPU has it, 8-wide nodes on
//!   AVX and up).
//! - **Build quality**: measured twice. `embree` keeps the scene's default quality (`MEDIUM`:
//!   binned SAH, no spatial splits), what a renderer gets without asking. `embree-high` sets
//!   `RTC_BUILD_QUALITY_HIGH`, which for triangle meshes selects Embree's spatial-split SAH
//!   builder (its "final-frame" quality), the like of a spatial-split build of rdbvh.
//!   Both trees are traced by the same kernels.
//! - **One thread**: the build device is created with `threads=1`. Embree runs its builds on TBB,
//!   and `threads=1` caps TBB's whole process at one thread (`tbb::global_control`), so the build
//!   runs on the calling thread and its thread CPU time is the build's. `build_mt` creates a
//!   device with every thread for that one build; Embree sizes TBB by the largest live device,
//!   so that device is released with the tree it built, and one-thread builds stay one-thread.
//!   Its timing includes creating that device (well under a millisecond; its TBB threads are
//!   started lazily).
//! - **Queries**: `rtcIntersect1` for closest hit, `rtcOccluded1` for any hit, one ray at a time
//!   with an incoherent context, as a renderer's path tracer calls them.
//! - **Semantics**: Embree's triangles are two-sided (the library is built without back-face
//!   culling), as rdbvh's are; `tnear`/`tfar` are the ray's `t_min`/`t_max` and Embree's `t` is
//!   in units of the unnormalised direction, as rdbvh's is, so segments (the shadow rays, whose
//!   direction runs to the light) end where rdbvh's do. Its triangle test is not watertight
//!   (no `ROBUST` flag): rays through shared edges may differ, within the agreement threshold.
//! - **Not set**: the flush-to-zero / denormals-are-zero modes Embree's guide recommends. They are
//!   per thread and would change the Rust libraries' arithmetic in the same loop; the scenes and
//!   rays make no denormals, so they would not change Embree's speed either.

use std::ffi::CString;
use std::ptr;

use embree::sys;
use rdbvh_core::geometry::{Ray, Triangle};

use super::Library;

/// `RTC_INVALID_GEOMETRY_ID` (`(unsigned)-1`, a macro of the C header the bindings leave out).
const INVALID_ID: u32 = u32::MAX;

/// An Embree device (the library's context: its thread count, its ISA).
struct Device(sys::RTCDevice);

impl Device {
    /// A device from an Embree configuration string, or why Embree refused it.
    fn new(config: &str) -> Result<Self, String> {
        let c = CString::new(config).map_err(|_| format!("bad Embree config {config:?}"))?;
        // SAFETY: `c` is a valid NUL-terminated string that outlives the call.
        let handle = unsafe { sys::rtcNewDevice(c.as_ptr()) };
        if handle.is_null() {
            // SAFETY: a null device asks for the error of the failed creation.
            let e = unsafe { sys::rtcGetDeviceError(ptr::null_mut()) };
            return Err(format!("Embree refused a device ({config}): {e:?}"));
        }
        Ok(Self(handle))
    }

    /// The device's pending error, if any.
    fn error(&self) -> Option<sys::RTCError> {
        // SAFETY: the handle is a live device.
        let e = unsafe { sys::rtcGetDeviceError(self.0) };
        (e != sys::RTCError::NONE).then_some(e)
    }
}

impl Drop for Device {
    fn drop(&mut self) {
        // SAFETY: the handle is a live device, released once; scenes retain it themselves.
        unsafe { sys::rtcReleaseDevice(self.0) }
    }
}

/// Whether this process can run Embree: a one-thread device is created and released. Callers
/// check this first so that a missing or broken library is one clear error, not a panic.
/// It also refuses a library built with back-face culling, whose one-sided triangles would
/// answer other questions than the two-sided ones every other library tests.
pub fn available() -> Result<(), String> {
    let device = Device::new(ONE_THREAD)?;
    // SAFETY: a live device and a property every Embree 3 knows.
    let culling = unsafe {
        sys::rtcGetDeviceProperty(device.0, sys::RTCDeviceProperty::BACKFACE_CULLING_ENABLED)
    };
    if culling != 0 {
        return Err(
            "this Embree was built with back-face culling (EMBREE_BACKFACE_CULLING): its \
                    triangles are one-sided and cannot be compared"
                .into(),
        );
    }
    Ok(())
}

/// The one-thread device configuration.
const ONE_THREAD: &str = "threads=1";

/// The scene in Embree's format: vertex and index buffers, and the one-thread device.
pub struct EmbreeScene {
    device: Device,
    /// Three vertices per triangle, `x y z` each, plus one padding float: Embree reads the last
    /// vertex with a 16-byte load and asks shared buffers to allow it.
    vertices: Vec<f32>,
    /// `3i, 3i + 1, 3i + 2` per triangle `i`: the scenes are triangle soups.
    indices: Vec<u32>,
}

// SAFETY: Embree devices are thread-safe (its API may be called from any thread), and the
// buffers are owned plain data.
unsafe impl Send for EmbreeScene {}

/// A committed Embree scene (its BVH), released on drop.
pub struct EmbreeAccel {
    scene: sys::RTCScene,
}

// SAFETY: a committed Embree scene may be traced from any thread and released from any thread.
unsafe impl Send for EmbreeAccel {}

impl Drop for EmbreeAccel {
    fn drop(&mut self) {
        // SAFETY: the handle is a live scene, released once.
        unsafe { sys::rtcReleaseScene(self.scene) }
    }
}

/// Builds the scene over `s`'s buffers on `device`, with build quality `quality`.
fn build_on(device: &Device, s: &EmbreeScene, quality: sys::RTCBuildQuality) -> EmbreeAccel {
    let tris = s.indices.len() / 3;
    // SAFETY: the device is live; the shared buffers outlive the scene for as long as it is
    // traced (the accel is used only beside the `EmbreeScene` it was built from, which the
    // `Library` contract keeps alive and unchanged), they have the sizes and strides declared
    // here, and the vertex buffer carries the padding Embree's 16-byte loads need.
    unsafe {
        let scene = sys::rtcNewScene(device.0);
        sys::rtcSetSceneBuildQuality(scene, quality);
        let geom = sys::rtcNewGeometry(device.0, sys::RTCGeometryType::TRIANGLE);
        sys::rtcSetSharedGeometryBuffer(
            geom,
            sys::RTCBufferType::VERTEX,
            0,
            sys::RTCFormat::FLOAT3,
            s.vertices.as_ptr().cast(),
            0,
            12,
            3 * tris,
        );
        sys::rtcSetSharedGeometryBuffer(
            geom,
            sys::RTCBufferType::INDEX,
            0,
            sys::RTCFormat::UINT3,
            s.indices.as_ptr().cast(),
            0,
            12,
            tris,
        );
        sys::rtcCommitGeometry(geom);
        sys::rtcAttachGeometry(scene, geom);
        sys::rtcReleaseGeometry(geom);
        sys::rtcCommitScene(scene);
        EmbreeAccel { scene }
    }
}

/// A built tree, or the error Embree reported while building it.
fn checked(device: &Device, accel: EmbreeAccel) -> EmbreeAccel {
    if let Some(e) = device.error() {
        // The scenes are validated before any adapter runs (finite triangles, at least
        // one), and `available` proved the device works: an error here is Embree's own
        // failure (out of memory), which no benchmark can go on from.
        panic!("Embree failed to build the scene: {e:?}");
    }
    accel
}

/// Embree 3, traced one ray at a time: its default build (`MEDIUM`), or with `HIGH` its
/// spatial-split build (`RTC_BUILD_QUALITY_HIGH`).
pub struct Embree<const HIGH: bool = false>;

/// Embree's spatial-split build.
pub type EmbreeHigh = Embree<true>;

impl<const HIGH: bool> Embree<HIGH> {
    /// The scene's build quality.
    const QUALITY: sys::RTCBuildQuality = if HIGH {
        sys::RTCBuildQuality::HIGH
    } else {
        sys::RTCBuildQuality::MEDIUM
    };
}

impl<const HIGH: bool> Library for Embree<HIGH> {
    const NAME: &'static str = if HIGH { "embree-high" } else { "embree" };
    const PARALLEL_BUILD: Option<&'static str> = Some(
        "rtcCommitScene on a device with every thread (TBB), created for the build and released \
         with its tree",
    );
    type Scene = EmbreeScene;
    type Ray = sys::RTCRayHit;
    type Accel = EmbreeAccel;

    fn scene(tris: &[Triangle]) -> Self::Scene {
        let mut vertices = Vec::with_capacity(9 * tris.len() + 1);
        for t in tris {
            for v in [t.v0, t.v1, t.v2] {
                vertices.extend_from_slice(&v.to_array());
            }
        }
        vertices.push(0.0);
        let indices = (0..3 * tris.len() as u32).collect();
        // `available` was checked before any adapter is made (see `compare::run`).
        let device = Device::new(ONE_THREAD).expect("Embree device (checked by `available`)");
        EmbreeScene {
            device,
            vertices,
            indices,
        }
    }

    fn rays(rays: &[Ray]) -> Vec<Self::Ray> {
        rays.iter()
            .map(|r| sys::RTCRayHit {
                ray: sys::RTCRay {
                    org_x: r.origin.x,
                    org_y: r.origin.y,
                    org_z: r.origin.z,
                    tnear: r.t_min,
                    dir_x: r.dir.x,
                    dir_y: r.dir.y,
                    dir_z: r.dir.z,
                    time: 0.0,
                    tfar: r.t_max,
                    mask: u32::MAX,
                    id: 0,
                    flags: 0,
                },
                hit: sys::RTCHit {
                    Ng_x: 0.0,
                    Ng_y: 0.0,
                    Ng_z: 0.0,
                    u: 0.0,
                    v: 0.0,
                    primID: INVALID_ID,
                    geomID: INVALID_ID,
                    instID: [INVALID_ID; 1],
                },
            })
            .collect()
    }

    fn build(scene: &mut Self::Scene) -> Self::Accel {
        checked(&scene.device, build_on(&scene.device, scene, Self::QUALITY))
    }

    fn build_mt(scene: &mut Self::Scene) -> Self::Accel {
        // `threads=0`: every hardware thread. The scene retains the device, so it lives (and
        // keeps TBB wide) exactly as long as this tree.
        let device = Device::new("threads=0").expect("Embree device (checked by `available`)");
        checked(&device, build_on(&device, scene, Self::QUALITY))
    }

    #[inline]
    fn closest(accel: &Self::Accel, _scene: &Self::Scene, ray: &Self::Ray) -> Option<f32> {
        let mut rh = *ray;
        let mut ctx = context();
        // SAFETY: a committed scene, a valid context and a ray-hit record Embree may write.
        unsafe { sys::rtcIntersect1(accel.scene, &mut ctx, &mut rh) };
        (rh.hit.geomID != INVALID_ID).then_some(rh.ray.tfar)
    }

    #[inline]
    fn any(accel: &Self::Accel, _scene: &Self::Scene, ray: &Self::Ray) -> bool {
        let mut r = ray.ray;
        let mut ctx = context();
        // SAFETY: a committed scene, a valid context and a ray record Embree may write.
        unsafe { sys::rtcOccluded1(accel.scene, &mut ctx, &mut r) };
        // Embree marks an occluded ray by setting `tfar` to -inf.
        r.tfar == f32::NEG_INFINITY
    }
}

/// `rtcInitIntersectContext` (an inline function of the C header, so not in the bindings):
/// incoherent rays, no filter, no instance.
#[inline]
fn context() -> sys::RTCIntersectContext {
    sys::RTCIntersectContext {
        flags: sys::RTCIntersectContextFlags::INCOHERENT,
        filter: None,
        instID: [INVALID_ID; 1],
    }
}
