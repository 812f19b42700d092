//! Shared helpers of the integration and property tests: where the reference data lives, a
//! deterministic random generator, ray sets, and the comparison of every BVH query against the
//! brute-force oracle.
//!
//! The real scenes are read from `../shared/scenes/` beside the checkout (they must not be copied
//! into the repository). A developer without that folder gets a printed skip; CI (`CI=true`) gets a
//! failure, because there a missing `../shared` means the tests did not run.
#![deny(missing_docs)]

use std::path::PathBuf;

use rdbvh_core::brute_force;
use rdbvh_core::bvh::{AllHitStats, Bvh, Hit, TraversalStats, WideBvh};
use rdbvh_core::geometry::{Aabb, Ray, Triangle};
use rdbvh_core::Vec3;

/// Where `../shared` is expected: beside the checkout, two levels above this crate.
pub const SHARED_DIR: &str = concat!(env!("CARGO_MANIFEST_DIR"), "/../../shared");

/// True when the environment says this is a CI run (`CI=true`, as CI sets it).
pub fn in_ci() -> bool {
    std::env::var("CI").is_ok_and(|v| v.eq_ignore_ascii_case("true") || v == "1")
}

/// The `../shared` folder, or `None` after printing `skipped: ../shared not found (<reason>)`.
///
/// # Panics
/// When `CI=true` and the folder is missing: in CI a missing `../shared` is a failure, not a skip.
pub fn require_shared() -> Option<PathBuf> {
    let path = PathBuf::from(SHARED_DIR);
    let reason = match std::fs::metadata(&path) {
        Ok(m) if m.is_dir() => return Some(path.canonicalize().unwrap_or(path)),
        Ok(_) => format!("{} is not a directory", path.display()),
        Err(e) => format!("{}: {e}", path.display()),
    };
    if in_ci() {
        panic!("../shared not found ({reason}): with CI=true the real-scene tests must run, so a missing ../shared is a failure");
    }
    println!("skipped: ../shared not found ({reason})");
    None
}

/// A scene file under `../shared/scenes/`, or `None` (with the same skip or CI failure as
/// [`require_shared`]). A missing file inside an existing `../shared` is always a failure.
pub fn require_scene(relative: &str) -> Option<PathBuf> {
    let path = require_shared()?.join("scenes").join(relative);
    assert!(
        path.is_file(),
        "scene {} is missing from ../shared/scenes",
        path.display()
    );
    Some(path)
}

/// SplitMix64: a tiny deterministic generator, so real-scene tests trace the same rays every run.
#[derive(Clone, Debug)]
pub struct Rng(u64);

impl Rng {
    /// A generator from a seed.
    pub fn new(seed: u64) -> Self {
        Self(seed)
    }

    /// The next 64 random bits.
    pub fn next_u64(&mut self) -> u64 {
        self.0 = self.0.wrapping_add(0x9E37_79B9_7F4A_7C15);
        let mut z = self.0;
        z = (z ^ (z >> 30)).wrapping_mul(0xBF58_476D_1CE4_E5B9);
        z = (z ^ (z >> 27)).wrapping_mul(0x94D0_49BB_1331_11EB);
        z ^ (z >> 31)
    }

    /// Uniform in `[0, 1)`.
    pub fn f32(&mut self) -> f32 {
        (self.next_u64() >> 40) as f32 / (1u64 << 24) as f32
    }

    /// Uniform in `[lo, hi)`.
    pub fn range(&mut self, lo: f32, hi: f32) -> f32 {
        lo + (hi - lo) * self.f32()
    }

    /// Uniform in `0..n` (`n > 0`).
    pub fn below(&mut self, n: usize) -> usize {
        (self.next_u64() % n as u64) as usize
    }

    /// A point uniform in the box.
    pub fn in_box(&mut self, b: &Aabb) -> Vec3 {
        Vec3::new(
            self.range(b.min.x, b.max.x),
            self.range(b.min.y, b.max.y),
            self.range(b.min.z, b.max.z),
        )
    }

    /// A direction uniform on the unit sphere.
    pub fn unit_vector(&mut self) -> Vec3 {
        let z = self.range(-1.0, 1.0);
        let phi = self.range(0.0, std::f32::consts::TAU);
        let r = (1.0 - z * z).max(0.0).sqrt();
        Vec3::new(r * phi.cos(), r * phi.sin(), z)
    }
}

