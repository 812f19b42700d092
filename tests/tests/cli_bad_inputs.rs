//! The bad-input catalogue through the `rdbvh` binary: each bad input exits non-zero with one
//! readable `error: ...` line on standard error, never a panic.
//!
//! `env!("CARGO_BIN_EXE_rdbvh")` exists only in std-host's own tests, so this finds the binary
//! beside the test executable (`target/<profile>/deps/cli_bad_inputs-*` -> `target/<profile>/rdbvh`).
//! `cargo test --workspace` (the test command) builds it, since std-host's tests need it too. When
//! it is missing (`cargo test -p rdbvh-tests` alone on a fresh target) the tests print a skip,
//! and fail under `CI=true`.

use std::path::{Path, PathBuf};
use std::process::Command;

use rdbvh_tests::in_ci;

fn binary() -> Option<PathBuf> {
    let exe = std::env::current_exe().ok()?;
    let dir = exe.parent()?.parent()?;
    let bin = dir.join(format!("rdbvh{}", std::env::consts::EXE_SUFFIX));
    if bin.is_file() {
        return Some(bin);
    }
    assert!(
        !in_ci(),
        "CI=true but {} is missing: run cargo test --workspace",
        bin.display()
    );
    println!(
        "skipped: {} not built (run cargo test --workspace)",
        bin.display()
    );
    None
}

fn scratch(name: &str) -> PathBuf {
    let dir = std::env::temp_dir().join(format!("rdbvh-bad-{}-{name}", std::process::id()));
    std::fs::create_dir_all(&dir).unwrap();
    dir
}

/// Runs `rdbvh args` and expects success.
fn succeeds(bin: &Path, args: &[&str]) {
    let out = Command::new(bin).args(args).output().unwrap();
    let stderr = String::from_utf8_lossy(&out.stderr);
    assert!(out.status.success(), "{args:?} failed: {stderr}");
}

/// Runs `rdbvh args`, expects failure with exactly one `error: ` line containing `needle`.
fn fails(bin: &Path, args: &[&str], needle: &str) {
    let out = Command::new(bin).args(args).output().unwrap();
    let stderr = String::from_utf8_lossy(&out.stderr);
    assert!(!out.status.success(), "{args:?} succeeded: {stderr}");
    assert_ne!(out.status.code(), Some(101), "{args:?} panicked: {stderr}");
    let lines: Vec<&str> = stderr
        .lines()
        .filter(|l| !l.starts_with("warning:"))
        .collect();
    assert_eq!(lines.len(), 1, "{args:?}: not one line: {stderr}");
    assert!(lines[0].starts_with("error: "), "{args:?}: {stderr}");
    assert!(!stderr.contains("panicked"), "{args:?}: {stderr}");
    assert!(
        lines[0].to_lowercase().contains(&needle.to_lowercase()),
        "{args:?}: {:?} lacks {needle:?}",
        lines[0]
    );
}

#[test]
fn bad_scenes_are_one_line_errors() {
    let Some(bin) = binary() else { return };
    let dir = scratch("scenes");
    let tri = "v 0 0 0\nv 1 0 0\nv 0 1 0\n";
    for (name, text, needle) in [
        ("empty.obj", String::new(), "no triangles"),
        ("nofaces.obj", tri.to_string(), "no triangles"),
        ("missing.obj", format!("{tri}f 1 2 7\n"), "line 4"),
        ("negative.obj", format!("{tri}f -1 -2 -9\n"), "line 4"),
        (
            "huge.obj",
            format!("{tri}f 1 2 99999999999999999999\n"),
            "huge.obj",
        ),
        (
            "nan.obj",
            "v nan 0 0\nv 1 0 0\nv 0 1 0\nf 1 2 3\n".into(),
            "NaN or infinite",
        ),
        (
            "inf.obj",
            "v 0 0 inf\nv 1 0 0\nv 0 1 0\nf 1 2 3\n".into(),
            "NaN or infinite",
        ),
        ("badv.obj", "v 0 0 0\nv 1 x 0\n".into(), "line 2"),
        ("badvt.obj", format!("{tri}vt 0\nf 1 2 3\n"), "line 4"),
    ] {
        let path = dir.join(name);
        std::fs::write(&path, text).unwrap();
        let p = path.to_str().unwrap();
        fails(&bin, &["build", p], needle);
        fails(&bin, &["build", p, "--json"], needle);
    }
    fails(
        &bin,
        &["build", dir.join("absent.obj").to_str().unwrap()],
        "absent.obj",
    );
    fails(&bin, &["build", "builtin:nope"], "builtin:nope");
}

