//! PAH predicts what it models: on every thesis scene with its influence areas from `experiments.toml`, the
//! PAH estimate of a built tree equals the measured all-hit cost of the rays PAH models, within 2%
//! for plane areas and 3% for point areas whose sampler matches the measure (solid angle, image
//! plane), also at a 130-degree field of view. SAH, measured the same way, is far off: PAH's
//! accuracy is not an accident of the cost function.

use rdbvh::areas::read_areas;
use rdbvh::scene::Scene;
use rdbvh_core::builder::{BuildArena, BuildOptions, Preset, PresetOptions};
use rdbvh_core::bvh::Bvh;
use rdbvh_core::geometry::Triangle;
use rdbvh_core::heuristics::AreaPah;
use rdbvh_core::heuristics::{PerspectiveMeasure, Sah};
use rdbvh_core::influence::{InfluenceArea, PointArea, PointDistribution, RaySampler};
use rdbvh_tests::require_shared;

/// Rays per configuration, as the issue asks.
const RAYS: u32 = 100_000;

/// The local BVH of `area` with `preset`, over the triangles that overlap it.
fn local_bvh(tris: &[Triangle], area: &InfluenceArea, preset: Preset, o: &PresetOptions) -> Bvh {
    let mut arena = BuildArena::with_capacity(tris.len());
    arena
        .load_triangle_subset(tris, area.triangles_in(tris))
        .unwrap();
    let mut bvh = Bvh::with_capacity(arena.len());
    BuildOptions::with_settings(preset, *o)
        .build_into(&mut arena, Some(area), &mut bvh)
        .unwrap();
    bvh
}

/// `(PAH estimate, SAH-style estimate over the same rays, measured all-hit cost)` per ray.
fn estimate_and_measure(
    tris: &[Triangle],
    bvh: &Bvh,
    area: &InfluenceArea,
    o: &PresetOptions,
    distribution: PointDistribution,
) -> (f64, f64, f64) {
    let pah = AreaPah::new(area, o.perspective);
    let estimate = bvh.estimated_cost_over(&pah, o.constants, pah.window_measure());
    let sah = bvh.estimated_cost(&Sah, o.constants);
    let mut rays = RaySampler::new(*area, 2026).distribution(distribution);
    let measured: f64 = (0..RAYS)
        .map(|_| f64::from(bvh.all_hit(&rays.sample(), tris).cost(o.constants)))
        .sum::<f64>()
        / f64::from(RAYS);
    (f64::from(estimate), f64::from(sah), measured)
}

#[test]
fn pah_estimates_match_measured_cost_on_every_thesis_configuration() {
    let Some(shared) = require_shared() else {
        return;
    };
    let file = read_areas(&shared.join("thesis/experiments.toml")).unwrap();
    let scene_dir = shared.join("scenes/thesis");
    let mut checked = 0;
    let mut worst = [0.0f64; 2];
    let mut sah_errors = Vec::new();
    let mut by_file: Vec<(&str, Vec<&rdbvh::areas::AreaEntry>)> = Vec::new();
    for e in &file.entries {
        let Some(f) = e.file.as_deref() else { continue };
        match by_file.iter_mut().find(|(name, _)| *name == f) {
            Some((_, list)) => list.push(e),
            None => by_file.push((f, vec![e])),
        }
    }
    for (name, entries) in by_file {
        let path = scene_dir.join(name);
        if !path.exists() {
            // Crowd and Sponza were never published with the thesis framework.
            println!("no scene file for {name}: its configurations are not checked");
            continue;
        }
        let scene = Scene::load(&path).unwrap();
        for entry in entries {
            let area = &entry.area;
            let (kind, limit, distribution) = match area {
                InfluenceArea::Plane(_) => (0, 0.02, PointDistribution::SolidAngle),
                InfluenceArea::Point(_) => (1, 0.03, PointDistribution::SolidAngle),
            };
            let o = PresetOptions {
                perspective: PerspectiveMeasure::SolidAngle,
                ..PresetOptions::default()
            };
            let bvh = local_bvh(&scene.triangles, area, Preset::Full, &o);
            let (estimate, sah, measured) =
                estimate_and_measure(&scene.triangles, &bvh, area, &o, distribution);
            let error = (estimate - measured).abs() / measured;
            let test = entry.thesis_test.as_deref().unwrap_or("?");
            println!(
                "{test}: PAH {estimate:.3}, measured {measured:.3}, error {:.2}%",
                error * 100.0
            );
            assert!(
                error < limit,
                "{test}: PAH estimate {estimate} vs measured {measured}"
            );
            worst[kind] = worst[kind].max(error);
            sah_errors.push((sah - measured).abs() / measured);
            checked += 1;
        }
    }
    assert!(checked >= 40, "only {checked} configurations had scenes");
    let mean_sah = sah_errors.iter().sum::<f64>() / sah_errors.len() as f64;
    println!(
        "{checked} configurations: worst PAH error {:.2}% (plane), {:.2}% (point); mean SAH error {:.1}%",
        worst[0] * 100.0,
        worst[1] * 100.0,
        mean_sah * 100.0
    );
    assert!(
        mean_sah > 0.1,
        "SAH should not predict these rays: {mean_sah}"
    );
}

