//! `rdbvh`: the host side of rdbvh. Loads scenes (Wavefront OBJ or built-in recipes), builds BVHs
//! with `rdbvh-core`, traces batches of rays in parallel, and drives the `rdbvh` command line.
//!
//! The core crate is `no_std` so it can run in embedded renderers; everything that needs files,
//! threads or clocks lives here, organised by the user's jobs: [`scene`] loads what to trace,
//! [`render`] path traces it with next event estimation, [`cli`] is the command line.
#![deny(missing_docs)]
#![forbid(unsafe_code)]

pub mod areas;
pub mod cli;
pub mod clock;
pub mod experiment;
pub mod render;
pub mod same_file;
pub mod scene;
pub mod text_lines;

/// The README's Rust examples, compiled as doctests so that they stay true to the API.
#[cfg(doctest)]
#[doc = include_str!("../../README.md")]
pub struct ReadmeDoctests;

/// The library guide's Rust examples, compiled as doctests too.
#[cfg(doctest)]
#[doc = include_str!("../../docs/library.md")]
pub struct LibraryDoctests;
