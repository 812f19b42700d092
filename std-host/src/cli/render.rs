//! `rdbvh render`: path trace a scene with next event estimation, write the PNG, and report
//! the shadow rays' cost through the structure chosen.

use std::fs;
use std::io::{BufWriter, IsTerminal, Write};
use std::path::{Path, PathBuf};

use clap::{value_parser, Args};
use rdbvh_core::geometry::Ray;
use rdbvh_core::Vec3;
use serde::Serialize;

use super::answers::{write_answers, Answers};
use super::error::CliError;
use super::inputs::load_scene;
use super::rays::write_rays;
use crate::render::{
    build_lights, emissive_lights, encode_png, mean_luminance, pilot_size, read_lights,
    render_frame, replay_shadow_rays, to_srgb8, Camera, FrameSettings, Integrator, LightSet,
    PilotReport, RecordedRays, RenderError, Structure, StructureKind, DEFAULT_FOV_DEG,
};

/// Arguments of `rdbvh render`.
#[derive(Args, Clone, Debug)]
pub struct RenderArgs {
    /// The scene: an OBJ file (with its MTL), or builtin:NAME for a built-in scene.
    #[arg(value_name = "SCENE.obj")]
    pub scene: String,
    /// Point, spot and quad lights (TOML, one `[[light]]` table each), added to the scene's
    /// emissive triangles.
    #[arg(long, value_name = "LIGHTS.toml")]
    pub lights: Option<PathBuf>,
    /// Where to write the image (PNG).
    #[arg(long, value_name = "FILE.png", default_value = "render.png")]
    pub out: PathBuf,
    /// Image width in pixels.
    #[arg(long, default_value_t = 512, value_parser = value_parser!(u32).range(1..=16384))]
    pub width: u32,
    /// Image height in pixels.
    #[arg(long, default_value_t = 512, value_parser = value_parser!(u32).range(1..=16384))]
    pub height: u32,
    /// Samples per pixel.
    #[arg(long, default_value_t = 16, value_parser = value_parser!(u32).range(1..=1_000_000))]
    pub spp: u32,
    /// Bounces after the camera ray's hit; 0 is direct light only.
    #[arg(long, value_name = "N", default_value_t = 3, value_parser = value_parser!(u32).range(0..=1000))]
    pub max_bounces: u32,
    /// The seed of every random number: the image depends on it alone.
    #[arg(long, default_value_t = 1)]
    pub seed: u64,
    /// Worker threads (0: every core; at most 1024).
    #[arg(long, default_value_t = 0, value_parser = value_parser!(u32).range(0..=1024))]
    pub threads: u32,
    /// The camera's position [default: the scene's own view (builtin:room: inside, by the front
    /// wall), else in front of the scene's +z face, framing its bounds]
    #[arg(long, value_name = "X,Y,Z", value_parser = parse_vec3, allow_hyphen_values = true)]
    pub eye: Option<Vec3>,
    /// The point the camera looks at [default: the scene's own view, else the centre of its
    /// bounds]
    #[arg(long, value_name = "X,Y,Z", value_parser = parse_vec3, allow_hyphen_values = true)]
    pub look_at: Option<Vec3>,
    /// The image's up direction [default: 0,1,0]
    #[arg(long, value_name = "X,Y,Z", value_parser = parse_vec3, allow_hyphen_values = true)]
    pub up: Option<Vec3>,
    /// Vertical field of view in degrees, in (0, 180).
    #[arg(long, value_name = "DEG", default_value_t = DEFAULT_FOV_DEG)]
    pub fov: f32,
    /// Which structure answers the shadow rays (and, for `lights`, the camera rays; bounce rays
    /// always use the global BVH); every structure gives the same image, byte for byte.
    #[arg(long, value_enum, default_value_t = StructureKind::Global)]
    pub structure: StructureKind,
    /// Single-thread replays of the frame's shadow rays for shadow_ms (the best one counts).
    #[arg(long, value_name = "N", default_value_t = 5, value_parser = value_parser!(u32).range(1..=100))]
    pub shadow_replays: u32,
    /// Write the first rays of each kind with the renderer's answers to DIR (created if
    /// missing): camera_rays.csv + camera_hits.csv, bounce_rays.csv + bounce_hits.csv,
    /// shadow_rays.csv + shadow_hits.csv.
    #[arg(long, value_name = "DIR")]
    pub record_rays: Option<PathBuf>,
    /// With --record-rays: how many rays of each kind.
    #[arg(
        long,
        value_name = "N",
        default_value_t = 100_000,
        requires = "record_rays"
    )]
    pub record_limit: usize,
    /// Print the report as one JSON object, the last line of standard output.
    #[arg(long)]
    pub json: bool,
}

