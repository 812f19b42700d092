//! The top-level structure: the area lookup, and queries through the structure against its
//! fallback BVH alone.
//!
//! `lookup/N/{list,octree-L}`: time per looked-up point of the naive area list against the octree
//! with `L` levels, for `N` = 1 to 80 random areas (plane and point areas in turn, in a 10 x 10 x
//! 10 region, fixed seed) and points uniform in the areas' bounds. A lookup is what a renderer
//! does per ray origin: `candidates(p)`, then the containment test of each candidate. Levels 3, 5
//! and 8 for every count, every level from 3 to 8 for 8 and 80 areas (the thesis found the octree
//! faster from about 8 areas at 7 levels).
//!
//! `query/SCENE/AREA/{structure,fallback}`: closest hit of affine rays (sampled from the area with
//! `RaySampler`, fixed seed) through the scene structure (both areas, `full` local BVHs, octree of
//! the default 5 levels, one try) against the fallback BVH (3-axis SAH) alone, on the bunny (areas
//! over its box, as in `presets.rs`) and the thesis's WoodScene (its oblique plane and point areas
//! from `../shared/thesis/experiments.toml`). Before timing, the two answers are compared ray by
//! ray and the mean traversal cost per ray (inner nodes + triangle tests) of each is printed.
//! `query/SCENE/AREA/{structure,fallback}-wide`: the same after `TopLevel::widen` (4-wide local and
//! fallback BVHs), checked ray by ray against the binary scene first.
//! `query/SCENE/AREA/lookup-clip`: what every query through the structure pays before it touches
//! a tree (`TopLevel::affine_segments`: the octree lookup, the affinity test and the clip).
//!
//! Clock per `RDBVH_BENCH_CLOCK` (thread CPU time by default).

mod clock;

use std::hint::black_box;
use std::time::Duration;

use clock::Clock;
use criterion::measurement::Measurement;
use criterion::{criterion_group, criterion_main, BenchmarkGroup, Criterion, Throughput};
use glam::Vec3;
use rdbvh_benches::areas::{plane_area_facing, point_area_facing, random_areas, random_points};
use rdbvh_benches::{bounds, load_scene, scenes_dir};
use rdbvh_core::bvh::TraversalStats;
use rdbvh_core::geometry::{Aabb, Ray, Triangle};
use rdbvh_core::heuristics::CostConstants;
use rdbvh_core::influence::{InfluenceArea, PlaneArea, PointArea, RaySampler};
use rdbvh_core::toplevel::{
    AreaList, AreaLookup, Octree, TopLevel, TopLevelOptions, TopLevelStats, DEFAULT_OCTREE_LEVELS,
};

/// Area counts of the lookup benchmark.
const AREA_COUNTS: [usize; 8] = [1, 2, 4, 8, 16, 32, 64, 80];
/// Points looked up per iteration.
const POINTS: usize = 4096;
/// Affine rays per area in the query benchmark.
const RAYS: usize = 16_384;
const AREA_SEED: u64 = 0xA7EA_2026;
const POINT_SEED: u64 = 0x9017_2026;
const RAY_SEED: u64 = 0x7A75_2026;

fn short<M: Measurement>(group: &mut BenchmarkGroup<'_, M>, elements: usize) {
    group
        .throughput(Throughput::Elements(elements as u64))
        .sample_size(10)
        .warm_up_time(Duration::from_millis(200))
        .measurement_time(Duration::from_millis(700));
}

/// What a renderer does per ray origin: the candidates, then each one's containment test.
#[inline]
fn lookups<L: AreaLookup>(lookup: &L, areas: &[InfluenceArea], points: &[Vec3]) -> usize {
    points
        .iter()
        .map(|&p| {
            lookup
                .candidates(p)
                .iter()
                .filter(|&&a| areas[a as usize].contains(p))
                .count()
        })
        .sum()
}

fn lookup(c: &mut Criterion<Clock>) {
    for n in AREA_COUNTS {
        let areas = random_areas(n, 10.0, AREA_SEED);
        let b = areas.iter().fold(Aabb::EMPTY, |b, a| b.union(a.bounds()));
        let points = random_points(&b, POINTS, POINT_SEED);
        let list = AreaList::new(n);
        let expected = lookups(&list, &areas, &points);
        let mut group = c.benchmark_group(format!("lookup/{n}"));
        short(&mut group, POINTS);
        group.bench_function("list", |bench| {
            bench.iter(|| lookups(&list, &areas, black_box(&points)))
        });
        let levels: &[u32] = if n == 8 || n == 80 {
            &[3, 4, 5, 6, 7, 8]
        } else {
            &[3, 5, 8]
        };
        for &l in levels {
            let octree = Octree::build(&areas, l);
            // Conservative lookup: the octree finds every containing area the list finds.
            assert_eq!(
                lookups(&octree, &areas, &points),
                expected,
                "{n} areas, {l} levels"
            );
            let s = octree.stats();
            eprintln!(
                "lookup/{n}/octree-{l}: {s:?}, {} bytes, {:.2} candidates per point (list {n}, {:.2} containing)",
                octree.memory_bytes(),
                points.iter().map(|&p| octree.candidates(p).len()).sum::<usize>() as f64
                    / POINTS as f64,
                expected as f64 / POINTS as f64,
            );
            group.bench_function(format!("octree-{l}"), |bench| {
                bench.iter(|| lookups(&octree, &areas, black_box(&points)))
            });
        }
        group.finish();
    }
}

