//! The renderer's shadow rays through the three `rdbvh render --structure` choices, on the scenes
//! and lights of `scripts/render-comparison.sh` at a smaller frame (128 x 128, 2 samples, 3
//! bounces, seed 1):
//!
//! - `render/SCENE/shadow/{global,lights,thesis}`: the frame's shadow segments answered on one
//!   thread, as `shadow_ms` replays them: in the frame's batches, each in the structure's order
//!   (throughput in segments);
//! - `render/SCENE/camera/{global,lights}`: the frame's camera rays on one thread, through the
//!   global BVH and through `lights` (its eye buffer where the pilot kept one);
//! - `render/SCENE/in_frame/{closest_alone,global,lights,thesis}`: the same shadow segments
//!   with the frame's camera and bounce rays (closest hit, through the structure's global BVH)
//!   in their frame order and ratio, on one thread, as the renderer traces them: a structure
//!   that answers in batches takes each batch's closest-hit rays and then its shadow segments,
//!   the others each segment between its share of closest-hit rays; `closest_alone` traces
//!   those closest-hit rays alone. A structure's time minus `closest_alone` is what its shadow
//!   segments cost inside a frame, where the global BVH's nodes and triangles share the caches
//!   with theirs (a light buffer's trees are memory the global BVH does not warm);
//! - `render/SCENE/build/{global,lights,thesis}`: building the structure, the `lights` pilot
//!   frame included (two threads).
//!
//! Untimed, printed before each group: each structure's node + triangle tests per shadow segment
//! (the machine-independent measure), and a check that it answers every segment as the frame did.
//! The room is built in; the other scenes need `../shared/scenes` and are skipped without it.

use std::hint::black_box;
use std::path::Path;
use std::time::Duration;

use criterion::{criterion_group, criterion_main, Criterion, Throughput};
use glam::Vec3;
use rdbvh::render::{
    answer_batches, build_lights, emissive_lights, parse_lights, pilot_size, render_frame,
    BatchOrder, Camera, FrameSettings, Integrator, LightSet, ShadowRay, Structure, StructureKind,
    DEFAULT_FOV_DEG,
};
use rdbvh::scene::Scene;
use rdbvh_benches::scenes_dir;
use rdbvh_core::bvh::{Hit, TraversalStats};
use rdbvh_core::geometry::Ray;

const SIZE: (u32, u32) = (128, 128);
const SPP: u32 = 2;
const BOUNCES: u32 = 3;
const SEED: u64 = 1;

/// A scene of the comparison: its file (or built-in name), its extra lights and its camera.
struct Case {
    name: &'static str,
    scene: &'static str,
    lights: &'static str,
    eye: Option<(Vec3, Vec3, f32)>,
}

const CASES: [Case; 4] = [
    Case {
        name: "room",
        scene: "builtin:room",
        lights: "",
        eye: Some((Vec3::new(5.0, 5.0, 0.3), Vec3::new(5.0, 4.0, 10.0), 75.0)),
    },
    Case {
        name: "cornell_box",
        scene: "cornell_box",
        lights: "",
        eye: None,
    },
    Case {
        name: "sponza_crytek",
        scene: "sponza_crytek",
        lights: "[[light]]\nkind = \"point\"\nposition = [0.0, 800.0, 0.0]\n\
                 intensity = [400000.0, 380000.0, 340000.0]\n",
        eye: Some((
            Vec3::new(1100.0, 200.0, -50.0),
            Vec3::new(-900.0, 400.0, 0.0),
            60.0,
        )),
    },
    Case {
        name: "sponza_quad",
        scene: "sponza_crytek",
        lights: "[[light]]\nkind = \"quad\"\ncorner = [-50.0, 800.0, -50.0]\n\
                 edge1 = [100.0, 0.0, 0.0]\nedge2 = [0.0, 0.0, 100.0]\n\
                 radiance = [40.0, 38.0, 34.0]\n",
        eye: Some((
            Vec3::new(1100.0, 200.0, -50.0),
            Vec3::new(-900.0, 400.0, 0.0),
            60.0,
        )),
    },
];

/// A frame's shadow segments, the sizes of its batches, its closest-hit rays (camera and bounce,
/// merged) and its camera rays with their hits.
type FrameRays = (
    Vec<ShadowRay>,
    Vec<usize>,
    Vec<Ray>,
    Vec<(Ray, Option<Hit>)>,
);

/// A loaded case: the scene, its lights and where the camera looks from.
struct Loaded {
    scene: Scene,
    lights: LightSet,
    /// Eye, look-at point and vertical field of view in degrees.
    view: (Vec3, Vec3, f32),
}

