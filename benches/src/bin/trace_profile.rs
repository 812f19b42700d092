//! `trace_profile SCENE [REPS]`: the four traversal measures of the `peers` table for
//! `rdbvh-wide` and its 8-wide tree `rdbvh-wide8` alone (with `--features cpp-peers`, Embree's and tinybvh's BVH8 beside it), in
//! interleaved rounds, best thread CPU time of `REPS` (default 7): a quick before/after check of
//! the traversal kernel that builds in `release` and skips the builds and the Rust peers. SCENE is
//! a name under `../shared/scenes` or a path to an OBJ file.
//!
//! `RDBVH_PROFILE_ONLY=closest_camera` (or `closest_random`, `any_random`, `any_shadow`) runs that
//! measure alone, once per round, inside `trace_profile::trace_once`, for
//! `valgrind --tool=callgrind --toggle-collect=trace_profile::trace_once`.

use std::hint::black_box;
use std::process::ExitCode;

use rdbvh_benches::peers::{Library, Prepared, RdbvhWide, RdbvhWide8};
use rdbvh_benches::{bounds, open_scene, ray_set, thread_cpu_seconds, RayKind};
use rdbvh_core::geometry::{Ray, Triangle};

const MEASURES: [(&str, RayKind, bool); 4] = [
    ("closest_camera", RayKind::Camera, true),
    ("closest_random", RayKind::Random, true),
    ("any_random", RayKind::Random, false),
    ("any_shadow", RayKind::Shadow, false),
];

/// One library's structure and its copy of every ray set.
struct Traced<L: Library> {
    prepared: Prepared<L>,
    rays: Vec<Vec<L::Ray>>,
}

impl<L: Library> Traced<L> {
    fn new(tris: &[Triangle], sets: &[Vec<Ray>]) -> Self {
        Self {
            prepared: Prepared::new(tris),
            rays: sets.iter().map(|s| L::rays(s)).collect(),
        }
    }

    /// Seconds of thread CPU time and hits for measure `m`.
    fn time(&self, m: usize) -> (f64, usize) {
        let start = thread_cpu_seconds();
        let hits = trace_once(&self.prepared, &self.rays[m], MEASURES[m].2);
        (thread_cpu_seconds() - start, hits)
    }
}

/// One pass over a ray set: the timed (and, under callgrind, the counted) work.
#[inline(never)]
fn trace_once<L: Library>(p: &Prepared<L>, rays: &[L::Ray], closest: bool) -> usize {
    if closest {
        black_box(p.closest_all(black_box(rays)))
    } else {
        black_box(p.any_all(black_box(rays)))
    }
}

fn main() -> ExitCode {
    let args: Vec<String> = std::env::args().skip(1).collect();
    let Some(scene) = args.first() else {
        eprintln!("usage: trace_profile SCENE [REPS]");
        return ExitCode::FAILURE;
    };
    let reps: usize = args.get(1).and_then(|s| s.parse().ok()).unwrap_or(7);
    let tris = match open_scene(scene) {
        Ok(t) => t,
        Err(e) => {
            eprintln!("error: {e}");
            return ExitCode::FAILURE;
        }
    };
    let b = bounds(&tris);
    let only = std::env::var("RDBVH_PROFILE_ONLY").ok();
    let chosen: Vec<usize> = (0..MEASURES.len())
        .filter(|&m| only.as_deref().is_none_or(|o| o == MEASURES[m].0))
        .collect();
    let sets: Vec<Vec<Ray>> = MEASURES
        .iter()
        .map(|&(_, kind, _)| ray_set(&tris, &b, kind))
        .collect();
    let wide = Traced::<RdbvhWide>::new(&tris, &sets);
    let wide8 = Traced::<RdbvhWide8>::new(&tris, &sets);
    #[cfg(feature = "cpp-peers")]
    let embree = Traced::<rdbvh_benches::peers::Embree>::new(&tris, &sets);
    #[cfg(feature = "cpp-peers")]
    let tiny = Traced::<rdbvh_benches::peers::TinybvhBvh8>::new(&tris, &sets);
    let mut best = vec![[f64::INFINITY; 4]; MEASURES.len()];
    for _ in 0..reps {
        for &m in &chosen {
            let (t, hits) = wide.time(m);
            best[m][0] = best[m][0].min(t);
            let (t8, hits8) = wide8.time(m);
            best[m][3] = best[m][3].min(t8);
            if hits8 != hits {
                eprintln!("{}: hits {hits} 4-wide, {hits8} 8-wide", MEASURES[m].0);
                return ExitCode::FAILURE;
            }
            #[cfg(feature = "cpp-peers")]
            {
                let (te, he) = embree.time(m);
                let (tt, ht) = tiny.time(m);
                best[m][1] = best[m][1].min(te);
                best[m][2] = best[m][2].min(tt);
                // Shared-edge rays may differ by a few; a large gap means a broken kernel.
                if hits.abs_diff(he) * 1000 > hits || hits.abs_diff(ht) * 1000 > hits {
                    eprintln!(
                        "{}: hits {hits} vs embree {he}, tinybvh {ht}",
                        MEASURES[m].0
                    );
                    return ExitCode::FAILURE;
                }
            }
            let _ = hits;
        }
    }
    println!("{scene}: Mrays/s, best of {reps} (thread CPU time)");
    for &m in &chosen {
        let n = sets[m].len() as f64;
        let rate = |t: f64| n / t * 1e-6;
        let [w, e, t, w8] = best[m];
        if e.is_finite() {
            println!(
                "{:<15} wide {:>6.2} ({:.2}x)  wide8 {:>6.2} ({:.2}x)  embree {:>6.2}  tinybvh8 {:>6.2}",
                MEASURES[m].0,
                rate(w),
                rate(w) / rate(e).max(rate(t)),
                rate(w8),
                rate(w8) / rate(e).max(rate(t)),
                rate(e),
                rate(t),
            );
        } else {
            println!(
                "{:<15} wide {:>6.2}  wide8 {:>6.2}",
                MEASURES[m].0,
                rate(w),
                rate(w8)
            );
        }
    }
    ExitCode::SUCCESS
}
