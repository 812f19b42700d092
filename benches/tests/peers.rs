//! The `peers` comparison on a built-in scene (no `../shared` needed): the JSON lines keep their
//! contract (exact keys, every library and measure once, the right units), every library agrees
//! with rdbvh, and bad input is one `error:` line with a failing exit status.

use std::collections::BTreeSet;
use std::process::Command;
use std::time::Duration;

use rdbvh_benches::compare::{main_with, Clock, Measure, Options, LIBRARIES};
use rdbvh_benches::MIN_AGREEMENT;

fn quick() -> Options {
    Options {
        min_reps: 1,
        max_reps: 1,
        budget: Duration::ZERO,
        clock: Clock::ThreadCpu,
        pah: true,
    }
}

fn args(a: &[&str]) -> Vec<String> {
    a.iter().map(|s| s.to_string()).collect()
}

#[test]
fn json_lines_keep_the_contract_and_libraries_agree() {
    let out = main_with(args(&["builtin:random1000", "--json"]), quick()).expect("runs");
    let mut seen = BTreeSet::new();
    for line in out.lines() {
        let v: serde_json::Value = serde_json::from_str(line).expect("one JSON object per line");
        let o = v.as_object().expect("an object");
        let keys: BTreeSet<&str> = o.keys().map(String::as_str).collect();
        assert_eq!(
            keys,
            BTreeSet::from(["library", "measure", "value", "unit"]),
            "{line}"
        );
        let library = o["library"].as_str().unwrap();
        let measure = o["measure"].as_str().unwrap();
        assert!(LIBRARIES.contains(&library), "{line}");
        let m = Measure::ALL
            .into_iter()
            .find(|m| m.name() == measure)
            .unwrap_or_else(|| panic!("unknown measure in {line}"));
        assert_eq!(o["unit"].as_str().unwrap(), m.unit(), "{line}");
        let value = o["value"].as_f64().expect("a number");
        assert!(value.is_finite() && value > 0.0, "{line}");
        assert!(
            seen.insert((library.to_string(), measure.to_string())),
            "twice: {line}"
        );
    }
    assert_eq!(seen.len(), LIBRARIES.len() * Measure::ALL.len());
}

#[test]
fn every_library_agrees_with_rdbvh_on_both_trees() {
    let scene = rdbvh::scene::Scene::open("builtin:random1000").unwrap();
    let report = rdbvh_benches::compare::run("builtin:random1000", &scene.triangles, &quick())
        .expect("runs");
    // obvhs (and tinybvh, with the C++ peers) are measured as two adapters each.
    let two_adapters = if cfg!(feature = "cpp-peers") { 2 } else { 1 };
    assert_eq!(report.left_out, []);
    assert_eq!(report.runs.len(), LIBRARIES.len() + two_adapters);
    for r in &report.runs {
        for g in r.agreement.iter().chain(&r.agreement_mt) {
            assert!(g.rays > 0);
            assert!(
                g.closest >= MIN_AGREEMENT && g.any >= MIN_AGREEMENT,
                "{}: {g:?}",
                r.name
            );
        }
    }
    // Hits exist in both ray sets, so the agreement is not only on misses.
    assert!(
        report.hit_share.iter().all(|&s| s > 0.05),
        "{:?}",
        report.hit_share
    );
    let text = report.text();
    assert!(text.contains("parry3d: no threaded build"), "{text}");
    assert!(text.contains("PAH vs SAH"), "{text}");
    assert!(text.contains("pah (PAH, all axes) plane area"), "{text}");
}

#[test]
fn bad_input_is_one_error_line() {
    let dir = std::env::temp_dir().join(format!("rdbvh-peers-{}", std::process::id()));
    std::fs::create_dir_all(&dir).unwrap();
    let empty = dir.join("empty.obj");
    std::fs::write(&empty, "# no faces\nv 0 0 0\n").unwrap();
    let missing = dir.join("missing.obj");
    for a in [
        vec![missing.to_str().unwrap().to_string()],
        vec![empty.to_str().unwrap().to_string(), "--json".into()],
        vec![],
        vec!["builtin:nope".into()],
    ] {
        let out = Command::new(env!("CARGO_BIN_EXE_peers"))
            .args(&a)
            .output()
            .unwrap();
        assert!(!out.status.success(), "{a:?}");
        assert!(out.stdout.is_empty(), "{a:?}");
        let err = String::from_utf8(out.stderr).unwrap();
        assert_eq!(err.lines().count(), 1, "{a:?}: {err}");
        assert!(err.starts_with("error: "), "{a:?}: {err}");
        assert!(!err.contains("panicked"), "{a:?}: {err}");
    }
    std::fs::remove_dir_all(&dir).ok();
}

