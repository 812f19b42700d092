//! Shared decoding and checks of the rdbvh fuzz targets.
//!
//! Fuzz bytes are decoded with `arbitrary::Unstructured` into scenes, areas and rays. Coordinates
//! come from a mix of ranges: a small grid (ties, shared edges, coplanar and axis-aligned rays),
//! sane values, values scaled by up to 10^±30 (a billion-unit scene beside a micro one), special
//! values (`0`, `-0`, `f32::MAX`, subnormals) and, rarely, raw bits (NaN and infinities), so the
//! builder's error paths are reached too. Every check compares against the brute-force oracle and
//! sets aside only rays that hit the one open, documented core rounding gap
//! ([`rdbvh_tests::known_core_bug`]).

use arbitrary::{Result, Unstructured};
use rdbvh_core::brute_force;
use rdbvh_core::builder::{BinSpace, BuildConfig, CutEvaluation, PresetOptions, ThesisCut};
use rdbvh_core::bvh::{Bvh, WideBvh, MAX_DEPTH};
use rdbvh_core::geometry::{Ray, RayError, Triangle};
use rdbvh_core::heuristics::PerspectiveMeasure;
use rdbvh_core::influence::{InfluenceArea, PlaneArea, PointArea};
use rdbvh_core::{BuildError, Vec3};

pub use rdbvh_tests::known_core_bug;

/// Most triangles a fuzz scene has: enough for several tree levels, few enough that the
/// brute-force oracle stays cheap.
pub const MAX_TRIANGLES: usize = 48;
/// Most rays traced per input.
pub const MAX_RAYS: usize = 12;

const SPECIAL: [f32; 10] = [
    0.0,
    -0.0,
    1.0,
    -1.0,
    f32::MAX,
    f32::MIN,
    f32::MIN_POSITIVE,
    1.0e-40, // subnormal
    f32::EPSILON,
    1.0e30,
];

/// How often (out of 64) a coordinate is raw bits: NaN, infinities and anything else.
const RAW_IN_64: u8 = 1;

/// One coordinate from the mix of ranges.
pub fn coord(u: &mut Unstructured) -> Result<f32> {
    let pick: u8 = u.int_in_range(0..=63)?;
    Ok(match pick {
        p if p < RAW_IN_64 => f32::from_bits(u.arbitrary()?),
        1..=20 => f32::from(u.int_in_range(-8i8..=8)?) * 0.25,
        21..=48 => sane(u)?,
        49..=58 => sane(u)? * 10f32.powi(i32::from(u.int_in_range(-30i8..=30)?)),
        _ => SPECIAL[usize::from(u.int_in_range(0u8..=9)?)],
    })
}

/// A coordinate that is always finite (no raw bits, no `f32::MAX`).
pub fn finite_coord(u: &mut Unstructured) -> Result<f32> {
    let c = coord(u)?;
    Ok(if c.is_finite() && c.abs() <= 1e30 {
        c
    } else {
        sane(u)?
    })
}

/// Uniform-ish in `[-10, 10]`.
pub fn sane(u: &mut Unstructured) -> Result<f32> {
    let x: u16 = u.arbitrary()?;
    Ok((f32::from(x) / 65535.0 * 2.0 - 1.0) * 10.0)
}

/// A vector of [`coord`]s.
pub fn vec3(u: &mut Unstructured) -> Result<Vec3> {
    Ok(Vec3::new(coord(u)?, coord(u)?, coord(u)?))
}

/// A vector of [`finite_coord`]s.
pub fn finite_vec3(u: &mut Unstructured) -> Result<Vec3> {
    Ok(Vec3::new(
        finite_coord(u)?,
        finite_coord(u)?,
        finite_coord(u)?,
    ))
}

