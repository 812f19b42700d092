//! End-to-end tests of the `rdbvh` binary: the output contracts scripts rely on, one-line errors,
//! and `trace` answers (with one BVH, and through the scene structure of influence areas) checked
//! against the brute-force oracle on built-in and real scenes.

use std::path::{Path, PathBuf};
use std::process::Output;

use rdbvh::scene::{Mt19937, Scene};
use rdbvh_core::brute_force;
use rdbvh_core::geometry::Ray;
use rdbvh_core::influence::{InfluenceArea, PointDistribution, RaySampler};
use rdbvh_core::Vec3;

mod common;
use common::{rdbvh, shared_scenes, text};

/// A fresh scratch folder for one test of this suite.
fn scratch(name: &str) -> PathBuf {
    common::scratch("cli", name)
}

#[test]
fn build_json_has_the_contract_keys() {
    let out = rdbvh(&["build", "builtin:random1000", "--json", "--max-leaf", "4"]);
    assert!(out.status.success(), "{}", text(&out.stderr));
    let stdout = text(&out.stdout);
    assert_eq!(stdout.lines().count(), 1, "one JSON object: {stdout}");
    let json: serde_json::Value = serde_json::from_str(&stdout).unwrap();
    for key in [
        "triangles",
        "nodes",
        "max_depth",
        "sah_cost",
        "bytes",
        "build_ms",
        "leaves",
        "mtris_per_s",
        "builder",
        "bins",
        "max_leaf",
    ] {
        assert!(json.get(key).is_some(), "missing {key}: {stdout}");
    }
    assert_eq!(json["triangles"], 1000);
    assert_eq!(json["max_leaf"], 4);
    assert_eq!(json["builder"], "sah");
    let nodes = json["nodes"].as_u64().unwrap();
    let leaves = json["leaves"].as_u64().unwrap();
    assert_eq!(nodes, 2 * leaves - 1, "a binary tree");
    assert_eq!(json["bytes"], nodes * 32 + 1000 * 4);
    assert!(json["sah_cost"].as_f64().unwrap() > 1.0);
    // The help lists exactly these keys.
    let help = text(&rdbvh(&["build", "--help"]).stdout).replace('\n', " ");
    let listed = help
        .split("--json prints one object with the keys ")
        .nth(1)
        .and_then(|rest| rest.split(" (null where").next())
        .unwrap();
    let mut listed: Vec<String> = listed
        .split(", ")
        .map(|k| k.split(' ').next().unwrap().to_string())
        .collect();
    listed.sort();
    let mut keys: Vec<String> = json.as_object().unwrap().keys().cloned().collect();
    keys.sort();
    assert_eq!(listed, keys);
}

#[test]
fn build_reinsert_reports_and_never_costs_more() {
    let plain = json_of(&rdbvh(&["build", "builtin:random1000", "--json"]));
    let better = json_of(&rdbvh(&[
        "build",
        "builtin:random1000",
        "--json",
        "--reinsert",
    ]));
    assert!(plain["reinsert_ms"].is_null() && plain["reinsert_moved"].is_null());
    assert!(better["reinsert_ms"].as_f64().unwrap() >= 0.0, "{better}");
    assert!(better["reinsert_moved"].as_u64().is_some(), "{better}");
    let cost = |j: &serde_json::Value| j["sah_cost"].as_f64().unwrap();
    assert!(
        cost(&better) <= cost(&plain) * (1.0 + 1e-6),
        "{plain} vs {better}"
    );
    assert_eq!(better["nodes"], plain["nodes"]);
    let table = text(&rdbvh(&["build", "builtin:room", "--reinsert"]).stdout);
    assert!(table.contains("reinsert "), "{table}");
}

#[test]
fn build_table_and_builders() {
    let sah = rdbvh(&["build", "builtin:room"]);
    let lsph = rdbvh(&["build", "builtin:room", "--builder", "lsph", "--bins", "8"]);
    for out in [&sah, &lsph] {
        assert!(out.status.success(), "{}", text(&out.stderr));
        let s = text(&out.stdout);
        for label in [
            "triangles",
            "nodes",
            "leaves",
            "max depth",
            "SAH cost",
            "bytes",
            "Mtris/s",
        ] {
            assert!(s.contains(label), "{label} missing: {s}");
        }
    }
    assert!(text(&lsph.stdout).contains("lsph (8 bins"));
}

