//! `rdbvh render`: a path tracer with next event estimation, the workload the ray-distribution
//! heuristics are for, and the structures that make its shadow rays cheaper.
//!
//! # Rendering
//!
//! - **Scene.** OBJ + MTL through the scene loader: each triangle's MTL `Kd` is its Lambertian
//!   albedo (textures are not read), its `Ke` its emission. Shading uses geometric normals, both
//!   faces of every triangle.
//! - **Lights.** Emissive triangles (both faces), plus point, hard-edged spot and one-sided quad
//!   lights from a lights file ([`lights_file`]). Next event estimation chooses one light per
//!   vertex in proportion to its power ([`Light::power`]) and one point on it.
//! - **Integrator.** Path tracing with one shadow segment per vertex, cosine-weighted bounces,
//!   Russian roulette from the third vertex ([`integrator`]).
//! - **Determinism.** Every random number is a hash of (seed, pixel, sample, dimension)
//!   ([`sampler`]): the image depends on the seed alone, not on threads or tiles.
//! - **Structures.** Bounce rays go through the global BVH; camera rays and shadow segments
//!   through the [`Structure`] chosen (`global`; `lights`: a light buffer per light, and one at
//!   the camera's eye for the camera rays ([`eye_buffer`]), each where a pilot frame shows it
//!   pays, [`pilot`]; or `thesis`: the thesis's influence areas, octree and fallback for the
//!   shadow segments, [`ThesisStructure`]). All answer exactly as the global BVH does, so their
//!   images are byte-identical.
//! - **Batches.** Where the structure answers shadow segments fastest together (`lights` with a
//!   buffer: cell by cell), a frame traces its paths in batches of tiles and answers each
//!   batch's segments at once, then sums every path's radiance in its own order
//!   ([`shadow_batch`]); the global BVH answers each segment where it is made, next to the hit
//!   whose nodes are still in the caches.
//! - **Measures.** The frame counts its rays and the shadow segments' node and triangle tests;
//!   [`replay_shadow_rays`] times the frame's shadow segments on one thread.

mod camera;
mod direction;
mod error;
pub mod eye_buffer;
mod frame;
mod image;
pub mod integrator;
mod light;
mod light_structure;
pub mod lights_file;
pub mod pilot;
mod replay;
pub mod sampler;
pub mod shadow_batch;
mod structure;
mod thesis;

pub use self::image::{encode_png, mean_luminance, srgb, to_srgb8};
pub use camera::{Camera, DEFAULT_FOV_DEG};
pub use error::RenderError;
pub use eye_buffer::EyeBufferReport;
pub use frame::{
    render_frame, Frame, FrameCounters, FrameSettings, RecordedRays, REPLAY_CAP, TILE,
};
pub use integrator::{Integrator, ShadowRay, SHADOW_END};
pub use light::{emissive_lights, luminance, Light, LightSample, LightSet};
pub use light_structure::{CLUSTER_EXTENT, MAX_LIGHT_BUFFERS};
pub use lights_file::{parse_lights, read_lights};
pub use pilot::{build_lights, pilot_size, prune_by_pilot, PilotReport, KEEP_RATIO, PILOT_DIVISOR};
pub use replay::{answer_batches, replay_shadow_rays};
pub use shadow_batch::{BatchOrder, PathBatch};
pub use structure::{Structure, StructureKind};
pub use thesis::{ThesisStructure, ThesisSummary};
