//! The experiment file: `scene_dir`, `[settings]` and the `[[config]]` entries.

use std::collections::HashMap;
use std::path::{Path, PathBuf};

use rdbvh_core::builder::{Preset, PresetOptions, ThesisCut};
use rdbvh_core::heuristics::CostConstants;
use serde::Deserialize;

use super::{orientation_group, run_base_name, ExperimentError};
use crate::areas::{parse_areas, AreaEntry, AreasErrorKind, TableKind};

/// `[settings]`: every key is optional. `rays_per_config` and `heuristics` apply in every mode;
/// the builder keys apply only with `--thesis-mode` (without it the project's binned builder runs
/// with its own defaults, see [`PresetOptions::default`]).
#[derive(Clone, Debug, Deserialize, PartialEq)]
#[serde(deny_unknown_fields, default)]
pub struct Settings {
    /// Rays traced per run (default 1000, the thesis's).
    pub rays_per_config: u32,
    /// Presets run on every configuration (default the thesis's four: full, longest, facing,
    /// standard).
    pub heuristics: Vec<String>,
    /// Candidate split planes per axis, uniformly over the node box (thesis mode; default 40).
    pub candidate_planes: u32,
    /// Largest leaf (thesis mode; default 2).
    pub max_triangles_per_leaf: u32,
    /// The thesis's depth limit (thesis mode; default 100, clamped to this project's bound of 64,
    /// `rdbvh_core::bvh::MAX_DEPTH`). A limit below what the leaf size needs makes the nodes at
    /// it leaves of any size, as in the thesis's builder.
    pub max_levels: u32,
    /// Octree levels of the top-level structure (every mode; default 5).
    pub octree_levels: u32,
    /// Cost per visited inner node, counted twice (thesis mode; default 1.0).
    pub inner_node_cost: f32,
    /// Cost per triangle test (thesis mode; default 1.2).
    pub triangle_cost: f32,
    /// SPFH's cut-evaluation quality threshold (thesis mode; default 0.4).
    pub spfh_quality_threshold: f32,
    /// LSPH's quality threshold (thesis mode; default 0.99).
    pub lsph_quality_threshold: f32,
    /// Acceptable `(P_left + P_right) / P_parent` (thesis mode; default 1.3).
    pub acceptable_ratio: f32,
    /// Excellent ratio (thesis mode; default 0.9).
    pub excellent_ratio: f32,
}

impl Default for Settings {
    fn default() -> Self {
        Self {
            rays_per_config: 1000,
            heuristics: ["full", "longest", "facing", "standard"]
                .map(String::from)
                .to_vec(),
            candidate_planes: 40,
            max_triangles_per_leaf: 2,
            max_levels: 100,
            octree_levels: 5,
            inner_node_cost: 1.0,
            triangle_cost: 1.2,
            spfh_quality_threshold: 0.4,
            lsph_quality_threshold: 0.99,
            acceptable_ratio: 1.3,
            excellent_ratio: 0.9,
        }
    }
}

impl Settings {
    /// The builder options for the local BVHs: the file's builder keys in thesis mode, the
    /// project's defaults otherwise.
    pub fn preset_options(&self, thesis_mode: bool) -> PresetOptions {
        if !thesis_mode {
            return PresetOptions::default();
        }
        PresetOptions {
            bins: self.candidate_planes.saturating_add(1),
            max_leaf: self.max_triangles_per_leaf,
            constants: self.constants(true),
            cut: ThesisCut {
                excellent_ratio: self.excellent_ratio,
                acceptable_ratio: self.acceptable_ratio,
                quality_threshold: self.spfh_quality_threshold,
            },
            lsph_quality_threshold: self.lsph_quality_threshold,
            // The thesis's `max_levels` (100) is above the core's bound: clamped to 64.
            max_depth: self.max_levels.min(rdbvh_core::bvh::MAX_DEPTH),
            ..PresetOptions::thesis()
        }
    }

