//! The peer comparison behind the `peers` binary: one scene, the same triangles and the same rays
//! for rdbvh (binary, 4-wide and 8-wide), obvhs 0.4, bvh 0.13 and parry3d 0.31, and with the `cpp-peers`
//! feature Embree 3 and tinybvh (each by its default build and by its spatial-split build);
//! single-threaded and threaded builds, closest hit on camera and random rays,
//! any hit on random rays and on shadow segments ([`crate::shadow_rays`]); every library's
//! answers (closest and any hit, on all three ray sets, for the trees of both of its builds)
//! checked against rdbvh's before any number is reported.
//!
//! **Clocks.** Single-threaded measurements (`build_1t` and the traversals) report the best
//! repetition's CPU time of the thread that ran them (`CLOCK_THREAD_CPUTIME_ID`), because the
//! reference machine is shared: wall time there measures the neighbours as much as the code.
//! `build_mt` can only be wall time (its work is spread over threads), so it is the best
//! repetition's wall time; [`Clock::Wall`] reports wall time everywhere. The 2-thread scaling is
//! always wall over wall.
//!
//! **Rounds.** Every tree is checked first; then every measurement of every library (and
//! rdbvh's serial top and PAH builds) runs one repetition per round, round after round, and each
//! keeps its best. The machines are shared and their speed drifts over seconds; in rounds, every
//! library meets the same fast and slow moments, so the ratios hold when absolute numbers move.
//!
//! **The JSON contract.** [`Report::json_lines`] prints one object per line with exactly the
//! keys `library` ([`LIBRARIES`]), `measure` ([`Measure::name`]), `value` and `unit`
//! (`Mtris/s` or `Mrays/s`). obvhs is measured twice (its binary tree and its 8-wide compressed
//! tree); under `obvhs`, builds report its binary-tree build (its fastest) and each traversal
//! reports the faster of the two trees, which the text output names.
//!
//! **Peers that cannot be measured.** A peer is left out of a run, with no lines, a `-` in the
//! text table and a `warning: left out: NAME: why` on stderr, when its answers disagree with
//! rdbvh's on more than 0.1% of a ray set (closest hits compared within 1e-4 of the distance or
//! of a tenth of the scene's diagonal); when its tree would overrun its traversal's fixed stack
//! (tinybvh on degenerate builds); or when it panics. Up to 32 of the rays of a disagreement are
//! re-traced by rdbvh's brute force, which must give its tree's answers (otherwise the run stops
//! with an error: rdbvh's tree is at fault), and by an independent double-precision test, whose
//! verdict the warning reports: where rdbvh's single-precision test refuses hits it cannot
//! resolve (oblique rays through slivers), the peer can be the one that is right. rdbvh's own
//! adapters are never left out: their disagreement stops the run. A measure over an empty ray
//! set (no shadow segments where no camera ray hits a surface facing the light) has no lines
//! either, and a warning says so.

use std::fmt::Write as _;
use std::time::{Duration, Instant};

use glam::Vec3;
use rdbvh_core::builder::{BuildArena, BuildOptions, Builder, Preset, PresetOptions};
use rdbvh_core::bvh::Bvh;
use rdbvh_core::geometry::{Aabb, Ray, Triangle};
use rdbvh_core::influence::{InfluenceArea, PlaneArea, PointArea};

use crate::peers::{
    BvhCrate, Library, ObvhsBvh2, ObvhsCwbvh, Parry, Prepared, Rdbvh, RdbvhWide, RdbvhWide8,
};
use crate::{
    agreement, bounds, ray_set, single_thread_pool, thread_cpu_seconds, Agreement, Answers,
    RayKind, MIN_AGREEMENT,
};

/// The library names of the JSON output, in output order.
#[cfg(not(feature = "cpp-peers"))]
pub const LIBRARIES: &[&str] = &[
    "rdbvh",
    "rdbvh-wide",
    "rdbvh-wide8",
    "obvhs",
    "bvh",
    "parry3d",
    "rdbvh-wide8-sbvh",
];
/// The library names of the JSON output, in output order: with the C++ peers.
#[cfg(feature = "cpp-peers")]
pub const LIBRARIES: &[&str] = &[
    "rdbvh",
    "rdbvh-wide",
    "rdbvh-wide8",
    "obvhs",
    "bvh",
    "parry3d",
    "embree",
    "tinybvh",
    "embree-high",
    "tinybvh8-hq",
    "rdbvh-wide8-sbvh",
];

/// What is measured.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash)]
pub enum Measure {
    /// Build on one thread, triangles per second.
    Build1t,
    /// Build on every thread of the machine (wall time), triangles per second.
    BuildMt,
    /// Closest hit of the camera rays.
    ClosestCamera,
    /// Closest hit of the random rays.
    ClosestRandom,
    /// Any hit of the random rays.
    AnyRandom,
    /// Any hit of the shadow segments ([`crate::shadow_rays`]).
    AnyShadow,
}

impl Measure {
    /// Every measure, in output order.
    pub const ALL: [Measure; 6] = [
        Measure::Build1t,
        Measure::BuildMt,
        Measure::ClosestCamera,
        Measure::ClosestRandom,
        Measure::AnyRandom,
        Measure::AnyShadow,
    ];

    /// The name in the JSON output.
    pub fn name(self) -> &'static str {
        match self {
            Measure::Build1t => "build_1t",
            Measure::BuildMt => "build_mt",
            Measure::ClosestCamera => "closest_camera",
            Measure::ClosestRandom => "closest_random",
            Measure::AnyRandom => "any_random",
            Measure::AnyShadow => "any_shadow",
        }
    }

    /// The unit of its value.
    pub fn unit(self) -> &'static str {
        match self {
            Measure::Build1t | Measure::BuildMt => "Mtris/s",
            _ => "Mrays/s",
        }
    }

    fn is_build(self) -> bool {
        matches!(self, Measure::Build1t | Measure::BuildMt)
    }
}

/// Which clock single-threaded measurements report.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Clock {
    /// CPU time of the measuring thread (the default; `build_mt` is wall time regardless).
    ThreadCpu,
    /// Wall time for everything.
    Wall,
}

/// How long to measure.
#[derive(Clone, Copy, Debug)]
pub struct Options {
    /// Fewest rounds: repetitions of every measurement, interleaved (see `interleave`).
    pub min_reps: usize,
    /// Most rounds.
    pub max_reps: usize,
    /// After `min_reps` rounds, run another while the rounds have taken less than this per
    /// measurement (every library's every measure is one repetition per round).
    pub budget: Duration,
    /// The clock of single-threaded measurements.
    pub clock: Clock,
    /// Also measure rdbvh's PAH builds against its SAH build.
    pub pah: bool,
}

impl Default for Options {
    /// 3 to 7 repetitions within about a second per measurement: Sponza runs in well under a
    /// minute on 2 cores.
    fn default() -> Self {
        Self {
            min_reps: 3,
            max_reps: 7,
            budget: Duration::from_millis(1000),
            clock: Clock::ThreadCpu,
            pah: true,
        }
    }
}

/// The best repetition of a measurement, by each clock, in seconds.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Timing {
    /// Best CPU time of the measuring thread.
    pub cpu: f64,
    /// Best wall time.
    pub wall: f64,
    /// Repetitions run.
    pub reps: usize,
}

