//! Recorded rays as the ray source of `rdbvh analyze` and `rdbvh experiment`: the sampler's own
//! rays, recorded, measure exactly what the sampler measures; a render's recording runs through
//! both; bad recordings are one-line errors.

use std::path::{Path, PathBuf};

use rdbvh_core::influence::{PointDistribution, RaySampler};

mod common;
use common::{rdbvh, text};

/// A fresh scratch folder for one test of this suite.
fn scratch(name: &str) -> PathBuf {
    common::scratch("recorded", name)
}

/// One plane area under the room's ceiling light, as an areas file and as an experiment file.
const PLANE_AREA: &str = r#"
kind = "plane"
orientation = "parallel"
center = [5.0, 9.9, 5.0]
normal = [0, -1, 0]
half_width = 1.0
half_height = 1.0
depth = 9.9
"#;

/// A point area at the ceiling light looking down, for the render's recording.
const POINT_AREA: &str = r#"
kind = "point"
eye = [5.0, 9.5, 5.0]
direction = [0.0, -1.0, 0.0]
fov_x_deg = 90.0
fov_y_deg = 90.0
near = 0.1
far = 9.4
"#;

const RAYS: u32 = 200;

/// The run's costs: every key but the clocks.
fn costs(area: &serde_json::Value) -> Vec<(String, serde_json::Value)> {
    let timed = |k: &str| k.contains("_ms") || k.contains("per_second") || k == "affine_rays";
    let mut out: Vec<_> = area
        .as_object()
        .unwrap()
        .iter()
        .filter(|(k, _)| !timed(k))
        .map(|(k, v)| (k.clone(), v.clone()))
        .collect();
    out.sort_by(|a, b| a.0.cmp(&b.0));
    out
}

fn analyze(areas: &Path, extra: &[&str]) -> serde_json::Value {
    let mut args = vec![
        "analyze",
        "builtin:room",
        "--areas",
        areas.to_str().unwrap(),
        "--preset",
        "full",
        "--json",
    ];
    args.extend(extra);
    let out = rdbvh(&args);
    assert!(out.status.success(), "{args:?}: {}", text(&out.stderr));
    serde_json::from_slice(&out.stdout).unwrap()
}

/// Writes the rays the first configuration's sampler draws (seed 1, project mode) to `path`.
fn record_sampler_rays(areas: &Path, path: &Path) {
    let area = rdbvh::areas::read_areas(areas).unwrap().entries[0].area;
    let mut sampler = RaySampler::new(area, 1).distribution(PointDistribution::SolidAngle);
    let rays: Vec<_> = (0..RAYS).map(|_| sampler.sample()).collect();
    let mut file = std::fs::File::create(path).unwrap();
    rdbvh::cli::write_rays(&mut file, &rays).unwrap();
}

#[test]
fn recorded_sampler_rays_measure_what_the_sampler_measures() {
    let dir = scratch("same");
    let areas = dir.join("room.toml");
    std::fs::write(&areas, format!("[[area]]\nscene = \"Room\"{PLANE_AREA}")).unwrap();
    let rays = dir.join("rays.csv");
    record_sampler_rays(&areas, &rays);

    let sampled = analyze(&areas, &["--rays", &RAYS.to_string()]);
    let recorded = analyze(&areas, &["--recorded-rays", rays.to_str().unwrap()]);
    assert_eq!(sampled["ray_source"], "sampled");
    assert_eq!(recorded["ray_source"], "recorded");
    let (s, r) = (&sampled["areas"][0], &recorded["areas"][0]);
    assert_eq!(s["rays"], RAYS);
    assert_eq!(costs(s), costs(r));
    // The sampler's rays are the area's own; every one of them takes the local BVH.
    assert_eq!(s["affine_rays"], RAYS);
    assert_eq!(r["affine_rays"], RAYS);

    // The experiment runner, on a one-configuration file: the same costs in results.csv.
    let file = dir.join("experiment.toml");
    let toml = format!(
        "[settings]\nrays_per_config = {RAYS}\nheuristics = [\"full\"]\n\n[[config]]\n\
         scene = \"Room\"\nfile = \"builtin:room\"{PLANE_AREA}"
    );
    std::fs::write(&file, toml).unwrap();
    let table = |extra: &[&str]| {
        let out_dir = dir.join(if extra.is_empty() {
            "sampled"
        } else {
            "recorded"
        });
        let mut args = vec![
            "experiment",
            file.to_str().unwrap(),
            "--out",
            out_dir.to_str().unwrap(),
        ];
        args.extend(extra);
        let out = rdbvh(&args);
        assert!(out.status.success(), "{args:?}: {}", text(&out.stderr));
        let csv = std::fs::read_to_string(out_dir.join("results.csv")).unwrap();
        let report = std::fs::read_to_string(out_dir.join("report.md")).unwrap();
        (csv, report)
    };
    let (sampled_csv, sampled_report) = table(&[]);
    let (recorded_csv, recorded_report) = table(&["--recorded-rays", rays.to_str().unwrap()]);
    assert!(sampled_report.contains(&format!("{RAYS} sampled rays per run")));
    assert!(
        recorded_report.contains(&format!("the {RAYS} rays recorded in")),
        "{recorded_report}"
    );
    let cost_columns = |csv: &str| -> Vec<String> {
        let mut lines = csv.lines();
        let header: Vec<&str> = lines.next().unwrap().split(',').collect();
        let keep: Vec<usize> = (0..header.len())
            // "Compute cost PAH average" is the build profile's clock, not a cost.
            .filter(|&i| !header[i].starts_with("Compute"))
            .filter(|&i| header[i].contains("cost") || header[i].contains("Intersections"))
            .collect();
        assert!(keep.len() >= 4, "{header:?}");
        lines
            .map(|l| {
                let cells: Vec<&str> = l.split(',').collect();
                keep.iter().map(|&i| cells[i]).collect::<Vec<_>>().join(",")
            })
            .collect()
    };
    assert_eq!(cost_columns(&sampled_csv), cost_columns(&recorded_csv));
    std::fs::remove_dir_all(&dir).ok();
}

