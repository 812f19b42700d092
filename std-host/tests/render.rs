//! End-to-end tests of `rdbvh render`: determinism across threads and structures, the `--json`
//! contract, recorded rays that replay through `rdbvh trace` and agree with brute force, and
//! one-line errors for bad lights and cameras.

use std::path::{Path, PathBuf};

use rdbvh::cli::read_rays;
use rdbvh::scene::Scene;
use rdbvh_core::brute_force;

mod common;
use common::{rdbvh, shared_scenes, text};

/// A fresh scratch folder for one test of this suite.
fn scratch(name: &str) -> PathBuf {
    common::scratch("render", name)
}

/// The room seen from inside, small and fast.
const ROOM: [&str; 10] = [
    "builtin:room",
    "--eye",
    "5,5,0.3",
    "--look-at",
    "5,4,10",
    "--fov",
    "75",
    "--width",
    "40",
    "--height",
];

/// Renders with `extra` arguments to `png` and returns the `--json` object.
fn render(scene: &[&str], png: &Path, extra: &[&str]) -> serde_json::Value {
    let mut args = vec!["render"];
    args.extend(scene);
    let png = png.to_str().unwrap();
    args.extend(["--out", png, "--json"]);
    args.extend(extra);
    let out = rdbvh(&args);
    assert!(out.status.success(), "{args:?}: {}", text(&out.stderr));
    let stdout = text(&out.stdout);
    let last = stdout.lines().last().expect("a report");
    serde_json::from_str(last).unwrap_or_else(|e| panic!("{e}: {last}"))
}

fn room() -> Vec<&'static str> {
    let mut a = ROOM.to_vec();
    a.extend(["32", "--spp", "2"]);
    a
}

/// Writes a lights file with a point light under the room's ceiling, whose buffer the pilot
/// frame keeps (the room's own ceiling quad is wide next to its shadow segments, and the pilot
/// drops its buffer).
fn point_light_under_the_ceiling(dir: &Path) -> PathBuf {
    let file = dir.join("point.toml");
    std::fs::write(
        &file,
        "[[light]]\nkind = \"point\"\nposition = [5.0, 4.5, 5.0]\nintensity = [20.0, 20.0, 20.0]\n",
    )
    .unwrap();
    file
}

#[test]
fn images_depend_on_the_seed_alone_whatever_the_threads_and_structure() {
    let dir = scratch("determinism");
    // The room's ceiling quad is wide next to its shadow segments, and the pilot frame drops
    // its buffer; a point light under the ceiling keeps one, so that all three structures
    // answer.
    // At 16 samples: at 2, the frame would not repay the buffer's build, and the pilot would
    // build none (`render::pilot::BUILD_TESTS_PER_TRIANGLE`).
    let lights_file = point_light_under_the_ceiling(&dir);
    let mut scene = ROOM.to_vec();
    scene.extend([
        "32",
        "--spp",
        "16",
        "--lights",
        lights_file.to_str().unwrap(),
    ]);
    let one = render(&scene, &dir.join("one.png"), &["--threads", "1"]);
    let two = render(&scene, &dir.join("two.png"), &["--threads", "2"]);
    let lights = render(&scene, &dir.join("lights.png"), &["--structure", "lights"]);
    let thesis = render(&scene, &dir.join("thesis.png"), &["--structure", "thesis"]);
    let other = render(&scene, &dir.join("seed.png"), &["--seed", "2"]);
    let png = |n: &str| std::fs::read(dir.join(n)).unwrap();
    assert_eq!(png("one.png"), png("two.png"));
    assert_eq!(png("one.png"), png("lights.png"));
    assert_eq!(png("one.png"), png("thesis.png"));
    assert_ne!(png("one.png"), png("seed.png"));
    for key in [
        "camera_rays",
        "bounce_rays",
        "shadow_rays",
        "shadow_occluded",
        "mean_luminance",
    ] {
        assert_eq!(one[key], two[key], "{key}");
        assert_eq!(one[key], lights[key], "{key}");
        assert_eq!(one[key], thesis[key], "{key}");
    }
    assert_eq!(thesis["structure"], "thesis");
    assert!(
        thesis["influence_areas"].as_u64().unwrap() > 2,
        "the room's emissive quad (a box on each side) and the point light's frustums"
    );
    assert_eq!(one["influence_areas"], 0);
    assert_ne!(one["mean_luminance"], other["mean_luminance"]);
    assert_eq!(one["structure"], "global");
    assert_eq!(lights["structure"], "lights");
    assert_eq!(one["light_buffers"], 0);
    assert!(lights["light_buffers"].as_u64().unwrap() >= 1);
    for j in [&one, &lights, &thesis] {
        let (all, global) = (
            j["build_ms"].as_f64().unwrap(),
            j["global_build_ms"].as_f64().unwrap(),
        );
        let pilot = j["pilot_ms"].as_f64().unwrap();
        assert!(
            global > 0.0 && global + pilot <= all,
            "the global BVH's and the pilot's parts of the build: {j}"
        );
    }
    assert!(
        lights["pilot_ms"].as_f64().unwrap() > 0.0,
        "lights renders a pilot frame"
    );
    assert_eq!(one["pilot_ms"].as_f64(), Some(0.0), "global renders none");
    // The point light's buffer saves triangle tests on the room's shadow rays.
    assert!(lights["shadow_triangle_tests"].as_u64() < one["shadow_triangle_tests"].as_u64());
}

