//! `rdbvh` with no arguments: a short, self-checking run of the main job on built-in scenes.
//!
//! It does what a renderer with next event estimation does, small: build SAH and LSPH BVHs over a
//! lit room, shoot camera-like rays and shadow rays towards the ceiling light, then build the
//! scene structure (a `full` local BVH over a plane influence area below the light, an octree and
//! a fallback BVH) and trace the light's parallel rays and unrelated rays through it. Every answer
//! is checked against brute force, so a first run both shows the tool and proves it works here.

use std::io::Write;
use std::path::Path;
use std::time::Instant;

use rayon::prelude::*;
use rdbvh_core::brute_force;
use rdbvh_core::builder::{BuildOptions, Preset};
use rdbvh_core::geometry::{Ray, Triangle};
use rdbvh_core::heuristics::{CostConstants, Sah};
use rdbvh_core::influence::{InfluenceArea, PlaneArea, RaySampler};
use rdbvh_core::toplevel::{TopLevel, TopLevelOptions, DEFAULT_OCTREE_LEVELS};
use rdbvh_core::Vec3;

use super::builder::{BuilderArgs, BuilderKind, BuiltBvh};
use clap::Parser;

use super::answers::Answers;
use super::error::CliError;
use super::inputs::load_scene;
use super::render::{render, RenderReport};
use super::structure::trace_structure;
use super::trace::trace;
use crate::scene::{Mt19937, Scene};

/// Rays per query kind and scene: enough to exercise the trees, few enough to finish at once.
const RAYS: usize = 2048;

/// A batch of rays and how they are queried.
struct Batch {
    what: &'static str,
    rays: Vec<Ray>,
    any_hit: bool,
}

/// The image the demo renders, in the current folder.
pub const DEMO_IMAGE: &str = "rdbvh-room.png";

/// Runs the demo, writing what it does to `out` and the rendered room to [`DEMO_IMAGE`].
pub fn run(out: &mut impl Write) -> Result<(), CliError> {
    run_with(out, Path::new(DEMO_IMAGE))
}

/// [`run`], writing the rendered room to `image`.
pub fn run_with(out: &mut impl Write, image: &Path) -> Result<(), CliError> {
    let w = |out: &mut dyn Write, text: String| writeln!(out, "{text}").map_err(CliError::Stdout);
    w(
        out,
        "rdbvh demo: build BVHs over built-in scenes, trace rays, check them against brute force\n\
         (run `rdbvh --help` for the build and trace commands)"
            .into(),
    )?;
    let mut checked = 0;
    for spec in ["builtin:room", "builtin:random1000"] {
        let (scene, load_s) = load_scene(spec, None)?;
        w(
            out,
            format!(
                "\n{}: {} triangles, {} emissive, made in {:.2} ms",
                scene.name,
                scene.len(),
                scene.emissive_count(),
                load_s * 1e3
            ),
        )?;
        w(
            out,
            "  builder  nodes  leaves  depth  SAH cost  build ms  Mtris/s".into(),
        )?;
        let mut bvhs = Vec::new();
        for kind in [BuilderKind::Sah, BuilderKind::Lsph] {
            let args = BuilderArgs::plain(kind);
            let built = args.build(&scene.triangles)?;
            w(out, format!("  {}", stats_row(kind, &built, scene.len())))?;
            bvhs.push((kind, built));
        }
        for batch in batches(&scene) {
            let start = Instant::now();
            let expected = brute(&scene.triangles, &batch);
            let brute_s = start.elapsed().as_secs_f64();
            let mut bvh_s = 0.0;
            for (kind, built) in &bvhs {
                let start = Instant::now();
                let got = trace(&built.bvh, &scene.triangles, &batch.rays, batch.any_hit);
                if *kind == BuilderKind::Sah {
                    bvh_s = start.elapsed().as_secs_f64();
                }
                if let Some(i) = first_difference(&got, &expected) {
                    return Err(CliError::Mismatch(format!(
                        "{} {}, {} BVH, ray {i}: {:?}",
                        scene.name,
                        batch.what,
                        kind.name(),
                        batch.rays[i]
                    )));
                }
            }
            checked += batch.rays.len();
            w(
                out,
                format!(
                    "  {} {}: {} hit, same answers as brute force (SAH BVH {:.2} ms, brute \
                     force {:.2} ms)",
                    batch.rays.len(),
                    batch.what,
                    expected.hits(),
                    bvh_s * 1e3,
                    brute_s * 1e3
                ),
            )?;
        }
    }
    checked += structure(out)?;
    render_room(out, image)?;
    w(
        out,
        format!(
            "\nall {checked} queries agree with brute force on both builders and through the \
             scene structure, on {}",
            super::words::count(rayon::current_num_threads(), "thread")
        ),
    )
}

