//! Proof that a build over a caller-sized arena allocates nothing, and neither do the traversals
//! or a reused reinsertion.
//!
//! A counting global allocator counts calls per thread (a `const` thread-local, so counting itself
//! never allocates), and each measurement reads the count of its own thread only, so tests running
//! in parallel in this binary cannot disturb each other.

use std::alloc::{GlobalAlloc, Layout, System};
use std::cell::Cell;
use std::hint::black_box;

use rdbvh_core::builder::{
    BinSpace, BuildArena, BuildConfig, Builder, CutEvaluation, ReinsertConfig, Reinserter,
    ThesisCut,
};
use rdbvh_core::bvh::{Bvh, TraversalStats};
use rdbvh_core::geometry::{Aabb, Ray, Triangle};
use rdbvh_core::heuristics::{
    AllAxes, AxisChooser, CostModel, LeafSize, LongestAxis, Sah, Termination,
};
use rdbvh_core::Vec3;
use rdbvh_tests::{camera_rays, interior_rays, scene_bounds, Rng};

struct Counting;

thread_local! {
    static CALLS: Cell<u64> = const { Cell::new(0) };
}

fn bump() {
    // `try_with`: during thread teardown the slot may be gone; those calls are not measured.
    let _ = CALLS.try_with(|c| c.set(c.get() + 1));
}

// SAFETY: every call is forwarded unchanged to the system allocator; counting touches only a
// thread-local `Cell`.
unsafe impl GlobalAlloc for Counting {
    unsafe fn alloc(&self, layout: Layout) -> *mut u8 {
        bump();
        // SAFETY: forwarded with the caller's guarantees.
        unsafe { System.alloc(layout) }
    }
    unsafe fn alloc_zeroed(&self, layout: Layout) -> *mut u8 {
        bump();
        // SAFETY: forwarded with the caller's guarantees.
        unsafe { System.alloc_zeroed(layout) }
    }
    unsafe fn realloc(&self, ptr: *mut u8, layout: Layout, new_size: usize) -> *mut u8 {
        bump();
        // SAFETY: forwarded with the caller's guarantees.
        unsafe { System.realloc(ptr, layout, new_size) }
    }
    unsafe fn dealloc(&self, ptr: *mut u8, layout: Layout) {
        bump();
        // SAFETY: forwarded with the caller's guarantees.
        unsafe { System.dealloc(ptr, layout) }
    }
}

#[global_allocator]
static GLOBAL: Counting = Counting;

/// Allocator calls (allocations, reallocations and frees) made by this thread while `f` runs.
fn allocator_calls<R>(f: impl FnOnce() -> R) -> (u64, R) {
    let before = CALLS.with(Cell::get);
    let r = f();
    let after = CALLS.with(Cell::get);
    (after - before, r)
}

/// Random small triangles in a 10-unit cube, the thesis's recipe, plus some degenerate ones.
fn soup(n: usize, seed: u64) -> Vec<Triangle> {
    let mut rng = Rng::new(seed);
    let cube = Aabb::new(Vec3::ZERO, Vec3::splat(10.0));
    let unit = Aabb::new(Vec3::splat(-1.0), Vec3::ONE);
    (0..n)
        .map(|i| {
            let v0 = rng.in_box(&cube);
            match i % 50 {
                0 => Triangle::new(v0, v0, v0),
                1 => Triangle::new(v0, v0 + Vec3::X, v0 + Vec3::X * 2.0),
                _ => {
                    let v1 = v0 + rng.in_box(&unit);
                    Triangle::new(v0, v1, v1 + rng.in_box(&unit))
                }
            }
        })
        .collect()
}

#[test]
fn the_counter_counts() {
    let (calls, v) = allocator_calls(|| black_box(vec![1u8; 100]));
    assert!(calls >= 1, "a Vec allocation was not counted");
    let (calls, _) = allocator_calls(|| drop(v));
    assert!(calls >= 1, "a free was not counted");
    // The allocating path of the builder is seen too, so a zero below means something.
    let tris = soup(100, 1);
    let (calls, _) = allocator_calls(|| Builder::sah().build(&tris).unwrap());
    assert!(calls > 0);
}

