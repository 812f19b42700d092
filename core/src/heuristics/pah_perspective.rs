//! The projected area heuristic for radial rays: perspective projection from the light, measured
//! the way the rays are sampled.

use glam::{Vec2, Vec3};
use wide::f32x4;

use crate::geometry::{box_solid_angle4, perspective_silhouette, Aabb, ConvexPolygon, Frame};
use crate::influence::PointArea;
use crate::simd::Aabb4;

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

    /// The hull path: the silhouette beyond the near plane, clipped to the window when culling.
    fn hull_measure(&self, b: &Aabb) -> f32 {
        if b.is_empty() {
            return 0.0;
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

    /// Which lanes of `b` lie wholly beyond the near plane and, when culling, wholly inside the
    /// fields of view (such a box never contains the eye, since the near distance is positive).
    /// For each bounding plane of the pyramid (normal `n`, through the eye) the box's farthest
    /// point along `n`, `n . (c - eye) + sum |n_k| h_k`, must be on the inner side. Empty and NaN
    /// lanes fail every comparison, so they are never inside.
    #[inline(always)]
    fn inside_pyramid4(&self, rel_lo: &[f32x4; 3], rel_hi: &[f32x4; 3]) -> f32x4 {
        let half = f32x4::splat(0.5);
        let c: [f32x4; 3] = core::array::from_fn(|k| (rel_lo[k] + rel_hi[k]) * half);
        let h: [f32x4; 3] = core::array::from_fn(|k| (rel_hi[k] - rel_lo[k]) * half);
        let reach = |n: Vec3| {
            let a = n.abs();
            c[0] * f32x4::splat(n.x)
                + c[1] * f32x4::splat(n.y)
                + c[2] * f32x4::splat(n.z)
                + h[0] * f32x4::splat(a.x)
                + h[1] * f32x4::splat(a.y)
                + h[2] * f32x4::splat(a.z)
        };
        let f = &self.frame;
        let mut inside = reach(-f.forward).simd_le(f32x4::splat(-self.near));
        if self.cull {
            let zero = f32x4::ZERO;
            for n in [
                f.right - f.forward * self.tan_x,
                -f.right - f.forward * self.tan_x,
                f.up - f.forward * self.tan_y,
                -f.up - f.forward * self.tan_y,
            ] {
                inside &= reach(n).simd_le(zero);
            }
        }
        inside
    }

    /// The measures of four boxes without a hull, and the mask of the lanes where they are exact:
    /// the boxes wholly beyond the near plane and (when culling) inside the fields of view, which
    /// are most boxes of a build below its top levels. Seen from a point outside a box, the faces
    /// turned towards it tile the silhouette, one face per axis at most, so the measure is a sum
    /// over those faces.
    ///
    /// Solid angle: [`box_solid_angle4`], one `atan2` per box, exact also for small, far boxes.
    ///
    /// Image-plane area: each face's projected quad by the shoelace formula.
    #[inline(always)]
    fn front_faces4(&self, b: &Aabb4) -> (f32x4, f32x4) {
        let e = self.eye;
        let rel_lo = [
            b.min[0] - f32x4::splat(e.x),
            b.min[1] - f32x4::splat(e.y),
            b.min[2] - f32x4::splat(e.z),
        ];
        let rel_hi = [
            b.max[0] - f32x4::splat(e.x),
            b.max[1] - f32x4::splat(e.y),
            b.max[2] - f32x4::splat(e.z),
        ];
        let inside = self.inside_pyramid4(&rel_lo, &rel_hi);
        if inside.to_bitmask() == 0 {
            return (f32x4::ZERO, inside);
        }
        if self.measure == PerspectiveMeasure::SolidAngle {
            return (box_solid_angle4(&rel_lo, &rel_hi), inside);
        }
        let zero = f32x4::ZERO;
        let mut total = zero;
        for k in 0..3 {
            let (a1, a2) = ((k + 1) % 3, (k + 2) % 3);
            // The eye below the slab sees the face at the minimum, above it the one at the maximum.
            let below = rel_lo[k].simd_gt(zero);
            let visible = below | rel_hi[k].simd_lt(zero);
            if (visible & inside).to_bitmask() == 0 {
                continue;
            }
            let face = self.face_image_area4(
                k,
                below,
                [rel_lo[k], rel_lo[a1], rel_lo[a2]],
                [rel_hi[k], rel_hi[a1], rel_hi[a2]],
                [a1, a2],
            );
            total += visible.select(face, zero);
        }
        (total, inside)
    }

    /// The image-plane area of each lane's face on axis `k` (at the minimum where `below`, else
    /// the maximum): its four corners in frame coordinates, divided by depth, by the shoelace
    /// formula. `lo` and `hi` hold the eye-relative bounds on axes `k`, `a[0]`, `a[1]`.
    #[inline(always)]
    fn face_image_area4(
        &self,
        k: usize,
        below: f32x4,
        lo: [f32x4; 3],
        hi: [f32x4; 3],
        a: [usize; 2],
    ) -> f32x4 {
        let f = &self.frame;
        // Column `axis` of the world-to-frame matrix, times a coordinate on that axis.
        let column = |axis: usize, t: f32x4| {
            [
                t * f32x4::splat(f.right[axis]),
                t * f32x4::splat(f.up[axis]),
                t * f32x4::splat(f.forward[axis]),
            ]
        };
        let plane = column(k, below.select(lo[0], hi[0]));
        let (u1, u2) = (column(a[0], lo[1]), column(a[0], hi[1]));
        let (v1, v2) = (column(a[1], lo[2]), column(a[1], hi[2]));
        let project = |u: &[f32x4; 3], v: &[f32x4; 3]| {
            let inv_z = f32x4::ONE / (plane[2] + u[2] + v[2]);
            (
                (plane[0] + u[0] + v[0]) * inv_z,
                (plane[1] + u[1] + v[1]) * inv_z,
            )
        };
        let p = [
            project(&u1, &v1),
            project(&u2, &v1),
            project(&u2, &v2),
            project(&u1, &v2),
        ];
        let cross = |i: usize, j: usize| p[i].0 * p[j].1 - p[i].1 * p[j].0;
        (cross(0, 1) + cross(1, 2) + cross(2, 3) + cross(3, 0)).abs() * f32x4::splat(0.5)
    }
}

impl CostModel for PahPerspective {
    fn measure(&self, b: &Aabb) -> f32 {
        if b.is_empty() {
            return 0.0;
        }
        let (m, inside) = self.front_faces4(&Aabb4::splat(b));
        if inside.to_bitmask() & 1 != 0 {
            m.to_array()[0]
        } else {
            self.hull_measure(b)
        }
    }

    /// Four boxes at once: the hull-free path for every lane inside the pyramid, the hull for
    /// the rest (boxes at the top of a build, straddling the window or the near plane, and empty
    /// padding lanes).
    #[inline]
    fn measure4(&self, b: &Aabb4) -> f32x4 {
        let (m, inside) = self.front_faces4(b);
        let mask = inside.to_bitmask();
        if mask == 0b1111 {
            return m;
        }
        let mut out = m.to_array();
        for (j, o) in out.iter_mut().enumerate() {
            if mask & (1 << j) == 0 {
                *o = self.hull_measure(&b.lane(j));
            }
        }
        f32x4::from(out)
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
                    let (fast, inside) = pah.front_faces4(&Aabb4::splat(&b));
                    if inside.to_bitmask() != 0b1111 {
                        continue;
                    }
                    let fast = fast.to_array()[0];
                    let hull = pah.hull_measure(&b);
                    assert!(
                        (fast - hull).abs() <= 1e-4 * hull.max(1e-3),
                        "{m:?} {b:?}: {fast} vs {hull}"
                    );
                    checked += 1;
                }
            }
        }
        assert!(checked > 2000, "the fast path ran {checked} times");
    }

    #[test]
    fn four_lanes_equal_one_at_a_time() {
        let area =
            PointArea::new(Vec3::new(0.5, 0.2, -3.0), Vec3::Z, 90.0, 70.0, 0.5, 50.0).unwrap();
        let mut rng = crate::random::Pcg32::new(11);
        for m in [
            PerspectiveMeasure::SolidAngle,
            PerspectiveMeasure::ImagePlane,
        ] {
            let pah = PahPerspective::for_area(&area, m);
            for _ in 0..500 {
                // Boxes inside the window, straddling it or the near plane, behind the eye, and
                // empty, mixed in one group of four.
                let lanes: [Aabb; 4] = core::array::from_fn(|_| {
                    if rng.range(0.0, 1.0) < 0.1 {
                        return Aabb::EMPTY;
                    }
                    let lo = Vec3::new(
                        rng.range(-8.0, 8.0),
                        rng.range(-8.0, 8.0),
                        rng.range(-6.0, 20.0),
                    );
                    Aabb::new(
                        lo,
                        lo + Vec3::new(
                            rng.range(0.0, 4.0),
                            rng.range(0.0, 4.0),
                            rng.range(0.0, 4.0),
                        ),
                    )
                });
                let four = pah.measure4(&Aabb4::from_boxes(lanes)).to_array();
                for (j, b) in lanes.iter().enumerate() {
                    assert_eq!(four[j].to_bits(), pah.measure(b).to_bits(), "{m:?} {b:?}");
                }
            }
        }
    }

    #[test]
    fn solid_angle_is_scale_free_and_exact_for_far_small_faces() {
        // A unit cube 1e4 away straight ahead shows one face: about 1 / r^2 steradians.
        let base = Aabb::new(Vec3::new(-0.5, -0.5, 1e4), Vec3::new(0.5, 0.5, 1e4 + 1.0));
        for scale in [1e-12f32, 1e-6, 1.0, 1e6, 1e12] {
            let area =
                PointArea::new(Vec3::ZERO, Vec3::Z, 60.0, 60.0, 0.5 * scale, 2e4 * scale).unwrap();
            let pah = PahPerspective::for_area(&area, PerspectiveMeasure::SolidAngle);
            let b = Aabb::new(base.min * scale, base.max * scale);
            let got = pah.measure(&b);
            let expect = 4.0 * libm::atanf(0.25 / (1e4 * libm::sqrtf(1e8 + 0.5)));
            assert!(
                (got - expect).abs() <= 1e-5 * expect,
                "scale {scale}: {got} vs {expect}"
            );
        }
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
