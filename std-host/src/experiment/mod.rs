//! The experiment runner: every configuration of an experiment file (such as the thesis's
//! `experiments.toml`) that has a scene, with every heuristic of its `[settings]`, in parallel;
//! then `results.csv`, `report.md` and charts.
//!
//! Definitions of the result columns (per run, means over the run's rays):
//!
//! - `Estimated PAH cost`: the local BVH's expected cost per ray of the area's distribution under
//!   PAH (sum of `C m(n)` over nodes, over the window's measure), the cost constants of the mode.
//! - `Estimated SAH cost`: the local BVH's SAH cost (relative to its root).
//! - `Real cost without fallback`: the all-hit cost (every node whose box the segment touches and
//!   every triangle in those leaves, no early exit, as the thesis measured) of the local BVH over
//!   the part of each ray inside the area. `Intersections without fallback`: the inner nodes plus
//!   triangles that walk touched.
//! - `Real cost with fallback`: the same plus, for rays whose local walk hit no triangle, the
//!   all-hit cost of the fallback BVH over the rest of the ray. `Intersections with fallback`
//!   likewise.
//! - `Only fallback cost`: the mean fallback part over the rays that fell back (0 when none did).
//! - `Fallback BVH cost`: the all-hit cost of the same rays through the fallback BVH alone.
//! - `Hit percentage`: the share of rays whose local walk hit a triangle (0 to 1).
//! - `Overlapping % L` / `culled L` / `3D L`: the mean, over inner nodes of depth `< L`, of the
//!   overlap of the two children over the smaller child, in the light's projection, in the
//!   projection clipped to its window, and in 3D (see `rdbvh_core::analyze::SiblingOverlap`).
//! - `Max level`: levels of the local BVH (root = level 1).
//! - `Compute cost PAH average` / `count`: mean microseconds of one axis's sweep (pricing every
//!   candidate plane on it with the preset's cost model), and sweeps per priced node;
//!   `Choose split plane PAH average` / `count`: mean microseconds of the axis chooser's
//!   orientation choice, and choices per inner node (a node priced and then kept as a leaf makes
//!   one too, so this can exceed 1; median-fallback splits make none). Both from a second build
//!   of the same BVH with a clock (`PhaseProfile`).
//! - `EPO`, closest-hit and any-hit costs, rays per second, build milliseconds, memory: see the
//!   column names; closest-hit and any-hit costs are of real ordered traversals with early exit.

mod error;
mod plots;
mod ray_source;
mod report;
mod results;
mod run;
mod settings;
mod summary;
mod toplevel_study;

pub use error::ExperimentError;
pub use plots::fonts_available;
pub use ray_source::RaySource;
pub use results::{
    header, read_table, read_thesis_files, read_thesis_results, thesis_result_files, RunRow, Table,
    THESIS_COLUMNS,
};
pub use run::{build_fallback, run_one, sample_rays, RunMetrics, RunSetup};
pub use settings::{parse_presets, settings_of, ExperimentFile, Settings, MAX_CANDIDATE_PLANES};
pub use summary::{cheaper_groups, findings, pair_thesis, Findings, Pairing, RunKey, GROUPS};

use std::collections::HashMap;
use std::io::Write;
use std::path::{Path, PathBuf};
use std::sync::Arc;
use std::time::Instant;

use indicatif::{ProgressBar, ProgressStyle};
use rayon::prelude::*;
use rdbvh_core::builder::{Preset, PresetOptions};
use rdbvh_core::influence::{InfluenceArea, PointDistribution};

use crate::areas::AreaEntry;
use crate::scene::Scene;

/// Command-line overrides of the experiment file's settings.
#[derive(Clone, Debug, Default, PartialEq)]
pub struct Overrides {
    /// Rays per run.
    pub rays: Option<u32>,
    /// Presets.
    pub presets: Option<Vec<Preset>>,
    /// Candidate planes (thesis mode).
    pub candidate_planes: Option<u32>,
    /// Largest leaf (thesis mode).
    pub max_leaf: Option<u32>,
    /// Octree levels.
    pub octree_levels: Option<u32>,
}