/// Builds into a pre-sized arena and output with no allocator call, for a first build and for a
/// rebuild over other triangles, then checks the result against the allocating path.
fn build_into_allocates_nothing<A: AxisChooser, C: CostModel, T: Termination>(
    name: &str,
    builder: &Builder<A, C, T>,
) {
    let n = 4000;
    let tris = soup(n, 7);
    let mut arena = BuildArena::with_capacity(n);
    arena.load_triangles(&tris).unwrap();
    let mut bvh = Bvh::with_capacity(n);
    let (calls, stats) = allocator_calls(|| builder.build_into(&mut arena, &mut bvh).unwrap());
    assert_eq!(calls, 0, "{name}: build_into made {calls} allocator calls");
    assert!(stats.nodes > 1, "{name}: {stats:?}");
    assert_eq!(bvh, builder.build(&tris).unwrap(), "{name}");
    bvh.validate(n, |i| tris[i as usize].bounds()).unwrap();

    // Reuse: loading fewer triangles into the arena and rebuilding allocates nothing either.
    let other = soup(n / 2, 8);
    let (calls, _) = allocator_calls(|| {
        arena.load_triangles(&other).unwrap();
        builder.build_into(&mut arena, &mut bvh).unwrap()
    });
    assert_eq!(
        calls, 0,
        "{name}: reload and rebuild made {calls} allocator calls"
    );
    bvh.validate(other.len(), |i| other[i as usize].bounds())
        .unwrap();
    assert_eq!(bvh, builder.build(&other).unwrap(), "{name}");
}

#[test]
fn builds_into_an_arena_allocate_nothing() {
    build_into_allocates_nothing("sah", &Builder::sah());
    build_into_allocates_nothing("lsph", &Builder::lsph());
    let thesis = BuildConfig {
        bins: 40,
        cut: CutEvaluation::Thesis(ThesisCut::LSPH),
        bin_space: BinSpace::NodeBox,
        ..BuildConfig::default()
    };
    build_into_allocates_nothing(
        "leaf size 2, thesis cut, node-box bins",
        &Builder::new(LongestAxis, Sah, LeafSize { max_leaf: 2 }, thesis),
    );
    let shallow = BuildConfig {
        max_depth: 6,
        ..BuildConfig::default()
    };
    build_into_allocates_nothing(
        "depth bound 6 (median splits)",
        &Builder::new(AllAxes, Sah, LeafSize { max_leaf: 1 }, shallow),
    );
}

#[test]
fn traversals_allocate_nothing() {
    let tris = soup(3000, 3);
    let bvh = Builder::sah().build(&tris).unwrap();
    let bounds = scene_bounds(&tris);
    let mut rays: Vec<Ray> = camera_rays(&bounds, 500, 11);
    rays.extend(interior_rays(&bounds, 500, 12));
    let (calls, (hits, any, all, stats)) = allocator_calls(|| {
        let mut stats = TraversalStats::default();
        let (mut hits, mut any, mut all) = (0u32, 0u32, 0u32);
        for ray in &rays {
            hits += u32::from(bvh.closest_hit(ray, &tris).is_some());
            hits += u32::from(bvh.closest_hit_with_stats(ray, &tris, &mut stats).is_some());
            any += u32::from(bvh.any_hit(ray, &tris));
            any += u32::from(bvh.any_hit_with_stats(ray, &tris, &mut stats));
            all += bvh.all_hit(ray, &tris).hits;
        }
        (hits, any, all, stats)
    });
    assert_eq!(calls, 0, "traversals made {calls} allocator calls");
    // The traversals did real work.
    assert!(
        hits > 0 && any == hits && all >= hits / 2,
        "{hits} {any} {all}"
    );
    assert!(stats.inner_nodes > 0 && stats.triangles > 0, "{stats:?}");
}

/// A `Reinserter` reused on the same tree again allocates nothing: its working memory, and the
/// output arrays it traded for the first tree's, are large enough.
#[test]
fn a_reused_reinserter_allocates_nothing() {
    let mut tris = soup(4000, 5);
    // Long triangles across the soup, so that reinsertion has something to move.
    tris.extend((0..60).map(|i| {
        let y = i as f32 * 0.3 - 9.0;
        Triangle::new(
            Vec3::new(-10.0, y, -10.0),
            Vec3::new(10.0, y, 10.0),
            Vec3::new(-10.0, y + 0.1, 10.0),
        )
    }));
    let built = Builder::sah().build(&tris).unwrap();
    let config = ReinsertConfig::default();
    let mut reinserter = Reinserter::new();
    let mut first = built.clone();
    let once = reinserter.optimize(&mut first, &Sah, &config);
    assert!(once.moved > 0, "{once:?}");
    let mut again = built.clone();
    let (calls, twice) = allocator_calls(|| reinserter.optimize(&mut again, &Sah, &config));
    assert_eq!(calls, 0, "reinsertion allocated {calls} times");
    assert_eq!((twice, &again), (once, &first));
}