/// Both perspective measures at a 130-degree field of view, each with its own sampler.
#[test]
fn perspective_pah_holds_at_130_degrees_for_both_measures() {
    let Some(shared) = require_shared() else {
        return;
    };
    let scene = Scene::load(shared.join("scenes/thesis/WoodScene.obj")).unwrap();
    let area: InfluenceArea = PointArea::new(
        [0.1, 4.0, 0.2].into(),
        [0.0, -1.0, 0.05].into(),
        130.0,
        130.0,
        0.5,
        10.0,
    )
    .unwrap()
    .into();
    for (measure, distribution) in [
        (
            PerspectiveMeasure::SolidAngle,
            PointDistribution::SolidAngle,
        ),
        (
            PerspectiveMeasure::ImagePlane,
            PointDistribution::ImagePlane,
        ),
    ] {
        let o = PresetOptions {
            perspective: measure,
            ..PresetOptions::default()
        };
        let bvh = local_bvh(&scene.triangles, &area, Preset::Full, &o);
        let (estimate, _, measured) =
            estimate_and_measure(&scene.triangles, &bvh, &area, &o, distribution);
        let error = (estimate - measured).abs() / measured;
        println!(
            "{measure:?}: PAH {estimate:.3}, measured {measured:.3}, error {:.2}%",
            error * 100.0
        );
        assert!(error < 0.03, "{measure:?}: {estimate} vs {measured}");
    }
}

/// The `pah` preset (PAH over all three axes) against the thesis's `full` (PAH + SPFH) on every
/// thesis configuration with a scene: by the PAH estimate (exact for the tree) and by the
/// measured all-hit cost of the same 20,000 rays, `pah` is never costlier than `full` by more
/// than a rounding margin, and cheaper on the whole. Pricing every axis is what makes it so;
/// SPFH trusts the facing axis to save sweeps.
#[test]
fn pah_preset_costs_no_more_than_full_on_every_thesis_configuration() {
    let Some(shared) = require_shared() else {
        return;
    };
    let file = read_areas(&shared.join("thesis/experiments.toml")).unwrap();
    let mut scenes: std::collections::HashMap<String, Scene> = Default::default();
    let o = PresetOptions::default();
    let (mut log_estimates, mut log_measured, mut checked) = (0.0f64, 0.0f64, 0);
    for entry in &file.entries {
        let Some(name) = entry.file.as_deref() else {
            continue;
        };
        let path = shared.join("scenes/thesis").join(name);
        if !path.exists() {
            continue;
        }
        let scene = scenes
            .entry(name.to_string())
            .or_insert_with(|| Scene::load(&path).unwrap());
        let tris = &scene.triangles;
        let pah = AreaPah::new(&entry.area, o.perspective);
        let [full, all_axes] = [Preset::Full, Preset::Pah].map(|preset| {
            let bvh = local_bvh(tris, &entry.area, preset, &o);
            let estimate = bvh.estimated_cost_over(&pah, o.constants, pah.window_measure());
            let mut rays =
                RaySampler::new(entry.area, 7).distribution(PointDistribution::SolidAngle);
            let measured = (0..20_000)
                .map(|_| f64::from(bvh.all_hit(&rays.sample(), tris).cost(o.constants)))
                .sum::<f64>()
                / 20_000.0;
            (f64::from(estimate), measured)
        });
        let test = entry.thesis_test.as_deref().unwrap_or("?");
        println!(
            "{test}: pah {:.3} / full {:.3} estimated, {:.3} / {:.3} measured",
            all_axes.0, full.0, all_axes.1, full.1
        );
        assert!(
            all_axes.0 <= full.0 * 1.001,
            "{test}: estimates {all_axes:?} vs {full:?}"
        );
        assert!(
            all_axes.1 <= full.1 * 1.01,
            "{test}: measured {all_axes:?} vs {full:?}"
        );
        log_estimates += (all_axes.0 / full.0).ln();
        log_measured += (all_axes.1 / full.1).ln();
        checked += 1;
    }
    assert!(checked >= 40, "only {checked} configurations had scenes");
    let (estimated, measured) = (
        (log_estimates / f64::from(checked)).exp(),
        (log_measured / f64::from(checked)).exp(),
    );
    println!("{checked} configurations: pah / full geometric mean {estimated:.3} estimated, {measured:.3} measured");
    assert!(
        estimated < 0.95 && measured < 0.95,
        "{estimated}, {measured}"
    );
}