/// What to run.
#[derive(Clone, Debug, Default, PartialEq)]
pub struct ExperimentOptions {
    /// The experiment file.
    pub file: PathBuf,
    /// Output folder (created).
    pub out: PathBuf,
    /// Reproduce the thesis's builder with the file's builder settings.
    pub thesis_mode: bool,
    /// The thesis's result files, to show beside ours.
    pub thesis_results: Option<PathBuf>,
    /// Overrides.
    pub overrides: Overrides,
    /// The rays each run measures with.
    pub rays: RaySource,
    /// Show a progress bar on standard error.
    pub progress: bool,
}

/// What an experiment produced.
#[derive(Clone, Debug)]
pub struct ExperimentSummary {
    /// One row per run, in file and preset order.
    pub rows: Vec<RunRow>,
    /// Configurations skipped and why, and areas that hold no triangle of their scene.
    pub skipped: Vec<String>,
    /// Our findings.
    pub ours: Findings,
    /// The thesis's findings over the same runs, when its results were given.
    pub thesis: Option<Findings>,
    /// How our runs found the thesis's rows, when its results were given.
    pub pairing: Option<Pairing>,
    /// Wall-clock seconds.
    pub seconds: f64,
}

impl ExperimentSummary {
    /// Runs without an `orientation`, which join no group table (their rows are in
    /// `results.csv`).
    pub fn ungrouped_runs(&self) -> usize {
        self.rows
            .iter()
            .filter(|r| r.orientation == "Unknown")
            .count()
    }

    /// Why the structure could not be compared with the fallback BVH alone in any group: no
    /// `full` run at all, or none with an orientation.
    pub fn no_structure_comparison(&self) -> &'static str {
        if self
            .rows
            .iter()
            .any(|r| r.heuristic == Preset::Full.thesis_name())
        {
            "no `full` run has an orientation (parallel, 15deg, 45deg or oblique), so none joins a \
             group to compare the structure with the fallback BVH alone"
        } else {
            "no `full` run to compare the structure with the fallback BVH alone"
        }
    }
}

/// The report's group of an `orientation` value (any case): `Unknown` for none, `None` for a
/// value that names no group (the experiment file is refused).
pub(crate) fn orientation_group(o: Option<&str>) -> Option<&'static str> {
    match o.map(str::to_ascii_lowercase).as_deref() {
        Some("parallel") => Some("Parallel"),
        Some("15deg" | "15") => Some("15"),
        Some("45deg" | "45") => Some("45"),
        Some("oblique") => Some("Oblique"),
        None => Some("Unknown"),
        Some(_) => None,
    }
}

fn kind_name(a: &InfluenceArea) -> &'static str {
    match a {
        InfluenceArea::Plane(_) => "Plane",
        InfluenceArea::Point(_) => "Point",
    }
}

/// A configuration's scene name: `scene`, else `file` without its extension, else `configN`.
fn scene_name(entry: &AreaEntry) -> String {
    entry
        .scene
        .clone()
        .or_else(|| {
            entry.file.as_ref().map(|f| {
                f.rsplit_once('.')
                    .map_or(f.as_str(), |(s, _)| s)
                    .to_string()
            })
        })
        .unwrap_or_else(|| format!("config{}", entry.index + 1))
}

/// A configuration's orientation group (`Unknown` without one, or for a value that names none).
fn orientation_name(entry: &AreaEntry) -> &'static str {
    orientation_group(entry.orientation.as_deref()).unwrap_or("Unknown")
}

/// A configuration's run name before the preset's suffix: its `thesis_test`, else
/// `SCENE_KIND_ORIENTATION`. Unique within an experiment file (checked when it is read).
pub(crate) fn run_base_name(entry: &AreaEntry) -> String {
    entry.thesis_test.clone().unwrap_or_else(|| {
        format!(
            "{}_{}_{}",
            scene_name(entry),
            kind_name(&entry.area),
            orientation_name(entry)
        )
    })
}

