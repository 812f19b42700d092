//! Prints, per scene, ray set and library, the agreement with rdbvh and a rough single-pass speed:
//! a quick check before (or without) the criterion run.
//!
//! `cargo run --release -p rdbvh-benches --example agreement [SCENE...]` (default: bunny and
//! Crytek Sponza).

use std::time::Instant;

use rdbvh_benches::peers::{
    BvhCrate, Library, ObvhsBvh2, ObvhsCwbvh, Parry, Prepared, Rdbvh, RdbvhWide,
};
use rdbvh_benches::{agreement, bounds, load_scene, ray_set, Answers, RayKind, BENCH_SCENES};
use rdbvh_core::geometry::{Ray, Triangle};

fn report<L: Library>(tris: &[Triangle], rays: &[Ray], reference: &Answers, kind: RayKind) {
    let t0 = Instant::now();
    let prepared = Prepared::<L>::new(tris);
    let build = t0.elapsed().as_secs_f64();
    let native = L::rays(rays);
    let t1 = Instant::now();
    let hits = prepared.closest_all(&native);
    let closest = t1.elapsed().as_secs_f64();
    let t2 = Instant::now();
    let any_hits = prepared.any_all(&native);
    let any = t2.elapsed().as_secs_f64();
    let g = agreement(reference, &prepared.answers(&native));
    println!(
        "{:>7} {:<12} build {:>7.2} Mtris/s  closest {:>6.2} Mrays/s  any {:>6.2} Mrays/s  \
         hits {hits}/{any_hits}  agree closest {:.4}% any {:.4}%",
        kind.name(),
        L::NAME,
        tris.len() as f64 / build / 1e6,
        rays.len() as f64 / closest / 1e6,
        rays.len() as f64 / any / 1e6,
        100.0 * g.closest,
        100.0 * g.any,
    );
}

fn main() {
    let args: Vec<String> = std::env::args().skip(1).collect();
    let scenes: Vec<&str> = if args.is_empty() {
        BENCH_SCENES.to_vec()
    } else {
        args.iter().map(String::as_str).collect()
    };
    for name in scenes {
        let tris = match load_scene(name) {
            Ok(t) => t,
            Err(e) => {
                eprintln!("skipping {name}: {e}");
                continue;
            }
        };
        println!("{name}: {} triangles", tris.len());
        let b = bounds(&tris);
        for kind in [RayKind::Camera, RayKind::Random] {
            let rays = ray_set(&tris, &b, kind);
            let reference = Prepared::<Rdbvh>::new(&tris).answers(&rays);
            report::<Rdbvh>(&tris, &rays, &reference, kind);
            report::<RdbvhWide>(&tris, &rays, &reference, kind);
            report::<ObvhsBvh2>(&tris, &rays, &reference, kind);
            report::<ObvhsCwbvh>(&tris, &rays, &reference, kind);
            report::<BvhCrate>(&tris, &rays, &reference, kind);
            report::<Parry>(&tris, &rays, &reference, kind);
        }
    }
}
