//! Why a scene could not be loaded, and what was loaded with reservations.
//!
//! Errors stop the load: the caller gets no triangles, because a scene with silently missing or
//! corrupt geometry would give wrong BVH statistics and wrong hits. Warnings are for what only
//! affects shading (materials): the geometry is complete, so the scene is still useful for building
//! and tracing, and the caller decides whether to show them.

use std::fmt;
use std::io;
use std::path::PathBuf;

/// Which kind of OBJ vertex data a face index refers to.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum VertexKind {
    /// A `v` position.
    Position,
    /// A `vt` texture coordinate.
    TexCoord,
    /// A `vn` normal.
    Normal,
}

impl VertexKind {
    /// `n` of this kind, in words: "1 vertex", "2 vertices".
    fn count(self, n: usize) -> String {
        let (one, many) = match self {
            VertexKind::Position => ("vertex", "vertices"),
            VertexKind::TexCoord => ("texture coordinate", "texture coordinates"),
            VertexKind::Normal => ("normal", "normals"),
        };
        format!("{n} {}", if n == 1 { one } else { many })
    }
}

impl fmt::Display for VertexKind {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        f.write_str(match self {
            VertexKind::Position => "vertex",
            VertexKind::TexCoord => "texture coordinate",
            VertexKind::Normal => "normal",
        })
    }
}

/// A scene that cannot be used. Every message names the file (or `<memory>` for in-memory input)
/// and, where the loader knows it, the line or triangle, so the user can fix the input.
#[derive(Debug)]
pub enum SceneError {
    /// The file is missing, unreadable or not UTF-8 text.
    Io {
        /// The scene file.
        path: PathBuf,
        /// What the operating system (or the UTF-8 check) said.
        source: io::Error,
    },
    /// The OBJ text is not valid Wavefront OBJ (as found by our checks or by `tobj`).
    Malformed {
        /// The scene file.
        path: PathBuf,
        /// 1-based line number, when known (`tobj` does not report lines).
        line: Option<usize>,
        /// What is wrong.
        reason: String,
    },
    /// A face refers to a vertex (or texture coordinate, or normal) that is not defined before it.
    MissingVertex {
        /// The scene file.
        path: PathBuf,
        /// 1-based line number of the face.
        line: usize,
        /// What the index refers to.
        kind: VertexKind,
        /// The index as written in the file (1-based, or negative for relative indices).
        index: i64,
        /// How many of that kind were defined before the face.
        defined: usize,
    },
    /// The file has no faces with three or more vertices.
    NoTriangles {
        /// The scene file.
        path: PathBuf,
    },
    /// A triangle has a NaN or infinite coordinate (written as `nan`/`inf`, or overflowing `f32`).
    NonFiniteVertex {
        /// The scene file.
        path: PathBuf,
        /// 1-based line of the vertex, when found.
        line: Option<usize>,
        /// 0-based triangle index in load order.
        triangle: usize,
        /// Which corner of the triangle (0, 1 or 2).
        corner: usize,
        /// The offending position.
        position: [f32; 3],
    },
    /// A `builtin:` scene name that does not exist.
    UnknownBuiltin {
        /// The name after `builtin:`.
        name: String,
    },
}

impl fmt::Display for SceneError {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        match self {
            SceneError::Io { path, source } => {
                write!(f, "cannot read scene {}: {source}", path.display())
            }
            SceneError::Malformed { path, line, reason } => match line {
                Some(line) => write!(f, "malformed OBJ {} line {line}: {reason}", path.display()),
                None => write!(f, "malformed OBJ {}: {reason}", path.display()),
            },
            SceneError::MissingVertex {
                path,
                line,
                kind,
                index,
                defined,
            } => write!(
                f,
                "{} line {line}: face refers to {kind} {index}, but only {} {} defined before it",
                path.display(),
                kind.count(*defined),
                if *defined == 1 { "is" } else { "are" }
            ),
            SceneError::NoTriangles { path } => {
                write!(
                    f,
                    "{}: no triangles (no face has 3 or more vertices)",
                    path.display()
                )
            }
            SceneError::NonFiniteVertex {
                path,
                line,
                triangle,
                corner,
                position,
            } => {
                write!(f, "{}", path.display())?;
                if let Some(line) = line {
                    write!(f, " line {line}")?;
                }
                write!(
                    f,
                    ": vertex ({}, {}, {}) has a NaN or infinite coordinate (or one past single \
                     precision's range, about 3.4e38); it is corner {corner} of triangle \
                     {triangle} (0-based, load order)",
                    position[0], position[1], position[2]
                )
            }
            SceneError::UnknownBuiltin { name } => write!(
                f,
                "unknown built-in scene 'builtin:{name}' (known: {})",
                super::builtin::BUILTIN_SCENES
                    .iter()
                    .map(|(n, _)| format!("builtin:{n}"))
                    .collect::<Vec<_>>()
                    .join(", ")
            ),
        }
    }
}