/// The thesis's oblique WoodScene areas (`Wood_Plane_Oblique`, `Wood_Point_Oblique`).
fn wood_areas() -> Result<(InfluenceArea, InfluenceArea), String> {
    let plane = PlaneArea::new(
        Vec3::new(2.5, 1.5, -1.0),
        Vec3::new(-1.0, -0.3, 0.4),
        1.8,
        1.3,
        20.0,
    )
    .map_err(|e| e.to_string())?;
    let point = PointArea::new(
        Vec3::new(2.5, 1.5, -1.0),
        Vec3::new(-1.0, -0.3, 0.4),
        90.0,
        60.0,
        1.0,
        20.0,
    )
    .map_err(|e| e.to_string())?;
    Ok((plane.into(), point.into()))
}

fn scene_areas(name: &str, tris: &[Triangle]) -> Result<(InfluenceArea, InfluenceArea), String> {
    if name == "thesis/WoodScene" {
        return wood_areas();
    }
    let b = bounds(tris);
    Ok((plane_area_facing(&b)?.into(), point_area_facing(&b)?.into()))
}

fn query(c: &mut Criterion<Clock>) {
    if let Err(e) = scenes_dir() {
        eprintln!("query benchmarks skipped: {e}");
        return;
    }
    for name in ["bunny", "thesis/WoodScene"] {
        let loaded = load_scene(name).and_then(|t| scene_areas(name, &t).map(|a| (t, a)));
        let (tris, (plane, point)) = match loaded {
            Ok(x) => x,
            Err(e) => {
                eprintln!("query benchmarks skipped for {name}: {e}");
                continue;
            }
        };
        let scene = match TopLevel::with_octree(
            &tris,
            vec![plane, point],
            &TopLevelOptions::default(),
            DEFAULT_OCTREE_LEVELS,
        ) {
            Ok(s) => s,
            Err(e) => {
                eprintln!("query benchmarks skipped for {name}: {e}");
                continue;
            }
        };
        let wide = scene.clone().widen(&tris);
        let short_name = name.rsplit('/').next().unwrap_or(name);
        for (kind, area) in [("plane", plane), ("point", point)] {
            let mut sampler = RaySampler::new(area, RAY_SEED);
            let rays: Vec<Ray> = (0..RAYS).map(|_| sampler.sample()).collect();
            report_costs(&format!("query/{short_name}/{kind}"), &scene, &rays, &tris);
            let mut group = c.benchmark_group(format!("query/{short_name}/{kind}"));
            short(&mut group, RAYS);
            group.bench_function("structure", |bench| {
                bench.iter(|| {
                    black_box(&rays)
                        .iter()
                        .filter(|r| scene.closest_hit(r, &tris).is_some())
                        .count()
                })
            });
            // What every query pays before any tree: the lookup, the affinity test and the clip.
            group.bench_function("lookup-clip", |bench| {
                bench.iter(|| {
                    black_box(&rays)
                        .iter()
                        .map(|r| scene.affine_segments(r).count())
                        .sum::<usize>()
                })
            });
            let fallback = scene.fallback();
            group.bench_function("fallback", |bench| {
                bench.iter(|| {
                    black_box(&rays)
                        .iter()
                        .filter(|r| fallback.closest_hit(r, &tris).is_some())
                        .count()
                })
            });
            for r in &rays {
                assert_eq!(wide.closest_hit(r, &tris), scene.closest_hit(r, &tris));
            }
            group.bench_function("structure-wide", |bench| {
                bench.iter(|| {
                    black_box(&rays)
                        .iter()
                        .filter(|r| wide.closest_hit(r, &tris).is_some())
                        .count()
                })
            });
            let fallback = wide.fallback();
            group.bench_function("fallback-wide", |bench| {
                bench.iter(|| {
                    black_box(&rays)
                        .iter()
                        .filter(|r| fallback.closest_hit(r).is_some())
                        .count()
                })
            });
            group.finish();
        }
    }
}

/// Untimed: agreement of the structure with the fallback BVH, the local hit rate and the mean
/// cost per ray of each (`C_trav = C_isect = 1`).
fn report_costs(id: &str, scene: &TopLevel<Octree>, rays: &[Ray], tris: &[Triangle]) {
    let k = CostConstants::default();
    let (mut same, mut hits, mut local_hits, mut tried) = (0usize, 0usize, 0usize, 0usize);
    let (mut cost_s, mut cost_f) = (0f64, 0f64);
    for r in rays {
        let mut s = TopLevelStats::default();
        let a = scene.closest_hit_with_stats(r, tris, &mut s);
        let mut f = TraversalStats::default();
        let b = scene.fallback().closest_hit_with_stats(r, tris, &mut f);
        same += usize::from(match (a, b) {
            (None, None) => true,
            (Some(x), Some(y)) => x.triangle == y.triangle || (x.t - y.t).abs() <= 1e-5 * x.t,
            _ => false,
        });
        hits += usize::from(b.is_some());
        local_hits += usize::from(s.answered_by.is_some());
        tried += usize::from(s.tries > 0);
        cost_s += f64::from(s.cost(k));
        cost_f += f64::from(f.cost(k));
    }
    let n = rays.len() as f64;
    eprintln!(
        "{id}: {} rays, {:.2}% agree, {:.1}% hit, {:.1}% affine-tried, local hit rate {:.1}%, \
         cost per ray structure {:.1} vs fallback {:.1} ({:.2}x)",
        rays.len(),
        100.0 * same as f64 / n,
        100.0 * hits as f64 / n,
        100.0 * tried as f64 / n,
        100.0 * local_hits as f64 / n,
        cost_s / n,
        cost_f / n,
        cost_s / cost_f.max(1e-9),
    );
    assert_eq!(
        same,
        rays.len(),
        "{id}: the structure disagrees with the fallback BVH"
    );
}

criterion_group! {
    name = benches;
    config = Criterion::default().with_measurement(Clock::from_env());
    targets = lookup, query
}
criterion_main!(benches);
