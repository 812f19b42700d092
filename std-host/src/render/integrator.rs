//! Path tracing with next event estimation over Lambertian surfaces.
//!
//! At every vertex: one light chosen by power, one point on it, one shadow segment; then a
//! cosine-weighted bounce, with Russian roulette from the third vertex on. Emission is added where
//! a camera ray lands on an emissive triangle; a bounce ray that lands on one adds nothing,
//! because next event estimation already counted that light (no double counting, no MIS).

use std::f32::consts::{FRAC_1_PI, TAU};

use rdbvh_core::bvh::{Hit, TraversalStats};
use rdbvh_core::geometry::{Ray, Triangle};
use rdbvh_core::{prefetch, Vec3};

use super::direction::unit;
use super::sampler::{vertex_dim, Sampler};
use super::shadow_batch::{PathBatch, ShadowTests};
use super::{LightSet, RenderError, Structure};
use crate::scene::{Scene, DEFAULT_DIFFUSE};

/// Where a shadow segment ends: `origin + (1 - SHADOW_END) * (target - origin)`. The light's own
/// surface (an emissive triangle) is then never its occluder, while anything in front of it is:
/// the gap is a 10^-4 part of the segment.
pub const SHADOW_END: f32 = 1e-4;

/// Ray origins leave a surface along its normal by this fraction of the scene's largest
/// coordinate, which is where f32 rounding puts a hit point off its triangle.
pub const OFFSET_SCALE: f32 = 1e-4;

/// The first vertex (counting the camera ray's hit as 0) where Russian roulette may end a path.
pub const ROULETTE_DEPTH: u32 = 2;

/// A shadow segment the renderer traced, with its light and its answer.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct ShadowRay {
    /// The index of its light in the renderer's light set.
    pub light: u32,
    /// The segment.
    pub ray: Ray,
    /// Whether something blocked it.
    pub occluded: bool,
}

/// What one path tells the frame besides its radiance: its rays, for the counters and records.
pub trait PathObserver {
    /// A camera (`depth == 0`) or bounce ray and its closest hit.
    fn closest(&mut self, depth: u32, ray: &Ray, hit: Option<&Hit>);
    /// A shadow segment and its answer, in path order.
    fn shadow(&mut self, shadow: &ShadowRay);
    /// Shadow segments, in path order: [`PathObserver::shadow`] for each.
    fn shadows(&mut self, shadows: &[ShadowRay]) {
        for s in shadows {
            self.shadow(s);
        }
    }
    /// The node and triangle tests shadow segments cost: one segment's where it was answered
    /// alone, a batch's sum where its segments were answered together.
    fn shadow_tests(&mut self, tests: &ShadowTests);
}

/// Everything a path needs, shared by every thread.
pub struct Integrator<'a> {
    triangles: &'a [Triangle],
    /// Per triangle, its material's index in `shading` (the scene's own indices, which a
    /// quarter of the memory of per-triangle colours keeps in the caches).
    material: &'a [u32],
    /// Per material, its diffuse colour and emission; the last entry is for a triangle whose
    /// index names no material.
    shading: Vec<Shading>,
    lights: &'a LightSet,
    structure: &'a Structure,
    max_bounces: u32,
    offset: f32,
    /// Whether the structure answers shadow segments fastest in batches.
    batched: bool,
}