/// The camera of the demo's render: inside the room, looking past the boxes at the back wall.
const ROOM_CAMERA: [&str; 6] = ["--eye", "5,5,0.3", "--look-at", "5,4,10", "--fov", "75"];

/// A bulb under the room's ceiling, beside its emissive quad: the lights file the demo writes
/// next to its image (`rdbvh-room-lights.toml` beside `rdbvh-room.png`). The quad is wide next to the room's shadow segments and the pilot frame
/// builds it no light buffer; the bulb's shadow rays converge on a point, where a buffer pays.
const ROOM_BULB: &str = "# The demo's bulb, beside the room's emissive ceiling quad.
[[light]]
kind = \"point\"
position = [5.0, 4.5, 5.0]
intensity = [20.0, 20.0, 20.0]
";

/// Renders the room with next event estimation through both structures, checks that the images
/// are byte-identical, writes one, and prints what the shadow rays cost through each, and what
/// the camera rays cost through `lights`'s eye buffer.
fn render_room(out: &mut impl Write, image: &Path) -> Result<(), CliError> {
    let w = |out: &mut dyn Write, text: String| writeln!(out, "{text}").map_err(CliError::Stdout);
    let image_arg = image.to_string_lossy();
    let stem = image.file_stem().unwrap_or_default().to_string_lossy();
    let lights = image.with_file_name(format!("{stem}-lights.toml"));
    super::inputs::check_output(&lights, &[])?;
    std::fs::write(&lights, ROOM_BULB).map_err(|source| CliError::Write {
        path: lights.clone(),
        source,
    })?;
    let lights_arg = lights.to_string_lossy();
    let mut command = vec!["render", "builtin:room", "--lights", &lights_arg];
    command.extend(ROOM_CAMERA);
    command.extend(["--width", "256", "--height", "256", "--spp", "8"]);
    command.extend(["--out", &image_arg]);
    w(
        out,
        format!(
            "\nrender (next event estimation): rdbvh {} --structure global|lights",
            command.join(" ")
        ),
    )?;
    super::inputs::check_output(image, &[])?;
    let mut reports: Vec<(RenderReport, Vec<u8>)> = Vec::new();
    for structure in ["global", "lights"] {
        let mut line = vec!["rdbvh"];
        line.extend(&command);
        line.extend(["--structure", structure]);
        let args = match super::Cli::try_parse_from(&line).map(|c| c.command) {
            Ok(Some(super::Command::Render(args))) => args,
            _ => return Err(CliError::Mismatch("the demo's render command line".into())),
        };
        let report = render(&args)?;
        let png = std::fs::read(image).map_err(|source| CliError::Write {
            path: image.to_path_buf(),
            source,
        })?;
        reports.push((report, png));
    }
    let [(global, global_png), (lights, lights_png)] = &reports[..] else {
        unreachable!("two structures rendered");
    };
    if global_png != lights_png || global.shadow_occluded != lights.shadow_occluded {
        return Err(CliError::Mismatch(
            "the lights structure's image differs from the global BVH's".into(),
        ));
    }
    w(
        out,
        format!(
            "  {} camera, {} bounce, {} shadow rays; the same image, byte for byte, from both \
             structures: {}",
            global.camera_rays,
            global.bounce_rays,
            global.shadow_rays,
            image.display()
        ),
    )?;
    w(
        out,
        "  structure  build ms  nodes + triangles a shadow ray  shadow rays, 1 thread".into(),
    )?;
    for r in [global, lights] {
        let per_ray = |x: u64| x as f64 / r.shadow_rays.max(1) as f64;
        w(
            out,
            format!(
                "  {:<9}  {:>8.1}  {:>12.2} + {:<16.2}  {:>7.1} ms ({:.2}x global)",
                r.structure,
                r.build_ms,
                per_ray(r.shadow_node_tests),
                per_ray(r.shadow_triangle_tests),
                r.shadow_ms,
                r.shadow_ms / global.shadow_ms.max(1e-9)
            ),
        )?;
    }
    if lights.eye_buffer_tests > 0.0 {
        w(
            out,
            format!(
                "  lights' eye buffer for the camera rays: {:.2}x the global BVH's tests on the \
                 pilot frame's, {}",
                lights.eye_buffer_tests,
                if lights.eye_buffer {
                    "kept".to_string()
                } else {
                    format!(
                        "dropped (kept at {:.2}x or less)",
                        crate::render::KEEP_RATIO
                    )
                }
            ),
        )?;
    }
    Ok(())
}

