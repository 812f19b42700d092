//! The eye buffer: a light buffer at the camera's eye that answers the camera rays.
//!
//! Camera rays leave one point and fan out, as a point light's shadow rays converge on it, so
//! the light buffer built for a spot light at the eye, its cone the camera's view, holds per cell
//! of directions exactly the triangles those rays can hit (the item buffer of Weghorst, Hooper
//! and Greenberg 1984, made exact). A camera ray then walks one cell's small tree instead of
//! the global BVH, and finds the same closest hit bit for bit (see
//! [`LightBuffer::closest_hit_leaving`]). The pilot frame's camera rays decide, by counted tests
//! as for the lights' buffers ([`super::pilot`]): the buffer is built only if the frame's camera
//! rays could repay its build, and kept only if it needs at most [`super::KEEP_RATIO`] of the
//! global BVH's tests.

use rayon::prelude::*;
use rdbvh_core::bvh::{TraversalStats, WideBvh8};
use rdbvh_core::geometry::{Ray, Triangle};
use rdbvh_core::light_buffer::{LightBuffer, LightBufferBuilder, LightBufferOptions, LightSource};

use super::pilot::{pays, repays_build, tests};
use super::{Camera, RenderError, Structure};

/// What the pilot decided for the eye buffer.
#[derive(Clone, Copy, Debug, Default, PartialEq)]
pub struct EyeBufferReport {
    /// Whether the frame's camera rays go through an eye buffer.
    pub kept: bool,
    /// The eye buffer's tests on the pilot's camera rays over the global BVH's (0 when none
    /// was built).
    pub test_ratio: f64,
}

/// Builds the eye buffer of `camera` (the frame's) into `structure` if the pilot camera's rays
/// (`pilot`, one through each pixel's centre) show that it pays in a frame of `scale` times
/// their number of camera rays (see the module documentation).
pub(super) fn install_eye_buffer(
    triangles: &[Triangle],
    structure: &mut Structure,
    camera: &Camera,
    pilot: &Camera,
    (width, height): (u32, u32),
    scale: f64,
) -> Result<EyeBufferReport, RenderError> {
    let rays: Vec<Ray> = (0..height)
        .flat_map(|y| (0..width).map(move |x| (x, y)))
        .map(|(x, y)| pilot.ray(x as f32 + 0.5, y as f32 + 0.5))
        .collect();
    // Node + triangle tests of the pilot's camera rays, through the eye buffer or the global BVH.
    let through = |s: &Structure, eye: bool| -> u64 {
        rays.par_iter()
            .map(|ray| {
                let mut stats = TraversalStats::default();
                if eye {
                    s.closest_hit_camera_counted(ray, &mut stats);
                } else {
                    s.global().closest_hit_with_stats(ray, &mut stats);
                }
                tests(&stats)
            })
            .sum()
    };
    let global_tests = through(structure, false);
    if !repays_build(global_tests, scale, triangles.len()) {
        return Ok(EyeBufferReport::default());
    }
    structure.install_eye(Some(build_eye_buffer(
        triangles,
        structure.global(),
        camera,
    )?));
    let eye_tests = through(structure, true);
    let kept = pays(eye_tests, global_tests);
    if !kept {
        structure.install_eye(None);
    }
    Ok(EyeBufferReport {
        kept,
        test_ratio: eye_tests as f64 / global_tests as f64,
    })
}