impl Timing {
    const NONE: Timing = Timing {
        cpu: f64::INFINITY,
        wall: f64::INFINITY,
        reps: 0,
    };

    fn add(&mut self, (cpu, wall): (f64, f64)) {
        self.cpu = self.cpu.min(cpu);
        self.wall = self.wall.min(wall);
        self.reps += 1;
    }
}

/// One run of `f`: its thread CPU and wall seconds. The output is dropped outside the timing.
fn time<R>(f: impl FnOnce() -> R) -> (f64, f64) {
    let c0 = thread_cpu_seconds();
    let w0 = Instant::now();
    let out = f();
    let wall = w0.elapsed().as_secs_f64();
    let cpu = thread_cpu_seconds() - c0;
    drop(out);
    (cpu, wall)
}

/// Something measured in several ways (`count()` of them), one repetition at a time.
trait Reps {
    fn count(&self) -> usize;
    /// One repetition of measurement `k` (thread CPU and wall seconds), or `None` when this
    /// measurement does not apply.
    fn rep(
        &mut self,
        k: usize,
        one: &rayon::ThreadPool,
        all: &rayon::ThreadPool,
    ) -> Option<(f64, f64)>;
}

/// Runs every measurement of every entry round by round: one repetition of each in turn, then
/// the next round, between `min_reps` and `max_reps` rounds and while the rounds have taken
/// less than `budget` per measurement. The machines this runs on are shared and their speed
/// drifts over seconds; interleaving gives every library the same share of fast and slow
/// moments, so the ratios hold even when the absolute numbers wander.
fn interleave(
    entries: &mut [&mut dyn Reps],
    opts: &Options,
    one: &rayon::ThreadPool,
    all: &rayon::ThreadPool,
) -> Vec<Vec<Timing>> {
    let mut best: Vec<Vec<Timing>> = entries
        .iter()
        .map(|e| vec![Timing::NONE; e.count()])
        .collect();
    let measurements: usize = entries.iter().map(|e| e.count()).sum();
    let budget = opts.budget.mul_f64(measurements as f64);
    let start = Instant::now();
    let mut rounds = 0;
    while rounds < opts.min_reps.max(1) || (rounds < opts.max_reps && start.elapsed() < budget) {
        for (entry, best) in entries.iter_mut().zip(&mut best) {
            for (k, slot) in best.iter_mut().enumerate() {
                if let Some(t) = entry.rep(k, one, all) {
                    slot.add(t);
                }
            }
        }
        rounds += 1;
    }
    best
}

/// One library's measurements, before obvhs's two trees are folded into one name.
#[derive(Clone, Debug)]
pub struct LibraryRun {
    /// The adapter's name (`obvhs-bvh2`, `obvhs-cwbvh` for obvhs).
    pub name: &'static str,
    /// Its threaded build, or `None` when `build_mt` is its one-thread build.
    pub parallel_build: Option<&'static str>,
    /// Timings per measure, in [`Measure::ALL`] order.
    pub timings: [Timing; 6],
    /// Agreement with rdbvh on the camera, random and shadow rays, tree of the one-thread build.
    pub agreement: [Agreement; 3],
    /// Agreement with rdbvh on the camera, random and shadow rays, tree of the threaded build.
    pub agreement_mt: [Agreement; 3],
}

/// One reported number.
#[derive(Clone, Debug, PartialEq)]
pub struct Row {
    /// One of [`LIBRARIES`].
    pub library: &'static str,
    /// What was measured.
    pub measure: Measure,
    /// Millions of triangles or rays per second.
    pub value: f64,
    /// The adapter that produced the number (differs from `library` only for obvhs).
    pub source: &'static str,
}

/// rdbvh's PAH builds beside its SAH build, single-threaded, on the same triangles.
#[derive(Clone, Debug)]
pub struct PahBuilds {
    /// `Preset::Sah`.
    pub sah: Timing,
    /// `Preset::Full` (PAH + SPFH) with a plane area over the scene (parallel rays).
    pub full_plane: Timing,
    /// `Preset::Full` with a point area over the scene (radial rays, perspective PAH).
    pub full_point: Timing,
    /// `Preset::Pah` (SAH's builder pricing its cuts with the area's PAH; the default of the
    /// scene structure's local BVHs) with the plane area.
    pub pah_plane: Timing,
    /// `Preset::Pah` with the point area.
    pub pah_point: Timing,
}

