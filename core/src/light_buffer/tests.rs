//! Light buffers against brute force: every answer the buffer gives is the answer over all
//! triangles, for point, spot, one-sided quad and many-point lights, at every subdivision.

use alloc::vec::Vec;

use glam::Vec3;

use super::{LightBuffer, LightBufferOptions, LightSource};
use crate::brute_force;
use crate::bvh::{TraversalStats, WideBvh8};
use crate::geometry::{Ray, Triangle};
use crate::random::Pcg32;
use crate::{BuildError, BuildOptions, Preset};

/// A buffer with the scene BVH its trees point into.
struct Built {
    buffer: LightBuffer,
    scene: WideBvh8,
}

impl Built {
    fn occluded(&self, ray: &Ray) -> Option<bool> {
        self.buffer.occluded(&self.scene, ray)
    }
}

/// The scene BVH of `tris` (SAH, 8-wide; empty for a scene it cannot build).
fn scene_of(tris: &[Triangle]) -> WideBvh8 {
    BuildOptions::new(Preset::Sah)
        .build(tris, None)
        .map(|bvh| WideBvh8::from_binary(&bvh, tris))
        .unwrap_or_default()
}

/// [`LightBuffer::build`] over `tris` and their scene BVH.
fn built(
    tris: &[Triangle],
    source: LightSource,
    opts: &LightBufferOptions,
) -> Result<Built, BuildError> {
    let scene = scene_of(tris);
    let buffer = LightBuffer::build(tris, &scene, source, opts)?;
    Ok(Built { buffer, scene })
}

/// The thesis's random scene recipe, `n` triangles in `[0, 10]^3`.
fn soup(n: usize, rng: &mut Pcg32) -> Vec<Triangle> {
    let mut v =
        |lo: f32, hi: f32| Vec3::new(rng.range(lo, hi), rng.range(lo, hi), rng.range(lo, hi));
    (0..n)
        .map(|_| {
            let a = v(0.0, 10.0);
            let b = a + v(-1.0, 1.0);
            let c = b + v(-1.0, 1.0);
            Triangle::new(a, b, c)
        })
        .collect()
}

fn point_in(rng: &mut Pcg32, lo: f32, hi: f32) -> Vec3 {
    Vec3::new(rng.range(lo, hi), rng.range(lo, hi), rng.range(lo, hi))
}

/// A shadow segment from `p` to the light point `s`, ending just short of it.
fn shadow(p: Vec3, s: Vec3) -> Ray {
    Ray::segment(p, s - p, 0.0, 1.0 - 1e-4).unwrap()
}

/// Checks `rays` through `buffer` against brute force, and the cell by cell query against the
/// whole one (answers and counts); returns how many it answered.
fn check(buffer: &Built, tris: &[Triangle], rays: &[Ray]) -> usize {
    let (b, scene) = (&buffer.buffer, &buffer.scene);
    let mut answered = 0;
    for (i, ray) in rays.iter().enumerate() {
        let mut whole = TraversalStats::default();
        let answer = b.occluded_with_stats(scene, ray, &mut whole);
        let cell = b.cell_of(scene, ray);
        assert!(cell.is_none_or(|c| (c as usize) < b.cells()), "ray {i}");
        let mut by_cell = TraversalStats::default();
        let via = cell.and_then(|c| b.occluded_in_cell_with_stats(c, scene, ray, &mut by_cell));
        assert_eq!((via, by_cell), (answer, whole), "ray {i}: {ray:?}");
        assert_eq!(cell.and_then(|c| b.occluded_in_cell(c, scene, ray)), answer);
        if let Some(hit) = buffer.occluded(ray) {
            assert_eq!(hit, brute_force::any_hit(ray, tris), "ray {i}: {ray:?}");
            answered += 1;
        }
    }
    answered
}

fn options(max_level: u32, leaf_triangles: u32) -> LightBufferOptions {
    LightBufferOptions {
        max_level,
        leaf_triangles,
        ..LightBufferOptions::default()
    }
}

#[test]
fn point_lights_answer_every_segment_as_brute_force_does() {
    let mut rng = Pcg32::new(1);
    let tris = soup(1500, &mut rng);
    for (light, opts) in [
        (Vec3::new(5.0, 5.0, 5.0), options(6, 8)),
        (Vec3::new(5.0, 12.0, 5.0), options(3, 32)),
        (Vec3::new(-20.0, 3.0, 40.0), options(8, 1)),
        (tris[7].v1, options(5, 4)),
    ] {
        let buffer = built(&tris, LightSource::point(light).unwrap(), &opts).unwrap();
        let rays: Vec<Ray> = (0..3000)
            .map(|_| shadow(point_in(&mut rng, -1.0, 11.0), light))
            .collect();
        assert_eq!(
            check(&buffer, &tris, &rays),
            rays.len(),
            "every segment answered"
        );
    }
}

