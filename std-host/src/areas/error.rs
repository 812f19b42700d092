//! Why an area file could not be used. Every message names the file and, where it applies, the
//! line and the entry (`area 2`, or `config 2` in an experiments file, counted from 0 in file
//! order), so the user can fix the input from one line of standard error.

use std::fmt;
use std::io;
use std::path::PathBuf;

use rdbvh_core::influence::AreaError;

use super::TableKind;

/// An area file that cannot be used.
#[derive(Debug)]
pub struct AreasError {
    /// The area file.
    pub path: PathBuf,
    /// 1-based line of the offending value or table, when known.
    pub line: Option<usize>,
    /// The entry at fault, when the problem is in one: its table kind and 0-based index.
    pub entry: Option<(TableKind, usize)>,
    /// What is wrong.
    pub kind: AreasErrorKind,
}

/// What is wrong with an area file.
#[derive(Debug)]
pub enum AreasErrorKind {
    /// The file is missing or unreadable.
    Io(io::Error),
    /// The file is not valid TOML, or `area`/`config` is not an array of tables.
    Syntax(String),
    /// The file has neither `[[area]]` nor `[[config]]` tables.
    NoAreas,
    /// The file has both `[[area]]` and `[[config]]` tables, so "the first area" is ambiguous.
    BothTables,
    /// An entry lacks a required key.
    MissingKey {
        /// The key.
        key: &'static str,
        /// The entry's kind (`plane` or `point`), once known.
        area_kind: Option<AreaKind>,
    },
    /// A key holds the wrong type of value.
    WrongType {
        /// The key.
        key: String,
        /// What it must be.
        expected: &'static str,
        /// What it is.
        found: String,
    },
    /// `kind` is neither `"plane"` nor `"point"`.
    UnknownKind(String),
    /// A key that is neither one of the kind's keys nor one of the ignored experiment keys: a typo,
    /// or a key of the other kind.
    UnknownKey {
        /// The key.
        key: String,
        /// The entry's kind.
        area_kind: AreaKind,
    },
    /// The values do not make an area (as `rdbvh-core` decided; the message names the key).
    Invalid(AreaError),
    /// [`AreasErrorKind::Invalid`] for a number that single precision, in which areas are made,
    /// reads as another value than the file wrote (`fov_x_deg = 179.99999999` reads as 180).
    InvalidAsRead {
        /// Why the area is invalid.
        error: AreaError,
        /// The number as the file wrote it.
        written: String,
        /// The number as read.
        read: f32,
    },
    /// An experiments file (`[[config]]` tables) has no entry for the scene.
    NoneForScene {
        /// The scene's name.
        scene: String,
        /// The distinct `file` values the entries name, in file order.
        files: Vec<String>,
    },
}

/// The two kinds of influence area, as an area file spells them.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum AreaKind {
    /// `kind = "plane"`: an oriented box of parallel rays.
    Plane,
    /// `kind = "point"`: a frustum of radial rays.
    Point,
}

impl AreaKind {
    /// The value of `kind`.
    pub fn name(self) -> &'static str {
        match self {
            AreaKind::Plane => "plane",
            AreaKind::Point => "point",
        }
    }

    /// The keys an entry of this kind must have, besides `kind`, in `experiments.toml` order.
    pub fn keys(self) -> &'static [&'static str] {
        match self {
            AreaKind::Plane => &["center", "normal", "half_width", "half_height", "depth"],
            AreaKind::Point => &["eye", "direction", "fov_x_deg", "fov_y_deg", "near", "far"],
        }
    }
}

impl fmt::Display for AreasError {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        write!(f, "{}", self.path.display())?;
        if let Some(line) = self.line {
            write!(f, " line {line}")?;
        }
        f.write_str(": ")?;
        if let Some((table, index)) = self.entry {
            write!(f, "{} {index}: ", table.entry_name())?;
        }
        self.kind.fmt(f)
    }
}

impl fmt::Display for AreasErrorKind {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        match self {
            AreasErrorKind::Io(e) => write!(f, "cannot read: {e}"),
            AreasErrorKind::Syntax(why) => write!(f, "not a valid area file: {why}"),
            AreasErrorKind::NoAreas => f.write_str(
                "no areas: list each as an [[area]] table with kind = \"plane\" or \"point\" \
                 (or [[config]] tables, as in experiments.toml)",
            ),
            AreasErrorKind::BothTables => f.write_str(
                "has both [[area]] and [[config]] tables; use one kind, so the order of the areas \
                 is clear",
            ),
            AreasErrorKind::MissingKey { key, area_kind } => {
                write!(f, "missing key `{key}`")?;
                match area_kind {
                    Some(k) => write!(f, " (a {} area needs {})", k.name(), k.keys().join(", ")),
                    None => f.write_str(" (\"plane\" or \"point\")"),
                }
            }
            AreasErrorKind::WrongType {
                key,
                expected,
                found,
            } => write!(f, "`{key}` must be {expected}, not {found}"),
            AreasErrorKind::UnknownKind(kind) => {
                // Debug-quoted: a value is echoed escaped, so the message stays one line.
                write!(f, "unknown kind {kind:?} (expected \"plane\" or \"point\")")
            }
            AreasErrorKind::UnknownKey { key, area_kind } => write!(
                f,
                "unknown key `{}` for a {} area (expected kind, {}; scene, file, orientation \
                 and thesis_test are allowed and ignored)",
                key.escape_debug(),
                area_kind.name(),
                area_kind.keys().join(", ")
            ),
            AreasErrorKind::Invalid(e) => e.fmt(f),
            AreasErrorKind::InvalidAsRead {
                error,
                written,
                read,
            } => write!(
                f,
                "{error}; {} reads as {read} in single precision",
                written.escape_debug()
            ),
            AreasErrorKind::NoneForScene { scene, files } => {
                write!(
                    f,
                    "no [[config]] entry is for scene {} (entries are matched by their \
                     `file` key",
                    scene.escape_debug()
                )?;
                if files.is_empty() {
                    f.write_str(", and none has one)")
                } else {
                    write!(f, "; this file names {})", files.join(", ").escape_debug())
                }
            }
        }
    }
}

impl std::error::Error for AreasError {
    fn source(&self) -> Option<&(dyn std::error::Error + 'static)> {
        match &self.kind {
            AreasErrorKind::Io(e) => Some(e),
            _ => None,
        }
    }
}
