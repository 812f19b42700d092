//! The BVH analyzer: composable per-node and final actions run in one walk of a tree, kept apart
//! from construction so that measuring never changes what is built.
//!
//! An [`Analysis`] sees every node once (its index, depth, parent and the parent's per-node data)
//! and keeps its own accumulators; [`Analysis::finish`] turns them into an output. Tuples of up
//! to eight analyses are analyses too, so any set of them runs in one walk of [`analyze`],
//! statically dispatched:
//!
//! ```
//! use rdbvh_core::analyze::{analyze, Analysis, EstimatedCost, NodeView, TreeShape};
//! use rdbvh_core::builder::Builder;
//! use rdbvh_core::bvh::Bvh;
//! use rdbvh_core::geometry::Triangle;
//! use rdbvh_core::heuristics::CostConstants;
//! use rdbvh_core::Vec3;
//!
//! /// A user's own analysis: how many leaves sit below a node whose box is wider than its parent's
//! /// half width (the parent's width is the per-node data passed down).
//! struct WideLeaves(u32);
//!
//! impl Analysis for WideLeaves {
//!     type NodeData = f32;
//!     type Output = u32;
//!     fn visit(&mut self, v: &NodeView<'_>, parent_width: Option<&f32>) -> f32 {
//!         let width = v.node.bounds().extent().x;
//!         if v.node.is_leaf() && parent_width.is_some_and(|&p| width > 0.5 * p) {
//!             self.0 += 1;
//!         }
//!         width
//!     }
//!     fn finish(self, _bvh: &Bvh) -> u32 {
//!         self.0
//!     }
//! }
//!
//! let tris: Vec<Triangle> = (0..8)
//!     .map(|i| {
//!         let x = i as f32;
//!         Triangle::new(Vec3::new(x, 0.0, 0.0), Vec3::new(x + 0.5, 0.0, 0.0), Vec3::new(x, 1.0, 0.0))
//!     })
//!     .collect();
//! let bvh = Builder::sah().build(&tris).unwrap();
//! let (shape, sah, wide) = analyze(
//!     &bvh,
//!     (TreeShape::default(), EstimatedCost::sah(CostConstants::default()), WideLeaves(0)),
//! );
//! assert_eq!(shape.nodes as usize, bvh.nodes().len());
//! assert!(sah.per_ray >= 1.0);
//! assert!(wide <= shape.leaves);
//! ```
//!
//! The metrics: [`EstimatedCost`] (SAH and PAH), [`Epo`] (end-point overlap), [`SiblingOverlap`]
//! (the thesis's overlap of sibling boxes in 3D, projected, or projected and culled),
//! [`TreeShape`] (depth, counts, leaf sizes, memory), [`NodeRecords`] (one record per node, for
//! JSON and CSV export). Outside the tree walk: [`containment`] (how well an area lookup such as
//! the octree approximates the areas) and [`RayCostSums`] (measured costs from tracing rays).

mod analyzer;
mod containment;
mod epo;
mod estimated_cost;
mod export;
mod measured;
mod overlap;
mod shape;

pub use analyzer::{analyze, Analysis, NodeView};
pub use containment::{containment, Containment};
pub use epo::{clipped_triangle_area, Epo, EpoReport};
pub use estimated_cost::{EstimatedCost, EstimatedCostReport};
pub use export::{NodeRecord, NodeRecords};
pub use measured::{structure_all_hit, RayCostSums, RayCosts, StructureAllHit};
pub use overlap::{
    convex_intersection_area, OverlapReport, OverlapSpace, SiblingOverlap, THESIS_LEVELS,
};
pub use shape::{ShapeReport, TreeShape};
