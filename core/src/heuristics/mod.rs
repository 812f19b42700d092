//! The pluggable parts of a build: how a node's hit probability is measured ([`CostModel`]), which
//! split axes are tried ([`AxisChooser`]) and when a node becomes a leaf ([`Termination`]). The
//! builder is generic over all three, so each is statically dispatched and a user's own type costs
//! nothing extra.
//!
//! | thesis name | here |
//! |---|---|
//! | SAH | [`Sah`] |
//! | PAH, parallel rays | [`PahOrtho`] |
//! | PAH, radial rays | [`PahPerspective`] |
//! | LSPH | [`LongestAxis`] |
//! | SPFH | [`Spfh`] |
//!
//! A strategy of your own plugs in without touching the builder. Here, a cost model for rays that
//! all travel along +z (the orthographic projected area onto the xy plane), a chooser that never
//! splits along z, and a stop rule by leaf size and depth:
//!
//! ```
//! use rdbvh_core::builder::{BuildConfig, Builder};
//! use rdbvh_core::geometry::{Aabb, Ray, Triangle};
//! use rdbvh_core::heuristics::{AxisChooser, AxisOrder, CostModel, Termination};
//! use rdbvh_core::Vec3;
//!
//! /// Rays along +z hit a box with probability proportional to its xy footprint.
//! struct Footprint;
//! impl CostModel for Footprint {
//!     fn measure(&self, b: &Aabb) -> f32 {
//!         let e = b.extent();
//!         e.x * e.y
//!     }
//! }
//!
//! /// Planes parallel to the rays: x first, then y.
//! struct AcrossRays;
//! impl AxisChooser for AcrossRays {
//!     fn order(&self, _node: &Aabb) -> AxisOrder {
//!         AxisOrder::new(&[(0, 1.0), (1, 1.0)])
//!     }
//! }
//!
//! /// Leaves of at most 4 primitives, never deeper than 20.
//! struct Small;
//! impl Termination for Small {
//!     fn must_stop(&self, count: u32, depth: u32) -> bool {
//!         count <= 4 || depth >= 20
//!     }
//!     fn prefer_leaf(&self, _count: u32, _leaf: f32, _split: f32) -> bool {
//!         false
//!     }
//! }
//!
//! let tris: Vec<Triangle> = (0..100)
//!     .map(|i| {
//!         let o = Vec3::new((i % 10) as f32, (i / 10) as f32, 5.0);
//!         Triangle::new(o, o + Vec3::X * 0.5, o + Vec3::Y * 0.5)
//!     })
//!     .collect();
//! let bvh = Builder::new(AcrossRays, Footprint, Small, BuildConfig::default()).build(&tris)?;
//! let ray = Ray::new(Vec3::new(3.1, 4.1, 0.0), Vec3::Z)?;
//! assert_eq!(bvh.closest_hit(&ray, &tris).map(|h| h.triangle), Some(43));
//! # Ok::<(), Box<dyn core::error::Error>>(())
//! ```

mod area_pah;
mod axis;
mod cost;
mod pah_ortho;
mod pah_perspective;
mod spfh;
mod termination;

pub use area_pah::AreaPah;
pub use axis::{AllAxes, AxisChooser, AxisOrder, LongestAxis};
pub use cost::{CostConstants, CostModel, Sah};
pub use pah_ortho::PahOrtho;
pub use pah_perspective::{PahPerspective, PerspectiveMeasure};
pub use spfh::Spfh;
pub use termination::{LeafSize, MinLeaf, SahTermination, Termination};
