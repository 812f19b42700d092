//! `build_profile SCENE [REPS] [AREAS.toml [PRESET]]`: rdbvh's single-threaded SAH build alone,
//! for profilers and quick before/after checks of the builder. SCENE is a name under
//! `../shared/scenes` (`bunny`, `sponza_crytek`) or a path to any OBJ file (or `builtin:NAME`).
//! Prints the best thread CPU time of `REPS` builds (default 7), the tree's SAH cost, its node count and a hash of its nodes and leaf order (two builds with
//! the same hash made the same tree), then the threaded build's best wall time on the global pool
//! and on one thread, the single-threaded build's best wall time (the `peers` scaling is that
//! over the threaded build's) and whether the threaded tree equals the single-threaded one.
//!
//! `RDBVH_PROFILE_PAH=1` adds the `full` (PAH + SPFH) and `pah` (PAH over all axes) presets over
//! the `peers` table's plane and point areas: CPU time, its ratio to the SAH build's, and the
//! tree's PAH cost (`C_trav = C_isect = 1`) and hash, and over the point area each preset again
//! pricing its splits by the centre estimate (`PresetOptions::perspective_estimate`), its tree's
//! PAH cost still by the exact measure; `plane` or `point` instead of `1` builds over that area alone, and
//! `RDBVH_PROFILE_PRESET=full` (or `pah`) that preset alone (for
//! `--toggle-collect=build_profile::pah_once`).
//! With AREAS.toml (an area file, as `rdbvh build --areas` takes), PRESET (default `full`) is
//! built over every triangle of the scene with each of its areas in turn, timed the same way:
//! how to benchmark a PAH build over your own light.
//!
//! Under `valgrind --tool=callgrind --toggle-collect=build_profile::build_once`, only the builds
//! (loading the triangle bounds included) are counted; `RDBVH_PROFILE_MT=0` skips the threaded
//! part, so callgrind runs stay short.

use std::hash::{Hash, Hasher};
use std::hint::black_box;
use std::process::ExitCode;
use std::time::Instant;

use rdbvh_benches::compare::{plane_area_over, point_area_over};
use rdbvh_benches::{open_scene, thread_cpu_seconds};
use rdbvh_core::builder::{BuildArena, BuildOptions, Builder, Preset, PresetError, PresetOptions};
use rdbvh_core::bvh::Bvh;
use rdbvh_core::geometry::Triangle;
use rdbvh_core::heuristics::AreaPah;
use rdbvh_core::heuristics::{CostConstants, Sah};
use rdbvh_core::influence::InfluenceArea;

/// One timed build: loading the bounds and the binned SAH build, as the `peers` table times it.
#[inline(never)]
fn build_once(tris: &[Triangle]) -> Bvh {
    Builder::sah().build(black_box(tris)).expect("finite scene")
}

/// One threaded build on the current rayon pool.
#[inline(never)]
fn build_mt_once(tris: &[Triangle]) -> Bvh {
    rdbvh_core::builder::parallel::build(&Builder::sah(), black_box(tris)).expect("finite scene")
}

/// One timed build of `preset` over `area`: loading the bounds and the preset's build, pricing a
/// point area's splits by the centre estimate when `estimate`.
#[inline(never)]
fn pah_once(
    tris: &[Triangle],
    preset: Preset,
    area: &InfluenceArea,
    estimate: bool,
    arena: &mut BuildArena,
    out: &mut Bvh,
) -> Result<(), PresetError> {
    arena.load_triangles(black_box(tris)).expect("finite");
    let settings = PresetOptions {
        perspective_estimate: estimate,
        ..PresetOptions::default()
    };
    BuildOptions::with_settings(preset, settings)
        .build_into(arena, Some(area), out)
        .map(|_| ())
}

fn tree_hash(bvh: &Bvh) -> u64 {
    let mut h = std::collections::hash_map::DefaultHasher::new();
    for n in bvh.nodes() {
        bytemuck_bits(n).hash(&mut h);
    }
    bvh.prim_indices().hash(&mut h);
    h.finish()
}

fn bytemuck_bits(n: &rdbvh_core::bvh::BvhNode) -> [u32; 8] {
    let b = n.bounds();
    let (lo, hi) = (b.min, b.max);
    [
        lo.x.to_bits(),
        lo.y.to_bits(),
        lo.z.to_bits(),
        hi.x.to_bits(),
        hi.y.to_bits(),
        hi.z.to_bits(),
        n.left_first,
        n.count,
    ]
}

fn best_wall(reps: usize, mut f: impl FnMut() -> Bvh) -> f64 {
    (0..reps)
        .map(|_| {
            let t = Instant::now();
            drop(black_box(f()));
            t.elapsed().as_secs_f64()
        })
        .fold(f64::INFINITY, f64::min)
}