#[test]
fn bad_rays_are_one_line_errors_and_empty_segments_miss() {
    let Some(bin) = binary() else { return };
    let dir = scratch("rays");
    let out = dir.join("hits.csv");
    let out = out.to_str().unwrap();
    for (name, rows, needle) in [
        ("zero.csv", "0,0,0,0,0,0\n", "line 2"),
        ("nan.csv", "0,0,0,nan,0,1\n", "line 2"),
        ("nanorigin.csv", "nan,0,0,0,0,1\n", "line 2"),
        ("short.csv", "0,0,0,0,0\n", "line 2"),
    ] {
        let path = dir.join(name);
        std::fs::write(&path, format!("ox,oy,oz,dx,dy,dz\n{rows}")).unwrap();
        fails(
            &bin,
            &[
                "trace",
                "builtin:room",
                "--rays",
                path.to_str().unwrap(),
                "--out",
                out,
            ],
            needle,
        );
    }
    // tmin > tmax: a valid, empty segment that hits nothing.
    let path = dir.join("empty_segment.csv");
    std::fs::write(
        &path,
        "ox,oy,oz,dx,dy,dz,tmin,tmax\n5,5,5,0,-1,0,10,1\n5,5,5,0,-1,0,0,inf\n",
    )
    .unwrap();
    succeeds(
        &bin,
        &[
            "trace",
            "builtin:room",
            "--rays",
            path.to_str().unwrap(),
            "--out",
            out,
        ],
    );
    let hits = std::fs::read_to_string(out).unwrap();
    let rows: Vec<&str> = hits.lines().collect();
    assert_eq!(rows[0], "ray,t,triangle,u,v");
    assert_eq!(rows[1], "0,,,,", "the empty segment misses");
    assert!(rows[2].len() > 5, "the full ray hits the room: {hits}");
}

#[test]
fn bad_areas_are_one_line_errors() {
    let Some(bin) = binary() else { return };
    let dir = scratch("areas");
    let plane = |hw: &str| {
        format!(
            "[[area]]\nkind = \"plane\"\ncenter = [5.0, 9.9, 5.0]\nnormal = [0.0, -1.0, 0.0]\n\
             half_width = {hw}\nhalf_height = 1.0\ndepth = 9.9\n"
        )
    };
    let point = |fov: &str, near: &str| {
        format!(
            "[[area]]\nkind = \"point\"\neye = [5.0, 9.0, 5.0]\ndirection = [0.0, -1.0, 0.0]\n\
             fov_x_deg = {fov}\nfov_y_deg = 60.0\nnear = {near}\nfar = 10.0\n"
        )
    };
    for (name, text, needle) in [
        ("zero.toml", plane("0.0"), "half_width"),
        ("negative.toml", plane("-1.0"), "half_width"),
        ("nan.toml", plane("nan"), "half_width"),
        ("fov0.toml", point("0.0", "0.1"), "fov_x_deg"),
        ("fov180.toml", point("180.0", "0.1"), "fov_x_deg"),
        ("nearfar.toml", point("60.0", "20.0"), "near"),
        (
            "garbage.toml",
            "[[area]\nkind = ".to_string(),
            "garbage.toml",
        ),
    ] {
        let path = dir.join(name);
        std::fs::write(&path, text).unwrap();
        fails(
            &bin,
            &["build", "builtin:room", "--areas", path.to_str().unwrap()],
            needle,
        );
    }
    // A byte that is not UTF-8 is located by its line, like every other area-file error.
    let latin1 = dir.join("latin1.toml");
    std::fs::write(&latin1, [plane("1.0").as_bytes(), b"# caf\xe9\n"].concat()).unwrap();
    fails(
        &bin,
        &["build", "builtin:room", "--areas", latin1.to_str().unwrap()],
        "latin1.toml line 8: cannot read: not UTF-8",
    );
    // An option the chosen lookup would ignore is refused, not ignored.
    let areas = dir.join("ok.toml");
    std::fs::write(&areas, plane("1.0")).unwrap();
    let rays = dir.join("rays.csv");
    std::fs::write(&rays, "ox,oy,oz,dx,dy,dz\n5,9,5,0,-1,0\n").unwrap();
    let (a, r, o) = (
        areas.to_str().unwrap(),
        rays.to_str().unwrap(),
        dir.join("hits.csv"),
    );
    let o = o.to_str().unwrap();
    let args = [
        "trace",
        "builtin:room",
        "--areas",
        a,
        "--rays",
        r,
        "--out",
        o,
    ];
    fails(
        &bin,
        &[&args[..], &["--lookup", "list", "--octree-levels", "4"]].concat(),
        "--octree-levels",
    );
    succeeds(&bin, &[&args[..], &["--octree-levels", "4"]].concat());
}