/// `--builder sbvh` builds with spatial splits (the room's long wall and floor quads split, so
/// the tree holds more references than triangles), and `--perspective-estimate` builds a point
/// area's PAH tree whose exact PAH cost stays near the exact build's (the room's bulb sits among
/// boxes close to it, where the centre estimate errs most: 1.06x).
#[test]
fn build_sbvh_and_the_perspective_estimate() {
    let sah = json_of(&rdbvh(&["build", "builtin:room", "--json"]));
    let sbvh = json_of(&rdbvh(&[
        "build",
        "builtin:room",
        "--builder",
        "sbvh",
        "--json",
    ]));
    assert_eq!(sbvh["builder"], "sbvh");
    let cost = |j: &serde_json::Value| j["sah_cost"].as_f64().unwrap();
    assert!(cost(&sbvh) < cost(&sah), "SBVH {sbvh} against SAH {sah}");
    let references = (sbvh["bytes"].as_u64().unwrap() - sbvh["nodes"].as_u64().unwrap() * 32) / 4;
    assert!(references > sbvh["triangles"].as_u64().unwrap(), "{sbvh}");

    let dir = scratch("perspective-estimate");
    let areas = dir.join("point.toml");
    let point = ROOM_AREAS.split("[[area]]").nth(2).unwrap();
    std::fs::write(&areas, format!("[[area]]{point}")).unwrap();
    let areas = areas.to_str().unwrap();
    let args = [
        "build",
        "builtin:room",
        "--preset",
        "pah",
        "--areas",
        areas,
        "--json",
    ];
    let exact = json_of(&rdbvh(&args));
    let estimate = json_of(&rdbvh(&[&args[..], &["--perspective-estimate"]].concat()));
    assert_eq!(exact["area_kind"], "point");
    let pah = |j: &serde_json::Value| j["pah_cost"].as_f64().unwrap();
    let ratio = pah(&estimate) / pah(&exact);
    assert!((0.9..1.15).contains(&ratio), "{estimate} against {exact}");
    // Without a preset the flag would change nothing: a usage error, before loading anything.
    let args = ["build", "builtin:room", "--perspective-estimate"];
    assert_one_line_error(
        &rdbvh(&args),
        2,
        &["--perspective-estimate", "--preset"],
        &args,
    );
}

#[test]
fn demo_runs_and_checks_itself() {
    let out = rdbvh(&[]);
    assert!(out.status.success(), "{}", text(&out.stderr));
    assert!(text(&out.stdout).contains("agree with brute force"));
}

/// Every failure: non-zero exit, exactly one `error: ` line on stderr, no panic.
#[test]
fn errors_are_one_line() {
    let dir = scratch("errors");
    let bad_rays = dir.join("bad.csv");
    std::fs::write(&bad_rays, "ox,oy,oz,dx,dy,dz\n0,0,0,1,0,0\n0,0,0,x,0,0\n").unwrap();
    let bad_obj = dir.join("bad.obj");
    std::fs::write(&bad_obj, "v 0 0 0\nv 1 0 0\nf 1 2 3\n").unwrap();
    let empty_obj = dir.join("empty.obj");
    std::fs::write(&empty_obj, "# nothing\n").unwrap();
    let out_csv = dir.join("hits.csv");
    let (bad_rays, out_csv) = (bad_rays.to_str().unwrap(), out_csv.to_str().unwrap());
    for (args, needle) in [
        (
            vec!["build", "/nonexistent/scene.obj"],
            "/nonexistent/scene.obj",
        ),
        (vec!["build", bad_obj.to_str().unwrap()], "line 3"),
        (vec!["build", empty_obj.to_str().unwrap()], "no triangles"),
        (vec!["build", "builtin:nope"], "builtin:room"),
        (vec!["build", "builtin:room", "--bins", "65"], "--bins"),
        (vec!["build", "builtin:room", "--builder", "x"], "--builder"),
        (vec!["build"], "SCENE"),
        (vec!["trace", "builtin:room", "--rays", bad_rays], "--out"),
        (
            vec![
                "trace",
                "builtin:room",
                "--rays",
                bad_rays,
                "--out",
                out_csv,
            ],
            "line 3",
        ),
        (
            vec![
                "trace",
                "builtin:room",
                "--rays",
                "/nonexistent.csv",
                "--out",
                out_csv,
            ],
            "/nonexistent.csv",
        ),
        (vec!["frobnicate"], "frobnicate"),
    ] {
        let out = rdbvh(&args);
        let stderr = text(&out.stderr);
        assert!(!out.status.success(), "{args:?} succeeded");
        assert_eq!(stderr.lines().count(), 1, "{args:?}: {stderr}");
        assert!(stderr.starts_with("error: "), "{args:?}: {stderr}");
        assert!(stderr.contains(needle), "{args:?}: {stderr}");
        assert!(!stderr.contains("panicked"), "{args:?}: {stderr}");
    }
    std::fs::remove_dir_all(&dir).ok();
}

/// Random rays for a scene: origins in and around its bounds, directions on the sphere, and on
/// every third ray a finite segment.
fn random_rays(scene: &Scene, n: usize, seed: u32) -> Vec<[f32; 8]> {
    let mut rng = Mt19937::new(seed);
    let mut u = move || rng.canonical_f64() as f32;
    let b = scene.bounds;
    (0..n)
        .map(|i| {
            let o = b.min - b.extent() * 0.1 + b.extent() * 1.2 * Vec3::new(u(), u(), u());
            let mut d = Vec3::new(u() - 0.5, u() - 0.5, u() - 0.5);
            if i % 7 == 0 {
                // Axis-parallel rays.
                d = Vec3::new(d.x, 0.0, 0.0);
            }
            let (t_min, t_max) = if i % 3 == 0 {
                (u() * 0.1, u() * 10.0)
            } else {
                (0.0, f32::INFINITY)
            };
            [o.x, o.y, o.z, d.x, d.y, d.z, t_min, t_max]
        })
        .filter(|r| r[3] != 0.0 || r[4] != 0.0 || r[5] != 0.0)
        .collect()
}