    /// The cost constants of estimates and measurements: the file's in thesis mode (an inner node
    /// counted twice), `C_trav = C_isect = 1` otherwise.
    pub fn constants(&self, thesis_mode: bool) -> CostConstants {
        if thesis_mode {
            CostConstants {
                traversal: 2.0 * self.inner_node_cost,
                intersection: self.triangle_cost,
            }
        } else {
            CostConstants::default()
        }
    }

    /// Checks every value's range, as the command line checks its overrides, so a bad file is an
    /// error naming its key and line rather than a failure of some later step (or a run that
    /// quietly does something else). `text` is the file, to find the key's line.
    fn check(&self, text: &str, path: &Path) -> Result<(), ExperimentError> {
        let finite_non_negative = |x: f32| x.is_finite() && x >= 0.0;
        let max_octree = rdbvh_core::toplevel::MAX_OCTREE_LEVELS;
        let rules: [(&str, bool, String); 11] = [
            (
                "rays_per_config",
                self.rays_per_config >= 1,
                "must be at least 1".into(),
            ),
            (
                "candidate_planes",
                (1..=MAX_CANDIDATE_PLANES).contains(&self.candidate_planes),
                format!(
                    "must be between 1 and {MAX_CANDIDATE_PLANES} (planes + 1 bins, at most 64)"
                ),
            ),
            (
                "max_triangles_per_leaf",
                self.max_triangles_per_leaf >= 1,
                "must be at least 1".into(),
            ),
            (
                "max_levels",
                self.max_levels >= 1,
                "must be at least 1".into(),
            ),
            (
                "octree_levels",
                (1..=max_octree).contains(&self.octree_levels),
                format!("must be between 1 and {max_octree}"),
            ),
            (
                "inner_node_cost",
                finite_non_negative(self.inner_node_cost),
                "must be finite and >= 0".into(),
            ),
            (
                "triangle_cost",
                self.triangle_cost.is_finite() && self.triangle_cost > 0.0,
                "must be finite and > 0".into(),
            ),
            (
                "spfh_quality_threshold",
                finite_non_negative(self.spfh_quality_threshold),
                "must be finite and >= 0".into(),
            ),
            (
                "lsph_quality_threshold",
                finite_non_negative(self.lsph_quality_threshold),
                "must be finite and >= 0".into(),
            ),
            (
                "acceptable_ratio",
                finite_non_negative(self.acceptable_ratio),
                "must be finite and >= 0".into(),
            ),
            (
                "excellent_ratio",
                finite_non_negative(self.excellent_ratio),
                "must be finite and >= 0".into(),
            ),
        ];
        let at_key = |key: &str, why: &str| {
            let line = settings_line(text, key)
                .map(|n| format!(" line {n}"))
                .unwrap_or_default();
            ExperimentError::Settings(format!("{}{line}: `{key}` {why}", path.display()))
        };
        if let Some((key, _, why)) = rules.into_iter().find(|(_, ok, _)| !ok) {
            return Err(at_key(key, &why));
        }
        // Checked even when --presets overrides them: a bad file is a bad file.
        match self.presets() {
            Ok(_) => Ok(()),
            Err(e) => Err(at_key("heuristics", &format!("lists {e}"))),
        }
    }

    /// The presets named in `heuristics`, checked.
    pub fn presets(&self) -> Result<Vec<Preset>, ExperimentError> {
        parse_presets(self.heuristics.iter().map(String::as_str))
    }
}

/// Presets from their names (`full`, `longest`, `facing`, `standard`, `sah`, `pah`), without
/// repeats.
pub fn parse_presets<'a>(
    names: impl IntoIterator<Item = &'a str>,
) -> Result<Vec<Preset>, ExperimentError> {
    let mut out = Vec::new();
    for name in names {
        let name = name.trim();
        let p = Preset::from_name(name).ok_or_else(|| {
            ExperimentError::Settings(format!(
                "unknown heuristic `{name}` (expected full, longest, facing, standard, sah or pah)"
            ))
        })?;
        if !out.contains(&p) {
            out.push(p);
        }
    }
    if out.is_empty() {
        return Err(ExperimentError::Settings("no heuristic to run".into()));
    }
    Ok(out)
}

