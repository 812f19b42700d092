//! One run: a configuration's area, a preset, a build, its analysis and its measured costs.

use std::time::Instant;

use rdbvh_core::analyze::{
    analyze, Epo, EstimatedCost, OverlapSpace, RayCostSums, RayCosts, SiblingOverlap, TreeShape,
};
use rdbvh_core::builder::{BuildArena, BuildOptions, Preset, PresetOptions};
use rdbvh_core::bvh::Bvh;
use rdbvh_core::geometry::{Ray, Triangle};
use rdbvh_core::heuristics::AreaPah;
use rdbvh_core::heuristics::CostConstants;
use rdbvh_core::influence::{InfluenceArea, PointDistribution, RaySampler};
use rdbvh_core::toplevel::{Octree, TopLevel};

use super::ExperimentError;
use crate::clock::StdClock;

/// How a run is set up.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct RunSetup {
    /// Local build options.
    pub local: PresetOptions,
    /// Fallback build options.
    pub fallback: PresetOptions,
    /// The fallback's preset: `standard` (SAH + LSPH) in thesis mode, as the thesis built its
    /// global BVH; `sah` (binned SAH over all axes) otherwise.
    pub fallback_preset: Preset,
    /// Cost constants of estimates and measurements.
    pub constants: CostConstants,
    /// Rays per run.
    pub rays: u32,
    /// Octree levels.
    pub octree_levels: u32,
    /// Point areas' direction sampler: the thesis's yaw/pitch in thesis mode, uniform solid angle
    /// (what solid-angle PAH models) otherwise.
    pub point_distribution: PointDistribution,
}

/// Everything measured for one run.
#[derive(Clone, Debug, Default, PartialEq)]
pub struct RunMetrics {
    /// Triangles in the local BVH.
    pub local_triangles: u32,
    /// Milliseconds to build the local BVH (selection of the area's triangles excluded).
    pub build_ms: f64,
    /// Phase times and calls of a second, profiled build of the same local BVH (timing every
    /// phase slows a build, so `build_ms` comes from the unprofiled one).
    pub profile: rdbvh_core::builder::PhaseProfile,
    /// Shape of the local BVH.
    pub shape: rdbvh_core::analyze::ShapeReport,
    /// PAH estimate per ray of the area (over its window measure).
    pub pah: f32,
    /// PAH estimate relative to the root's projection.
    pub pah_root: f32,
    /// SAH estimate.
    pub sah: f32,
    /// End-point overlap.
    pub epo: f32,
    /// Sibling overlap in 3D at the thesis levels.
    pub overlap_3d: Vec<f32>,
    /// Projected sibling overlap at the thesis levels.
    pub overlap_projected: Vec<f32>,
    /// Projected and culled sibling overlap at the thesis levels.
    pub overlap_culled: Vec<f32>,
    /// Measured costs.
    pub costs: RayCosts,
    /// Closest-hit rays per second through the structure (one thread).
    pub rays_per_second: f64,
    /// Closest-hit rays per second through the fallback BVH alone (one thread).
    pub rays_per_second_fallback: f64,
    /// SAH estimate of the fallback BVH.
    pub fallback_sah: f32,
    /// Bytes of the fallback BVH.
    pub fallback_bytes: usize,
    /// Octree levels used, leaves and bytes.
    pub octree: rdbvh_core::toplevel::OctreeStats,
    /// Bytes of the area description.
    pub area_bytes: usize,
}

/// The rays of a run: the same for every preset of a configuration (seeded by its index).
pub fn sample_rays(area: &InfluenceArea, setup: &RunSetup, seed: u64) -> Vec<Ray> {
    let mut s = RaySampler::new(*area, seed).distribution(setup.point_distribution);
    (0..setup.rays).map(|_| s.sample()).collect()
}

/// Builds the fallback BVH of a scene.
pub fn build_fallback(tris: &[Triangle], setup: &RunSetup) -> Result<Bvh, ExperimentError> {
    let mut arena = BuildArena::with_capacity(tris.len());
    arena
        .load_triangles(tris)
        .map_err(|e| ExperimentError::Build(format!("fallback BVH: {e}")))?;
    let mut out = Bvh::with_capacity(tris.len());
    BuildOptions::with_settings(setup.fallback_preset, setup.fallback)
        .build_into(&mut arena, None, &mut out)
        .map_err(|e| ExperimentError::Build(format!("fallback BVH: {e}")))?;
    Ok(out)
}