/// Writes `rays` (`[ox, oy, oz, dx, dy, dz, tmin, tmax]`) as CSV, columns out of the documented
/// order to check they are found by name, and returns the rays as the CLI reads them.
fn write_rays(path: &Path, rays: &[[f32; 8]]) -> Vec<Ray> {
    let mut csv = String::from("tmax,dx,dy,dz,ox,oy,oz,tmin\n");
    for r in rays {
        csv += &format!(
            "{},{},{},{},{},{},{},{}\n",
            r[7], r[3], r[4], r[5], r[0], r[1], r[2], r[6]
        );
    }
    std::fs::write(path, csv).unwrap();
    rays.iter()
        .map(|r| {
            Ray::segment(
                Vec3::new(r[0], r[1], r[2]),
                Vec3::new(r[3], r[4], r[5]),
                r[6],
                r[7],
            )
            .unwrap()
        })
        .collect()
}

/// Checks the answers file `hits_csv` against brute force for every ray, exactly; returns how
/// many rays hit.
fn assert_answers(
    hits_csv: &Path,
    rays: &[Ray],
    scene: &Scene,
    any_hit: bool,
    label: &str,
) -> usize {
    let answers = std::fs::read_to_string(hits_csv).unwrap();
    let mut lines = answers.lines();
    let header = lines.next().unwrap();
    assert_eq!(
        header,
        if any_hit {
            "ray,hit"
        } else {
            "ray,t,triangle,u,v"
        }
    );
    let mut count = 0;
    let mut hits = 0;
    for (i, (line, ray)) in lines.zip(rays).enumerate() {
        let f: Vec<&str> = line.split(',').collect();
        assert_eq!(f[0], i.to_string(), "rays stay in input order");
        if any_hit {
            let expected = brute_force::any_hit(ray, &scene.triangles);
            assert_eq!(f[1], if expected { "1" } else { "0" }, "{label} ray {i}");
            hits += usize::from(expected);
        } else {
            match brute_force::closest_hit(ray, &scene.triangles) {
                None => assert_eq!(&f[1..], ["", "", "", ""], "{label} ray {i}"),
                Some(h) => {
                    let t: f32 = f[1].parse().unwrap();
                    let tri: u32 = f[2].parse().unwrap();
                    let u: f32 = f[3].parse().unwrap();
                    let v: f32 = f[4].parse().unwrap();
                    assert_eq!(
                        (t, tri, u, v),
                        (h.t, h.triangle, h.u, h.v),
                        "{label} ray {i}"
                    );
                    hits += 1;
                }
            }
        }
        count += 1;
    }
    assert_eq!(count, rays.len(), "{label}");
    hits
}

/// Runs `trace` on `scene_arg` for closest and any hit, on the built tree and on the reinserted
/// one, and compares every answer with brute force, exactly.
fn check_trace(scene_arg: &str, rays_count: usize) {
    let scene = Scene::open(scene_arg).unwrap();
    let rays = random_rays(&scene, rays_count, 7);
    let dir = scratch(&scene.name.replace(['/', ':'], "_"));
    let rays_csv = dir.join("rays.csv");
    let rays = write_rays(&rays_csv, &rays);

    for (any_hit, reinsert) in [(false, false), (true, false), (false, true), (true, true)] {
        let hits_csv = dir.join(if any_hit { "any.csv" } else { "closest.csv" });
        let mut args = vec![
            "trace",
            scene_arg,
            "--rays",
            rays_csv.to_str().unwrap(),
            "--out",
            hits_csv.to_str().unwrap(),
        ];
        if any_hit {
            args.push("--any-hit");
        }
        if reinsert {
            args.push("--reinsert");
        }
        let out = rdbvh(&args);
        assert!(out.status.success(), "{}", text(&out.stderr));
        assert!(
            text(&out.stderr).contains("rays/s"),
            "{}",
            text(&out.stderr)
        );
        let hits = assert_answers(&hits_csv, &rays, &scene, any_hit, scene_arg);
        assert!(
            hits > 0 && hits < rays.len(),
            "{scene_arg}: {hits} of {} rays hit",
            rays.len()
        );
    }
    std::fs::remove_dir_all(&dir).ok();
}

#[test]
fn trace_agrees_with_brute_force_on_builtin_scenes() {
    check_trace("builtin:room", 3000);
    check_trace("builtin:random1000", 3000);
}

#[test]
fn trace_agrees_with_brute_force_on_real_scenes() {
    let Some(dir) = shared_scenes("trace_agrees_with_brute_force_on_real_scenes") else {
        return;
    };
    for file in [
        "cornell_box.obj",
        "teapot.obj",
        "thesis/MonkeyModel.obj",
        "thesis/WoodScene.obj",
        "bunny.obj",
    ] {
        check_trace(dir.join(file).to_str().unwrap(), 3000);
    }
}

#[test]
fn real_scenes_build_and_load_their_lights() {
    let Some(dir) = shared_scenes("real_scenes_build_and_load_their_lights") else {
        return;
    };
    // (file, triangles from MANIFEST.tsv, emissive triangles from the README)
    for (file, triangles, emissive) in [
        ("cornell_box.obj", 36, 2),
        ("sibenik.obj", 76_529, 1_719),
        ("thesis/Cube.obj", 44, 0),
        ("thesis/Random100.obj", 100, 0),
    ] {
        let path = dir.join(file);
        let scene = Scene::load(&path).unwrap();
        assert_eq!(scene.len(), triangles, "{file}");
        assert_eq!(scene.emissive_count(), emissive, "{file}");
        let out = rdbvh(&["build", path.to_str().unwrap(), "--json"]);
        assert!(out.status.success(), "{file}: {}", text(&out.stderr));
        let json: serde_json::Value = serde_json::from_slice(&out.stdout).unwrap();
        assert_eq!(json["triangles"], triangles, "{file}");
    }
    // The Cube's .mtl was never shipped: a warning on stderr, and the build still succeeds.
    let out = rdbvh(&["build", dir.join("thesis/Cube.obj").to_str().unwrap()]);
    assert!(out.status.success());
    assert!(
        text(&out.stderr).starts_with("warning: "),
        "{}",
        text(&out.stderr)
    );
}