/// `lights` answers its shadow segments in batches of several tiles (as many as make a batch,
/// at most a quarter of a thread's share of the tiles): the batches differ with the threads, and
/// the image and the counts do not.
#[test]
fn batches_of_tiles_change_neither_the_image_nor_the_counts() {
    let dir = scratch("batches");
    let lights_file = point_light_under_the_ceiling(&dir);
    // 6 x 4 tiles: batches of 6 tiles on one thread, of 3 on two.
    let mut scene = ROOM[..7].to_vec();
    scene.extend(["--width", "96", "--height", "64", "--spp", "2"]);
    scene.extend(["--lights", lights_file.to_str().unwrap()]);
    let global = render(&scene, &dir.join("g.png"), &["--threads", "1"]);
    let one = render(
        &scene,
        &dir.join("l1.png"),
        &["--structure", "lights", "--threads", "1"],
    );
    let two = render(
        &scene,
        &dir.join("l2.png"),
        &["--structure", "lights", "--threads", "2"],
    );
    assert!(one["light_buffers"].as_u64().unwrap() >= 1);
    let png = |n: &str| std::fs::read(dir.join(n)).unwrap();
    assert_eq!(png("g.png"), png("l1.png"));
    assert_eq!(png("g.png"), png("l2.png"));
    for key in [
        "shadow_rays",
        "shadow_occluded",
        "shadow_node_tests",
        "shadow_triangle_tests",
    ] {
        assert_eq!(one[key], two[key], "{key}");
    }
    assert_eq!(global["shadow_occluded"], one["shadow_occluded"]);
}

#[test]
fn json_has_the_contract_keys() {
    let dir = scratch("json");
    let json = render(&room(), &dir.join("r.png"), &["--max-bounces", "0"]);
    for key in [
        "width",
        "height",
        "spp",
        "structure",
        "build_ms",
        "global_build_ms",
        "pilot_ms",
        "render_ms",
        "camera_rays",
        "shadow_rays",
        "bounce_rays",
        "shadow_node_tests",
        "shadow_triangle_tests",
        "shadow_ms",
        "mean_luminance",
        "scene",
        "triangles",
        "lights",
        "max_bounces",
        "seed",
        "threads",
        "light_buffers",
        "light_buffers_dropped",
        "light_buffers_skipped",
        "pilot_shadow_rays",
        "influence_areas",
        "influence_area_triangles",
        "eye_buffer",
        "eye_buffer_tests",
    ] {
        assert!(json.get(key).is_some(), "{key} missing: {json}");
    }
    assert_eq!(json["width"], 40);
    assert_eq!(json["height"], 32);
    assert_eq!(json["camera_rays"], 40 * 32 * 2);
    assert_eq!(
        json["bounce_rays"], 0,
        "--max-bounces 0 is direct light only"
    );
    assert!(json["mean_luminance"].as_f64().unwrap() > 0.0);
    let png = image::open(dir.join("r.png")).unwrap();
    assert_eq!((png.width(), png.height()), (40, 32));
}

