//! Errors of BVH construction.

use core::fmt;

/// Why a build could not run. Every input the builder rejects gets one of these, never a panic.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum BuildError {
    /// A primitive's bounds have a NaN or infinite coordinate (or are empty).
    InvalidPrimitive {
        /// Index of the primitive, as given to the arena.
        index: u32,
    },
    /// More primitives than the arena was sized for.
    ArenaFull {
        /// The arena's capacity in primitives.
        capacity: usize,
    },
    /// More primitives than `u32` indices can address.
    TooManyPrimitives,
    /// A subset's id names no triangle of the slice
    /// ([`crate::builder::BuildArena::load_triangle_subset`]).
    NoSuchPrimitive {
        /// The id, or `None` when it is not a `u32` at all (negative, or too large).
        index: Option<u32>,
        /// How many triangles the slice holds.
        count: usize,
    },
    /// A configuration value is out of range.
    InvalidConfig(&'static str),
}

impl fmt::Display for BuildError {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        match self {
            BuildError::InvalidPrimitive { index } => {
                write!(f, "primitive {index} has a NaN or infinite coordinate")
            }
            BuildError::ArenaFull { capacity } => {
                write!(f, "build arena is full (capacity {capacity} primitives)")
            }
            BuildError::TooManyPrimitives => f.write_str("more than 2^32 - 1 primitives"),
            BuildError::NoSuchPrimitive { index, count } => {
                match index {
                    Some(i) => write!(f, "id {i} names no triangle")?,
                    None => f.write_str("an id that is not a u32 names no triangle")?,
                }
                match count.checked_sub(1) {
                    Some(last) => write!(f, " (the slice holds {count}, ids 0 to {last})"),
                    None => f.write_str(" (the slice is empty)"),
                }
            }
            BuildError::InvalidConfig(why) => write!(f, "invalid build configuration: {why}"),
        }
    }
}

impl core::error::Error for BuildError {}