/// The most candidate planes per axis `candidate_planes` (and `--candidate-planes`) may name: a
/// node box gets one bin more than planes, and a sweep at most 64 bins.
pub const MAX_CANDIDATE_PLANES: u32 = rdbvh_core::builder::MAX_BINS - 1;

/// The line (from 1) of `key = ...` in the file's `[settings]` table, if it is written there.
fn settings_line(text: &str, key: &str) -> Option<usize> {
    let mut in_settings = false;
    for (i, line) in text.lines().enumerate() {
        let line = line.trim_start();
        if line.starts_with('[') {
            // `[settings]`, `[ settings ]`, with or without a trailing comment.
            let header = line.split('#').next().unwrap_or("").trim();
            in_settings = header
                .strip_prefix('[')
                .and_then(|h| h.strip_suffix(']'))
                .is_some_and(|h| h.trim() == "settings");
        } else if in_settings {
            let is_key = line
                .strip_prefix(key)
                .is_some_and(|rest| rest.trim_start().starts_with('='));
            if is_key {
                return Some(i + 1);
            }
        }
    }
    None
}

/// The file's top level. Unknown keys are errors: a misspelt `[setting]` table would otherwise
/// run every setting at its default without a word. The `[[config]]` (and `[[area]]`) tables are
/// read by [`parse_areas`], which checks their keys.
#[derive(Deserialize)]
#[serde(deny_unknown_fields)]
struct Top {
    #[serde(default)]
    scene_dir: Option<String>,
    #[serde(default)]
    settings: Settings,
    #[serde(default, rename = "config")]
    _config: Option<toml::Value>,
    #[serde(default, rename = "area")]
    _area: Option<toml::Value>,
}

/// A parsed experiment file.
#[derive(Clone, Debug)]
pub struct ExperimentFile {
    /// Where it was read from.
    pub path: PathBuf,
    /// Where scene files are found: `scene_dir` relative to the file's folder (default: the
    /// file's folder).
    pub scene_dir: PathBuf,
    /// `[settings]`.
    pub settings: Settings,
    /// The `[[config]]` entries, in file order.
    pub configs: Vec<AreaEntry>,
}

impl ExperimentFile {
    /// Reads and checks an experiment file.
    pub fn read(path: &Path) -> Result<Self, ExperimentError> {
        let io = |why: String| ExperimentError::Io(path.to_path_buf(), why);
        let bytes = std::fs::read(path).map_err(|e| io(e.to_string()))?;
        let text = crate::text_lines::utf8_text(bytes).map_err(|at| io(at.to_string()))?;
        Self::parse(&text, path)
    }

    /// Parses an experiment file's text; `path` locates `scene_dir` and labels errors.
    pub fn parse(text: &str, path: &Path) -> Result<Self, ExperimentError> {
        let top: Top = toml::from_str(text).map_err(|e| toml_error(&e, text, path))?;
        top.settings.check(text, path)?;
        let areas = parse_areas(text, path).map_err(|e| match e.kind {
            // The area files' wording names [[area]] tables first; an experiment lists configs.
            AreasErrorKind::NoAreas => ExperimentError::Areas(format!(
                "{}: no configurations: list each as a [[config]] table with kind = \"plane\" or \
                 \"point\", as in the thesis's experiments.toml",
                path.display()
            )),
            _ => ExperimentError::Areas(e.to_string()),
        })?;
        if areas.tables == TableKind::Area {
            return Err(ExperimentError::Areas(format!(
                "{}: an experiment runs [[config]] tables, each naming its scene with `file = ...`; \
                 [[area]] tables (for build, trace and analyze) name none, so nothing would run",
                path.display()
            )));
        }
        for e in &areas.entries {
            check_orientation(e, path)?;
        }
        check_run_names(&areas.entries, path)?;
        let base = path.parent().unwrap_or(Path::new("."));
        let scene_dir = match top.scene_dir {
            Some(d) => base.join(d),
            None => base.to_path_buf(),
        };
        Ok(Self {
            path: path.to_path_buf(),
            scene_dir,
            settings: top.settings,
            configs: areas.entries,
        })
    }
}

