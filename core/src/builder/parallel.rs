//! Threaded builds on rayon's pool (the `rayon` feature): the same trees as the one-thread
//! build, sooner. [`super::BuildOptions::parallel`] runs a preset here; these functions run any
//! [`Builder`].
//!
//! One thread builds the top of the tree and hands over each node of at most `cutoff` primitives
//! as a job the moment it reaches it ([`Builder::build_top_into`]); rayon builds the jobs on all
//! threads meanwhile, largest first ([`Builder::build_subtree_into`]), and [`Bvh::graft_with`]
//! splices them in, in the single-threaded order. The result is the single-threaded tree node
//! for node. The serial part is kept small: triangle loading
//! ([`BuildArena::load_triangles_with`]) and the top nodes' binning ([`Builder::build_top_with`])
//! run in parallel parts, which merge exactly.

use alloc::collections::BinaryHeap;
use alloc::vec::Vec;
use core::cmp::{Ordering, Reverse};

use rayon::prelude::*;
use std::sync::Mutex;

use super::{
    BinJob, BuildArena, Builder, GraftBlock, LoadedBounds, NodeBinner, NodeBins, Subtree,
    SubtreeSink, TriangleLoad,
};
use crate::bvh::Bvh;
use crate::geometry::Triangle;
use crate::heuristics::{AxisChooser, CostModel, Termination};
use crate::BuildError;

/// Jobs per thread: enough that uneven subtrees still balance across threads, few enough that
/// the top (whose partitions run on one thread) stays shallow; 4 was faster than 2 and 16.
const JOBS_PER_THREAD: usize = 4;

/// The smallest subtree worth a job of its own: below this, scheduling costs more than it saves.
const MIN_JOB: u32 = 2048;

/// Triangles per part of a threaded load, and primitives per part of a threaded binning pass:
/// large enough that a part outweighs the cost of a rayon task, small enough to balance.
const PART: usize = 16 * 1024;

/// Loads the triangles of `load` in parts of at most [`PART`] on the current pool.
fn load_parallel(load: TriangleLoad<'_>) -> Result<LoadedBounds, BuildError> {
    if load.len() <= PART {
        return load.run();
    }
    let mid = load.len() / 2;
    let (a, b) = load.split_at(mid);
    let (a, b) = rayon::join(|| load_parallel(a), || load_parallel(b));
    LoadedBounds::merge(a, b)
}

/// Bins nodes of at least two parts' primitives in parts on the current pool.
#[derive(Clone, Copy, Debug, Default)]
struct ParallelBinner;

impl ParallelBinner {
    fn bin_range(job: &BinJob<'_>, range: std::ops::Range<usize>) -> NodeBins {
        if range.len() <= PART {
            return job.bin_range(range);
        }
        let mid = range.start + range.len() / 2;
        let (mut a, b) = rayon::join(
            || Self::bin_range(job, range.start..mid),
            || Self::bin_range(job, mid..range.end),
        );
        a.merge(&b);
        a
    }
}

impl NodeBinner for ParallelBinner {
    fn bin(&self, job: &BinJob<'_>) -> Option<NodeBins> {
        (job.len() >= 2 * PART).then(|| Self::bin_range(job, 0..job.len()))
    }
}

/// The cutoff for `n` primitives on the current rayon pool.
fn cutoff(n: usize) -> u32 {
    let jobs = rayon::current_num_threads().max(1) * JOBS_PER_THREAD;
    ((n / jobs) as u32).max(MIN_JOB)
}

/// Builds over `tris` with every rayon thread. Equal to `builder.build(tris)`.
pub fn build<A, C, T>(builder: &Builder<A, C, T>, tris: &[Triangle]) -> Result<Bvh, BuildError>
where
    A: AxisChooser + Sync,
    C: CostModel + Sync,
    T: Termination + Sync,
{
    let mut arena = BuildArena::with_capacity(tris.len());
    arena.load_triangles_with(tris, load_parallel)?;
    build_loaded(builder, &mut arena)
}

/// Starts the global pool's threads, which rayon does on first use: a command calls it before
/// its clock starts, so a timed build does not include creating threads.
pub fn start_pool() {
    rayon::current_num_threads();
}

/// Loads every triangle of `tris` into `arena` in parallel parts: the same primitives, and the
/// same error for the first bad triangle, as `arena.load_triangles(tris)`.
pub fn load_triangles(arena: &mut BuildArena, tris: &[Triangle]) -> Result<(), BuildError> {
    arena.load_triangles_with(tris, load_parallel)
}

