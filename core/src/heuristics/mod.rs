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

mod axis;
mod cost;
mod pah_ortho;
mod pah_perspective;
mod spfh;
mod termination;

pub use axis::{AllAxes, AxisChooser, AxisOrder, LongestAxis};
pub use cost::{CostConstants, CostModel, Sah};
pub use pah_ortho::PahOrtho;
pub use pah_perspective::{PahPerspective, PerspectiveMeasure};
pub use spfh::Spfh;
pub use termination::{LeafSize, SahTermination, Termination};
