//! `rdbvh analyze`: every analyzer metric for one build over each influence area of a scene.

use std::io::Write;
use std::path::{Path, PathBuf};

use clap::Args;
use rdbvh_core::analyze::{analyze, containment, NodeRecord, NodeRecords, THESIS_LEVELS};
use rdbvh_core::builder::{BuildOptions, Preset};
use rdbvh_core::heuristics::AreaPah;
use rdbvh_core::heuristics::Sah;
use rdbvh_core::influence::InfluenceArea;
use rdbvh_core::toplevel::Octree;
use serde_json::{json, Value};

use super::areas::load_areas;
use super::error::CliError;
use super::inputs::load_scene;
use crate::experiment::{
    build_fallback, run_one, settings_of, ExperimentError, RaySource, RunMetrics, RunSetup,
    Settings,
};

/// The per-node columns `--nodes FILE.csv` can write.
pub const NODE_COLUMNS: [&str; 17] = [
    "index",
    "parent",
    "depth",
    "min_x",
    "min_y",
    "min_z",
    "max_x",
    "max_y",
    "max_z",
    "count",
    "left_first",
    "measure",
    "hit_probability",
    "is_leaf",
    "area",
    "pah_measure",
    "pah_hit_probability",
];

/// Arguments of `rdbvh analyze`.
#[derive(Args, Debug, Clone)]
pub struct AnalyzeArgs {
    /// The scene: an OBJ file, or builtin:NAME.
    #[arg(value_name = "SCENE.obj")]
    pub scene: String,
    /// Influence areas (TOML): one build and analysis per area that applies to the scene.
    #[arg(long, value_name = "AREAS.toml")]
    pub areas: PathBuf,
    /// The local BVH's preset: full, longest, facing, standard, sah or pah.
    #[arg(long, value_name = "NAME", default_value = "full")]
    pub preset: String,
    /// Rays traced per area for the measured costs (default: the file's
    /// `[settings]` rays_per_config, else 1000).
    #[arg(long, value_name = "N", value_parser = clap::value_parser!(u32).range(1..))]
    pub rays: Option<u32>,
    /// Measure every area on these rays instead of its sampler (as `experiment
    /// --recorded-rays`): a CSV as `rdbvh trace --rays` reads it, such as `rdbvh render
    /// --record-rays` writes.
    #[arg(long, value_name = "RAYS.csv", conflicts_with = "rays")]
    pub recorded_rays: Option<PathBuf>,
    /// The thesis's builder, constants, fallback and ray sampler (as `experiment --thesis-mode`,
    /// with the builder keys of the file's `[settings]` when it has them, as an experiment file
    /// does).
    #[arg(long)]
    pub thesis_mode: bool,
    /// Print one JSON object instead of the table.
    #[arg(long)]
    pub json: bool,
    /// Export the first area's local BVH per node: JSON (whole tree) for a `.json` file, CSV
    /// otherwise. Both hold the --columns fields under the same names: `measure` is the node's
    /// SAH measure (half its surface area), `hit_probability` that over its parent's (the chance
    /// that a uniform ray through the parent enters it), `area` its surface area; `pah_measure`
    /// is its measure under the area's PAH (projected area, or solid angle, inside the light's
    /// window) and `pah_hit_probability` that over its parent's (the chance that one of the
    /// area's rays through the parent enters it; 0 under a parent no such ray reaches); both
    /// probabilities are 1 at the root; `parent` is empty (CSV) or null (JSON) at the root.
    #[arg(long, value_name = "FILE")]
    pub nodes: Option<PathBuf>,
    /// CSV columns for --nodes, comma-separated (default: all of index, parent, depth, min_x,
    /// min_y, min_z, max_x, max_y, max_z, count, left_first, measure, hit_probability, is_leaf,
    /// area, pah_measure, pah_hit_probability).
    #[arg(long, value_name = "a,b", value_delimiter = ',', requires = "nodes")]
    pub columns: Option<Vec<String>>,
}

/// The run set-up of `experiment` for the areas file's `[settings]` (see [`settings_of`]) and
/// the arguments.
fn setup(args: &AnalyzeArgs, file: &Settings) -> RunSetup {
    use rdbvh_core::builder::PresetOptions;
    use rdbvh_core::influence::PointDistribution;
    let s = Settings {
        rays_per_config: args.rays.unwrap_or(file.rays_per_config),
        ..file.clone()
    };
    let local = s.preset_options(args.thesis_mode);
    RunSetup {
        local,
        fallback: if args.thesis_mode {
            local
        } else {
            PresetOptions::default()
        },
        fallback_preset: if args.thesis_mode {
            Preset::Standard
        } else {
            Preset::Sah
        },
        constants: s.constants(args.thesis_mode),
        rays: s.rays_per_config,
        octree_levels: s.octree_levels,
        point_distribution: if args.thesis_mode {
            PointDistribution::YawPitch
        } else {
            PointDistribution::SolidAngle
        },
    }
}

