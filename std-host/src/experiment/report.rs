//! `report.md` and its charts.

use std::fmt::Write as _;
use std::path::{Path, PathBuf};

use super::plots::{fonts_available, save, Bars, Lines};
use super::summary::{cheaper_groups, PerGroup, GROUPS};
use super::toplevel_study::{CountRow, LevelRow};
use super::{ExperimentError, ExperimentOptions, ExperimentSummary, Settings};

fn pct(x: Option<f64>) -> String {
    x.map_or("-".into(), |v| format!("{:.1}%", 100.0 * v))
}

fn ratio(x: Option<f64>) -> String {
    x.map_or("-".into(), |v| format!("{v:.3}"))
}

fn group_names() -> Vec<String> {
    GROUPS.iter().map(|(k, o)| format!("{k} {o}")).collect()
}

/// The charts' file stems (each written as `.svg` and `.png`).
const CHARTS: [&str; 6] = [
    "estimate_error",
    "spfh_vs_lsph",
    "structure_vs_fallback",
    "octree_levels_error",
    "octree_levels_lookup",
    "octree_vs_list",
];

/// Every file a run writes into `dir`: `results.csv`, `report.md` and each chart as SVG and PNG.
pub fn output_files(dir: &Path) -> Vec<PathBuf> {
    ["results.csv".to_string(), "report.md".to_string()]
        .into_iter()
        .chain(
            CHARTS
                .iter()
                .flat_map(|stem| [format!("{stem}.svg"), format!("{stem}.png")]),
        )
        .map(|f| dir.join(f))
        .collect()
}

/// Removes an earlier run's `results.csv`, `report.md` and charts from `dir`, before a run
/// writes its own: a run stopped while writing leaves only its own files, never a new
/// `results.csv` beside an old report.
pub fn clear_outputs(dir: &Path) -> Result<(), ExperimentError> {
    for path in output_files(dir) {
        match std::fs::remove_file(&path) {
            Err(e) if e.kind() != std::io::ErrorKind::NotFound => {
                return Err(ExperimentError::Io(path, e.to_string()))
            }
            _ => {}
        }
    }
    Ok(())
}