/// The bounds of all triangles.
pub fn scene_bounds(tris: &[Triangle]) -> Aabb {
    tris.iter().fold(Aabb::EMPTY, |b, t| b.union(t.bounds()))
}

/// Camera-like rays: origins on a sphere around the scene (outside its bounds), each aimed at a
/// random point inside the bounds, so most of them hit something.
pub fn camera_rays(bounds: &Aabb, count: usize, seed: u64) -> Vec<Ray> {
    let mut rng = Rng::new(seed);
    let centre = bounds.center();
    let radius = bounds.extent().length().max(1e-3);
    (0..count)
        .filter_map(|_| {
            let eye = centre + rng.unit_vector() * (1.5 * radius);
            let target = rng.in_box(bounds);
            Ray::new(eye, target - eye).ok()
        })
        .collect()
}

/// Rays from random points inside the bounds in random directions; every fourth one is a finite
/// segment (a shadow ray towards another point inside the bounds, `t` in `[0, 1]`).
pub fn interior_rays(bounds: &Aabb, count: usize, seed: u64) -> Vec<Ray> {
    let mut rng = Rng::new(seed);
    (0..count)
        .filter_map(|i| {
            let o = rng.in_box(bounds);
            if i % 4 == 3 {
                let p = rng.in_box(bounds);
                Ray::segment(o, p - o, 0.0, 1.0).ok()
            } else {
                Ray::new(o, rng.unit_vector()).ok()
            }
        })
        .collect()
}

/// Which open core bug (each reproduced by an ignored `CORE BUG` test in
/// `tests/core_regressions.rs`) a ray runs into, if any, so the property tests can set those rays
/// aside by name instead of loosening their assertions. Remove the case when the core fixes it.
pub fn known_core_bug(ray: &Ray, tris: &[Triangle]) -> Option<&'static str> {
    tris.iter().find_map(|tri| {
        let h = tri.intersect(ray, ray.t_max)?;
        // The hit must pass the box test of the triangle's own padded box (as BVH nodes store
        // it) at that very `t`; then it passes every enclosing node's too. An ill-conditioned
        // Moller-Trumbore `t` (a ray nearly in the triangle's plane, or a tiny triangle far from
        // both the ray's origin and its anchor) can put the hit point far outside, where no BVH
        // can find it.
        let at_hit = Ray::segment(ray.origin, ray.dir, h.t, h.t).ok()?;
        tri.bounds()
            .padded()
            .intersect(&at_hit, h.t)
            .is_none()
            .then_some("core_bug_ill_conditioned_hit_outside_its_box")
    })
}

/// Counters of a comparison run, for a test's report and its sanity checks.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub struct Agreement {
    /// Rays compared.
    pub rays: usize,
    /// Rays with a closest hit.
    pub hits: usize,
}

/// The brute-force answers for one ray, computed once and compared against any number of BVHs.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Oracle {
    /// The closest hit over all triangles.
    pub closest: Option<Hit>,
    /// Whether any triangle is hit.
    pub any: bool,
    /// How many triangles are hit.
    pub count: u32,
}

impl Oracle {
    /// Asks the brute-force oracle about `ray`.
    pub fn new(ray: &Ray, tris: &[Triangle]) -> Self {
        Self {
            closest: brute_force::closest_hit(ray, tris),
            any: brute_force::any_hit(ray, tris),
            count: brute_force::hit_count(ray, tris),
        }
    }
}

/// Checks one ray against the oracle: the closest hit is exactly the oracle's, any-hit agrees with
/// it, the all-hit walk counts exactly the oracle's hits and tests at least that many triangles,
/// and the traversal counters are consistent with the tree. Returns the closest hit.
///
/// # Panics
/// On the first disagreement, naming the ray.
pub fn check_ray(bvh: &Bvh, tris: &[Triangle], ray: &Ray) -> Option<Hit> {
    check_ray_against(bvh, tris, ray, &Oracle::new(ray, tris))
}

