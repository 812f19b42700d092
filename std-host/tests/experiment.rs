//! End to end: a two-configuration experiment file over tiny OBJ scenes written here, run through
//! the `rdbvh experiment` command line, then `rdbvh analyze` on one of them.

use std::path::{Path, PathBuf};
use std::process::Command;

const THESIS_COLUMNS: [&str; 16] = [
    "Scene",
    "Estimated PAH cost",
    "Estimated SAH cost",
    "Real cost with fallback",
    "Intersections with fallback",
    "Real cost without fallback",
    "Intersections without fallback",
    "Fallback BVH cost",
    "Only fallback cost",
    "Hit percentage",
    "Overlapping % 4",
    "Overlapping % culled 4",
    "Overlapping % culled 100",
    "Max level",
    "EPO",
    "Build milliseconds",
];

fn temp_dir(name: &str) -> PathBuf {
    let dir = std::env::temp_dir().join(format!("rdbvh-{name}-{}", std::process::id()));
    let _ = std::fs::remove_dir_all(&dir);
    std::fs::create_dir_all(&dir).unwrap();
    dir
}

/// A grid of small quads facing +z at several depths: enough triangles for a real tree.
fn grid_obj(n: usize, depths: &[f32]) -> String {
    let mut s = String::new();
    let mut v = 0;
    for &z in depths {
        for i in 0..n {
            for j in 0..n {
                let (x, y) = (i as f32, j as f32);
                for (dx, dy) in [(0.0, 0.0), (0.8, 0.0), (0.8, 0.8), (0.0, 0.8)] {
                    s += &format!("v {} {} {}\n", x + dx, y + dy, z + 0.1 * (i + j) as f32);
                }
                s += &format!(
                    "f {} {} {}\nf {} {} {}\n",
                    v + 1,
                    v + 2,
                    v + 3,
                    v + 1,
                    v + 3,
                    v + 4
                );
                v += 4;
            }
        }
    }
    s
}

fn rdbvh(args: &[&str]) -> std::process::Output {
    Command::new(env!("CARGO_BIN_EXE_rdbvh"))
        .args(args)
        .env("RDBVH_FONT", "")
        .output()
        .unwrap()
}

fn write_experiment(dir: &Path) -> PathBuf {
    std::fs::create_dir_all(dir.join("scenes")).unwrap();
    std::fs::write(dir.join("scenes/Grid.obj"), grid_obj(6, &[2.0, 5.0])).unwrap();
    let toml = r#"
scene_dir = "scenes"

[settings]
rays_per_config = 64
heuristics = ["full", "standard"]

[[config]]
scene = "Grid"
file = "Grid.obj"
kind = "plane"
orientation = "parallel"
center = [3.0, 3.0, 0.0]
normal = [0.0, 0.0, 1.0]
half_width = 3.0
half_height = 3.0
depth = 10.0
thesis_test = "Grid_Plane_Parallel"

[[config]]
scene = "Grid"
file = "Grid.obj"
kind = "point"
orientation = "15deg"
eye = [3.0, 3.0, -1.0]
direction = [0.259, 0.0, 0.966]
fov_x_deg = 90.0
fov_y_deg = 90.0
near = 0.5
far = 12.0
thesis_test = "Grid_Point_15"

[[config]]
scene = "Hidden"
kind = "plane"
orientation = "45deg"
center = [0.0, 0.0, 0.0]
normal = [1.0, 0.0, 1.0]
half_width = 1.0
half_height = 1.0
depth = 1.0
"#;
    let path = dir.join("experiment.toml");
    std::fs::write(&path, toml).unwrap();
    path
}