/// Everything one run measured.
#[derive(Clone, Debug)]
pub struct Report {
    /// The scene as given.
    pub scene: String,
    /// The shadow rays' point light ([`crate::shadow_light`]).
    pub light: Vec3,
    /// Triangles.
    pub triangles: usize,
    /// Rays per set: camera, random, shadow.
    pub rays: [usize; 3],
    /// Share of rays rdbvh finds a hit for, camera, random and shadow.
    pub hit_share: [f64; 3],
    /// Threads of the threaded builds.
    pub threads: usize,
    /// The clock of single-threaded numbers.
    pub clock: Clock,
    /// `/proc/loadavg`'s first three fields before and after the run.
    pub load: [String; 2],
    /// Per adapter.
    pub runs: Vec<LibraryRun>,
    /// The reported numbers, [`LIBRARIES`] x [`Measure::ALL`], but for libraries left out and
    /// measures over an empty ray set.
    pub rows: Vec<Row>,
    /// The peers' adapters left out, and why.
    pub left_out: Vec<(&'static str, String)>,
    /// PAH against SAH, when measured.
    pub pah: Option<PahBuilds>,
    /// Why PAH against SAH was asked for and not measured.
    pub pah_error: Option<String>,
    /// rdbvh's top of the threaded build run on one thread (`Builder::build_top`, loading the
    /// arena included) and its whole single-threaded build, CPU seconds. The threaded build
    /// loads and bins its large top nodes on all threads, so this share bounds its serial part
    /// from above, and the Amdahl bound from it is a floor, not a ceiling.
    pub serial_top: (Timing, Timing),
}

fn load_average() -> String {
    std::fs::read_to_string("/proc/loadavg")
        .map(|s| s.split_whitespace().take(3).collect::<Vec<_>>().join(" "))
        .unwrap_or_else(|_| "unknown".into())
}

/// One adapter between its checks and its timings: a scene to build from, its tree built once
/// for the traversals, the rays in its own format, and how its one-thread and threaded trees
/// agreed with rdbvh.
struct Contender<L: Library> {
    build: L::Scene,
    prepared: Prepared<L>,
    camera: Vec<L::Ray>,
    random: Vec<L::Ray>,
    shadow: Vec<L::Ray>,
    agreement: [Agreement; 3],
    agreement_mt: [Agreement; 3],
}

impl<L: Library> Contender<L> {
    /// Its timings (in [`Measure::ALL`] order) as its [`LibraryRun`]: a library without a
    /// threaded build reports its one-thread build as `build_mt`.
    fn run(&self, t: &[Timing]) -> LibraryRun {
        let build_mt = match L::PARALLEL_BUILD {
            Some(_) => t[1],
            None => t[0],
        };
        LibraryRun {
            name: L::NAME,
            parallel_build: L::PARALLEL_BUILD,
            timings: [t[0], build_mt, t[2], t[3], t[4], t[5]],
            agreement: self.agreement,
            agreement_mt: self.agreement_mt,
        }
    }
}

impl<L: Library> Reps for Contender<L>
where
    L::Scene: Send,
    L::Accel: Send,
{
    /// [`Measure::ALL`].
    fn count(&self) -> usize {
        Measure::ALL.len()
    }

    fn rep(
        &mut self,
        k: usize,
        one: &rayon::ThreadPool,
        all: &rayon::ThreadPool,
    ) -> Option<(f64, f64)> {
        let scene = &mut self.build;
        let p = &self.prepared;
        Some(match Measure::ALL[k] {
            // In the pools, so the thread CPU time is the building thread's.
            Measure::Build1t => one.install(|| time(|| L::build(scene))),
            Measure::BuildMt => {
                L::PARALLEL_BUILD?;
                all.install(|| time(|| L::build_mt(scene)))
            }
            Measure::ClosestCamera => time(|| p.closest_all(std::hint::black_box(&self.camera))),
            Measure::ClosestRandom => time(|| p.closest_all(std::hint::black_box(&self.random))),
            Measure::AnyRandom => time(|| p.any_all(std::hint::black_box(&self.random))),
            Measure::AnyShadow => time(|| p.any_all(std::hint::black_box(&self.shadow))),
        })
    }
}

/// A ray set: its kind, its rays, and rdbvh's answers on them (the reference).
pub type RaySet = (RayKind, Vec<Ray>, Answers);

/// The camera, random and shadow ray sets of `tris` ([`ray_set`]), each with the answers of
/// rdbvh's binary BVH, which every library's are checked against.
pub fn reference_sets(tris: &[Triangle]) -> Vec<RaySet> {
    let b = bounds(tris);
    let reference = Prepared::<Rdbvh>::new(tris);
    let diagonal = (b.max - b.min).length();
    [RayKind::Camera, RayKind::Random, RayKind::Shadow]
        .into_iter()
        .map(|kind| {
            let rays = ray_set(tris, &b, kind);
            let answers = reference.answers(&rays).scaled_to(&rays, diagonal);
            (kind, rays, answers)
        })
        .collect()
}

/// Why an adapter is not measured.
enum Failure {
    /// rdbvh is at fault (one of its adapters disagrees, or its brute force gives an answer its
    /// tree does not): the run stops.
    Fatal(String),
    /// A peer cannot be measured on this scene (wrong answers, a tree its traversal cannot
    /// take, a panic); the others are.
    LeftOut(String),
}

/// Rays of a disagreement that are traced again to tell whose answers are right.
const ARBITRATED: usize = 32;

/// The closest hit on `ray`'s segment over `tris` by Moller-Trumbore in double precision, two
/// sided, with no test of the determinant but zero: an arbiter that shares no code and no
/// precision rule with rdbvh's test.
fn closest_f64(ray: &Ray, tris: &[Triangle]) -> Option<f32> {
    let f = |v: Vec3| glam::DVec3::new(v.x.into(), v.y.into(), v.z.into());
    let (o, d) = (f(ray.origin), f(ray.dir));
    let (t_min, t_max) = (f64::from(ray.t_min), f64::from(ray.t_max));
    let mut best: Option<f64> = None;
    for tri in tris {
        let (v0, e1, e2) = (f(tri.v0), f(tri.v1) - f(tri.v0), f(tri.v2) - f(tri.v0));
        let p = d.cross(e2);
        let det = e1.dot(p);
        if det == 0.0 {
            continue;
        }
        let s = o - v0;
        let u = s.dot(p) / det;
        let q = s.cross(e1);
        let v = d.dot(q) / det;
        let t = e2.dot(q) / det;
        if u >= 0.0 && v >= 0.0 && u + v <= 1.0 && t >= t_min && t <= t_max {
            best = Some(best.map_or(t, |b| b.min(t)));
        }
    }
    best.map(|t| t as f32)
}

/// What re-tracing the rays of a peer's disagreement said.
struct Verdict {
    /// Rays re-traced.
    checked: usize,
    /// Of those, rays where the double-precision arbiter gives rdbvh's answer and not the peer's.
    rdbvh: usize,
    /// Rays where it gives the peer's answer and not rdbvh's.
    peer: usize,
}

/// Up to [`ARBITRATED`] of the rays where a peer's answers differ from rdbvh's, traced twice:
/// by rdbvh's own brute force (the same triangle test, so the same bits: any other answer is a
/// fault of rdbvh's tree, returned as the error) and by an independent double-precision test
/// ([`closest_f64`]), which says whose answer it is.
fn arbitrate(
    tris: &[Triangle],
    rays: &[Ray],
    reference: &Answers,
    peer: &Answers,
) -> Result<Verdict, String> {
    let mut verdict = Verdict {
        checked: 0,
        rdbvh: 0,
        peer: 0,
    };
    for i in crate::disagreements(reference, peer)
        .into_iter()
        .take(ARBITRATED)
    {
        let closest = rdbvh_core::brute_force::closest_hit(&rays[i], tris).map(|h| h.t);
        let any = rdbvh_core::brute_force::any_hit(&rays[i], tris);
        if closest != reference.closest[i] || any != reference.any[i] {
            return Err(format!(
                "ray {i} ({:?}): rdbvh answers closest {:?}, any {}; brute force {closest:?}, \
                 {any}",
                rays[i], reference.closest[i], reference.any[i]
            ));
        }
        let exact = closest_f64(&rays[i], tris);
        let right = |a: &Answers| {
            crate::same_closest(a.closest[i], exact, reference.floor(i))
                && a.any[i] == exact.is_some()
        };
        match (right(reference), right(peer)) {
            (true, false) => verdict.rdbvh += 1,
            (false, true) => verdict.peer += 1,
            _ => {}
        }
        verdict.checked += 1;
    }
    Ok(verdict)
}

/// A peer left out measures nothing.
impl<L: Library> Reps for Option<Contender<L>>
where
    L::Scene: Send,
    L::Accel: Send,
{
    fn count(&self) -> usize {
        Measure::ALL.len()
    }

    fn rep(
        &mut self,
        k: usize,
        one: &rayon::ThreadPool,
        all: &rayon::ThreadPool,
    ) -> Option<(f64, f64)> {
        self.as_mut()?.rep(k, one, all)
    }
}

/// An adapter's trees (threaded and one-thread) checked against `sets`' reference answers, and
/// the adapter ready to be timed. A peer whose answers disagree is left out, with what re-tracing
/// its disagreement said ([`arbitrate`]); rdbvh's own adapters must agree.
fn check<L: Library>(
    tris: &[Triangle],
    sets: &[RaySet],
    one: &rayon::ThreadPool,
    all: &rayon::ThreadPool,
) -> Result<Contender<L>, Failure>
where
    L::Scene: Send,
    L::Accel: Send,
{
    let own = L::NAME.starts_with("rdbvh");
    let agree = |prepared: &Prepared<L>, which: &str| -> Result<[Agreement; 3], Failure> {
        if let Some(why) = L::unusable(&prepared.accel) {
            return Err(Failure::LeftOut(format!("{which} build: {why}")));
        }
        let mut out = [Agreement {
            rays: 0,
            closest: 1.0,
            any: 1.0,
        }; 3];
        for (slot, (kind, rays, reference)) in out.iter_mut().zip(sets) {
            let answers = prepared.answers(&L::rays(rays));
            let g = agreement(reference, &answers);
            if g.closest < MIN_AGREEMENT || g.any < MIN_AGREEMENT {
                let what = format!(
                    "{which} build disagrees with rdbvh on the {} rays: closest hit {:.4}%, any \
                     hit {:.4}% of {} rays (at least {}% required)",
                    kind.name(),
                    100.0 * g.closest,
                    100.0 * g.any,
                    g.rays,
                    100.0 * MIN_AGREEMENT
                );
                if own {
                    return Err(Failure::Fatal(what));
                }
                return match arbitrate(tris, rays, reference, &answers) {
                    Ok(v) => Err(Failure::LeftOut(format!(
                        "{what}; of {} of those rays re-traced, an independent double-precision \
                         test gives rdbvh's answer on {} and {}'s on {}{}",
                        v.checked,
                        v.rdbvh,
                        L::NAME,
                        v.peer,
                        if v.peer > 0 {
                            " (rdbvh's single-precision test refuses hits it cannot resolve, \
                             such as oblique rays through slivers: docs/limits.md)"
                        } else {
                            ""
                        }
                    ))),
                    Err(e) => Err(Failure::Fatal(format!(
                        "rdbvh's tree disagrees with its brute force on the {} rays, found where {} {what}: \
                         {e}",
                        kind.name(),
                        L::NAME
                    ))),
                };
            }
            *slot = g;
        }
        Ok(out)
    };
    let mut scene = L::scene(tris);
    let accel = all.install(|| L::build_mt(&mut scene));
    let prepared = Prepared::<L> { scene, accel };
    let agreement_mt = agree(&prepared, "threaded")?;
    let mut scene = prepared.scene;
    let accel = one.install(|| L::build(&mut scene));
    let prepared = Prepared::<L> { scene, accel };
    let agreement_1t = agree(&prepared, "one-thread")?;
    let native = |kind: RayKind| {
        let set = sets.iter().find(|(k, _, _)| *k == kind).expect("ray set");
        L::rays(&set.1)
    };
    Ok(Contender {
        build: L::scene(tris),
        prepared,
        camera: native(RayKind::Camera),
        random: native(RayKind::Random),
        shadow: native(RayKind::Shadow),
        agreement: agreement_1t,
        agreement_mt,
    })
}

/// rdbvh's own adapter, checked: any failure stops the run.
fn own<L: Library>(
    tris: &[Triangle],
    sets: &[RaySet],
    one: &rayon::ThreadPool,
    all: &rayon::ThreadPool,
) -> Result<Contender<L>, String>
where
    L::Scene: Send,
    L::Accel: Send,
{
    check::<L>(tris, sets, one, all).map_err(|f| match f {
        Failure::Fatal(e) | Failure::LeftOut(e) => format!("{}: {e}", L::NAME),
    })
}

/// A peer, checked: `None` when it is left out (its name and why pushed on `left_out`), an
/// error when checking it showed rdbvh wrong. A panic in the peer's build or queries leaves it
/// out too (the panic message is kept, the default hook's report silenced meanwhile).
fn peer<L: Library>(
    tris: &[Triangle],
    sets: &[RaySet],
    one: &rayon::ThreadPool,
    all: &rayon::ThreadPool,
    left_out: &mut Vec<(&'static str, String)>,
) -> Result<Option<Contender<L>>, String>
where
    L::Scene: Send,
    L::Accel: Send,
{
    let hook = std::panic::take_hook();
    std::panic::set_hook(Box::new(|_| {}));
    let checked = std::panic::catch_unwind(std::panic::AssertUnwindSafe(|| {
        check::<L>(tris, sets, one, all)
    }));
    std::panic::set_hook(hook);
    let why = match checked {
        Ok(Ok(c)) => return Ok(Some(c)),
        Ok(Err(Failure::Fatal(e))) => return Err(e),
        Ok(Err(Failure::LeftOut(why))) => why,
        Err(payload) => {
            let message = payload
                .downcast_ref::<&str>()
                .map(|s| s.to_string())
                .or_else(|| payload.downcast_ref::<String>().cloned())
                .unwrap_or_else(|| "no message".into());
            format!("it panicked: {message}")
        }
    };
    left_out.push((L::NAME, why));
    Ok(None)
}

/// A plane area over `b`: a light rectangle on top of the box (largest y), rays straight down,
/// wide enough to cover the box whatever the rectangle's rotation about y, as deep as the box.
pub fn plane_area_over(b: &Aabb) -> Result<PlaneArea, String> {
    let e = (b.max - b.min).max(Vec3::splat(1e-3 * (b.max - b.min).length().max(1e-6)));
    let c = b.center();
    let half = 0.5 * (e.x * e.x + e.z * e.z).sqrt();
    PlaneArea::new(Vec3::new(c.x, b.max.y, c.z), -Vec3::Y, half, half, e.y)
        .map_err(|e| format!("plane area over the scene: {e}"))
}

/// A point area over `b`: a light above the box looking down, its frustum holding the box's
/// bounding sphere.
pub fn point_area_over(b: &Aabb) -> Result<PointArea, String> {
    let c = b.center();
    let r = (0.5 * (b.max - b.min).length()).max(1e-6);
    let dist = 2.0 * r;
    let fov = (2.0 * (r / dist).asin().to_degrees() * 1.1).min(170.0);
    PointArea::new(c + Vec3::Y * dist, -Vec3::Y, fov, fov, 0.0, dist + r)
        .map_err(|e| format!("point area over the scene: {e}"))
}

/// rdbvh's `sah` build, then the `full` and the `pah` presets over a plane and a point area, in
/// that order.
struct PahReps<'a> {
    tris: &'a [Triangle],
    areas: [InfluenceArea; 2],
    arena: BuildArena,
    bvh: Bvh,
}

impl<'a> PahReps<'a> {
    fn new(tris: &'a [Triangle], b: &Aabb) -> Result<Self, String> {
        let plane: InfluenceArea = plane_area_over(b)?.into();
        let point: InfluenceArea = point_area_over(b)?.into();
        let mut reps = Self {
            tris,
            areas: [plane, point],
            arena: BuildArena::with_capacity(tris.len()),
            bvh: Bvh::with_capacity(tris.len()),
        };
        // Once untimed, so a failing build is an error here, not a skipped timing.
        for k in 0..Self::BUILDS {
            reps.build(k)?;
        }
        Ok(reps)
    }