/// Two influence areas in the built-in room: the light's parallel rays (an `experiments.toml`
/// entry pasted with its experiment keys) and a tilted spot light's radial rays.
const ROOM_AREAS: &str = r#"
[[area]]
scene = "Room"
kind = "plane"
orientation = "parallel"
center = [5.0, 9.9, 5.0]
normal = [0, -1, 0]
half_width = 1.0
half_height = 1.0
depth = 9.9
thesis_test = "Room_Plane"

[[area]]
kind = "point"
eye = [5.0, 9.5, 5.0]
direction = [0.2, -1.0, 0.1]
fov_x_deg = 90.0
fov_y_deg = 60.0
near = 0.1
far = 9.4
"#;

fn json_of(out: &Output) -> serde_json::Value {
    assert!(out.status.success(), "{}", text(&out.stderr));
    let stdout = text(&out.stdout);
    assert_eq!(stdout.lines().count(), 1, "one JSON object: {stdout}");
    serde_json::from_str(&stdout).unwrap()
}

/// A failure with exit status `code` and exactly one `error: ` line containing every needle.
fn assert_one_line_error(out: &Output, code: i32, needles: &[&str], args: &[&str]) {
    let stderr = text(&out.stderr);
    assert_eq!(out.status.code(), Some(code), "{args:?}: {stderr}");
    assert_eq!(stderr.lines().count(), 1, "{args:?}: {stderr}");
    assert!(stderr.starts_with("error: "), "{args:?}: {stderr}");
    assert!(!stderr.contains("panicked"), "{args:?}: {stderr}");
    for needle in needles {
        assert!(
            stderr.contains(needle),
            "{args:?}: {needle} not in {stderr}"
        );
    }
}

#[test]
fn build_with_areas_reports_the_area_build() {
    let dir = scratch("build-areas");
    let areas = dir.join("room.toml");
    std::fs::write(&areas, ROOM_AREAS).unwrap();
    let areas = areas.to_str().unwrap();
    let room = Scene::open("builtin:room").unwrap();
    let first = rdbvh::areas::read_areas(Path::new(areas)).unwrap().entries[0].area;
    let inside = room
        .triangles
        .iter()
        .filter(|t| first.overlaps_triangle(t))
        .count();
    assert!(inside > 0 && inside < room.len());

    let full = json_of(&rdbvh(&[
        "build",
        "builtin:room",
        "--preset",
        "full",
        "--areas",
        areas,
        "--json",
    ]));
    for key in [
        "triangles",
        "scene_triangles",
        "nodes",
        "leaves",
        "max_depth",
        "sah_cost",
        "pah_cost",
        "bytes",
        "load_ms",
        "select_ms",
        "build_ms",
        "mtris_per_s",
        "builder",
        "preset",
        "thesis_mode",
        "area_kind",
        "bins",
        "max_leaf",
    ] {
        assert!(full.get(key).is_some(), "missing {key}: {full}");
    }
    assert_eq!(full["triangles"], inside, "{full}");
    assert_eq!(full["scene_triangles"], room.len());
    assert_eq!(full["preset"], "full");
    assert_eq!(full["builder"], "spfh");
    assert_eq!(full["area_kind"], "plane");
    assert_eq!(full["thesis_mode"], false);
    assert_eq!(
        (full["bins"].as_u64(), full["max_leaf"].as_u64()),
        (Some(16), Some(8))
    );
    let pah = full["pah_cost"].as_f64().unwrap();
    assert!(pah > 0.0 && pah.is_finite(), "{full}");
    // Reinsertion of a PAH preset's tree moves nodes under the area's PAH: never a higher cost.
    let reinserted = json_of(&rdbvh(&[
        "build",
        "builtin:room",
        "--preset",
        "full",
        "--areas",
        areas,
        "--reinsert",
        "--json",
    ]));
    let after = reinserted["pah_cost"].as_f64().unwrap();
    assert!(after <= pah * (1.0 + 1e-6), "{full} vs {reinserted}");

    // Every preset and the plain builders build the same subset.
    for (flag, name) in [
        ("--preset", "sah"),
        ("--preset", "standard"),
        ("--preset", "facing"),
        ("--preset", "longest"),
        ("--builder", "lsph"),
    ] {
        let j = json_of(&rdbvh(&[
            "build",
            "builtin:room",
            flag,
            name,
            "--areas",
            areas,
            "--json",
        ]));
        assert_eq!(j["triangles"], inside, "{name}: {j}");
        assert!(j["pah_cost"].as_f64().unwrap() > 0.0, "{name}: {j}");
        if flag == "--builder" {
            assert_eq!(j["preset"], serde_json::Value::Null);
            assert_eq!(j["builder"], "lsph");
        } else {
            assert_eq!(j["preset"], name);
        }
    }

    // Thesis mode: the thesis's bins and leaf size, each still overridable.
    let thesis = json_of(&rdbvh(&[
        "build",
        "builtin:room",
        "--preset",
        "full",
        "--areas",
        areas,
        "--thesis-mode",
        "--json",
    ]));
    assert_eq!(thesis["thesis_mode"], true);
    assert_eq!(
        (thesis["bins"].as_u64(), thesis["max_leaf"].as_u64()),
        (Some(41), Some(2))
    );
    // Its costs are priced as `analyze --thesis-mode` prices the same tree.
    let analyzed = json_of(&rdbvh(&[
        "analyze",
        "builtin:room",
        "--preset",
        "full",
        "--areas",
        areas,
        "--thesis-mode",
        "--rays",
        "10",
        "--json",
    ]));
    let first = &analyzed["areas"][0];
    assert_eq!(first["nodes"], thesis["nodes"]);
    for key in ["sah_cost", "pah_cost"] {
        let (a, b) = (thesis[key].as_f64().unwrap(), first[key].as_f64().unwrap());
        assert!((a - b).abs() <= 1e-5 * b, "{key}: build {a}, analyze {b}");
    }
    let overridden = json_of(&rdbvh(&[
        "build",
        "builtin:room",
        "--preset",
        "longest",
        "--areas",
        areas,
        "--thesis-mode",
        "--max-leaf",
        "4",
        "--bins",
        "9",
        "--json",
    ]));
    assert_eq!(
        (overridden["bins"].as_u64(), overridden["max_leaf"].as_u64()),
        (Some(9), Some(4))
    );

    // The table names the preset and shows the PAH cost.
    let table = rdbvh(&[
        "build",
        "builtin:room",
        "--preset",
        "full",
        "--areas",
        areas,
    ]);
    assert!(table.status.success(), "{}", text(&table.stderr));
    let t = text(&table.stdout);
    for label in ["preset full", "PAH cost", "plane area", "select time"] {
        assert!(t.contains(label), "{label} missing: {t}");
    }
    std::fs::remove_dir_all(&dir).ok();
}

