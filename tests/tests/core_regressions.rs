//! Minimal reproductions of core bugs that the property tests found, kept as regression tests.
//! The first four were fixed in the core ("fix four disagreements with the oracle found by the
//! property tests"), the last by rejecting hits whose determinant is rounding noise. A new core bug
//! gets its repro here, marked `#[ignore = "CORE BUG: ..."]` while it is open, so
//! `cargo test -p rdbvh-tests --release -- --ignored` lists exactly what still fails.

use rdbvh_core::brute_force;
use rdbvh_core::builder::{BuildArena, Builder};
use rdbvh_core::geometry::{Ray, Triangle};
use rdbvh_core::{BuildError, Vec3};

/// Was a core bug: `BuildArena::push` checks `Triangle::bounds().is_valid()`, but `Vec3::min`/`max`
/// drop a NaN operand, so a NaN in `v0` or `v1` yields finite bounds and the build succeeds.
/// Documented behaviour (`BuildError::InvalidPrimitive`): a NaN coordinate is a typed error.
#[test]
fn core_bug_nan_vertex_is_rejected() {
    for vertex in 0..3 {
        let mut v = [Vec3::ZERO, Vec3::X, Vec3::Y];
        v[vertex].x = f32::NAN;
        let tris = [Triangle::new(v[0], v[1], v[2])];
        assert_eq!(
            Builder::sah().build(&tris).map(|_| ()),
            Err(BuildError::InvalidPrimitive { index: 0 }),
            "NaN in vertex {vertex}"
        );
        let mut arena = BuildArena::with_capacity(1);
        assert!(
            arena.load_triangles(&tris).is_err(),
            "NaN in vertex {vertex}"
        );
    }
}

/// Was a core bug: Moller-Trumbore's `t` overflows to `+inf` for a ray whose true hit lies beyond
/// `f32::MAX` (tiny direction, far triangle). `Triangle::intersect` accepts `t = inf <= t_max = inf`
/// as a hit, so the oracle reports `Some(t = inf)`; the BVH's slab test computes
/// `inf - inf * SLAB_PAD = NaN` for the entry and culls the root, so the BVH reports `None`.
#[test]
fn core_bug_infinite_t_hit() {
    let z = 1e20;
    let tris = [Triangle::new(
        Vec3::new(0.0, 0.0, z),
        Vec3::new(1.0, 0.0, z),
        Vec3::new(0.0, 1.0, z),
    )];
    let ray = Ray::new(Vec3::new(0.25, 0.25, 0.0), Vec3::new(0.0, 0.0, 1e-20)).unwrap();
    let bvh = Builder::sah().build(&tris).unwrap();
    let expect = brute_force::closest_hit(&ray, &tris);
    assert_eq!(bvh.closest_hit(&ray, &tris), expect);
    assert_eq!(bvh.any_hit(&ray, &tris), expect.is_some());
    // The documented policy says overflow cannot produce a hit: a finite `t` is required.
    assert!(expect.is_none_or(|h| h.t.is_finite()), "{expect:?}");
}

/// Was a core rounding gap: Moller-Trumbore's `t`, `u` and `v` carry rounding errors that the slab
/// test's padding (relative to `|t|`, so zero at `t = 0`) does not cover, so the triangle test can
/// report a hit that the box test of the triangle's own box rejects:
/// 1. a ray that starts exactly on a vertex and leaves the box at once gets `t = -2.9e-8` (the
///    true hit is at `t = 0`); the segment `[t, t]` is culled by the BVH while the oracle hits;
/// 2. a ray that starts one ulp outside the box, beside a vertex, and runs parallel to the box's
///    face gets `u = 1, v = -0`: a hit for the oracle, a miss for the BVH.
#[test]
fn core_bug_rounding_hit_outside_triangle_box() {
    let mut failures = Vec::new();

    let tris = [Triangle::new(
        Vec3::new(-1.239_800_8, -1.481_550_7, 0.0),
        Vec3::new(0.0, -0.0, 0.0),
        Vec3::new(0.0, 0.183_143_91, -1.5),
    )];
    let bvh = Builder::sah().build(&tris).unwrap();
    let origin = tris[0].v2;
    let dir = Vec3::new(-1.0, 1.0, 0.0);
    let full = Ray::segment(origin, dir, -1.0, 1.0).unwrap();
    let hit = brute_force::closest_hit(&full, &tris).expect("the ray starts on the triangle");
    assert_eq!(
        bvh.closest_hit(&full, &tris),
        Some(hit),
        "the whole segment agrees"
    );
    let ray = Ray::segment(origin, dir, hit.t, hit.t).unwrap();
    let (got, expect) = (
        bvh.closest_hit(&ray, &tris),
        brute_force::closest_hit(&ray, &tris),
    );
    if got != expect {
        failures.push(format!(
            "1. segment [t, t] at the oracle's own t: BVH {got:?}, oracle {expect:?}"
        ));
    }

    let t = Triangle::new(
        Vec3::new(0.5, 0.0, 0.0),
        Vec3::new(-0.918_832, 0.0, 0.0),
        Vec3::new(0.0, 0.0, 0.837_388_5),
    );
    let tris = [t, t];
    // `v0 + (v1 - v0) * 1.0` rounds to one ulp below `v1.x`: just outside the box.
    let origin = t.v0 + (t.v1 - t.v0) * 1.0;
    assert!(origin.x < t.v1.x);
    let ray = Ray::new(origin, Vec3::Y).unwrap();
    let bvh = Builder::sah().build(&tris).unwrap();
    let (got, expect) = (
        bvh.closest_hit(&ray, &tris),
        brute_force::closest_hit(&ray, &tris),
    );
    if got != expect {
        failures.push(format!(
            "2. ray beside a vertex, parallel to a face: BVH {got:?}, oracle {expect:?}"
        ));
    }
    assert!(failures.is_empty(), "{failures:#?}");
}