impl Loaded {
    fn new(case: &Case) -> Result<Self, String> {
        let scene = if case.scene.starts_with("builtin:") {
            Scene::open(case.scene)
        } else {
            Scene::load(scenes_dir()?.join(format!("{}.obj", case.scene)))
        }
        .map_err(|e| e.to_string())?;
        let mut lights = emissive_lights(&scene);
        lights.extend(parse_lights(case.lights, Path::new("bench")).map_err(|e| e.to_string())?);
        let lights = LightSet::new(lights, &scene.triangles).ok_or("no light")?;
        let view = match case.eye {
            Some(view) => view,
            None => {
                let framing = Camera::framing(scene.bounds, DEFAULT_FOV_DEG, SIZE.0, SIZE.1)
                    .map_err(|e| e.to_string())?;
                (framing.eye(), scene.bounds.center(), DEFAULT_FOV_DEG)
            }
        };
        Ok(Self {
            scene,
            lights,
            view,
        })
    }

    /// The camera for an image of `size`.
    fn camera(&self, (w, h): (u32, u32)) -> Camera {
        let (eye, at, fov) = self.view;
        Camera::new(eye, at, Vec3::Y, fov, w, h).expect("a valid camera")
    }

    /// Builds `kind`, as `rdbvh render` does (the pilot frame for `lights`).
    fn build(&self, kind: StructureKind) -> Structure {
        let built = match kind {
            StructureKind::Lights => {
                let size = pilot_size(SIZE.0, SIZE.1);
                let camera = self.camera(SIZE);
                // The buffers the comparison's full frame repays, whose shadow segments this
                // smaller frame samples: at its own size, the pilot would find none worth it.
                let full_frame = 512 * 512 * 16;
                build_lights(
                    &self.scene,
                    &self.lights,
                    BOUNCES,
                    &camera,
                    size,
                    SEED,
                    full_frame,
                )
                .map(|(s, _)| s)
            }
            kind => Structure::build(kind, &self.scene.triangles, self.lights.lights()),
        };
        built.expect("the structure builds")
    }

    /// The frame's shadow segments, the sizes of the batches `lights` answers them in, its
    /// camera and bounce rays (merged in frame order, in their ratio), and its camera rays with
    /// their hits: the rays are every structure's, the batches those of `structure`.
    fn frame_rays(&self, structure: &Structure) -> FrameRays {
        let integrator =
            Integrator::new(&self.scene, &self.lights, structure, BOUNCES).expect("an integrator");
        let settings = FrameSettings {
            width: SIZE.0,
            height: SIZE.1,
            spp: SPP,
            seed: SEED,
            record_limit: usize::MAX,
            progress: false,
        };
        let frame = render_frame(&integrator, &self.camera(SIZE), &settings);
        let (camera, bounce) = (&frame.recorded.camera, &frame.recorded.bounce);
        let total = camera.len() + bounce.len();
        // Camera ray `c` takes position `c * total / camera` of the merge and bounce rays fill
        // the rest: both kinds stay in frame order, spread evenly.
        let mut closest = Vec::with_capacity(total);
        let (mut c, mut b) = (0, 0);
        for k in 0..total {
            if c < camera.len() && (c * total <= k * camera.len() || b == bounce.len()) {
                closest.push(camera[c].0);
                c += 1;
            } else {
                closest.push(bounce[b].0);
                b += 1;
            }
        }
        (
            frame.shadow_rays,
            frame.shadow_batches,
            closest,
            frame.recorded.camera,
        )
    }
}

fn render(c: &mut Criterion) {
    for case in &CASES {
        let loaded = match Loaded::new(case) {
            Ok(x) => x,
            Err(e) => {
                eprintln!("render benchmarks skipped for {}: {e}", case.name);
                continue;
            }
        };
        let kinds = [
            StructureKind::Global,
            StructureKind::Lights,
            StructureKind::Thesis,
        ];
        let structures: Vec<Structure> = kinds.iter().map(|&k| loaded.build(k)).collect();
        let (shadow, batches, closest, camera) = loaded.frame_rays(&structures[1]);
        let mut group = c.benchmark_group(format!("render/{}/shadow", case.name));
        group
            .throughput(Throughput::Elements(shadow.len() as u64))
            .sample_size(10)
            .warm_up_time(Duration::from_millis(300))
            .measurement_time(Duration::from_secs(2));
        for (kind, structure) in kinds.iter().zip(&structures) {
            let mut stats = TraversalStats::default();
            for s in &shadow {
                let blocked = structure.occluded_counted(s.light as usize, &s.ray, &mut stats);
                assert_eq!(
                    blocked,
                    s.occluded,
                    "{} answers as the frame did",
                    kind.name()
                );
            }
            let n = shadow.len().max(1) as f64;
            eprintln!(
                "render/{}/shadow/{}: {} segments, {:.2} nodes + {:.2} triangles a segment",
                case.name,
                kind.name(),
                shadow.len(),
                f64::from(stats.inner_nodes) / n,
                f64::from(stats.triangles) / n
            );
            group.bench_function(kind.name(), |b| {
                b.iter(|| replay(structure, black_box(&shadow), &batches))
            });
        }
        group.finish();
        camera_rays(c, case.name, &kinds[..2], &structures[..2], &camera);
        in_frame(
            c,
            case.name,
            &kinds,
            &structures,
            (&shadow, &batches),
            &closest,
        );
        let mut group = c.benchmark_group(format!("render/{}/build", case.name));
        group
            .sample_size(10)
            .warm_up_time(Duration::from_millis(300))
            .measurement_time(Duration::from_secs(3));
        for kind in kinds {
            group.bench_function(kind.name(), |b| {
                b.iter(|| black_box(&loaded).build(kind).build_ms())
            });
        }
        group.finish();
    }
}

