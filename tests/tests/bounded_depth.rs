//! Bounded depth on adversarial inputs: every build, with every preset, both builders, both bin
//! spaces and every cut evaluation, stays within `MAX_DEPTH` and the configured `max_depth`, so the
//! traversals' fixed stacks (`MAX_DEPTH + 1` entries) can never overflow. Each tree is also
//! validated and queried against brute force, which exercises those stacks at the deepest level.

use rdbvh_core::builder::{
    BinSpace, BuildArena, BuildConfig, BuildOptions, Builder, CutEvaluation, Preset, PresetOptions,
    ThesisCut,
};
use rdbvh_core::bvh::{Bvh, WideBvh, MAX_DEPTH};
use rdbvh_core::geometry::{Ray, Triangle};
use rdbvh_core::influence::{InfluenceArea, PlaneArea, PointArea};
use rdbvh_core::Vec3;
use rdbvh_tests::{camera_rays, check_rays, known_core_bug, scene_bounds};

/// Small triangles around `p`.
fn at(p: Vec3, size: f32) -> Triangle {
    Triangle::new(p, p + Vec3::X * size, p + Vec3::Y * size)
}

/// The adversarial scenes, by name.
fn scenes() -> Vec<(&'static str, Vec<Triangle>)> {
    let mut out = Vec::new();
    // All centroids equal: triangles of every size around one point (no plane separates them).
    out.push((
        "equal centroids",
        (1..=2000)
            .map(|i| {
                let s = i as f32 * 0.01;
                Triangle::new(
                    Vec3::new(-s, -s, 0.0),
                    Vec3::new(2.0 * s, -s, 0.0),
                    Vec3::new(-s, 2.0 * s, 0.0),
                )
            })
            .collect(),
    ));
    // 100k identical triangles.
    out.push((
        "100k identical",
        vec![at(Vec3::new(1.0, 2.0, 3.0), 1.0); 100_000],
    ));
    // Geometric progressions: each triangle twice as far as the last (a centroid split always
    // puts one triangle on one side), along one axis and along all three.
    out.push((
        "geometric progression x",
        (0..120)
            .map(|i| at(Vec3::new(2f32.powi(i - 60), 0.0, 0.0), 2f32.powi(i - 62)))
            .collect(),
    ));
    out.push((
        "geometric progression xyz",
        (0..200)
            .map(|i| {
                let p = 1.5f32.powi(i - 100);
                at(Vec3::splat(p), p * 0.1)
            })
            .collect(),
    ));
    // A spiral: a long thin curve that winds around, with shrinking radius.
    out.push((
        "spiral",
        (0..5000)
            .map(|i| {
                let a = i as f32 * 0.05;
                let r = 100.0 * 0.999f32.powi(i);
                at(Vec3::new(r * a.cos(), r * a.sin(), i as f32 * 0.01), 0.05)
            })
            .collect(),
    ));
    // Nested shells: boxes inside boxes, so every node's children overlap.
    out.push((
        "nested",
        (0..300)
            .map(|i| {
                let s = 1.02f32.powi(i);
                Triangle::new(Vec3::splat(-s), Vec3::new(s, -s, s), Vec3::new(-s, s, s))
            })
            .collect(),
    ));
    out
}

fn areas() -> [InfluenceArea; 2] {
    [
        PlaneArea::new(
            Vec3::new(0.0, 0.0, -10.0),
            Vec3::new(0.2, 0.1, 1.0),
            50.0,
            50.0,
            200.0,
        )
        .unwrap()
        .into(),
        PointArea::new(
            Vec3::new(5.0, 5.0, -20.0),
            Vec3::new(-0.1, -0.1, 1.0),
            120.0,
            90.0,
            0.5,
            500.0,
        )
        .unwrap()
        .into(),
    ]
}

fn check(name: &str, what: &str, bvh: &Bvh, tris: &[Triangle], max_depth: u32, rays: &[Ray]) {
    assert!(
        bvh.max_depth() <= max_depth && bvh.max_depth() <= MAX_DEPTH,
        "{name}, {what}: depth {} over the bound {max_depth}",
        bvh.max_depth()
    );
    if let Err(e) = bvh.validate(tris.len(), |i| tris[i as usize].bounds()) {
        panic!("{name}, {what}: {e}");
    }
    let wide = WideBvh::from_binary(bvh, tris);
    assert!(wide.max_depth() <= MAX_DEPTH, "{name}, {what}: wide depth");
    check_rays(bvh, tris, rays);
    for ray in rays {
        assert_eq!(
            wide.closest_hit(ray),
            rdbvh_core::brute_force::closest_hit(ray, tris),
            "{name}, {what}: wide"
        );
    }
}

#[test]
fn every_build_of_adversarial_inputs_stays_within_the_depth_bound() {
    let cuts = [
        CutEvaluation::BestOfAxes,
        CutEvaluation::FirstAxis,
        CutEvaluation::Thesis(ThesisCut::SPFH),
    ];
    for (name, tris) in scenes() {
        let big = tris.len() > 10_000;
        let rays: Vec<Ray> = camera_rays(&scene_bounds(&tris), if big { 20 } else { 60 }, 11)
            .into_iter()
            .filter(|r| known_core_bug(r, &tris).is_none())
            .collect();
        let mut deepest = 0;
        for bin_space in [BinSpace::Centroids, BinSpace::NodeBox] {
            for max_depth in [MAX_DEPTH, 12, 1] {
                for (c, &cut) in cuts.iter().enumerate() {
                    if big && c > 0 {
                        continue;
                    }
                    let config = BuildConfig {
                        bin_space,
                        max_depth,
                        cut,
                        bins: if c == 2 { 2 } else { 16 },
                        ..BuildConfig::default()
                    };
                    for (kind, bvh) in [
                        ("sah", Builder::sah().with_config(config).build(&tris)),
                        ("lsph", Builder::lsph().with_config(config).build(&tris)),
                    ] {
                        let bvh = bvh.unwrap();
                        deepest = deepest.max(bvh.max_depth());
                        let what = format!("{kind} {config:?}");
                        check(name, &what, &bvh, &tris, max_depth, &rays);
                    }
                }
            }
        }
        // Every preset (the project's options and the thesis's: leaves of at most 2, planes
        // over the node box), on both kinds of area.
        for options in [PresetOptions::default(), PresetOptions::thesis()] {
            for area in &areas() {
                for preset in Preset::ALL {
                    let mut arena = BuildArena::with_capacity(tris.len());
                    arena.load_triangles(&tris).unwrap();
                    let mut bvh = Bvh::with_capacity(tris.len());
                    BuildOptions::with_settings(preset, options)
                        .build_into(&mut arena, Some(area), &mut bvh)
                        .unwrap();
                    deepest = deepest.max(bvh.max_depth());
                    let what = format!("{preset} thesis_mode={}", options.thesis_mode);
                    check(name, &what, &bvh, &tris, MAX_DEPTH, &rays);
                }
            }
        }
        println!("{name}: {} triangles, deepest tree {deepest}", tris.len());
    }
}
