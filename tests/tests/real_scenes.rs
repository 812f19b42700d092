//! Whole pipeline on the real scenes of `../shared/scenes/`: load with the host's OBJ loader, check
//! the load against `MANIFEST.tsv`, build with SAH and LSPH (and the SAH tree reinserted), validate,
//! and trace deterministic camera-like and interior rays, comparing every answer with the
//! brute-force oracle.
//!
//! Brute force costs rays x triangles, so big scenes compare a deterministic subset of their rays
//! with the oracle (about `ORACLE_BUDGET` triangle tests per scene) and check the rest for
//! consistency between the traversals only. Without `../shared` each test prints a skip; with
//! `CI=true` it fails.

use std::collections::HashMap;
use std::path::Path;

use rdbvh::scene::Scene;
use rdbvh_core::builder::{reinsert, BuildArena, Builder, ReinsertConfig};
use rdbvh_core::bvh::{Bvh, WideBvh};
use rdbvh_core::geometry::{Ray, Triangle};
use rdbvh_core::heuristics::{CostConstants, Sah};
use rdbvh_tests::{
    camera_rays, check_ray_against, check_ray_consistency, check_structure, check_wide_ray,
    check_wide_structure, interior_rays, require_scene, require_shared, scene_bounds, Oracle,
};

/// Triangle tests the oracle may spend per scene (each ray costs about `3 * triangles`).
const ORACLE_BUDGET: usize = 150_000_000;

/// One row of `MANIFEST.tsv`.
#[derive(Debug)]
struct ManifestRow {
    triangles: usize,
    bounds_min: [f32; 3],
    bounds_max: [f32; 3],
}

fn manifest(shared: &Path) -> HashMap<String, ManifestRow> {
    let text = std::fs::read_to_string(shared.join("scenes/MANIFEST.tsv"))
        .expect("../shared/scenes/MANIFEST.tsv is readable");
    let triple = |s: &str| -> [f32; 3] {
        let v: Vec<f32> = s.split(',').map(|x| x.parse().unwrap()).collect();
        [v[0], v[1], v[2]]
    };
    text.lines()
        .skip(1)
        .filter(|l| !l.trim().is_empty())
        .map(|line| {
            let f: Vec<&str> = line.split('\t').collect();
            (
                f[0].to_string(),
                ManifestRow {
                    triangles: f[2].parse().unwrap(),
                    bounds_min: triple(f[4]),
                    bounds_max: triple(f[5]),
                },
            )
        })
        .collect()
}

/// What one scene test did, for its printed report.
#[derive(Debug, Default)]
#[allow(dead_code)] // Read through `Debug` in the printed report.
struct Report {
    triangles: usize,
    rays: usize,
    oracle_rays: usize,
    hits: usize,
}

