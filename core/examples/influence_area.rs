//! Influence areas with the top-level structure: local BVHs for the rays of a plane light and a
//! point light, an octree over the areas, and a fallback BVH for every other ray, all checked
//! against the brute-force oracle.
//!
//! `cargo run --release -p rdbvh-core --example influence_area`
//!
//! The scene is a room made here (a floor grid, a back wall, a sphere and scattered boxes, about
//! 4,000 triangles). Two influence areas model where next event estimation makes rays coherent:
//!
//! - a [`PlaneArea`]: the oriented box swept down from a rectangular ceiling light along its
//!   normal, holding parallel rays;
//! - a [`PointArea`]: the frustum in front of a spot light in a corner, holding radial rays.
//!
//! [`TopLevel::with_octree`] selects each area's triangles with the exact separating-axis test,
//! builds its local BVH (preset `pah`: the area's projected area heuristic), the fallback BVH
//! (preset `sah`) over every triangle, and the octree that maps a ray origin to the areas that may
//! contain it. A query takes the local BVH of an area the ray is affine to (origin inside,
//! direction within 1 degree of the area's), accepts a local hit only up to where the ray leaves
//! the area, and hands everything else to the fallback BVH.
//!
//! Four ray sets go through it: each area's own rays ([`RaySampler`]), the plane light's rays
//! tilted 10 degrees (inside the area but not affine), and random rays anywhere in the room. Every
//! closest-hit and any-hit answer of the octree scene, the naive-list scene
//! ([`TopLevel::with_list`]) and the 4-wide scene ([`TopLevel::widen`]) must equal brute force, or the
//! example exits with an error. It prints how many rays went through a local BVH, how many it
//! answered, and the mean cost per ray (`C_trav = C_isect = 1`) through the scene against the
//! fallback BVH alone; then each area's break-even rule ([`TopLevel::break_even`]).

use std::error::Error;
use std::f32::consts::{PI, TAU};
use std::time::Instant;

use rdbvh_core::brute_force;
use rdbvh_core::bvh::{Traversable, TraversalStats, WideBvh};
use rdbvh_core::geometry::{Aabb, Ray, Triangle};
use rdbvh_core::heuristics::CostConstants;
use rdbvh_core::influence::{InfluenceArea, PlaneArea, PointArea, PointDistribution, RaySampler};
use rdbvh_core::random::Pcg32;
use rdbvh_core::toplevel::{
    AreaList, TopLevel, TopLevelOptions, TopLevelStats, DEFAULT_OCTREE_LEVELS,
};
use rdbvh_core::Vec3;

/// Rays per set.
const RAYS: usize = 2000;