/// The room's influence area: parallel rays straight down from just below the 2 x 2 ceiling
/// light to the floor, as an area file would give it:
/// `kind = "plane"`, `center = [5, 9.9, 5]`, `normal = [0, -1, 0]`, `half_width = 1`,
/// `half_height = 1`, `depth = 9.9`.
pub fn room_light_area() -> Result<InfluenceArea, CliError> {
    PlaneArea::new(Vec3::new(5.0, 9.9, 5.0), -Vec3::Y, 1.0, 1.0, 9.9)
        .map(InfluenceArea::from)
        .map_err(|e| CliError::Mismatch(format!("the demo's own area is invalid: {e}")))
}

/// Builds the scene structure over the room with a `full` local BVH for the light's area, traces
/// the area's rays and unrelated rays through it, and returns how many queries it checked.
fn structure(out: &mut impl Write) -> Result<usize, CliError> {
    let w = |out: &mut dyn Write, text: String| writeln!(out, "{text}").map_err(CliError::Stdout);
    let (scene, _) = load_scene("builtin:room", None)?;
    let area = room_light_area()?;
    let options = TopLevelOptions {
        local: BuildOptions::new(Preset::Full),
        ..TopLevelOptions::default()
    };
    let start = Instant::now();
    let s = TopLevel::with_octree(
        &scene.triangles,
        vec![area],
        &options,
        DEFAULT_OCTREE_LEVELS,
    )?;
    let build_s = start.elapsed().as_secs_f64();
    w(
        out,
        format!(
            "\n{} with a scene structure: a `full` (PAH + SPFH) local BVH over the {} triangles \
             of a plane area below the light, an octree and a SAH fallback BVH, built in {:.2} ms",
            scene.name,
            s.triangles_per_area()[0],
            build_s * 1e3
        ),
    )?;
    let along_normal: Vec<Ray> = RaySampler::new(area, 11).take(RAYS).collect();
    let unrelated = batches(&scene).swap_remove(0).rays;
    let mut checked = 0;
    for (what, rays) in [
        ("rays from the light along its normal", along_normal),
        ("camera rays, unrelated to the area,", unrelated),
    ] {
        let t = trace_structure(&s, &scene.triangles, &rays, false, CostConstants::default());
        let batch = Batch {
            what,
            rays,
            any_hit: false,
        };
        let expected = brute(&scene.triangles, &batch);
        if let Some(i) = first_difference(&t.answers, &expected) {
            return Err(CliError::Mismatch(format!(
                "{} {what}, scene structure, ray {i}: {:?}",
                scene.name, batch.rays[i]
            )));
        }
        checked += batch.rays.len();
        w(
            out,
            format!(
                "  {} {what} (closest hit): local hit rate {:.1}%, mean cost {:.2} with the \
                 structure vs {:.2} with the fallback BVH alone, same answers as brute force",
                batch.rays.len(),
                100.0 * t.local_hit_rate(batch.rays.len()),
                t.cost_structure,
                t.cost_fallback
            ),
        )?;
    }
    Ok(checked)
}

fn stats_row(kind: BuilderKind, b: &BuiltBvh, triangles: usize) -> String {
    format!(
        "{:<7} {:>6} {:>7} {:>6} {:>9.2} {:>9.3} {:>8.2}",
        kind.name(),
        b.bvh.nodes().len(),
        b.bvh.leaf_count(),
        b.bvh.max_depth(),
        b.bvh.estimated_cost(&Sah, CostConstants::default()),
        b.seconds * 1e3,
        b.mtris_per_s(triangles)
    )
}

