//! Influence-area files: where a renderer's rays are coherent, written as TOML.
//!
//! An area file lists `[[area]]` tables with exactly the keys of a `[[config]]` entry of the
//! thesis's `experiments.toml`, so an entry can be pasted from there:
//!
//! ```toml
//! [[area]]                      # parallel rays below a planar light
//! kind = "plane"
//! center = [5.0, 9.9, 5.0]      # centre of the light rectangle
//! normal = [0.0, -1.0, 0.0]     # the ray direction (any length)
//! half_width = 1.0
//! half_height = 1.0
//! depth = 9.9                   # how far the box reaches along `normal`
//!
//! [[area]]                      # radial rays from a point or spot light
//! kind = "point"
//! eye = [5.0, 9.0, 5.0]
//! direction = [0.0, -1.0, 0.0]
//! fov_x_deg = 90.0
//! fov_y_deg = 60.0
//! near = 0.1
//! far = 10.0
//! ```
//!
//! Vectors are arrays of three numbers, numbers are integers or floats. The experiment keys
//! `scene`, `file`, `orientation` and `thesis_test` are allowed (strings) and do not change the
//! area; any other key is an error, since a misspelt key would otherwise vanish silently.
//! Other top-level keys and tables (`scene_dir`, `[settings]`) are ignored.
//!
//! A file of `[[config]]` tables instead, such as `experiments.toml` itself, is read the same way
//! but is a list of experiments over many scenes: [`AreaFile::for_scene`] keeps only the entries
//! whose `file` names the scene. A file may not mix the two.

mod error;
mod parse;

pub use error::{AreaKind, AreasError, AreasErrorKind};
pub use parse::{parse_areas, read_areas};

use std::path::{Path, PathBuf};

use rdbvh_core::influence::InfluenceArea;

use crate::scene::BUILTIN_PREFIX;

/// Which array of tables an area file uses.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum TableKind {
    /// `[[area]]`: every entry applies to whatever scene the file is used with.
    Area,
    /// `[[config]]` (as in `experiments.toml`): each entry is for the scene its `file` names.
    Config,
}

impl TableKind {
    /// How errors name one entry: `area` or `config`.
    pub fn entry_name(self) -> &'static str {
        match self {
            TableKind::Area => "area",
            TableKind::Config => "config",
        }
    }
}

/// One entry of an area file: the area and the experiment keys that came with it.
#[derive(Clone, Debug, PartialEq)]
pub struct AreaEntry {
    /// The influence area.
    pub area: InfluenceArea,
    /// 0-based position among the file's tables.
    pub index: usize,
    /// 1-based line of the entry's table.
    pub line: usize,
    /// `scene`, if given: the experiment's scene name.
    pub scene: Option<String>,
    /// `file`, if given: the experiment's OBJ file name.
    pub file: Option<String>,
    /// `orientation`, if given (`parallel`, `15deg`, `45deg`, `oblique`).
    pub orientation: Option<String>,
    /// `thesis_test`, if given: the thesis's name of the run.
    pub thesis_test: Option<String>,
}

/// A parsed area file.
#[derive(Clone, Debug, PartialEq)]
pub struct AreaFile {
    /// Where it was read from (or the label given to [`parse_areas`]).
    pub path: PathBuf,
    /// Whether the entries were `[[area]]` or `[[config]]` tables.
    pub tables: TableKind,
    /// The entries in file order; never empty.
    pub entries: Vec<AreaEntry>,
}

impl AreaFile {
    /// The areas of every entry, in file order.
    pub fn areas(&self) -> Vec<InfluenceArea> {
        self.entries.iter().map(|e| e.area).collect()
    }

    /// The entries that apply to the scene named `scene` (a file name or path, or
    /// `builtin:NAME`): all of them for `[[area]]` tables; for `[[config]]` tables, those whose
    /// `file` has the scene's file stem, ignoring case (so `builtin:random100` takes the
    /// `Random100.obj` entries). Never empty: an experiments file without an entry for the
    /// scene is an error naming the files it does have entries for.
    pub fn for_scene(&self, scene: &str) -> Result<Vec<&AreaEntry>, AreasError> {
        if self.tables == TableKind::Area {
            return Ok(self.entries.iter().collect());
        }
        let wanted = scene_stem(scene);
        let found: Vec<&AreaEntry> = self
            .entries
            .iter()
            .filter(|e| {
                e.file
                    .as_deref()
                    .is_some_and(|f| scene_stem(f).eq_ignore_ascii_case(wanted))
            })
            .collect();
        if !found.is_empty() {
            return Ok(found);
        }
        let mut files: Vec<String> = Vec::new();
        for f in self.entries.iter().filter_map(|e| e.file.as_ref()) {
            if !files.contains(f) {
                files.push(f.clone());
            }
        }
        Err(AreasError {
            path: self.path.clone(),
            line: None,
            entry: None,
            kind: AreasErrorKind::NoneForScene {
                scene: scene.to_string(),
                files,
            },
        })
    }
}

/// `WoodScene` for `dir/WoodScene.obj`, `random100` for `builtin:random100`.
fn scene_stem(scene: &str) -> &str {
    if let Some(name) = scene.strip_prefix(BUILTIN_PREFIX) {
        return name;
    }
    Path::new(scene)
        .file_stem()
        .and_then(|s| s.to_str())
        .unwrap_or(scene)
}
