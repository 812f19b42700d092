//! `results.csv`: one row per run under the thesis's column names, plus this project's columns;
//! and reading the thesis's own result files back.

use std::collections::HashMap;
use std::path::{Path, PathBuf};

use rdbvh_core::analyze::THESIS_LEVELS;

use super::run::RunMetrics;
use super::ExperimentError;
use crate::text_lines::line_at;

/// The columns of the thesis's `Plane_*.csv` / `Point_*.csv` files, in their order. Every one is
/// in `results.csv` under the same name. The four build-profile columns (`Compute cost PAH
/// average` .. `Choose split plane PAH average count`) are this project's phase timers, from a
/// second build with a clock (see the module docs): their `count` columns count sweeps per priced
/// node and choices per inner node, not what the thesis's timers counted (its files hold 35 to
/// 73 there), so they do not compare with the thesis's.
pub const THESIS_COLUMNS: [&str; 26] = [
    "Scene",
    "Estimated PAH cost",
    "Estimated SAH cost",
    "Real cost with fallback",
    "Intersections with fallback",
    "Real cost without fallback",
    "Intersections without fallback",
    "Fallback BVH cost",
    "Only fallback cost",
    "Hit percentage",
    "Overlapping % 4",
    "Overlapping % culled 4",
    "Overlapping % culled 7",
    "Overlapping % culled 10",
    "Overlapping % culled 15",
    "Overlapping % culled 100",
    "Max level",
    "Max triangles per leaf",
    "Max non fallback levels",
    "Split plane quality threshold",
    "Acceptable children/father hit probability",
    "Excellent children/father hit probability",
    "Compute cost PAH average",
    "Compute cost PAH average count",
    "Choose split plane PAH average",
    "Choose split plane PAH average count",
];

/// One run's row.
#[derive(Clone, Debug, PartialEq)]
pub struct RunRow {
    /// `<Scene>_<Plane|Point>_<Parallel|15|45|Oblique>_<Full|Longest|Facing|Standard>` (the
    /// configuration's `thesis_test` and the preset).
    pub name: String,
    /// The configuration's scene name.
    pub scene: String,
    /// `Plane` or `Point`.
    pub kind: String,
    /// `Parallel`, `15`, `45` or `Oblique`.
    pub orientation: String,
    /// The preset's thesis name.
    pub heuristic: String,
    /// `thesis` or `project`.
    pub mode: String,
    /// Largest leaf allowed.
    pub max_leaf: u32,
    /// The file's `max_levels`.
    pub max_levels: u32,
    /// The preset's cut quality threshold.
    pub quality_threshold: f32,
    /// Acceptable ratio.
    pub acceptable_ratio: f32,
    /// Excellent ratio.
    pub excellent_ratio: f32,
    /// What was measured.
    pub metrics: RunMetrics,
}

fn level(v: &[f32], l: u32) -> f32 {
    THESIS_LEVELS
        .iter()
        .position(|&x| x == l)
        .and_then(|i| v.get(i).copied())
        .unwrap_or(0.0)
}

/// The header of `results.csv`: the thesis's columns, then this project's.
pub fn header() -> Vec<String> {
    let mut h: Vec<String> = THESIS_COLUMNS.iter().map(|s| s.to_string()).collect();
    for l in &THESIS_LEVELS[1..] {
        h.push(format!("Overlapping % {l}"));
    }
    for l in THESIS_LEVELS {
        h.push(format!("Overlapping 3D % {l}"));
    }
    h.extend(
        [
            "Estimated PAH cost relative to root",
            "EPO",
            "Closest-hit cost with fallback",
            "Closest-hit cost without fallback",
            "Closest-hit cost fallback BVH alone",
            "Closest-hit local answer percentage",
            "Any-hit cost with fallback",
            "Any-hit cost fallback BVH alone",
            "Rays per second",
            "Rays per second fallback BVH alone",
            "Build milliseconds",
            "Rays",
            "Local triangles",
            "Nodes",
            "Leaves",
            "Mean leaf depth",
            "Local BVH bytes",
            "Fallback BVH bytes",
            "Fallback SAH cost",
            "Octree levels",
            "Octree leaves",
            "Octree bytes",
            "Area bytes",
            "Kind",
            "Orientation",
            "Heuristic",
            "Mode",
        ]
        .map(String::from),
    );
    h
}

