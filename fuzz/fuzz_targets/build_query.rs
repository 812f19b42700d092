//! Build with every preset and both builders over arbitrary triangles, and reinsert each tree,
//! then check the tree invariants and every traversal (binary and 4-wide) against brute force;
//! both builders' trees built `for_wide` must collapse to the same 4-wide nodes. An SBVH with
//! arbitrary settings is checked the same way, as far as split triangles allow.
#![no_main]

use arbitrary::{Result, Unstructured};
use libfuzzer_sys::fuzz_target;
use rdbvh_core::brute_force;
use rdbvh_core::builder::{
    reinsert, BuildArena, BuildOptions, Builder, Preset, ReinsertConfig, SpatialBuilder,
    SpatialSplits,
};
use rdbvh_core::bvh::{Bvh, WideBvh, MAX_DEPTH};
use rdbvh_core::geometry::{Ray, Triangle};
use rdbvh_core::heuristics::{CostConstants, Sah};
use rdbvh_core::influence::{InfluenceArea, PlaneArea};
use rdbvh_core::Vec3;
use rdbvh_fuzz::*;

fuzz_target!(|data: &[u8]| {
    let _ = run(&mut Unstructured::new(data));
});

fn run(u: &mut Unstructured) -> Result<()> {
    let finite = u.int_in_range(0u8..=7)? != 0;
    let tris = scene(u, finite)?;
    let expect_err = expected_build_error(&tris);
    let area = area(u, &tris)?.unwrap_or_else(|| {
        PlaneArea::new(Vec3::new(0.0, 0.0, -5.0), Vec3::Z, 5.0, 5.0, 20.0)
            .unwrap()
            .into()
    });
    let rays: Vec<Ray> = rays(u, &tris, MAX_RAYS)?
        .into_iter()
        .filter_map(|r| r.ok())
        .collect();

    let mut built: Vec<(String, Bvh, u32)> = Vec::new();
    for round in 0..2 {
        let config = build_config(u)?;
        // With the tree built for the 4-wide collapse alone, which must collapse alike.
        let (name, result, for_wide) = if round == 0 {
            let b = Builder::sah().with_config(config);
            ("sah", b.build(&tris), b.for_wide().build(&tris))
        } else {
            let b = Builder::lsph().with_config(config);
            ("lsph", b.build(&tris), b.for_wide().build(&tris))
        };
        assert_eq!(
            for_wide.as_ref().err(),
            result.as_ref().err(),
            "{name} for_wide"
        );
        match (result, expect_err) {
            (Ok(bvh), None) => {
                let pruned = for_wide.expect("same outcome as the full build");
                assert_eq!(
                    WideBvh::from_binary(&pruned, &tris).nodes(),
                    WideBvh::from_binary(&bvh, &tris).nodes(),
                    "{name} {config:?}: for_wide collapses otherwise"
                );
                built.push((format!("{name} {config:?}"), bvh, config.max_depth))
            }
            (Err(e), Some(x)) => assert_eq!(e, x, "{name}"),
            (r, x) => panic!(
                "{name} {config:?}: got {:?}, expected error {x:?}",
                r.map(|_| ())
            ),
        }
    }

    let options = preset_options(u)?;
    let mut arena = BuildArena::with_capacity(tris.len());
    let loaded = arena.load_triangles(&tris);
    assert_eq!(loaded.err(), expect_err, "arena load");
    if loaded.is_ok() {
        for preset in Preset::ALL {
            let mut bvh = Bvh::with_capacity(tris.len());
            let area: Option<&InfluenceArea> = Some(&area);
            let stats =
                BuildOptions::with_settings(preset, options).build_into(&mut arena, area, &mut bvh);
            if let Err(e) = stats {
                panic!(
                    "preset {preset} {options:?} over {} triangles: {e}",
                    tris.len()
                );
            }
            built.push((format!("{preset} {options:?}"), bvh, MAX_DEPTH));
        }
    }

    // Every tree again after reinsertion (every node tried, within the tree's own depth bound):
    // the same invariants, the same answers, never a higher SAH cost.
    let fraction = if u.arbitrary::<bool>()? { 1.0 } else { 0.1 };
    let reinserted: Vec<(String, Bvh, u32)> = built
        .iter()
        .map(|(what, bvh, max_depth)| {
            let mut better = bvh.clone();
            let config = ReinsertConfig {
                fraction,
                max_passes: 2,
                max_depth: *max_depth,
                ..ReinsertConfig::default()
            };
            reinsert(&mut better, &Sah, &config);
            let k = CostConstants::default();
            let (before, after) = (bvh.estimated_cost(&Sah, k), better.estimated_cost(&Sah, k));
            assert!(
                !(after > before * (1.0 + 1e-5)),
                "{what}: reinsertion raised the SAH cost {before} -> {after}"
            );
            (format!("{what} reinserted"), better, *max_depth)
        })
        .collect();
    built.extend(reinserted);

    for (what, bvh, max_depth) in &built {
        check_tree(bvh, &tris, *max_depth, what);
        let wide = WideBvh::from_binary(bvh, &tris);
        assert!(wide.max_depth() <= MAX_DEPTH, "{what}: wide depth");
        for ray in &rays {
            check_queries(bvh, &wide, &tris, ray, what);
        }
    }
    // The SBVH: split triangles may sit in several leaves, so `validate_split`, and closest and
    // any hit (an all-hit count would count a split triangle once per part) against brute force.
    let splits = SpatialSplits {
        alpha: if u.arbitrary::<bool>()? { 0.0 } else { 1e-5 },
        budget: f32::from(u.int_in_range(0u8..=8)?) * 0.25,
        spatial_bins: u.int_in_range(2u32..=64)?,
        max_leaf: u.int_in_range(1u32..=8)?,
        ..SpatialSplits::default()
    };
    match (SpatialBuilder::new(splits).build(&tris), expect_err) {
        (Ok(bvh), None) => {
            let what = format!("sbvh {splits:?}");
            if let Err(e) = bvh.validate_split(tris.len(), |i| tris[i as usize].bounds()) {
                panic!("{what}: invalid SBVH over {} triangles: {e}", tris.len());
            }
            let wide = WideBvh::from_binary(&bvh, &tris);
            for ray in rays.iter().filter(|r| known_core_bug(r, &tris).is_none()) {
                let expect = brute_force::closest_hit(ray, &tris);
                assert_eq!(bvh.closest_hit(ray, &tris), expect, "{what}: {ray:?}");
                assert_eq!(wide.closest_hit(ray), expect, "{what} 4-wide: {ray:?}");
                let any = expect.is_some();
                assert_eq!(bvh.any_hit(ray, &tris), any, "{what}: {ray:?}");
                assert_eq!(wide.any_hit(ray), any, "{what} 4-wide: {ray:?}");
            }
        }
        (Err(e), Some(x)) => assert_eq!(e, x, "sbvh"),
        (r, x) => panic!(
            "sbvh {splits:?}: got {:?}, expected error {x:?}",
            r.map(|_| ())
        ),
    }

    // An empty scene hits nothing, whatever the ray.
    if tris.is_empty() {
        let empty: &[Triangle] = &[];
        for (_, bvh, _) in &built {
            for ray in &rays {
                assert_eq!(bvh.closest_hit(ray, empty), None);
            }
        }
    }
    Ok(())
}