    /// `sah`, then `full` and `pah` over the plane and the point area.
    const BUILDS: usize = 5;

    fn build(&mut self, k: usize) -> Result<(), String> {
        let (preset, area) = match k {
            0 => (Preset::Sah, None),
            1 | 2 => (Preset::Full, Some(&self.areas[k - 1])),
            _ => (Preset::Pah, Some(&self.areas[k - 3])),
        };
        self.arena
            .load_triangles(self.tris)
            .map_err(|e| e.to_string())
            .and_then(|_| {
                BuildOptions::with_settings(preset, PresetOptions::default())
                    .build_into(&mut self.arena, area, &mut self.bvh)
                    .map(|_| ())
                    .map_err(|e| e.to_string())
            })
            .map_err(|e| format!("{preset} build: {e}"))
    }
}

impl Reps for PahReps<'_> {
    fn count(&self) -> usize {
        Self::BUILDS
    }

    fn rep(
        &mut self,
        k: usize,
        one: &rayon::ThreadPool,
        _: &rayon::ThreadPool,
    ) -> Option<(f64, f64)> {
        // Built once untimed in `new`: a timed build does not fail.
        Some(one.install(|| time(|| self.build(k).is_ok())))
    }
}

/// Measures every library on `tris` (named `scene` in the report).
pub fn run(scene: &str, tris: &[Triangle], opts: &Options) -> Result<Report, String> {
    if tris.is_empty() {
        return Err(format!("{scene} has no triangles"));
    }
    // Validate once with rdbvh's typed errors, so no adapter's `expect` can fire.
    Builder::sah()
        .build(tris)
        .map_err(|e| format!("{scene}: {e}"))?;
    let load_before = load_average();
    let one = single_thread_pool();
    let all = rayon::ThreadPoolBuilder::new()
        .thread_name(|i| format!("bench-mt-{i}"))
        .build()
        .map_err(|e| format!("cannot start the rayon pool: {e}"))?;
    let b = bounds(tris);
    let sets = reference_sets(tris);
    let share = |a: &Answers| {
        a.closest.iter().filter(|t| t.is_some()).count() as f64 / a.closest.len().max(1) as f64
    };
    // Every tree checked first, then every number measured in interleaved rounds.
    let mut left_out = Vec::new();
    let mut rdbvh = own::<Rdbvh>(tris, &sets, &one, &all)?;
    let mut wide = own::<RdbvhWide>(tris, &sets, &one, &all)?;
    let mut wide8 = own::<RdbvhWide8>(tris, &sets, &one, &all)?;
    let mut bvh2 = peer::<ObvhsBvh2>(tris, &sets, &one, &all, &mut left_out)?;
    let mut cwbvh = peer::<ObvhsCwbvh>(tris, &sets, &one, &all, &mut left_out)?;
    let mut bvh = peer::<BvhCrate>(tris, &sets, &one, &all, &mut left_out)?;
    let mut parry = peer::<Parry>(tris, &sets, &one, &all, &mut left_out)?;
    let mut wide8_sbvh = own::<crate::peers::RdbvhWide8Sbvh>(tris, &sets, &one, &all)?;
    #[cfg(feature = "cpp-peers")]
    let (mut embree, mut tiny8, mut tiny4, mut embree_high, mut tiny8_hq) = {
        crate::peers::embree::available()?;
        crate::peers::tinybvh::available()?;
        if u32::try_from(3 * tris.len()).is_err() {
            return Err(format!(
                "{scene}: {} triangles is more than tinybvh's 32-bit vertex count holds",
                tris.len()
            ));
        }
        let l = &mut left_out;
        (
            peer::<crate::peers::Embree>(tris, &sets, &one, &all, l)?,
            peer::<crate::peers::TinybvhBvh8>(tris, &sets, &one, &all, l)?,
            peer::<crate::peers::TinybvhBvh4>(tris, &sets, &one, &all, l)?,
            peer::<crate::peers::EmbreeHigh>(tris, &sets, &one, &all, l)?,
            peer::<crate::peers::TinybvhBvh8Hq>(tris, &sets, &one, &all, l)?,
        )
    };
    let mut top = SerialTop::new(tris, all.current_num_threads());
    // Its influence areas span the scene; where they cannot (a scene whose extent overflows
    // single precision's squares) the PAH builds go unmeasured, and the rest is still reported.
    let (mut pah_reps, pah_error) = match opts.pah.then(|| PahReps::new(tris, &b)) {
        Some(Ok(p)) => (Some(p), None),
        Some(Err(e)) => (None, Some(e)),
        None => (None, None),
    };
    let mut entries: Vec<&mut dyn Reps> = vec![
        &mut rdbvh,
        &mut wide,
        &mut wide8,
        &mut bvh2,
        &mut cwbvh,
        &mut bvh,
        &mut parry,
        &mut top,
        &mut wide8_sbvh,
    ];
    #[cfg(feature = "cpp-peers")]
    entries.extend([
        &mut embree as &mut dyn Reps,
        &mut tiny8 as &mut dyn Reps,
        &mut tiny4 as &mut dyn Reps,
        &mut embree_high as &mut dyn Reps,
        &mut tiny8_hq as &mut dyn Reps,
    ]);
    // The C++ peers come after the serial top and the SBVH, so the PAH builds are always last.
    let cpp_entries = entries.len() - 9;
    if let Some(p) = pah_reps.as_mut() {
        entries.push(p);
    }
    let t = interleave(&mut entries, opts, &one, &all);
    #[allow(unused_mut)]
    let mut runs: Vec<LibraryRun> = vec![
        Some(rdbvh.run(&t[0])),
        Some(wide.run(&t[1])),
        Some(wide8.run(&t[2])),
        bvh2.as_ref().map(|c| c.run(&t[3])),
        cwbvh.as_ref().map(|c| c.run(&t[4])),
        bvh.as_ref().map(|c| c.run(&t[5])),
        parry.as_ref().map(|c| c.run(&t[6])),
    ]
    .into_iter()
    .flatten()
    .collect();
    #[cfg(feature = "cpp-peers")]
    runs.extend(
        [
            embree.as_ref().map(|c| c.run(&t[9])),
            tiny8.as_ref().map(|c| c.run(&t[10])),
            tiny4.as_ref().map(|c| c.run(&t[11])),
            embree_high.as_ref().map(|c| c.run(&t[12])),
            tiny8_hq.as_ref().map(|c| c.run(&t[13])),
        ]
        .into_iter()
        .flatten(),
    );
    // Last, so the lines of the libraries before it keep their order.
    runs.push(wide8_sbvh.run(&t[8]));
    let serial_top = (t[7][0], t[7][1]);
    let pah = t.get(9 + cpp_entries).map(|p| PahBuilds {
        sah: p[0],
        full_plane: p[1],
        full_point: p[2],
        pah_plane: p[3],
        pah_point: p[4],
    });
    let n = tris.len();
    let rays = [sets[0].1.len(), sets[1].1.len(), sets[2].1.len()];
    let rows = fold_rows(&runs, n, rays, opts.clock);
    Ok(Report {
        scene: scene.to_string(),
        light: crate::shadow_light(&b),
        triangles: n,
        rays,
        hit_share: [share(&sets[0].2), share(&sets[1].2), share(&sets[2].2)],
        threads: all.current_num_threads(),
        clock: opts.clock,
        load: [load_before, load_average()],
        runs,
        rows,
        left_out,
        pah,
        pah_error,
        serial_top,
    })
}

