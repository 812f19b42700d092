//! Build a BVH over a mesh and trace closest-hit and any-hit rays through it, binary and 4-wide,
//! checking every answer against the brute-force oracle.
//!
//! `cargo run --release -p rdbvh-core --example trace_mesh`
//!
//! The core has no file loader, so the mesh is made here: a tessellated sphere resting on a
//! rolling terrain grid, about 7,000 triangles. The example builds a binned-SAH BVH
//! ([`Builder::sah`]), checks its invariants ([`Bvh::validate`]), collapses it into a 4-wide
//! [`WideBvh`], and traces three sets of rays through both trees:
//!
//! - `camera`: a pinhole camera's primary rays (coherent, the query is the closest hit);
//! - `shadow`: from each camera hit, the segment to a point light (the query is any hit);
//! - `random`: origins anywhere in the scene's box, directions uniform on the sphere (incoherent).
//!
//! Each ray gets both queries on both trees, and each answer must equal
//! [`brute_force::closest_hit`] or [`brute_force::any_hit`], or the example exits with an error.
//! It prints, per ray set and tree, the inner nodes and triangles each query tested per ray (brute
//! force tests every triangle) and the single-thread query rate of a pass without counters.

use std::error::Error;
use std::f32::consts::{PI, TAU};
use std::time::Instant;

use rdbvh_core::brute_force;
use rdbvh_core::builder::Builder;
use rdbvh_core::bvh::{Bvh, Hit, Traversable, TraversalStats, WideBvh};
use rdbvh_core::geometry::{Ray, Triangle};
use rdbvh_core::heuristics::{CostConstants, Sah};
use rdbvh_core::random::Pcg32;
use rdbvh_core::Vec3;

/// Sphere tessellation: segments around and from pole to pole.
const SLICES: u32 = 48;
const STACKS: u32 = 24;
/// Terrain grid cells per side (two triangles per cell).
const GRID: u32 = 48;
/// Camera image size in pixels (one primary ray per pixel).
const WIDTH: u32 = 64;
const HEIGHT: u32 = 48;
/// Incoherent rays.
const RANDOM_RAYS: u32 = 2048;
/// Timed passes per query; the best counts.
const TIMED_PASSES: u32 = 5;

fn main() -> Result<(), Box<dyn Error>> {
    let mut tris = sphere(Vec3::new(0.0, 2.2, 0.0), 2.0, SLICES, STACKS);
    let sphere_count = tris.len();
    tris.extend(terrain(12.0, GRID));
    println!(
        "mesh: {} triangles (sphere {}, terrain {})",
        tris.len(),
        sphere_count,
        tris.len() - sphere_count
    );

    let start = Instant::now();
    let bvh = Builder::sah().build(&tris)?;
    let build_ms = start.elapsed().as_secs_f64() * 1e3;
    bvh.validate(tris.len(), |id| tris[id as usize].bounds())?;
    let start = Instant::now();
    let wide = WideBvh::from_binary(&bvh, &tris);
    let wide_ms = start.elapsed().as_secs_f64() * 1e3;
    println!(
        "binary BVH (sah): {} nodes, {} leaves, depth {}, SAH cost {:.1}, {} KiB, built in {:.2} ms",
        bvh.nodes().len(),
        bvh.leaf_count(),
        bvh.max_depth(),
        bvh.estimated_cost(&Sah, CostConstants::default()),
        bvh.memory_bytes() / 1024,
        build_ms
    );
    println!(
        "4-wide BVH: {} nodes, depth {}, {} KiB, collapsed in {:.2} ms",
        wide.nodes().len(),
        wide.max_depth(),
        wide.memory_bytes() / 1024,
        wide_ms
    );

    let (camera, shadow) = camera_and_shadow_rays(&tris);
    let random = random_rays(&tris, RANDOM_RAYS);
    println!(
        "\n{:<7} {:<6} {:>5} {:>5} | {:>13} {:>10} {:>9} | {:>13} {:>10} {:>9}",
        "rays",
        "tree",
        "count",
        "hit%",
        "closest nodes",
        "tris/ray",
        "Mrays/s",
        "any nodes",
        "tris/ray",
        "Mrays/s"
    );
    let mut checked = 0;
    for (name, rays) in [
        ("camera", &camera),
        ("shadow", &shadow),
        ("random", &random),
    ] {
        checked += report(name, rays, &tris, &bvh, &wide)?;
    }
    println!(
        "\nall {checked} answers equal brute force ({} triangle tests per ray)",
        tris.len()
    );
    Ok(())
}