/// An `f32` as JSON by its shortest decimal, as the CSV export and the table write it (`json!`
/// widens it to `f64` first, which writes 20.73 as 20.729999542236328); `null` for NaN and
/// infinity, as `json!` gives.
fn real(x: f32) -> Value {
    x.to_string()
        .parse::<f64>()
        .ok()
        .and_then(serde_json::Number::from_f64)
        .map_or(Value::Null, Value::Number)
}

fn levels_json(v: &[f32]) -> Value {
    Value::Object(
        THESIS_LEVELS
            .iter()
            .zip(v)
            .map(|(l, &x)| (l.to_string(), real(x)))
            .collect(),
    )
}

fn metrics_json(area: usize, kind: &str, m: &RunMetrics, error: f32) -> Value {
    let c = &m.costs;
    let mut o = serde_json::Map::new();
    let mut put = |k: &str, v: Value| {
        o.insert(k.to_string(), v);
    };
    put("area", json!(area));
    put("kind", json!(kind));
    put("local_triangles", json!(m.local_triangles));
    put("build_ms", json!(m.build_ms));
    put("nodes", json!(m.shape.nodes));
    put("inner_nodes", json!(m.shape.inner));
    put("leaves", json!(m.shape.leaves));
    put("max_depth", json!(m.shape.max_depth));
    put("levels", json!(m.shape.levels()));
    put("mean_leaf_depth", real(m.shape.mean_leaf_depth));
    put("leaf_sizes", json!(m.shape.leaf_sizes));
    put("sah_cost", real(m.sah));
    put("pah_cost", real(m.pah));
    put("pah_cost_relative_to_root", real(m.pah_root));
    put("epo", real(m.epo));
    put("overlap_3d", json!(levels_json(&m.overlap_3d)));
    put(
        "overlap_projected",
        json!(levels_json(&m.overlap_projected)),
    );
    put("overlap_culled", json!(levels_json(&m.overlap_culled)));
    put("rays", json!(c.rays));
    put("all_hit_cost_with_fallback", real(c.all_hit_structure));
    put("all_hit_cost_without_fallback", real(c.all_hit_local));
    put(
        "all_hit_cost_fallback_part_when_fell_back",
        real(c.all_hit_fallback_when_fell_back),
    );
    put(
        "all_hit_cost_fallback_alone",
        real(c.all_hit_fallback_alone),
    );
    put(
        "intersections_with_fallback",
        real(c.intersections_structure),
    );
    put(
        "intersections_without_fallback",
        real(c.intersections_local),
    );
    put("local_hit_rate", real(c.local_hit_rate));
    put(
        "closest_hit_cost_with_fallback",
        real(c.closest_hit_structure),
    );
    put(
        "closest_hit_cost_without_fallback",
        real(c.closest_hit_local),
    );
    put(
        "closest_hit_cost_fallback_alone",
        real(c.closest_hit_fallback_alone),
    );
    put("closest_hit_local_rate", real(c.closest_hit_local_rate));
    put("any_hit_cost_with_fallback", real(c.any_hit_structure));
    put(
        "any_hit_cost_fallback_alone",
        real(c.any_hit_fallback_alone),
    );
    put("rays_per_second", json!(m.rays_per_second));
    put(
        "rays_per_second_fallback_alone",
        json!(m.rays_per_second_fallback),
    );
    put("local_bvh_bytes", json!(m.shape.memory_bytes));
    put("fallback_bvh_bytes", json!(m.fallback_bytes));
    put("fallback_sah_cost", real(m.fallback_sah));
    put("octree_levels", json!(m.octree.levels));
    put("octree_leaves", json!(m.octree.leaves));
    put("octree_bytes", json!(m.octree.bytes));
    put("octree_containment_error", real(error));
    put("area_bytes", json!(m.area_bytes));
    Value::Object(o)
}

/// One field of a node export, typed so the CSV and the JSON export write the same values.
enum Field {
    Int(u32),
    Real(f32),
    Flag(bool),
    Missing,
}