/// A triangle soup whose vertices come from a small shared pool (shared edges, duplicates,
/// degenerate triangles) or are fresh, with whole triangles sometimes repeated or scaled.
pub fn scene(u: &mut Unstructured, finite: bool) -> Result<Vec<Triangle>> {
    let point = |u: &mut Unstructured| if finite { finite_vec3(u) } else { vec3(u) };
    let pool_len = u.int_in_range(1..=12)?;
    let mut pool = Vec::with_capacity(pool_len);
    for _ in 0..pool_len {
        pool.push(point(u)?);
    }
    let n = u.int_in_range(0..=MAX_TRIANGLES)?;
    let mut tris: Vec<Triangle> = Vec::with_capacity(n);
    for _ in 0..n {
        let tri = match u.int_in_range(0u8..=9)? {
            0 if !tris.is_empty() => *u.choose(&tris)?,
            1 if !tris.is_empty() => {
                // A copy of an earlier triangle, scaled by a power of ten: a micro or huge twin.
                let t = *u.choose(&tris)?;
                let s = 10f32.powi(i32::from(u.int_in_range(-12i8..=12)?));
                Triangle::new(t.v0 * s, t.v1 * s, t.v2 * s)
            }
            2..=5 => Triangle::new(*u.choose(&pool)?, *u.choose(&pool)?, *u.choose(&pool)?),
            _ => Triangle::new(point(u)?, point(u)?, point(u)?),
        };
        tris.push(tri);
    }
    Ok(tris)
}

/// A point on a triangle at arbitrary barycentrics (possibly just outside it).
fn on_triangle(u: &mut Unstructured, t: &Triangle) -> Result<Vec3> {
    let a = f32::from(u.int_in_range(0u8..=16)?) / 16.0;
    let b = f32::from(u.int_in_range(0u8..=16)?) / 16.0;
    let (a, b) = if a + b > 1.0 {
        (1.0 - a, 1.0 - b)
    } else {
        (a, b)
    };
    Ok(t.v0 + (t.v1 - t.v0) * a + (t.v2 - t.v0) * b)
}

/// What a ray decoder made of its inputs: a ray, or the error `Ray::segment` gave.
pub type RayResult = core::result::Result<Ray, RayError>;

/// Rays aimed at the scene's vertices and triangle points, along axes, from vertices, and
/// arbitrary ones, over whole lines, half-lines, segments and empty segments.
pub fn rays(u: &mut Unstructured, tris: &[Triangle], count: usize) -> Result<Vec<RayResult>> {
    let mut out = Vec::with_capacity(count);
    for _ in 0..count {
        if u.is_empty() {
            break;
        }
        let origin = match u.int_in_range(0u8..=5)? {
            0 if !tris.is_empty() => u.choose(tris)?.v0,
            1 if !tris.is_empty() => {
                let t = *u.choose(tris)?;
                on_triangle(u, &t)?
            }
            _ => vec3(u)?,
        };
        let dir = match u.int_in_range(0u8..=7)? {
            0..=2 if !tris.is_empty() => {
                let t = *u.choose(tris)?;
                on_triangle(u, &t)? - origin
            }
            3 => [
                Vec3::X,
                Vec3::NEG_X,
                Vec3::Y,
                Vec3::NEG_Y,
                Vec3::Z,
                Vec3::NEG_Z,
            ][usize::from(u.int_in_range(0u8..=5)?)],
            _ => vec3(u)?,
        };
        let (t_min, t_max) = match u.int_in_range(0u8..=5)? {
            0 => (f32::NEG_INFINITY, f32::INFINITY),
            1 => (0.0, 1.0),
            2 => (coord(u)?, coord(u)?),
            _ => (0.0, f32::INFINITY),
        };
        let ray = Ray::segment(origin, dir, t_min, t_max);
        check_ray_error(origin, dir, t_min, t_max, ray);
        out.push(ray);
    }
    Ok(out)
}

/// `Ray::segment`'s documented contract: NaN anywhere, infinite origins or directions and the
/// zero direction are errors, everything else is a ray (an empty segment included).
pub fn check_ray_error(origin: Vec3, dir: Vec3, t_min: f32, t_max: f32, ray: RayResult) {
    let expect = if !origin.is_finite() {
        Err(RayError::NonFiniteOrigin)
    } else if !dir.is_finite() {
        Err(RayError::NonFiniteDirection)
    } else if dir == Vec3::ZERO {
        Err(RayError::ZeroDirection)
    } else if t_min.is_nan() || t_max.is_nan() {
        Err(RayError::NanSegment)
    } else {
        Ok(())
    };
    assert_eq!(
        ray.map(|_| ()),
        expect,
        "{origin:?} {dir:?} [{t_min}, {t_max}]"
    );
    if let Ok(r) = ray {
        if t_min > t_max {
            assert_eq!(brute_force::closest_hit(&r, &[]), None);
        }
    }
}