/// A row's fields, in [`header`] order.
pub fn fields(r: &RunRow) -> Vec<String> {
    let m = &r.metrics;
    let c = &m.costs;
    let f = |x: f32| format!("{x}");
    let mut v = vec![
        r.name.clone(),
        f(m.pah),
        f(m.sah),
        f(c.all_hit_structure),
        f(c.intersections_structure),
        f(c.all_hit_local),
        f(c.intersections_local),
        f(c.all_hit_fallback_alone),
        f(c.all_hit_fallback_when_fell_back),
        f(c.local_hit_rate),
        f(level(&m.overlap_projected, 4)),
    ];
    for l in THESIS_LEVELS {
        v.push(f(level(&m.overlap_culled, l)));
    }
    v.push(m.shape.levels().to_string());
    v.push(r.max_leaf.to_string());
    v.push(r.max_levels.to_string());
    v.push(f(r.quality_threshold));
    v.push(f(r.acceptable_ratio));
    v.push(f(r.excellent_ratio));
    // The thesis's profile columns: mean microseconds per call, and calls per priced node.
    let p = &m.profile;
    let per_call = |ns: u64, calls: u64| ns as f64 / 1e3 / calls.max(1) as f64;
    let per_node = |calls: u64| calls as f64 / p.choose_calls.max(1) as f64;
    v.extend([
        format!("{}", per_call(p.cost_ns, p.cost_calls)),
        format!("{}", per_node(p.cost_calls)),
        format!("{}", per_call(p.choose_ns, p.choose_calls)),
        format!("{}", p.choose_calls as f64 / m.shape.inner.max(1) as f64),
    ]);
    for l in &THESIS_LEVELS[1..] {
        v.push(f(level(&m.overlap_projected, *l)));
    }
    for l in THESIS_LEVELS {
        v.push(f(level(&m.overlap_3d, l)));
    }
    v.extend([
        f(m.pah_root),
        f(m.epo),
        f(c.closest_hit_structure),
        f(c.closest_hit_local),
        f(c.closest_hit_fallback_alone),
        f(c.closest_hit_local_rate),
        f(c.any_hit_structure),
        f(c.any_hit_fallback_alone),
        format!("{:.0}", m.rays_per_second),
        format!("{:.0}", m.rays_per_second_fallback),
        format!("{:.3}", m.build_ms),
        c.rays.to_string(),
        m.local_triangles.to_string(),
        m.shape.nodes.to_string(),
        m.shape.leaves.to_string(),
        f(m.shape.mean_leaf_depth),
        m.shape.memory_bytes.to_string(),
        m.fallback_bytes.to_string(),
        f(m.fallback_sah),
        m.octree.levels.to_string(),
        m.octree.leaves.to_string(),
        m.octree.bytes.to_string(),
        m.area_bytes.to_string(),
        r.kind.clone(),
        r.orientation.clone(),
        r.heuristic.clone(),
        r.mode.clone(),
    ]);
    v
}

/// Writes `results.csv`.
pub fn write_results(path: &Path, rows: &[RunRow]) -> Result<(), ExperimentError> {
    let err = |e: csv::Error| ExperimentError::Csv(format!("{}: {e}", path.display()));
    let mut w = csv::Writer::from_path(path).map_err(err)?;
    w.write_record(header()).map_err(err)?;
    for r in rows {
        w.write_record(fields(r)).map_err(err)?;
    }
    w.flush()
        .map_err(|e| ExperimentError::Io(path.to_path_buf(), e.to_string()))
}

/// A result table read back: per run name, its numeric columns.
pub type Table = HashMap<String, HashMap<String, f64>>;

/// Reads a results CSV (ours or one of the thesis's) into a [`Table`]; non-numeric fields (our
/// text columns, such as `Mode`) are skipped.
pub fn read_table(path: &Path) -> Result<Table, ExperimentError> {
    read_table_checked(path, false)
}

/// [`read_table`]; with `numeric`, every field but the run name must be a number (the thesis's
/// files are all numbers, and a field skipped would silently change its averages).
fn read_table_checked(path: &Path, numeric: bool) -> Result<Table, ExperimentError> {
    let err = |e: csv::Error| ExperimentError::Csv(format!("{}: {e}", path.display()));
    let mut r = csv::Reader::from_path(path).map_err(err)?;
    let header: Vec<String> = r.headers().map_err(err)?.iter().map(String::from).collect();
    if header.first().map(String::as_str) != Some("Scene") {
        return Err(ExperimentError::Csv(format!(
            "{}: the first column is not `Scene`",
            path.display()
        )));
    }
    let mut out = Table::new();
    for rec in r.records() {
        let rec = rec.map_err(err)?;
        let Some(name) = rec.get(0) else { continue };
        if numeric {
            let bad = header
                .iter()
                .zip(rec.iter())
                .skip(1)
                .find(|(_, v)| v.trim().parse::<f64>().is_err());
            if let Some((column, value)) = bad {
                // Counted in the file itself: the reader's count misses CRLF lines.
                let at = rec.position().map_or(0, |p| p.byte());
                let line = std::fs::read(path).map_or(0, |text| line_at(&text, at));
                return Err(ExperimentError::Csv(format!(
                    "{} line {line}: column `{column}` of {name} is `{value}`, not a number",
                    path.display()
                )));
            }
        }
        let cols = header
            .iter()
            .zip(rec.iter())
            .skip(1)
            .filter_map(|(h, v)| v.trim().parse::<f64>().ok().map(|x| (h.clone(), x)))
            .collect();
        out.insert(name.to_string(), cols);
    }
    Ok(out)
}

