//! The projected area heuristic for radial rays: perspective projection from the light, measured
//! the way the rays are sampled.

use glam::{Vec2, Vec3};
use wide::f32x4;

use crate::geometry::{box_corner, perspective_silhouette, Aabb, ConvexPolygon, Frame};
use crate::influence::PointArea;

use super::CostModel;

/// Which measure of a projected box is proportional to its hit probability. It must match how the
/// rays' directions are drawn (see [`crate::influence::PointDistribution`]).
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub enum PerspectiveMeasure {
    /// Solid angle: directions uniform over the sphere (or the frustum's pyramid).
    #[default]
    SolidAngle,
    /// Area on the image plane `z = 1`: directions uniform on the image plane.
    ImagePlane,
}

/// PAH for rays from a point: the box's silhouette seen from the eye, clipped to the frustum's
/// fields of view and measured by solid angle or image-plane area. Rays start on the near plane
/// (as the thesis cast them), so the box is first cut at the near plane: only its part beyond it can
/// be hit. The silhouette of a convex body from a point in front of it is the convex hull of its
/// projected vertices, so one hull of at most 14 points (8 corners, 6 near-plane cuts) and one
/// rectangle clip give the exact measure, also for boxes that contain the eye.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct PahPerspective {
    eye: Vec3,
    frame: Frame,
    tan_x: f32,
    tan_y: f32,
    near: f32,
    measure: PerspectiveMeasure,
    cull: bool,
}

impl PahPerspective {
    /// The rays of a point area, with the given measure, culled to its fields of view.
    pub fn for_area(area: &PointArea, measure: PerspectiveMeasure) -> Self {
        let f = area.frustum();
        Self {
            eye: f.eye,
            frame: f.frame,
            tan_x: f.tan_x,
            tan_y: f.tan_y,
            // A positive cut keeps every projected point finite when near is 0.
            near: f.near.max(1e-6 * f.far),
            measure,
            cull: true,
        }
    }

    /// The same model without culling to the fields of view.
    pub fn unculled(self) -> Self {
        Self {
            cull: false,
            ..self
        }
    }

    /// The measure of the whole window: the frustum's solid angle
    /// `4 atan(tx ty / sqrt(1 + tx^2 + ty^2))`, or its image-plane area `4 tx ty`.
    pub fn window_measure(&self) -> f32 {
        let (tx, ty) = (self.tan_x, self.tan_y);
        match self.measure {
            PerspectiveMeasure::SolidAngle => {
                4.0 * libm::atanf(tx * ty / libm::sqrtf(1.0 + tx * tx + ty * ty))
            }
            PerspectiveMeasure::ImagePlane => 4.0 * tx * ty,
        }
    }

    /// The projected silhouette of `b` beyond the near plane, on the image plane `z = 1`.
    fn silhouette(&self, b: &Aabb) -> ConvexPolygon {
        perspective_silhouette(b, self.eye, &self.frame, self.near)
    }

    /// True when `b` lies wholly beyond the near plane and, when culling, wholly inside the
    /// fields of view: for each bounding plane of the pyramid (normal `n`, through the eye), the
    /// box's farthest point along `n`, `n . (c - eye) + sum |n_k| h_k`, is on the inner side.
    #[inline]
    fn inside_pyramid(&self, b: &Aabb) -> bool {
        let (c, h) = (b.center() - self.eye, b.extent() * 0.5);
        let f = &self.frame;
        let reach = |n: Vec3| n.dot(c) + n.abs().dot(h);
        if reach(-f.forward) > -self.near {
            return false;
        }
        if !self.cull {
            return true;
        }
        [
            f.right - f.forward * self.tan_x,
            -f.right - f.forward * self.tan_x,
            f.up - f.forward * self.tan_y,
            -f.up - f.forward * self.tan_y,
        ]
        .iter()
        .all(|&n| reach(n) <= 0.0)
    }