#[test]
fn presets_without_areas() {
    for preset in ["sah", "standard"] {
        let j = json_of(&rdbvh(&[
            "build",
            "builtin:room",
            "--preset",
            preset,
            "--json",
        ]));
        assert_eq!(j["triangles"], j["scene_triangles"]);
        assert_eq!(j["preset"], preset);
        assert_eq!(j["pah_cost"], serde_json::Value::Null);
        assert_eq!(j["area_kind"], serde_json::Value::Null);
    }
    let dir = scratch("presets-no-areas");
    let rays = dir.join("rays.csv");
    std::fs::write(&rays, "ox,oy,oz,dx,dy,dz\n5,5,5,0,1,0\n").unwrap();
    let hits = dir.join("hits.csv");
    let (rays, hits) = (rays.to_str().unwrap(), hits.to_str().unwrap());
    for preset in ["facing", "longest", "full", "pah"] {
        let args = ["build", "builtin:room", "--preset", preset];
        assert_one_line_error(&rdbvh(&args), 2, &[preset, "--areas"], &args);
        let args = [
            "trace",
            "builtin:room",
            "--preset",
            preset,
            "--rays",
            rays,
            "--out",
            hits,
        ];
        assert_one_line_error(&rdbvh(&args), 2, &[preset, "--areas"], &args);
    }
    // A plain trace with a preset that needs no area works as before.
    let out = rdbvh(&[
        "trace",
        "builtin:room",
        "--preset",
        "standard",
        "--rays",
        rays,
        "--out",
        hits,
    ]);
    assert!(out.status.success(), "{}", text(&out.stderr));
    assert!(std::fs::read_to_string(hits)
        .unwrap()
        .starts_with("ray,t,triangle,u,v\n0,"));
    std::fs::remove_dir_all(&dir).ok();
}

