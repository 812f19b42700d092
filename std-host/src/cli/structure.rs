//! `rdbvh trace --areas`: answer rays through the scene structure (influence areas, their local
//! BVHs, an octree or list lookup, and the fallback BVH), and measure what the structure saves
//! against the fallback BVH alone on the same rays.

use std::io::Write;
use std::path::Path;
use std::time::Instant;

use rayon::prelude::*;
use rdbvh_core::builder::{BuildOptions, Preset, ReinsertConfig};
use rdbvh_core::bvh::{Bvh, TraversalStats};
use rdbvh_core::geometry::{Ray, Triangle};
use rdbvh_core::heuristics::CostConstants;
use rdbvh_core::toplevel::{
    AreaList, AreaLookup, Octree, TopLevel, TopLevelOptions, TopLevelStats, DEFAULT_OCTREE_LEVELS,
};

use super::answers::{write_answers, Answers};
use super::areas::load_areas;
use super::error::CliError;
use super::inputs::load_scene;
use super::rays::read_rays;
use super::trace::{check_outputs, LookupKind, TraceArgs};

/// The preset of the local BVHs when `--preset` is not given: `pah`, the binned SAH builder
/// pricing its cuts with the area's PAH ([`TopLevelOptions`]'s default too). Over the thesis's 48
/// configurations with published scenes (20,000 rays each), its local trees' closest-hit cost per
/// ray is 0.98x the `sah` trees' (geometric mean; 0.69x to 1.32x), the thesis's `full` 1.07x
/// (0.69x to 1.69x); any hit 0.99x and 1.04x (`benches/RESULTS.md`).
pub const DEFAULT_LOCAL_PRESET: Preset = Preset::Pah;

/// What tracing a batch through the structure did, with the fallback BVH alone as the baseline.
#[derive(Clone, Debug, PartialEq)]
pub struct StructureTrace {
    /// The answers, in ray order (equal to brute force).
    pub answers: Answers,
    /// Rays whose origin was in an area they were affine to (they traversed a local BVH).
    pub affine: usize,
    /// Rays a local BVH answered (a hit no farther than the area's exit).
    pub local: usize,
    /// Mean cost per ray through the structure: local plus fallback work.
    pub cost_structure: f64,
    /// Mean cost per ray of the same query in the fallback BVH alone.
    pub cost_fallback: f64,
    /// Wall-clock seconds through the structure.
    pub seconds: f64,
    /// Wall-clock seconds in the fallback BVH alone.
    pub fallback_seconds: f64,
}

impl StructureTrace {
    /// Share of rays a local BVH answered.
    pub fn local_hit_rate(&self, rays: usize) -> f64 {
        if rays == 0 {
            0.0
        } else {
            self.local as f64 / rays as f64
        }
    }
}

/// Per-ray counters, summed over the batch.
#[derive(Clone, Copy, Debug, Default)]
struct Tally {
    affine: usize,
    local: usize,
    cost: f64,
}

impl Tally {
    fn of(s: &TopLevelStats, k: CostConstants) -> Self {
        Tally {
            affine: usize::from(s.tries > 0),
            local: usize::from(s.answered_by.is_some()),
            cost: f64::from(s.cost(k)),
        }
    }

    fn add(self, o: Tally) -> Tally {
        Tally {
            affine: self.affine + o.affine,
            local: self.local + o.local,
            cost: self.cost + o.cost,
        }
    }
}