#[test]
fn a_bom_is_not_part_of_the_first_vertex_and_an_experiment_checks_its_folder_first() {
    let Some(bin) = binary() else { return };
    let dir = scratch("bom");
    // Found by black-box testing: the BOM made the first vertex vanish and shifted every index.
    let obj = dir.join("bom.obj");
    std::fs::write(
        &obj,
        "\u{feff}v 0 0 0\nv 1 0 0\nv 0 1 0\nv 5 5 5\nf 1 2 3 # comment\n",
    )
    .unwrap();
    let rays = dir.join("rays.csv");
    std::fs::write(&rays, "ox,oy,oz,dx,dy,dz\n0.2,0.2,-1,0,0,1\n").unwrap();
    let hits = dir.join("hits.csv");
    let (o, r) = (obj.to_str().unwrap(), rays.to_str().unwrap());
    succeeds(
        &bin,
        &["trace", o, "--rays", r, "--out", hits.to_str().unwrap()],
    );
    let text = std::fs::read_to_string(&hits).unwrap();
    assert_eq!(text.lines().nth(1), Some("0,1,0,0.2,0.2"), "{text}");
    // An --out that names a file fails before any run, with words for it.
    let file = dir.join("taken");
    std::fs::write(&file, "").unwrap();
    let experiment = dir.join("e.toml");
    std::fs::write(
        &experiment,
        "[settings]\nrays_per_config = 10\n[[config]]\nfile = \"bom.obj\"\nkind = \"plane\"\n\
         center = [0.2, 0.2, -1.0]\nnormal = [0.0, 0.0, 1.0]\nhalf_width = 1.0\n\
         half_height = 1.0\ndepth = 3.0\n",
    )
    .unwrap();
    let e = experiment.to_str().unwrap();
    // So do trace's outputs in a folder that does not exist, or that is a folder.
    let nowhere = dir.join("absent").join("out.csv");
    let w = nowhere.to_str().unwrap();
    fails(
        &bin,
        &["trace", o, "--rays", r, "--out", w],
        "folder does not exist",
    );
    fails(
        &bin,
        &["trace", o, "--rays", r, "--out", dir.to_str().unwrap()],
        "is a folder",
    );
    // Or that is one of its inputs (it used to replace the rays with the hits).
    fails(&bin, &["trace", o, "--rays", r, "--out", r], "input files");
    assert!(std::fs::read_to_string(&rays)
        .unwrap()
        .starts_with("ox,oy,oz"));
    fails(
        &bin,
        &["experiment", e, "--out", file.to_str().unwrap()],
        "not a folder",
    );
    // And analyze's --nodes (the area file here is the experiment's, [[config]] tables).
    fails(
        &bin,
        &["analyze", o, "--areas", e, "--nodes", w],
        "folder does not exist",
    );
    let json = dir.join("nodes.json");
    let args = [
        "analyze",
        o,
        "--areas",
        e,
        "--nodes",
        json.to_str().unwrap(),
    ];
    fails(
        &bin,
        &[&args[..], &["--columns", "index"]].concat(),
        "--columns",
    );
}