#[test]
fn area_and_option_errors_are_one_line() {
    let dir = scratch("area-errors");
    let write = |name: &str, body: &str| {
        let p = dir.join(name);
        std::fs::write(&p, body).unwrap();
        p.to_str().unwrap().to_string()
    };
    let good = write("good.toml", ROOM_AREAS);
    let missing = write("missing.toml", &ROOM_AREAS.replace("far = 9.4\n", ""));
    let kind = write("kind.toml", &ROOM_AREAS.replace("\"point\"", "\"spot\""));
    let value = write(
        "value.toml",
        &ROOM_AREAS.replace("depth = 9.9", "depth = 0"),
    );
    let typed = write(
        "type.toml",
        &ROOM_AREAS.replace("fov_y_deg = 60.0", "fov_y_deg = \"60\""),
    );
    let configs = write(
        "configs.toml",
        &ROOM_AREAS.replace("[[area]]", "[[config]]\nfile = \"WoodScene.obj\""),
    );
    let rays = write("rays.csv", "ox,oy,oz,dx,dy,dz\n5,5,5,0,1,0\n");
    let hits = dir.join("hits.csv");
    let hits = hits.to_str().unwrap();
    let build = |areas: &str| -> Vec<String> {
        [
            "build",
            "builtin:room",
            "--preset",
            "full",
            "--areas",
            areas,
        ]
        .map(String::from)
        .to_vec()
    };
    let trace = |areas: &str| -> Vec<String> {
        [
            "trace",
            "builtin:room",
            "--areas",
            areas,
            "--rays",
            &rays,
            "--out",
            hits,
        ]
        .map(String::from)
        .to_vec()
    };
    let cases: Vec<(Vec<String>, i32, Vec<&str>)> = vec![
        (
            build(&missing),
            1,
            vec!["missing.toml line 13: area 1: missing key `far`"],
        ),
        (trace(&missing), 1, vec!["area 1: missing key `far`"]),
        (
            build(&kind),
            1,
            vec!["kind.toml line 14: area 1: unknown kind \"spot\""],
        ),
        (
            build(&value),
            1,
            vec!["value.toml line 10: area 0: `depth` must be positive"],
        ),
        (
            build(&typed),
            1,
            vec!["area 1: `fov_y_deg` must be a number, not the string"],
        ),
        (
            build(&configs),
            1,
            vec![
                "no [[config]] entry is for scene builtin:room",
                "WoodScene.obj",
            ],
        ),
        (
            build("/nonexistent/areas.toml"),
            1,
            vec!["/nonexistent/areas.toml: cannot read"],
        ),
        (
            trace("/nonexistent/areas.toml"),
            1,
            vec!["/nonexistent/areas.toml"],
        ),
        (
            [
                "build",
                "builtin:room",
                "--preset",
                "full",
                "--builder",
                "lsph",
                "--areas",
                &good,
            ]
            .map(String::from)
            .to_vec(),
            2,
            vec!["--builder", "--preset"],
        ),
        (
            ["build", "builtin:room", "--thesis-mode"]
                .map(String::from)
                .to_vec(),
            2,
            vec!["--preset"],
        ),
        (
            ["build", "builtin:room", "--preset", "pha"]
                .map(String::from)
                .to_vec(),
            2,
            vec!["--preset", "full", "pah"],
        ),
        (
            {
                let mut a = trace(&good);
                a.extend(["--builder".into(), "lsph".into()]);
                a
            },
            2,
            vec!["--builder", "--preset"],
        ),
        (
            {
                let mut a = trace(&good);
                a.extend(["--octree-levels".into(), "0".into()]);
                a
            },
            2,
            vec!["--octree-levels"],
        ),
        (
            {
                let mut a = trace(&good);
                a.extend(["--max-tries".into(), "0".into()]);
                a
            },
            2,
            vec!["--max-tries"],
        ),
        (
            [
                "trace",
                "builtin:room",
                "--lookup",
                "list",
                "--rays",
                &rays,
                "--out",
                hits,
            ]
            .map(String::from)
            .to_vec(),
            2,
            vec!["--areas"],
        ),
    ];
    for (args, code, needles) in cases {
        let args: Vec<&str> = args.iter().map(String::as_str).collect();
        assert_one_line_error(&rdbvh(&args), code, &needles, &args);
    }
    std::fs::remove_dir_all(&dir).ok();
}

/// Rays for a scene with areas: per area, rays sampled from it (affine), the same jittered a few
/// degrees (mostly just outside the affinity tolerance), and unrelated random rays.
fn area_rays(scene: &Scene, areas: &[InfluenceArea], per_area: usize, seed: u32) -> Vec<[f32; 8]> {
    let mut rays = Vec::new();
    for (i, area) in areas.iter().enumerate() {
        let seed = u64::from(seed) * 100 + i as u64;
        let affine = RaySampler::new(*area, seed).distribution(PointDistribution::SolidAngle);
        let jittered = RaySampler::new(*area, seed + 50).jitter_deg(3.0);
        for r in affine.take(per_area).chain(jittered.take(per_area / 3)) {
            rays.push([
                r.origin.x, r.origin.y, r.origin.z, r.dir.x, r.dir.y, r.dir.z, r.t_min, r.t_max,
            ]);
        }
    }
    rays.extend(random_rays(scene, per_area, seed));
    rays
}

/// The local hit rate (percent) from `trace --areas`'s summary, checking the summary's lines.
fn local_hit_rate(stderr: &str) -> f64 {
    for needle in [
        "rays/s",
        "local hit rate",
        "with the structure",
        "with the fallback BVH alone",
        "structure: `",
    ] {
        assert!(stderr.contains(needle), "{needle} missing: {stderr}");
    }
    let rest = stderr.split("local hit rate ").nth(1).unwrap();
    rest.split('%').next().unwrap().parse().unwrap()
}

/// Runs `trace --areas AREAS` on `scene_arg` with `extra` options, closest and any hit, and checks
/// every answer against brute force; returns the closest-hit local hit rate and summary.
fn check_structure_trace(
    scene_arg: &str,
    areas_file: &Path,
    rays: &[[f32; 8]],
    extra: &[&str],
    dir: &Path,
) -> (f64, String) {
    let scene = Scene::open(scene_arg).unwrap();
    let rays_csv = dir.join("rays.csv");
    let rays = write_rays(&rays_csv, rays);
    let (mut rate, mut summary) = (0.0, String::new());
    for any_hit in [false, true] {
        let hits_csv = dir.join("hits.csv");
        let mut args = vec![
            "trace",
            scene_arg,
            "--areas",
            areas_file.to_str().unwrap(),
            "--rays",
            rays_csv.to_str().unwrap(),
            "--out",
            hits_csv.to_str().unwrap(),
        ];
        args.extend_from_slice(extra);
        if any_hit {
            args.push("--any-hit");
        }
        let out = rdbvh(&args);
        let stderr = text(&out.stderr);
        assert!(out.status.success(), "{args:?}: {stderr}");
        let r = local_hit_rate(&stderr);
        if !any_hit {
            (rate, summary) = (r, stderr.clone());
        }
        let label = format!("{scene_arg} {extra:?}");
        let hits = assert_answers(&hits_csv, &rays, &scene, any_hit, &label);
        assert!(hits > 0, "{label}: no hits");
    }
    (rate, summary)
}