impl std::error::Error for SceneError {
    fn source(&self) -> Option<&(dyn std::error::Error + 'static)> {
        match self {
            SceneError::Io { source, .. } => Some(source),
            _ => None,
        }
    }
}

/// Something the loader tolerated. The scene's geometry is complete; material information (and
/// so the emissive flags) may be missing, or its scale may keep rays from hitting it.
#[derive(Clone, Debug, PartialEq)]
pub enum SceneWarning {
    /// A `mtllib` file could not be read: its materials are missing, so the triangles that use
    /// them get no material and are not emissive.
    MaterialLibraryUnreadable {
        /// The material library as resolved against the OBJ's folder.
        path: PathBuf,
        /// Why it could not be read.
        reason: String,
    },
    /// A `mtllib` file could be read but not parsed; its materials are missing.
    MaterialLibraryMalformed {
        /// The material library.
        path: PathBuf,
        /// What is wrong.
        reason: String,
    },
    /// `usemtl` names a material that no loaded library defines; its faces get no material.
    UnknownMaterial {
        /// The material name.
        name: String,
    },
    /// Points (`p`, one-vertex faces) and polylines (`l`, two-vertex faces) are not surfaces, so
    /// they were left out of the triangles.
    SkippedNonSurfaces {
        /// How many such elements were skipped.
        count: usize,
    },
    /// The scene's coordinates reach past [`SceneWarning::FAR`] (or the whole scene is smaller
    /// than [`SceneWarning::TINY`]): there the single-precision ray/triangle test overflows (or
    /// underflows) and refuses hits, so rays would miss what they should hit (README, Known
    /// limits). The scene loads; scaling or recentring it fixes it.
    OutsidePrecisionRange {
        /// The largest coordinate's magnitude.
        largest: f32,
        /// The scene box's longest side.
        extent: f32,
    },
}

impl SceneWarning {
    /// Coordinates past this refuse hits: Moller-Trumbore's `t` numerator is about the cube of
    /// the coordinates (relative to the ray), which overflows f32 near 1e12 and more.
    pub const FAR: f32 = 1e12;
    /// A scene smaller than this refuses hits: the same cube underflows below about 1e-12.
    pub const TINY: f32 = 1e-11;

    /// The warning for a scene with bounds `bounds`, if it needs one.
    pub fn precision(bounds: &rdbvh_core::geometry::Aabb) -> Option<SceneWarning> {
        if bounds.is_empty() {
            return None;
        }
        let largest = bounds.min.abs().max(bounds.max.abs()).max_element();
        let extent = (bounds.max - bounds.min).max_element();
        (largest > Self::FAR || extent < Self::TINY)
            .then_some(SceneWarning::OutsidePrecisionRange { largest, extent })
    }
}

impl fmt::Display for SceneWarning {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        match self {
            SceneWarning::MaterialLibraryUnreadable { path, reason } => write!(
                f,
                "material library {} not loaded ({reason}); the scene has no materials from it \
                 and none of its triangles are emissive",
                path.display()
            ),
            SceneWarning::MaterialLibraryMalformed { path, reason } => write!(
                f,
                "material library {} is malformed ({reason}); the scene has no materials from it",
                path.display()
            ),
            SceneWarning::UnknownMaterial { name } => write!(
                f,
                "material '{name}' is used but not defined; its faces have no material"
            ),
            SceneWarning::SkippedNonSurfaces { count } => write!(
                f,
                "skipped {count} point or line elements (not surfaces, so not triangles)"
            ),
            SceneWarning::OutsidePrecisionRange { largest, extent } => write!(
                f,
                "coordinates reach {largest:e} and the scene spans {extent:e}: single-precision \
                 ray/triangle tests refuse hits past about {:e} units or on scenes smaller than \
                 about {:e}, so rays may miss what they should hit; scale or recentre the scene",
                Self::FAR,
                Self::TINY
            ),
        }
    }
}