/// The first triangle with a NaN or infinite coordinate: the one the builder must name.
pub fn first_non_finite(tris: &[Triangle]) -> Option<u32> {
    tris.iter().position(|t| !t.is_finite()).map(|i| i as u32)
}

/// The build error every builder must give for `tris`, or `None` when it must succeed.
pub fn expected_build_error(tris: &[Triangle]) -> Option<BuildError> {
    first_non_finite(tris).map(|index| BuildError::InvalidPrimitive { index })
}

/// A valid build configuration from the fuzz input: every bin count, depth bound, cut evaluation,
/// bin space and exhaustive-split size the builder accepts.
pub fn build_config(u: &mut Unstructured) -> Result<BuildConfig> {
    let bins = match u.int_in_range(0u8..=3)? {
        0 => 2,
        1 => 3,
        2 => 16,
        _ => u.int_in_range(2..=rdbvh_core::builder::MAX_BINS)?,
    };
    let max_depth = match u.int_in_range(0u8..=3)? {
        0 => u.int_in_range(1..=MAX_DEPTH)?,
        1 => u.int_in_range(1..=4)?,
        _ => MAX_DEPTH,
    };
    let cut = match u.int_in_range(0u8..=3)? {
        0 => CutEvaluation::FirstAxis,
        1 => CutEvaluation::Thesis(ThesisCut::SPFH),
        2 => CutEvaluation::Thesis(ThesisCut::LSPH),
        _ => CutEvaluation::BestOfAxes,
    };
    let bin_space = if u.arbitrary()? {
        BinSpace::NodeBox
    } else {
        BinSpace::Centroids
    };
    let exhaustive_max = u.int_in_range(0..=rdbvh_core::builder::MAX_EXHAUSTIVE)?;
    Ok(BuildConfig {
        bins,
        max_depth,
        cut,
        bin_space,
        exhaustive_max,
        ..BuildConfig::default()
    })
}

/// Preset options: the project's defaults or the thesis's, with bins and leaf size from the input.
pub fn preset_options(u: &mut Unstructured) -> Result<PresetOptions> {
    let mut o = if u.arbitrary()? {
        PresetOptions::thesis()
    } else {
        PresetOptions::default()
    };
    if u.arbitrary()? {
        o.bins = u.int_in_range(2..=rdbvh_core::builder::MAX_BINS)?;
    }
    if u.arbitrary()? {
        o.max_leaf = u.int_in_range(1..=16)?;
    }
    o.perspective = match u.int_in_range(0u8..=1)? {
        0 => PerspectiveMeasure::SolidAngle,
        _ => PerspectiveMeasure::ImagePlane,
    };
    Ok(o)
}

/// An influence area with parameters near the scene (or arbitrary ones); `None` when the
/// constructor rejected them.
pub fn area(u: &mut Unstructured, tris: &[Triangle]) -> Result<Option<InfluenceArea>> {
    let anchor = if tris.is_empty() || u.arbitrary()? {
        finite_vec3(u)?
    } else {
        u.choose(tris)?.centroid()
    };
    let offset = finite_vec3(u)?;
    let dir = finite_vec3(u)?;
    let len = |u: &mut Unstructured| -> Result<f32> {
        Ok(match u.int_in_range(0u8..=3)? {
            0 => finite_coord(u)?.abs(),
            _ => f32::from(u.int_in_range(1u8..=40)?) * 0.5,
        })
    };
    let area: Option<InfluenceArea> = if u.arbitrary()? {
        PlaneArea::new(anchor + offset, dir, len(u)?, len(u)?, len(u)?)
            .ok()
            .map(Into::into)
    } else {
        let fov =
            |u: &mut Unstructured| -> Result<f32> { Ok(f32::from(u.int_in_range(1u8..=179)?)) };
        let near = len(u)? * 0.25;
        let far = near + len(u)?;
        PointArea::new(anchor + offset, dir, fov(u)?, fov(u)?, near, far)
            .ok()
            .map(Into::into)
    };
    let Some(area) = area else { return Ok(None) };
    let deg = f32::from(u.int_in_range(0u8..=45)?);
    Ok(match area {
        InfluenceArea::Plane(a) => a.with_tolerance_deg(deg).ok().map(Into::into),
        InfluenceArea::Point(a) => a.with_tolerance_deg(deg).ok().map(Into::into),
    })
}