#[test]
fn trace_through_the_structure_agrees_with_brute_force() {
    let dir = scratch("structure");
    let areas_file = dir.join("room.toml");
    std::fs::write(&areas_file, ROOM_AREAS).unwrap();
    let scene = Scene::open("builtin:room").unwrap();
    let areas = rdbvh::areas::read_areas(&areas_file).unwrap().areas();
    let rays = area_rays(&scene, &areas, 600, 3);
    for extra in [
        &[][..],
        &["--lookup", "list"],
        &[
            "--preset",
            "standard",
            "--max-tries",
            "2",
            "--octree-levels",
            "3",
        ],
        &["--preset", "longest", "--thesis-mode"],
        &["--thesis-mode", "--octree-levels", "7"],
        &["--preset", "facing", "--lookup", "list", "--max-tries", "2"],
        &["--reinsert"],
        &["--preset", "standard", "--reinsert", "--lookup", "list"],
    ] {
        let (rate, summary) =
            check_structure_trace("builtin:room", &areas_file, &rays, extra, &dir);
        // Most of the sampled rays are affine and hit inside their area.
        assert!(rate > 25.0, "{extra:?}: local hit rate {rate}%");
        // Without --preset the local BVHs are `pah`'s (`DEFAULT_LOCAL_PRESET`), and the summary
        // names it.
        if extra.is_empty() {
            assert!(summary.contains("structure: `pah`"), "{summary}");
        }
    }
    // Unrelated rays only: nothing is answered locally, and the answers are still exact.
    let random = random_rays(&scene, 500, 9);
    let (rate, _) = check_structure_trace("builtin:room", &areas_file, &random, &[], &dir);
    assert!(rate < 1.0, "random rays: local hit rate {rate}%");
    std::fs::remove_dir_all(&dir).ok();
}

/// The thesis scenes with their own areas, read straight from `experiments.toml`: the file's
/// `[[config]]` entries for each scene become the structure's areas.
#[test]
fn trace_through_the_structure_on_thesis_scenes() {
    let Some(scenes) = shared_scenes("trace_through_the_structure_on_thesis_scenes") else {
        return;
    };
    let experiments = scenes.join("../thesis/experiments.toml");
    let file = rdbvh::areas::read_areas(&experiments).unwrap();
    let dir = scratch("thesis-structure");
    let mut local = 0.0;
    for name in [
        "Random100.obj",
        "Random1000.obj",
        "MonkeyModel.obj",
        "Cottage.obj",
        "CottageWalls.obj",
        "WoodScene.obj",
    ] {
        let path = scenes.join("thesis").join(name);
        let scene = Scene::load(&path).unwrap();
        let areas: Vec<InfluenceArea> = file
            .for_scene(&scene.name)
            .unwrap()
            .iter()
            .map(|e| e.area)
            .collect();
        assert_eq!(areas.len(), 8, "{name}");
        let rays = area_rays(&scene, &areas, 150, 5);
        // Every tree reinserted on the larger scenes (the local BVHs under their areas' PAH).
        let extra: &[&str] = if scene.len() > 1000 {
            &["--reinsert"]
        } else {
            &[]
        };
        local += check_structure_trace(path.to_str().unwrap(), &experiments, &rays, extra, &dir).0;
    }
    assert!(
        local > 0.0,
        "no local BVH answered anything on any thesis scene"
    );

    // `build` takes the first config of the scene, and a scene without configs is an error.
    let wood = scenes.join("thesis/WoodScene.obj");
    let args = [
        "build",
        wood.to_str().unwrap(),
        "--preset",
        "full",
        "--areas",
        experiments.to_str().unwrap(),
        "--json",
    ];
    let j = json_of(&rdbvh(&args));
    assert_eq!(j["area_kind"], "plane");
    assert!(j["triangles"].as_u64().unwrap() > 0, "{j}");
    let cube = scenes.join("thesis/Cube.obj");
    let args = [
        "build",
        cube.to_str().unwrap(),
        "--preset",
        "full",
        "--areas",
        experiments.to_str().unwrap(),
    ];
    let out = rdbvh(&args);
    // The Cube's missing .mtl is a warning line before the error.
    let stderr = text(&out.stderr);
    assert_eq!(out.status.code(), Some(1), "{stderr}");
    let last = stderr.lines().last().unwrap_or("");
    assert!(
        last.starts_with("error: ") && last.contains("no [[config]] entry is for scene Cube.obj"),
        "{stderr}"
    );
    std::fs::remove_dir_all(&dir).ok();
}