#[test]
fn two_configuration_experiment_end_to_end() {
    let dir = temp_dir("experiment");
    let file = write_experiment(&dir);
    let out = dir.join("out");
    for mode in [&[][..], &["--thesis-mode"][..]] {
        let mut args = vec![
            "experiment",
            file.to_str().unwrap(),
            "--out",
            out.to_str().unwrap(),
        ];
        args.extend_from_slice(mode);
        let o = rdbvh(&args);
        let stderr = String::from_utf8_lossy(&o.stderr);
        assert!(o.status.success(), "{stderr}");
        assert!(stderr.contains("Hidden: no scene file"), "{stderr}");
        let stdout = String::from_utf8_lossy(&o.stdout);
        assert!(stdout.contains("4 runs"), "{stdout}");

        let mut r = csv::Reader::from_path(out.join("results.csv")).unwrap();
        let header: Vec<String> = r.headers().unwrap().iter().map(String::from).collect();
        for c in THESIS_COLUMNS {
            assert!(header.iter().any(|h| h == c), "missing column {c}");
        }
        assert_eq!(header[0], "Scene");
        let rows: Vec<csv::StringRecord> = r.records().map(Result::unwrap).collect();
        let names: Vec<&str> = rows.iter().map(|r| r.get(0).unwrap()).collect();
        assert_eq!(
            names,
            [
                "Grid_Plane_Parallel_Full",
                "Grid_Plane_Parallel_Standard",
                "Grid_Point_15_Full",
                "Grid_Point_15_Standard"
            ]
        );
        let col = |name: &str| header.iter().position(|h| h == name).unwrap();
        for row in &rows {
            let get = |c: &str| row.get(col(c)).unwrap().parse::<f64>().unwrap();
            let hit = get("Hit percentage");
            assert!((0.0..=1.0).contains(&hit));
            assert!(get("Real cost with fallback") >= get("Real cost without fallback"));
            assert!(get("Estimated PAH cost") > 0.0 && get("Estimated SAH cost") > 0.0);
            assert!(get("Max level") >= 2.0);
            assert_eq!(get("Rays"), 64.0);
        }
        // Axis-parallel rays over a plane area: PAH estimates the measured all-hit cost closely.
        let first = &rows[0];
        let est: f64 = first
            .get(col("Estimated PAH cost"))
            .unwrap()
            .parse()
            .unwrap();
        let real: f64 = first
            .get(col("Real cost without fallback"))
            .unwrap()
            .parse()
            .unwrap();
        assert!((est - real).abs() / real < 0.15, "PAH {est} vs real {real}");

        let report = std::fs::read_to_string(out.join("report.md")).unwrap();
        assert!(report.contains("Estimate error"), "{report}");
        for stem in [
            "estimate_error",
            "spfh_vs_lsph",
            "structure_vs_fallback",
            "octree_levels_error",
            "octree_vs_list",
        ] {
            for ext in ["svg", "png"] {
                let p = out.join(format!("{stem}.{ext}"));
                assert!(
                    std::fs::metadata(&p)
                        .map(|m| m.len() > 100)
                        .unwrap_or(false),
                    "{}",
                    p.display()
                );
            }
        }
    }

    // The analyzer on one build, as JSON, with a per-node CSV export.
    let nodes = dir.join("nodes.csv");
    let o = rdbvh(&[
        "analyze",
        dir.join("scenes/Grid.obj").to_str().unwrap(),
        "--areas",
        file.to_str().unwrap(),
        "--preset",
        "full",
        "--rays",
        "32",
        "--json",
        "--nodes",
        nodes.to_str().unwrap(),
        "--columns",
        "index,depth,count",
    ]);
    assert!(o.status.success(), "{}", String::from_utf8_lossy(&o.stderr));
    let v: serde_json::Value = serde_json::from_slice(&o.stdout).unwrap();
    let areas = v["areas"].as_array().unwrap();
    assert_eq!(areas.len(), 2);
    assert!(areas[0]["epo"].as_f64().unwrap() >= 0.0);
    assert!(areas[0]["nodes"].as_u64().unwrap() >= 3);
    let csv = std::fs::read_to_string(&nodes).unwrap();
    assert!(csv.starts_with("index,depth,count\n0,0,0\n"), "{csv}");

    // The JSON export holds every CSV column under the same name, with the same values.
    let all = dir.join("nodes_all.csv");
    let json = dir.join("nodes.json");
    for export in [&all, &json] {
        let o = rdbvh(&[
            "analyze",
            dir.join("scenes/Grid.obj").to_str().unwrap(),
            "--areas",
            file.to_str().unwrap(),
            "--rays",
            "8",
            "--nodes",
            export.to_str().unwrap(),
        ]);
        assert!(o.status.success(), "{}", String::from_utf8_lossy(&o.stderr));
    }
    let csv = std::fs::read_to_string(&all).unwrap();
    let mut rows = csv.lines();
    let header: Vec<&str> = rows.next().unwrap().split(',').collect();
    assert_eq!(header, rdbvh::cli::NODE_COLUMNS);
    let v: serde_json::Value =
        serde_json::from_str(&std::fs::read_to_string(&json).unwrap()).unwrap();
    let records = v["nodes"].as_array().unwrap();
    let rows: Vec<&str> = rows.collect();
    assert_eq!(records.len(), rows.len());
    let mut leaf_prims = 0;
    for (record, row) in records.iter().zip(&rows) {
        let record = record.as_object().unwrap();
        let keys: Vec<&str> = record.keys().map(|k| k.as_str()).collect();
        let mut columns = header.clone();
        columns.sort_unstable();
        assert_eq!(keys, columns);
        for (column, cell) in header.iter().zip(row.split(',')) {
            let value = &record[*column];
            let same = match value {
                serde_json::Value::Null => cell.is_empty(),
                serde_json::Value::Bool(b) => cell == b.to_string(),
                // The CSV writes f32s shortest; JSON the same f32 through f64.
                n => n.as_f64().unwrap() as f32 == cell.parse::<f32>().unwrap(),
            };
            assert!(same, "{column}: {value} vs {cell}");
        }
        let f = |k: &str| record[k].as_f64().unwrap();
        let e = [
            f("max_x") - f("min_x"),
            f("max_y") - f("min_y"),
            f("max_z") - f("min_z"),
        ];
        let half = e[0] * e[1] + e[1] * e[2] + e[2] * e[0];
        assert!((f("measure") - half).abs() <= 1e-5 * half.max(1.0));
        assert!((f("area") - 2.0 * half).abs() <= 1e-5 * half.max(1.0));
        // Conditional probabilities, under SAH and under the area's PAH.
        for p in [f("hit_probability"), f("pah_hit_probability")] {
            assert!((0.0..=1.0 + 1e-5).contains(&p), "{p}");
        }
        assert!(f("pah_measure") >= 0.0);
        if record["is_leaf"].as_bool().unwrap() {
            leaf_prims += record["count"].as_u64().unwrap();
        }
    }
    // Every triangle of the first area's local BVH sits in one leaf.
    assert_eq!(leaf_prims, areas[0]["local_triangles"].as_u64().unwrap());

    // Bad input: one line, non-zero exit.
    let o = rdbvh(&[
        "experiment",
        dir.join("missing.toml").to_str().unwrap(),
        "--out",
        out.to_str().unwrap(),
    ]);
    assert!(!o.status.success());
    let e = String::from_utf8_lossy(&o.stderr);
    assert!(
        e.starts_with("error: ") && e.trim_end().lines().count() == 1,
        "{e}"
    );
    let o = rdbvh(&[
        "experiment",
        file.to_str().unwrap(),
        "--out",
        out.to_str().unwrap(),
        "--presets",
        "bogus",
    ]);
    assert_eq!(o.status.code(), Some(2));
    let _ = std::fs::remove_dir_all(&dir);
}