/// [`check_ray`] with the oracle's answers already known.
pub fn check_ray_against(bvh: &Bvh, tris: &[Triangle], ray: &Ray, oracle: &Oracle) -> Option<Hit> {
    assert_eq!(
        oracle.any,
        oracle.closest.is_some(),
        "the oracle's own answers disagree for {ray:?}"
    );
    let expect = oracle.closest;
    let mut cs = TraversalStats::default();
    let got = bvh.closest_hit_with_stats(ray, tris, &mut cs);
    assert_eq!(
        got, expect,
        "closest hit differs from brute force for {ray:?}"
    );
    assert_eq!(
        bvh.closest_hit(ray, tris),
        got,
        "closest_hit and closest_hit_with_stats differ for {ray:?}"
    );
    let mut anys = TraversalStats::default();
    let any = bvh.any_hit_with_stats(ray, tris, &mut anys);
    assert_eq!(
        any, oracle.any,
        "any hit differs from brute force for {ray:?}"
    );
    assert_eq!(bvh.any_hit(ray, tris), any);
    let all = bvh.all_hit(ray, tris);
    assert_eq!(
        all.hits, oracle.count,
        "all-hit count differs from brute force for {ray:?}"
    );
    check_traversal_consistency(bvh, tris, ray, (got, &cs), (any, &anys), &all);
    expect
}

/// The checks that need no oracle: any-hit agrees with closest-hit, the all-hit walk saw at least
/// the closest hit, each walk's counters are within the tree, and the ordered and early-exit walks
/// never do more than the exhaustive one.
pub fn check_traversal_consistency(
    bvh: &Bvh,
    _tris: &[Triangle],
    ray: &Ray,
    (closest, cs): (Option<Hit>, &TraversalStats),
    (any, anys): (bool, &TraversalStats),
    all: &AllHitStats,
) {
    assert_eq!(
        any,
        closest.is_some(),
        "any hit and closest hit disagree for {ray:?}"
    );
    assert!(all.triangles >= all.hits, "{all:?} for {ray:?}");
    assert_eq!(
        all.hits > 0,
        any,
        "all-hit {all:?} vs any hit {any} for {ray:?}"
    );
    check_stats_sane(bvh, cs, closest.is_some(), ray);
    check_stats_sane(bvh, anys, any, ray);
    for s in [cs, anys] {
        assert!(
            s.inner_nodes <= all.inner_nodes
                && s.leaves <= all.leaves
                && s.triangles <= all.triangles,
            "traversal {s:?} did more than the all-hit walk {all:?} for {ray:?}"
        );
    }
}

/// Runs every traversal on `ray` and checks them against each other (no oracle).
pub fn check_ray_consistency(bvh: &Bvh, tris: &[Triangle], ray: &Ray) -> Option<Hit> {
    let mut cs = TraversalStats::default();
    let closest = bvh.closest_hit_with_stats(ray, tris, &mut cs);
    let mut anys = TraversalStats::default();
    let any = bvh.any_hit_with_stats(ray, tris, &mut anys);
    let all = bvh.all_hit(ray, tris);
    check_traversal_consistency(bvh, tris, ray, (closest, &cs), (any, &anys), &all);
    closest
}

/// Checks the 4-wide collapse of a tree over `tris` against the answer every traversal must give
/// (`expect`, the brute-force closest hit): closest hit exactly, any hit consistent, NaN-free
/// hits, and counters within the collapsed tree's size. Returns the closest hit.
///
/// # Panics
/// When the wide tree disagrees.
pub fn check_wide_ray(wide: &WideBvh, tris: &[Triangle], ray: &Ray, expect: Option<Hit>) {
    let mut cs = TraversalStats::default();
    let got = wide.closest_hit_with_stats(ray, &mut cs);
    assert_eq!(got, expect, "wide closest hit differs for {ray:?}");
    assert_eq!(wide.closest_hit(ray), got);
    if let Some(h) = got {
        assert!(
            h.t.is_finite() && h.u.is_finite() && h.v.is_finite(),
            "wide hit {h:?} for {ray:?}"
        );
    }
    let mut anys = TraversalStats::default();
    let any = wide.any_hit_with_stats(ray, &mut anys);
    assert_eq!(any, expect.is_some(), "wide any hit differs for {ray:?}");
    assert_eq!(wide.any_hit(ray), any);
    for s in [cs, anys] {
        assert!(
            s.inner_nodes as usize <= wide.nodes().len(),
            "{s:?} for {ray:?}"
        );
        assert!(s.triangles as usize <= tris.len(), "{s:?} for {ray:?}");
    }
}

