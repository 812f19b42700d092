//! `rdbvh build`: build one BVH over a scene and report its shape, quality and build speed.

use std::io::Write;

use clap::Args;
use rdbvh_core::heuristics::{CostConstants, Sah};
use serde::Serialize;

use super::builder::{BuilderArgs, BuilderKind};
use super::{load_scene, CliError};

/// Arguments of `rdbvh build`.
#[derive(Args, Clone, Debug)]
pub struct BuildArgs {
    /// The scene: an OBJ file, or builtin:NAME for a built-in scene.
    #[arg(value_name = "SCENE.obj")]
    pub scene: String,
    /// How to build.
    #[command(flatten)]
    pub builder: BuilderArgs,
    /// Print one JSON object instead of the table.
    #[arg(long)]
    pub json: bool,
}

/// What `rdbvh build` reports; `--json` prints it as one object with these keys.
#[derive(Clone, Debug, Serialize)]
pub struct BuildReport {
    /// The scene's name.
    pub scene: String,
    /// Triangles in the scene.
    pub triangles: usize,
    /// BVH nodes, inner and leaves.
    pub nodes: usize,
    /// Leaves.
    pub leaves: usize,
    /// Depth of the deepest node (the root has depth 0).
    pub max_depth: u32,
    /// The SAH cost of the tree with `C_trav = C_isect = 1`.
    pub sah_cost: f32,
    /// Bytes of the node and primitive-index arrays.
    pub bytes: usize,
    /// Milliseconds to load the scene (parse the OBJ or generate the built-in scene).
    pub load_ms: f64,
    /// Milliseconds of the build alone.
    pub build_ms: f64,
    /// Millions of triangles built per second.
    pub mtris_per_s: f64,
    /// The builder.
    pub builder: BuilderKind,
    /// Bins per axis.
    pub bins: u32,
    /// The SAH termination's largest leaf.
    pub max_leaf: u32,
}

/// Runs `rdbvh build`, writing the report to `out`.
pub fn run(args: &BuildArgs, out: &mut impl Write) -> Result<(), CliError> {
    let (scene, load_seconds) = load_scene(&args.scene)?;
    let built = args.builder.build(&scene.triangles)?;
    let report = BuildReport {
        scene: scene.name.clone(),
        triangles: scene.len(),
        nodes: built.bvh.nodes().len(),
        leaves: built.bvh.leaf_count(),
        max_depth: built.bvh.max_depth(),
        sah_cost: built.bvh.estimated_cost(&Sah, CostConstants::default()),
        bytes: built.bvh.memory_bytes(),
        load_ms: load_seconds * 1e3,
        build_ms: built.seconds * 1e3,
        mtris_per_s: built.mtris_per_s(scene.len()),
        builder: args.builder.builder,
        bins: args.builder.bins,
        max_leaf: args.builder.max_leaf,
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
    format!(
        "scene       {}\n\
         triangles   {}\n\
         builder     {} ({} bins, max leaf {})\n\
         nodes       {}\n\
         leaves      {}\n\
         max depth   {}\n\
         SAH cost    {:.3}\n\
         memory      {} bytes\n\
         load time   {:.3} ms\n\
         build time  {:.3} ms ({:.2} Mtris/s)",
        r.scene,
        r.triangles,
        r.builder.name(),
        r.bins,
        r.max_leaf,
        r.nodes,
        r.leaves,
        r.max_depth,
        r.sah_cost,
        r.bytes,
        r.load_ms,
        r.build_ms,
        r.mtris_per_s
    )
}