/// The C++ adapters (feature `cpp-peers`; CI builds without it, so only a machine with Embree
/// installed runs this) against brute force: every triangle tested per ray with rdbvh's
/// double-sided test, on all three ray sets, before the comparison's own agreement check with
/// rdbvh is asserted for both of their trees.
#[cfg(feature = "cpp-peers")]
#[test]
fn cpp_peers_agree_with_brute_force_and_rdbvh() {
    use rdbvh_benches::peers::{
        Embree, EmbreeHigh, Library, Prepared, TinybvhBvh4, TinybvhBvh8, TinybvhBvh8Hq,
    };
    use rdbvh_benches::{agreement, bounds, ray_set, Answers, RayKind};

    rdbvh_benches::peers::embree::available().expect("Embree 3 is installed");
    rdbvh_benches::peers::tinybvh::available().expect("tinybvh matches its adapter");
    let scene = rdbvh::scene::Scene::open("builtin:random1000").unwrap();
    let tris = &scene.triangles;
    let b = bounds(tris);
    fn check<L: Library>(
        tris: &[rdbvh_core::geometry::Triangle],
        rays: &[rdbvh_core::geometry::Ray],
        brute: &Answers,
        kind: RayKind,
    ) {
        let g = agreement(brute, &Prepared::<L>::new(tris).answers(&L::rays(rays)));
        assert!(
            g.closest >= MIN_AGREEMENT && g.any >= MIN_AGREEMENT,
            "{} {}: {g:?}",
            L::NAME,
            kind.name()
        );
    }
    for kind in [RayKind::Camera, RayKind::Random, RayKind::Shadow] {
        let rays = ray_set(tris, &b, kind);
        assert!(rays.len() > 1000, "{}: {} rays", kind.name(), rays.len());
        let brute = Answers {
            closest: rays
                .iter()
                .map(|r| {
                    tris.iter().fold(None::<f32>, |best, t| {
                        t.intersect(r, best.unwrap_or(r.t_max))
                            .map(|h| h.t)
                            .or(best)
                    })
                })
                .collect(),
            any: rays
                .iter()
                .map(|r| tris.iter().any(|t| t.intersect(r, r.t_max).is_some()))
                .collect(),
            floor: Vec::new(),
        };
        let hits = brute.any.iter().filter(|&&h| h).count();
        assert!(
            hits > rays.len() / 20 && hits < rays.len(),
            "{}: {hits} hits",
            kind.name()
        );
        check::<Embree>(tris, &rays, &brute, kind);
        check::<TinybvhBvh8>(tris, &rays, &brute, kind);
        check::<TinybvhBvh4>(tris, &rays, &brute, kind);
        // The spatial-split builds reference a triangle from several leaves: the answers must
        // not change.
        check::<EmbreeHigh>(tris, &rays, &brute, kind);
        check::<TinybvhBvh8Hq>(tris, &rays, &brute, kind);
    }
    let report = rdbvh_benches::compare::run("builtin:random1000", tris, &quick()).expect("runs");
    for name in [
        "embree",
        "tinybvh-bvh8",
        "tinybvh-bvh4",
        "embree-high",
        "tinybvh8-hq",
    ] {
        let r = report
            .runs
            .iter()
            .find(|r| r.name == name)
            .unwrap_or_else(|| panic!("{name} measured"));
        for g in r.agreement.iter().chain(&r.agreement_mt) {
            assert!(
                g.rays > 0 && g.closest >= MIN_AGREEMENT && g.any >= MIN_AGREEMENT,
                "{name}: {g:?}"
            );
        }
    }
}

/// A scene of 1e-20 units: tinybvh's builds cannot split it and make trees deeper than its
/// traversals' unchecked 256-entry stack (tracing them crashed the process). They are left out
/// with a reason; every other library is measured.
#[cfg(feature = "cpp-peers")]
#[test]
fn a_peer_whose_tree_would_overrun_its_stack_is_left_out() {
    use rdbvh_benches::SplitMix64;
    use rdbvh_core::geometry::Triangle;
    use rdbvh_core::Vec3;

    let mut rng = SplitMix64::new(3);
    let mut point = |scale: f32| {
        Vec3::new(rng.next_f32(), rng.next_f32(), rng.next_f32()) * (2.0 * scale) - scale
    };
    let tris: Vec<Triangle> = (0..3000)
        .map(|_| {
            let c = point(1e-20);
            Triangle::new(c + point(1e-22), c + point(1e-22), c + point(1e-22))
        })
        .collect();
    let report = rdbvh_benches::compare::run("tiny", &tris, &quick()).expect("runs");
    let left_out: Vec<&str> = report.left_out.iter().map(|(name, _)| *name).collect();
    assert!(left_out.contains(&"tinybvh-bvh8"), "{:?}", report.left_out);
    for (_, why) in &report.left_out {
        assert!(why.contains("traversal stack entries"), "{why}");
    }
    assert!(report.runs.iter().any(|r| r.name == "embree"));
    assert!(report.text().contains("left out: tinybvh-bvh8: "));
}