    /// The measure of a box that lies wholly beyond the near plane and (when culling) inside the
    /// fields of view, without a hull: seen from a point outside a box, the faces turned towards it
    /// tile the silhouette, one face per axis at most, so the measure is a sum over those faces.
    /// Solid angle: an axis-aligned rectangle at distance `d` with corners `(u, v)` relative to
    /// the eye subtends `sum +- atan(u v / (d sqrt(u^2 + v^2 + d^2)))` over its corners, four
    /// arctangents in one 4-wide evaluation per face (the four terms cancel for small, far faces,
    /// which costs up to 1e-3 relative precision in f32: far below what a cost estimate can tell
    /// apart). Image-plane area: each face's projected quad by the shoelace formula. `None` for
    /// every other box (the hull path handles it).
    #[inline]
    fn front_faces(&self, b: &Aabb) -> Option<f32> {
        if b.contains_point(self.eye) || !self.inside_pyramid(b) {
            return None;
        }
        let mut total = 0.0;
        for k in 0..3 {
            let (near_face, side) = if self.eye[k] < b.min[k] {
                (b.min[k], 0)
            } else if self.eye[k] > b.max[k] {
                (b.max[k], 1 << k)
            } else {
                continue;
            };
            let (a1, a2) = ((k + 1) % 3, (k + 2) % 3);
            total += match self.measure {
                PerspectiveMeasure::SolidAngle => {
                    let d = (near_face - self.eye[k]).abs();
                    let (u1, u2) = (b.min[a1] - self.eye[a1], b.max[a1] - self.eye[a1]);
                    let (v1, v2) = (b.min[a2] - self.eye[a2], b.max[a2] - self.eye[a2]);
                    let u = f32x4::from([u2, u1, u2, u1]);
                    let v = f32x4::from([v2, v2, v1, v1]);
                    let dd = f32x4::splat(d);
                    let f = (u * v / (dd * (u * u + v * v + dd * dd).sqrt())).atan();
                    let f = f.to_array();
                    (f[0] - f[1] - f[2] + f[3]).abs()
                }
                PerspectiveMeasure::ImagePlane => {
                    let quad = [
                        side,
                        side | 1 << a1,
                        side | 1 << a1 | 1 << a2,
                        side | 1 << a2,
                    ];
                    let p = quad.map(|i| {
                        let q = self.frame.to_local(box_corner(b, i) - self.eye);
                        Vec2::new(q.x, q.y) / q.z
                    });
                    0.5 * (p[0].perp_dot(p[1])
                        + p[1].perp_dot(p[2])
                        + p[2].perp_dot(p[3])
                        + p[3].perp_dot(p[0]))
                    .abs()
                }
            };
        }
        Some(total)
    }
}