/// Traces `rays` in parallel through `structure`, then through its fallback BVH alone, costing
/// both with `k`.
pub fn trace_structure<L: AreaLookup + Sync>(
    structure: &TopLevel<L>,
    triangles: &[Triangle],
    rays: &[Ray],
    any_hit: bool,
    k: CostConstants,
) -> StructureTrace {
    let start = Instant::now();
    let (answers, tally) = if any_hit {
        let (hits, tallies): (Vec<bool>, Vec<Tally>) = rays
            .par_iter()
            .map(|r| {
                let mut s = TopLevelStats::default();
                let hit = structure.any_hit_with_stats(r, triangles, &mut s);
                (hit, Tally::of(&s, k))
            })
            .unzip();
        (Answers::Any(hits), sum(&tallies))
    } else {
        let (hits, tallies): (Vec<_>, Vec<Tally>) = rays
            .par_iter()
            .map(|r| {
                let mut s = TopLevelStats::default();
                let hit = structure.closest_hit_with_stats(r, triangles, &mut s);
                (hit, Tally::of(&s, k))
            })
            .unzip();
        (Answers::Closest(hits), sum(&tallies))
    };
    let seconds = start.elapsed().as_secs_f64();

    let start = Instant::now();
    let fallback_cost = fallback_alone(structure.fallback(), triangles, rays, any_hit, k);
    let fallback_seconds = start.elapsed().as_secs_f64();
    let n = rays.len().max(1) as f64;
    StructureTrace {
        answers,
        affine: tally.affine,
        local: tally.local,
        cost_structure: tally.cost / n,
        cost_fallback: fallback_cost / n,
        seconds,
        fallback_seconds,
    }
}

fn sum(tallies: &[Tally]) -> Tally {
    tallies.iter().fold(Tally::default(), |a, &b| a.add(b))
}

/// The summed cost of the same queries in `bvh` alone.
fn fallback_alone(
    bvh: &Bvh,
    triangles: &[Triangle],
    rays: &[Ray],
    any_hit: bool,
    k: CostConstants,
) -> f64 {
    rays.par_iter()
        .map(|r| {
            let mut s = TraversalStats::default();
            if any_hit {
                bvh.any_hit_with_stats(r, triangles, &mut s);
            } else {
                bvh.closest_hit_with_stats(r, triangles, &mut s);
            }
            f64::from(s.cost(k))
        })
        // From +0.0: the standard float sum of no rays is -0.0, which prints as "-0.00".
        .reduce(|| 0.0, |a, b| a + b)
}

/// The scene-structure options of a command line: the local preset (`pah` unless --preset says
/// otherwise) with --thesis-mode/--bins/--max-leaf, the fallback with the defaults, and with
/// --reinsert every tree reinserted with the default settings.
pub fn structure_options(args: &TraceArgs) -> TopLevelOptions {
    let local = args.builder.preset().unwrap_or(DEFAULT_LOCAL_PRESET);
    TopLevelOptions {
        local: BuildOptions::with_settings(local, args.builder.preset_options()),
        fallback: BuildOptions::new(Preset::Sah),
        max_tries: args.max_tries,
    }
    .reinsert(args.builder.reinsert.then(ReinsertConfig::default))
    .parallel(true)
}

/// Runs `rdbvh trace --areas ...`; the summary goes to `log`.
pub fn run(args: &TraceArgs, areas_path: &Path, log: &mut impl Write) -> Result<(), CliError> {
    check_outputs(args)?;
    if args.builder.builder.is_some() {
        return Err(CliError::Usage(
            "--builder chooses the single BVH of a trace without --areas; with --areas, choose \
             the local BVHs with --preset (the fallback BVH is always binned SAH)"
                .into(),
        ));
    }
    if args.lookup == LookupKind::List && args.octree_levels.is_some() {
        return Err(CliError::Usage(
            "--octree-levels sizes the octree lookup; --lookup list has no levels".into(),
        ));
    }
    let (scene, _) = load_scene(&args.scene, Some(&args.out))?;
    let entries = load_areas(areas_path, &scene)?;
    let rays = read_rays(&args.rays)?;
    let areas: Vec<_> = entries.iter().map(|e| e.area).collect();
    let options = structure_options(args);

    rdbvh_core::builder::parallel::start_pool();
    let start = Instant::now();
    match args.lookup {
        LookupKind::Octree => {
            let levels = args.octree_levels.unwrap_or(DEFAULT_OCTREE_LEVELS);
            let s = TopLevel::build(&scene.triangles, areas, &options, |a| {
                Octree::build(a, levels)
            })?;
            let build_seconds = start.elapsed().as_secs_f64();
            let o = s.lookup().stats();
            let lookup = format!(
                "octree of {} ({} used, {} nodes, {} leaves)",
                super::words::count(levels as usize, "level"),
                o.levels,
                o.nodes,
                o.leaves
            );
            finish(args, &scene, &rays, &s, &lookup, build_seconds, log)
        }
        LookupKind::List => {
            let s = TopLevel::build(&scene.triangles, areas, &options, |a| {
                AreaList::new(a.len())
            })?;
            let build_seconds = start.elapsed().as_secs_f64();
            finish(args, &scene, &rays, &s, "area list", build_seconds, log)
        }
    }
}