/// The top of `rdbvh_core::builder::parallel::build` (the tree down to its job cutoff, the same rule: 4 jobs
/// per thread, at least 2048 primitives) run on one thread, then the whole one-thread build.
struct SerialTop<'a> {
    tris: &'a [Triangle],
    cutoff: u32,
    arena: BuildArena,
    top: Bvh,
    jobs: Vec<rdbvh_core::builder::Subtree>,
    out: Bvh,
}

impl<'a> SerialTop<'a> {
    fn new(tris: &'a [Triangle], threads: usize) -> Self {
        Self {
            tris,
            cutoff: ((tris.len() / (threads.max(1) * 4)) as u32).max(2048),
            arena: BuildArena::with_capacity(tris.len()),
            top: Bvh::with_capacity(tris.len()),
            jobs: Vec::new(),
            out: Bvh::with_capacity(tris.len()),
        }
    }
}

impl Reps for SerialTop<'_> {
    fn count(&self) -> usize {
        2
    }

    fn rep(
        &mut self,
        k: usize,
        one: &rayon::ThreadPool,
        _: &rayon::ThreadPool,
    ) -> Option<(f64, f64)> {
        let builder = Builder::sah();
        let Self {
            tris,
            cutoff,
            arena,
            top,
            jobs,
            out,
        } = self;
        Some(one.install(|| {
            time(|| {
                arena.load_triangles(tris).is_ok()
                    && if k == 0 {
                        builder.build_top(arena, top, *cutoff, jobs).is_ok()
                    } else {
                        builder.build_into(arena, out).is_ok()
                    }
            })
        }))
    }
}

