//! What reinsertion buys on one scene: `cargo run --release -p rdbvh-benches --example reinsert --
//! SCENE [--for-wide] [FRACTION PASSES]...`. Builds the binned SAH tree, then for each `(fraction,
//! passes)` pair (default: a small sweep) optimizes a copy and prints its time (thread CPU) and SAH
//! cost, then the 4-wide collapse's traversal cost over eleven views, then its closest-hit speed on
//! the `peers` camera and random rays (interleaved rounds, best of 5, every answer checked).
//! `--for-wide` adds the same for the tree of `Builder::sah().for_wide()` (nodes of at most four
//! triangles left unsplit), whose reinsertion moves four-triangle leaves as units.
//!
//! The views: six pinhole cameras outside the scene's box from different sides, four inside it
//! looking across, and uniform random rays. A view's cost is the 4-wide traversal's inner nodes
//! plus triangles over four (a node test and a four-triangle block test cost about the same) per
//! ray, as a ratio to the unoptimized tree's; the geometric mean over the views is what the
//! default settings were chosen by. One camera alone can mislead: a move that lowers the SAH cost
//! can leave one side's rays entering more boxes (the `peers` camera is `out0`).

use std::process::ExitCode;

use glam::Vec3;
use rdbvh_benches::{
    bounds, load_scene, pinhole_rays, random_rays, ray_set, thread_cpu_seconds, RayKind,
};
use rdbvh_core::builder::{Builder, ReinsertConfig, Reinserter};
use rdbvh_core::bvh::{Bvh, TraversalStats, WideBvh};
use rdbvh_core::geometry::{Aabb, Ray, Triangle};
use rdbvh_core::heuristics::{CostConstants, Sah};

/// 128 x 128 rays from `eye` towards `target`, the half field of view's tangent `half`.
fn camera(eye: Vec3, target: Vec3, half: f32) -> Vec<Ray> {
    pinhole_rays(eye, (target - eye).normalize(), half, 128)
}

/// The eleven views of the module docs.
fn views(b: &Aabb) -> Vec<(String, Vec<Ray>)> {
    let (c, e) = (b.center(), b.max - b.min);
    let r = 0.5 * e.length();
    let outside = [
        Vec3::new(0.35, 0.45, 1.0),
        Vec3::new(-1.0, 0.3, 0.2),
        Vec3::new(0.5, 1.0, -0.5),
        Vec3::new(-0.3, -0.2, -1.0),
        Vec3::new(1.0, 0.1, 0.0),
        Vec3::new(0.0, 1.0, 0.1),
    ];
    let inside = [
        (Vec3::new(0.5, 0.2, 0.5), Vec3::new(0.9, 0.3, 0.5)),
        (Vec3::new(0.2, 0.3, 0.5), Vec3::new(0.8, 0.5, 0.5)),
        (Vec3::new(0.5, 0.5, 0.3), Vec3::new(0.5, 0.1, 0.8)),
        (Vec3::new(0.8, 0.15, 0.6), Vec3::new(0.1, 0.6, 0.4)),
    ];
    let mut v: Vec<(String, Vec<Ray>)> = outside
        .iter()
        .enumerate()
        .map(|(i, d)| {
            (
                format!("out{i}"),
                camera(c + d.normalize() * 1.5 * r, c, 0.7),
            )
        })
        .collect();
    v.extend(inside.iter().enumerate().map(|(i, (p, t))| {
        let (eye, target) = (b.min + e * *p, b.min + e * *t);
        (format!("in{i}"), camera(eye, target, 1.0))
    }));
    v.push(("random".into(), random_rays(b, 32_768, 7)));
    v
}

/// Inner nodes plus triangles over four, per ray, of the 4-wide closest-hit traversal.
fn view_cost(wide: &WideBvh, rays: &[Ray]) -> f64 {
    let mut s = TraversalStats::default();
    for r in rays {
        wide.closest_hit_with_stats(r, &mut s);
    }
    (f64::from(s.inner_nodes) + f64::from(s.triangles) / 4.0) / rays.len().max(1) as f64
}

/// `values` (one per view) as their geometric mean, then each with its view's name.
fn per_view(views: &[(String, Vec<Ray>)], values: &[f64]) -> String {
    let geo = (values.iter().map(|v| v.ln()).sum::<f64>() / values.len() as f64).exp();
    let each: Vec<String> = views
        .iter()
        .zip(values)
        .map(|((v, _), x)| format!("{v} {x:.2}"))
        .collect();
    format!("geometric mean {geo:.3} ({})", each.join(", "))
}

/// Mrays/s of closest-hit queries over `rays`, thread CPU time; the hits' distances for checking.
fn trace(wide: &WideBvh, rays: &[Ray]) -> (f64, Vec<Option<f32>>) {
    let t = thread_cpu_seconds();
    let hits: Vec<Option<f32>> = rays
        .iter()
        .map(|r| wide.closest_hit(r).map(|h| h.t))
        .collect();
    let s = thread_cpu_seconds() - t;
    (rays.len() as f64 / s / 1e6, hits)
}