/// A TOML error of `text` (read from `path`) with the line of the offending key or value, when
/// the parser says where it is.
fn toml_error(e: &toml::de::Error, text: &str, path: &Path) -> ExperimentError {
    let line = e
        .span()
        .map(|at| format!(" line {}", text[..at.start].matches('\n').count() + 1))
        .unwrap_or_default();
    ExperimentError::Settings(format!(
        "{}{line}: {}",
        path.display(),
        e.message().lines().next().unwrap_or("invalid TOML")
    ))
}

/// The `[settings]` of an area or experiment file's `text` (the defaults without one), checked
/// as [`ExperimentFile::parse`] checks them: `analyze` reads an experiment file as an area file
/// and runs its areas with the experiment's settings.
pub fn settings_of(text: &str, path: &Path) -> Result<Settings, ExperimentError> {
    #[derive(Deserialize)]
    struct Only {
        #[serde(default)]
        settings: Settings,
    }
    let only: Only = toml::from_str(text).map_err(|e| toml_error(&e, text, path))?;
    only.settings.check(text, path)?;
    Ok(only.settings)
}

/// An `orientation` must name one of the thesis's groups (or be left out): it decides which
/// group a run joins, and an unknown one would drop the run from every group table.
fn check_orientation(e: &AreaEntry, path: &Path) -> Result<(), ExperimentError> {
    match e.orientation.as_deref() {
        Some(o) if orientation_group(Some(o)).is_none() => Err(ExperimentError::Areas(format!(
            "{} line {}: config {}: orientation \"{o}\" is not one of \"parallel\", \"15deg\", \
             \"45deg\", \"oblique\" (it names the run's group in the report)",
            path.display(),
            e.line,
            e.index
        ))),
        _ => Ok(()),
    }
}