impl<'a> Integrator<'a> {
    /// The integrator for `scene` lit by `lights`, tracing through `structure`. Fails on a
    /// material colour that is negative or not finite.
    pub fn new(
        scene: &'a Scene,
        lights: &'a LightSet,
        structure: &'a Structure,
        max_bounces: u32,
    ) -> Result<Self, RenderError> {
        for m in &scene.materials {
            for (field, c) in [("Kd", m.diffuse), ("Ke", m.emission)] {
                if c.iter().any(|x| !x.is_finite() || *x < 0.0) {
                    return Err(RenderError::Material {
                        name: m.name.clone(),
                        reason: format!(
                            "`{field}` must be finite and non-negative, got {} {} {}",
                            c[0], c[1], c[2]
                        ),
                    });
                }
            }
        }
        let shading = scene
            .materials
            .iter()
            .map(|m| Shading {
                albedo: Vec3::from(m.diffuse),
                emission: Vec3::from(m.emission),
            })
            .chain([Shading {
                albedo: Vec3::from(DEFAULT_DIFFUSE),
                emission: Vec3::ZERO,
            }])
            .collect();
        let b = scene.bounds;
        let scale = b.min.abs().max(b.max.abs()).max_element();
        Ok(Self {
            triangles: &scene.triangles,
            material: &scene.material,
            shading,
            lights,
            structure,
            max_bounces,
            offset: (OFFSET_SCALE * scale).max(f32::MIN_POSITIVE),
            batched: structure.answers_in_batches(),
        })
    }

    /// The radiance a path started by `camera_ray` carries back, drawing its numbers from
    /// `sampler`; its rays go to `observer`, each shadow segment answered where it is made.
    pub fn radiance(
        &self,
        camera_ray: Ray,
        sampler: &Sampler,
        observer: &mut impl PathObserver,
    ) -> Vec3 {
        let mut now = AnswerNow {
            radiance: Vec3::ZERO,
        };
        self.path(camera_ray, sampler, observer, &mut now);
        now.radiance
    }

    /// Whether a frame should trace its paths with [`Integrator::trace`] into batches and
    /// answer them with [`Integrator::answer`] (the structure answers shadow segments fastest
    /// so) rather than with [`Integrator::radiance`].
    pub fn batched(&self) -> bool {
        self.batched
    }

    /// Answers the shadow segments of `batch` through the structure.
    pub fn answer(&self, batch: &mut PathBatch) {
        batch.answer(self.structure);
    }

    /// Traces the path started by `camera_ray` into `batch`, drawing its numbers from
    /// `sampler`: its camera and bounce rays now (they go to `observer`); its shadow segments,
    /// and what each vertex adds to the radiance, kept for [`Integrator::answer`] and
    /// [`PathBatch::radiance`], which give the radiance [`Integrator::radiance`] gives, bit for
    /// bit. The path's course does not depend on its shadow segments' answers, only its
    /// radiance does.
    pub fn trace(
        &self,
        camera_ray: Ray,
        sampler: &Sampler,
        observer: &mut impl PathObserver,
        batch: &mut PathBatch,
    ) {
        self.path(camera_ray, sampler, observer, batch);
        batch.end_path();
    }