/// Writes `dir/report.md` and the charts.
pub fn write_report(
    dir: &Path,
    opts: &ExperimentOptions,
    settings: &Settings,
    s: &ExperimentSummary,
    levels: &[LevelRow],
    counts: &[CountRow],
) -> Result<(), ExperimentError> {
    let ours = &s.ours;
    let th = s.thesis.as_ref();
    let t = |f: fn(&super::Findings) -> &PerGroup, g: usize| th.and_then(|x| f(x)[g]);
    let mut md = String::new();
    let mode = if opts.thesis_mode {
        format!(
            "thesis mode (the thesis's builder: {} candidate planes per axis, leaves of up to {} \
             triangles, depth limit {}, inner node cost {} counted twice, triangle cost {}; from \
             the file's [settings] and the command line)",
            settings.candidate_planes,
            settings.max_triangles_per_leaf,
            settings.max_levels.min(rdbvh_core::bvh::MAX_DEPTH),
            settings.inner_node_cost,
            settings.triangle_cost
        )
    } else {
        "project mode (binned builder, project defaults)".to_string()
    };
    let _ = writeln!(md, "# Experiment report\n");
    let _ = writeln!(
        md,
        "- file: `{}`\n- {mode}\n- {} runs, {}, octree of {} levels\n- {:.1} s wall clock",
        opts.file.display(),
        s.rows.len(),
        opts.rays.describe(settings.rays_per_config),
        settings.octree_levels,
        s.seconds
    );
    for note in &s.skipped {
        let _ = writeln!(md, "- note: {note}");
    }
    let ungrouped = s.ungrouped_runs();
    if ungrouped > 0 {
        let _ = writeln!(
            md,
            "- {ungrouped} runs have no `orientation` and join no group table (their rows are in \
             results.csv; the estimate errors by kind include them)"
        );
    }
    if let Some(p) = &s.pairing {
        let _ = writeln!(
            md,
            "- thesis columns: the thesis's own results over the same runs (same run names): {} \
             of our {} runs found theirs",
            p.matched, p.runs
        );
        if !p.excluded.is_empty() {
            let _ = writeln!(
                md,
                "- left out of the thesis columns, as the thesis's row of that name measured \
                 another area (its hit fraction differs from ours by more than sampling \
                 explains): {}",
                p.excluded.join(", ")
            );
        }
    }
    if !fonts_available() {
        let _ = writeln!(md, "- RDBVH_FONT is empty: charts are drawn without text");
    }
    let k = |i: usize, v: [Option<f64>; 2]| pct(v[i]);
    let _ = writeln!(
        md,
        "\n## Estimate error (|estimate - real cost without fallback| / real cost, every run)\n"
    );
    let _ = writeln!(
        md,
        "| areas | PAH (ours) | PAH (thesis) | SAH (ours) | SAH (thesis) |\n|---|---|---|---|---|"
    );
    for (i, kind) in ["plane", "point"].iter().enumerate() {
        let _ = writeln!(
            md,
            "| {kind} | {} | {} | {} | {} |",
            k(i, ours.pah_error_by_kind),
            th.map_or("-".into(), |x| k(i, x.pah_error_by_kind)),
            k(i, ours.sah_error_by_kind),
            th.map_or("-".into(), |x| k(i, x.sah_error_by_kind)),
        );
    }
    let _ = writeln!(md, "\n## Per orientation group\n");
    let _ = writeln!(md, "Ratios below 1 favour the first named. SPFH/LSPH: mean over scenes of facing / standard (and full / longest) real cost without fallback. Structure / fallback: the full preset's summed cost through the structure over the same rays through the fallback BVH alone. pah/full: mean over scenes of pah / full real cost without fallback, where both ran (`--presets` with pah).\n");
    let _ = writeln!(md, "| group | PAH err | PAH err (thesis) | SAH err | SAH err (thesis) | SPFH/LSPH (SAH) | (thesis) | SPFH/LSPH (PAH) | (thesis) | structure/fallback all-hit | (thesis) | structure/fallback closest-hit | pah/full |");
    let _ = writeln!(md, "|---|---|---|---|---|---|---|---|---|---|---|---|---|");
    for (g, name) in group_names().iter().enumerate() {
        let _ = writeln!(
            md,
            "| {name} | {} | {} | {} | {} | {} | {} | {} | {} | {} | {} | {} | {} |",
            pct(ours.pah_error[g]),
            pct(t(|f| &f.pah_error, g)),
            pct(ours.sah_error[g]),
            pct(t(|f| &f.sah_error, g)),
            ratio(ours.spfh_over_lsph[g]),
            ratio(t(|f| &f.spfh_over_lsph, g)),
            ratio(ours.spfh_over_lsph_pah[g]),
            ratio(t(|f| &f.spfh_over_lsph_pah, g)),
            ratio(ours.structure_over_fallback[g]),
            ratio(t(|f| &f.structure_over_fallback, g)),
            ratio(ours.structure_over_fallback_closest[g]),
            ratio(ours.pah_over_full[g]),
        );
    }
    let (c, n) = cheaper_groups(&ours.structure_over_fallback);
    if n == 0 {
        // Without `full` runs there is no structure to compare ("in 0 of 0 groups").
        let _ = writeln!(md, "\nNot compared: {}.", s.no_structure_comparison());
    } else {
        let _ = write!(
            md,
            "\nThe full structure is cheaper than the fallback BVH alone (all-hit) in {c} of {n} \
             groups"
        );
        if let Some(x) = th {
            let (c, n) = cheaper_groups(&x.structure_over_fallback);
            let _ = write!(md, " (thesis: {c} of {n})");
        }
        let (c, n) = cheaper_groups(&ours.structure_over_fallback_closest);
        let _ = writeln!(md, "; with closest-hit traversal in {c} of {n}.");
    }

    let _ = writeln!(
        md,
        "\n## Octree levels (one octree per scene name over its configurations' areas, skipped \
         configurations included: the lookup needs no triangles; error = false positives / true \
         positives)\n"
    );
    let _ = writeln!(
        md,
        "| levels | error | lookup ns | build us | leaves | bytes |\n|---|---|---|---|---|---|"
    );
    for r in levels {
        let _ = writeln!(
            md,
            "| {} | {:.3} | {:.1} | {:.1} | {:.0} | {:.0} |",
            r.levels, r.error, r.lookup_ns, r.build_us, r.leaves, r.bytes
        );
    }
    let _ = writeln!(
        md,
        "\n## Octree vs list (the file's first N areas, of every configuration and scene, in one \
         structure: a lookup study, not a scene's)\n"
    );
    let _ = writeln!(
        md,
        "| areas | octree ns | list ns | octree error |\n|---|---|---|---|"
    );
    for r in counts {
        let _ = writeln!(
            md,
            "| {} | {:.1} | {:.1} | {:.3} |",
            r.areas, r.octree_ns, r.list_ns, r.octree_error
        );
    }
    let _ = writeln!(md, "\n## Charts\n");
    for stem in CHARTS {
        let _ = writeln!(md, "- ![{stem}]({stem}.svg) ([PNG]({stem}.png))");
    }
    let path = dir.join("report.md");
    std::fs::write(&path, md).map_err(|e| ExperimentError::Io(path.clone(), e.to_string()))?;

    // Charts.
    let cats = group_names();
    // Series `k` is drawn in colour 2k (ours) and 2k + 1 (the thesis's), with or without the
    // thesis's results beside it.
    let with_thesis = |name: &str, k: usize, o: PerGroup, t: Option<PerGroup>| {
        let mut v = vec![(format!("{name} (rdbvh)"), 2 * k, o.to_vec())];
        if let Some(t) = t {
            v.push((format!("{name} (thesis)"), 2 * k + 1, t.to_vec()));
        }
        v
    };
    // Titles say the mode, so charts of two runs can be told apart.
    let mode_tag = if opts.thesis_mode {
        "thesis mode"
    } else {
        "project mode"
    };
    let title = |t: &str| format!("{t} ({mode_tag})");
    let mut series = with_thesis("PAH error", 0, ours.pah_error, th.map(|x| x.pah_error));
    series.extend(with_thesis(
        "SAH error",
        1,
        ours.sah_error,
        th.map(|x| x.sah_error),
    ));
    save(
        &Bars {
            title: &title("Estimate error vs measured all-hit cost"),
            y_label: "relative error",
            categories: &cats,
            series,
            reference: None,
        },
        dir,
        "estimate_error",
    )?;
    save(
        &Bars {
            title: &title("SPFH vs LSPH: facing / standard real cost"),
            y_label: "cost ratio",
            categories: &cats,
            series: with_thesis(
                "facing/standard",
                0,
                ours.spfh_over_lsph,
                th.map(|x| x.spfh_over_lsph),
            ),
            reference: Some(1.0),
        },
        dir,
        "spfh_vs_lsph",
    )?;
    let mut series = with_thesis(
        "all-hit",
        0,
        ours.structure_over_fallback,
        th.map(|x| x.structure_over_fallback),
    );
    series.push((
        "closest-hit (rdbvh)".into(),
        2,
        ours.structure_over_fallback_closest.to_vec(),
    ));
    save(
        &Bars {
            title: &title("Full structure / fallback BVH alone"),
            y_label: "cost ratio",
            categories: &cats,
            series,
            reference: Some(1.0),
        },
        dir,
        "structure_vs_fallback",
    )?;
    save(
        &Lines {
            title: &title("Octree levels vs containment error"),
            x_label: "levels",
            y_label: "false / true positives",
            series: vec![(
                "error".into(),
                levels
                    .iter()
                    .map(|r| (f64::from(r.levels), r.error))
                    .collect(),
            )],
        },
        dir,
        "octree_levels_error",
    )?;
    save(
        &Lines {
            title: &title("Octree levels vs lookup time"),
            x_label: "levels",
            y_label: "ns per lookup",
            series: vec![(
                "lookup".into(),
                levels
                    .iter()
                    .map(|r| (f64::from(r.levels), r.lookup_ns))
                    .collect(),
            )],
        },
        dir,
        "octree_levels_lookup",
    )?;
    save(
        &Lines {
            title: &title("Octree vs list by number of areas"),
            x_label: "areas",
            y_label: "ns per lookup",
            series: vec![
                (
                    "octree".into(),
                    counts
                        .iter()
                        .map(|r| (r.areas as f64, r.octree_ns))
                        .collect(),
                ),
                (
                    "list".into(),
                    counts.iter().map(|r| (r.areas as f64, r.list_ns)).collect(),
                ),
            ],
        },
        dir,
        "octree_vs_list",
    )?;
    Ok(())
}