/// The eye buffer of `camera` over `triangles` and their global BVH `global`: the buffer of a
/// spot light at the eye whose cone is the camera's view ([`Camera::view_cone`]), its faces
/// built in parallel on the current rayon pool.
pub fn build_eye_buffer(
    triangles: &[Triangle],
    global: &WideBvh8,
    camera: &Camera,
) -> Result<LightBuffer, RenderError> {
    let (axis, half_angle) = camera.view_cone();
    let source = LightSource::spot(camera.eye(), axis, half_angle)?;
    let builder =
        LightBufferBuilder::new(triangles, global, source, &LightBufferOptions::default())?;
    let faces = (0..LightBufferBuilder::FACES)
        .into_par_iter()
        .map(|face| builder.face(face))
        .collect::<Result<Vec<_>, _>>()?;
    Ok(builder.finish(faces)?)
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::render::{render_frame, FrameSettings, Integrator, Light, LightSet, StructureKind};
    use crate::scene::Scene;
    use rdbvh_core::Vec3;

    /// The room from inside, a point light under its ceiling.
    fn room() -> (Scene, LightSet, Camera) {
        let scene = Scene::open("builtin:room").unwrap();
        let light = Light::Point {
            position: Vec3::new(5.0, 9.0, 5.0),
            intensity: Vec3::splat(50.0),
        };
        let lights = LightSet::new(vec![light], &scene.triangles).unwrap();
        let (eye, at) = (Vec3::new(5.0, 5.0, 0.3), Vec3::new(5.0, 4.0, 10.0));
        let camera = Camera::new(eye, at, Vec3::Y, 75.0, 48, 32).unwrap();
        (scene, lights, camera)
    }

    #[test]
    fn camera_rays_through_the_eye_buffer_render_the_same_image() {
        let (scene, lights, camera) = room();
        let global =
            Structure::build(StructureKind::Global, &scene.triangles, lights.lights()).unwrap();
        let mut with_eye = global.clone();
        let buffer = build_eye_buffer(&scene.triangles, global.global(), &camera).unwrap();
        assert!(buffer.stats().dark_cells > 0, "the view leaves cells dark");
        with_eye.install_eye(Some(buffer));
        let settings = FrameSettings {
            width: 48,
            height: 32,
            spp: 2,
            seed: 3,
            record_limit: usize::MAX,
            progress: false,
        };
        let frame = |s: &Structure| {
            render_frame(
                &Integrator::new(&scene, &lights, s, 2).unwrap(),
                &camera,
                &settings,
            )
        };
        let (a, b) = (frame(&global), frame(&with_eye));
        let bits = |p: &[Vec3]| {
            p.iter()
                .map(|v| v.to_array().map(f32::to_bits))
                .collect::<Vec<_>>()
        };
        assert_eq!(bits(&a.pixels), bits(&b.pixels));
        assert_eq!(a.recorded.camera, b.recorded.camera);
        // Every camera ray was the eye buffer's, and it found fewer tests than the global BVH.
        let (mut via_eye, mut via_global) = (TraversalStats::default(), TraversalStats::default());
        for (ray, hit) in &a.recorded.camera {
            let eye = with_eye.eye_buffer().unwrap();
            let found = eye.closest_hit_leaving_with_stats(with_eye.global(), ray, &mut via_eye);
            assert_eq!(found.map(|f| f.map(|(h, _)| h)), Some(*hit));
            global.global().closest_hit_with_stats(ray, &mut via_global);
        }
        assert!(
            tests(&via_eye) < tests(&via_global),
            "{via_eye:?} {via_global:?}"
        );
    }

    #[test]
    fn the_pilot_builds_an_eye_buffer_only_where_the_frame_repays_it() {
        let (scene, lights, camera) = room();
        let pilot = camera.resized(6, 4);
        let decide = |scale: f64| {
            let mut s =
                Structure::build(StructureKind::Global, &scene.triangles, lights.lights()).unwrap();
            let report =
                install_eye_buffer(&scene.triangles, &mut s, &camera, &pilot, (6, 4), scale)
                    .unwrap();
            (report, s.eye_buffer().is_some())
        };
        // One sample a pixel of a 48 x 32 frame cannot repay a build over the room.
        assert_eq!(decide(64.0), (EyeBufferReport::default(), false));
        // A long frame can; whether it keeps the buffer is the pilot's count.
        let (report, installed) = decide(1e6);
        assert!(report.test_ratio > 0.0);
        assert_eq!(report.kept, installed);
        assert_eq!(
            report.kept,
            report.test_ratio <= f64::from(super::super::KEEP_RATIO)
        );
    }
}
