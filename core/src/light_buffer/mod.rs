//! The light buffer (Haines and Greenberg 1986), made exact for segments: an acceleration
//! structure for the shadow rays toward one light.
//!
//! A shadow segment of next event estimation ends on its light, so its direction alone (from the
//! light toward the receiver, `-ray.dir`) tells which part of the scene it can cross. The buffer
//! bins those directions on a cube map around the light. Each cell finds the triangles that
//! segments of its directions can reach: the cell's cone swept over the light's surface (a
//! Minkowski sum, bounded by shifted planes), tested by exact polygon clipping with conservative
//! margins. It keeps a small [`WideBvh8`] over the scene BVH's leaves that hold them, each boxed
//! by the clipped parts of its reached triangles, so a leaf crossing many cells costs each cell
//! only its own piece. The trees name the scene BVH's triangle blocks instead of copying them: a
//! buffer adds only nodes to memory, and its segments test the blocks the renderer's other rays
//! keep in the caches. Cells subdivide as a quadtree while that splits their triangles; a lookup
//! is one index into the finest grid. Cells the light does not
//! illuminate (behind a one-sided light, outside a spot's cone) hold nothing. Each tree's nodes
//! list their children nearest the light first: an any-hit query meets the occluders between
//! the light and the receiver before the receiver's own neighbourhood, which its segment starts
//! in and which rarely blocks it.
//!
//! A query is one cell lookup plus an any-hit traversal of that cell's tree with the scene's own
//! triangle test, over a superset of the triangles the segment can touch (a scene leaf's other
//! triangles included: any the segment hits, the scene BVH reports too): the answer is the one a
//! BVH over the whole scene gives, bit for bit. A segment the buffer was not built for (one that
//! does not end on the light, or starts where the light sends no light) gets `None`, so that the
//! caller can ask another structure instead.
//!
//! [`WideBvh8`]: crate::bvh::WideBvh8

mod buffer;
mod cell;
mod cell_tree;
mod clip;
mod source;
mod subdivide;

pub use buffer::{LightBuffer, LightBufferOptions, LightBufferStats};
pub use source::{LightSource, LightSourceError};
pub use subdivide::{LightBufferBuilder, LightBufferFace};

#[cfg(test)]
mod tests;
