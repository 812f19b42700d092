//! Closest-hit and any-hit traversal of camera rays and random rays, and any hit of shadow
//! segments, on the bunny and Crytek Sponza: rdbvh beside the peers (with the C++ ones under the
//! `cpp-peers` feature, each by its default build and its spatial-split build, beside rdbvh's
//! SBVH), on the same triangles and the same rays, throughput in rays.
//!
//! Before anything is timed, every library's answers are compared with rdbvh's, ray by ray, and
//! the run stops if any library agrees on fewer than [`MIN_AGREEMENT`] of the rays: a speed
//! measured on wrong answers means nothing. The agreement rates are printed with the results.

mod clock;

use std::hint::black_box;
use std::time::Duration;

use clock::Clock;
use criterion::{
    criterion_group, criterion_main, BenchmarkGroup, Criterion, SamplingMode, Throughput,
};
use rdbvh_benches::compare::{reference_sets, RaySet};
use rdbvh_benches::peers::{
    BvhCrate, Library, ObvhsBvh2, ObvhsCwbvh, Parry, Prepared, Rdbvh, RdbvhWide, RdbvhWide8,
    RdbvhWide8Sbvh,
};
use rdbvh_benches::{agreement, load_scene, RayKind, BENCH_SCENES, MIN_AGREEMENT};
use rdbvh_core::bvh::{AnyHit, ClosestHit};
use rdbvh_core::geometry::{Ray, Triangle};

/// One library, built once, with the rays of both sets in its own format.
struct Subject<L: Library> {
    prepared: Prepared<L>,
    rays: Vec<(RayKind, Vec<L::Ray>)>,
}

impl<L: Library> Subject<L> {
    /// Builds, converts the rays and checks agreement with rdbvh's `reference` answers.
    fn new(scene: &str, tris: &[Triangle], sets: &[RaySet]) -> Self {
        let prepared = Prepared::<L>::new(tris);
        let mut rays = Vec::new();
        for (kind, set, reference) in sets {
            let native = L::rays(set);
            let g = agreement(reference, &prepared.answers(&native));
            println!(
                "agreement {scene} {} {}: closest {:.4}%, any {:.4}% of {} rays",
                kind.name(),
                L::NAME,
                100.0 * g.closest,
                100.0 * g.any,
                g.rays
            );
            assert!(
                g.closest >= MIN_AGREEMENT && g.any >= MIN_AGREEMENT,
                "{} disagrees with rdbvh on {scene} {} rays: {g:?}",
                L::NAME,
                kind.name()
            );
            rays.push((*kind, native));
        }
        Self { prepared, rays }
    }

    fn bench(&self, group: &mut BenchmarkGroup<'_, Clock>, kind: RayKind, any: bool) {
        let rays = &self.rays.iter().find(|(k, _)| *k == kind).expect("set").1;
        group.bench_function(L::NAME, |b| {
            if any {
                b.iter(|| self.prepared.any_all(black_box(rays)))
            } else {
                b.iter(|| self.prepared.closest_all(black_box(rays)))
            }
        });
    }
}

