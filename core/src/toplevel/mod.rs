//! The top-level structure that lets a renderer use local BVHs: influence areas, a lookup from a
//! ray origin to the areas that may contain it (a naive [`AreaList`] or an [`Octree`]), one local
//! BVH per area and a fallback BVH for every other ray, behind exact closest-hit and any-hit
//! queries ([`TopLevel`]).

mod break_even;
mod lookup;
mod octree;
mod top_level;

pub use break_even::BreakEven;
pub use lookup::{AreaList, AreaLookup};
pub use octree::{Octree, OctreeStats, DEFAULT_OCTREE_LEVELS, MAX_OCTREE_LEVELS};
pub use top_level::{TopLevel, TopLevelError, TopLevelOptions, TopLevelStats};