/// Without `--eye` and `--look-at` the closed room is seen from its own view, inside, exactly as
/// with that view given (framed from outside it would show only its unlit outer walls).
#[test]
fn a_scene_without_a_camera_uses_its_own_view() {
    let dir = scratch("own-view");
    let small = ["--width", "40", "--height", "32", "--spp", "2"];
    let own = render(
        &["builtin:room", "--fov", "75"],
        &dir.join("own.png"),
        &small,
    );
    let given = render(&ROOM[..7], &dir.join("given.png"), &small);
    assert!(own["mean_luminance"].as_f64().unwrap() > 0.05, "{own}");
    assert!(own["shadow_rays"].as_u64().unwrap() > 0, "{own}");
    assert_eq!(
        std::fs::read(dir.join("own.png")).unwrap(),
        std::fs::read(dir.join("given.png")).unwrap()
    );
    assert_eq!(own["mean_luminance"], given["mean_luminance"]);
}

#[test]
fn recorded_rays_replay_through_trace_and_agree_with_brute_force() {
    let dir = scratch("record");
    let rays = dir.join("rays");
    let json = render(
        &room(),
        &dir.join("r.png"),
        &[
            "--record-rays",
            rays.to_str().unwrap(),
            "--record-limit",
            "500",
        ],
    );
    let scene = Scene::open("builtin:room").unwrap();
    for kind in ["camera", "bounce", "shadow"] {
        let file = rays.join(format!("{kind}_rays.csv"));
        let recorded = read_rays(&file).unwrap();
        assert_eq!(recorded.len(), 500, "{kind}");
        let hits = std::fs::read_to_string(rays.join(format!("{kind}_hits.csv"))).unwrap();
        let rows: Vec<&str> = hits.lines().skip(1).collect();
        assert_eq!(rows.len(), 500);
        for (ray, row) in recorded.iter().zip(&rows) {
            let cells: Vec<&str> = row.split(',').collect();
            if kind == "shadow" {
                assert_eq!(
                    cells[1] == "1",
                    brute_force::any_hit(ray, &scene.triangles),
                    "{row}"
                );
            } else {
                let truth = brute_force::closest_hit(ray, &scene.triangles);
                assert_eq!(
                    cells[2].parse::<u32>().ok(),
                    truth.map(|h| h.triangle),
                    "{row}"
                );
            }
        }
        // `rdbvh trace` answers the recorded rays with the same bytes.
        let replay = dir.join(format!("{kind}_replay.csv"));
        let mut args = vec!["trace", "builtin:room", "--rays", file.to_str().unwrap()];
        args.extend(["--out", replay.to_str().unwrap()]);
        if kind == "shadow" {
            args.push("--any-hit");
        }
        let out = rdbvh(&args);
        assert!(out.status.success(), "{}", text(&out.stderr));
        assert_eq!(std::fs::read_to_string(&replay).unwrap(), hits, "{kind}");
    }
    assert!(json["shadow_rays"].as_u64().unwrap() >= 500);
}

/// Runs `render` with `args` and returns its one-line error.
fn error_of(args: &[&str]) -> String {
    let out = rdbvh(args);
    assert!(!out.status.success(), "{args:?} succeeded");
    let err = text(&out.stderr);
    assert_eq!(err.lines().count(), 1, "{err}");
    assert!(!err.contains("panicked"), "{err}");
    err
}

