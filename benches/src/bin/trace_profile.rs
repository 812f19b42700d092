//! `trace_profile SCENE [REPS]`: the four traversal measures of the `peers` table for
//! `rdbvh-wide`, its 8-wide tree `rdbvh-wide8` and the 8-wide SBVH `rdbvh-wide8-sbvh` alone (with
//! `--features cpp-peers`, Embree's and tinybvh's BVH8 beside them, each by its default build and
//! by its spatial-split build, `embree-high` and `tinybvh8-hq`), in interleaved rounds, best
//! thread CPU time of `REPS` (default 7): a quick before/after check of the traversal kernel that
//! builds in `release` and skips the builds and the Rust peers. SCENE is a name under
//! `../shared/scenes` or a path to an OBJ file. Like against like: `wide` and `wide8` (no split
//! triangles) are over the faster of the C++ default builds, `sbvh` over the faster of their
//! spatial-split builds.
//!
//! `RDBVH_PROFILE_ONLY=closest_camera` (or `closest_random`, `any_random`, `any_shadow`) runs that
//! measure alone, once per round, inside `trace_profile::trace_once`, for
//! `valgrind --tool=callgrind --toggle-collect=trace_profile::trace_once`.
//!
//! `RDBVH_PROFILE_WARM=N` (default 1) has each library trace a measure N times in a row within a
//! round and keep its best pass: from the second pass on its tree and triangles are in the
//! caches, with no other library run in between, so the table shows the kernels' own work with
//! little of their memory traffic (the default interleaving shows both).

use std::fmt::Write as _;
use std::hint::black_box;
use std::process::ExitCode;

use rdbvh_benches::peers::{Library, Prepared, RdbvhWide, RdbvhWide8, RdbvhWide8Sbvh};
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

    /// [`Traced::new`] for a peer, refused when its tree cannot be traced safely
    /// ([`Library::unusable`]): this tool compares every peer or none.
    #[cfg(feature = "cpp-peers")]
    fn peer(tris: &[Triangle], sets: &[Vec<Ray>]) -> Result<Box<dyn Timed>, String>
    where
        L: 'static,
    {
        let traced = Self::new(tris, sets);
        match L::unusable(&traced.prepared.accel) {
            Some(why) => Err(format!("{}: {why}", L::NAME)),
            None => Ok(Box::new(traced)),
        }
    }
}

/// A traced library whatever its type, so the C++ peers can be one list.
trait Timed {
    /// The best of `passes` passes in a row over measure `m`'s rays: seconds of thread CPU
    /// time, and hits.
    fn time(&self, m: usize, passes: usize) -> (f64, usize);
}

impl<L: Library> Timed for Traced<L> {
    fn time(&self, m: usize, passes: usize) -> (f64, usize) {
        let mut best = (f64::INFINITY, 0);
        for _ in 0..passes.max(1) {
            let start = thread_cpu_seconds();
            let hits = trace_once(&self.prepared, &self.rays[m], MEASURES[m].2);
            best = (best.0.min(thread_cpu_seconds() - start), hits);
        }
        best
    }
}