/// Checks the structure of a 4-wide collapse of `bvh` over `tris`: every triangle in exactly one
/// lane of one leaf, unused lanes empty, leaf boxes holding their triangles, and depth no deeper
/// than the binary tree's.
///
/// # Panics
/// When the wide tree is malformed.
pub fn check_wide_structure(wide: &WideBvh, bvh: &Bvh, tris: &[Triangle]) {
    assert!(wide.max_depth() <= bvh.max_depth());
    let mut seen = vec![false; tris.len()];
    let blocks = wide.triangles();
    for node in wide.nodes() {
        for i in 0..4 {
            if node.child[i] == rdbvh_core::bvh::WideNode::EMPTY || node.count[i] == 0 {
                continue;
            }
            let (first, count) = (node.child[i] as usize, node.count[i] as usize);
            let bounds = node.child_bounds(i);
            for k in 0..count.div_ceil(4) * 4 {
                let block = &blocks[first + k / 4];
                let lane = k % 4;
                let id = block.id[lane];
                if k >= count {
                    assert_eq!(id, rdbvh_core::geometry::Triangle4::UNUSED_ID);
                    continue;
                }
                assert!(
                    !std::mem::replace(&mut seen[id as usize], true),
                    "{id} twice"
                );
                let tri = &tris[id as usize];
                assert!(bounds.contains_box(&tri.bounds()), "{id} outside its leaf");
                let v0 = Vec3::new(block.v0[0][lane], block.v0[1][lane], block.v0[2][lane]);
                assert_eq!(v0, tri.v0);
            }
        }
    }
    assert!(seen.iter().all(|&s| s), "a triangle is in no leaf");
}

/// Counters of one closest-hit or any-hit query: within the tree's size, leaves visited only if
/// the walk reached them, and at least one triangle tested when something was hit.
pub fn check_stats_sane(bvh: &Bvh, s: &TraversalStats, hit: bool, ray: &Ray) {
    let leaves = bvh.leaf_count() as u32;
    let inner = bvh.nodes().len() as u32 - leaves.min(bvh.nodes().len() as u32);
    let prims = bvh.prim_indices().len() as u32;
    assert!(
        s.inner_nodes <= inner,
        "{s:?} > {inner} inner nodes for {ray:?}"
    );
    assert!(s.leaves <= leaves, "{s:?} > {leaves} leaves for {ray:?}");
    assert!(
        s.triangles <= prims,
        "{s:?} > {prims} triangles for {ray:?}"
    );
    if hit {
        assert!(
            s.leaves >= 1 && s.triangles >= 1,
            "a hit with {s:?} for {ray:?}"
        );
    }
    if s.leaves > 0 && inner > 0 {
        assert!(
            s.inner_nodes >= 1,
            "a leaf below the root reached without the root: {s:?}"
        );
    }
}

/// Checks every ray of `rays` with [`check_ray`].
pub fn check_rays(bvh: &Bvh, tris: &[Triangle], rays: &[Ray]) -> Agreement {
    let mut a = Agreement::default();
    for ray in rays {
        a.rays += 1;
        if check_ray(bvh, tris, ray).is_some() {
            a.hits += 1;
        }
    }
    a
}

/// Validates a BVH built over `tris` (every invariant of [`Bvh::validate`]) and checks its shape:
/// at most `2n - 1` nodes, all triangles referenced.
///
/// # Panics
/// When an invariant is broken.
pub fn check_structure(bvh: &Bvh, tris: &[Triangle]) {
    if let Err(e) = bvh.validate(tris.len(), |i| tris[i as usize].bounds()) {
        panic!("BVH over {} triangles is invalid: {e} ({e:?})", tris.len());
    }
    assert!(bvh.nodes().len() <= (2 * tris.len()).saturating_sub(1));
    assert_eq!(bvh.prim_indices().len(), tris.len());
    assert!(bvh.max_depth() <= rdbvh_core::bvh::MAX_DEPTH);
    if !tris.is_empty() {
        // Nodes store their exact boxes padded by a hair (`Aabb::padded`), never more.
        let (root, exact) = (bvh.bounds(), scene_bounds(tris));
        assert!(
            root.contains_box(&exact) && exact.padded().contains_box(&root),
            "root box {root:?} is not the scene's box {exact:?}, padded"
        );
    }
}