/// The run key of a configuration and preset: the thesis's run name and its group.
pub fn run_key(entry: &AreaEntry, preset: Preset) -> RunKey {
    RunKey {
        name: format!("{}_{}", run_base_name(entry), preset.thesis_name()),
        scene: scene_name(entry),
        kind: kind_name(&entry.area).to_string(),
        orientation: orientation_name(entry).to_string(),
        heuristic: preset.thesis_name().to_string(),
    }
}

/// Where a configuration is written, as an error's prefix: `FILE line N: config I: ` (`I`
/// counted from 0, as the area files' errors count).
fn config_at(file: &ExperimentFile, entry: &AreaEntry) -> String {
    format!(
        "{} line {}: config {}: ",
        file.path.display(),
        entry.line,
        entry.index
    )
}

/// Runs an experiment, writing `results.csv`, `report.md` and the charts into `opts.out`; notes
/// (skipped configurations) go to `log`.
pub fn run_experiment(
    opts: &ExperimentOptions,
    log: &mut dyn Write,
) -> Result<ExperimentSummary, ExperimentError> {
    let start = Instant::now();
    let file = ExperimentFile::read(&opts.file)?;
    let mut settings = file.settings.clone();
    let o = &opts.overrides;
    if let Some(r) = o.rays {
        settings.rays_per_config = r;
    }
    if let Some(c) = o.candidate_planes {
        settings.candidate_planes = c;
    }
    if let Some(l) = o.max_leaf {
        settings.max_triangles_per_leaf = l;
    }
    if let Some(l) = o.octree_levels {
        settings.octree_levels = l;
    }
    let presets = match &o.presets {
        Some(p) => p.clone(),
        None => settings.presets()?,
    };
    if settings.octree_levels == 0 {
        return Err(ExperimentError::Settings(
            "octree_levels must be at least 1".into(),
        ));
    }
    // The thesis's results before any run: a folder that cannot be read fails in a moment, not
    // after the runs, and its files join the inputs that no output may be.
    let thesis_results = match &opts.thesis_results {
        Some(dir) => {
            let files = thesis_result_files(dir)?;
            Some((read_thesis_files(&files)?, files))
        }
        None => None,
    };
    // The output folder first: a path that cannot be one fails before the runs, not after.
    if opts.out.exists() && !opts.out.is_dir() {
        return Err(ExperimentError::Io(
            opts.out.clone(),
            "exists and is not a folder (--out names the folder for results.csv, report.md and \
             the charts)"
                .into(),
        ));
    }
    std::fs::create_dir_all(&opts.out)
        .map_err(|e| ExperimentError::Io(opts.out.clone(), e.to_string()))?;
    let local = settings.preset_options(opts.thesis_mode);
    let setup = RunSetup {
        local,
        fallback: if opts.thesis_mode {
            local
        } else {
            PresetOptions::default()
        },
        fallback_preset: if opts.thesis_mode {
            Preset::Standard
        } else {
            Preset::Sah
        },
        constants: settings.constants(opts.thesis_mode),
        rays: settings.rays_per_config,
        octree_levels: settings.octree_levels,
        point_distribution: if opts.thesis_mode {
            PointDistribution::YawPitch
        } else {
            PointDistribution::SolidAngle
        },
    };

    // Configurations with a scene file; notes for the others.
    let mut skipped = Vec::new();
    let mut missing: Vec<(String, usize)> = Vec::new();
    let mut runnable: Vec<(&AreaEntry, PathBuf)> = Vec::new();
    for e in &file.configs {
        match &e.file {
            // A built-in scene is a name, not a file under scene_dir.
            Some(f) if f.starts_with(crate::scene::BUILTIN_PREFIX) => {
                runnable.push((e, PathBuf::from(f)))
            }
            Some(f) => runnable.push((e, file.scene_dir.join(f))),
            None => {
                let name = e
                    .scene
                    .clone()
                    .unwrap_or_else(|| format!("config {}", e.index));
                match missing.iter_mut().find(|(n, _)| *n == name) {
                    Some((_, c)) => *c += 1,
                    None => missing.push((name, 1)),
                }
            }
        }
    }
    for (name, count) in missing {
        let note = format!("{name}: no scene file, {count} configuration(s) skipped");
        writeln!(log, "note: {note}").ok();
        skipped.push(note);
    }

    // Each scene once, with its fallback BVH.
    let mut paths: Vec<PathBuf> = runnable.iter().map(|(_, p)| p.clone()).collect();
    paths.sort();
    paths.dedup();
    let loaded: Vec<(PathBuf, Arc<Scene>, Arc<rdbvh_core::bvh::Bvh>)> = paths
        .par_iter()
        .map(|p| {
            let scene = Scene::open(&p.to_string_lossy()).map_err(|e| {
                // Named by the first configuration that wants it, so the file can be fixed.
                let at = runnable
                    .iter()
                    .find(|(_, q)| q == p)
                    .map(|(e, _)| config_at(&file, e))
                    .unwrap_or_default();
                ExperimentError::Scene(format!("{at}{e}"))
            })?;
            let fallback = build_fallback(&scene.triangles, &setup)?;
            Ok((p.clone(), Arc::new(scene), Arc::new(fallback)))
        })
        .collect::<Result<_, ExperimentError>>()?;
    let scenes: HashMap<PathBuf, (Arc<Scene>, Arc<rdbvh_core::bvh::Bvh>)> =
        loaded.into_iter().map(|(p, s, f)| (p, (s, f))).collect();
    // A run clears its outputs before it writes them: an output that is an input, under its own
    // name or through a link, would delete the input.
    let mut inputs: Vec<&Path> = vec![opts.file.as_path()];
    for (path, (scene, _)) in &scenes {
        inputs.push(path);
        inputs.extend(scene.material_files.iter().map(PathBuf::as_path));
    }
    if let Some((_, files)) = &thesis_results {
        inputs.extend(files.iter().map(PathBuf::as_path));
    }
    if let RaySource::Recorded { path, .. } = &opts.rays {
        inputs.push(path);
    }
    for output in report::output_files(&opts.out) {
        if let Some(input) = crate::same_file::input_named_by(&output, inputs.iter().copied()) {
            let why = format!(
                "cannot write: it is one of the experiment's input files ({})",
                input.display()
            );
            return Err(ExperimentError::Io(output, why));
        }
    }

    let jobs: Vec<(usize, &AreaEntry, &PathBuf, Preset)> = runnable
        .iter()
        .enumerate()
        .flat_map(|(i, (e, p))| presets.iter().map(move |&pr| (i, *e, p, pr)))
        .collect();
    let bar = if opts.progress {
        ProgressBar::new(jobs.len() as u64)
    } else {
        ProgressBar::hidden()
    };
    bar.set_style(
        ProgressStyle::with_template("{elapsed_precise} [{bar:40}] {pos}/{len} runs {msg}")
            .unwrap_or_else(|_| ProgressStyle::default_bar()),
    );
    let mode = if opts.thesis_mode {
        "thesis"
    } else {
        "project"
    };
    let mut rows: Vec<(usize, usize, RunRow)> = jobs
        .par_iter()
        .map(|&(i, entry, path, preset)| {
            let (scene, fallback) = &scenes[path];
            let rays = opts.rays.rays_for(&entry.area, entry.index, &setup);
            let metrics = run_one(
                &scene.triangles,
                &entry.area,
                preset,
                fallback,
                &rays,
                &setup,
            )
            .map_err(|e| match e {
                ExperimentError::Build(m) => ExperimentError::Build(format!(
                    "{}{}: {m}",
                    config_at(&file, entry),
                    path.display()
                )),
                other => other,
            })?;
            let key = run_key(entry, preset);
            bar.inc(1);
            let spfh = matches!(preset, Preset::Facing | Preset::Full);
            let row = RunRow {
                name: key.name,
                scene: key.scene,
                kind: key.kind,
                orientation: key.orientation,
                heuristic: key.heuristic,
                mode: mode.into(),
                max_leaf: setup.local.max_leaf,
                max_levels: settings.max_levels,
                quality_threshold: if spfh {
                    setup.local.cut.quality_threshold
                } else {
                    setup.local.lsph_quality_threshold
                },
                acceptable_ratio: setup.local.cut.acceptable_ratio,
                excellent_ratio: setup.local.cut.excellent_ratio,
                metrics,
            };
            let p = presets.iter().position(|&x| x == preset).unwrap_or(0);
            Ok((i, p, row))
        })
        .collect::<Result<_, ExperimentError>>()?;
    bar.finish_and_clear();
    rows.sort_by_key(|(i, p, _)| (*i, *p));
    // An area that holds no triangle of its scene runs, with rows of zeros: say so.
    let mut empty: Vec<usize> = rows
        .iter()
        .filter(|(_, _, r)| r.metrics.local_triangles == 0)
        .map(|(i, _, _)| *i)
        .collect();
    empty.dedup();
    for i in empty {
        let (entry, path) = &runnable[i];
        let note = format!(
            "config {} (line {}): its area holds no triangle of {}, so its runs' rows are zeros",
            entry.index,
            entry.line,
            path.display()
        );
        writeln!(log, "note: {note}").ok();
        skipped.push(note);
    }
    let rows: Vec<RunRow> = rows.into_iter().map(|(_, _, r)| r).collect();

    // Every run succeeded: the earlier run's outputs go now, so a run stopped from here on
    // leaves its own files only (a failed run leaves the earlier ones whole).
    report::clear_outputs(&opts.out)?;
    let results = opts.out.join("results.csv");
    results::write_results(&results, &rows)?;

    let keys: Vec<RunKey> = rows
        .iter()
        .map(|r| RunKey {
            name: r.name.clone(),
            scene: r.scene.clone(),
            kind: r.kind.clone(),
            orientation: r.orientation.clone(),
            heuristic: r.heuristic.clone(),
        })
        .collect();
    let ours_table = read_table(&results)?;
    let ours = findings(&ours_table, &keys);
    let (thesis, pairing) = match &thesis_results {
        Some((table, _)) => {
            let (paired, pairing) =
                pair_thesis(table, &ours_table, &keys, settings.rays_per_config);
            (Some(findings(&paired, &keys)), Some(pairing))
        }
        None => (None, None),
    };

    // The top-level studies over the file's areas (every configuration has one, scene or not).
    let mut by_scene: Vec<(String, Vec<InfluenceArea>)> = Vec::new();
    for e in &file.configs {
        let name = e.scene.clone().unwrap_or_default();
        match by_scene.iter_mut().find(|(n, _)| *n == name) {
            Some((_, v)) => v.push(e.area),
            None => by_scene.push((name, vec![e.area])),
        }
    }
    let sets: Vec<Vec<InfluenceArea>> = by_scene.into_iter().map(|(_, v)| v).collect();
    let levels = toplevel_study::octree_levels(&sets, 8);
    let all_areas: Vec<InfluenceArea> = file.configs.iter().map(|e| e.area).collect();
    let counts = toplevel_study::octree_vs_list(&all_areas, settings.octree_levels);

    let summary = ExperimentSummary {
        rows,
        skipped,
        ours,
        thesis,
        pairing,
        seconds: start.elapsed().as_secs_f64(),
    };
    report::write_report(&opts.out, opts, &settings, &summary, &levels, &counts)?;
    Ok(summary)
}