/// A node's records: under SAH, and under the area's PAH (the same node, other measures).
struct NodeRow<'a> {
    sah: &'a NodeRecord,
    pah: &'a NodeRecord,
}

/// Column `col` (one of [`NODE_COLUMNS`]) of node `row`; both exports take every value from here.
fn node_field(row: &NodeRow<'_>, col: &str) -> Field {
    let r = row.sah;
    match col {
        "pah_measure" => Field::Real(row.pah.measure),
        "pah_hit_probability" => Field::Real(row.pah.hit_probability),
        "index" => Field::Int(r.index),
        "parent" if r.parent == u32::MAX => Field::Missing,
        "parent" => Field::Int(r.parent),
        "depth" => Field::Int(r.depth),
        "min_x" => Field::Real(r.min[0]),
        "min_y" => Field::Real(r.min[1]),
        "min_z" => Field::Real(r.min[2]),
        "max_x" => Field::Real(r.max[0]),
        "max_y" => Field::Real(r.max[1]),
        "max_z" => Field::Real(r.max[2]),
        "count" => Field::Int(r.count),
        "left_first" => Field::Int(r.left_first),
        "measure" => Field::Real(r.measure),
        "hit_probability" => Field::Real(r.hit_probability),
        "is_leaf" => Field::Flag(r.count > 0),
        "area" => {
            let e = glam::Vec3::from(r.max) - glam::Vec3::from(r.min);
            Field::Real(2.0 * (e.x * e.y + e.y * e.z + e.z * e.x))
        }
        _ => Field::Missing,
    }
}

impl Field {
    /// The CSV cell: empty for a missing value (the root's parent).
    fn csv(&self) -> String {
        match self {
            Field::Int(v) => v.to_string(),
            Field::Real(v) => v.to_string(),
            Field::Flag(v) => v.to_string(),
            Field::Missing => String::new(),
        }
    }

    /// The JSON value: `null` for a missing value.
    fn json(&self) -> Value {
        match self {
            Field::Int(v) => json!(v),
            Field::Real(v) => real(*v),
            Field::Flag(v) => json!(v),
            Field::Missing => Value::Null,
        }
    }
}

/// True for a `.json` node export (JSON, the whole tree), false for CSV.
fn is_json(path: &Path) -> bool {
    path.extension()
        .is_some_and(|e| e.eq_ignore_ascii_case("json"))
}