#[test]
fn bad_lights_cameras_and_scenes_are_one_line_errors() {
    let dir = scratch("errors");
    let lights = dir.join("lights.toml");
    let out = dir.join("x.png");
    let (l, o) = (lights.to_str().unwrap(), out.to_str().unwrap());
    for (file, expected) in [
        (
            "[[light]]\nkind = \"laser\"\n",
            "light 0: unknown kind `laser`",
        ),
        (
            "[[light]]\nkind = \"spot\"\nposition = [5, 9, 5]\ndirection = [0, -1, 0]\n\
             angle_deg = 95\nintensity = [1, 1, 1]\n",
            "light 0 (spot): `angle_deg` must be in (0, 90], got 95",
        ),
        (
            "[[light]]\nkind = \"quad\"\ncorner = [0, 0, 0]\nedge1 = [1, 0, 0]\n\
             edge2 = [-1, 0, 0]\nradiance = [1, 1, 1]\n",
            "light 0 (quad): `edge1` [1, 0, 0] and `edge2` [-1, 0, 0] span no area",
        ),
        (
            "[[light]]\nkind = \"point\"\nposition = [5, 5, 5]\n",
            "missing field `intensity`",
        ),
        ("not toml [", "lights file"),
    ] {
        std::fs::write(&lights, file).unwrap();
        let err = error_of(&["render", "builtin:room", "--lights", l, "--out", o]);
        assert!(err.contains(expected), "{file:?}: {err}");
    }
    let missing = dir.join("missing.toml");
    let err = error_of(&[
        "render",
        "builtin:room",
        "--lights",
        missing.to_str().unwrap(),
        "--out",
        o,
    ]);
    assert!(err.contains("cannot read lights file"), "{err}");
    std::fs::write(&lights, "").unwrap();
    let err = error_of(&["render", "builtin:random100", "--lights", l, "--out", o]);
    assert!(
        err.contains("has no light") && err.contains("holds no [[light]]"),
        "{err}"
    );
    let err = error_of(&["render", "builtin:random100", "--out", o]);
    assert!(err.contains("no --lights file was given"), "{err}");
    // A light whose power rounds to zero is dropped, and the error says so.
    std::fs::write(
        &lights,
        "[[light]]\nkind = \"spot\"\nposition = [5, 9, 5]\ndirection = [0, -1, 0]\n\
         angle_deg = 1e-30\nintensity = [1, 1, 1]\n",
    )
    .unwrap();
    let err = error_of(&["render", "builtin:random100", "--lights", l, "--out", o]);
    assert!(err.contains("no light of positive power"), "{err}");
    // A light too bright for f32: no image, rather than an image of infinities.
    std::fs::write(
        &lights,
        "[[light]]\nkind = \"point\"\nposition = [5, 5, 5]\nintensity = [3e38, 3e38, 3e38]\n",
    )
    .unwrap();
    let err = error_of(&[
        "render",
        "builtin:room",
        "--lights",
        l,
        "--width",
        "8",
        "--height",
        "8",
        "--spp",
        "1",
        "--out",
        o,
    ]);
    assert!(err.contains("radiance overflows single precision"), "{err}");
    assert!(!out.exists());
    let err = error_of(&["render", "builtin:room", "--threads", "5000", "--out", o]);
    assert!(err.contains("--threads"), "{err}");
    let err = error_of(&[
        "render",
        "builtin:room",
        "--eye",
        "1,2,3",
        "--look-at",
        "1,2,3",
        "--out",
        o,
    ]);
    assert!(err.contains("--look-at"), "{err}");
    let err = error_of(&["render", "builtin:room", "--fov", "0", "--out", o]);
    assert!(err.contains("--fov"), "{err}");
    let err = error_of(&["render", "builtin:room", "--eye", "1,nan,3", "--out", o]);
    assert!(err.contains("--eye"), "{err}");
    let err = error_of(&["render", "builtin:room", "--out", dir.to_str().unwrap()]);
    assert!(err.contains("folder"), "{err}");
    assert!(!out.exists(), "no image is written on an error");
}

#[test]
fn cornell_box_with_every_light_kind_is_identical_across_structures() {
    let Some(scenes) = shared_scenes("cornell_box_with_every_light_kind") else {
        return;
    };
    let dir = scratch("cornell");
    let lights = dir.join("lights.toml");
    std::fs::write(
        &lights,
        "[[light]]\nkind = \"point\"\nposition = [0.5, 1.5, 0.3]\nintensity = [1, 1, 1]\n\
         [[light]]\nkind = \"spot\"\nposition = [-0.5, 1.8, 0.5]\ndirection = [0.3, -1, -0.4]\n\
         angle_deg = 25\nintensity = [3, 2, 1]\n\
         [[light]]\nkind = \"quad\"\ncorner = [-0.9, 0.2, -1.0]\nedge1 = [0, 0.4, 0]\n\
         edge2 = [0.3, 0, 0]\nradiance = [0, 2, 4]\n",
    )
    .unwrap();
    let obj = scenes.join("cornell_box.obj");
    let scene = [
        obj.to_str().unwrap(),
        "--width",
        "48",
        "--height",
        "48",
        "--spp",
        "2",
    ];
    let l = ["--lights", lights.to_str().unwrap()];
    let global = render(&scene, &dir.join("g.png"), &l);
    let mut args = l.to_vec();
    args.extend(["--structure", "lights"]);
    let buffered = render(&scene, &dir.join("l.png"), &args);
    assert_eq!(
        std::fs::read(dir.join("g.png")).unwrap(),
        std::fs::read(dir.join("l.png")).unwrap()
    );
    assert_eq!(
        global["lights"], 5,
        "2 emissive triangles and 3 lights from the file"
    );
    assert_eq!(global["shadow_occluded"], buffered["shadow_occluded"]);
    assert!(global["mean_luminance"].as_f64().unwrap() > 0.01);
    // The thesis's structure: the same image, and its recorded shadow answers are brute force's.
    let rays = dir.join("rays");
    let mut args = l.to_vec();
    let limit = "3000";
    args.extend(["--structure", "thesis", "--record-rays"]);
    args.extend([rays.to_str().unwrap(), "--record-limit", limit]);
    let thesis = render(&scene, &dir.join("t.png"), &args);
    assert_eq!(
        std::fs::read(dir.join("g.png")).unwrap(),
        std::fs::read(dir.join("t.png")).unwrap()
    );
    assert_eq!(global["shadow_occluded"], thesis["shadow_occluded"]);
    // Six faces of the point light (those that see the box), one spot frustum, one quad box,
    // and boxes on the sides of the emissive light that face the box.
    assert!(thesis["influence_areas"].as_u64().unwrap() >= 5, "{thesis}");
    let triangles = Scene::open(obj.to_str().unwrap()).unwrap().triangles;
    let recorded = read_rays(&rays.join("shadow_rays.csv")).unwrap();
    let hits = std::fs::read_to_string(rays.join("shadow_hits.csv")).unwrap();
    let rows: Vec<&str> = hits.lines().skip(1).collect();
    assert_eq!(recorded.len(), rows.len());
    assert_eq!(recorded.len(), 3000);
    for (ray, row) in recorded.iter().zip(&rows) {
        let blocked = row.split(',').nth(1) == Some("1");
        assert_eq!(blocked, brute_force::any_hit(ray, &triangles), "{row}");
    }
}