/// `X,Y,Z`: three finite numbers.
fn parse_vec3(s: &str) -> Result<Vec3, String> {
    let xs: Result<Vec<f32>, _> = s.split(',').map(|x| x.trim().parse::<f32>()).collect();
    match xs.as_deref() {
        Ok(&[x, y, z]) if [x, y, z].iter().all(|c| c.is_finite()) => Ok(Vec3::new(x, y, z)),
        _ => Err(format!("expected three finite numbers X,Y,Z, got `{s}`")),
    }
}

/// The report of one render (`--json` prints it as one object).
#[derive(Clone, Debug, Serialize)]
pub struct RenderReport {
    /// The scene's name.
    pub scene: String,
    /// Its triangles.
    pub triangles: usize,
    /// Lights the renderer samples (emissive triangles and the lights file's).
    pub lights: usize,
    /// Light buffers in use (0 for `global`): those built that the pilot frame kept.
    pub light_buffers: usize,
    /// Light buffers dropped because the pilot frame's shadow rays showed that they do not pay
    /// (their lights use the global BVH), whether built first or not.
    pub light_buffers_dropped: usize,
    /// Of those dropped, the ones never built: the light is too wide next to its pilot shadow
    /// segments' lengths for a buffer to pay (`render::pilot::MAX_EXTENT_RATIO`), or its share of
    /// the frame's shadow tests could not repay the build
    /// (`render::pilot::BUILD_TESTS_PER_TRIANGLE`).
    pub light_buffers_skipped: usize,
    /// Shadow segments of the pilot frame (0 when there was no buffer to decide on).
    pub pilot_shadow_rays: usize,
    /// Whether the camera rays go through an eye buffer (`lights` only): a light buffer at the
    /// camera's eye, kept where the pilot frame's camera rays show that it pays.
    pub eye_buffer: bool,
    /// The eye buffer's node and triangle tests on the pilot frame's camera rays over the
    /// global BVH's (0 when it was not built).
    pub eye_buffer_tests: f64,
    /// Influence areas of the `thesis` structure (0 for the others): frustums of point and
    /// spot lights plus oriented boxes of quad lights and emissive clusters.
    pub influence_areas: usize,
    /// Triangles over every local BVH of the `thesis` structure (one in two areas counts twice).
    pub influence_area_triangles: u64,
    /// Image width.
    pub width: u32,
    /// Image height.
    pub height: u32,
    /// Samples per pixel.
    pub spp: u32,
    /// Bounces after the first hit.
    pub max_bounces: u32,
    /// The seed.
    pub seed: u64,
    /// Threads that rendered.
    pub threads: usize,
    /// `global`, `lights` or `thesis`.
    pub structure: &'static str,
    /// Wall-clock milliseconds of the structure's build (global BVH, light buffers and the pilot
    /// frame that chose among them).
    pub build_ms: f64,
    /// The global BVH's share of `build_ms` (all of it for `global`).
    pub global_build_ms: f64,
    /// The pilot frame's share of `build_ms` (`lights` only, 0 otherwise): what is left,
    /// `build_ms - global_build_ms - pilot_ms`, is the light buffers and the choice among them.
    pub pilot_ms: f64,
    /// Wall-clock milliseconds of the frame.
    pub render_ms: f64,
    /// Camera rays traced.
    pub camera_rays: u64,
    /// Shadow segments traced.
    pub shadow_rays: u64,
    /// Bounce rays traced.
    pub bounce_rays: u64,
    /// Shadow segments that something blocked.
    pub shadow_occluded: u64,
    /// Inner nodes the shadow segments visited, 8-wide nodes for every structure (a light
    /// buffer's cell lookup, and the `thesis` octree's, counts as one).
    pub shadow_node_tests: u64,
    /// Ray/triangle tests of the shadow segments.
    pub shadow_triangle_tests: u64,
    /// Shadow segments in the replay (the frame's first, at most `REPLAY_CAP`).
    pub shadow_replay_rays: usize,
    /// Best single-thread time of the replay, in milliseconds.
    pub shadow_ms: f64,
    /// Mean Rec. 709 luminance of the linear image.
    pub mean_luminance: f64,
    /// The PNG written.
    pub out: String,
}