fn main() -> ExitCode {
    let mut args = std::env::args().skip(1);
    let usage = "usage: build_profile SCENE [REPS] [AREAS.toml [PRESET]] (SCENE: a name under \
                 ../shared/scenes, an OBJ path or builtin:NAME)";
    let Some(scene) = args.next().filter(|s| !s.starts_with('-')) else {
        eprintln!("{usage}");
        return ExitCode::FAILURE;
    };
    let reps = match args.next().map(|r| r.parse::<usize>()) {
        None => 7,
        Some(Ok(r)) if r > 0 => r,
        Some(_) => {
            eprintln!("error: REPS must be a positive number; {usage}");
            return ExitCode::FAILURE;
        }
    };
    let own_areas = match args.next() {
        None => None,
        Some(file) => {
            let preset = args.next().unwrap_or_else(|| "full".to_string());
            let Some(preset) = Preset::from_name(&preset) else {
                eprintln!("error: unknown preset {preset}; {usage}");
                return ExitCode::FAILURE;
            };
            match rdbvh::areas::read_areas(std::path::Path::new(&file)) {
                Ok(f) => Some((f, preset)),
                Err(e) => {
                    eprintln!("error: {e}");
                    return ExitCode::FAILURE;
                }
            }
        }
    };
    let tris = match open_scene(&scene) {
        Ok(t) => t,
        Err(e) => {
            eprintln!("error: {e}");
            return ExitCode::FAILURE;
        }
    };
    let n = tris.len();
    let mut best = f64::INFINITY;
    let mut bvh = Bvh::default();
    for _ in 0..reps {
        let t = thread_cpu_seconds();
        bvh = build_once(&tris);
        best = best.min(thread_cpu_seconds() - t);
    }
    let cost = bvh.estimated_cost(&Sah, CostConstants::default());
    let hash = tree_hash(&bvh);
    println!(
        "{scene}: {n} tris; build_1t {:.2} ms ({:.2} Mtris/s, thread CPU, best of {reps}); \
         sah_cost {cost:.4}; nodes {}; tree {hash:016x}",
        best * 1e3,
        n as f64 / best * 1e-6,
        bvh.nodes().len()
    );
    // PAH: the `full` (PAH + SPFH) and `pah` presets with the plane and point areas the `peers`
    // table uses.
    let pah = std::env::var("RDBVH_PROFILE_PAH").unwrap_or_default();
    let only = std::env::var("RDBVH_PROFILE_PRESET").ok();
    let presets = [Preset::Full, Preset::Pah]
        .into_iter()
        .filter(|p| only.as_deref().is_none_or(|o| o == p.name()));
    if ["1", "plane", "point"].contains(&pah.as_str()) {
        let b = tris.iter().fold(rdbvh_core::geometry::Aabb::EMPTY, |b, t| {
            b.union(t.bounds())
        });
        let areas: [(&str, InfluenceArea); 2] = [
            ("plane", plane_area_over(&b).expect("plane").into()),
            ("point", point_area_over(&b).expect("point").into()),
        ];
        let areas = areas.iter().filter(|(name, _)| pah == "1" || pah == *name);
        let runs = areas
            .flat_map(|a| presets.clone().map(move |p| (a, p)))
            .flat_map(|((name, area), p)| {
                let point = matches!(area, InfluenceArea::Point(_));
                [(name, area, p, false), (name, area, p, true)]
                    .into_iter()
                    .filter(move |r| point || !r.3)
            });
        for (name, area, preset, estimate) in runs {
            let mut arena = BuildArena::with_capacity(n);
            let mut out = Bvh::with_capacity(n);
            let mut best_pah = f64::INFINITY;
            for _ in 0..reps {
                let t = thread_cpu_seconds();
                pah_once(&tris, preset, area, estimate, &mut arena, &mut out).expect("pah build");
                best_pah = best_pah.min(thread_cpu_seconds() - t);
            }
            let name = if estimate {
                format!("{name} (centre estimate)")
            } else {
                name.to_string()
            };
            let pah = AreaPah::new(area, PresetOptions::default().perspective);
            let pah_cost =
                out.estimated_cost_over(&pah, CostConstants::default(), pah.window_measure());
            println!(
                "  {preset} {name} area: {:.2} ms ({:.2}x the SAH build); pah_cost {pah_cost:.4}; \
                 tree {:016x}",
                best_pah * 1e3,
                best_pah / best,
                tree_hash(&out)
            );
        }
    }
    if let Some((file, preset)) = &own_areas {
        let mut arena = BuildArena::with_capacity(n);
        let mut out = Bvh::with_capacity(n);
        for entry in &file.entries {
            let mut best_area = f64::INFINITY;
            for _ in 0..reps {
                let t = thread_cpu_seconds();
                if let Err(e) = pah_once(&tris, *preset, &entry.area, false, &mut arena, &mut out) {
                    eprintln!("error: area {} (line {}): {e}", entry.index, entry.line);
                    return ExitCode::FAILURE;
                }
                best_area = best_area.min(thread_cpu_seconds() - t);
            }
            println!(
                "  {} area {} (line {}): {:.2} ms ({:.2}x the SAH build); nodes {}; tree {:016x}",
                preset.name(),
                entry.index,
                entry.line,
                best_area * 1e3,
                best_area / best,
                out.nodes().len(),
                tree_hash(&out)
            );
        }
    }
    if std::env::var("RDBVH_PROFILE_MT").is_ok_and(|v| v == "0") {
        return ExitCode::SUCCESS;
    }
    let one = rayon::ThreadPoolBuilder::new()
        .num_threads(1)
        .build()
        .expect("pool");
    let mt = build_mt_once(&tris);
    let same = mt == bvh;
    let wall_mt = best_wall(reps, || build_mt_once(&tris));
    let wall_1 = one.install(|| best_wall(reps, || build_mt_once(&tris)));
    let wall_serial = best_wall(reps, || build_once(&tris));
    println!(
        "  parallel::build: {} threads {:.2} ms, 1 thread {:.2} ms ({:.2}x); single-threaded \
         build {:.2} ms wall, scaling {:.2}x (as peers: 1t build / threaded); same tree as 1t: \
         {same}; load {:?}",
        rayon::current_num_threads(),
        wall_mt * 1e3,
        wall_1 * 1e3,
        wall_1 / wall_mt,
        wall_serial * 1e3,
        wall_serial / wall_mt,
        std::fs::read_to_string("/proc/loadavg")
            .unwrap_or_default()
            .trim()
    );
    if same {
        ExitCode::SUCCESS
    } else {
        ExitCode::FAILURE
    }
}
