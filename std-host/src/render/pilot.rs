//! The pilot frame: a low-resolution pass of the same camera whose shadow segments decide which
//! light buffers the `lights` structure keeps.
//!
//! A light buffer pays where shadow rays converge on a small light in a large scene, and costs
//! more than it saves where the light is large next to the scene or spread over it (every cell
//! then holds most of the triangles). Which case a light is in shows in its own shadow rays, so
//! the structure asks them: it traces the pilot's segments toward each buffered light through
//! the buffer and through the global BVH, counting node and triangle tests, and keeps the buffer
//! only if it needs at most [`KEEP_RATIO`] of the global BVH's tests. Counts, not clocks, decide,
//! so the choice is the same on every run; the answers are the global BVH's either way, so the
//! image does not change.
//!
//! [`build_lights`] traces the pilot through the global BVH before building any buffer, and
//! builds none for a light too wide next to its pilot segments ([`MAX_EXTENT_RATIO`]): such a
//! buffer never paid, and costs the most to build; nor for a light whose share of the frame's
//! shadow tests could not repay its buffer's build ([`BUILD_TESTS_PER_TRIANGLE`]).
//! [`prune_by_pilot`] decides for a structure whose buffers are all built already.

use std::time::Instant;

use rdbvh_core::bvh::TraversalStats;

use super::eye_buffer::{install_eye_buffer, EyeBufferReport};
use super::light_structure::{build_buffers, light_groups};
use super::{
    render_frame, Camera, FrameSettings, Integrator, LightSet, RenderError, Structure,
    StructureKind,
};
use crate::scene::Scene;

/// The pilot's resolution divides the frame's by this (at least one pixel a side).
pub const PILOT_DIVISOR: u32 = 8;

/// A buffer is kept when its pilot tests are at most this share of the global BVH's. Below 1
/// because a test in a buffer's cell tree costs more than one in the global tree (its lookup,
/// and a forest of trees that the cache holds less of): measured buffers that saved 24 % of the
/// tests were still 4 % slower.
pub const KEEP_RATIO: f32 = 0.7;

/// What the pilot decided.
#[derive(Clone, Copy, Debug, Default, PartialEq)]
pub struct PilotReport {
    /// Shadow segments the pilot traced.
    pub shadow_rays: usize,
    /// Light buffers kept.
    pub kept: usize,
    /// Light buffers dropped (their lights use the global BVH), built or not.
    pub dropped: usize,
    /// Of those dropped, the ones decided before building ([`build_lights`]).
    pub skipped: usize,
    /// Wall-clock milliseconds of the pilot frame (its render, through the global BVH).
    pub ms: f64,
    /// The eye buffer's decision ([`super::eye_buffer`]).
    pub eye: EyeBufferReport,
}

/// Renders the pilot frame of `camera` (made at the pilot's resolution, `width` x `height`)
/// through `integrator`, whose structure is `structure` not yet pruned; returns per buffer
/// whether it pays, and the shadow segments that decided.
fn decide(
    integrator: &Integrator,
    structure: &Structure,
    camera: &Camera,
    (width, height): (u32, u32),
    seed: u64,
) -> (Vec<bool>, usize) {
    let settings = FrameSettings {
        width,
        height,
        spp: 1,
        seed,
        record_limit: 0,
        progress: false,
    };
    let pilot = render_frame(integrator, camera, &settings);
    let n = structure.light_buffers().len();
    let (mut through_buffer, mut through_global) = (vec![0u64; n], vec![0u64; n]);
    for s in &pilot.shadow_rays {
        let Some(b) = structure.buffer_of(s.light as usize) else {
            continue;
        };
        let mut via_buffer = TraversalStats::default();
        let mut via_global = TraversalStats::default();
        structure.occluded_counted(s.light as usize, &s.ray, &mut via_buffer);
        structure
            .global()
            .any_hit_with_stats(&s.ray, &mut via_global);
        through_buffer[b] += tests(&via_buffer);
        through_global[b] += tests(&via_global);
    }
    let keep = (0..n).map(|b| pays(through_buffer[b], through_global[b]));
    (keep.collect(), pilot.shadow_rays.len())
}