    /// The path proper: its shadow segments and radiance terms go to `sink`, in order.
    #[inline(always)]
    fn path(
        &self,
        camera_ray: Ray,
        sampler: &Sampler,
        observer: &mut impl PathObserver,
        sink: &mut impl PathSink,
    ) {
        let mut throughput = Vec3::ONE;
        let mut ray = camera_ray;
        for depth in 0..=self.max_bounces {
            let found = if depth == 0 {
                self.structure.closest_hit_camera(&ray)
            } else {
                self.structure.closest_hit(&ray)
            };
            observer.closest(depth, &ray, found.as_ref().map(|(hit, _)| hit));
            let Some((hit, t)) = found else { break };
            let id = hit.triangle as usize;
            // The material's index is read after the light sample: fetched now, it arrives
            // meanwhile, where read here it was the costliest load of the shading.
            prefetch(&self.material[id]);
            // The hit point from the barycentrics: on the triangle up to rounding, wherever the
            // ray started. The edges are the leaf block's, bit for bit `v1 - v0` and `v2 - v0`
            // of the scene's triangle, which is not read: the block is in the caches, the
            // triangle array's entry usually is not.
            let p = t.v0 + t.e1 * hit.u + t.e2 * hit.v;
            // `unit`: a triangle of edges past about 4e9 or below 3e-10 units still has a normal.
            let mut n = unit(t.e1.cross(t.e2));
            if n == Vec3::ZERO {
                break;
            }
            // Both faces are surfaces: shade the one the ray arrived at.
            if n.dot(ray.dir) > 0.0 {
                n = -n;
            }
            let origin = p + n * self.offset;
            let dim = vertex_dim(depth);

            let (light, probability) = self.lights.choose(sampler.get(dim));
            let sample = self.lights.lights()[light].sample(
                self.triangles,
                origin,
                sampler.get(dim + 1),
                sampler.get(dim + 2),
            );
            // The light sample's segment, weight and geometric factor.
            let mut lit = None;
            if let Some(s) = sample {
                let d = s.target - origin;
                let cos = n.dot(d);
                if cos > 0.0 {
                    if let Ok(segment) = Ray::segment(origin, d, 0.0, 1.0 - SHADOW_END) {
                        let gate = sink.segment(light, segment, self.structure, observer);
                        lit = Some((gate, s.weight, FRAC_1_PI * cos / (d.length() * probability)));
                    }
                }
            }
            let shading = &self.shading[(self.material[id] as usize).min(self.shading.len() - 1)];
            if depth == 0 {
                sink.term(throughput * shading.emission, Gate::Open);
            }
            let albedo = shading.albedo;
            if let Some((gate, weight, geometry)) = lit {
                sink.term(throughput * albedo * weight * geometry, gate);
            }

            if depth == self.max_bounces {
                break;
            }
            // Lambertian with cosine-weighted directions: f cos / pdf = albedo.
            throughput *= albedo;
            if depth >= ROULETTE_DEPTH {
                let survive = throughput.max_element().min(0.95);
                if sampler.get(dim + 5) >= survive {
                    break;
                }
                throughput /= survive;
            }
            let dir = cosine_direction(n, sampler.get(dim + 3), sampler.get(dim + 4));
            match Ray::new(origin, dir) {
                Ok(r) => ray = r,
                Err(_) => break,
            }
        }
    }
}

/// A material as the integrator shades it.
#[derive(Clone, Copy, Debug)]
struct Shading {
    albedo: Vec3,
    emission: Vec3,
}

/// What must hold for a vertex's radiance term to count.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Gate {
    /// Nothing: it always counts (a camera ray's emission).
    Open,
    /// A shadow segment answered already: it counts where the segment is clear.
    Answered {
        /// Whether the segment is blocked.
        occluded: bool,
    },
    /// A shadow segment of a batch, by its index, answered later.
    Pending(u32),
}

/// Where a path's shadow segments and radiance terms go: answered and summed now
/// ([`Integrator::radiance`]), or kept in a batch ([`PathBatch`]).
pub trait PathSink {
    /// A shadow segment toward `light`, which `structure` answers now (telling `observer`) or
    /// later; the gate of the term it decides.
    fn segment(
        &mut self,
        light: usize,
        ray: Ray,
        structure: &Structure,
        observer: &mut impl PathObserver,
    ) -> Gate;
    /// A radiance term, added in order, where `gate` lets it.
    fn term(&mut self, value: Vec3, gate: Gate);
}

/// Each segment answered where it is made, the radiance summed as the path goes.
struct AnswerNow {
    radiance: Vec3,
}

impl PathSink for AnswerNow {
    #[inline(always)]
    fn segment(
        &mut self,
        light: usize,
        ray: Ray,
        structure: &Structure,
        observer: &mut impl PathObserver,
    ) -> Gate {
        let mut stats = TraversalStats::default();
        let occluded = structure.occluded_counted(light, &ray, &mut stats);
        observer.shadow(&ShadowRay {
            light: light as u32,
            ray,
            occluded,
        });
        observer.shadow_tests(&ShadowTests::of(&stats));
        Gate::Answered { occluded }
    }

    #[inline(always)]
    fn term(&mut self, value: Vec3, gate: Gate) {
        if !matches!(gate, Gate::Answered { occluded: true }) {
            self.radiance += value;
        }
    }
}