/// Found by black-box testing: `trace` hit a 12-unit triangle at the origin with a ray from 1e8
/// units away that passed 3 units beside it. Rays from 1e6 to 1e10 units away now answer as
/// exact arithmetic on the rays' own f32 values (as read from the file) does, except within 1e-3
/// of the triangle's size of an edge.
#[test]
fn trace_decides_far_rays_by_the_scene_not_the_origin() {
    let dir = scratch("far-rays");
    let obj = dir.join("triangle.obj");
    std::fs::write(&obj, "v -6 -6 0.5\nv 6 -6 -0.5\nv 0 6 0\nf 1 2 3\n").unwrap();
    let tri = Scene::open(obj.to_str().unwrap()).unwrap().triangles[0];
    let mut rng = Mt19937::new(11);
    let mut uniform = |lo: f32, hi: f32| lo + (hi - lo) * (rng.next_u32() as f32 / u32::MAX as f32);
    let mut rays = Vec::new();
    for i in 0..400 {
        let distance = [1e6f32, 1e8, 1e10][i % 3];
        let (theta, phi) = (uniform(0.1, 1.4), uniform(0.0, std::f32::consts::TAU));
        let from = Vec3::new(
            theta.sin() * phi.cos(),
            theta.sin() * phi.sin(),
            theta.cos(),
        );
        let origin = from * distance;
        let target = Vec3::new(uniform(-12.0, 12.0), uniform(-12.0, 12.0), 0.0);
        let d = target - origin;
        rays.push([
            origin.x,
            origin.y,
            origin.z,
            d.x,
            d.y,
            d.z,
            0.0,
            f32::INFINITY,
        ]);
    }
    let rays_csv = dir.join("rays.csv");
    let rays = write_rays(&rays_csv, &rays);
    let hits_csv = dir.join("hits.csv");
    let out = rdbvh(&[
        "trace",
        obj.to_str().unwrap(),
        "--rays",
        rays_csv.to_str().unwrap(),
        "--out",
        hits_csv.to_str().unwrap(),
    ]);
    assert!(out.status.success(), "{}", text(&out.stderr));
    let answers = std::fs::read_to_string(&hits_csv).unwrap();
    let f64s = |v: Vec3| v.to_array().map(f64::from);
    let sub = |a: [f64; 3], b: [f64; 3]| [a[0] - b[0], a[1] - b[1], a[2] - b[2]];
    let dot = |a: [f64; 3], b: [f64; 3]| a[0] * b[0] + a[1] * b[1] + a[2] * b[2];
    let cross = |a: [f64; 3], b: [f64; 3]| {
        [
            a[1] * b[2] - a[2] * b[1],
            a[2] * b[0] - a[0] * b[2],
            a[0] * b[1] - a[1] * b[0],
        ]
    };
    let (v0, e1, e2) = (
        f64s(tri.v0),
        sub(f64s(tri.v1), f64s(tri.v0)),
        sub(f64s(tri.v2), f64s(tri.v0)),
    );
    let (mut inside, mut outside) = (0, 0);
    for (line, ray) in answers.lines().skip(1).zip(&rays) {
        // Moller-Trumbore in f64 on the ray as the file gives it.
        let p = cross(f64s(ray.dir), e2);
        let det = dot(e1, p);
        let s = sub(f64s(ray.origin), v0);
        let q = cross(s, e1);
        let (u, v) = (dot(s, p) / det, dot(f64s(ray.dir), q) / det);
        if [u, v, 1.0 - u - v].iter().any(|x| x.abs() < 1e-3) {
            continue;
        }
        let f: Vec<&str> = line.split(',').collect();
        if u > 0.0 && v > 0.0 && u + v < 1.0 {
            let missed = || panic!("{ray:?}: missed, exact u {u} v {v}");
            let (hu, hv): (f64, f64) = (
                f[3].parse().unwrap_or_else(|_| missed()),
                f[4].parse().unwrap_or_else(|_| missed()),
            );
            assert!(
                (hu - u).abs() < 1e-3 && (hv - v).abs() < 1e-3,
                "{ray:?}: {line}, exact u {u} v {v}"
            );
            inside += 1;
        } else {
            assert_eq!(&f[1..], ["", "", "", ""], "{ray:?}: exact u {u} v {v}");
            outside += 1;
        }
    }
    assert!(
        inside > 40 && outside > 40,
        "{inside} inside, {outside} outside"
    );
    std::fs::remove_dir_all(&dir).ok();
}

/// Columns a rays file has beyond `ox..dz, tmin, tmax` are not read, and `trace` says so: a
/// misspelt `t_max` would otherwise make every segment a whole ray without a word.
#[test]
fn trace_names_the_columns_it_does_not_read() {
    let dir = scratch("columns");
    let (rays, out) = (dir.join("rays.csv"), dir.join("hits.csv"));
    let run = |header: &str| {
        std::fs::write(&rays, format!("{header}\n0.5,0.5,-2,0,0,1,0.5,7\n")).unwrap();
        let args = [
            "trace",
            "builtin:random100",
            "--rays",
            rays.to_str().unwrap(),
            "--out",
            out.to_str().unwrap(),
        ];
        let result = rdbvh(&args);
        assert!(result.status.success(), "{}", text(&result.stderr));
        text(&result.stderr)
    };
    let stderr = run("ox,oy,oz,dx,dy,dz,t_max,id");
    for name in ["t_max", "id"] {
        let line = format!("column '{name}' is not read");
        assert!(
            stderr.contains("warning: ") && stderr.contains(&line),
            "{stderr}"
        );
    }
    assert!(!run("ox,oy,oz,dx,dy,dz,tmin,tmax").contains("warning"));
    std::fs::remove_dir_all(&dir).ok();
}