/// Directions on the cube map's face edges and corners, and receivers on the triangles.
#[test]
fn face_edges_and_surface_receivers_agree_with_brute_force() {
    let mut rng = Pcg32::new(2);
    let tris = soup(800, &mut rng);
    let light = Vec3::new(5.0, 5.0, 5.0);
    let buffer = built(&tris, LightSource::point(light).unwrap(), &options(6, 4)).unwrap();
    let mut rays = Vec::new();
    for _ in 0..2000 {
        let a = rng.range(-6.0, 6.0);
        let b = rng.range(-6.0, 6.0);
        for d in [
            Vec3::new(a, a, b),
            Vec3::new(a, b, -a),
            Vec3::new(a, a, a),
            Vec3::new(b, -b, -b),
        ] {
            if d != Vec3::ZERO {
                rays.push(shadow(light + d, light));
            }
        }
        let t = &tris[(rng.next_u32() % tris.len() as u32) as usize];
        let (u, v) = (rng.next_f32(), rng.next_f32());
        let (u, v) = if u + v > 1.0 {
            (1.0 - u, 1.0 - v)
        } else {
            (u, v)
        };
        let p = t.v0 + (t.v1 - t.v0) * u + (t.v2 - t.v0) * v;
        rays.push(shadow(p, light));
    }
    assert_eq!(check(&buffer, &tris, &rays), rays.len());
}

#[test]
fn spot_lights_answer_inside_their_cone() {
    let mut rng = Pcg32::new(3);
    let tris = soup(1500, &mut rng);
    let light = Vec3::new(5.0, 11.0, 5.0);
    let axis = Vec3::new(0.2, -1.0, 0.1).normalize();
    let half = 0.5f32;
    let source = LightSource::spot(light, axis, half).unwrap();
    let buffer = built(&tris, source, &options(6, 8)).unwrap();
    let mut inside = 0;
    let rays: Vec<Ray> = (0..4000)
        .map(|_| {
            let p = point_in(&mut rng, -1.0, 11.0);
            if (p - light).normalize().dot(axis) >= libm::cosf(half) {
                inside += 1;
            }
            shadow(p, light)
        })
        .collect();
    let answered = check(&buffer, &tris, &rays);
    assert!(
        answered >= inside,
        "{answered} answered, {inside} inside the cone"
    );
    assert!(
        buffer.buffer.stats().dark_cells > 0,
        "the cone leaves cells dark"
    );
}

#[test]
fn one_sided_quads_and_many_point_lights_agree_with_brute_force() {
    let mut rng = Pcg32::new(4);
    let tris = soup(1500, &mut rng);
    let corner = Vec3::new(3.0, 10.5, 4.0);
    let (e1, e2) = (Vec3::new(3.0, 0.0, 0.5), Vec3::new(0.0, -0.4, 2.0));
    let normal = e1.cross(e2).normalize();
    let corners = [corner, corner + e1, corner + e1 + e2, corner + e2];
    // One-sided, and a light of 300 points (its support over their box).
    let mut many: Vec<Vec3> = (0..300)
        .map(|_| corner + e1 * rng.next_f32() + e2 * rng.next_f32())
        .collect();
    many.extend(corners);
    for source in [
        LightSource::polygon(&corners, Some(normal)).unwrap(),
        LightSource::polygon(&corners, None).unwrap(),
        LightSource::polygon(&many, Some(normal)).unwrap(),
    ] {
        let buffer = built(&tris, source, &options(5, 8)).unwrap();
        let mut front = 0;
        let rays: Vec<Ray> = (0..3000)
            .map(|_| {
                let p = point_in(&mut rng, -1.0, 11.0);
                let s = corner + e1 * rng.next_f32() + e2 * rng.next_f32();
                if normal.dot(p - corner) > 0.0 {
                    front += 1;
                }
                shadow(p, s)
            })
            .collect();
        let answered = check(&buffer, &tris, &rays);
        assert!(answered >= front, "{answered} answered, {front} in front");
        // Segments that end off the tilted quad but inside its box are answered exactly too.
        let b = buffer.buffer.source().bounds();
        let off: Vec<Ray> = (0..3000)
            .map(|_| {
                let s = b.min
                    + (b.max - b.min) * Vec3::new(rng.next_f32(), rng.next_f32(), rng.next_f32());
                shadow(point_in(&mut rng, -1.0, 11.0), s)
            })
            .collect();
        check(&buffer, &tris, &off);
    }
}

