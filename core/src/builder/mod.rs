//! Top-down binned BVH construction over caller-sized arenas.
//!
//! The [`Builder`] is a skeleton: choose axes, bin primitive centroids, sweep the bins to price every
//! candidate plane, then stop or split and repeat. What "price" and "axis" mean comes from its type
//! parameters ([`crate::heuristics`]). All memory a build touches lives in a [`BuildArena`] sized up
//! front, and the output [`crate::bvh::Bvh`] can be pre-sized too, so a build allocates nothing.

mod apply_split;
mod arena;
mod bin_map;
mod binning;
mod config;
mod cut;
mod exhaustive;
mod graft;
mod keys;
mod options;
#[cfg(feature = "rayon")]
pub mod parallel;
mod partition;
mod preset;
mod profile;
mod reinsert;
mod skeleton;
mod spatial;
mod sweep;

pub use arena::{BuildArena, LoadedBounds, TriangleLoad};
pub use binning::{BinJob, NodeBinner, NodeBins, SerialBinner};
pub use config::{BinSpace, BuildConfig, CutEvaluation, ThesisCut, MAX_BINS, MAX_EXHAUSTIVE};
pub use graft::{GraftBlock, GraftError};
pub use options::BuildOptions;
pub use preset::{Preset, PresetError, PresetOptions, PresetVisitor};
pub use profile::{Clock, NoClock, PhaseProfile};
pub use reinsert::{reinsert, ReinsertConfig, ReinsertStats, Reinserter};
pub use skeleton::{BuildStats, Builder, Subtree, SubtreeSink};
pub use spatial::{SpatialBuilder, SpatialSplits};
