//! The scene structure (plane and point areas, octree and list, every preset for the local BVHs)
//! against brute force, and the octree's conservativeness: a point inside an area finds that
//! area in its leaf's list.
#![no_main]

use arbitrary::{Result, Unstructured};
use libfuzzer_sys::fuzz_target;
use rdbvh_core::brute_force;
use rdbvh_core::builder::{BuildOptions, Preset};
use rdbvh_core::geometry::Ray;
use rdbvh_core::influence::{PointDistribution, RaySampler};
use rdbvh_core::toplevel::{AreaLookup, Octree, TopLevel, TopLevelOptions};
use rdbvh_core::Vec3;
use rdbvh_fuzz::*;

fuzz_target!(|data: &[u8]| {
    let _ = run(&mut Unstructured::new(data));
});

fn run(u: &mut Unstructured) -> Result<()> {
    let finite = u.int_in_range(0u8..=15)? != 0;
    let tris = scene(u, finite)?;
    let n_areas = u.int_in_range(0..=4)?;
    let mut areas = Vec::new();
    for _ in 0..n_areas {
        if let Some(a) = area(u, &tris)? {
            areas.push(a);
        }
    }
    let options = TopLevelOptions {
        local: BuildOptions::with_settings(*u.choose(&Preset::ALL)?, preset_options(u)?),
        fallback: BuildOptions::with_settings(Preset::Sah, preset_options(u)?),
        max_tries: u.int_in_range(0..=3)?,
        ..TopLevelOptions::default()
    };
    // Up to 6 levels: 10 (the clamp) can make millions of cells and slows fuzzing 100x.
    let levels = u.int_in_range(0..=6)?;

    let octree = TopLevel::with_octree(&tris, areas.clone(), &options, levels);
    let list = TopLevel::with_list(&tris, areas.clone(), &options);
    if first_non_finite(&tris).is_some() {
        assert!(
            octree.is_err() && list.is_err(),
            "non-finite triangles must be an error"
        );
        return Ok(());
    }
    let (octree, list) = match (octree, list) {
        (Ok(o), Ok(l)) => (o, l),
        (o, l) => panic!(
            "scene over finite triangles failed: {:?} / {:?}",
            o.err(),
            l.err()
        ),
    };
    assert_eq!(octree.areas().len(), areas.len());
    // The same scene over 4-wide trees must answer the same.
    let wide = octree.clone().widen(&tris);

    // Rays each area models (affine, so the local BVHs answer), with jitter, and arbitrary ones.
    let mut rays: Vec<Ray> = Vec::new();
    for (i, a) in areas.iter().enumerate() {
        let seed = u64::from(u.arbitrary::<u16>()?);
        let dist = *u.choose(&[
            PointDistribution::YawPitch,
            PointDistribution::SolidAngle,
            PointDistribution::ImagePlane,
        ])?;
        let jitter = f32::from(u.int_in_range(0u8..=5)?);
        let mut s = RaySampler::new(*a, seed + i as u64)
            .distribution(dist)
            .from_near(u.arbitrary()?)
            .jitter_deg(jitter);
        for _ in 0..4 {
            let r = s.sample();
            rays.push(r);
            // The same ray as a finite segment: a shadow ray that may end inside the area.
            let t = f32::from(u.int_in_range(1u8..=40)?) * 0.5;
            if let Ok(seg) = Ray::segment(r.origin, r.dir, 0.0, t) {
                rays.push(seg);
            }
        }
    }
    rays.extend(rays_of(u, &tris)?);

    for ray in &rays {
        if known_core_bug(ray, &tris).is_some() {
            continue;
        }
        let expect = brute_force::closest_hit(ray, &tris);
        let any = brute_force::any_hit(ray, &tris);
        // Everything needed for a regression test, printed on a disagreement.
        let case = format!("{ray:?}\ntris {tris:?}\nareas {areas:?}\n{options:?}, levels {levels}");
        assert_eq!(
            octree.closest_hit(ray, &tris),
            expect,
            "octree scene, {case}"
        );
        assert_eq!(list.closest_hit(ray, &tris), expect, "list scene, {case}");
        assert_eq!(octree.any_hit(ray, &tris), any, "octree scene any, {ray:?}");
        assert_eq!(list.any_hit(ray, &tris), any, "list scene any, {ray:?}");
        assert_eq!(wide.closest_hit(ray, &tris), expect, "wide scene, {case}");
        assert_eq!(wide.any_hit(ray, &tris), any, "wide scene any, {ray:?}");
    }

    // Octree conservativeness, on points strictly inside some area (vertex averages, sampled
    // origins pushed inside) and on the rays' origins.
    let lookup: &Octree = octree.lookup();
    let stand_alone = Octree::build(&areas, levels);
    let mut points: Vec<Vec3> = rays.iter().map(|r| r.origin).collect();
    for a in &areas {
        let v = &a.polytope().vertices;
        let c = v.iter().map(|&x| x * 0.125).sum::<Vec3>();
        points.push(c);
        for &corner in v {
            let w = f32::from(u.int_in_range(0u8..=15)?) / 16.0;
            points.push(c + (corner - c) * w);
        }
    }
    for p in points {
        for (i, a) in areas.iter().enumerate() {
            if strictly_inside(a, p) {
                let found = lookup.candidates(p);
                assert!(
                    found.contains(&(i as u32)),
                    "octree leaf at {p:?} misses area {i} that contains it: {found:?}"
                );
                assert!(stand_alone.leaf(p).1.contains(&(i as u32)));
            }
        }
    }
    Ok(())
}

fn rays_of(u: &mut Unstructured, tris: &[rdbvh_core::geometry::Triangle]) -> Result<Vec<Ray>> {
    Ok(rays(u, tris, MAX_RAYS / 2)?
        .into_iter()
        .filter_map(|r| r.ok())
        .collect())
}
