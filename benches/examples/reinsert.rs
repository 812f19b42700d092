//! What reinsertion buys on one scene: `cargo run --release -p rdbvh-benches --example reinsert --
//! SCENE [FRACTION PASSES]...`. Builds the binned SAH tree, then for each `(fraction, passes)`
//! pair (default: a small sweep) optimizes a copy and prints its time (thread CPU), its SAH cost,
//! and the 4-wide collapse's closest-hit speed on the `peers` camera and random rays, measured in
//! interleaved rounds against the unoptimized tree (best of 5), every answer checked against it.

use std::process::ExitCode;

use rdbvh_benches::{bounds, load_scene, ray_set, thread_cpu_seconds, RayKind};
use rdbvh_core::build::{Builder, ReinsertConfig, Reinserter};
use rdbvh_core::bvh::{Bvh, WideBvh};
use rdbvh_core::geometry::{Ray, Triangle};
use rdbvh_core::heuristics::{CostConstants, Sah};

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

fn run(scene: &str, configs: &[(f32, u32)]) -> Result<(), String> {
    let tris: Vec<Triangle> = load_scene(scene)?;
    let base = Builder::sah().build(&tris).map_err(|e| e.to_string())?;
    let k = CostConstants::default();
    let b = bounds(&tris);
    let sets: Vec<(RayKind, Vec<Ray>)> = [RayKind::Camera, RayKind::Random]
        .into_iter()
        .map(|kind| (kind, ray_set(&b, kind)))
        .collect();
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
    for &(fraction, passes) in configs {
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
            "  fraction {fraction} passes {passes}: {best_ms:.1} ms ({:.2}x the build), sah_cost {:.4}, depth {}, {stats:?}",
            best_ms / build_ms,
            tree.estimated_cost(&Sah, k),
            tree.max_depth()
        );
        trees.push((format!("{fraction}/{passes}"), tree));
    }
    let wides: Vec<WideBvh> = trees
        .iter()
        .map(|(_, t)| WideBvh::from_binary(t, &tris))
        .collect();
    for (kind, rays) in &sets {
        let mut best = vec![0.0f64; wides.len()];
        let (_, reference) = trace(&wides[0], rays);
        for _ in 0..5 {
            for (w, slot) in wides.iter().zip(best.iter_mut()) {
                let (rate, hits) = trace(w, rays);
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
        println!("  wide closest {}: {}", kind.name(), row.join(", "));
    }
    Ok(())
}

fn main() -> ExitCode {
    let args: Vec<String> = std::env::args().skip(1).collect();
    let Some(scene) = args.first() else {
        eprintln!("error: usage: reinsert SCENE [FRACTION PASSES]...");
        return ExitCode::FAILURE;
    };
    let mut configs = Vec::new();
    for pair in args[1..].chunks(2) {
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
        configs = vec![(0.01, 1), (0.02, 3), (0.05, 3), (0.1, 5)];
    }
    match run(scene, &configs) {
        Ok(()) => ExitCode::SUCCESS,
        Err(e) => {
            eprintln!("error: {e}");
            ExitCode::FAILURE
        }
    }
}