fn traversals(c: &mut Criterion<Clock>) {
    for name in BENCH_SCENES {
        let tris = match load_scene(name) {
            Ok(t) => t,
            Err(e) => {
                eprintln!("traversal benchmarks skipped for {name}: {e}");
                continue;
            }
        };
        let sets = reference_sets(&tris);
        let rdbvh = Subject::<Rdbvh>::new(name, &tris, &sets);
        let wide = Subject::<RdbvhWide>::new(name, &tris, &sets);
        let wide8 = Subject::<RdbvhWide8>::new(name, &tris, &sets);
        let sbvh = Subject::<RdbvhWide8Sbvh>::new(name, &tris, &sets);
        let obvhs2 = Subject::<ObvhsBvh2>::new(name, &tris, &sets);
        let obvhs8 = Subject::<ObvhsCwbvh>::new(name, &tris, &sets);
        let bvh = Subject::<BvhCrate>::new(name, &tris, &sets);
        let parry = Subject::<Parry>::new(name, &tris, &sets);
        #[cfg(feature = "cpp-peers")]
        let embree = {
            if let Err(e) = rdbvh_benches::peers::embree::available() {
                panic!("the cpp-peers feature needs a working Embree 3: {e}");
            }
            Subject::<rdbvh_benches::peers::Embree>::new(name, &tris, &sets)
        };
        #[cfg(feature = "cpp-peers")]
        let (tiny8, tiny4) = {
            if let Err(e) = rdbvh_benches::peers::tinybvh::available() {
                panic!("the cpp-peers feature's tinybvh does not match its adapter: {e}");
            }
            (
                Subject::<rdbvh_benches::peers::TinybvhBvh8>::new(name, &tris, &sets),
                Subject::<rdbvh_benches::peers::TinybvhBvh4>::new(name, &tris, &sets),
            )
        };
        #[cfg(feature = "cpp-peers")]
        let (embree_high, tiny8_hq) = (
            Subject::<rdbvh_benches::peers::EmbreeHigh>::new(name, &tris, &sets),
            Subject::<rdbvh_benches::peers::TinybvhBvh8Hq>::new(name, &tris, &sets),
        );
        for (query, any) in [("closest", false), ("any", true)] {
            for (kind, rays, _) in &sets {
                // Shadow segments are any-hit queries only, as renderers trace them.
                if *kind == RayKind::Shadow && !any {
                    continue;
                }
                let mut group =
                    c.benchmark_group(format!("traverse/{name}/{query}-{}", kind.name()));
                group
                    .throughput(Throughput::Elements(rays.len() as u64))
                    .sampling_mode(SamplingMode::Flat)
                    .sample_size(10)
                    .warm_up_time(Duration::from_millis(500))
                    .measurement_time(Duration::from_secs(2));
                rdbvh.bench(&mut group, *kind, any);
                wide.bench(&mut group, *kind, any);
                wide8.bench(&mut group, *kind, any);
                sbvh.bench(&mut group, *kind, any);
                obvhs2.bench(&mut group, *kind, any);
                obvhs8.bench(&mut group, *kind, any);
                bvh.bench(&mut group, *kind, any);
                parry.bench(&mut group, *kind, any);
                #[cfg(feature = "cpp-peers")]
                {
                    embree.bench(&mut group, *kind, any);
                    tiny8.bench(&mut group, *kind, any);
                    tiny4.bench(&mut group, *kind, any);
                    embree_high.bench(&mut group, *kind, any);
                    tiny8_hq.bench(&mut group, *kind, any);
                }
                group.finish();
            }
        }
        skeleton(c, name, &wide.prepared.accel, &sets[1].1);
    }
}

/// The queries (`closest_hit`, `any_hit`) beside the same visitors run through the public
/// skeleton (`WideBvh::traverse`), on the random rays: a caller's own leaf callback pays nothing
/// for going through the shared loop.
fn skeleton(c: &mut Criterion<Clock>, name: &str, wide: &rdbvh_core::bvh::WideBvh, rays: &[Ray]) {
    let mut group = c.benchmark_group(format!("traverse/{name}/skeleton-random"));
    group
        .throughput(Throughput::Elements(rays.len() as u64))
        .sampling_mode(SamplingMode::Flat)
        .sample_size(10)
        .warm_up_time(Duration::from_millis(500))
        .measurement_time(Duration::from_secs(2));
    group.bench_function("closest_hit", |b| {
        b.iter(|| {
            black_box(rays)
                .iter()
                .filter(|r| wide.closest_hit(r).is_some())
                .count()
        })
    });
    group.bench_function("traverse-ClosestHit", |b| {
        b.iter(|| {
            black_box(rays)
                .iter()
                .filter(|r| {
                    let mut v = ClosestHit::new(r);
                    wide.traverse(r, &mut v);
                    v.best.is_some()
                })
                .count()
        })
    });
    group.bench_function("any_hit", |b| {
        b.iter(|| black_box(rays).iter().filter(|r| wide.any_hit(r)).count())
    });
    group.bench_function("traverse-AnyHit", |b| {
        b.iter(|| {
            black_box(rays)
                .iter()
                .filter(|r| wide.traverse(r, &mut AnyHit::new(r)))
                .count()
        })
    });
    group.finish();
}

criterion_group! {
    name = benches;
    config = Criterion::default().with_measurement(Clock::from_env());
    targets = traversals
}
criterion_main!(benches);
