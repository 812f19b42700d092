//! End-to-end tests of the `rdbvh` binary: the output contracts scripts rely on, one-line errors,
//! and `trace` answers checked against the brute-force oracle on built-in and real scenes.

use std::path::{Path, PathBuf};
use std::process::{Command, Output};

use rdbvh::scene::{Mt19937, Scene};
use rdbvh_core::brute_force;
use rdbvh_core::geometry::Ray;
use rdbvh_core::Vec3;

fn rdbvh(args: &[&str]) -> Output {
    Command::new(env!("CARGO_BIN_EXE_rdbvh"))
        .args(args)
        .output()
        .expect("the rdbvh binary runs")
}

fn text(bytes: &[u8]) -> String {
    String::from_utf8_lossy(bytes).into_owned()
}

/// The shared scenes beside the workspace, or `None` (with a note) when they are not checked out.
/// Under `CI=true` their absence is a failure, not a skip.
fn shared_scenes(test: &str) -> Option<PathBuf> {
    let dir = Path::new(concat!(env!("CARGO_MANIFEST_DIR"), "/../../shared/scenes"));
    if dir.is_dir() {
        return Some(dir.to_path_buf());
    }
    assert!(
        std::env::var("CI").as_deref() != Ok("true"),
        "CI=true but {} is missing",
        dir.display()
    );
    eprintln!(
        "{test}: real scenes skipped: {} not found (check out ../shared beside the workspace)",
        dir.display()
    );
    None
}

/// A fresh scratch folder for one test.
fn scratch(name: &str) -> PathBuf {
    let dir = std::env::temp_dir().join(format!("rdbvh-cli-{}-{name}", std::process::id()));
    std::fs::create_dir_all(&dir).unwrap();
    dir
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

/// Runs `trace` on `scene_arg` both ways and compares every answer with brute force, exactly.
fn check_trace(scene_arg: &str, rays_count: usize) {
    let scene = Scene::open(scene_arg).unwrap();
    let rays = random_rays(&scene, rays_count, 7);
    let dir = scratch(&scene.name.replace(['/', ':'], "_"));
    let rays_csv = dir.join("rays.csv");
    // Columns out of the documented order, to check they are found by name.
    let mut csv = String::from("tmax,dx,dy,dz,ox,oy,oz,tmin\n");
    for r in &rays {
        csv += &format!(
            "{},{},{},{},{},{},{},{}\n",
            r[7], r[3], r[4], r[5], r[0], r[1], r[2], r[6]
        );
    }
    std::fs::write(&rays_csv, csv).unwrap();
    let rays: Vec<Ray> = rays
        .iter()
        .map(|r| {
            Ray::segment(
                Vec3::new(r[0], r[1], r[2]),
                Vec3::new(r[3], r[4], r[5]),
                r[6],
                r[7],
            )
            .unwrap()
        })
        .collect();

    for any_hit in [false, true] {
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
        let out = rdbvh(&args);
        assert!(out.status.success(), "{}", text(&out.stderr));
        assert!(
            text(&out.stderr).contains("rays/s"),
            "{}",
            text(&out.stderr)
        );
        let answers = std::fs::read_to_string(&hits_csv).unwrap();
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
        for (i, (line, ray)) in lines.zip(&rays).enumerate() {
            let f: Vec<&str> = line.split(',').collect();
            assert_eq!(f[0], i.to_string(), "rays stay in input order");
            if any_hit {
                let expected = brute_force::any_hit(ray, &scene.triangles);
                assert_eq!(
                    f[1],
                    if expected { "1" } else { "0" },
                    "{scene_arg} ray {i}"
                );
                hits += usize::from(expected);
            } else {
                match brute_force::closest_hit(ray, &scene.triangles) {
                    None => assert_eq!(&f[1..], ["", "", "", ""], "{scene_arg} ray {i}"),
                    Some(h) => {
                        let t: f32 = f[1].parse().unwrap();
                        let tri: u32 = f[2].parse().unwrap();
                        let u: f32 = f[3].parse().unwrap();
                        let v: f32 = f[4].parse().unwrap();
                        assert_eq!(
                            (t, tri, u, v),
                            (h.t, h.triangle, h.u, h.v),
                            "{scene_arg} ray {i}"
                        );
                        hits += 1;
                    }
                }
            }
            count += 1;
        }
        assert_eq!(count, rays.len());
        assert!(
            hits > 0 && hits < count,
            "{scene_arg}: {hits} of {count} rays hit"
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