/// Sibenik seen down its nave: the pilot keeps the eye buffer (its camera rays need about 0.6x
/// the global BVH's tests through it), the image is the global BVH's byte for byte, and the
/// recorded camera hits, answered through the eye buffer, are brute force's.
#[test]
fn the_eye_buffer_answers_camera_rays_as_brute_force_does() {
    let Some(scenes) = shared_scenes("the_eye_buffer_answers_camera_rays_as_brute_force_does")
    else {
        return;
    };
    let dir = scratch("eye");
    let obj = scenes.join("sibenik.obj");
    // 64 x 64 at 128 samples: enough camera rays to repay the buffer's build.
    let scene = [
        obj.to_str().unwrap(),
        "--eye",
        "1200,300,100",
        "--look-at",
        "-1000,300,100",
        "--fov",
        "70",
        "--width",
        "64",
        "--height",
        "64",
        "--spp",
        "128",
        "--max-bounces",
        "0",
    ];
    let global = render(&scene, &dir.join("g.png"), &[]);
    let rays = dir.join("rays");
    let lights = render(
        &scene,
        &dir.join("l.png"),
        &[
            "--structure",
            "lights",
            "--record-rays",
            rays.to_str().unwrap(),
            "--record-limit",
            "2000",
        ],
    );
    assert_eq!(lights["eye_buffer"], true, "{lights}");
    assert!(
        lights["eye_buffer_tests"].as_f64().unwrap() <= 0.7,
        "{lights}"
    );
    assert_eq!(global["eye_buffer"], false);
    assert_eq!(
        std::fs::read(dir.join("g.png")).unwrap(),
        std::fs::read(dir.join("l.png")).unwrap()
    );
    let triangles = Scene::open(obj.to_str().unwrap()).unwrap().triangles;
    let recorded = read_rays(&rays.join("camera_rays.csv")).unwrap();
    let hits = std::fs::read_to_string(rays.join("camera_hits.csv")).unwrap();
    let rows: Vec<&str> = hits.lines().skip(1).collect();
    assert_eq!((recorded.len(), rows.len()), (2000, 2000));
    for (ray, row) in recorded.iter().zip(&rows) {
        let truth = brute_force::closest_hit(ray, &triangles);
        let cells: Vec<&str> = row.split(',').collect();
        assert_eq!(
            cells[2].parse::<u32>().ok(),
            truth.map(|h| h.triangle),
            "{row}"
        );
        assert_eq!(cells[1].parse::<f32>().ok(), truth.map(|h| h.t), "{row}");
    }
}