/// A C++ peer's name in the table and its traced trees.
type Peer = (&'static str, Box<dyn Timed>);

/// The C++ peers with their names in the table: first the two default builds (the ratios'
/// base), then the two spatial-split builds.
#[cfg(feature = "cpp-peers")]
fn cpp_peers(tris: &[Triangle], sets: &[Vec<Ray>]) -> Result<Vec<Peer>, String> {
    use rdbvh_benches::peers::{Embree, EmbreeHigh, TinybvhBvh8, TinybvhBvh8Hq};
    Ok(vec![
        ("embree", Traced::<Embree>::peer(tris, sets)?),
        ("tinybvh8", Traced::<TinybvhBvh8>::peer(tris, sets)?),
        ("embree-high", Traced::<EmbreeHigh>::peer(tris, sets)?),
        ("tinybvh8-hq", Traced::<TinybvhBvh8Hq>::peer(tris, sets)?),
    ])
}

/// Without the C++ peers: none.
#[cfg(not(feature = "cpp-peers"))]
fn cpp_peers(_: &[Triangle], _: &[Vec<Ray>]) -> Result<Vec<Peer>, String> {
    Ok(Vec::new())
}

/// How many of [`cpp_peers`] are default builds (the base of the unsplit trees' ratios); the
/// rest are spatial-split builds (the SBVH's base).
const DEFAULT_BUILDS: usize = 2;

/// rdbvh's trees in the table: 4-wide, 8-wide, 8-wide SBVH.
const RDBVH: usize = 3;

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
    let passes: usize = std::env::var("RDBVH_PROFILE_WARM")
        .ok()
        .and_then(|s| s.parse().ok())
        .unwrap_or(1);
    let chosen: Vec<usize> = (0..MEASURES.len())
        .filter(|&m| only.as_deref().is_none_or(|o| o == MEASURES[m].0))
        .collect();
    let sets: Vec<Vec<Ray>> = MEASURES
        .iter()
        .map(|&(_, kind, _)| ray_set(&tris, &b, kind))
        .collect();
    let wide = Traced::<RdbvhWide>::new(&tris, &sets);
    let wide8 = Traced::<RdbvhWide8>::new(&tris, &sets);
    let sbvh = Traced::<RdbvhWide8Sbvh>::new(&tris, &sets);
    let peers = match cpp_peers(&tris, &sets) {
        Ok(p) => p,
        Err(e) => {
            eprintln!("error: {e}");
            return ExitCode::FAILURE;
        }
    };
    // Per measure: rdbvh-wide, rdbvh-wide8, rdbvh-wide8-sbvh, then each C++ peer.
    let mut best = vec![vec![f64::INFINITY; RDBVH + peers.len()]; MEASURES.len()];
    let mut peer_hits = vec![0; peers.len()];
    for _ in 0..reps {
        for &m in &chosen {
            let (t, hits) = wide.time(m, passes);
            best[m][0] = best[m][0].min(t);
            let (t8, hits8) = wide8.time(m, passes);
            best[m][1] = best[m][1].min(t8);
            let (ts, hits_s) = sbvh.time(m, passes);
            best[m][2] = best[m][2].min(ts);
            if hits8 != hits || hits_s != hits {
                eprintln!(
                    "{}: hits {hits} 4-wide, {hits8} 8-wide, {hits_s} SBVH",
                    MEASURES[m].0
                );
                return ExitCode::FAILURE;
            }
            for (i, (_, peer)) in peers.iter().enumerate() {
                let (tp, hp) = peer.time(m, passes);
                best[m][RDBVH + i] = best[m][RDBVH + i].min(tp);
                peer_hits[i] = hp;
            }
            // Shared-edge rays may differ by a few; a large gap means a broken kernel.
            if peer_hits.iter().any(|&h| hits.abs_diff(h) * 1000 > hits) {
                let each: Vec<String> = peers
                    .iter()
                    .zip(&peer_hits)
                    .map(|((name, _), h)| format!("{name} {h}"))
                    .collect();
                eprintln!("{}: hits {hits} vs {}", MEASURES[m].0, each.join(", "));
                return ExitCode::FAILURE;
            }
        }
    }
    let warm = if passes > 1 {
        format!(", {passes} passes in a row per library (warm caches)")
    } else {
        String::new()
    };
    println!("{scene}: Mrays/s, best of {reps} (thread CPU time){warm}");
    for &m in &chosen {
        let n = sets[m].len() as f64;
        let rate = |t: f64| n / t * 1e-6;
        let (w, w8, ws) = (rate(best[m][0]), rate(best[m][1]), rate(best[m][2]));
        let mut line = format!("{:<15} wide {w:>6.2}", MEASURES[m].0);
        if peers.is_empty() {
            let _ = write!(line, "  wide8 {w8:>6.2}  sbvh {ws:>6.2}");
        } else {
            let fastest = |builds: &[f64]| builds.iter().map(|&t| rate(t)).fold(0.0, f64::max);
            let base = fastest(&best[m][RDBVH..RDBVH + DEFAULT_BUILDS]);
            let split_base = fastest(&best[m][RDBVH + DEFAULT_BUILDS..]);
            let _ = write!(
                line,
                " ({:.2}x)  wide8 {w8:>6.2} ({:.2}x)  sbvh {ws:>6.2} ({:.2}x)",
                w / base,
                w8 / base,
                ws / split_base
            );
            for (i, (name, _)) in peers.iter().enumerate() {
                let _ = write!(line, "  {name} {:>6.2}", rate(best[m][RDBVH + i]));
            }
        }
        println!("{line}");
    }
    ExitCode::SUCCESS
}
