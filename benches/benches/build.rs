//! Single-threaded BVH builds on the bunny and Crytek Sponza: rdbvh's binned SAH beside the
//! peers' builders, throughput in triangles.
//!
//! Each library builds from triangles already in its own format (converted once, untimed); the
//! timed build includes bounding the triangles, which every builder must do. Outputs are dropped
//! outside the timing (`iter_with_large_drop`), so freeing a tree is not counted against anyone.

mod clock;

use std::hint::black_box;
use std::time::Duration;

use clock::Clock;
use criterion::{criterion_group, criterion_main, Criterion, SamplingMode, Throughput};
use rdbvh_benches::peers::{BvhCrate, Library, ObvhsBvh2, ObvhsCwbvh, Parry, Rdbvh, RdbvhWide};
use rdbvh_benches::{load_scene, RdbvhReuse, BENCH_SCENES};
use rdbvh_core::geometry::Triangle;

fn bench_library<L: Library>(group: &mut criterion::BenchmarkGroup<'_, Clock>, tris: &[Triangle]) {
    let mut scene = L::scene(tris);
    group.bench_function(L::NAME, |b| {
        b.iter_with_large_drop(|| L::build(black_box(&mut scene)))
    });
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
        let mut group = c.benchmark_group(format!("build/{name}"));
        group
            .throughput(Throughput::Elements(tris.len() as u64))
            // Builds take tens to hundreds of milliseconds: flat sampling keeps ten samples
            // within the time budget instead of criterion's growing iteration counts.
            .sampling_mode(SamplingMode::Flat)
            .sample_size(10)
            .warm_up_time(Duration::from_secs(1))
            .measurement_time(Duration::from_secs(3));
        bench_library::<Rdbvh>(&mut group, &tris);
        // The allocation-free path: arena and output sized once, reused by every build.
        let mut reuse = RdbvhReuse::with_capacity(tris.len());
        group.bench_function("rdbvh-reuse", |b| {
            b.iter(|| reuse.build(black_box(&tris)).nodes().len())
        });
        bench_library::<RdbvhWide>(&mut group, &tris);
        bench_library::<ObvhsBvh2>(&mut group, &tris);
        bench_library::<ObvhsCwbvh>(&mut group, &tris);
        bench_library::<BvhCrate>(&mut group, &tris);
        bench_library::<Parry>(&mut group, &tris);
        group.finish();
    }
}

criterion_group! {
    name = benches;
    config = Criterion::default().with_measurement(Clock::from_env());
    targets = builds
}
criterion_main!(benches);