/// Two configurations with one run name (the same `thesis_test`, or without one the same scene,
/// kind and orientation) would give `results.csv` two rows of each name, of which the report
/// could only take one.
fn check_run_names(entries: &[AreaEntry], path: &Path) -> Result<(), ExperimentError> {
    let mut seen: HashMap<String, &AreaEntry> = HashMap::new();
    for e in entries {
        let name = run_base_name(e);
        if let Some(first) = seen.insert(name.clone(), e) {
            return Err(ExperimentError::Areas(format!(
                "{} line {}: config {} has the run name {name} of config {} (line {}): give one \
                 of them its own thesis_test",
                path.display(),
                e.line,
                e.index,
                first.index,
                first.line
            )));
        }
    }
    Ok(())
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn every_key_is_optional_and_unknown_ones_are_errors() {
        let text = "[[config]]\nkind = \"plane\"\ncenter = [0.0, 0.0, 0.0]\nnormal = [0.0, 0.0, 1.0]\nhalf_width = 1.0\nhalf_height = 1.0\ndepth = 1.0\n";
        let f = ExperimentFile::parse(text, Path::new("/x/e.toml")).unwrap();
        assert_eq!(f.settings, Settings::default());
        assert_eq!(f.scene_dir, Path::new("/x"));
        assert_eq!(f.configs.len(), 1);
        let bad = format!("[settings]\nrays_per_confg = 3\n{text}");
        let e = ExperimentFile::parse(&bad, Path::new("e.toml")).unwrap_err();
        assert!(e.to_string().contains("rays_per_confg"), "{e}");
        assert!(e.to_string().starts_with("e.toml line 2: "), "{e}");
        let e = ExperimentFile::parse("[settings]\n", Path::new("e.toml")).unwrap_err();
        assert!(e.to_string().contains("no configurations"), "{e}");
        let areas = text.replace("[[config]]", "[[area]]");
        let e = ExperimentFile::parse(&areas, Path::new("e.toml")).unwrap_err();
        assert!(e.to_string().contains("[[config]] tables"), "{e}");
        // Values out of range name their key and line, as the command line's options do.
        for (setting, key) in [
            ("octree_levels = 50", "octree_levels"),
            ("candidate_planes = 64", "candidate_planes"),
            ("candidate_planes = 0", "candidate_planes"),
            ("triangle_cost = -1.0", "triangle_cost"),
            ("max_triangles_per_leaf = 0", "max_triangles_per_leaf"),
            ("rays_per_config = 0", "rays_per_config"),
            ("excellent_ratio = nan", "excellent_ratio"),
        ] {
            let bad = format!("[settings]\nheuristics = [\"sah\"]\n{setting}\n{text}");
            let e = ExperimentFile::parse(&bad, Path::new("e.toml")).unwrap_err();
            let e = e.to_string();
            assert!(e.starts_with(&format!("e.toml line 3: `{key}` ")), "{e}");
        }
        // The line is found under a header with a comment too (the thesis's file has one).
        let bad = format!("[settings]   # the thesis's\n\noctree_levels = 0\n{text}");
        let e = ExperimentFile::parse(&bad, Path::new("e.toml")).unwrap_err();
        assert!(e.to_string().starts_with("e.toml line 3: "), "{e}");
        let fine = format!("[settings]\ncandidate_planes = 63\noctree_levels = 10\n{text}");
        assert!(ExperimentFile::parse(&fine, Path::new("e.toml")).is_ok());
        assert!(parse_presets(["full", "bogus"]).is_err());
        assert_eq!(
            parse_presets(["Full", "full", "standard"]).unwrap(),
            vec![Preset::Full, Preset::Standard]
        );
    }

    #[test]
    fn run_names_orientations_and_top_level_keys_are_checked() {
        let config = |extra: &str| {
            format!(
                "[[config]]\nkind = \"plane\"\nfile = \"a.obj\"\n{extra}center = [0.0, 0.0, 0.0]\n\
                 normal = [0.0, 0.0, 1.0]\nhalf_width = 1.0\nhalf_height = 1.0\ndepth = 1.0\n"
            )
        };
        let parse = |text: &str| ExperimentFile::parse(text, Path::new("e.toml"));
        // Two lights on one scene and orientation: one run name, refused with both lines.
        let two = format!("{}{}", config(""), config(""));
        let e = parse(&two).unwrap_err().to_string();
        assert!(
            e.starts_with(
                "e.toml line 9: config 1 has the run name a_Plane_Unknown of config 0 (line 1)"
            ),
            "{e}"
        );
        let named = format!(
            "{}{}",
            config("thesis_test = \"x\"\n"),
            config("thesis_test = \"y\"\n")
        );
        assert!(parse(&named).is_ok());
        // An orientation must name a group; any case of a known one does.
        let e = parse(&config("orientation = \"45 deg\"\n"))
            .unwrap_err()
            .to_string();
        assert!(e.contains("orientation \"45 deg\" is not one of"), "{e}");
        assert!(parse(&config("orientation = \"PARALLEL\"\n")).is_ok());
        // A misspelt table or a setting at the top level is an error, not the defaults.
        for bad in ["[setting]\nrays_per_config = 3\n", "rays_per_config = 3\n"] {
            let e = parse(&format!("{bad}{}", config("")))
                .unwrap_err()
                .to_string();
            assert!(e.starts_with("e.toml line 1: unknown field"), "{e}");
        }
        // `analyze` reads the same [settings] from the file.
        let text = format!("[settings]\ncandidate_planes = 7\n{}", config(""));
        assert_eq!(
            settings_of(&text, Path::new("e.toml"))
                .unwrap()
                .candidate_planes,
            7
        );
        assert_eq!(
            settings_of(&config(""), Path::new("e.toml")).unwrap(),
            Settings::default()
        );
    }

    #[test]
    fn thesis_mode_takes_the_files_builder_values() {
        let s = Settings {
            candidate_planes: 10,
            inner_node_cost: 0.5,
            ..Settings::default()
        };
        let o = s.preset_options(true);
        assert_eq!(o.bins, 11);
        assert!(o.thesis_mode);
        assert_eq!(s.constants(true).traversal, 1.0);
        assert_eq!(s.preset_options(false), PresetOptions::default());
    }
}