/// The `lights` structure built with the pilot frame deciding first: the global BVH, the pilot
/// frame (the frame's `camera` made at [`pilot_size`], `size`, by [`Camera::resized`]) traced
/// through it, then a buffer built only for the light groups whose pilot segments leave it a
/// chance to pay ([`MAX_EXTENT_RATIO`]) in a frame of `frame_samples` samples
/// ([`BUILD_TESTS_PER_TRIANGLE`]), and of those kept only the ones that need at most
/// [`KEEP_RATIO`] of the global BVH's tests on the same segments. The pilot's segments do not
/// depend on the structure (every structure answers alike), so one pilot serves both decisions.
/// Last, the eye buffer for the camera rays, decided by the pilot camera's rays in the same way
/// ([`super::eye_buffer`]).
pub fn build_lights(
    scene: &Scene,
    lights: &LightSet,
    max_bounces: u32,
    camera: &Camera,
    size: (u32, u32),
    seed: u64,
    frame_samples: u64,
) -> Result<(Structure, PilotReport), RenderError> {
    let start = Instant::now();
    let triangles = &scene.triangles;
    let mut structure = Structure::build(StructureKind::Global, triangles, lights.lights())?;
    let groups = light_groups(triangles, lights.lights());
    let mut group_of = vec![u32::MAX; lights.lights().len()];
    for (g, group) in groups.iter().enumerate() {
        for &l in &group.lights {
            group_of[l as usize] = g as u32;
        }
    }
    let settings = FrameSettings {
        width: size.0,
        height: size.1,
        spp: 1,
        seed,
        record_limit: 0,
        progress: false,
    };
    let pilot_camera = camera.resized(size.0, size.1);
    let pilot_start = Instant::now();
    let pilot = render_frame(
        &Integrator::new(scene, lights, &structure, max_bounces)?,
        &pilot_camera,
        &settings,
    );
    let pilot_ms = pilot_start.elapsed().as_secs_f64() * 1e3;
    // Per group: its pilot segments, their tests through the global BVH, and their lengths.
    let mut segments: Vec<Vec<usize>> = vec![Vec::new(); groups.len()];
    let mut global_tests = vec![0u64; groups.len()];
    for (i, s) in pilot.shadow_rays.iter().enumerate() {
        let g = group_of[s.light as usize];
        if g == u32::MAX {
            continue;
        }
        let mut stats = TraversalStats::default();
        structure.global().any_hit_with_stats(&s.ray, &mut stats);
        global_tests[g as usize] += tests(&stats);
        segments[g as usize].push(i);
    }
    // The frame traces this many times the pilot's samples (the pilot's are one a pixel).
    let scale = frame_samples as f64 / (f64::from(size.0) * f64::from(size.1));
    let chosen: Vec<usize> = (0..groups.len())
        .filter(|&g| {
            let lengths = segments[g].iter().map(|&i| {
                let r = &pilot.shadow_rays[i].ray;
                r.dir.length() * (r.t_max - r.t_min)
            });
            worth_building(groups[g].extent(), lengths.collect())
                && repays_build(global_tests[g], scale, triangles.len())
        })
        .collect();
    let chosen_groups: Vec<_> = chosen.iter().map(|&g| &groups[g]).collect();
    let (buffers, buffer_of) = build_buffers(
        triangles,
        structure.global(),
        &chosen_groups,
        lights.lights().len(),
    )?;
    structure.install_buffers(buffers, buffer_of);
    let keep: Vec<bool> = chosen
        .iter()
        .map(|&g| {
            let through_buffer: u64 = segments[g]
                .iter()
                .map(|&i| {
                    let s = &pilot.shadow_rays[i];
                    let mut stats = TraversalStats::default();
                    structure.occluded_counted(s.light as usize, &s.ray, &mut stats);
                    tests(&stats)
                })
                .sum();
            pays(through_buffer, global_tests[g])
        })
        .collect();
    structure.keep_buffers(&keep);
    let eye = install_eye_buffer(
        triangles,
        &mut structure,
        camera,
        &pilot_camera,
        size,
        scale,
    )?;
    let ms = start.elapsed().as_secs_f64() * 1e3;
    structure.set_build_ms(ms);
    let kept = structure.light_buffers().len();
    Ok((
        structure,
        PilotReport {
            shadow_rays: pilot.shadow_rays.len(),
            kept,
            dropped: groups.len() - kept,
            skipped: groups.len() - chosen.len(),
            ms: pilot_ms,
            eye,
        },
    ))
}

/// Node plus triangle tests.
pub(super) fn tests(s: &TraversalStats) -> u64 {
    u64::from(s.inner_nodes) + u64::from(s.triangles)
}

/// Whether `through_buffer` tests pay against `through_global` on the same segments. A buffer
/// no pilot segment used has shown no saving: its light is rarely chosen, or unseen.
pub(super) fn pays(through_buffer: u64, through_global: u64) -> bool {
    through_global > 0 && through_buffer as f64 <= f64::from(KEEP_RATIO) * through_global as f64
}