/// Was a core bug: closest-hit traversal pops a deferred subtree only if `t_entry <= best.t`, with no
/// padding, while the box test that admitted the subtree pads its interval. When the triangle
/// test's `t` lands a little before the slab entry (rounding), a subtree holding a hit at the
/// same `t` with a lower id (or, in general, a hit a few ulps closer) is pruned: here the BVH
/// returns triangle 2 where the oracle's tie rule gives triangle 0 (0, 2 and 3 are duplicates).
#[test]
fn core_bug_ordered_prune_breaks_tie_rule() {
    use rdbvh_core::builder::BuildConfig;
    use rdbvh_core::heuristics::{AllAxes, LeafSize, Sah};
    let t = Triangle::new(
        Vec3::new(0.117_943_935, 0.0, -0.172_248_54),
        Vec3::new(0.072_127_94, 0.0, 0.1),
        Vec3::new(0.048_326_574, 0.0, 0.149_350_73),
    );
    let tris = [t, Triangle::new(Vec3::ZERO, Vec3::ZERO, Vec3::ZERO), t, t];
    let origin = Vec3::new(0.0, 0.05, 0.0);
    let target = t.v0 + (t.v2 - t.v0) * 0.888_154_6;
    let full = Ray::new(origin, target - origin).unwrap();
    let hit = brute_force::closest_hit(&full, &tris).unwrap();
    let ray = Ray::segment(origin, target - origin, 0.0, hit.t).unwrap();
    let expect = brute_force::closest_hit(&ray, &tris);
    assert_eq!(expect.map(|h| h.triangle), Some(0));
    let config = BuildConfig {
        bins: 2,
        ..BuildConfig::default()
    };
    let thesis = Builder::new(AllAxes, Sah, LeafSize { max_leaf: 2 }, config);
    for (name, bvh) in [
        (
            "sah",
            Builder::sah().with_config(config).build(&tris).unwrap(),
        ),
        (
            "lsph",
            Builder::lsph().with_config(config).build(&tris).unwrap(),
        ),
        ("leaf-size 2", thesis.build(&tris).unwrap()),
    ] {
        assert_eq!(bvh.closest_hit(&full, &tris), Some(hit), "{name}, full ray");
        assert_eq!(
            bvh.closest_hit(&ray, &tris),
            expect,
            "{name}, segment [0, t]"
        );
    }
}

/// Fixed (a determinant within rounding of zero is no hit): Moller-Trumbore's `t` was ill-conditioned when the ray is nearly in the
/// triangle's plane or the triangle is tiny next to the ray origin's magnitude; the oracle then
/// reports a hit whose point lies far outside the triangle's box (padded as nodes store it), and
/// a segment around that `t` is culled by the BVH. The node padding (`2^-19` of the box's own
/// magnitude) covers ulps, not this.
/// 1. a triangle of size `1e-15` near the origin, a ray from 1.6 units away aimed at its vertex:
///    the oracle hits at `t = 0` (the true `t` is 1), on the ray's origin;
/// 2. a ray from a point of a triangle toward its vertex (in its plane up to rounding): the oracle
///    hits at `t = 2` with `u = v = 0`, twice as far as the vertex.
#[test]
fn core_bug_ill_conditioned_hit_outside_its_box() {
    let mut failures = Vec::new();
    let tiny = [Triangle::new(
        Vec3::new(0.0, -0.0, -4.532_538e-16),
        Vec3::new(-5e-16, 5e-16, 1.794_471e-15),
        Vec3::new(4.536_395e-16, -4.536_395e-16, -2.492_567_2e-15),
    )];
    let origin = Vec3::new(-1.589_339_1, 0.0, -0.5);
    let t = tiny[0];
    let in_plane = [t_plane(), t_plane()];
    let p = in_plane[0];
    let from = p.v0 + (p.v1 - p.v0) * (1.0 - 0.545_983_14) + (p.v2 - p.v0) * 0.5;
    for (name, tris, origin, target) in [
        ("tiny triangle far away", &tiny[..], origin, t.v0),
        ("ray in the triangle's plane", &in_plane[..], from, p.v0),
    ] {
        let full = Ray::new(origin, target - origin).unwrap();
        let bvh = Builder::sah().build(tris).unwrap();
        let Some(hit) = brute_force::closest_hit(&full, tris) else {
            continue;
        };
        let ray = Ray::segment(full.origin, full.dir, hit.t, hit.t).unwrap();
        let (got, expect) = (
            bvh.closest_hit(&ray, tris),
            brute_force::closest_hit(&ray, tris),
        );
        if got != expect {
            failures.push(format!(
                "{name}: segment [t, t], BVH {got:?}, oracle {expect:?}"
            ));
        }
    }
    assert!(failures.is_empty(), "{failures:#?}");
}

fn t_plane() -> Triangle {
    Triangle::new(
        Vec3::new(0.0, 1.0, -0.5),
        Vec3::new(-0.410_314_23, 1.140_831_8, -0.548_380_5),
        Vec3::new(-0.410_314_23, 0.654_524_45, -0.362_989_78),
    )
}