/// Runs `rdbvh render`, printing the report to `out`.
pub fn run(args: &RenderArgs, out: &mut impl Write) -> Result<(), CliError> {
    let mut inputs = vec![Path::new(&args.scene)];
    inputs.extend(args.lights.as_deref());
    super::inputs::check_output(&args.out, &inputs)?;
    if let Some(dir) = &args.record_rays {
        fs::create_dir_all(dir).map_err(|source| CliError::Write {
            path: dir.clone(),
            source,
        })?;
    }
    let pool = rayon::ThreadPoolBuilder::new()
        .num_threads(args.threads as usize)
        .build()
        .map_err(|e| CliError::Usage(format!("cannot start {} threads: {e}", args.threads)))?;
    let report = pool.install(|| render(args))?;
    print_summary(&report, out).map_err(CliError::Stdout)?;
    if args.json {
        let json = serde_json::to_string(&report).map_err(std::io::Error::other);
        json.and_then(|json| writeln!(out, "{json}"))
            .map_err(CliError::Stdout)?;
    }
    Ok(())
}

/// Loads, builds, renders, replays and writes; runs on the current thread pool.
pub(super) fn render(args: &RenderArgs) -> Result<RenderReport, CliError> {
    let (scene, _) = load_scene(&args.scene, Some(&args.out))?;
    let mut lights = emissive_lights(&scene);
    let emissive = lights.len();
    let mut from_file = None;
    if let Some(path) = &args.lights {
        let file = read_lights(path)?;
        from_file = Some((path.display().to_string(), file.len()));
        lights.extend(file);
    }
    let lights = LightSet::new(lights, &scene.triangles).ok_or_else(|| RenderError::NoLights {
        scene: scene.name.clone(),
        emissive,
        from_file,
    })?;
    let (eye, look_at) = match scene.view {
        Some(view) => (view.eye, view.look_at),
        // The framing camera only where it is used: a scene too large to frame still renders
        // from the caller's own eye.
        None => (
            match args.eye {
                Some(eye) => eye,
                None => Camera::framing(scene.bounds, args.fov, args.width, args.height)?.eye(),
            },
            scene.bounds.center(),
        ),
    };
    let camera = Camera::new(
        args.eye.unwrap_or(eye),
        args.look_at.unwrap_or(look_at),
        args.up.unwrap_or(Vec3::Y),
        args.fov,
        args.width,
        args.height,
    )?;
    let size = pilot_size(args.width, args.height);
    let (structure, pilot) = match args.structure {
        StructureKind::Lights => build_lights(
            &scene,
            &lights,
            args.max_bounces,
            &camera,
            size,
            args.seed,
            u64::from(args.width) * u64::from(args.height) * u64::from(args.spp),
        )?,
        kind => (
            Structure::build(kind, &scene.triangles, lights.lights())?,
            PilotReport::default(),
        ),
    };
    let integrator = Integrator::new(&scene, &lights, &structure, args.max_bounces)?;
    let settings = FrameSettings {
        width: args.width,
        height: args.height,
        spp: args.spp,
        seed: args.seed,
        record_limit: if args.record_rays.is_some() {
            args.record_limit
        } else {
            0
        },
        progress: std::io::stderr().is_terminal(),
    };
    let frame = render_frame(&integrator, &camera, &settings);
    let luminance = mean_luminance(&frame.pixels);
    if !luminance.is_finite() {
        return Err(RenderError::RadianceOverflow.into());
    }
    let shadow_ms = replay_shadow_rays(
        &structure,
        &frame.shadow_rays,
        &frame.shadow_batches,
        args.shadow_replays,
    )?;

    let png = encode_png(&to_srgb8(&frame.pixels), args.width, args.height)?;
    fs::write(&args.out, png).map_err(|source| CliError::Write {
        path: args.out.clone(),
        source,
    })?;
    if let Some(dir) = &args.record_rays {
        write_records(dir, &frame.recorded)?;
    }
    let c = frame.counters;
    let thesis = structure.thesis().map(|t| t.summary()).unwrap_or_default();
    Ok(RenderReport {
        scene: scene.name.clone(),
        triangles: scene.len(),
        lights: lights.lights().len(),
        light_buffers: structure.light_buffers().len(),
        light_buffers_dropped: pilot.dropped,
        light_buffers_skipped: pilot.skipped,
        pilot_shadow_rays: pilot.shadow_rays,
        eye_buffer: pilot.eye.kept,
        eye_buffer_tests: pilot.eye.test_ratio,
        influence_areas: thesis.point_areas + thesis.plane_areas,
        influence_area_triangles: thesis.local_triangles,
        width: args.width,
        height: args.height,
        spp: args.spp,
        max_bounces: args.max_bounces,
        seed: args.seed,
        threads: rayon::current_num_threads(),
        structure: structure.kind().name(),
        build_ms: structure.build_ms(),
        global_build_ms: structure.global_build_ms(),
        pilot_ms: pilot.ms,
        render_ms: frame.render_ms,
        camera_rays: c.camera_rays,
        shadow_rays: c.shadow_rays,
        bounce_rays: c.bounce_rays,
        shadow_occluded: c.shadow_occluded,
        shadow_node_tests: c.shadow_node_tests,
        shadow_triangle_tests: c.shadow_triangle_tests,
        shadow_replay_rays: frame.shadow_rays.len(),
        shadow_ms,
        mean_luminance: luminance,
        out: args.out.display().to_string(),
    })
}