/// Builds over the primitives loaded in `arena` with every rayon thread. Equal to
/// `builder.build_into(arena, ..)`.
pub fn build_loaded<A, C, T>(
    builder: &Builder<A, C, T>,
    arena: &mut BuildArena,
) -> Result<Bvh, BuildError>
where
    A: AxisChooser + Sync,
    C: CostModel + Sync,
    T: Termination + Sync,
{
    let cutoff = cutoff(arena.len());
    if arena.len() <= cutoff as usize {
        // The root would be the only job: no thread to share it with.
        let mut bvh = Bvh::with_capacity(arena.len());
        builder.build_into(arena, &mut bvh)?;
        return Ok(bvh);
    }
    let mut top = Bvh::with_capacity(arena.len());
    let mut jobs = Vec::new();
    let pending = Mutex::new(BinaryHeap::new());
    let built = Mutex::new(Vec::new());
    let top_built = rayon::scope(|scope| {
        let mut sink = Spawner {
            scope,
            builder,
            jobs: &mut jobs,
            pending: &pending,
            built: &built,
        };
        builder.build_top_into(arena, &mut top, cutoff, &mut sink, &ParallelBinner)
    });
    top_built?;
    // A job that panicked has already re-raised its panic through the scope.
    let mut built = built.into_inner().unwrap_or_else(|e| e.into_inner());
    built.sort_unstable_by_key(|(index, _)| *index);
    let subtrees = built
        .into_iter()
        .map(|(_, subtree)| subtree)
        .collect::<Result<Vec<Bvh>, BuildError>>()?;
    // The subtrees' copies into the whole tree, and the first touches of its pages, run on all
    // threads (see `Bvh::graft_with`).
    Bvh::graft_with(top, &jobs, &subtrees, |blocks| {
        blocks.into_par_iter().for_each(GraftBlock::copy)
    })
    .map_err(|_| BuildError::InvalidConfig("graft mismatch"))
}

/// A subtree built by a job, by its index among the jobs.
type Built = (usize, Result<Bvh, BuildError>);

/// A job waiting for a thread: its subtree, its index among the jobs, and its primitives, already
/// copied out of the top's arena (or the copy's error).
struct Pending {
    index: usize,
    job: Subtree,
    local: BuildArena,
    loaded: Result<(), BuildError>,
}

/// Waiting jobs, the largest first (ties: the earlier one), so a free thread takes the largest.
impl Ord for Pending {
    fn cmp(&self, other: &Self) -> Ordering {
        (self.job.count, Reverse(self.index)).cmp(&(other.job.count, Reverse(other.index)))
    }
}

impl PartialOrd for Pending {
    fn partial_cmp(&self, other: &Self) -> Option<Ordering> {
        Some(self.cmp(other))
    }
}

impl PartialEq for Pending {
    fn eq(&self, other: &Self) -> bool {
        self.cmp(other) == Ordering::Equal
    }
}

impl Eq for Pending {}

/// Starts each subtree's build as soon as the top leaves it: its primitives are copied into an
/// arena of its own on the top's thread (the top never touches those slots again), and the build
/// runs on any thread while the top goes on, so the top's serial partitions overlap the subtree
/// builds instead of preceding them all.
///
/// Each job spawned is a ticket, not a subtree: the task that runs takes the largest job waiting
/// then (longest job first), so a large subtree never starts last and runs alone at the end while
/// the other threads idle.
struct Spawner<'scope, 'env, A, C, T> {
    scope: &'env rayon::Scope<'scope>,
    builder: &'scope Builder<A, C, T>,
    jobs: &'env mut Vec<Subtree>,
    pending: &'scope Mutex<BinaryHeap<Pending>>,
    built: &'scope Mutex<Vec<Built>>,
}

impl<A, C, T> SubtreeSink for Spawner<'_, '_, A, C, T>
where
    A: AxisChooser + Sync,
    C: CostModel + Sync,
    T: Termination + Sync,
{
    fn take(&mut self, job: Subtree, arena: &BuildArena) {
        let index = self.jobs.len();
        self.jobs.push(job);
        let mut local = BuildArena::with_capacity(job.count as usize);
        let loaded = local.load_slots(arena, job.start as usize..(job.start + job.count) as usize);
        let (builder, pending, built) = (self.builder, self.pending, self.built);
        lock(pending).push(Pending {
            index,
            job,
            local,
            loaded,
        });
        self.scope.spawn(move |_| {
            // One ticket per job pushed, so there is always one to take.
            let Some(Pending {
                index,
                job,
                mut local,
                loaded,
            }) = lock(pending).pop()
            else {
                return;
            };
            let subtree = loaded.and_then(|()| {
                let mut out = Bvh::with_capacity(job.count as usize);
                builder.build_subtree_into(&mut local, &mut out, &job)?;
                Ok(out)
            });
            lock(built).push((index, subtree));
        });
    }
}

