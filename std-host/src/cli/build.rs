//! `rdbvh build`: build one BVH over a scene, or over the triangles of an influence area, and
//! report its shape, quality and build speed.

use std::io::Write;
use std::path::PathBuf;
use std::time::Instant;

use clap::Args;
use rdbvh_core::heuristics::AreaPah;
use rdbvh_core::heuristics::{CostConstants, Sah};

use serde::Serialize;

use super::areas::{kind_name, load_areas, overlapping};
use super::builder::BuilderArgs;
use super::error::CliError;
use super::inputs::load_scene;

/// Arguments of `rdbvh build`.
#[derive(Args, Clone, Debug)]
pub struct BuildArgs {
    /// The scene: an OBJ file, or builtin:NAME for a built-in scene.
    #[arg(value_name = "SCENE.obj")]
    pub scene: String,
    /// Influence areas (TOML): build over the triangles that overlap the first area that
    /// applies to the scene, and report its PAH cost.
    #[arg(long, value_name = "AREAS.toml")]
    pub areas: Option<PathBuf>,
    /// How to build.
    #[command(flatten)]
    pub builder: BuilderArgs,
    /// Print one JSON object instead of the table.
    #[arg(long)]
    pub json: bool,
}

/// What `rdbvh build` reports; `--json` prints it as one object with these keys, every key always
/// present (`null` where it does not apply).
#[derive(Clone, Debug, Serialize)]
pub struct BuildReport {
    /// The scene's name.
    pub scene: String,
    /// Triangles in the build: the whole scene, or those that overlap the area.
    pub triangles: usize,
    /// Triangles in the scene.
    pub scene_triangles: usize,
    /// BVH nodes, inner and leaves.
    pub nodes: usize,
    /// Leaves.
    pub leaves: usize,
    /// Depth of the deepest node (the root has depth 0).
    pub max_depth: u32,
    /// The SAH cost of the tree with `C_trav = C_isect = 1`.
    pub sah_cost: f32,
    /// With an area: the expected cost per ray of the area's rays under its PAH (orthographic
    /// for a plane area, solid-angle perspective for a point area, culled to the light's window),
    /// with `C_trav = C_isect = 1`. Rays that miss the root count as costing nothing.
    pub pah_cost: Option<f32>,
    /// Bytes of the node and primitive-index arrays.
    pub bytes: usize,
    /// Milliseconds to load the scene (parse the OBJ or generate the built-in scene).
    pub load_ms: f64,
    /// With an area: milliseconds to pick the triangles that overlap it (the separating-axis test).
    pub select_ms: Option<f64>,
    /// Milliseconds of the build alone, on `threads` threads (the single-threaded build's tree).
    pub build_ms: f64,
    /// With `--reinsert`: milliseconds of the reinsertion after the build (not in `build_ms`).
    pub reinsert_ms: Option<f64>,
    /// With `--reinsert`: how many nodes reinsertion moved.
    pub reinsert_moved: Option<u32>,
    /// Millions of triangles built per second.
    pub mtris_per_s: f64,
    /// Threads the build ran on (rayon's pool: every core, or `RAYON_NUM_THREADS`).
    pub threads: usize,
    /// The split-axis chooser: `sah` (all three axes), `lsph` (longest) or `spfh` (facing).
    pub builder: &'static str,
    /// The preset, with `--preset`.
    pub preset: Option<&'static str>,
    /// True with `--thesis-mode`.
    pub thesis_mode: bool,
    /// With an area: `plane` or `point`.
    pub area_kind: Option<&'static str>,
    /// Bins per axis.
    pub bins: u32,
    /// The largest leaf (the leaf-size split target in thesis mode).
    pub max_leaf: u32,
}

