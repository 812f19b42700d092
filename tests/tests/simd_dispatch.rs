//! The wide traversals give the same answers, bit for bit, whichever instruction set
//! `bvh::set_simd_level` chooses (AVX2 where the CPU has it, the compiled baseline otherwise), on
//! a real scene through the public API. One test in its own binary, since the level is global.

use rdbvh::scene::Scene;
use rdbvh_core::bvh::{
    set_simd_level, simd_level, Lanes, SimdLevel, TraversalStats, WideBvh8, WideBvhN, Width,
};
use rdbvh_core::geometry::Ray;
use rdbvh_core::{BuildOptions, Preset, WideBvh};
use rdbvh_tests::{camera_rays, interior_rays, require_scene, scene_bounds};

/// Every query's answer and statistics, as bits.
type Answer = (
    Option<[u32; 4]>,
    TraversalStats,
    bool,
    TraversalStats,
    [u32; 4],
);

fn answers<const W: usize>(wide: &WideBvhN<W>, rays: &[Ray]) -> Vec<Answer>
where
    Width<W>: Lanes<W>,
{
    rays.iter()
        .map(|r| {
            let (mut closest, mut any) = (TraversalStats::default(), TraversalStats::default());
            let hit = wide
                .closest_hit_with_stats(r, &mut closest)
                .map(|h| [h.t.to_bits(), h.triangle, h.u.to_bits(), h.v.to_bits()]);
            let occluded = wide.any_hit_with_stats(r, &mut any);
            let all = wide.all_hit(r);
            let all = [all.inner_nodes, all.leaves, all.triangles, all.hits];
            (hit, closest, occluded, any, all)
        })
        .collect()
}

#[test]
fn bunny_answers_do_not_depend_on_the_simd_level() {
    let Some(path) = require_scene("bunny.obj") else {
        return;
    };
    let scene = Scene::load(&path).unwrap();
    let tris = &scene.triangles;
    let bvh = BuildOptions::new(Preset::Sah).build(tris, None).unwrap();
    let (wide4, wide8) = (
        WideBvh::from_binary(&bvh, tris),
        WideBvh8::from_binary(&bvh, tris),
    );
    let b = scene_bounds(tris);
    let mut rays = camera_rays(&b, 20_000, 1);
    rays.extend(interior_rays(&b, 20_000, 2));
    // Segments that start part-way along (t_min > 0), and axis-aligned rays (NaN slab lanes).
    let more: Vec<Ray> = rays
        .iter()
        .enumerate()
        .filter_map(|(i, r)| match i % 3 {
            0 => Ray::segment(r.origin, r.dir, 0.05 * b.extent().length(), r.t_max).ok(),
            1 => {
                let mut d = r.dir;
                d[i % 3] = 0.0;
                Ray::new(r.origin, d).ok()
            }
            _ => None,
        })
        .collect();
    rays.extend(more);

    let before = simd_level();
    set_simd_level(SimdLevel::Baseline);
    let base = (answers(&wide4, &rays), answers(&wide8, &rays));
    let level = set_simd_level(SimdLevel::Avx2);
    println!(
        "comparing the baseline with {level:?} on {} rays",
        rays.len()
    );
    let dispatched = (answers(&wide4, &rays), answers(&wide8, &rays));
    set_simd_level(before);
    assert!(base.0.iter().filter(|a| a.0.is_some()).count() > rays.len() / 4);
    for (i, (a, b)) in base.0.iter().zip(&dispatched.0).enumerate() {
        assert_eq!(a, b, "4-wide, ray {i}: {:?}", rays[i]);
    }
    for (i, (a, b)) in base.1.iter().zip(&dispatched.1).enumerate() {
        assert_eq!(a, b, "8-wide, ray {i}: {:?}", rays[i]);
    }
}
