//! `rdbvh experiment`: run an experiment file (such as the thesis's `experiments.toml`).

use std::io::{IsTerminal, Write};
use std::path::PathBuf;

use clap::Args;

use super::error::CliError;
use crate::experiment::{
    cheaper_groups, parse_presets, run_experiment, ExperimentOptions, Overrides,
};

/// Arguments of `rdbvh experiment`.
#[derive(Args, Debug, Clone)]
#[command(after_help = "\
Runs every [[config]] of FILE.toml that names a scene file (`file = ...`, found under scene_dir,
relative to FILE.toml; a config without `file` is skipped with a note, a named file that cannot
be read is an error) with every heuristic of [settings].heuristics, in parallel, and writes
DIR/results.csv (one row per run, the thesis's columns first), DIR/report.md and charts (SVG
and PNG).
Every [settings] key is optional; rays_per_config, heuristics and octree_levels apply in every
mode, the builder keys (candidate_planes, max_triangles_per_leaf, max_levels (the depth limit, at
most 64), inner_node_cost, triangle_cost, thresholds) only with --thesis-mode. Unknown keys and
tables are errors.
A run is named by its config's thesis_test, else SCENE_KIND_ORIENTATION, plus the heuristic; two
configs with one name are an error. orientation (parallel, 15deg, 45deg or oblique) puts a run in
its group of the report; a run without one is in results.csv and the estimate errors by kind, in
no group table. A config's rays are seeded by its position in the file (the Nth config, whatever
the others), so a file cut down to some of its configs traces other rays for them.
Charts draw their text with the bundled DejaVu Sans (RDBVH_FONT=path.ttf picks another font,\nRDBVH_FONT= with no value draws no text).")]
pub struct ExperimentArgs {
    /// The experiment file.
    #[arg(value_name = "FILE.toml")]
    pub file: PathBuf,
    /// Output folder (created if missing).
    #[arg(long, value_name = "DIR")]
    pub out: PathBuf,
    /// Reproduce the thesis's builder: the file's candidate planes over the node box, leaf size,
    /// cost constants and thresholds, an SAH + LSPH fallback, yaw/pitch point rays.
    #[arg(long)]
    pub thesis_mode: bool,
    /// Rays per run (overrides rays_per_config).
    #[arg(long, value_name = "N", value_parser = clap::value_parser!(u32).range(1..))]
    pub rays: Option<u32>,
    /// Measure every run on these rays instead of the areas' samplers: a CSV as `rdbvh trace
    /// --rays` reads it, such as `rdbvh render --record-rays` writes. All of them go through
    /// the structure (its local BVH takes those the area's affinity test accepts) and through
    /// the fallback alone.
    #[arg(long, value_name = "RAYS.csv", conflicts_with = "rays")]
    pub recorded_rays: Option<PathBuf>,
    /// Heuristics to run, comma-separated: full, longest, facing, standard, sah, pah (overrides
    /// heuristics).
    #[arg(long, value_name = "a,b", value_delimiter = ',')]
    pub presets: Option<Vec<String>>,
    /// The thesis's results folder (its Plane_*.csv and Point_*.csv): shown beside ours.
    #[arg(long, value_name = "DIR")]
    pub thesis_results: Option<PathBuf>,
    /// Candidate planes per axis, 1 to 63 (overrides candidate_planes; needs --thesis-mode).
    #[arg(long, value_name = "N", requires = "thesis_mode", value_parser = clap::value_parser!(u32)
        .range(1..=i64::from(crate::experiment::MAX_CANDIDATE_PLANES)))]
    pub candidate_planes: Option<u32>,
    /// Largest leaf (overrides max_triangles_per_leaf; needs --thesis-mode).
    #[arg(long, value_name = "N", requires = "thesis_mode", value_parser = clap::value_parser!(u32).range(1..))]
    pub max_leaf: Option<u32>,
    /// Octree levels, 1 to 10 (overrides octree_levels).
    #[arg(long, value_name = "N", value_parser = clap::value_parser!(u32)
        .range(1..=i64::from(rdbvh_core::toplevel::MAX_OCTREE_LEVELS)))]
    pub octree_levels: Option<u32>,
}

/// Runs the experiment and prints a short summary to `out`.
pub fn run(args: &ExperimentArgs, out: &mut dyn Write) -> Result<(), CliError> {
    let presets = match &args.presets {
        Some(names) => Some(
            parse_presets(names.iter().map(String::as_str))
                .map_err(|e| CliError::Usage(e.to_string()))?,
        ),
        None => None,
    };
    let opts = ExperimentOptions {
        file: args.file.clone(),
        out: args.out.clone(),
        thesis_mode: args.thesis_mode,
        thesis_results: args.thesis_results.clone(),
        overrides: Overrides {
            rays: args.rays,
            presets,
            candidate_planes: args.candidate_planes,
            max_leaf: args.max_leaf,
            octree_levels: args.octree_levels,
        },
        progress: std::io::stderr().is_terminal(),
        rays: super::rays::ray_source(args.recorded_rays.as_deref())?,
    };
    let s = run_experiment(&opts, &mut std::io::stderr())?;
    let w = |e| CliError::Stdout(e);
    writeln!(
        out,
        "{} in {:.1} s -> {}",
        super::words::count(s.rows.len(), "run"),
        s.seconds,
        args.out.join("results.csv").display()
    )
    .map_err(w)?;
    let pct = |x: Option<f64>| x.map_or("-".to_string(), |v| format!("{:.1}%", 100.0 * v));
    writeln!(
        out,
        "PAH estimate error: plane {} point {}; SAH: plane {} point {}",
        pct(s.ours.pah_error_by_kind[0]),
        pct(s.ours.pah_error_by_kind[1]),
        pct(s.ours.sah_error_by_kind[0]),
        pct(s.ours.sah_error_by_kind[1]),
    )
    .map_err(w)?;
    let (c, n) = cheaper_groups(&s.ours.structure_over_fallback);
    let structure = if n == 0 {
        s.no_structure_comparison().to_string()
    } else {
        format!("full structure cheaper than the fallback BVH alone in {c} of {n} groups")
    };
    writeln!(
        out,
        "{structure}; report: {}",
        args.out.join("report.md").display()
    )
    .map_err(w)?;
    Ok(())
}