fn run_scene(relative: &str, rays_per_kind: usize) -> Option<Report> {
    let shared = require_shared()?;
    let path = require_scene(relative)?;
    let scene = Scene::load(&path).unwrap_or_else(|e| panic!("loading {relative}: {e}"));
    let tris: &[Triangle] = &scene.triangles;

    // The loader agrees with the manifest: triangle count and bounds (printed to 4 digits).
    let row = manifest(&shared)
        .remove(relative)
        .unwrap_or_else(|| panic!("{relative} is not in MANIFEST.tsv"));
    assert_eq!(tris.len(), row.triangles, "{relative}: triangle count");
    let bounds = scene_bounds(tris);
    for axis in 0..3 {
        for (got, want) in [
            (bounds.min[axis], row.bounds_min[axis]),
            (bounds.max[axis], row.bounds_max[axis]),
        ] {
            let tol = 1e-3 * (bounds.max - bounds.min).max_element().max(1e-3);
            assert!(
                (got - want).abs() <= tol,
                "{relative}: bounds axis {axis}: loaded {got}, manifest {want}"
            );
        }
    }

    // Build with SAH and LSPH, through both the allocating and the arena path.
    let sah = Builder::sah().build(tris).expect("SAH build");
    let lsph = Builder::lsph().build(tris).expect("LSPH build");
    let mut arena = BuildArena::with_capacity(tris.len());
    arena.load_triangles(tris).unwrap();
    let mut again = Bvh::with_capacity(tris.len());
    Builder::sah().build_into(&mut arena, &mut again).unwrap();
    assert_eq!(again, sah, "{relative}: build and build_into differ");
    // The SAH tree improved by reinsertion: same leaves, never a higher SAH cost.
    let mut reinserted = sah.clone();
    reinsert(&mut reinserted, &Sah, &ReinsertConfig::default());
    let k = CostConstants::default();
    let (before, after) = (
        sah.estimated_cost(&Sah, k),
        reinserted.estimated_cost(&Sah, k),
    );
    assert!(
        after <= before * (1.0 + 1e-6),
        "{relative}: reinsertion raised the SAH cost {before} -> {after}"
    );
    for bvh in [&sah, &lsph, &reinserted] {
        check_structure(bvh, tris);
        assert!(
            bvh.nodes().len() > 1 || tris.len() <= 8,
            "{relative}: no split at all"
        );
    }

    // Camera rays from outside toward the scene, and rays (and shadow segments) inside it.
    let seed = relative
        .bytes()
        .fold(0u64, |h, b| h.wrapping_mul(31) ^ u64::from(b));
    let mut rays: Vec<Ray> = camera_rays(&bounds, rays_per_kind, seed);
    rays.extend(interior_rays(&bounds, rays_per_kind, seed ^ 0x5eed));
    // A deterministic subset within the oracle's budget, spread over both kinds.
    let oracle_rays = (ORACLE_BUDGET / (3 * tris.len().max(1))).clamp(200, rays.len());
    let stride = rays.len().div_ceil(oracle_rays);

    let mut report = Report {
        triangles: tris.len(),
        rays: rays.len(),
        ..Report::default()
    };
    // The 4-wide collapse of the SAH tree, with its own leaf-ordered triangle blocks.
    let wide = WideBvh::from_binary(&sah, tris);
    check_wide_structure(&wide, &sah, tris);
    // A tree built for the collapse alone (nodes of at most four triangles unsplit) collapses to
    // the same wide nodes.
    let for_wide = Builder::sah().for_wide().build(tris).unwrap();
    assert_eq!(
        WideBvh::from_binary(&for_wide, tris).nodes(),
        wide.nodes(),
        "{relative}: the tree built for_wide collapses to other wide nodes"
    );
    for (i, ray) in rays.iter().enumerate() {
        if i % stride == 0 {
            let oracle = Oracle::new(ray, tris);
            for bvh in [&sah, &lsph, &reinserted] {
                check_ray_against(bvh, tris, ray, &oracle);
            }
            check_wide_ray(&wide, tris, ray, oracle.closest);
            report.oracle_rays += 1;
            report.hits += usize::from(oracle.closest.is_some());
        } else {
            let a = check_ray_consistency(&sah, tris, ray);
            let b = check_ray_consistency(&lsph, tris, ray);
            let c = check_ray_consistency(&reinserted, tris, ray);
            // Valid BVHs over the same triangles give the same exact closest hit.
            assert_eq!(a, b, "{relative}: SAH and LSPH disagree for {ray:?}");
            assert_eq!(
                a, c,
                "{relative}: SAH before and after reinsertion disagree for {ray:?}"
            );
            check_wide_ray(&wide, tris, ray, a);
        }
    }
    // The rays were aimed at the scene: a test that hits nothing proves little.
    assert!(
        report.hits * 20 >= report.oracle_rays,
        "{relative}: only {} of {} oracle rays hit",
        report.hits,
        report.oracle_rays
    );
    println!("{relative}: {report:?}");
    Some(report)
}

#[test]
fn cornell_box() {
    if let Some(r) = run_scene("cornell_box.obj", 2000) {
        assert_eq!(r.oracle_rays, r.rays, "small scenes compare every ray");
    }
}

#[test]
fn cornell_box_lights_are_emissive() {
    let Some(path) = require_scene("cornell_box.obj") else {
        return;
    };
    let scene = Scene::load(path).unwrap();
    // `../shared/scenes/README.md`: material `light` (`Ke 17 12 4`) covers 2 triangles.
    assert_eq!(scene.emissive_count(), 2);
}

#[test]
fn teapot() {
    run_scene("teapot.obj", 2000);
}

#[test]
fn thesis_small_scenes() {
    for name in ["Cube", "MonkeyModel", "Random100", "Random1000"] {
        run_scene(&format!("thesis/{name}.obj"), 1500);
    }
}

#[test]
fn thesis_cottages() {
    for name in ["Cottage", "CottageWalls"] {
        run_scene(&format!("thesis/{name}.obj"), 1500);
    }
}

#[test]
fn thesis_wood_scenes() {
    for name in ["WoodScene", "WoodSceneUfo"] {
        run_scene(&format!("thesis/{name}.obj"), 1500);
    }
}

#[test]
fn bunny() {
    run_scene("bunny.obj", 2000);
}

#[test]
fn sibenik() {
    run_scene("sibenik.obj", 1500);
}

#[test]
fn sponza() {
    run_scene("sponza_crytek.obj", 1500);
}

/// Loading a missing file is an error, not a panic (the loader's contract the tests rely on).
#[test]
fn missing_scene_is_an_error() {
    assert!(Scene::load("/nonexistent/definitely-missing.obj").is_err());
}