/// Traces, writes the answers and prints the summary.
fn finish<L: AreaLookup + Sync>(
    args: &TraceArgs,
    scene: &crate::scene::Scene,
    rays: &[Ray],
    structure: &TopLevel<L>,
    lookup: &str,
    build_seconds: f64,
    log: &mut impl Write,
) -> Result<(), CliError> {
    let k = CostConstants::default();
    let t = trace_structure(structure, &scene.triangles, rays, args.any_hit, k);
    write_answers(&args.out, &t.answers)?;

    let n = rays.len();
    let per_second = |s: f64| if n == 0 { 0.0 } else { n as f64 / s.max(1e-9) };
    let kind = if args.any_hit {
        "any hit"
    } else {
        "closest hit"
    };
    let options = structure_options(args);
    let areas = structure.areas().len();
    let local_triangles: u64 = structure
        .triangles_per_area()
        .iter()
        .map(|&c| u64::from(c))
        .sum();
    let ratio = if t.cost_fallback > 0.0 {
        format!("{:.2}x", t.cost_structure / t.cost_fallback)
    } else {
        "-".into()
    };
    let lines = [
        format!(
            "traced {} ({kind}) against {} through {} with {}: {}, {:.3} ms, {:.0} rays/s",
            super::words::count(n, "ray"),
            super::words::count(scene.len(), "triangle"),
            super::words::count(areas, "influence area"),
            super::words::count(rayon::current_num_threads(), "thread"),
            super::words::count(t.answers.hits(), "hit"),
            t.seconds * 1e3,
            per_second(t.seconds)
        ),
        format!(
            "local hit rate {:.2}% ({} of {} answered by a local BVH; {} affine to an area, {} \
             used the fallback BVH)",
            100.0 * t.local_hit_rate(n),
            t.local,
            super::words::count(n, "ray"),
            t.affine,
            n - t.local
        ),
        format!(
            "mean cost per ray (C_trav = C_isect = 1): {:.2} with the structure, {:.2} with the \
             fallback BVH alone ({ratio}); fallback alone {:.3} ms, {:.0} rays/s",
            t.cost_structure,
            t.cost_fallback,
            t.fallback_seconds * 1e3,
            per_second(t.fallback_seconds)
        ),
        format!(
            "structure: `{}` {}{} holding {} (a triangle once per area it overlaps), {lookup}, \
             up to {} tr{} per ray, {} bytes, built in {:.3} ms",
            options.local.preset,
            super::words::count(areas, "local BVH"),
            if options.local.settings.thesis_mode {
                " (thesis mode)"
            } else {
                ""
            },
            super::words::count(local_triangles as usize, "triangle"),
            options.max_tries,
            if options.max_tries == 1 { "y" } else { "ies" },
            structure.memory_bytes(),
            build_seconds * 1e3
        ),
    ];
    for line in lines {
        writeln!(log, "{line}").map_err(CliError::Stdout)?;
    }
    Ok(())
}