impl CostModel for PahPerspective {
    fn measure(&self, b: &Aabb) -> f32 {
        if b.is_empty() {
            return 0.0;
        }
        if let Some(m) = self.front_faces(b) {
            return m;
        }
        let mut poly = self.silhouette(b);
        if self.cull {
            let t = Vec2::new(self.tan_x, self.tan_y);
            poly = poly.clip_to_rect(-t, t);
        }
        match self.measure {
            PerspectiveMeasure::SolidAngle => poly.solid_angle_on_image_plane(),
            PerspectiveMeasure::ImagePlane => poly.area(),
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::geometry::Ray;
    use crate::influence::{PointDistribution, RaySampler};

    #[test]
    fn window_measures() {
        let a = PointArea::new(Vec3::ZERO, Vec3::Z, 90.0, 90.0, 0.1, 10.0).unwrap();
        let sa = PahPerspective::for_area(&a, PerspectiveMeasure::SolidAngle);
        // A 90 x 90 degree pyramid is one face of a cube seen from its centre: 4 pi / 6.
        assert!((sa.window_measure() - 4.0 * core::f32::consts::PI / 6.0).abs() < 1e-5);
        let ip = PahPerspective::for_area(&a, PerspectiveMeasure::ImagePlane);
        assert!((ip.window_measure() - 4.0).abs() < 1e-6);
        // A box covering the whole window covers all of it.
        let wall = Aabb::new(Vec3::new(-100.0, -100.0, 5.0), Vec3::new(100.0, 100.0, 6.0));
        assert!((sa.measure(&wall) - sa.window_measure()).abs() < 1e-4);
        assert!((ip.measure(&wall) - 4.0).abs() < 1e-4);
        // A box around the eye covers the whole window too.
        let around = Aabb::new(Vec3::splat(-1.0), Vec3::splat(1.0));
        assert!((ip.measure(&around) - 4.0).abs() < 1e-4);
        // A box behind the eye is never hit.
        let behind = Aabb::new(Vec3::new(-1.0, -1.0, -3.0), Vec3::new(1.0, 1.0, -2.0));
        assert_eq!(sa.measure(&behind), 0.0);
    }

    #[test]
    fn front_faces_equal_the_hull_measure() {
        let area = PointArea::new(
            Vec3::new(0.3, -0.2, 0.1),
            Vec3::new(0.2, 0.1, 1.0),
            130.0,
            100.0,
            0.5,
            50.0,
        )
        .unwrap();
        let mut rng = crate::random::Pcg32::new(3);
        let mut checked = 0;
        for m in [
            PerspectiveMeasure::SolidAngle,
            PerspectiveMeasure::ImagePlane,
        ] {
            for cull in [true, false] {
                let mut pah = PahPerspective::for_area(&area, m);
                pah.cull = cull;
                for _ in 0..2000 {
                    let lo = Vec3::new(
                        rng.range(-10.0, 10.0),
                        rng.range(-10.0, 10.0),
                        rng.range(-2.0, 20.0),
                    );
                    let b = Aabb::new(
                        lo,
                        lo + Vec3::new(
                            rng.range(0.0, 3.0),
                            rng.range(0.0, 3.0),
                            rng.range(0.0, 3.0),
                        ),
                    );
                    let Some(fast) = pah.front_faces(&b) else {
                        continue;
                    };
                    let mut poly = pah.silhouette(&b);
                    if cull {
                        poly = poly.clip_to_rect(
                            -Vec2::new(pah.tan_x, pah.tan_y),
                            Vec2::new(pah.tan_x, pah.tan_y),
                        );
                    }
                    let hull = match m {
                        PerspectiveMeasure::SolidAngle => poly.solid_angle_on_image_plane(),
                        PerspectiveMeasure::ImagePlane => poly.area(),
                    };
                    // The corner formula cancels for small, far faces: 1e-3 relative in f32, far
                    // below what a cost estimate can tell apart.
                    assert!(
                        (fast - hull).abs() <= 1e-3 * hull.max(1e-3),
                        "{m:?} {b:?}: {fast} vs {hull}"
                    );
                    checked += 1;
                }
            }
        }
        assert!(checked > 2000, "the fast path ran {checked} times");
    }

    /// The measure over the window measure is the probability that a sampled ray hits the box.
    fn hit_fraction(area: &PointArea, dist: PointDistribution, b: &Aabb, n: u32) -> f32 {
        let mut s = RaySampler::new((*area).into(), 1).distribution(dist);
        let hits = (0..n)
            .filter(|_| {
                let r: Ray = s.sample();
                b.intersect(&r, f32::INFINITY).is_some()
            })
            .count();
        hits as f32 / n as f32
    }

    #[test]
    fn measures_match_their_samplers_at_wide_fov() {
        let area = PointArea::new(
            Vec3::ZERO,
            Vec3::new(0.2, 0.1, 1.0),
            130.0,
            100.0,
            0.5,
            50.0,
        )
        .unwrap();
        let boxes = [
            Aabb::new(Vec3::new(-1.0, -1.0, 3.0), Vec3::new(1.0, 1.0, 4.0)),
            Aabb::new(Vec3::new(3.0, -2.0, 1.0), Vec3::new(8.0, 0.5, 2.0)),
            Aabb::new(Vec3::new(-9.0, 1.0, 0.2), Vec3::new(-4.0, 6.0, 3.0)),
            Aabb::new(Vec3::new(-0.3, -0.3, -0.3), Vec3::new(0.3, 0.3, 0.8)),
        ];
        for (dist, m) in [
            (
                PointDistribution::SolidAngle,
                PerspectiveMeasure::SolidAngle,
            ),
            (
                PointDistribution::ImagePlane,
                PerspectiveMeasure::ImagePlane,
            ),
        ] {
            let pah = PahPerspective::for_area(&area, m);
            for b in &boxes {
                let expect = pah.measure(b) / pah.window_measure();
                let got = hit_fraction(&area, dist, b, 100_000);
                assert!(
                    (got - expect).abs() < 0.005,
                    "{m:?} {b:?}: sampled {got}, measure {expect}"
                );
            }
        }
    }
}