fn main() -> Result<(), Box<dyn Error>> {
    let tris = room();
    let plane: InfluenceArea = PlaneArea::new(
        Vec3::new(-2.0, 8.0, 1.0), // centre of the ceiling light
        Vec3::new(0.0, -1.0, 0.0), // its normal: straight down
        3.0,                       // half width
        2.0,                       // half height
        8.5,                       // depth: through the floor
    )?
    .into();
    let point: InfluenceArea = PointArea::new(
        Vec3::new(8.5, 6.0, -8.5),  // the spot light in a corner
        Vec3::new(-1.0, -0.7, 1.0), // aimed at the middle of the room
        60.0,                       // horizontal field of view, degrees
        45.0,                       // vertical field of view
        0.2,                        // near
        22.0,                       // far
    )?
    .into();
    let areas = vec![plane, point];

    let options = TopLevelOptions::default();
    let start = Instant::now();
    let octree = TopLevel::with_octree(&tris, areas.clone(), &options, DEFAULT_OCTREE_LEVELS)?;
    let build_ms = start.elapsed().as_secs_f64() * 1e3;
    let list: TopLevel<AreaList> = TopLevel::with_list(&tris, areas.clone(), &options)?;
    let wide: TopLevel<_, WideBvh> = octree.clone().widen(&tris);

    let o = octree.lookup().stats();
    println!(
        "room: {} triangles; built in {build_ms:.1} ms (local preset {}, fallback {})",
        tris.len(),
        options.local.preset,
        options.fallback.preset
    );
    println!(
        "octree: {} levels, {} nodes, {} leaves, {} area references, {} bytes",
        o.levels, o.nodes, o.leaves, o.references, o.bytes
    );
    let per_area = octree.triangles_per_area();
    println!(
        "local BVHs: plane area {} triangles, point area {} triangles; fallback {}; {} KiB in all",
        per_area[0],
        per_area[1],
        octree.fallback().prim_count(),
        octree.memory_bytes() / 1024
    );

    let sets: [(&str, Vec<Ray>); 4] = [
        (
            "plane light",
            RaySampler::new(plane, 1).take(RAYS).collect(),
        ),
        (
            "point light",
            RaySampler::new(point, 2)
                .distribution(PointDistribution::SolidAngle)
                .take(RAYS)
                .collect(),
        ),
        (
            "plane, 10 deg off",
            RaySampler::new(plane, 3)
                .jitter_deg(10.0)
                .take(RAYS)
                .collect(),
        ),
        ("random", random_rays(&tris, RAYS, 4)),
    ];
    let k = CostConstants::default();
    println!(
        "\n{:<18} {:>5} {:>8} {:>9} {:>10} {:>11} {:>13}",
        "rays", "count", "hit%", "to local", "answered", "cost/ray", "fallback only"
    );
    let mut checked = 0;
    for (name, rays) in &sets {
        let mut row = Row::default();
        for (i, ray) in rays.iter().enumerate() {
            let expect = brute_force::closest_hit(ray, &tris);
            let occluded = brute_force::any_hit(ray, &tris);
            let mut s = TopLevelStats::default();
            let got = octree.closest_hit_with_stats(ray, &tris, &mut s);
            let answers = [
                (got == expect, "octree closest hit"),
                (list.closest_hit(ray, &tris) == expect, "list closest hit"),
                (wide.closest_hit(ray, &tris) == expect, "wide closest hit"),
                (octree.any_hit(ray, &tris) == occluded, "octree any hit"),
                (list.any_hit(ray, &tris) == occluded, "list any hit"),
                (wide.any_hit(ray, &tris) == occluded, "wide any hit"),
            ];
            if let Some((_, query)) = answers.iter().find(|(ok, _)| !ok) {
                return Err(format!(
                    "{name} ray {i}: the {query} differs from brute force ({expect:?})"
                )
                .into());
            }
            checked += answers.len();
            let mut alone = TraversalStats::default();
            octree
                .fallback()
                .closest_hit_with_stats(ray, &tris, &mut alone);
            row.add(&s, expect.is_some(), s.cost(k), alone.cost(k));
        }
        row.print(name, rays.len());
    }

    println!("\nbreak-even (local pays off when its hit rate exceeds cost_local / cost_global):");
    for (a, name) in [(0, "plane"), (1, "point")] {
        let rays = sets[a].1.iter().copied();
        let Some(b) = octree.break_even(a, rays, &tris, k) else {
            return Err(format!("no area {a}").into());
        };
        println!(
            "  {name} area: hit rate {:.2}, threshold {:.2} (local {:.1}, global {:.1} per ray): {}",
            b.hit_rate,
            b.threshold(),
            b.cost_local,
            b.cost_global,
            if b.pays_off() {
                "pays off"
            } else {
                "does not pay off"
            }
        );
    }
    println!("\nall {checked} answers equal brute force");
    Ok(())
}

/// Counts for one ray set.
#[derive(Default)]
struct Row {
    hits: usize,
    /// Rays that went into a local BVH (the octree found an area they are affine to).
    to_local: usize,
    /// Rays a local BVH answered, with no fallback traversal.
    answered: usize,
    cost: f64,
    fallback_cost: f64,
}

impl Row {
    fn add(&mut self, s: &TopLevelStats, hit: bool, cost: f32, fallback_cost: f32) {
        self.hits += usize::from(hit);
        self.to_local += usize::from(s.tries > 0);
        self.answered += usize::from(s.answered_by.is_some());
        self.cost += f64::from(cost);
        self.fallback_cost += f64::from(fallback_cost);
    }

