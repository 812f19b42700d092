//! BVH builds on the bunny and Crytek Sponza: rdbvh's binned SAH beside the peers' builders,
//! throughput in triangles. `build/SCENE/LIB` is the single-threaded build (inside a one-thread
//! rayon pool, so obvhs's `parallel` feature cannot spread it; clock per `RDBVH_BENCH_CLOCK`),
//! `build_mt/SCENE/LIB` the threaded build on every core, always in wall time (its work is on
//! several threads), `build_pah/SCENE/...` rdbvh's SAH preset beside PAH + SPFH (`full`) with
//! a plane and a point area over the scene, `reinsert/SCENE` the reinsertion pass alone (these
//! are the rows of the `peers` binary's table), and `wide/SCENE/...` the SAH build and its 4-wide
//! collapse beside `Builder::for_wide`'s build and the same collapse.
//!
//! Each library builds from triangles already in its own format (converted once, untimed); the
//! timed build includes bounding the triangles, which every builder must do. Outputs are dropped
//! outside the timing (`iter_with_large_drop`), so freeing a tree is not counted against anyone.

mod clock;

use std::hint::black_box;
use std::time::Duration;

use clock::Clock;
use criterion::measurement::{Measurement, WallTime};
use criterion::{
    criterion_group, criterion_main, BatchSize, BenchmarkGroup, Criterion, SamplingMode, Throughput,
};
use rdbvh_benches::compare::{plane_area_over, point_area_over};
use rdbvh_benches::peers::{BvhCrate, Library, ObvhsBvh2, ObvhsCwbvh, Parry, Rdbvh, RdbvhWide};
use rdbvh_benches::{bounds, load_scene, single_thread_pool, RdbvhReuse, BENCH_SCENES};
use rdbvh_core::builder::{
    BuildArena, BuildOptions, Builder, Preset, PresetOptions, ReinsertConfig, Reinserter,
};
use rdbvh_core::bvh::{Bvh, WideBvh};
use rdbvh_core::geometry::Triangle;
use rdbvh_core::heuristics::Sah;
use rdbvh_core::influence::InfluenceArea;

/// The single-threaded build, measured on the pool's one thread (where the clock is read).
fn bench_library<L: Library>(
    group: &mut BenchmarkGroup<'_, Clock>,
    pool: &rayon::ThreadPool,
    tris: &[Triangle],
) where
    L::Scene: Send,
    L::Accel: Send,
{
    let mut scene = L::scene(tris);
    group.bench_function(L::NAME, |b| {
        pool.install(|| b.iter_with_large_drop(|| L::build(black_box(&mut scene))))
    });
}

/// The threaded build on the global rayon pool (every core); libraries without one are skipped.
fn bench_library_mt<L: Library, M: Measurement>(
    group: &mut BenchmarkGroup<'_, M>,
    tris: &[Triangle],
) {
    if L::PARALLEL_BUILD.is_none() {
        return;
    }
    let mut scene = L::scene(tris);
    group.bench_function(L::NAME, |b| {
        b.iter_with_large_drop(|| L::build_mt(black_box(&mut scene)))
    });
}

fn configure<M: Measurement>(group: &mut BenchmarkGroup<'_, M>, n: usize) {
    group
        .throughput(Throughput::Elements(n as u64))
        // Builds take tens to hundreds of milliseconds: flat sampling keeps ten samples
        // within the time budget instead of criterion's growing iteration counts.
        .sampling_mode(SamplingMode::Flat)
        .sample_size(10)
        .warm_up_time(Duration::from_secs(1))
        .measurement_time(Duration::from_secs(3));
}