/// Found by black-box testing: an output that was a hard link to the rays, or the scene's own
/// material library, was written over. Both are inputs and fail before anything is written.
#[test]
fn an_output_is_never_an_input_under_another_name() {
    let Some(bin) = binary() else { return };
    let dir = scratch("same-file");
    let obj = dir.join("lit.obj");
    std::fs::write(
        &obj,
        "mtllib lit.mtl\nv 0 0 0\nv 1 0 0\nv 0 1 0\nusemtl lamp\nf 1 2 3\n",
    )
    .unwrap();
    let mtl = dir.join("lit.mtl");
    let mtl_text = "newmtl lamp\nKe 1 1 1\n";
    std::fs::write(&mtl, mtl_text).unwrap();
    let rays = dir.join("rays.csv");
    let rays_text = "ox,oy,oz,dx,dy,dz\n0.2,0.2,-1,0,0,1\n";
    std::fs::write(&rays, rays_text).unwrap();
    let linked = dir.join("linked.csv");
    let _ = std::fs::remove_file(&linked);
    std::fs::hard_link(&rays, &linked).unwrap();
    let (o, r) = (obj.to_str().unwrap(), rays.to_str().unwrap());
    for out in [&linked, &mtl] {
        let out = out.to_str().unwrap();
        fails(
            &bin,
            &["trace", o, "--rays", r, "--out", out],
            "input files",
        );
    }
    assert_eq!(std::fs::read_to_string(&rays).unwrap(), rays_text);
    assert_eq!(std::fs::read_to_string(&mtl).unwrap(), mtl_text);
    // The material library is an input of analyze's --nodes too.
    let areas = dir.join("areas.toml");
    std::fs::write(
        &areas,
        "[[area]]\nkind = \"plane\"\ncenter = [0.2, 0.2, -1.0]\nnormal = [0.0, 0.0, 1.0]\n\
         half_width = 1.0\nhalf_height = 1.0\ndepth = 3.0\n",
    )
    .unwrap();
    let a = areas.to_str().unwrap();
    let m = mtl.to_str().unwrap();
    fails(
        &bin,
        &["analyze", o, "--areas", a, "--nodes", m],
        "input files",
    );
    assert_eq!(std::fs::read_to_string(&mtl).unwrap(), mtl_text);
}

/// Found by black-box testing: an experiment whose --out folder held one of its inputs under an
/// output's name (the experiment file as `report.md`, a scene as `results.csv`, its material
/// library as a chart) deleted it and wrote its results in its place. Each fails before any run,
/// and the input is kept.
#[test]
fn an_experiment_never_writes_over_its_inputs() {
    let Some(bin) = binary() else { return };
    let out = scratch("experiment-inputs");
    let config = "[[config]]\nkind = \"plane\"\ncenter = [0.2, 0.2, -1.0]\n\
                  normal = [0.0, 0.0, 1.0]\nhalf_width = 1.0\nhalf_height = 1.0\ndepth = 3.0\n";
    let experiment = |file: &str| {
        format!(
            "[settings]\nrays_per_config = 10\nheuristics = [\"sah\"]\n{config}file = \"{file}\"\n"
        )
    };
    let scene = "mtllib lit.mtl\nv 0 0 0\nv 1 0 0\nv 0 1 0\nusemtl lamp\nf 1 2 3\n";
    std::fs::write(out.join("lit.obj"), scene).unwrap();
    let mtl = "newmtl lamp\nKe 1 1 1\n";
    std::fs::write(out.join("lit.mtl"), mtl).unwrap();
    let o = out.to_str().unwrap();

    // The experiment file itself, as report.md.
    let report = out.join("report.md");
    std::fs::write(&report, experiment("lit.obj")).unwrap();
    let r = report.to_str().unwrap();
    fails(&bin, &["experiment", r, "--out", o], "input files");
    assert_eq!(
        std::fs::read_to_string(&report).unwrap(),
        experiment("lit.obj")
    );
    std::fs::remove_file(&report).unwrap();

    // A scene named results.csv, and a material library hard-linked as a chart.
    let file = out.join("e.toml");
    let e = file.to_str().unwrap();
    std::fs::write(out.join("results.csv"), scene).unwrap();
    std::fs::write(&file, experiment("results.csv")).unwrap();
    fails(&bin, &["experiment", e, "--out", o], "input files");
    assert_eq!(
        std::fs::read_to_string(out.join("results.csv")).unwrap(),
        scene
    );
    let chart = out.join("estimate_error.png");
    let _ = std::fs::remove_file(&chart);
    std::fs::hard_link(out.join("lit.mtl"), &chart).unwrap();
    std::fs::write(&file, experiment("lit.obj")).unwrap();
    fails(&bin, &["experiment", e, "--out", o], "input files");
    assert_eq!(std::fs::read_to_string(out.join("lit.mtl")).unwrap(), mtl);
    std::fs::remove_file(&chart).unwrap();

    // With the names free, the same experiment runs.
    succeeds(&bin, &["experiment", e, "--out", o]);
    assert_eq!(std::fs::read_to_string(out.join("lit.mtl")).unwrap(), mtl);
    assert!(std::fs::read_to_string(out.join("report.md"))
        .unwrap()
        .starts_with('#'));
}