/// Writes the node export: every field as JSON for a `.json` path, else the CSV `columns`.
fn write_nodes(path: &Path, records: &[NodeRow<'_>], columns: &[String]) -> Result<(), CliError> {
    let fail = |e: std::io::Error| CliError::Write {
        path: path.to_path_buf(),
        source: e,
    };
    if is_json(path) {
        let nodes: Vec<Value> = records
            .iter()
            .map(|r| {
                let fields = NODE_COLUMNS
                    .iter()
                    .map(|&c| (c.to_string(), node_field(r, c).json()));
                Value::Object(fields.collect())
            })
            .collect();
        let text = serde_json::to_string(&json!({ "nodes": nodes }))
            .map_err(|e| fail(std::io::Error::other(e)))?;
        return std::fs::write(path, text).map_err(fail);
    }
    let mut text = columns.join(",");
    text.push('\n');
    for r in records {
        let row: Vec<String> = columns.iter().map(|c| node_field(r, c).csv()).collect();
        text.push_str(&row.join(","));
        text.push('\n');
    }
    std::fs::write(path, text).map_err(fail)
}

/// The CSV export's columns: `--columns` checked (each a known column, none twice), or all.
fn node_columns(columns: Option<&[String]>) -> Result<Vec<String>, CliError> {
    let cols: Vec<String> = match columns {
        Some(c) => c.iter().map(|s| s.trim().to_string()).collect(),
        None => NODE_COLUMNS.iter().map(|s| s.to_string()).collect(),
    };
    for (i, col) in cols.iter().enumerate() {
        if !NODE_COLUMNS.contains(&col.as_str()) {
            return Err(CliError::Usage(format!(
                "unknown node column `{col}` (expected {})",
                NODE_COLUMNS.join(", ")
            )));
        }
        if cols[..i].contains(col) {
            return Err(CliError::Usage(format!(
                "node column `{col}` appears twice in --columns"
            )));
        }
    }
    Ok(cols)
}

/// Builds and analyses; prints a table (or JSON) to `out`.
pub fn run(args: &AnalyzeArgs, out: &mut dyn Write) -> Result<(), CliError> {
    let preset = Preset::from_name(&args.preset).ok_or_else(|| {
        CliError::Usage(format!(
            "unknown preset `{}` (expected full, longest, facing, standard, sah or pah)",
            args.preset
        ))
    })?;
    // Before any work, as clap's own checks are: a bad column must not wait for the analysis.
    let columns = node_columns(args.columns.as_deref())?;
    if let Some(nodes) = &args.nodes {
        let mut inputs = vec![Path::new(&args.scene), args.areas.as_path()];
        inputs.extend(args.recorded_rays.as_deref());
        super::inputs::check_output(nodes, &inputs)?;
        if args.columns.is_some() && is_json(nodes) {
            return Err(CliError::Usage(
                "--columns chooses the CSV export's columns; a .json export writes every field"
                    .into(),
            ));
        }
    }
    let (scene, _) = load_scene(&args.scene, args.nodes.as_deref())?;
    let source = super::rays::ray_source(args.recorded_rays.as_deref())?;
    let entries = load_areas(&args.areas, &scene)?;
    // Read again for its [settings] (load_areas has read it whole already).
    let text = std::fs::read_to_string(&args.areas)
        .map_err(|e| ExperimentError::Io(args.areas.clone(), e.to_string()))?;
    let setup = setup(args, &settings_of(&text, &args.areas)?);
    let fallback = build_fallback(&scene.triangles, &setup)?;
    let mut reports = Vec::new();
    for (i, entry) in entries.iter().enumerate() {
        let rays = source.rays_for(&entry.area, entry.index, &setup);
        let m = run_one(
            &scene.triangles,
            &entry.area,
            preset,
            &fallback,
            &rays,
            &setup,
        )?;
        let octree = Octree::build(&[entry.area], setup.octree_levels);
        let c = containment(&octree, &[entry.area], &entry.area.bounds(), 20_000, 1);
        let kind = match entry.area {
            InfluenceArea::Plane(_) => "plane",
            InfluenceArea::Point(_) => "point",
        };
        if i == 0 {
            if let Some(path) = &args.nodes {
                // The same build again, for its per-node records.
                let ids: Vec<u32> = entry.area.triangles_in(&scene.triangles).collect();
                let mut arena = rdbvh_core::builder::BuildArena::with_capacity(ids.len());
                arena.load_triangle_subset(&scene.triangles, ids)?;
                let mut bvh = rdbvh_core::bvh::Bvh::with_capacity(arena.len());
                BuildOptions::with_settings(preset, setup.local)
                    .build_into(&mut arena, Some(&entry.area), &mut bvh)
                    .map_err(|e| CliError::Usage(e.to_string()))?;
                let pah = AreaPah::new(&entry.area, setup.local.perspective);
                let (sah, pah) = analyze(&bvh, (NodeRecords::new(Sah), NodeRecords::new(pah)));
                let rows: Vec<NodeRow<'_>> = sah
                    .iter()
                    .zip(&pah)
                    .map(|(sah, pah)| NodeRow { sah, pah })
                    .collect();
                write_nodes(path, &rows, &columns)?;
            }
        }
        let mut report = metrics_json(entry.index + 1, kind, &m, c.error());
        // The rays the structure gives the local BVH: all of a sampler's, some of a recording's.
        report["affine_rays"] = json!(rays.iter().filter(|r| entry.area.is_affine(r)).count());
        reports.push(report);
    }
    let doc = json!({
        "scene": scene.name,
        "triangles": scene.triangles.len(),
        "preset": preset.name(),
        "mode": if args.thesis_mode { "thesis" } else { "project" },
        "ray_source": match source {
            RaySource::Sampled => "sampled",
            RaySource::Recorded { .. } => "recorded",
        },
        "areas": reports,
    });
    let w = CliError::Stdout;
    if args.json {
        writeln!(out, "{doc}").map_err(w)?;
        return Ok(());
    }
    writeln!(
        out,
        "{}: {} triangles, preset {}, {} mode, {}",
        scene.name,
        scene.triangles.len(),
        preset.name(),
        if args.thesis_mode {
            "thesis"
        } else {
            "project"
        },
        source.describe(setup.rays)
    )
    .map_err(w)?;
    for r in &reports {
        writeln!(
            out,
            "area {} ({}):",
            r["area"],
            r["kind"].as_str().unwrap_or("")
        )
        .map_err(w)?;
        if let Some(obj) = r.as_object() {
            for (k, v) in obj.iter().filter(|(k, _)| *k != "area" && *k != "kind") {
                writeln!(out, "  {k:<44} {v}").map_err(w)?;
            }
        }
    }
    Ok(())
}