#[test]
fn a_render_recording_runs_through_analyze() {
    let dir = scratch("render");
    let rec = dir.join("rec");
    let out = rdbvh(&[
        "render",
        "builtin:room",
        "--eye",
        "5,5,0.3",
        "--look-at",
        "5,4,10",
        "--width",
        "24",
        "--height",
        "16",
        "--spp",
        "2",
        "--out",
        dir.join("room.png").to_str().unwrap(),
        "--record-rays",
        rec.to_str().unwrap(),
    ]);
    assert!(out.status.success(), "{}", text(&out.stderr));
    let shadow = rec.join("shadow_rays.csv");
    let recorded = std::fs::read_to_string(&shadow).unwrap().lines().count() - 1;
    assert!(recorded > 100, "{recorded} shadow rays");

    let areas = dir.join("room.toml");
    let toml = format!("[[area]]\nscene = \"Room\"{PLANE_AREA}\n[[area]]{POINT_AREA}");
    std::fs::write(&areas, toml).unwrap();
    let v = analyze(&areas, &["--recorded-rays", shadow.to_str().unwrap()]);
    assert_eq!(v["ray_source"], "recorded");
    let runs = v["areas"].as_array().unwrap();
    assert_eq!(runs.len(), 2);
    for run in runs {
        // Every recorded ray measures every area; the affine ones take its local BVH.
        assert_eq!(run["rays"], recorded);
        assert!(run["affine_rays"].as_u64().unwrap() <= recorded as u64);
        for key in ["any_hit_cost_with_fallback", "any_hit_cost_fallback_alone"] {
            assert!(run[key].as_f64().unwrap() > 0.0, "{key}: {run}");
        }
    }
    std::fs::remove_dir_all(&dir).ok();
}

#[test]
fn bad_recordings_are_one_line_errors() {
    let dir = scratch("errors");
    let areas = dir.join("room.toml");
    std::fs::write(&areas, format!("[[area]]\nscene = \"Room\"{PLANE_AREA}")).unwrap();
    let empty = dir.join("empty.csv");
    std::fs::write(&empty, "ox,oy,oz,dx,dy,dz\n").unwrap();
    let nan = dir.join("nan.csv");
    std::fs::write(&nan, "ox,oy,oz,dx,dy,dz\n0,0,0,NaN,1,0\n").unwrap();
    let missing = dir.join("missing.csv");
    let a = areas.to_str().unwrap();
    let cases: [(&[&str], i32, &str); 4] = [
        (
            &["--recorded-rays", empty.to_str().unwrap()],
            1,
            "holds no ray",
        ),
        (&["--recorded-rays", nan.to_str().unwrap()], 1, "line 2"),
        (
            &["--recorded-rays", missing.to_str().unwrap()],
            1,
            "cannot open",
        ),
        (
            &["--recorded-rays", empty.to_str().unwrap(), "--rays", "5"],
            2,
            "cannot be used with",
        ),
    ];
    for (extra, code, needle) in cases {
        let mut args = vec!["analyze", "builtin:room", "--areas", a];
        args.extend(extra);
        let out = rdbvh(&args);
        let stderr = text(&out.stderr);
        assert_eq!(out.status.code(), Some(code), "{args:?}: {stderr}");
        assert!(
            stderr.contains(needle),
            "{args:?}: {needle} not in {stderr}"
        );
        assert!(!stderr.contains("panicked"), "{args:?}: {stderr}");
        if code == 1 {
            assert_eq!(stderr.lines().count(), 1, "{args:?}: {stderr}");
        }
    }
    std::fs::remove_dir_all(&dir).ok();
}