/// The structural invariants of a BVH over `tris` built with depth bound `max_depth`: every
/// triangle in exactly one leaf, boxes contain their children and primitives, depth within both
/// bounds, at most `2n - 1` nodes.
pub fn check_tree(bvh: &Bvh, tris: &[Triangle], max_depth: u32, what: &str) {
    if let Err(e) = bvh.validate(tris.len(), |i| tris[i as usize].bounds()) {
        panic!(
            "{what}: invalid BVH over {} triangles: {e} ({e:?})",
            tris.len()
        );
    }
    assert!(
        bvh.max_depth() <= max_depth.min(MAX_DEPTH),
        "{what}: depth {} > bound {max_depth}",
        bvh.max_depth()
    );
    assert!(
        bvh.nodes().len() <= (2 * tris.len()).saturating_sub(1),
        "{what}"
    );
    assert_eq!(bvh.prim_indices().len(), tris.len(), "{what}");
}

/// Every traversal of `bvh` (closest, any, all-hit) and of its 4-wide collapse against brute force
/// on `ray`, unless the ray hits the known core rounding gap.
pub fn check_queries(bvh: &Bvh, wide: &WideBvh, tris: &[Triangle], ray: &Ray, what: &str) {
    if known_core_bug(ray, tris).is_some() {
        return;
    }
    let expect = brute_force::closest_hit(ray, tris);
    let any = brute_force::any_hit(ray, tris);
    assert_eq!(
        any,
        expect.is_some(),
        "oracle disagrees with itself: {ray:?}"
    );
    assert_eq!(
        bvh.closest_hit(ray, tris),
        expect,
        "{what}: closest hit, {ray:?}"
    );
    assert_eq!(bvh.any_hit(ray, tris), any, "{what}: any hit, {ray:?}");
    let all = bvh.all_hit(ray, tris);
    assert_eq!(
        all.hits,
        brute_force::hit_count(ray, tris),
        "{what}: all-hit count, {ray:?}"
    );
    assert!(all.triangles >= all.hits, "{what}: {all:?}");
    assert_eq!(
        wide.closest_hit(ray),
        expect,
        "{what}: wide closest hit, {ray:?}"
    );
    assert_eq!(
        wide.any_hit(ray),
        any,
        "{what}: wide any hit, {ray:?}"
    );
}

/// True when `p` is inside every plane of the area's polytope with a margin, computed without the
/// polytope's own tolerance: a point that every conservative test must treat as inside.
pub fn strictly_inside(area: &InfluenceArea, p: Vec3) -> bool {
    let poly = area.polytope();
    let scale = poly.scale.max(p.abs().max_element()).max(1e-30);
    p.is_finite()
        && poly
            .planes
            .iter()
            .all(|pl| pl.signed(p) < -1e-4 * scale * pl.normal.length())
}

/// Checks what the fixed area bugs broke (`area_near_f32_max_is_an_error` and
/// `tiny_direction_gives_a_unit_frame` in `tests/tests/bad_inputs.rs`): an accepted area has
/// finite planes and corners, and an orthonormal frame.
pub fn check_area_sane(area: &InfluenceArea) {
    let poly = area.polytope();
    assert!(
        poly.vertices.iter().all(|v| v.is_finite())
            && poly
                .planes
                .iter()
                .all(|pl| pl.normal.is_finite() && pl.offset.is_finite()),
        "accepted area with non-finite geometry: {area:?}"
    );
    let frame = match area {
        InfluenceArea::Plane(a) => a.frame,
        InfluenceArea::Point(a) => a.frustum().frame,
    };
    let unit = |v: Vec3| (v.length() - 1.0).abs() < 1e-4;
    assert!(
        unit(frame.forward) && unit(frame.right) && unit(frame.up),
        "non-unit frame: {area:?}"
    );
}