/// The rays of a scene: for a scene with lights, camera-like rays from inside plus shadow rays
/// from random surface points to random points on the lights; otherwise random rays through its
/// bounds, queried both ways.
fn batches(scene: &Scene) -> Vec<Batch> {
    let mut rng = Mt19937::new(2024);
    let lights: Vec<u32> = scene.emissive_triangles().collect();
    let b = scene.bounds;
    // Origins uniform in the scene's bounds shrunk by 5% on every side.
    let inside = |rng: &mut Mt19937| {
        let u = Vec3::new(unit(rng), unit(rng), unit(rng));
        b.min + b.extent() * (Vec3::splat(0.05) + u * 0.9)
    };
    let camera: Vec<Ray> = (0..RAYS)
        .filter_map(|_| {
            let o = inside(&mut rng);
            Ray::new(o, sphere(&mut rng)).ok()
        })
        .collect();
    if lights.is_empty() {
        return vec![
            Batch {
                what: "random rays (closest hit)",
                rays: camera.clone(),
                any_hit: false,
            },
            Batch {
                what: "random rays (any hit)",
                rays: camera,
                any_hit: true,
            },
        ];
    }
    let surfaces: Vec<u32> = (0..scene.len() as u32)
        .filter(|&i| !scene.emissive[i as usize])
        .collect();
    let shadow: Vec<Ray> = (0..RAYS)
        .filter_map(|_| {
            let from = pick(&mut rng, &surfaces)
                .map(|i| on_triangle(&mut rng, &scene.triangles[i as usize]))?;
            let to = pick(&mut rng, &lights)
                .map(|i| on_triangle(&mut rng, &scene.triangles[i as usize]))?;
            // Unnormalised direction with t in (0, 1): the segment between the two points, minus
            // a little at each end so neither endpoint's own triangle counts as an occluder.
            Ray::segment(from, to - from, 1e-4, 1.0 - 1e-4).ok()
        })
        .collect();
    vec![
        Batch {
            what: "camera rays (closest hit)",
            rays: camera,
            any_hit: false,
        },
        Batch {
            what: "shadow rays to the light (any hit = occluded)",
            rays: shadow,
            any_hit: true,
        },
    ]
}

fn brute(triangles: &[Triangle], batch: &Batch) -> Answers {
    if batch.any_hit {
        Answers::Any(
            batch
                .rays
                .par_iter()
                .map(|r| brute_force::any_hit(r, triangles))
                .collect(),
        )
    } else {
        Answers::Closest(
            batch
                .rays
                .par_iter()
                .map(|r| brute_force::closest_hit(r, triangles))
                .collect(),
        )
    }
}

fn first_difference(a: &Answers, b: &Answers) -> Option<usize> {
    match (a, b) {
        (Answers::Closest(a), Answers::Closest(b)) => a.iter().zip(b).position(|(x, y)| x != y),
        (Answers::Any(a), Answers::Any(b)) => a.iter().zip(b).position(|(x, y)| x != y),
        _ => Some(0),
    }
}

fn unit(rng: &mut Mt19937) -> f32 {
    rng.canonical_f64() as f32
}

/// A direction uniform on the unit sphere.
fn sphere(rng: &mut Mt19937) -> Vec3 {
    let z = 2.0 * unit(rng) - 1.0;
    let phi = std::f32::consts::TAU * unit(rng);
    let r = (1.0 - z * z).max(0.0).sqrt();
    Vec3::new(r * phi.cos(), r * phi.sin(), z)
}

/// A point uniform on triangle `t`.
fn on_triangle(rng: &mut Mt19937, t: &Triangle) -> Vec3 {
    let s = unit(rng).sqrt();
    let r = unit(rng);
    t.v0 * (1.0 - s) + t.v1 * (s * (1.0 - r)) + t.v2 * (s * r)
}

fn pick(rng: &mut Mt19937, ids: &[u32]) -> Option<u32> {
    let i = (unit(rng) * ids.len() as f32) as usize;
    ids.get(i.min(ids.len().saturating_sub(1))).copied()
}