/// Millions per second from a count and a timing, by the clock the measure reports.
fn rate(count: usize, t: &Timing, measure: Measure, clock: Clock) -> f64 {
    let secs = if measure == Measure::BuildMt || clock == Clock::Wall {
        t.wall
    } else {
        t.cpu
    };
    count as f64 / secs.max(1e-9) / 1e6
}

/// Folds the adapters into the reported libraries: obvhs's build is its binary tree's, each of
/// its traversals the faster tree's.
fn fold_rows(runs: &[LibraryRun], tris: usize, rays: [usize; 3], clock: Clock) -> Vec<Row> {
    let [camera, random, shadow] = rays;
    let count = |m: Measure| match m {
        Measure::Build1t | Measure::BuildMt => tris,
        Measure::ClosestCamera => camera,
        Measure::ClosestRandom | Measure::AnyRandom => random,
        Measure::AnyShadow => shadow,
    };
    // Timings are in `Measure::ALL` order.
    let value = |run: &LibraryRun, m: Measure| {
        let i = Measure::ALL
            .iter()
            .position(|&x| x == m)
            .expect("a measure");
        rate(count(m), &run.timings[i], m, clock)
    };
    let find = |name: &str| runs.iter().find(|r| r.name == name);
    // The faster of two adapters of one library (either may be left out); `first_builds`:
    // builds are the first's while it is measured.
    let faster = |first: &str, second: &str, m: Measure, first_builds: bool| match (
        find(first),
        find(second),
    ) {
        (Some(x), Some(y)) => {
            let (a, b) = (value(x, m), value(y, m));
            Some(if (first_builds && m.is_build()) || a >= b {
                (x.name, a)
            } else {
                (y.name, b)
            })
        }
        (Some(r), None) | (None, Some(r)) => Some((r.name, value(r, m))),
        (None, None) => None,
    };
    let mut rows = Vec::new();
    for &library in LIBRARIES {
        // A rate over no rays is no number: no line (a scene that no camera ray hits has no
        // shadow segments).
        for m in Measure::ALL.into_iter().filter(|&m| count(m) > 0) {
            let row = match library {
                "obvhs" => faster("obvhs-bvh2", "obvhs-cwbvh", m, true),
                "tinybvh" => faster("tinybvh-bvh8", "tinybvh-bvh4", m, false),
                _ => find(library).map(|r| (r.name, value(r, m))),
            };
            if let Some((source, v)) = row {
                rows.push(Row {
                    library,
                    measure: m,
                    value: v,
                    source,
                });
            }
        }
    }
    rows
}

impl Report {
    /// The reported number of `library` for `measure`.
    pub fn value(&self, library: &str, measure: Measure) -> Option<f64> {
        self.rows
            .iter()
            .find(|r| r.library == library && r.measure == measure)
            .map(|r| r.value)
    }

    /// One JSON object per row: `library`, `measure`, `value` (rounded to 4 decimals) and `unit`.
    pub fn json_lines(&self) -> Vec<String> {
        self.rows
            .iter()
            .map(|r| {
                format!(
                    "{{\"library\":\"{}\",\"measure\":\"{}\",\"value\":{:.4},\"unit\":\"{}\"}}",
                    r.library,
                    r.measure.name(),
                    if r.value.is_finite() { r.value } else { 0.0 },
                    r.measure.unit()
                )
            })
            .collect()
    }

    /// What the table and the JSON lines leave out, a line each: every adapter left out (its
    /// name and why), and a measure over an empty ray set.
    pub fn omissions(&self) -> Vec<String> {
        let mut lines: Vec<String> = self
            .left_out
            .iter()
            .map(|(name, why)| format!("left out: {name}: {why}"))
            .collect();
        if self.rays[2] == 0 {
            lines.push(
                "any_shadow: no shadow segments (no camera ray hits a surface facing the light)"
                    .into(),
            );
        }
        lines
    }

    /// rdbvh's build speed-up from 1 thread to all threads, wall time over wall time.
    pub fn rdbvh_scaling(&self) -> f64 {
        let r = self.runs.iter().find(|r| r.name == "rdbvh").expect("rdbvh");
        r.timings[0].wall / r.timings[1].wall.max(1e-12)
    }