/// A direction about the unit normal `n` with density `cos / pi` (Malley's method on an
/// orthonormal basis from Duff et al. 2017).
#[inline]
fn cosine_direction(n: Vec3, u: f32, v: f32) -> Vec3 {
    let sign = 1.0f32.copysign(n.z);
    let a = -1.0 / (sign + n.z);
    let b = n.x * n.y * a;
    let tangent = Vec3::new(1.0 + sign * n.x * n.x * a, sign * b, -sign * n.x);
    let bitangent = Vec3::new(b, sign + n.y * n.y * a, -n.y);
    let r = u.sqrt();
    let phi = TAU * v;
    let (x, y) = (r * phi.cos(), r * phi.sin());
    let z = (1.0 - u).max(0.0).sqrt();
    tangent * x + bitangent * y + n * z
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::render::{Light, StructureKind};
    use crate::scene::Material;
    use rdbvh_core::geometry::Aabb;

    /// Counts nothing.
    struct Ignore;
    impl PathObserver for Ignore {
        fn closest(&mut self, _: u32, _: &Ray, _: Option<&Hit>) {}
        fn shadow(&mut self, _: &ShadowRay) {}
        fn shadow_tests(&mut self, _: &ShadowTests) {}
    }

    /// A 20 x 20 floor at y = 0 with albedo 0.5.
    fn floor() -> Scene {
        let (a, b, c, d) = (
            Vec3::new(-10.0, 0.0, -10.0),
            Vec3::new(10.0, 0.0, -10.0),
            Vec3::new(10.0, 0.0, 10.0),
            Vec3::new(-10.0, 0.0, 10.0),
        );
        let triangles = vec![Triangle::new(a, b, c), Triangle::new(a, c, d)];
        Scene {
            name: "floor".into(),
            bounds: triangles
                .iter()
                .fold(Aabb::EMPTY, |x, t| x.union(t.bounds())),
            triangles,
            material: vec![0, 0],
            emissive: vec![false, false],
            materials: vec![Material {
                name: "grey".into(),
                diffuse: [0.5; 3],
                emission: [0.0; 3],
            }],
            warnings: vec![],
            material_files: vec![],
            view: None,
        }
    }

    #[test]
    fn direct_light_from_a_point_matches_the_closed_form() {
        // Kd / pi * I * cos / r^2 at the point below a light 2 units up and 1 unit aside.
        let scene = floor();
        let light = Light::Point {
            position: Vec3::new(1.0, 2.0, 0.0),
            intensity: Vec3::new(10.0, 20.0, 30.0),
        };
        let lights = LightSet::new(vec![light], &scene.triangles).unwrap();
        let structure =
            Structure::build(StructureKind::Global, &scene.triangles, lights.lights()).unwrap();
        let integrator = Integrator::new(&scene, &lights, &structure, 0).unwrap();
        let ray = Ray::new(Vec3::new(0.0, 5.0, 0.0), Vec3::NEG_Y).unwrap();
        let l = integrator.radiance(ray, &Sampler::new(1, 0, 0), &mut Ignore);
        let (r2, cos) = (5.0f32, 2.0 / 5.0f32.sqrt());
        let expected = 0.5 * FRAC_1_PI * Vec3::new(10.0, 20.0, 30.0) * cos / r2;
        assert!(
            (l - expected).length() < 1e-3 * expected.length(),
            "{l} vs {expected}"
        );
    }

    #[test]
    fn an_open_floor_reflects_nothing_onto_itself() {
        // Bounce rays off a plane never come back to it: every bounce count gives the direct
        // light's answer, bit for bit, whatever the random numbers.
        let scene = floor();
        let light = Light::Point {
            position: Vec3::new(0.0, 1.0, 0.0),
            intensity: Vec3::ONE,
        };
        let lights = LightSet::new(vec![light], &scene.triangles).unwrap();
        let structure =
            Structure::build(StructureKind::Global, &scene.triangles, lights.lights()).unwrap();
        let direct = Integrator::new(&scene, &lights, &structure, 0).unwrap();
        let ray = Ray::new(Vec3::new(0.0, 0.5, 0.0), Vec3::new(0.3, -1.0, 0.1)).unwrap();
        let a = direct.radiance(ray, &Sampler::new(3, 0, 0), &mut Ignore);
        assert!(a.min_element() > 0.0);
        let bounced = Integrator::new(&scene, &lights, &structure, 5).unwrap();
        for s in 0..64 {
            assert_eq!(
                bounced.radiance(ray, &Sampler::new(3, 0, s), &mut Ignore),
                a
            );
        }
    }

    #[test]
    fn paths_in_a_batch_give_each_path_alone_bit_for_bit() {
        // A floor under a point light, with a box on it that casts a shadow, through a light
        // buffer: the batch answers cell by cell, out of the paths' order.
        let mut scene = floor();
        let (lo, hi) = (Vec3::new(-1.0, 0.0, -1.0), Vec3::new(1.0, 1.0, 1.0));
        for axis in 0..3 {
            for side in [lo, hi] {
                let mut c = [lo, lo, lo, lo];
                for (k, corner) in c.iter_mut().enumerate() {
                    let (u, v) = ((axis + 1) % 3, (axis + 2) % 3);
                    corner[axis] = side[axis];
                    corner[u] = if k & 1 == 0 { lo[u] } else { hi[u] };
                    corner[v] = if k & 2 == 0 { lo[v] } else { hi[v] };
                }
                scene.triangles.push(Triangle::new(c[0], c[1], c[3]));
                scene.triangles.push(Triangle::new(c[0], c[3], c[2]));
                scene.material.extend([0, 0]);
                scene.emissive.extend([false, false]);
            }
        }
        let light = Light::Point {
            position: Vec3::new(0.5, 3.0, 0.2),
            intensity: Vec3::splat(10.0),
        };
        let lights = LightSet::new(vec![light], &scene.triangles).unwrap();
        let structure =
            Structure::build(StructureKind::Lights, &scene.triangles, lights.lights()).unwrap();
        assert!(structure.answers_in_batches());
        let integrator = Integrator::new(&scene, &lights, &structure, 3).unwrap();
        let mut batch = PathBatch::default();
        let mut alone = Vec::new();
        for i in 0..256u32 {
            let dir = Vec3::new(i as f32 / 64.0 - 2.0, -1.0, (i % 17) as f32 / 8.0 - 1.0);
            let ray = Ray::new(Vec3::new(0.0, 4.0, 0.0), dir).unwrap();
            let sampler = Sampler::new(5, u64::from(i), 0);
            alone.push(integrator.radiance(ray, &sampler, &mut Ignore));
            integrator.trace(ray, &sampler, &mut Ignore, &mut batch);
        }
        integrator.answer(&mut batch);
        let batched: Vec<Vec3> = batch.radiance().collect();
        assert_eq!(batched, alone);
        let blocked = batch.segments.iter().filter(|s| s.occluded).count();
        assert!(blocked > 0 && blocked < batch.segments.len(), "{blocked}");
    }

    #[test]
    fn cosine_directions_lie_in_the_hemisphere_with_mean_cosine_two_thirds() {
        for n in [
            Vec3::Y,
            Vec3::NEG_Z,
            Vec3::new(0.6, 0.0, 0.8),
            Vec3::new(0.0, 0.0, -1.0),
        ] {
            let mut sum = 0.0;
            let k = 64;
            for i in 0..k {
                for j in 0..k {
                    let d = cosine_direction(
                        n,
                        (i as f32 + 0.5) / k as f32,
                        (j as f32 + 0.5) / k as f32,
                    );
                    assert!((d.length() - 1.0).abs() < 1e-4 && d.dot(n) >= 0.0, "{d}");
                    sum += d.dot(n);
                }
            }
            let mean = sum / (k * k) as f32;
            assert!((mean - 2.0 / 3.0).abs() < 0.01, "{n}: {mean}");
        }
    }
}
