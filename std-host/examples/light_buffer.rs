//! A light buffer against the global BVH on a point light's shadow rays.
//!
//! `cargo run --release -p rdbvh --example light_buffer -- [SCENE] [HEIGHT]`
//!
//! SCENE is an OBJ path or `builtin:NAME` (default `builtin:room`); the point light sits over the
//! centre of the scene's bounds at HEIGHT (a fraction of the bounds' height, default 0.6). Shadow
//! segments run from the first hits of a pinhole camera's rays (512 x 512, in 16 x 16 tiles, as a
//! renderer shoots them) to the light. The example builds the global BVH (SAH, reinsertion, 8-wide)
//! and the light buffer (its six faces on rayon's threads), checks that every answer agrees, and
//! prints the node and triangle tests per ray and the single-thread query time of each.

use std::time::Instant;

use rayon::prelude::*;
use rdbvh::scene::Scene;
use rdbvh_core::builder::{reinsert, Builder, ReinsertConfig};
use rdbvh_core::bvh::{TraversalStats, WideBvh8};
use rdbvh_core::geometry::Ray;
use rdbvh_core::heuristics::Sah;
use rdbvh_core::light_buffer::{LightBufferBuilder, LightBufferOptions, LightSource};
use rdbvh_core::Vec3;

/// Image side and tile side of the camera that finds the receivers.
const RESOLUTION: u32 = 512;
const TILE: u32 = 16;

fn main() -> Result<(), Box<dyn std::error::Error>> {
    let args: Vec<String> = std::env::args().skip(1).collect();
    let scene = Scene::open(args.first().map_or("builtin:room", String::as_str))?;
    let height: f32 = args.get(1).map_or(Ok(0.6), |s| s.parse())?;
    let (tris, b) = (&scene.triangles, scene.bounds);
    let light = Vec3::new(
        b.center().x,
        b.min.y + height * (b.max.y - b.min.y),
        b.center().z,
    );

    let start = Instant::now();
    let mut bvh = Builder::sah().build(tris)?;
    reinsert(&mut bvh, &Sah, &ReinsertConfig::default());
    let global = WideBvh8::from_binary(&bvh, tris);
    let global_ms = start.elapsed().as_secs_f64() * 1e3;

    let start = Instant::now();
    let build = LightBufferBuilder::new(
        tris,
        &global,
        LightSource::point(light)?,
        &LightBufferOptions::default(),
    )?;
    let faces = (0..LightBufferBuilder::FACES)
        .into_par_iter()
        .map(|face| build.face(face))
        .collect::<Result<Vec<_>, _>>()?;
    let buffer = build.finish(faces)?;
    let buffer_ms = start.elapsed().as_secs_f64() * 1e3;
    let s = buffer.stats();
    println!(
        "{}: {} triangles, point light at {light}",
        scene.name,
        tris.len()
    );
    println!(
        "build: global BVH {global_ms:.1} ms (one thread), light buffer {buffer_ms:.1} ms ({} threads): \
         {} trees, {:.2} references a triangle, {:.1} MB",
        rayon::current_num_threads(),
        s.trees,
        s.references as f64 / tris.len() as f64,
        s.memory_bytes as f64 / 1e6
    );

    // Receivers: the camera's first hits, the camera a fifth of the way in along x, looking +x.
    let eye = Vec3::new(
        b.min.x + 0.15 * (b.max.x - b.min.x),
        b.min.y + 0.2 * (b.max.y - b.min.y),
        b.center().z,
    );
    let eps = 1e-4 * b.extent().max_element();
    let tiles = RESOLUTION / TILE;
    let mut rays = Vec::new();
    for tile in 0..tiles * tiles {
        for k in 0..TILE * TILE {
            let x = (tile % tiles) * TILE + k % TILE;
            let y = (tile / tiles) * TILE + k / TILE;
            let u = (x as f32 + 0.5) / RESOLUTION as f32 * 2.0 - 1.0;
            let v = 1.0 - (y as f32 + 0.5) / RESOLUTION as f32 * 2.0;
            let d = Vec3::X + Vec3::Z * (1.2 * u) + Vec3::Y * (1.2 * v);
            let camera = Ray::new(eye, d)?;
            let Some(hit) = global.closest_hit(&camera) else {
                continue;
            };
            let t = &tris[hit.triangle as usize];
            let mut n = (t.v1 - t.v0).cross(t.v2 - t.v0).normalize_or_zero();
            if n.dot(d) > 0.0 {
                n = -n;
            }
            let o = camera.at(hit.t) + n * eps;
            if n.dot(light - o) > 0.0 {
                rays.push(Ray::segment(o, light - o, 0.0, 1.0 - 1e-4)?);
            }
        }
    }
    if rays.is_empty() {
        return Err("the camera sees no surface facing the light".into());
    }

    let (mut g, mut l) = (TraversalStats::default(), TraversalStats::default());
    let mut occluded = 0;
    for ray in &rays {
        let answer = global.any_hit_with_stats(ray, &mut g);
        if buffer.occluded_with_stats(&global, ray, &mut l) != Some(answer) {
            return Err(
                format!("the light buffer disagrees with the global BVH on {ray:?}").into(),
            );
        }
        occluded += usize::from(answer);
    }
    let n = rays.len() as f64;
    println!(
        "{} shadow rays, {:.1} % occluded; per ray: global {:.2} nodes + {:.2} triangles, \
         light buffer {:.2} + {:.2}",
        rays.len(),
        100.0 * occluded as f64 / n,
        g.inner_nodes as f64 / n,
        g.triangles as f64 / n,
        l.inner_nodes as f64 / n,
        l.triangles as f64 / n
    );
    let best = |f: &dyn Fn() -> usize| {
        (0..5)
            .map(|_| {
                let start = Instant::now();
                std::hint::black_box(f());
                start.elapsed().as_secs_f64()
            })
            .fold(f64::INFINITY, f64::min)
    };
    let tg = best(&|| rays.iter().filter(|r| global.any_hit(r)).count());
    let tl = best(&|| {
        rays.iter()
            .filter(|r| buffer.occluded(&global, r) == Some(true))
            .count()
    });
    println!(
        "query, one thread, best of 5: global {:.1} ns a ray, light buffer {:.1} ns ({:.2}x)",
        tg / n * 1e9,
        tl / n * 1e9,
        tl / tg
    );
    Ok(())
}
