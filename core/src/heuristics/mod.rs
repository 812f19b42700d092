//! The pluggable parts of a build: how a node's hit probability is measured ([`CostModel`]), which
//! split axes are tried ([`AxisChooser`]) and when a node becomes a leaf ([`Termination`]). The
//! builder is generic over all three, so each is statically dispatched and a user's own type costs
//! nothing extra.

mod axis;
mod cost;
mod termination;

pub use axis::{AllAxes, AxisChooser, AxisOrder, LongestAxis};
pub use cost::{CostConstants, CostModel, Sah};
pub use termination::{LeafSize, SahTermination, Termination};