#[test]
fn segments_that_do_not_end_on_the_light_are_not_answered() {
    let mut rng = Pcg32::new(5);
    let tris = soup(100, &mut rng);
    let light = Vec3::new(5.0, 5.0, 5.0);
    let buffer = built(
        &tris,
        LightSource::point(light).unwrap(),
        &LightBufferOptions::default(),
    )
    .unwrap();
    let ray = Ray::segment(Vec3::ZERO, Vec3::new(1.0, 2.0, 3.0), 0.0, 1.0).unwrap();
    assert_eq!(buffer.occluded(&ray), None);
    let behind = built(
        &tris,
        LightSource::polygon(&[light, light + Vec3::X, light + Vec3::Z], Some(Vec3::Y)).unwrap(),
        &LightBufferOptions::default(),
    )
    .unwrap();
    let below = Vec3::new(5.2, 1.0, 5.2);
    assert_eq!(
        behind.occluded(&shadow(below, light + Vec3::new(0.2, 0.0, 0.2))),
        None
    );
}

#[test]
fn bad_sources_and_options_are_errors() {
    assert!(LightSource::point(Vec3::new(f32::NAN, 0.0, 0.0)).is_err());
    assert!(LightSource::spot(Vec3::ZERO, Vec3::ZERO, 0.5).is_err());
    assert!(LightSource::spot(Vec3::ZERO, Vec3::Y, 2.0).is_err());
    assert!(LightSource::spot(Vec3::ZERO, Vec3::Y, 0.0).is_err());
    assert!(LightSource::polygon(&[], None).is_err());
    assert!(LightSource::polygon(&[Vec3::ZERO], Some(Vec3::ZERO)).is_err());
    let tris = [Triangle::new(Vec3::ZERO, Vec3::X, Vec3::Y)];
    let source = LightSource::point(Vec3::Z).unwrap();
    assert!(built(&tris, source.clone(), &options(9, 8)).is_err());
    let bad = [Triangle::new(
        Vec3::ZERO,
        Vec3::X,
        Vec3::splat(f32::INFINITY),
    )];
    assert!(built(&bad, source.clone(), &options(4, 8)).is_err());
    // An empty scene: every segment is clear.
    let empty = built(&[], source, &options(4, 8)).unwrap();
    assert_eq!(empty.occluded(&shadow(Vec3::ONE, Vec3::Z)), Some(false));
}

/// Faces built apart and finished in any order make the same buffer; a face twice, a missing
/// face or a face of another resolution is an error.
#[test]
fn faces_built_apart_make_the_same_buffer() {
    use super::LightBufferBuilder;
    let mut rng = Pcg32::new(9);
    let tris = soup(800, &mut rng);
    let source = LightSource::point(Vec3::new(4.0, 6.0, 5.0)).unwrap();
    let opts = options(5, 8);
    let whole = built(&tris, source.clone(), &opts).unwrap();
    let build = LightBufferBuilder::new(&tris, &whole.scene, source.clone(), &opts).unwrap();
    let faces: Vec<_> = (0..LightBufferBuilder::FACES)
        .rev()
        .map(|f| build.face(f).unwrap())
        .collect();
    assert!(build.face(LightBufferBuilder::FACES).is_err());
    let mut twice = faces.clone();
    twice[0] = faces[1].clone();
    assert!(build.clone().finish(twice).is_err());
    assert!(build.clone().finish(faces[1..].to_vec()).is_err());
    let coarse = LightBufferBuilder::new(&tris, &whole.scene, source, &options(3, 8)).unwrap();
    let mut foreign = faces.clone();
    foreign[2] = coarse.face(LightBufferBuilder::FACES - 3).unwrap();
    assert!(build.clone().finish(foreign).is_err());
    let apart = Built {
        buffer: build.finish(faces).unwrap(),
        scene: whole.scene.clone(),
    };
    assert_eq!(apart.buffer.stats(), whole.buffer.stats());
    let rays: Vec<Ray> = (0..2000)
        .map(|_| shadow(point_in(&mut rng, -1.0, 11.0), Vec3::new(4.0, 6.0, 5.0)))
        .collect();
    for ray in &rays {
        assert_eq!(apart.occluded(ray), whole.occluded(ray));
    }
    assert_eq!(check(&apart, &tris, &rays), rays.len());
}

