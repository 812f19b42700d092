//! Influence areas for the heuristic and top-level benchmarks: a plane and a point area placed
//! over a scene's box from an oblique side, and deterministic random areas for the lookup
//! benchmark.

use glam::Vec3;
use rdbvh_core::geometry::{Aabb, Frame};
use rdbvh_core::influence::{InfluenceArea, PlaneArea, PointArea};

use crate::SplitMix64;

/// The plane area's ray direction: mostly down, tilted about 13 degrees so no axis is exactly
/// facing (the closed-form PAH then weighs all three face areas).
pub const PLANE_NORMAL: Vec3 = Vec3::new(0.2, -1.0, 0.1);

/// The point area's eye direction from the box's centre: oblique, as the camera rays' eye.
pub const EYE_SIDE: Vec3 = Vec3::new(0.35, 0.45, 1.0);

/// The eight corners of `b`.
fn corners(b: &Aabb) -> [Vec3; 8] {
    core::array::from_fn(|i| {
        Vec3::select(
            glam::BVec3::new(i & 1 != 0, i & 2 != 0, i & 4 != 0),
            b.max,
            b.min,
        )
    })
}

/// A plane area whose light rectangle lies just outside `b`, facing into it along
/// [`PLANE_NORMAL`], and whose box holds all of `b` (a 1% margin on every side).
pub fn plane_area_facing(b: &Aabb) -> Result<PlaneArea, String> {
    let frame = Frame::look_at(PLANE_NORMAL).ok_or("degenerate plane normal")?;
    let local = corners(b).map(|c| frame.to_local(c));
    let lo = local
        .iter()
        .fold(Vec3::splat(f32::INFINITY), |m, v| m.min(*v));
    let hi = local
        .iter()
        .fold(Vec3::splat(f32::NEG_INFINITY), |m, v| m.max(*v));
    let margin = 0.01 * (hi - lo).max_element().max(1e-6);
    let mid = 0.5 * (lo + hi);
    let center = frame.to_world(Vec3::new(mid.x, mid.y, lo.z - margin));
    PlaneArea::new(
        center,
        PLANE_NORMAL,
        0.5 * (hi.x - lo.x) + margin,
        0.5 * (hi.y - lo.y) + margin,
        hi.z - lo.z + 2.0 * margin,
    )
    .map_err(|e| format!("plane area over the scene: {e}"))
}

/// A point area with its eye outside `b` (on [`EYE_SIDE`], 1.5 bounding-sphere radii from the
/// centre) looking at the centre with 90 x 90 degree fields of view: the cone inscribed in the
/// frustum has a 45 degree half angle, and the bounding sphere subtends asin(1 / 1.5) = 41.8
/// degrees, so the frustum holds the whole box.
pub fn point_area_facing(b: &Aabb) -> Result<PointArea, String> {
    let c = b.center();
    let r = (0.5 * (b.max - b.min).length()).max(1e-6);
    let back = EYE_SIDE.normalize();
    let dist = 1.5 * r;
    PointArea::new(c + back * dist, -back, 90.0, 90.0, 0.1 * r, dist + 1.01 * r)
        .map_err(|e| format!("point area over the scene: {e}"))
}

/// `n` random areas in the box `[0, side]^3`, half planes and half points in turn, from `seed`:
/// plane areas with half extents in `[0.5, 2]` and depth in `[1, 5]`, point areas with fields of
/// view in `[30, 90]` degrees and far in `[2, 6]`, every direction uniform on the sphere.
pub fn random_areas(n: usize, side: f32, seed: u64) -> Vec<InfluenceArea> {
    let mut rng = SplitMix64::new(seed);
    let mut areas = Vec::with_capacity(n);
    while areas.len() < n {
        let mut range = |lo: f32, hi: f32| lo + (hi - lo) * rng.next_f32();
        let p = Vec3::new(range(0.0, side), range(0.0, side), range(0.0, side));
        let z = range(-1.0, 1.0);
        let phi = range(0.0, core::f32::consts::TAU);
        let s = (1.0 - z * z).max(0.0).sqrt();
        let d = Vec3::new(s * phi.cos(), s * phi.sin(), z);
        let area: Option<InfluenceArea> = if areas.len() % 2 == 0 {
            PlaneArea::new(p, d, range(0.5, 2.0), range(0.5, 2.0), range(1.0, 5.0))
                .ok()
                .map(Into::into)
        } else {
            let fov_x = range(30.0, 90.0);
            let fov_y = range(30.0, 90.0);
            PointArea::new(p, d, fov_x, fov_y, 0.0, range(2.0, 6.0))
                .ok()
                .map(Into::into)
        };
        areas.extend(area);
    }
    areas
}

/// `n` points uniform in `b`, from `seed`.
pub fn random_points(b: &Aabb, n: usize, seed: u64) -> Vec<Vec3> {
    let mut rng = SplitMix64::new(seed);
    let e = b.max - b.min;
    (0..n)
        .map(|_| b.min + e * Vec3::new(rng.next_f32(), rng.next_f32(), rng.next_f32()))
        .collect()
}

#[cfg(test)]
mod tests {
    use super::*;

    fn boxes() -> [Aabb; 2] {
        [
            Aabb::new(Vec3::splat(-1.0), Vec3::new(3.0, 1.0, 2.0)),
            Aabb::new(
                Vec3::new(-1500.0, 0.0, -600.0),
                Vec3::new(1400.0, 1200.0, 600.0),
            ),
        ]
    }

    #[test]
    fn areas_over_a_box_hold_its_corners_and_start_outside() {
        for b in boxes() {
            let plane = plane_area_facing(&b).unwrap();
            let point = point_area_facing(&b).unwrap();
            for c in corners(&b) {
                assert!(plane.contains(c), "plane misses {c}");
                assert!(point.contains(c), "point misses {c}");
            }
            let eye = point.eye();
            assert!(!(eye.cmpge(b.min).all() && eye.cmple(b.max).all()));
            let light = plane.obb().center - plane.obb().frame.forward * (0.5 * plane.depth);
            assert!(!(light.cmpge(b.min).all() && light.cmple(b.max).all()));
        }
    }

    #[test]
    fn random_areas_are_deterministic_and_mixed() {
        let a = random_areas(10, 10.0, 3);
        assert_eq!(a.len(), 10);
        assert_eq!(a, random_areas(10, 10.0, 3));
        assert!(matches!(a[0], InfluenceArea::Plane(_)));
        assert!(matches!(a[1], InfluenceArea::Point(_)));
    }
}