    /// The human-readable report.
    pub fn text(&self) -> String {
        let mut s = String::new();
        let w = &mut s;
        let _ = writeln!(
            w,
            "scene {}: {} triangles; {} camera rays ({:.1}% hit), {} random rays ({:.1}% hit), \
             {} shadow rays ({:.1}% occluded) to a light at {:?}",
            self.scene,
            self.triangles,
            self.rays[0],
            100.0 * self.hit_share[0],
            self.rays[1],
            100.0 * self.hit_share[1],
            self.rays[2],
            100.0 * self.hit_share[2],
            self.light.to_array(),
        );
        let _ = writeln!(
            w,
            "load average {} before, {} after; build_mt on {} threads; rdbvh-wide8 traverses \
             with {:?} (RDBVH_SIMD=baseline for the compiled baseline)",
            self.load[0],
            self.load[1],
            self.threads,
            rdbvh_core::bvh::simd_level()
        );
        let _ = writeln!(
            w,
            "clock: {}; best of {}-{} interleaved rounds; (ratio) = value / rdbvh's, higher is faster",
            match self.clock {
                Clock::ThreadCpu =>
                    "thread CPU time for build_1t and traversals, wall time for build_mt",
                Clock::Wall => "wall time everywhere",
            },
            self.runs
                .iter()
                .flat_map(|r| r.timings.iter().map(|t| t.reps))
                .min()
                .unwrap_or(0),
            self.runs
                .iter()
                .flat_map(|r| r.timings.iter().map(|t| t.reps))
                .max()
                .unwrap_or(0),
        );
        let _ = writeln!(w);
        let _ = write!(w, "{:<11}", "library");
        for m in Measure::ALL {
            let _ = write!(w, " {:>24}", format!("{} {}", m.name(), m.unit()));
        }
        let _ = writeln!(w);
        for &library in LIBRARIES {
            let _ = write!(w, "{library:<11}");
            for m in Measure::ALL {
                let base = self.value("rdbvh", m).unwrap_or(0.0);
                let cell = match self.value(library, m) {
                    None => "-".to_string(),
                    Some(v) if library == "rdbvh" => format!("{v:.2}"),
                    Some(v) => format!("{v:.2} ({:.2}x)", v / base.max(1e-12)),
                };
                let _ = write!(w, " {cell:>24}");
            }
            let _ = writeln!(w);
        }
        let _ = writeln!(w);
        for line in self.omissions() {
            let _ = writeln!(w, "{line}");
        }
        let obvhs: Vec<String> = self
            .rows
            .iter()
            .filter(|r| r.library == "obvhs")
            .map(|r| format!("{} {}", r.measure.name(), r.source))
            .collect();
        let _ = writeln!(
            w,
            "obvhs: its fast_build (PLOC); builds are obvhs-bvh2's (its faster build), traversals \
             its faster tree: {}",
            obvhs.join(", ")
        );
        let tinybvh: Vec<String> = self
            .rows
            .iter()
            .filter(|r| r.library == "tinybvh")
            .map(|r| format!("{} {}", r.measure.name(), r.source))
            .collect();
        if !tinybvh.is_empty() {
            let _ = writeln!(
                w,
                "tinybvh: its default Build (binned SAH) into BVH8_CPU or BVH4_CPU, each measure \
                 the faster layout: {}",
                tinybvh.join(", ")
            );
            let _ = writeln!(
                w,
                "embree-high, tinybvh8-hq: their spatial-split builds (Embree's \
                 RTC_BUILD_QUALITY_HIGH, where embree is its default MEDIUM; tinybvh's BuildHQ \
                 into BVH8_CPU)"
            );
        }
        for r in &self.runs {
            let _ = writeln!(
                w,
                "build_mt {}: {}",
                r.name,
                r.parallel_build
                    .unwrap_or("no threaded build; build_mt reports its 1-thread build")
            );
        }
        let _ = writeln!(
            w,
            "rdbvh build scaling, {} threads vs 1 (wall/wall): {:.2}x",
            self.threads,
            self.rdbvh_scaling()
        );
        let (top, whole) = &self.serial_top;
        let f = (top.cpu / whole.cpu.max(1e-12)).min(1.0);
        let p = self.threads.max(1) as f64;
        let _ = writeln!(
            w,
            "rdbvh threaded build: its top on one thread (load + build_top) {:.1} ms of a {:.1} ms \
             1-thread build ({:.0}%; the threaded build loads and bins it on all threads): Amdahl \
             bound on {} threads at least {:.2}x",
            1e3 * top.cpu,
            1e3 * whole.cpu,
            100.0 * f,
            self.threads,
            1.0 / (f + (1.0 - f) / p)
        );
        let _ = writeln!(w);
        let _ = writeln!(
            w,
            "agreement with rdbvh (closest / any hit), 1-thread tree | threaded tree:"
        );
        for r in &self.runs {
            let cell = |g: &Agreement| format!("{:.4}% / {:.4}%", 100.0 * g.closest, 100.0 * g.any);
            let _ = writeln!(
                w,
                "  {:<12} camera {} | {}   random {} | {}   shadow {} | {}",
                r.name,
                cell(&r.agreement[0]),
                cell(&r.agreement_mt[0]),
                cell(&r.agreement[1]),
                cell(&r.agreement_mt[1]),
                cell(&r.agreement[2]),
                cell(&r.agreement_mt[2]),
            );
        }
        if let Some(e) = &self.pah_error {
            let _ = writeln!(w);
            let _ = writeln!(w, "PAH vs SAH: not measured: {e}");
        }
        if let Some(p) = &self.pah {
            let m = |t: &Timing| rate(self.triangles, t, Measure::Build1t, self.clock);
            let sah = m(&p.sah);
            let _ = writeln!(w);
            let _ = write!(
                w,
                "PAH vs SAH, rdbvh presets, 1 thread: sah {sah:.2} Mtris/s"
            );
            for (name, plane, point) in [
                ("full (PAH+SPFH)", &p.full_plane, &p.full_point),
                ("pah (PAH, all axes)", &p.pah_plane, &p.pah_point),
            ] {
                let (plane, point) = (m(plane), m(point));
                let _ = write!(
                    w,
                    "; {name} plane area {plane:.2} Mtris/s ({:.2}x the SAH time), point area \
                     {point:.2} Mtris/s ({:.2}x)",
                    sah / plane.max(1e-12),
                    sah / point.max(1e-12)
                );
            }
            let _ = writeln!(w);
        }
        s
    }
}

/// What the `peers` binary was asked for.
#[derive(Clone, Debug, PartialEq)]
pub struct Args {
    /// An OBJ path or `builtin:NAME`.
    pub scene: String,
    /// JSON lines instead of the text report.
    pub json: bool,
    /// Wall time for every measure.
    pub wall: bool,
}

/// The usage line.
pub const USAGE: &str = "usage: peers SCENE.obj|builtin:NAME [--json] [--wall]";

/// Parses the binary's arguments.
pub fn parse_args(args: impl IntoIterator<Item = String>) -> Result<Args, String> {
    let mut scene = None;
    let mut json = false;
    let mut wall = false;
    for a in args {
        match a.as_str() {
            "--json" => json = true,
            "--wall" => wall = true,
            "-h" | "--help" => return Err(USAGE.to_string()),
            s if s.starts_with("--") => return Err(format!("unknown option {s}; {USAGE}")),
            s => {
                if scene.replace(s.to_string()).is_some() {
                    return Err(format!("more than one scene given; {USAGE}"));
                }
            }
        }
    }
    let scene = scene.ok_or_else(|| format!("no scene given; {USAGE}"))?;
    Ok(Args { scene, json, wall })
}

/// The whole binary: loads the scene, measures, and returns what to print.
pub fn main_with(args: impl IntoIterator<Item = String>, opts: Options) -> Result<String, String> {
    let args = parse_args(args)?;
    let scene = rdbvh::scene::Scene::open(&args.scene)
        .map_err(|e| format!("cannot load {}: {e}", args.scene))?;
    let opts = Options {
        clock: if args.wall { Clock::Wall } else { opts.clock },
        ..opts
    };
    let report = run(&args.scene, &scene.triangles, &opts)?;
    if args.json {
        // The JSON lines hold only what was measured; stderr says what was not.
        for line in report.omissions() {
            eprintln!("warning: {line}");
        }
    }
    Ok(if args.json {
        let mut s = report.json_lines().join("\n");
        s.push('\n');
        s
    } else {
        report.text()
    })
}

#[cfg(test)]
mod tests {
    use super::*;

    /// A peer that finds nothing, wrong on every ray that hits; `OWN`: under one of rdbvh's
    /// names, so its disagreement is rdbvh's own; `PANICS`: its build panics.
    struct Fake<const OWN: bool, const PANICS: bool>;

    type Blind = Fake<false, false>;
    type OwnBlind = Fake<true, false>;
    type Panics = Fake<false, true>;

