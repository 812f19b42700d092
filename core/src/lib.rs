//! `rdbvh-core`: bounding volume hierarchies that know where the rays go.
//!
//! A `#![no_std]` + `alloc` crate for embedded and bare-metal renderers. It builds binary BVHs
//! top-down with binned sweeps (Wald 2007) whose split-axis choice, cost model and termination
//! rule are statically dispatched types, traverses them with a fixed-size stack that the build's
//! depth bound makes provably large enough, and checks everything against a brute-force oracle.
//!
//! ```
//! use rdbvh_core::{BuildOptions, Preset, Ray, Triangle, Vec3, WideBvh};
//!
//! let tris = [Triangle::new(Vec3::new(-1.0, -1.0, 2.0), Vec3::new(1.0, -1.0, 2.0), Vec3::new(0.0, 1.0, 2.0))];
//! let bvh = BuildOptions::new(Preset::Sah).build(&tris, None)?;
//! let ray = Ray::new(Vec3::ZERO, Vec3::Z)?;
//! let hit = bvh.closest_hit(&ray, &tris).unwrap();
//! assert_eq!(hit.triangle, 0);
//! assert!((hit.t - 2.0).abs() < 1e-6);
//! // The 4-wide collapse answers the same, faster.
//! assert_eq!(WideBvh::from_binary(&bvh, &tris).closest_hit(&ray), Some(hit));
//! # Ok::<(), Box<dyn std::error::Error>>(())
//! ```
//!
//! The root holds what a renderer needs; the rest lives in its module, one concept a file:
//!
//! | module | what | thesis |
//! |---|---|---|
//! | [`geometry`] | boxes, rays, triangles, oriented boxes, frustums, separating-axis tests | |
//! | [`heuristics`] | cost models, split-axis choosers, termination rules | SAH, PAH, LSPH, SPFH |
//! | [`builder`] | [`BuildOptions`], presets, the binned [`Builder`] skeleton, arenas, reinsertion, threads | the builder |
//! | [`bvh`] | binary and 4-wide node arrays, their traversals, validation | |
//! | [`influence`] | plane and point influence areas, affinity, ray samplers | influence areas |
//! | [`toplevel`] | [`TopLevel`]: areas, local BVHs, octree or list, fallback BVH | octree, fallback |
//! | [`light_buffer`] | a shadow-ray structure around one light, cells of the light's view | |
//! | [`analyze`] | the composable BVH analyzer, estimated and measured cost, EPO, overlap | analyzer |
//!
//! Beside them, [`prefetch`]: a cache hint for what a renderer reads after a hit (its materials).
//!
//! Features: `std` (off) lets x86-64 builds choose the wide traversals' instructions at run time
//! (AVX2 where the CPU has it: [`bvh::simd_level`]); `rayon` (off) builds on every thread of
//! rayon's pool and implies `std`. Without them the crate is `no_std` + `alloc`.
#![no_std]
#![deny(missing_docs)]
#![forbid(unsafe_op_in_unsafe_fn)]

extern crate alloc;
#[cfg(any(feature = "std", test))]
extern crate std;

pub mod analyze;
pub mod brute_force;
pub mod builder;
pub mod bvh;
pub mod error;
pub mod geometry;
pub mod heuristics;
pub mod influence;
pub mod light_buffer;
mod prefetch;
pub mod random;
pub mod simd;
pub mod toplevel;

#[cfg(test)]
mod test_scenes;

pub use builder::{BuildOptions, Builder, Preset, PresetError, PresetOptions};
pub use bvh::{Bvh, Hit, WideBvh};
pub use error::BuildError;
pub use geometry::{Aabb, Ray, Triangle};
pub use glam::Vec3;
pub use influence::{InfluenceArea, PlaneArea, PointArea};
pub use prefetch::{prefetch, prefetch_all};
pub use toplevel::{TopLevel, TopLevelOptions};