/// Locks `m`; a panic that poisoned it has already been re-raised through the scope, and the
/// data (a list of jobs or results) is still whole.
fn lock<T>(m: &Mutex<T>) -> std::sync::MutexGuard<'_, T> {
    m.lock().unwrap_or_else(|e| e.into_inner())
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::builder::{BuildConfig, BuildOptions, Preset, PresetError, PresetOptions};
    use crate::heuristics::{AllAxes, PahPerspective, PerspectiveMeasure, SahTermination};
    use crate::influence::{InfluenceArea, PlaneArea, PointArea};
    use crate::random::Pcg32;
    use crate::Vec3;

    fn soup(n: usize) -> Vec<Triangle> {
        let mut rng = Pcg32::new(3);
        let mut v = |s: f32| Vec3::new(rng.range(-s, s), rng.range(-s, s), rng.range(-s, s));
        (0..n)
            .map(|_| {
                let a = v(10.0);
                Triangle::new(a, a + v(0.4), a + v(0.4))
            })
            .collect()
    }

    #[test]
    fn threaded_build_equals_single_threaded() {
        let tris = soup(40_000);
        let sah = Builder::sah();
        assert_eq!(build(&sah, &tris).unwrap(), sah.build(&tris).unwrap());
        let lsph = Builder::lsph();
        assert_eq!(build(&lsph, &tris).unwrap(), lsph.build(&tris).unwrap());
        assert_eq!(build(&lsph, &[]).unwrap(), lsph.build(&[]).unwrap());
    }

    #[test]
    fn threaded_perspective_pah_build_equals_single_threaded() {
        // The jobs' roots take the measures the top's splits priced them with, as the
        // single-threaded build does (`graft`'s tests check that a job's measure is used), and a
        // box's measure does not depend on the boxes beside it in a group of four.
        let tris = soup(40_000);
        for (eye, fov) in [
            (Vec3::new(0.0, 14.0, 0.0), 80.0),
            (Vec3::new(0.0, 11.0, 0.0), 120.0),
            (Vec3::new(1.0, 2.0, 0.5), 150.0),
        ] {
            let area = PointArea::new(eye, -Vec3::Y, fov, fov, 0.1, 30.0).unwrap();
            for measure in [
                PerspectiveMeasure::SolidAngle,
                PerspectiveMeasure::ImagePlane,
            ] {
                let pah = PahPerspective::for_area(&area, measure);
                let config = BuildConfig::default();
                let b = Builder::new(AllAxes, pah, SahTermination::default(), config);
                assert_eq!(
                    build(&b, &tris).unwrap(),
                    b.build(&tris).unwrap(),
                    "{eye} {fov}"
                );
            }
        }
    }

    #[test]
    fn threaded_presets_equal_single_threaded() {
        // Every preset, both kinds of area (one the soup straddles, so the window's border runs
        // through the top nodes), the project's and the thesis's settings.
        let tris = soup(30_000);
        let areas: [InfluenceArea; 2] = [
            PlaneArea::new(Vec3::new(2.0, 12.0, 0.0), -Vec3::Y, 6.0, 8.0, 30.0)
                .unwrap()
                .into(),
            PointArea::new(Vec3::new(0.0, 13.0, 1.0), -Vec3::Y, 70.0, 90.0, 0.5, 30.0)
                .unwrap()
                .into(),
        ];
        for settings in [PresetOptions::default(), PresetOptions::thesis()] {
            for area in &areas {
                for preset in Preset::ALL {
                    for for_wide in [false, true] {
                        let serial = BuildOptions {
                            settings,
                            for_wide,
                            ..BuildOptions::new(preset)
                        };
                        let threaded = BuildOptions {
                            parallel: true,
                            ..serial
                        };
                        assert!(
                            threaded.build(&tris, Some(area)) == serial.build(&tris, Some(area)),
                            "{preset} {area:?} {} {for_wide}",
                            settings.thesis_mode
                        );
                    }
                }
            }
        }
        let full = BuildOptions {
            parallel: true,
            ..BuildOptions::new(Preset::Full)
        };
        assert_eq!(
            full.build(&tris, None),
            Err(PresetError::NeedsArea(Preset::Full))
        );
    }

    #[test]
    fn threaded_top_binning_and_load_equal_single_threaded() {
        // Large enough that the root and the next levels are binned in parallel parts and the
        // load runs in parts.
        let tris = soup(150_000);
        let mut serial = BuildArena::with_capacity(tris.len());
        serial.load_triangles(&tris).unwrap();
        let mut parallel = BuildArena::with_capacity(tris.len());
        parallel.load_triangles_with(&tris, load_parallel).unwrap();
        assert!((0..tris.len()).all(|i| serial.prim(i) == parallel.prim(i)));
        let sah = Builder::sah();
        assert_eq!(build(&sah, &tris).unwrap(), sah.build(&tris).unwrap());
        let one = rayon::ThreadPoolBuilder::new()
            .num_threads(1)
            .build()
            .unwrap();
        assert_eq!(
            one.install(|| build(&sah, &tris)).unwrap(),
            sah.build(&tris).unwrap()
        );
    }

    #[test]
    fn threaded_load_reports_the_first_bad_triangle() {
        let mut tris = soup(100_000);
        tris[70_000].v1.x = f32::NAN;
        tris[20_000].v2.z = f32::INFINITY;
        let sah = Builder::sah();
        assert_eq!(build(&sah, &tris), sah.build(&tris));
        assert_eq!(
            build(&sah, &tris),
            Err(BuildError::InvalidPrimitive { index: 20_000 })
        );
    }
}