    impl<const OWN: bool, const PANICS: bool> Library for Fake<OWN, PANICS> {
        const NAME: &'static str = match (OWN, PANICS) {
            (true, _) => "rdbvh-blind",
            (false, true) => "panics",
            (false, false) => "blind",
        };
        const PARALLEL_BUILD: Option<&'static str> = None;
        type Scene = ();
        type Ray = ();
        type Accel = ();
        fn scene(_: &[Triangle]) {}
        fn rays(rays: &[Ray]) -> Vec<()> {
            vec![(); rays.len()]
        }
        fn build(_: &mut ()) {
            assert!(!PANICS, "a peer's own assertion");
        }
        fn closest(_: &(), _: &(), _: &()) -> Option<f32> {
            None
        }
        fn any(_: &(), _: &(), _: &()) -> bool {
            false
        }
    }

    /// rdbvh's answers, from a tree that its traversal could not take.
    struct Refused;

    impl Library for Refused {
        const NAME: &'static str = "refused";
        const PARALLEL_BUILD: Option<&'static str> = None;
        type Scene = Vec<Triangle>;
        type Ray = Ray;
        type Accel = Bvh;
        fn scene(tris: &[Triangle]) -> Vec<Triangle> {
            tris.to_vec()
        }
        fn rays(rays: &[Ray]) -> Vec<Ray> {
            rays.to_vec()
        }
        fn build(tris: &mut Vec<Triangle>) -> Bvh {
            Builder::sah().build(tris).expect("a scene")
        }
        fn unusable(_: &Bvh) -> Option<String> {
            Some("too deep".into())
        }
        fn closest(bvh: &Bvh, tris: &Vec<Triangle>, ray: &Ray) -> Option<f32> {
            bvh.closest_hit(ray, tris).map(|h| h.t)
        }
        fn any(bvh: &Bvh, tris: &Vec<Triangle>, ray: &Ray) -> bool {
            bvh.any_hit(ray, tris)
        }
    }

    fn scene() -> (Vec<Triangle>, Vec<RaySet>) {
        let tris = rdbvh::scene::Scene::open("builtin:random1000")
            .expect("built in")
            .triangles;
        let sets = reference_sets(&tris);
        (tris, sets)
    }

    #[test]
    fn a_peer_that_cannot_be_measured_is_left_out_and_says_why() {
        let (tris, sets) = scene();
        let (one, all) = (single_thread_pool(), single_thread_pool());
        let mut left_out = Vec::new();
        assert!(peer::<Blind>(&tris, &sets, &one, &all, &mut left_out)
            .expect("rdbvh is right")
            .is_none());
        assert!(peer::<Panics>(&tris, &sets, &one, &all, &mut left_out)
            .expect("a panic is the peer's")
            .is_none());
        assert!(peer::<Refused>(&tris, &sets, &one, &all, &mut left_out)
            .expect("refused")
            .is_none());
        let names: Vec<&str> = left_out.iter().map(|(n, _)| *n).collect();
        assert_eq!(names, ["blind", "panics", "refused"]);
        assert!(
            left_out[0].1.ends_with(
                "of 32 of those rays re-traced, an independent double-precision test gives \
                 rdbvh's answer on 32 and blind's on 0"
            ),
            "{}",
            left_out[0].1
        );
        assert_eq!(left_out[1].1, "it panicked: a peer's own assertion");
        assert_eq!(left_out[2].1, "threaded build: too deep");
        // The same failure in one of rdbvh's own adapters stops the run.
        let e = own::<OwnBlind>(&tris, &sets, &one, &all)
            .err()
            .expect("an error");
        assert!(
            e.starts_with("rdbvh-blind: threaded build disagrees with rdbvh on the camera rays"),
            "{e}"
        );
    }

    #[test]
    fn brute_force_decides_who_is_wrong() {
        let (tris, sets) = scene();
        let (_, rays, reference) = &sets[1];
        let blind = Answers {
            closest: vec![None; rays.len()],
            any: vec![false; rays.len()],
            floor: Vec::new(),
        };
        let wrong = crate::disagreements(reference, &blind);
        assert!(wrong.len() > ARBITRATED, "{}", wrong.len());
        let v = arbitrate(&tris, rays, reference, &blind).expect("rdbvh right");
        assert_eq!((v.checked, v.rdbvh, v.peer), (ARBITRATED, ARBITRATED, 0));
        // Were rdbvh the one that misses, its brute force says so, on the first ray it checks.
        let e = arbitrate(&tris, rays, &blind, reference)
            .err()
            .expect("rdbvh wrong");
        assert!(e.starts_with(&format!("ray {} (", wrong[0])), "{e}");
    }

    /// Slivers 2000 units long and 2e-3 high, hit 6 degrees off their plane: rdbvh's single-precision test
    /// refuses the hits (its determinant bound, `docs/limits.md`), the double-precision arbiter
    /// finds them, and a peer that finds them is the one it sides with.
    #[test]
    fn the_arbiter_sides_with_a_peer_where_rdbvh_refuses_a_hit() {
        let tris: Vec<Triangle> = (0..20)
            .map(|i| {
                let y = i as f32 * 0.1;
                Triangle::new(
                    Vec3::new(-1000.0, y, 0.0),
                    Vec3::new(1000.0, y, 0.0),
                    Vec3::new(0.0, y + 2e-3, 0.0),
                )
            })
            .collect();
        let rays: Vec<Ray> = (0..20)
            .map(|i| {
                let o = Vec3::new(0.0, i as f32 * 0.1 + 1e-3 - 10.0, 1.0);
                Ray::new(o, Vec3::new(0.0, 10.0, -1.0)).expect("a ray")
            })
            .collect();
        let diagonal = (bounds(&tris).max - bounds(&tris).min).length();
        let reference = Prepared::<Rdbvh>::new(&tris)
            .answers(&rays)
            .scaled_to(&rays, diagonal);
        let exact: Vec<Option<f32>> = rays.iter().map(|r| closest_f64(r, &tris)).collect();
        assert!(exact.iter().all(Option::is_some), "{exact:?}");
        let finder = Answers {
            any: exact.iter().map(Option::is_some).collect(),
            closest: exact,
            floor: Vec::new(),
        };
        let v = arbitrate(&tris, &rays, &reference, &finder).expect("rdbvh's tree is right");
        assert!(v.checked > 10, "{}", v.checked);
        assert_eq!((v.peer, v.rdbvh), (v.checked, 0));
    }

    #[test]
    fn rows_skip_what_was_left_out_and_empty_ray_sets() {
        let timing = Timing {
            cpu: 0.5,
            wall: 1.0,
            reps: 1,
        };
        let run = |name: &'static str| LibraryRun {
            name,
            parallel_build: None,
            timings: [timing; 6],
            agreement: [Agreement {
                rays: 1,
                closest: 1.0,
                any: 1.0,
            }; 3],
            agreement_mt: [Agreement {
                rays: 1,
                closest: 1.0,
                any: 1.0,
            }; 3],
        };
        // obvhs measured by its compressed tree only; `bvh` left out; no shadow segments.
        let runs = [run("rdbvh"), run("obvhs-cwbvh")];
        let rows = fold_rows(&runs, 1000, [100, 100, 0], Clock::ThreadCpu);
        let measured: Vec<Measure> = Measure::ALL
            .into_iter()
            .filter(|&m| m != Measure::AnyShadow)
            .collect();
        let of = |library: &str| -> Vec<(Measure, &str)> {
            rows.iter()
                .filter(|r| r.library == library)
                .map(|r| (r.measure, r.source))
                .collect()
        };
        let expect = |source| measured.iter().map(|&m| (m, source)).collect::<Vec<_>>();
        assert_eq!(of("rdbvh"), expect("rdbvh"));
        assert_eq!(of("obvhs"), expect("obvhs-cwbvh"));
        assert!(of("bvh").is_empty());
        assert_eq!(rows.len(), 2 * measured.len());
    }
}
