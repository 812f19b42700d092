//! A traversal loop to profile one library alone: `perf record -g -- target/release/examples/
//! profile_traverse SCENE LIBRARY camera|random [SECONDS]` with LIBRARY one of `rdbvh`,
//! `rdbvh-wide`, `obvhs-bvh2`, `obvhs-cwbvh`. Traces closest hit over the ray set until the time is
//! up, so the profile holds that library's traversal and little else.

use std::time::{Duration, Instant};

use rdbvh_benches::peers::{Library, ObvhsBvh2, ObvhsCwbvh, Prepared, Rdbvh, RdbvhWide};
use rdbvh_benches::{bounds, ray_set, RayKind};
use rdbvh_core::geometry::{Ray, Triangle};

fn spin<L: Library>(tris: &[Triangle], rays: &[Ray], secs: f64) {
    let prepared = Prepared::<L>::new(tris);
    let native = L::rays(rays);
    let start = Instant::now();
    let mut passes = 0u64;
    let mut hits = 0usize;
    while start.elapsed() < Duration::from_secs_f64(secs) {
        hits += prepared.closest_all(std::hint::black_box(&native));
        passes += 1;
    }
    let rate = passes as f64 * rays.len() as f64 / start.elapsed().as_secs_f64() / 1e6;
    println!(
        "{} {passes} passes, {hits} hits, {rate:.2} Mrays/s wall",
        L::NAME
    );
}

fn main() {
    let args: Vec<String> = std::env::args().skip(1).collect();
    if args.len() < 3 {
        eprintln!("error: usage: profile_traverse SCENE LIBRARY camera|random [SECONDS]");
        std::process::exit(1);
    }
    let scene = match rdbvh::scene::Scene::open(&args[0]) {
        Ok(s) if !s.triangles.is_empty() => s,
        Ok(_) => {
            eprintln!("error: {} has no triangles", args[0]);
            std::process::exit(1);
        }
        Err(e) => {
            eprintln!("error: {e}");
            std::process::exit(1);
        }
    };
    let kind = if args[2] == "random" {
        RayKind::Random
    } else {
        RayKind::Camera
    };
    let secs = args.get(3).and_then(|s| s.parse().ok()).unwrap_or(5.0);
    let tris = &scene.triangles;
    let rays = ray_set(tris, &bounds(tris), kind);
    match args[1].as_str() {
        "rdbvh" => spin::<Rdbvh>(tris, &rays, secs),
        "rdbvh-wide" => spin::<RdbvhWide>(tris, &rays, secs),
        "obvhs-bvh2" => spin::<ObvhsBvh2>(tris, &rays, secs),
        "obvhs-cwbvh" => spin::<ObvhsCwbvh>(tris, &rays, secs),
        other => {
            eprintln!("error: unknown library {other}");
            std::process::exit(1);
        }
    }
}