/// Builds the local BVH of `area` with `preset`, assembles the structure around `fallback`,
/// analyses the local tree and traces `rays` every way.
pub fn run_one(
    tris: &[Triangle],
    area: &InfluenceArea,
    preset: Preset,
    fallback: &Bvh,
    rays: &[Ray],
    setup: &RunSetup,
) -> Result<RunMetrics, ExperimentError> {
    let k = setup.constants;
    let ids: Vec<u32> = area.triangles_in(tris).collect();
    let mut arena = BuildArena::with_capacity(ids.len());
    let mut local = Bvh::with_capacity(ids.len());
    let start = Instant::now();
    arena
        .load_triangle_subset(tris, ids.iter().copied())
        .map_err(|e| ExperimentError::Build(format!("local BVH: {e}")))?;
    BuildOptions::with_settings(preset, setup.local)
        .build_into(&mut arena, Some(area), &mut local)
        .map_err(|e| ExperimentError::Build(format!("local BVH ({preset}): {e}")))?;
    let build_ms = start.elapsed().as_secs_f64() * 1e3;
    let profile = {
        arena
            .load_triangle_subset(tris, ids.iter().copied())
            .map_err(|e| ExperimentError::Build(format!("local BVH: {e}")))?;
        let mut scratch = Bvh::with_capacity(ids.len());
        BuildOptions::with_settings(preset, setup.local)
            .build_into_profiled(&mut arena, Some(area), &mut scratch, &StdClock::new())
            .map_err(|e| ExperimentError::Build(format!("local BVH ({preset}): {e}")))?
            .profile
    };

    let pah = AreaPah::new(area, setup.local.perspective);
    let window = pah.window_measure();
    let (shape, sah, pah_cost, epo, (o3, op, oc)) = analyze(
        &local,
        (
            TreeShape::default(),
            EstimatedCost::sah(k),
            EstimatedCost::over(pah, k, window),
            Epo::new(tris, k),
            (
                SiblingOverlap::new(OverlapSpace::Volume),
                SiblingOverlap::new(OverlapSpace::projected(area, false)),
                SiblingOverlap::new(OverlapSpace::projected(area, true)),
            ),
        ),
    );
    let (fb_shape, fb_sah) = analyze(fallback, (TreeShape::default(), EstimatedCost::sah(k)));

    let octree = Octree::build(&[*area], setup.octree_levels);
    let octree_stats = octree.stats();
    let scene = TopLevel::from_parts(vec![*area], vec![local], fallback.clone(), octree, 1)
        .ok_or_else(|| ExperimentError::Build("structure: one local BVH per area".into()))?;

    let mut sums = RayCostSums::default();
    for ray in rays {
        sums.add(&scene, ray, tris, k);
    }
    let timed = |f: &dyn Fn(&Ray) -> bool| {
        let start = Instant::now();
        let mut hits = 0usize;
        for ray in rays {
            hits += usize::from(f(ray));
        }
        std::hint::black_box(hits);
        let s = start.elapsed().as_secs_f64();
        if s > 0.0 {
            rays.len() as f64 / s
        } else {
            0.0
        }
    };
    let rays_per_second = timed(&|r| scene.closest_hit(r, tris).is_some());
    let rays_per_second_fallback = timed(&|r| fallback.closest_hit(r, tris).is_some());

    Ok(RunMetrics {
        local_triangles: ids.len() as u32,
        build_ms,
        profile,
        shape,
        pah: pah_cost.per_ray,
        pah_root: pah_cost.relative_to_root,
        sah: sah.per_ray,
        epo: epo.epo,
        overlap_3d: o3.mean,
        overlap_projected: op.mean,
        overlap_culled: oc.mean,
        costs: sums.finish(),
        rays_per_second,
        rays_per_second_fallback,
        fallback_sah: fb_sah.per_ray,
        fallback_bytes: fb_shape.memory_bytes,
        octree: octree_stats,
        area_bytes: std::mem::size_of::<InfluenceArea>(),
    })
}