fn builds(c: &mut Criterion<Clock>) {
    for name in BENCH_SCENES {
        let tris = match load_scene(name) {
            Ok(t) => t,
            Err(e) => {
                eprintln!("build benchmarks skipped for {name}: {e}");
                continue;
            }
        };
        let pool = single_thread_pool();
        let mut group = c.benchmark_group(format!("build/{name}"));
        configure(&mut group, tris.len());
        bench_library::<Rdbvh>(&mut group, &pool, &tris);
        // The allocation-free path: arena and output sized once, reused by every build.
        let mut reuse = RdbvhReuse::with_capacity(tris.len());
        group.bench_function("rdbvh-reuse", |b| {
            b.iter(|| reuse.build(black_box(&tris)).nodes().len())
        });
        bench_library::<RdbvhWide>(&mut group, &pool, &tris);
        bench_library::<ObvhsBvh2>(&mut group, &pool, &tris);
        bench_library::<ObvhsCwbvh>(&mut group, &pool, &tris);
        bench_library::<BvhCrate>(&mut group, &pool, &tris);
        bench_library::<Parry>(&mut group, &pool, &tris);
        group.finish();

        // PAH beside SAH (target: within 1.1x), the `peers` binary's areas over the scene.
        let b = bounds(&tris);
        let areas: Vec<(&str, Preset, Option<InfluenceArea>)> = vec![
            ("sah", Preset::Sah, None),
            (
                "full-plane",
                Preset::Full,
                plane_area_over(&b).ok().map(Into::into),
            ),
            (
                "full-point",
                Preset::Full,
                point_area_over(&b).ok().map(Into::into),
            ),
        ];
        let mut group = c.benchmark_group(format!("build_pah/{name}"));
        configure(&mut group, tris.len());
        let options = PresetOptions::default();
        let mut arena = BuildArena::with_capacity(tris.len());
        let mut out = Bvh::with_capacity(tris.len());
        for (id, preset, area) in &areas {
            if preset.needs_area() && area.is_none() {
                eprintln!("build_pah/{name}/{id} skipped: no area over the scene");
                continue;
            }
            group.bench_function(*id, |bench| {
                bench.iter(|| {
                    arena.load_triangles(&tris).expect("finite triangles");
                    BuildOptions::with_settings(*preset, options)
                        .build_into(&mut arena, area.as_ref(), &mut out)
                        .expect("valid preset")
                        .nodes
                })
            });
        }
        group.finish();

        // Reinsertion alone (the step `rdbvh-wide`'s build adds), on a copy of the SAH tree made
        // outside the timing.
        let mut group = c.benchmark_group(format!("reinsert/{name}"));
        configure(&mut group, tris.len());
        let built = Rdbvh::build(&mut tris.clone());
        let mut reinserter = Reinserter::new();
        group.bench_function("sah-default", |bench| {
            bench.iter_batched_ref(
                || built.clone(),
                |tree| {
                    reinserter
                        .optimize(tree, &Sah, &ReinsertConfig::default())
                        .moved
                },
                BatchSize::LargeInput,
            )
        });
        group.finish();

        // A 4-wide tree without reinsertion: the SAH build and its collapse, beside the build
        // that leaves the nodes of at most four triangles unsplit (the same wide nodes).
        let mut group = c.benchmark_group(format!("wide/{name}"));
        configure(&mut group, tris.len());
        for (id, for_wide) in [("sah-collapse", false), ("for_wide-collapse", true)] {
            group.bench_function(id, |bench| {
                bench.iter(|| {
                    let bvh = if for_wide {
                        Builder::sah().for_wide().build(black_box(&tris))
                    } else {
                        Builder::sah().build(black_box(&tris))
                    };
                    WideBvh::from_binary(&bvh.expect("finite triangles"), &tris)
                        .nodes()
                        .len()
                })
            });
        }
        group.finish();
    }
}

/// Threaded builds, wall time (the thread-CPU clock would see one thread's share only).
fn builds_mt(c: &mut Criterion<WallTime>) {
    for name in BENCH_SCENES {
        let tris = match load_scene(name) {
            Ok(t) => t,
            Err(e) => {
                eprintln!("build_mt benchmarks skipped for {name}: {e}");
                continue;
            }
        };
        let mut group = c.benchmark_group(format!("build_mt/{name}"));
        configure(&mut group, tris.len());
        bench_library_mt::<Rdbvh, _>(&mut group, &tris);
        bench_library_mt::<RdbvhWide, _>(&mut group, &tris);
        bench_library_mt::<ObvhsBvh2, _>(&mut group, &tris);
        bench_library_mt::<ObvhsCwbvh, _>(&mut group, &tris);
        bench_library_mt::<BvhCrate, _>(&mut group, &tris);
        group.finish();
    }
}

criterion_group! {
    name = benches;
    config = Criterion::default().with_measurement(Clock::from_env());
    targets = builds
}
criterion_group! {
    name = benches_mt;
    config = Criterion::default();
    targets = builds_mt
}
criterion_main!(benches, benches_mt);