/// Runs `rdbvh build`, writing the report to `out`.
pub fn run(args: &BuildArgs, out: &mut impl Write) -> Result<(), CliError> {
    args.builder.check_area(args.areas.is_some())?;
    let (scene, load_seconds) = load_scene(&args.scene, None)?;
    let area = match &args.areas {
        Some(path) => {
            let entries = load_areas(path, &scene)?;
            // `load_areas` never returns an empty list; `first` keeps that from being a panic.
            entries.first().map(|e| e.area)
        }
        None => None,
    };
    let (subset, select_seconds) = match &area {
        Some(a) => {
            let start = Instant::now();
            let ids = overlapping(&scene.triangles, a);
            (Some(ids), Some(start.elapsed().as_secs_f64()))
        }
        None => (None, None),
    };
    if let (Some(ids), Some(path)) = (&subset, &args.areas) {
        if ids.is_empty() {
            eprintln!(
                "warning: the first area of {} overlaps no triangle of {}; the BVH is empty",
                path.display(),
                scene.name
            );
        }
    }
    let built = args
        .builder
        .build_over(&scene.triangles, subset.as_deref(), area.as_ref())?;
    let triangles = subset.as_ref().map_or(scene.len(), Vec::len);
    // The mode's constants, as `analyze` and `experiment` report them: the thesis's (2 x 1.0 per
    // inner node, 1.2 per triangle) with --thesis-mode, C_trav = C_isect = 1 otherwise.
    let k = if args.builder.thesis_mode {
        CostConstants::THESIS
    } else {
        CostConstants::default()
    };
    let pah_cost = area.as_ref().map(|a| {
        let pah = AreaPah::new(a, args.builder.preset_options().perspective);
        built.bvh.estimated_cost_over(&pah, k, pah.window_measure())
    });
    let report = BuildReport {
        scene: scene.name.clone(),
        triangles,
        scene_triangles: scene.len(),
        nodes: built.bvh.nodes().len(),
        leaves: built.bvh.leaf_count(),
        max_depth: built.bvh.max_depth(),
        sah_cost: built.bvh.estimated_cost(&Sah, k),
        pah_cost,
        bytes: built.bvh.memory_bytes(),
        load_ms: load_seconds * 1e3,
        select_ms: select_seconds.map(|s| s * 1e3),
        build_ms: built.seconds * 1e3,
        reinsert_ms: built.reinsert.map(|(_, s)| s * 1e3),
        reinsert_moved: built.reinsert.map(|(r, _)| r.moved),
        mtris_per_s: built.mtris_per_s(triangles),
        threads: rayon::current_num_threads(),
        builder: args.builder.chooser_name(),
        preset: args.builder.preset().map(|p| p.name()),
        thesis_mode: args.builder.thesis_mode,
        area_kind: area.as_ref().map(kind_name),
        bins: args.builder.bins(),
        max_leaf: args.builder.max_leaf(),
    };
    let text = if args.json {
        // Serialising plain numbers and strings cannot fail; NaN would become `null`.
        serde_json::to_string(&report).map_err(|e| CliError::Stdout(e.into()))?
    } else {
        table(&report)
    };
    writeln!(out, "{text}").map_err(CliError::Stdout)
}

/// The human-readable report.
fn table(r: &BuildReport) -> String {
    let builder = match r.preset {
        Some(p) => format!(
            "preset {p} ({} axes{})",
            r.builder,
            if r.thesis_mode { ", thesis mode" } else { "" }
        ),
        None => r.builder.to_string(),
    };
    let triangles = match r.area_kind {
        Some(kind) => format!(
            "{} of {} (those overlapping the {kind} area)",
            r.triangles, r.scene_triangles
        ),
        None => r.triangles.to_string(),
    };
    let mut s = format!(
        "scene       {}\n\
         triangles   {triangles}\n\
         builder     {builder} ({} bins, max leaf {})\n\
         nodes       {}\n\
         leaves      {}\n\
         max depth   {}\n\
         SAH cost    {:.3}\n",
        r.scene, r.bins, r.max_leaf, r.nodes, r.leaves, r.max_depth, r.sah_cost,
    );
    if let Some(pah) = r.pah_cost {
        s += &format!("PAH cost    {pah:.3} per ray of the area\n");
    }
    s += &format!(
        "memory      {} bytes\n\
         load time   {:.3} ms\n",
        r.bytes, r.load_ms
    );
    if let Some(select) = r.select_ms {
        s += &format!("select time {select:.3} ms\n");
    }
    s += &format!(
        "build time  {:.3} ms ({:.2} Mtris/s, {} threads)",
        r.build_ms, r.mtris_per_s, r.threads
    );
    if let (Some(ms), Some(moved)) = (r.reinsert_ms, r.reinsert_moved) {
        s += &format!("\nreinsert    {ms:.3} ms ({moved} nodes moved)");
    }
    s
}