fn run(scene: &str, for_wide: bool, configs: &[(f32, u32)]) -> Result<(), String> {
    let tris: Vec<Triangle> = load_scene(scene)?;
    let base = Builder::sah().build(&tris).map_err(|e| e.to_string())?;
    let k = CostConstants::default();
    let b = bounds(&tris);
    let t = thread_cpu_seconds();
    let _ = Builder::sah().build(&tris);
    let build_ms = (thread_cpu_seconds() - t) * 1e3;
    println!(
        "{scene}: {} tris; SAH build {build_ms:.1} ms, sah_cost {:.4}",
        tris.len(),
        base.estimated_cost(&Sah, k)
    );
    let mut trees: Vec<(String, Bvh)> = vec![("build".to_string(), base.clone())];
    let mut reinserter = Reinserter::new();
    let mut runs = vec![(String::new(), base.clone())];
    if for_wide {
        let pruned = Builder::sah()
            .for_wide()
            .build(&tris)
            .map_err(|e| e.to_string())?;
        println!(
            "  for_wide build: {} nodes (the build's {})",
            pruned.nodes().len(),
            base.nodes().len()
        );
        trees.push(("for_wide".to_string(), pruned.clone()));
        runs.push(("for_wide ".to_string(), pruned));
    }
    for ((prefix, base), &(fraction, passes)) in runs
        .iter()
        .flat_map(|run| configs.iter().map(move |c| (run, c)))
    {
        let config = ReinsertConfig {
            fraction,
            max_passes: passes,
            ..ReinsertConfig::default()
        };
        let mut best_ms = f64::INFINITY;
        let mut tree = base.clone();
        let mut stats = Default::default();
        for _ in 0..3 {
            tree = base.clone();
            let t = thread_cpu_seconds();
            stats = reinserter.optimize(&mut tree, &Sah, &config);
            best_ms = best_ms.min((thread_cpu_seconds() - t) * 1e3);
        }
        tree.validate(tris.len(), |i| tris[i as usize].bounds())
            .map_err(|e| format!("reinserted tree invalid: {e}"))?;
        println!(
            "  {prefix}{fraction}/{passes}: {best_ms:.1} ms ({:.2}x the build), sah_cost {:.4}, depth {}, {stats:?}",
            best_ms / build_ms,
            tree.estimated_cost(&Sah, k),
            tree.max_depth()
        );
        trees.push((format!("{prefix}{fraction}/{passes}"), tree));
    }
    let wides: Vec<WideBvh> = trees
        .iter()
        .map(|(_, t)| WideBvh::from_binary(t, &tris))
        .collect();

    let views = views(&b);
    let base_costs: Vec<f64> = views.iter().map(|(_, r)| view_cost(&wides[0], r)).collect();
    println!(
        "  the build's traversal cost per ray: {}",
        per_view(&views, &base_costs)
    );
    println!("  traversal cost over the views, as a ratio to the build's:");
    for ((name, _), wide) in trees.iter().zip(&wides).skip(1) {
        let ratios: Vec<f64> = views
            .iter()
            .zip(&base_costs)
            .map(|((_, r), c0)| view_cost(wide, r) / c0)
            .collect();
        println!("  {name}: {}", per_view(&views, &ratios));
    }

    for kind in [RayKind::Camera, RayKind::Random] {
        let rays = ray_set(&tris, &b, kind);
        let mut best = vec![0.0f64; wides.len()];
        let (_, reference) = trace(&wides[0], &rays);
        for _ in 0..5 {
            for (w, slot) in wides.iter().zip(best.iter_mut()) {
                let (rate, hits) = trace(w, &rays);
                if hits != reference {
                    return Err("an optimized tree's hits differ from the build's".into());
                }
                *slot = slot.max(rate);
            }
        }
        let row: Vec<String> = trees
            .iter()
            .zip(&best)
            .map(|((name, _), r)| format!("{name} {r:.2} ({:.3}x)", r / best[0]))
            .collect();
        println!("  wide closest {} Mrays/s: {}", kind.name(), row.join(", "));
    }
    Ok(())
}

fn main() -> ExitCode {
    let args: Vec<String> = std::env::args().skip(1).collect();
    let Some(scene) = args.first() else {
        eprintln!("error: usage: reinsert SCENE [--for-wide] [FRACTION PASSES]...");
        return ExitCode::FAILURE;
    };
    let for_wide = args.iter().any(|a| a == "--for-wide");
    let rest: Vec<&String> = args[1..].iter().filter(|a| *a != "--for-wide").collect();
    let mut configs = Vec::new();
    for pair in rest.chunks(2) {
        match (
            pair[0].parse::<f32>(),
            pair.get(1).map(|p| p.parse::<u32>()),
        ) {
            (Ok(f), Some(Ok(p))) => configs.push((f, p)),
            _ => {
                eprintln!("error: expected FRACTION PASSES pairs, got {pair:?}");
                return ExitCode::FAILURE;
            }
        }
    }
    if configs.is_empty() {
        configs = vec![(0.01, 1), (0.01, 2), (0.02, 2), (0.02, 3), (0.05, 3)];
    }
    match run(scene, for_wide, &configs) {
        Ok(()) => ExitCode::SUCCESS,
        Err(e) => {
            eprintln!("error: {e}");
            ExitCode::FAILURE
        }
    }
}