/// Writes the recorded rays and answers in the formats `rdbvh trace` reads and writes.
fn write_records(dir: &Path, r: &RecordedRays) -> Result<(), CliError> {
    let rays = |name: &str, rays: &mut dyn Iterator<Item = &Ray>| {
        let path = dir.join(name);
        let fail = |source| CliError::Write {
            path: path.clone(),
            source,
        };
        let mut w = BufWriter::new(fs::File::create(&path).map_err(fail)?);
        write_rays(&mut w, rays)
            .and_then(|()| w.flush())
            .map_err(fail)
    };
    for (kind, recorded) in [("camera", &r.camera), ("bounce", &r.bounce)] {
        rays(
            &format!("{kind}_rays.csv"),
            &mut recorded.iter().map(|(ray, _)| ray),
        )?;
        let hits = Answers::Closest(recorded.iter().map(|(_, hit)| *hit).collect());
        write_answers(&dir.join(format!("{kind}_hits.csv")), &hits)?;
    }
    rays("shadow_rays.csv", &mut r.shadow.iter().map(|s| &s.ray))?;
    let hits = Answers::Any(r.shadow.iter().map(|s| s.occluded).collect());
    write_answers(&dir.join("shadow_hits.csv"), &hits)
}

/// The human summary: what was rendered, rays per second of each kind, the shadow replay.
fn print_summary(r: &RenderReport, out: &mut impl Write) -> std::io::Result<()> {
    let per_second = |n: u64, ms: f64| n as f64 / (ms * 1e-3).max(1e-9);
    writeln!(
        out,
        "{}: {} triangles, {} lights, {}x{} at {} spp, {} bounces, seed {}, {} threads",
        r.scene, r.triangles, r.lights, r.width, r.height, r.spp, r.max_bounces, r.seed, r.threads
    )?;
    writeln!(
        out,
        "structure {}: built in {:.1} ms{}",
        r.structure,
        r.build_ms,
        match (r.light_buffers, r.light_buffers_dropped) {
            (0, 0) if r.influence_areas > 0 => format!(
                " ({} influence areas, {} triangles in their local BVHs)",
                r.influence_areas, r.influence_area_triangles
            ),
            (0, 0) => String::new(),
            (kept, 0) => format!(" ({kept} light buffers)"),
            (kept, dropped) => format!(
                " ({kept} light buffers; {dropped} dropped by the pilot frame's {} shadow rays, \
                 {} of them before building)",
                r.pilot_shadow_rays, r.light_buffers_skipped
            ),
        }
    )?;
    if r.eye_buffer_tests > 0.0 {
        writeln!(
            out,
            "eye buffer {}: the pilot frame's camera rays need {:.2}x the global BVH's tests \
             through it",
            if r.eye_buffer { "kept" } else { "dropped" },
            r.eye_buffer_tests
        )?;
    }
    writeln!(
        out,
        "frame {:.1} ms: rays per second of the frame",
        r.render_ms
    )?;
    for (kind, n) in [
        ("camera", r.camera_rays),
        ("bounce", r.bounce_rays),
        ("shadow", r.shadow_rays),
    ] {
        writeln!(
            out,
            "  {kind:<7} {n:>11} rays  {:>7.2} Mrays/s",
            per_second(n, r.render_ms) * 1e-6
        )?;
    }
    let per_ray = |x: u64| x as f64 / r.shadow_rays.max(1) as f64;
    writeln!(
        out,
        "shadow rays: {:.1} % blocked, {:.2} nodes + {:.2} triangles a ray; replay of {} on one \
         thread {:.1} ms ({:.2} Mrays/s)",
        100.0 * per_ray(r.shadow_occluded),
        per_ray(r.shadow_node_tests),
        per_ray(r.shadow_triangle_tests),
        r.shadow_replay_rays,
        r.shadow_ms,
        per_second(r.shadow_replay_rays as u64, r.shadow_ms) * 1e-6
    )?;
    writeln!(
        out,
        "wrote {} (mean luminance {:.4})",
        r.out, r.mean_luminance
    )
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn vectors_parse_with_signs_and_spaces() {
        assert_eq!(
            parse_vec3("-1, 2.5,3e1").unwrap(),
            Vec3::new(-1.0, 2.5, 30.0)
        );
        for bad in ["1,2", "1,2,3,4", "a,b,c", "nan,0,0", "inf,0,0", ""] {
            assert!(parse_vec3(bad).is_err(), "{bad}");
        }
    }
}