/// A scene BVH over other triangles is an error at build time, and a BVH of another size at
/// query time gets `None`, never an answer from blocks the buffer does not know.
#[test]
fn the_scene_bvh_must_be_the_scenes() {
    let mut rng = Pcg32::new(13);
    let tris = soup(300, &mut rng);
    let source = LightSource::point(Vec3::new(5.0, 8.0, 5.0)).unwrap();
    let opts = LightBufferOptions::default();
    let fewer = scene_of(&tris[..200]);
    assert!(LightBuffer::build(&tris, &fewer, source.clone(), &opts).is_err());
    let mut doubled = tris.clone();
    doubled.extend_from_slice(&tris);
    assert!(LightBuffer::build(&tris, &scene_of(&doubled), source.clone(), &opts).is_err());
    let b = built(&tris, source, &opts).unwrap();
    let ray = shadow(Vec3::new(5.0, -1.0, 5.0), Vec3::new(5.0, 8.0, 5.0));
    assert!(b.occluded(&ray).is_some());
    assert_eq!(b.buffer.occluded(&scene_of(&tris[..200]), &ray), None);
}

/// Rays leaving a point or a spot (a camera's eye, with its view as the cone): every closest hit
/// the buffer gives is brute force's and, with its edges, the scene BVH's, bit for bit; rays
/// inside the cone are all answered, rays from elsewhere none.
#[test]
fn rays_leaving_the_source_find_the_closest_hit_as_brute_force_does() {
    let mut rng = Pcg32::new(9);
    let tris = soup(1500, &mut rng);
    let key = |h: Option<crate::bvh::Hit>| h.map(|h| (h.t.to_bits(), h.triangle, h.u.to_bits()));
    let axis = Vec3::new(0.3, -0.2, 1.0).normalize();
    for (eye, cone, opts) in [
        (Vec3::new(5.0, 5.0, 5.0), None, options(6, 8)),
        (Vec3::new(5.0, 6.0, -8.0), Some(0.7f32), options(4, 64)),
        (tris[3].v2, None, options(5, 4)),
        (
            Vec3::new(5.0, 5.0, 5.0),
            Some(core::f32::consts::FRAC_PI_2),
            options(3, 16),
        ),
    ] {
        let source = match cone {
            Some(half) => LightSource::spot(eye, axis, half).unwrap(),
            None => LightSource::point(eye).unwrap(),
        };
        let b = built(&tris, source, &opts).unwrap();
        let (mut answered, mut inside, mut hits) = (0, 0, 0);
        for i in 0..4000 {
            let d = point_in(&mut rng, -1.0, 1.0);
            let t_min = if i % 3 == 0 { rng.range(0.0, 4.0) } else { 0.0 };
            let Ok(ray) = Ray::segment(eye, d, t_min, f32::INFINITY) else {
                continue;
            };
            if cone.is_none_or(|half| d.normalize().dot(axis) >= libm::cosf(half) + 1e-4) {
                inside += 1;
            }
            let mut stats = TraversalStats::default();
            let Some(found) = b
                .buffer
                .closest_hit_leaving_with_stats(&b.scene, &ray, &mut stats)
            else {
                continue;
            };
            answered += 1;
            let expected = brute_force::closest_hit(&ray, &tris);
            assert_eq!(key(found.map(|f| f.0)), key(expected), "ray {i}");
            let scene = b.scene.closest_hit_edges(&ray);
            assert_eq!(found.map(|f| f.1), scene.map(|s| s.1), "edges, ray {i}");
            assert_eq!(b.buffer.closest_hit_leaving(&b.scene, &ray), Some(found));
            hits += usize::from(found.is_some());
        }
        assert!(answered >= inside, "{answered} answered, {inside} inside");
        assert!(hits > 100, "{hits} hits");
        // Rays from elsewhere are not the buffer's.
        let off = Ray::segment(eye + Vec3::new(0.5, 0.0, 0.0), axis, 0.0, f32::INFINITY).unwrap();
        assert_eq!(b.buffer.closest_hit_leaving(&b.scene, &off), None);
        assert_eq!(b.buffer.cell_leaving(&b.scene, &off), None);
    }
}