/// The frame's shadow segments through `structure` in the frame's batches, as `shadow_ms`
/// replays them. Returns how many are blocked.
fn replay(structure: &Structure, shadow: &[ShadowRay], batches: &[usize]) -> usize {
    let mut answers = vec![false; shadow.len()];
    answer_batches(
        structure,
        shadow,
        batches,
        &mut answers,
        &mut BatchOrder::default(),
    );
    answers.iter().filter(|&&a| a).count()
}

/// The `camera` group: the frame's camera rays on one thread through `global` and `lights`
/// (its eye buffer where the pilot kept one), after a check that both find the frame's hits,
/// with each one's node + triangle tests a ray printed.
fn camera_rays(
    c: &mut Criterion,
    name: &str,
    kinds: &[StructureKind],
    structures: &[Structure],
    camera: &[(Ray, Option<Hit>)],
) {
    let mut group = c.benchmark_group(format!("render/{name}/camera"));
    group
        .throughput(Throughput::Elements(camera.len() as u64))
        .sample_size(10)
        .warm_up_time(Duration::from_millis(300))
        .measurement_time(Duration::from_secs(2));
    for (kind, structure) in kinds.iter().zip(structures) {
        let mut stats = TraversalStats::default();
        for (ray, hit) in camera {
            let found = structure.closest_hit_camera_counted(ray, &mut stats);
            assert_eq!(found, *hit, "{} finds the frame's hit", kind.name());
        }
        let n = camera.len().max(1) as f64;
        eprintln!(
            "render/{name}/camera/{}: {} rays, {:.2} nodes + {:.2} triangles a ray{}",
            kind.name(),
            camera.len(),
            f64::from(stats.inner_nodes) / n,
            f64::from(stats.triangles) / n,
            if structure.eye_buffer().is_some() {
                " (eye buffer)"
            } else {
                ""
            }
        );
        group.bench_function(kind.name(), |b| {
            b.iter(|| {
                black_box(camera)
                    .iter()
                    .filter(|(r, _)| structure.closest_hit_camera(r).is_some())
                    .count()
            })
        });
    }
    group.finish();
}

/// The `in_frame` group: the shadow segments with their share of the frame's closest-hit rays
/// (each batch's rays then its segments, or each segment after its share), against those
/// closest-hit rays alone.
fn in_frame(
    c: &mut Criterion,
    name: &str,
    kinds: &[StructureKind],
    structures: &[Structure],
    (shadow, batches): (&[ShadowRay], &[usize]),
    closest: &[Ray],
) {
    let mut group = c.benchmark_group(format!("render/{name}/in_frame"));
    group
        .throughput(Throughput::Elements(shadow.len() as u64))
        .sample_size(10)
        .warm_up_time(Duration::from_millis(300))
        .measurement_time(Duration::from_secs(3));
    let global = &structures[0];
    group.bench_function("closest_alone", |b| {
        b.iter(|| {
            black_box(closest)
                .iter()
                .filter(|r| global.closest_hit(r).is_some())
                .count()
        })
    });
    let (n, m) = (shadow.len().max(1), closest.len());
    let closest_hits = |s: &Structure, from: usize, to: usize| {
        closest[from * m / n..to * m / n]
            .iter()
            .filter(|r| s.closest_hit(r).is_some())
            .count()
    };
    for (kind, structure) in kinds.iter().zip(structures) {
        group.bench_function(kind.name(), |b| {
            b.iter(|| {
                let mut hits = 0;
                if structure.answers_in_batches() {
                    let (mut answers, mut order) = (vec![false; n], BatchOrder::default());
                    let mut first = 0;
                    for &size in batches {
                        let end = (first + size).min(shadow.len());
                        hits += closest_hits(structure, first, end);
                        let (segments, answered) = (&shadow[first..end], &mut answers[first..end]);
                        structure.occluded_batch(black_box(segments), answered, &mut order);
                        hits += answered.iter().filter(|&&a| a).count();
                        first = end;
                    }
                } else {
                    for (i, s) in black_box(shadow).iter().enumerate() {
                        hits += usize::from(structure.occluded(s.light as usize, &s.ray));
                        hits += closest_hits(structure, i, i + 1);
                    }
                }
                hits
            })
        });
    }
    group.finish();
}

criterion_group!(benches, render);
criterion_main!(benches);