/// Traces `rays` through both trees with both queries, checks every answer against brute force,
/// prints one line per tree, and returns how many answers it checked.
fn report(
    name: &str,
    rays: &[Ray],
    tris: &[Triangle],
    bvh: &Bvh,
    wide: &WideBvh,
) -> Result<usize, Box<dyn Error>> {
    let expect: Vec<(Option<Hit>, bool)> = rays
        .iter()
        .map(|r| {
            (
                brute_force::closest_hit(r, tris),
                brute_force::any_hit(r, tris),
            )
        })
        .collect();
    let binary = report_tree(name, "binary", bvh, rays, tris, &expect)?;
    let wide = report_tree(name, "wide", wide, rays, tris, &expect)?;
    Ok(binary + wide)
}

/// [`report`] for one tree: the binary [`Bvh`] and the [`WideBvh`] answer the same queries
/// through [`Traversable`] (the wide tree ignores `tris`: it holds its own copy).
fn report_tree(
    set: &str,
    tree: &str,
    bvh: &impl Traversable,
    rays: &[Ray],
    tris: &[Triangle],
    expect: &[(Option<Hit>, bool)],
) -> Result<usize, Box<dyn Error>> {
    let (mut closest, mut any) = (TraversalStats::default(), TraversalStats::default());
    for (i, (ray, (hit, occluded))) in rays.iter().zip(expect).enumerate() {
        let got = bvh.closest_hit_with_stats(ray, tris, &mut closest);
        if got != *hit {
            return Err(format!(
                "{set} ray {i}, {tree} tree: closest hit {got:?}, brute force {hit:?}"
            )
            .into());
        }
        let got = bvh.any_hit_with_stats(ray, tris, &mut any);
        if got != *occluded {
            return Err(format!(
                "{set} ray {i}, {tree} tree: any hit {got}, brute force {occluded}"
            )
            .into());
        }
    }
    // The plain queries carry no counters: time them (the best of a few passes, since one pass
    // takes well under a millisecond), and check their hit counts too.
    let hits = expect.iter().filter(|e| e.0.is_some()).count();
    let (closest_hits, closest_rate) = best_rate(rays, |r| bvh.closest_hit(r, tris).is_some());
    let (any_hits, any_rate) = best_rate(rays, |r| bvh.any_hit(r, tris));
    if closest_hits != hits || any_hits != hits {
        return Err(format!("{set}, {tree} tree: the uncounted queries differ").into());
    }
    let n = rays.len().max(1) as f64;
    let per_ray = |s: &TraversalStats| (f64::from(s.inner_nodes) / n, f64::from(s.triangles) / n);
    let ((cn, ct), (an, at)) = (per_ray(&closest), per_ray(&any));
    let hit_pct = 100.0 * hits as f64 / n;
    println!(
        "{set:<7} {tree:<6} {:>5} {hit_pct:>5.1} | {cn:>13.1} {ct:>10.1} {closest_rate:>9.2} | \
         {an:>13.1} {at:>10.1} {any_rate:>9.2}",
        rays.len()
    );
    Ok(2 * rays.len())
}

/// Runs `query` over `rays` in [`TIMED_PASSES`] passes: how many rays it answered `true` and the
/// best pass's rate in millions of rays per second.
fn best_rate(rays: &[Ray], query: impl Fn(&Ray) -> bool) -> (usize, f64) {
    let mut best = f64::INFINITY;
    let mut count = 0;
    for _ in 0..TIMED_PASSES {
        let start = Instant::now();
        count = rays.iter().filter(|r| query(r)).count();
        best = best.min(start.elapsed().as_secs_f64());
    }
    (count, rays.len() as f64 / best / 1e6)
}