    fn print(&self, name: &str, rays: usize) {
        let n = rays.max(1) as f64;
        let pct = |x: usize| 100.0 * x as f64 / n;
        println!(
            "{name:<18} {rays:>5} {:>7.1}% {:>8.1}% {:>9.1}% {:>11.1} {:>13.1}",
            pct(self.hits),
            pct(self.to_local),
            pct(self.answered),
            self.cost / n,
            self.fallback_cost / n
        );
    }
}

/// A 20 x 20 room with a 9-unit ceiling (the ceiling itself left open): a floor grid, a back
/// wall, a sphere on the floor and boxes scattered around it.
fn room() -> Vec<Triangle> {
    let mut tris = grid(
        Vec3::new(-10.0, 0.0, -10.0),
        Vec3::new(20.0, 0.0, 0.0),
        Vec3::new(0.0, 0.0, 20.0),
        32,
    );
    tris.extend(grid(
        Vec3::new(-10.0, 0.0, 10.0),
        Vec3::new(20.0, 0.0, 0.0),
        Vec3::new(0.0, 9.0, 0.0),
        16,
    ));
    tris.extend(sphere(Vec3::new(-1.5, 1.6, 1.5), 1.6, 32, 16));
    let mut rng = Pcg32::new(7);
    for _ in 0..60 {
        let lo = Vec3::new(rng.range(-9.0, 8.0), 0.0, rng.range(-9.0, 8.0));
        let size = Vec3::new(
            rng.range(0.3, 1.5),
            rng.range(0.3, 3.0),
            rng.range(0.3, 1.5),
        );
        tris.extend(cuboid(lo, lo + size));
    }
    tris
}

/// A parallelogram from `corner` along `u` and `v`, `cells` x `cells` cells, two triangles each.
fn grid(corner: Vec3, u: Vec3, v: Vec3, cells: u32) -> Vec<Triangle> {
    let at =
        |i: u32, j: u32| corner + u * (i as f32 / cells as f32) + v * (j as f32 / cells as f32);
    let mut tris = Vec::with_capacity(2 * (cells * cells) as usize);
    for j in 0..cells {
        for i in 0..cells {
            let (a, b, c, d) = (at(i, j), at(i + 1, j), at(i + 1, j + 1), at(i, j + 1));
            tris.push(Triangle::new(a, b, c));
            tris.push(Triangle::new(a, c, d));
        }
    }
    tris
}

/// The 12 triangles of an axis-aligned box.
fn cuboid(lo: Vec3, hi: Vec3) -> Vec<Triangle> {
    let size = hi - lo;
    let (x, y, z) = (size.x * Vec3::X, size.y * Vec3::Y, size.z * Vec3::Z);
    [
        (lo, x, y),
        (lo, z, x),
        (lo, y, z),
        (hi, -y, -x),
        (hi, -x, -z),
        (hi, -z, -y),
    ]
    .into_iter()
    .flat_map(|(c, u, v)| grid(c, u, v, 1))
    .collect()
}

/// A UV sphere: `slices` segments around the vertical axis, `stacks` from pole to pole.
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

/// `count` rays with origins uniform in the room's box and directions uniform on the sphere.
fn random_rays(tris: &[Triangle], count: usize, seed: u64) -> Vec<Ray> {
    let b = tris.iter().fold(Aabb::EMPTY, |b, t| b.union(t.bounds()));
    let mut rng = Pcg32::new(seed);
    let mut rays = Vec::with_capacity(count);
    while rays.len() < count {
        let origin = Vec3::new(
            rng.range(b.min.x, b.max.x),
            rng.range(b.min.y, b.max.y),
            rng.range(b.min.z, b.max.z),
        );
        let z = rng.range(-1.0, 1.0);
        let phi = rng.range(0.0, TAU);
        let s = (1.0 - z * z).max(0.0).sqrt();
        if let Ok(ray) = Ray::new(origin, Vec3::new(s * phi.cos(), z, s * phi.sin())) {
            rays.push(ray);
        }
    }
    rays
}
