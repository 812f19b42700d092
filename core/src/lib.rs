//! `rdbvh-core`: bounding volume hierarchies that know where the rays go.
//!
//! A `#![no_std]` + `alloc` crate for embedded and bare-metal renderers. It builds binary BVHs
//! top-down with binned sweeps (Wald 2007) whose split-axis choice, cost model and termination
//! rule are statically dispatched types, traverses them with a fixed-size stack that the build's
//! depth bound makes provably large enough, and checks everything against a brute-force oracle.
//!
//! ```
//! use rdbvh_core::{builder::{Builder, BuildArena}, geometry::{Ray, Triangle}, Vec3};
//!
//! let tris = [Triangle::new(Vec3::new(-1.0, -1.0, 2.0), Vec3::new(1.0, -1.0, 2.0), Vec3::new(0.0, 1.0, 2.0))];
//! let bvh = Builder::sah().build(&tris).unwrap();
//! let ray = Ray::new(Vec3::ZERO, Vec3::Z).unwrap();
//! let hit = bvh.closest_hit(&ray, &tris).unwrap();
//! assert_eq!(hit.triangle, 0);
//! assert!((hit.t - 2.0).abs() < 1e-6);
//! ```
#![no_std]
#![deny(missing_docs)]
#![forbid(unsafe_op_in_unsafe_fn)]

extern crate alloc;

pub mod analyze;
pub mod brute_force;
pub mod builder;
pub mod bvh;
pub mod error;
pub mod geometry;
pub mod heuristics;
pub mod influence;
pub mod light_buffer;
pub mod random;
pub mod simd;
pub mod toplevel;

#[cfg(test)]
mod test_scenes;

pub use error::BuildError;
pub use glam::Vec3;