/// The pilot frame drops the Cornell box's buffer: its quad light is large next to the box, so
/// the buffer's cells hold most of the triangles and save too few tests (README, headline table).
/// The image stays the global BVH's.
#[test]
fn the_pilot_drops_a_buffer_that_does_not_pay() {
    let Some(scenes) = shared_scenes("the_pilot_drops_a_buffer_that_does_not_pay") else {
        return;
    };
    let dir = scratch("pilot");
    let obj = scenes.join("cornell_box.obj");
    let scene = [
        obj.to_str().unwrap(),
        "--width",
        "512",
        "--height",
        "512",
        "--spp",
        "1",
    ];
    let global = render(&scene, &dir.join("global.png"), &["--structure", "global"]);
    let lights = render(&scene, &dir.join("lights.png"), &["--structure", "lights"]);
    assert_eq!(global["pilot_shadow_rays"], 0);
    assert!(
        lights["pilot_shadow_rays"].as_u64().unwrap() > 1000,
        "{lights}"
    );
    assert_eq!(
        (
            lights["light_buffers"].as_u64(),
            lights["light_buffers_dropped"].as_u64()
        ),
        (Some(0), Some(1))
    );
    assert_eq!(global["shadow_node_tests"], lights["shadow_node_tests"]);
    let png = |n: &str| std::fs::read(dir.join(n)).unwrap();
    assert_eq!(png("global.png"), png("lights.png"));
    std::fs::remove_dir_all(&dir).ok();
}

/// A wall lit by an emissive quad over a small occluder, as OBJ text with every coordinate
/// times `scale`.
fn lit_wall(scale: f32) -> String {
    let quads: [(&str, [[f32; 3]; 4]); 3] = [
        (
            "wall",
            [
                [-1.0, -1.0, 0.0],
                [1.0, -1.0, 0.0],
                [1.0, 1.0, 0.0],
                [-1.0, 1.0, 0.0],
            ],
        ),
        (
            "wall",
            [
                [-0.3, -0.3, 0.3],
                [0.3, -0.3, 0.3],
                [0.3, 0.3, 0.3],
                [-0.3, 0.3, 0.3],
            ],
        ),
        (
            "light",
            [
                [-0.2, 0.6, 0.8],
                [0.2, 0.6, 0.8],
                [0.2, 0.9, 0.8],
                [-0.2, 0.9, 0.8],
            ],
        ),
    ];
    let mut obj = String::from("mtllib lit_wall.mtl\n");
    for (i, (material, corners)) in quads.iter().enumerate() {
        obj += &format!("usemtl {material}\n");
        for c in corners {
            obj += &format!("v {} {} {}\n", c[0] * scale, c[1] * scale, c[2] * scale);
        }
        let k = 4 * i + 1;
        obj += &format!("f {} {} {}\nf {} {} {}\n", k, k + 1, k + 2, k, k + 2, k + 3);
    }
    obj
}

/// Light, shading normals, the default camera and every offset are relative to the scene:
/// the same scene at 2^-33 (about 1e-10) and 2^33 (about 1e10) units renders as at one unit.
/// (A normal's and an area's length square the edges' cross product, about the fourth power
/// of the scale: past about 4e9 units that overflowed f32, and paths ended at every hit.)
#[test]
fn a_scene_renders_alike_at_any_scale_inside_the_documented_range() {
    let dir = scratch("scale");
    std::fs::write(
        dir.join("lit_wall.mtl"),
        "newmtl wall\nKd 0.8 0.8 0.8\nnewmtl light\nKd 0 0 0\nKe 20 20 20\n",
    )
    .unwrap();
    let mut reports = Vec::new();
    for (name, scale) in [
        ("one", 1.0),
        ("tiny", 2f32.powi(-33)),
        ("huge", 2f32.powi(33)),
    ] {
        let obj = dir.join(format!("{name}.obj"));
        std::fs::write(&obj, lit_wall(scale)).unwrap();
        let png = dir.join(format!("{name}.png"));
        let args = [
            "--width",
            "24",
            "--height",
            "24",
            "--spp",
            "2",
            "--max-bounces",
            "1",
        ];
        reports.push(render(&[obj.to_str().unwrap()], &png, &args));
    }
    let one = &reports[0];
    assert!(one["mean_luminance"].as_f64().unwrap() > 0.01, "{one}");
    for other in &reports[1..] {
        for key in [
            "camera_rays",
            "shadow_rays",
            "bounce_rays",
            "shadow_occluded",
        ] {
            assert_eq!(one[key], other[key], "{key}: {other}");
        }
        let (a, b) = (
            one["mean_luminance"].as_f64().unwrap(),
            other["mean_luminance"].as_f64().unwrap(),
        );
        assert!((a - b).abs() <= 1e-5 * a, "{a} against {b}");
    }
}