/// A light group is worth a buffer only when its width is at most this share of its pilot
/// segments' median length. A cell's segments sweep the light's whole width, so where the light
/// is wide next to the distances its shadow rays cross, every cell reaches most of what the
/// global BVH holds. Measured (512 x 512 frames, default cameras of
/// `scripts/render-comparison.sh`), width over median length against the buffer's share of the
/// global BVH's pilot tests: point and spot lights 0 (0.41-0.65, kept), the room's quad 0.39
/// (0.64, kept), the Cornell box's 0.42 (0.75, dropped by [`KEEP_RATIO`] after its build, which
/// takes 0.1 ms), Sibenik's window clusters 0.54 and 1.49 (0.91 and 0.98), a quad over the
/// bunny 1.69 (1.04): above 0.5 no buffer came near paying, and those cost the most to build.
pub const MAX_EXTENT_RATIO: f32 = 0.5;

/// Whether a light group of width `extent`, whose pilot segments have `lengths`, is worth
/// building a buffer for: it has pilot segments (a light the pilot never chose is rare or
/// unseen) and passes [`MAX_EXTENT_RATIO`].
fn worth_building(extent: f32, mut lengths: Vec<f32>) -> bool {
    if lengths.is_empty() {
        return false;
    }
    let mid = lengths.len() / 2;
    let (_, median, _) = lengths.select_nth_unstable_by(mid, f32::total_cmp);
    extent <= MAX_EXTENT_RATIO * *median
}

/// A light buffer's build takes about as long as this many of the frame's shadow-ray tests per
/// scene triangle (both on the same threads). Measured at 512 x 512, 16 samples, on an AMD EPYC
/// (2 cores) on 2026-12-07, against the global BVH's 22.5 ns a test in the single-thread replay
/// (11 ns on two threads): Sponza's point light 28, its quad light 51, Sibenik's point light 20,
/// 40 point lights over Sponza (buffers for the 32 most powerful) 26 each.
pub const BUILD_TESTS_PER_TRIANGLE: f64 = 25.0;

/// The share of its light's global BVH tests a kept buffer saves, about: 0.36-0.55 in the
/// rendering table of `docs/results.md`.
pub const EXPECTED_SAVING: f64 = 0.5;

/// Whether a light group's buffer would save the frame more than its build costs: the group's
/// pilot segments took `global_tests` tests through the global BVH, the frame traces `scale`
/// times the pilot's samples, and the scene has `triangles` triangles. Counts, not clocks, so
/// that the choice is the same on every run. A light that few of the frame's paths sample (one
/// of many lights, or a small frame) gets no buffer: with 40 point lights over Sponza at
/// 512 x 512, 16 samples, 32 buffers took 2.8 s to build (29 kept) for a frame of 9.8 s.
pub(super) fn repays_build(global_tests: u64, scale: f64, triangles: usize) -> bool {
    global_tests as f64 * scale * EXPECTED_SAVING >= BUILD_TESTS_PER_TRIANGLE * triangles as f64
}

/// The pilot's resolution for a frame of `width` x `height`.
pub fn pilot_size(width: u32, height: u32) -> (u32, u32) {
    (
        (width / PILOT_DIVISOR).max(1),
        (height / PILOT_DIVISOR).max(1),
    )
}