/// Found by black-box testing: some experiment-file errors named neither the file nor the line.
#[test]
fn experiment_errors_name_the_file_and_line() {
    let Some(bin) = binary() else { return };
    let dir = scratch("experiment-lines");
    let out = dir.join("out");
    let (o, file) = (out.to_str().unwrap(), dir.join("e.toml"));
    let e = file.to_str().unwrap();
    let config = "[[config]]\nkind = \"plane\"\ncenter = [0.2, 0.2, -1.0]\n\
                  normal = [0.0, 0.0, 1.0]\nhalf_width = 1.0\nhalf_height = 1.0\ndepth = 3.0\n";
    for (settings, needle) in [
        (
            "heuristics = [\"full\", \"bogus\"]",
            "e.toml line 3: `heuristics` lists unknown heuristic `bogus`",
        ),
        (
            "heuristics = []",
            "e.toml line 3: `heuristics` lists no heuristic",
        ),
    ] {
        let text =
            format!("[settings]\nrays_per_config = 10\n{settings}\n{config}file = \"a.obj\"\n");
        std::fs::write(&file, text).unwrap();
        fails(&bin, &["experiment", e, "--out", o], needle);
    }
    // A scene file that cannot be read is named with the configuration that wants it.
    let text = format!(
        "[settings]\nrays_per_config = 10\n{config}file = \"a.obj\"\n\
         {config}file = \"absent.obj\"\n"
    );
    std::fs::write(&file, text).unwrap();
    std::fs::write(dir.join("a.obj"), "v 0 0 0\nv 1 0 0\nv 0 1 0\nf 1 2 3\n").unwrap();
    fails(
        &bin,
        &["experiment", e, "--out", o],
        "e.toml line 11: config 1: cannot read scene",
    );
    assert!(!out.join("results.csv").exists());
    // So is a bad --thesis-results folder, before any run.
    std::fs::write(&file, format!("{config}file = \"a.obj\"\n")).unwrap();
    let empty = dir.join("empty");
    std::fs::create_dir_all(&empty).unwrap();
    let t = empty.to_str().unwrap();
    fails(
        &bin,
        &["experiment", e, "--out", o, "--thesis-results", t],
        "no Plane_*.csv or Point_*.csv",
    );
    assert!(!out.join("results.csv").exists());
    // And analyze's --columns names each column once.
    let a = dir.join("a.obj");
    let args = [
        "analyze",
        a.to_str().unwrap(),
        "--areas",
        e,
        "--columns",
        "index,index",
    ];
    let nodes = dir.join("nodes.csv");
    fails(
        &bin,
        &[&args[..], &["--nodes", nodes.to_str().unwrap()]].concat(),
        "`index` appears twice",
    );
}