/// A UV sphere: `slices` segments around the vertical axis, `stacks` from pole to pole, one
/// triangle per segment at the poles and two elsewhere.
fn sphere(center: Vec3, radius: f32, slices: u32, stacks: u32) -> Vec<Triangle> {
    let point = |i: u32, j: u32| {
        let (theta, phi) = (
            PI * j as f32 / stacks as f32,
            TAU * i as f32 / slices as f32,
        );
        center
            + radius
                * Vec3::new(
                    theta.sin() * phi.cos(),
                    theta.cos(),
                    theta.sin() * phi.sin(),
                )
    };
    let mut tris = Vec::new();
    for j in 0..stacks {
        for i in 0..slices {
            let (a, b) = (point(i, j), point(i + 1, j));
            let (c, d) = (point(i + 1, j + 1), point(i, j + 1));
            if j > 0 {
                tris.push(Triangle::new(a, b, c));
            }
            if j + 1 < stacks {
                tris.push(Triangle::new(a, c, d));
            }
        }
    }
    tris
}

/// A square grid of `cells` x `cells` cells over `[-half, half]` in x and z, two triangles per
/// cell, its height rolling gently around y = 0.
fn terrain(half: f32, cells: u32) -> Vec<Triangle> {
    let point = |i: u32, j: u32| {
        let x = -half + 2.0 * half * i as f32 / cells as f32;
        let z = -half + 2.0 * half * j as f32 / cells as f32;
        Vec3::new(x, 0.35 * (0.6 * x).sin() * (0.45 * z).cos(), z)
    };
    let mut tris = Vec::with_capacity(2 * (cells * cells) as usize);
    for j in 0..cells {
        for i in 0..cells {
            let (a, b, c, d) = (
                point(i, j),
                point(i + 1, j),
                point(i + 1, j + 1),
                point(i, j + 1),
            );
            tris.push(Triangle::new(a, b, c));
            tris.push(Triangle::new(a, c, d));
        }
    }
    tris
}

/// A pinhole camera's primary rays, one per pixel, and for every pixel whose ray hits (by brute
/// force, so the shadow rays do not depend on the structures under test) the segment from the
/// hit point to a point light, ending just before it.
fn camera_and_shadow_rays(tris: &[Triangle]) -> (Vec<Ray>, Vec<Ray>) {
    let eye = Vec3::new(0.0, 4.0, -13.0);
    let forward = (Vec3::new(0.0, 1.5, 0.0) - eye).normalize();
    let right = Vec3::Y.cross(forward).normalize();
    let up = forward.cross(right);
    let light = Vec3::new(7.0, 11.0, -5.0);
    let tan_half = (30f32).to_radians().tan();
    let aspect = WIDTH as f32 / HEIGHT as f32;
    let (mut camera, mut shadow) = (Vec::new(), Vec::new());
    for y in 0..HEIGHT {
        for x in 0..WIDTH {
            let u = (2.0 * (x as f32 + 0.5) / WIDTH as f32 - 1.0) * tan_half * aspect;
            let v = (1.0 - 2.0 * (y as f32 + 0.5) / HEIGHT as f32) * tan_half;
            let Ok(ray) = Ray::new(eye, forward + right * u + up * v) else {
                continue;
            };
            if let Some(hit) = brute_force::closest_hit(&ray, tris) {
                let p = ray.at(hit.t);
                // Parametric segment: t = 1 is the light; t_min keeps it off its own triangle.
                if let Ok(s) = Ray::segment(p, light - p, 1e-4, 1.0 - 1e-4) {
                    shadow.push(s);
                }
            }
            camera.push(ray);
        }
    }
    (camera, shadow)
}

/// `count` rays with origins uniform in the mesh's box and directions uniform on the sphere.
fn random_rays(tris: &[Triangle], count: u32) -> Vec<Ray> {
    let b = tris.iter().fold(rdbvh_core::geometry::Aabb::EMPTY, |b, t| {
        b.union(t.bounds())
    });
    let mut rng = Pcg32::new(29);
    (0..count)
        .filter_map(|_| {
            let origin = Vec3::new(
                rng.range(b.min.x, b.max.x),
                rng.range(b.min.y, b.max.y),
                rng.range(b.min.z, b.max.z),
            );
            let z = rng.range(-1.0, 1.0);
            let phi = rng.range(0.0, TAU);
            let s = (1.0 - z * z).max(0.0).sqrt();
            Ray::new(origin, Vec3::new(s * phi.cos(), z, s * phi.sin())).ok()
        })
        .collect()
}