/// Runs the pilot for `structure` over `scene` and `lights` and drops the buffers that do not
/// pay; the pilot's time joins the structure's build time. `camera` is the frame's camera made
/// at [`pilot_size`], `size`.
pub fn prune_by_pilot(
    structure: &mut Structure,
    scene: &Scene,
    lights: &LightSet,
    max_bounces: u32,
    camera: &Camera,
    size: (u32, u32),
    seed: u64,
) -> Result<PilotReport, RenderError> {
    let start = Instant::now();
    let before = structure.light_buffers().len();
    if before == 0 {
        return Ok(PilotReport::default());
    }
    let (keep, shadow_rays) = decide(
        &Integrator::new(scene, lights, structure, max_bounces)?,
        structure,
        camera,
        size,
        seed,
    );
    structure.keep_buffers(&keep);
    let ms = start.elapsed().as_secs_f64() * 1e3;
    structure.add_build_ms(ms);
    let kept = structure.light_buffers().len();
    Ok(PilotReport {
        shadow_rays,
        kept,
        dropped: before - kept,
        skipped: 0,
        ms,
        eye: EyeBufferReport::default(),
    })
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::render::Light;
    use rdbvh_core::geometry::Ray;
    use rdbvh_core::Vec3;

    fn point(position: Vec3) -> Light {
        Light::Point {
            position,
            intensity: Vec3::splat(50.0),
        }
    }

    /// The room seen from inside, with the pilot of a 64 x 64 frame.
    fn pilot(lights: Vec<Light>) -> (Structure, PilotReport) {
        let scene = Scene::open("builtin:room").unwrap();
        let lights = LightSet::new(lights, &scene.triangles).unwrap();
        let mut structure =
            Structure::build(StructureKind::Lights, &scene.triangles, lights.lights()).unwrap();
        let size = pilot_size(64, 64);
        let (eye, at) = (Vec3::new(5.0, 5.0, 0.3), Vec3::new(5.0, 4.0, 10.0));
        let camera = Camera::new(eye, at, Vec3::Y, 75.0, size.0, size.1).unwrap();
        let report = prune_by_pilot(&mut structure, &scene, &lights, 1, &camera, size, 7).unwrap();
        (structure, report)
    }

    #[test]
    fn wide_lights_next_to_short_segments_get_no_buffer() {
        assert!(!worth_building(0.0, Vec::new()), "no pilot segment");
        assert!(worth_building(0.0, vec![3.0, 1.0, 2.0]), "a point light");
        assert!(
            worth_building(1.0, vec![3.0, 1.0, 2.0]),
            "width 1, median 2"
        );
        assert!(
            !worth_building(1.5, vec![3.0, 1.0, 2.0]),
            "width 1.5, median 2"
        );
    }

    #[test]
    fn a_buffer_is_built_only_where_the_frame_repays_it() {
        // 1,000 triangles cost 25,000 tests; half of 500 tests, scaled.
        assert!(!repays_build(500, 99.0, 1000));
        assert!(repays_build(500, 100.0, 1000));
        assert!(!repays_build(0, 1e9, 1));
        // The room with a point light under its ceiling: a 64 x 64 frame of one sample cannot
        // repay the buffer's build, the same frame at 256 samples can.
        let scene = Scene::open("builtin:room").unwrap();
        let lights =
            LightSet::new(vec![point(Vec3::new(5.0, 9.0, 5.0))], &scene.triangles).unwrap();
        let size = pilot_size(64, 64);
        let (eye, at) = (Vec3::new(5.0, 5.0, 0.3), Vec3::new(5.0, 4.0, 10.0));
        let camera = Camera::new(eye, at, Vec3::Y, 75.0, 64, 64).unwrap();
        let build = |spp: u64| {
            build_lights(&scene, &lights, 1, &camera, size, 7, 64 * 64 * spp)
                .unwrap()
                .1
        };
        let small = build(1);
        assert_eq!((small.kept, small.skipped), (0, 1), "{small:?}");
        let large = build(256);
        assert_eq!((large.kept, large.skipped), (1, 0), "{large:?}");
    }

    #[test]
    fn a_buffer_that_saves_tests_is_kept() {
        // A point light under the room's ceiling: its shadow rays converge, the buffer pays.
        let (structure, report) = pilot(vec![point(Vec3::new(5.0, 9.0, 5.0))]);
        assert!(report.shadow_rays > 0);
        assert_eq!((report.kept, report.dropped), (1, 0), "{report:?}");
        assert_eq!(structure.buffer_of(0), Some(0));
    }

    #[test]
    fn dropping_a_buffer_sends_its_light_to_the_global_bvh() {
        // Two lights, two buffers; the first dropped by hand, the second renumbered.
        let scene = Scene::open("builtin:room").unwrap();
        let lights = [
            point(Vec3::new(2.0, 9.0, 2.0)),
            point(Vec3::new(8.0, 9.0, 8.0)),
        ];
        let mut structure =
            Structure::build(StructureKind::Lights, &scene.triangles, &lights).unwrap();
        assert_eq!(structure.light_buffers().len(), 2);
        let second = structure.buffer_of(1).unwrap();
        let keep: Vec<bool> = (0..2).map(|b| b == second).collect();
        structure.keep_buffers(&keep);
        assert_eq!(structure.light_buffers().len(), 1);
        assert_eq!(structure.buffer_of(0), None);
        assert_eq!(structure.buffer_of(1), Some(0));
        // Answers stay the global BVH's for both lights.
        for (l, light) in lights.iter().enumerate() {
            let Light::Point { position, .. } = light else {
                unreachable!()
            };
            for i in 0..200 {
                let origin = Vec3::new(
                    0.5 + (i % 19) as f32 * 0.5,
                    0.2,
                    0.5 + (i / 19) as f32 * 0.8,
                );
                let ray = Ray::segment(origin, *position - origin, 0.0, 0.999).unwrap();
                assert_eq!(
                    structure.occluded(l, &ray),
                    structure.global().any_hit(&ray)
                );
            }
        }
    }
}
