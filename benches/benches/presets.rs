//! Build time of the six presets on the bunny and Crytek Sponza, throughput in
//! triangles: `presets/SCENE/{sah,standard}` (no area: these presets ignore it) and
//! `presets/SCENE/{facing,longest,full}-{plane,point}` with a plane area (light rectangle just
//! outside the scene's box, normal tilted about 13 degrees from straight down, covering the box)
//! and a point area (eye outside the box, 90 x 90 degree frustum holding it); see
//! `rdbvh_benches::areas`. The targets: PAH orthographic (`longest`/`full` with the plane
//! area) within 1.25x of the `sah` build time, PAH perspective (with the point area) within 2x.
//!
//! One thread, `PresetOptions::default()`, arena and output reused; the timed build includes
//! loading the triangles into the arena (bounding them), as `build_pah` in `build.rs` does.
//! Clock per `RDBVH_BENCH_CLOCK` (thread CPU time by default).

mod clock;

use std::hint::black_box;
use std::time::Duration;

use clock::Clock;
use criterion::{criterion_group, criterion_main, Criterion, SamplingMode, Throughput};
use rdbvh_benches::areas::{plane_area_facing, point_area_facing};
use rdbvh_benches::{bounds, load_scene, BENCH_SCENES};
use rdbvh_core::builder::{BuildArena, BuildOptions, Preset, PresetOptions};
use rdbvh_core::bvh::Bvh;
use rdbvh_core::influence::InfluenceArea;

fn presets(c: &mut Criterion<Clock>) {
    for name in BENCH_SCENES {
        let tris = match load_scene(name) {
            Ok(t) => t,
            Err(e) => {
                eprintln!("preset benchmarks skipped for {name}: {e}");
                continue;
            }
        };
        let b = bounds(&tris);
        let (plane, point): (InfluenceArea, InfluenceArea) =
            match (plane_area_facing(&b), point_area_facing(&b)) {
                (Ok(p), Ok(q)) => (p.into(), q.into()),
                (Err(e), _) | (_, Err(e)) => {
                    eprintln!("preset benchmarks skipped for {name}: {e}");
                    continue;
                }
            };
        let mut rows: Vec<(String, Preset, Option<InfluenceArea>)> = Vec::new();
        for preset in Preset::ALL {
            if preset.needs_area() {
                rows.push((format!("{preset}-plane"), preset, Some(plane)));
                rows.push((format!("{preset}-point"), preset, Some(point)));
            } else {
                rows.push((preset.to_string(), preset, None));
            }
        }
        let mut group = c.benchmark_group(format!("presets/{name}"));
        group
            .throughput(Throughput::Elements(tris.len() as u64))
            // Builds take tens to hundreds of milliseconds: ten flat samples each.
            .sampling_mode(SamplingMode::Flat)
            .sample_size(10)
            .warm_up_time(Duration::from_millis(500))
            .measurement_time(Duration::from_secs(2));
        let options = PresetOptions::default();
        let mut arena = BuildArena::with_capacity(tris.len());
        let mut out = Bvh::with_capacity(tris.len());
        for (id, preset, area) in &rows {
            group.bench_function(id.as_str(), |bench| {
                bench.iter(|| {
                    arena
                        .load_triangles(black_box(&tris))
                        .expect("finite triangles");
                    BuildOptions::with_settings(*preset, options)
                        .build_into(&mut arena, area.as_ref(), &mut out)
                        .expect("valid preset")
                        .nodes
                })
            });
        }
        group.finish();
    }
}

criterion_group! {
    name = benches;
    config = Criterion::default().with_measurement(Clock::from_env());
    targets = presets
}
criterion_main!(benches);