/// Reads the thesis's `Plane_*.csv` and `Point_*.csv` files in `dir` into one table.
pub fn read_thesis_results(dir: &Path) -> Result<Table, ExperimentError> {
    read_thesis_files(&thesis_result_files(dir)?)
}

/// Reads the thesis's result `files` (as [`thesis_result_files`] lists them) into one table.
pub fn read_thesis_files(files: &[PathBuf]) -> Result<Table, ExperimentError> {
    let mut out = Table::new();
    for f in files {
        out.extend(read_table_checked(f, true)?);
    }
    Ok(out)
}

/// The thesis's result files in `dir` (`Plane_*.csv` and `Point_*.csv`), sorted; an error when
/// there is none.
pub fn thesis_result_files(dir: &Path) -> Result<Vec<PathBuf>, ExperimentError> {
    let entries = std::fs::read_dir(dir)
        .map_err(|e| ExperimentError::Io(dir.to_path_buf(), e.to_string()))?;
    let mut files: Vec<_> = entries
        .filter_map(Result::ok)
        .map(|e| e.path())
        .filter(|p| {
            let n = p.file_name().and_then(|n| n.to_str()).unwrap_or("");
            (n.starts_with("Plane_") || n.starts_with("Point_")) && n.ends_with(".csv")
        })
        .collect();
    files.sort();
    if files.is_empty() {
        return Err(ExperimentError::Csv(format!(
            "{}: no Plane_*.csv or Point_*.csv file",
            dir.display()
        )));
    }
    Ok(files)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn results_have_the_thesis_columns_first() {
        let h = header();
        assert_eq!(
            &h[..THESIS_COLUMNS.len()],
            &THESIS_COLUMNS.map(String::from)[..]
        );
        for extra in [
            "EPO",
            "Build milliseconds",
            "Rays per second",
            "Closest-hit cost with fallback",
        ] {
            assert!(h.iter().any(|c| c == extra), "{extra}");
        }
        let row = RunRow {
            name: "X_Plane_Parallel_Full".into(),
            scene: "X".into(),
            kind: "Plane".into(),
            orientation: "Parallel".into(),
            heuristic: "Full".into(),
            mode: "thesis".into(),
            max_leaf: 2,
            max_levels: 100,
            quality_threshold: 0.4,
            acceptable_ratio: 1.3,
            excellent_ratio: 0.9,
            metrics: RunMetrics::default(),
        };
        assert_eq!(fields(&row).len(), h.len());
    }

    /// A non-numeric field of a thesis file names its line, also in a CRLF file.
    #[test]
    fn non_numeric_thesis_fields_name_their_line() {
        let dir = std::env::temp_dir().join(format!("rdbvh-results-{}", std::process::id()));
        std::fs::create_dir_all(&dir).unwrap();
        for end in ["\n", "\r\n"] {
            let file = dir.join("Plane_x.csv");
            let text = [
                "Scene,Hit percentage",
                "A_Full,0.5",
                "B_Full,0.25",
                "C_Full,x",
                "",
            ]
            .join(end);
            std::fs::write(&file, text).unwrap();
            let e = read_thesis_results(&dir).unwrap_err().to_string();
            assert!(
                e.contains("line 4: column `Hit percentage` of C_Full"),
                "{end:?}: {e}"
            );
        }
        std::fs::remove_dir_all(&dir).ok();
    }

    #[test]
    fn thesis_files_match_our_header_when_present() {
        let dir = Path::new(env!("CARGO_MANIFEST_DIR")).join("../../shared/thesis/results");
        let Ok(t) = read_thesis_results(&dir) else {
            return; // the thesis's files are not part of the repository
        };
        assert_eq!(t.len(), 256);
        let mut r = csv::Reader::from_path(dir.join("Plane_FullStandard_NoSponza.csv")).unwrap();
        let theirs: Vec<String> = r.headers().unwrap().iter().map(String::from).collect();
        assert_eq!(theirs, THESIS_COLUMNS.map(String::from).to_vec());
    }
}
