//! The projected area heuristic for radial rays: perspective projection from the light, measured
//! the way the rays are sampled.

use glam::{Vec2, Vec3};
use wide::f32x4;

use crate::geometry::{
    box_solid_angle4, box_solid_angle_far4, far_field4, perspective_silhouette,
    windowed_silhouette, Aabb, ConvexPolygon, Frame, FAR_FIELD,
};
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
/// (as the thesis cast them) and stop at the far plane, so the box is first cut at both: only its
/// part between them can be hit (the far cut when culling to the frustum, with the fields of
/// view). A box wholly inside the frustum is measured as the sum of its faces turned towards the
/// eye, four boxes at a time (exact, or by the corrected midpoint rule when it is far: see
/// [`crate::geometry::far_field4`]). Any other box takes the hull path: the silhouette of a convex
/// body from a point in front of it is the convex hull of its projected vertices, so one hull of at
/// most 14 points (8 corners, 6 near-plane cuts) and one rectangle clip give the exact measure, also
/// for boxes that contain the eye.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct PahPerspective {
    eye: Vec3,
    frame: Frame,
    tan_x: f32,
    tan_y: f32,
    near: f32,
    far: f32,
    measure: PerspectiveMeasure,
    cull: bool,
    /// Price boxes by [`PahPerspective::estimated`]'s centre estimate instead of exactly.
    estimate: bool,
    /// [`PahPerspective::window_measure`], which the estimate clamps every box to.
    window: f32,
    lanes: Lanes,
}

/// The model's constants splatted to 4-wide lanes once, not per call: a sweep measures hundreds
/// of thousands of box groups, and re-splatting some forty constants would be a large share of
/// each measure.
#[derive(Clone, Copy, Debug, PartialEq)]
struct Lanes {
    eye: [f32x4; 3],
    forward: [f32x4; 3],
    /// The near plane's and (when culling) the far plane's and the four side planes' outward
    /// normals `n`, `|n|`, and the bound on the inner side (`-near`, `far`, then 0).
    normal: [[f32x4; 3]; 6],
    abs_normal: [[f32x4; 3]; 6],
    limit: [f32x4; 6],
    /// 6 when culling, else 1 (the near plane alone).
    planes: usize,
}

impl Lanes {
    fn new(eye: Vec3, f: &Frame, tan: (f32, f32), depth: (f32, f32), cull: bool) -> Self {
        let splat3 = |v: Vec3| [f32x4::splat(v.x), f32x4::splat(v.y), f32x4::splat(v.z)];
        let normals = [
            -f.forward,
            f.forward,
            f.right - f.forward * tan.0,
            -f.right - f.forward * tan.0,
            f.up - f.forward * tan.1,
            -f.up - f.forward * tan.1,
        ];
        Self {
            eye: splat3(eye),
            forward: splat3(f.forward),
            normal: normals.map(splat3),
            abs_normal: normals.map(|n| splat3(n.abs())),
            limit: [-depth.0, depth.1, 0.0, 0.0, 0.0, 0.0].map(f32x4::splat),
            planes: if cull { 6 } else { 1 },
        }
    }
}

impl PahPerspective {
    /// The rays of a point area, with the given measure, culled to its fields of view.
    pub fn for_area(area: &PointArea, measure: PerspectiveMeasure) -> Self {
        let f = area.frustum();
        // The hull path floors its own cut relative to each box (`perspective_silhouette`); the
        // 4-wide paths only need a box wholly in front of the eye to be strictly in front of it.
        let near = f.near.max(f32::MIN_POSITIVE);
        Self {
            eye: f.eye,
            frame: f.frame,
            tan_x: f.tan_x,
            tan_y: f.tan_y,
            near,
            far: f.far,
            measure,
            cull: true,
            estimate: false,
            window: window_measure(measure, f.tan_x, f.tan_y),
            lanes: Lanes::new(f.eye, &f.frame, (f.tan_x, f.tan_y), (near, f.far), true),
        }
    }

    /// The same model pricing every box by its centre estimate, an opt-in stand-in for builds:
    /// each face turned towards the eye counts as a small patch of its area `A_k` at its own
    /// distance along its axis, `|c_k| - h_k` for eye-relative centre `c` and half extents `h`,
    /// with the distance to the face's centre expanded to first order about the box's, so a box
    /// measures about `sum_k A_k (|c_k| - h_k) / r_k^3` with `r` the distance (solid angle) or
    /// the depth (image plane), clamped to the window's measure, and zero when it lies wholly
    /// outside the culled pyramid. One root and one division per box and no branch on the box's
    /// position, where the exact measure clips a hull near the eye and takes a root and a
    /// division per face elsewhere. Inside a node all children sit at about the node's distance,
    /// so the split choice, which compares children within a node, loses little (measured:
    /// benches/RESULTS.md, section Perspective PAH build cost). Estimate a built tree's cost with
    /// the exact model, not this one.
    pub fn estimated(self) -> Self {
        Self {
            estimate: true,
            ..self
        }
    }

    /// The centre estimate of four boxes ([`PahPerspective::estimated`]); `inside`: they are
    /// known to lie inside the pyramid (their node does), so the cull is skipped.
    #[inline(always)]
    fn estimate4(&self, b: &Aabb4, inside: bool) -> f32x4 {
        let (rel_lo, rel_hi) = self.relative(b);
        let (c, h) = centre_half(&rel_lo, &rel_hi);
        // The face turned towards the eye on axis `k` (none when the eye is within the box's
        // slab) lies at `|c_k| - h_k` along it, area `A_k`; its squared distance
        // `r_k^2 = r^2 (1 + x_k)` with `x_k = (h_k^2 - 2 |c_k| h_k) / r^2`, and
        // `r_k^-3 ~ r^-3 (1 - 1.5 x_k)`: one root and one division for the box, none per face.
        // The distance (solid angle) or the depth (image plane).
        let r = self.reach(&c);
        let inv_r2 = f32x4::ONE / (r * r);
        let (four, three_halves) = (f32x4::splat(4.0), f32x4::splat(1.5));
        let mut sum = f32x4::ZERO;
        for k in 0..3 {
            let (a1, a2) = ((k + 1) % 3, (k + 2) % 3);
            let ck = c[k].abs();
            let along = (ck - h[k]).fast_max(f32x4::ZERO);
            let x = (h[k] * h[k] - f32x4::splat(2.0) * ck * h[k]) * inv_r2;
            sum += four * h[a1] * h[a2] * along * (f32x4::ONE - three_halves * x);
        }
        let m = sum * inv_r2 / r;
        let window = f32x4::splat(self.window);
        // The eye inside or behind a box (depth <= 0, a division by zero, NaN) sees at most
        // the window.
        let m = (m.simd_ge(f32x4::ZERO) & m.simd_le(window)).select(m, window);
        let zero = if inside {
            b.empty()
        } else {
            b.empty() | self.outside_pyramid4(&c, &h)
        };
        zero.select(f32x4::ZERO, m)
    }

    /// Which lanes of `b` (eye-relative centres `c`, half extents `h`) lie wholly outside one of
    /// the pyramid's planes: the box's nearest point along the plane's outward normal `n`,
    /// `n . c - sum |n_k| h_k`, beyond the plane.
    #[inline(always)]
    fn outside_pyramid4(&self, c: &[f32x4; 3], h: &[f32x4; 3]) -> f32x4 {
        let l = &self.lanes;
        let mut outside = f32x4::ZERO;
        for p in 0..l.planes {
            let (n, a) = (&l.normal[p], &l.abs_normal[p]);
            let near =
                c[0] * n[0] + c[1] * n[1] + c[2] * n[2] - (h[0] * a[0] + h[1] * a[1] + h[2] * a[2]);
            outside |= near.simd_gt(l.limit[p]);
        }
        outside
    }

    /// The same model without culling to the fields of view and the far plane (boxes are still
    /// cut at the near plane).
    pub fn unculled(self) -> Self {
        let tan = (self.tan_x, self.tan_y);
        Self {
            cull: false,
            lanes: Lanes::new(self.eye, &self.frame, tan, (self.near, self.far), false),
            ..self
        }
    }

    /// The measure of the whole window: the frustum's solid angle
    /// `4 atan(tx ty / sqrt(1 + tx^2 + ty^2))`, or its image-plane area `4 tx ty`.
    pub fn window_measure(&self) -> f32 {
        self.window
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
        let poly = if self.cull {
            let t = Vec2::new(self.tan_x, self.tan_y);
            windowed_silhouette(b, self.eye, &self.frame, (self.near, self.far), t)
        } else {
            self.silhouette(b)
        };
        match self.measure {
            PerspectiveMeasure::SolidAngle => poly.solid_angle_on_image_plane(),
            PerspectiveMeasure::ImagePlane => poly.area(),
        }
    }

    /// Which lanes of `b` lie wholly beyond the near plane and, when culling, wholly inside the
    /// fields of view and before the far plane (such a box never contains the eye, since the
    /// near distance is positive): for each bounding plane (normal `n`, through the eye) the
    /// box's farthest point along `n`, `n . c + sum |n_k| h_k`, must be on the inner side, with
    /// `c` and `h` the eye-relative centres and half extents. Empty and NaN lanes fail every
    /// comparison, so they are never inside.
    #[inline(always)]
    fn inside_pyramid4(&self, c: &[f32x4; 3], h: &[f32x4; 3]) -> f32x4 {
        let l = &self.lanes;
        let mut inside = f32x4::splat(f32::from_bits(u32::MAX));
        for p in 0..l.planes {
            let (n, a) = (&l.normal[p], &l.abs_normal[p]);
            let reach =
                c[0] * n[0] + c[1] * n[1] + c[2] * n[2] + h[0] * a[0] + h[1] * a[1] + h[2] * a[2];
            inside &= reach.simd_le(l.limit[p]);
        }
        inside
    }

    /// The measures of four boxes without a hull, and the mask of the lanes where they are exact:
    /// the boxes wholly beyond the near plane and (when culling) inside the fields of view, which
    /// are most boxes of a build below its top levels. Seen from a point outside a box, the faces
    /// turned towards it tile the silhouette, one face per axis at most, so the measure is a sum
    /// over those faces, each lane by the rule its distance allows ([`Self::by_distance4`]).
    #[inline(always)]
    fn front_faces4(&self, b: &Aabb4) -> (f32x4, f32x4) {
        let (rel_lo, rel_hi) = self.relative(b);
        let (c, h) = centre_half(&rel_lo, &rel_hi);
        let inside = self.inside_pyramid4(&c, &h);
        let inside_bits = inside.to_bitmask();
        if inside_bits == 0 {
            return (f32x4::ZERO, inside);
        }
        let far = self.far_lanes(&c, &h);
        (self.by_distance4(&rel_lo, &rel_hi, far, !inside), inside)
    }

    /// The measures of four boxes in front of the eye, each by the rule its own distance allows:
    /// the corrected midpoint rule for the `far` lanes (as good as exact there, see
    /// `far_field4`), the exact formula for the others; lanes in `skip` are not needed. The rule
    /// is chosen per lane, so a box's measure never depends on the boxes that share its group (a
    /// sweep's padding, a threaded build's different neighbours): a group that mixes the two
    /// evaluates both.
    #[inline(always)]
    fn by_distance4(
        &self,
        rel_lo: &[f32x4; 3],
        rel_hi: &[f32x4; 3],
        far: f32x4,
        skip: f32x4,
    ) -> f32x4 {
        if (far | skip).all() {
            return self.far4(rel_lo, rel_hi);
        }
        let exact = self.exact4(rel_lo, rel_hi);
        if (far & !skip).any() {
            far.select(self.far4(rel_lo, rel_hi), exact)
        } else {
            exact
        }
    }

    /// The lanes far enough from the eye for the far-field rule (`far_field4`):
    /// half-diagonal^2 <= FAR_FIELD * reach^2, for eye-relative centres `c` and half extents `h`.
    #[inline(always)]
    fn far_lanes(&self, c: &[f32x4; 3], h: &[f32x4; 3]) -> f32x4 {
        let reach = self.reach(c);
        let diag2 = h[0] * h[0] + h[1] * h[1] + h[2] * h[2];
        diag2.simd_le(reach * reach * f32x4::splat(FAR_FIELD))
    }

    /// The boxes' bounds relative to the eye.
    #[inline(always)]
    fn relative(&self, b: &Aabb4) -> ([f32x4; 3], [f32x4; 3]) {
        let e = &self.lanes.eye;
        (
            core::array::from_fn(|k| b.min[k] - e[k]),
            core::array::from_fn(|k| b.max[k] - e[k]),
        )
    }

    /// What "far" is measured against for eye-relative point `p`: its distance (solid angle) or
    /// its depth (image plane), the `rho` of `far_field4`.
    #[inline(always)]
    fn reach(&self, p: &[f32x4; 3]) -> f32x4 {
        match self.measure {
            PerspectiveMeasure::SolidAngle => (p[0] * p[0] + p[1] * p[1] + p[2] * p[2]).sqrt(),
            PerspectiveMeasure::ImagePlane => {
                let f = &self.lanes.forward;
                p[0] * f[0] + p[1] * f[1] + p[2] * f[2]
            }
        }
    }

    /// The far-field measure of boxes in front of the eye (`far_field4`).
    #[inline(always)]
    fn far4(&self, rel_lo: &[f32x4; 3], rel_hi: &[f32x4; 3]) -> f32x4 {
        match self.measure {
            PerspectiveMeasure::SolidAngle => box_solid_angle_far4(rel_lo, rel_hi),
            // `1 / z^3` at depth `z`, which is linear along the face: along an in-plane axis
            // with forward component `alpha`, its second derivative is `12 alpha^2 / z^2` times
            // itself.
            PerspectiveMeasure::ImagePlane => far_field4(rel_lo, rel_hi, |f| {
                let inv_z = f32x4::ONE / self.reach(&f.centre);
                let inv_z2 = inv_z * inv_z;
                let fw = &self.lanes.forward;
                let [a, b] = f.axes.map(|k| fw[k] * fw[k]);
                let [a2, b2] = f.half_sq;
                let curve = (a2 * a + b2 * b) * inv_z2 * f32x4::splat(2.0);
                inv_z2 * inv_z * (f32x4::ONE + curve)
            }),
        }
    }

    /// The exact measure of boxes in front of the eye. Solid angle: [`box_solid_angle4`], one
    /// `atan2` per box. Image-plane area: each visible face's projected quad by the shoelace
    /// formula.
    #[inline(always)]
    fn exact4(&self, rel_lo: &[f32x4; 3], rel_hi: &[f32x4; 3]) -> f32x4 {
        if self.measure == PerspectiveMeasure::SolidAngle {
            return box_solid_angle4(rel_lo, rel_hi);
        }
        let zero = f32x4::ZERO;
        let mut total = zero;
        for k in 0..3 {
            let (a1, a2) = ((k + 1) % 3, (k + 2) % 3);
            // The eye below the slab sees the face at the minimum, above it the one at the maximum.
            let below = rel_lo[k].simd_gt(zero);
            let visible = below | rel_hi[k].simd_lt(zero);
            if visible.to_bitmask() == 0 {
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
        total
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
        if self.estimate {
            return self.estimate4(&Aabb4::splat(b), false).to_array()[0];
        }
        let (m, inside) = self.front_faces4(&Aabb4::splat(b));
        if inside.to_bitmask() & 1 != 0 {
            m.to_array()[0]
        } else {
            self.hull_measure(b)
        }
    }

    /// Decided once per node: whether every box inside `node` is inside the pyramid (a box
    /// inside a convex region has all its sub-boxes inside), and whether every such box is far
    /// (a sub-box's half-diagonal is at most the node's, and its centre is at most the node's
    /// half-diagonal nearer than the node's centre).
    fn hint(&self, node: &Aabb) -> u32 {
        let b = Aabb4::splat(node);
        let (rel_lo, rel_hi) = self.relative(&b);
        let (c, h) = centre_half(&rel_lo, &rel_hi);
        if self.inside_pyramid4(&c, &h).to_bitmask() & 1 == 0 {
            return 0;
        }
        if self.estimate {
            return HINT_INSIDE;
        }
        let diag = (h[0] * h[0] + h[1] * h[1] + h[2] * h[2]).sqrt().to_array()[0];
        let nearest = self.reach(&c).to_array()[0] - diag;
        if nearest > 0.0 && diag * diag <= FAR_FIELD * nearest * nearest {
            HINT_INSIDE | HINT_FAR
        } else {
            HINT_INSIDE
        }
    }

    /// [`CostModel::measure4`] without the per-lane tests the node's hint settled. Empty lanes
    /// (sweep padding) still measure zero.
    #[inline]
    fn measure4_hinted(&self, b: &Aabb4, hint: u32) -> f32x4 {
        if self.estimate {
            return self.estimate4(b, hint & HINT_INSIDE != 0);
        }
        if hint & HINT_INSIDE == 0 {
            return self.measure4(b);
        }
        let (rel_lo, rel_hi) = self.relative(b);
        let empty = b.empty();
        let m = if hint & HINT_FAR != 0 {
            self.far4(&rel_lo, &rel_hi)
        } else {
            let (c, h) = centre_half(&rel_lo, &rel_hi);
            self.by_distance4(&rel_lo, &rel_hi, self.far_lanes(&c, &h), empty)
        };
        empty.select(f32x4::ZERO, m)
    }

    /// Four boxes at once: the hull-free path for every lane inside the pyramid, zero for empty
    /// lanes (sweep padding), the hull for the rest (boxes at the top of a build, straddling the
    /// window or the near plane).
    #[inline]
    fn measure4(&self, b: &Aabb4) -> f32x4 {
        if self.estimate {
            return self.estimate4(b, false);
        }
        let (m, inside) = self.front_faces4(b);
        let mask = inside.to_bitmask();
        if mask == 0b1111 {
            return m;
        }
        let empty = b.empty();
        let rest = !(mask | empty.to_bitmask()) & 0b1111;
        let mut out = empty.select(f32x4::ZERO, m).to_array();
        for (j, o) in out.iter_mut().enumerate() {
            if rest & (1 << j) != 0 {
                *o = self.hull_measure(&b.lane(j));
            }
        }
        f32x4::from(out)
    }
}

/// The measure of a window of half-angle tangents `tx` and `ty` (see
/// [`PahPerspective::window_measure`]).
fn window_measure(measure: PerspectiveMeasure, tx: f32, ty: f32) -> f32 {
    match measure {
        PerspectiveMeasure::SolidAngle => {
            4.0 * libm::atanf(tx * ty / libm::sqrtf(1.0 + tx * tx + ty * ty))
        }
        PerspectiveMeasure::ImagePlane => 4.0 * tx * ty,
    }
}

/// The centres and half extents of boxes given by their bounds.
#[inline(always)]
fn centre_half(lo: &[f32x4; 3], hi: &[f32x4; 3]) -> ([f32x4; 3], [f32x4; 3]) {
    let half = f32x4::splat(0.5);
    (
        core::array::from_fn(|k| (lo[k] + hi[k]) * half),
        core::array::from_fn(|k| (hi[k] - lo[k]) * half),
    )
}

/// [`PahPerspective::hint`]: every box inside the node is inside the pyramid.
const HINT_INSIDE: u32 = 1;
/// [`PahPerspective::hint`]: every box inside the node is far from the eye (`far_field4`).
const HINT_FAR: u32 = 2;

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
        // Nearly flat windows: a box holding the eye measures one window, not many.
        for (fx, fy, near) in [
            (179.99, 1.0, 0.0),
            (1.0, 179.999, 0.0),
            (179.9, 179.9, 0.01),
        ] {
            let a = PointArea::new(Vec3::ZERO, Vec3::X, fx, fy, near, 100.0).unwrap();
            let sa = PahPerspective::for_area(&a, PerspectiveMeasure::SolidAngle);
            let w = sa.window_measure();
            // Holding the eye and the near plane's window (11.5 units wide at 179.9 degrees).
            let root = Aabb::new(Vec3::new(-1.0, -20.0, -20.0), Vec3::new(3.0, 20.0, 20.0));
            let m = sa.measure(&root);
            assert!((m - w).abs() <= 1e-5 * w, "{fx} x {fy}: {m} against {w}");
            let wall = Aabb::new(Vec3::new(3.0, -1.0, -1.0), Vec3::new(3.0, 1.0, 1.0));
            let part = sa.measure(&wall);
            assert!(part > 0.0 && part < w, "{fx} x {fy}: {part} against {w}");
        }
        // Nearly closed windows (1e-8 degrees): a box across the axis covers the whole window,
        // one beside it none.
        for fov in [1e-6, 1e-8, 1e-13] {
            let eye = Vec3::new(3.0, 1.0, -30.0);
            let a = PointArea::new(eye, Vec3::new(0.01, 0.02, 1.0), fov, fov, 0.0, 60.0).unwrap();
            for m in [
                PerspectiveMeasure::SolidAngle,
                PerspectiveMeasure::ImagePlane,
            ] {
                let pah = PahPerspective::for_area(&a, m);
                let w = pah.window_measure();
                let across = Aabb::new(Vec3::new(-17.0, -9.0, -3.0), Vec3::new(17.0, 9.0, 3.0));
                let m_across = pah.measure(&across);
                assert!(
                    (m_across - w).abs() <= 1e-6 * w,
                    "{fov} {m:?}: {m_across} against {w}"
                );
                let beside = Aabb::new(Vec3::new(5.0, -9.0, -3.0), Vec3::new(17.0, 9.0, 3.0));
                assert_eq!(pah.measure(&beside), 0.0, "{fov} {m:?}");
            }
        }
    }

    /// Rays stop at the far plane, so a box reaching past it measures as its part before it, and
    /// a box wholly past it as nothing (otherwise the estimate overstates the traced cost).
    /// The centre estimate is within 1% of the exact measure for small boxes inside the window,
    /// zero for boxes outside it, one window for a box around the eye, and the same through the
    /// hinted 4-wide path the sweeps use.
    #[test]
    fn the_centre_estimate_tracks_the_exact_measure() {
        let a = PointArea::new(Vec3::ZERO, Vec3::Z, 80.0, 60.0, 0.1, 50.0).unwrap();
        for measure in [
            PerspectiveMeasure::SolidAngle,
            PerspectiveMeasure::ImagePlane,
        ] {
            let exact = PahPerspective::for_area(&a, measure);
            let estimate = exact.estimated();
            let mut rng = crate::random::Pcg32::new(21);
            for _ in 0..200 {
                let c = Vec3::new(
                    rng.range(-2.0, 2.0),
                    rng.range(-1.5, 1.5),
                    rng.range(5.0, 20.0),
                );
                let h = Vec3::new(
                    rng.range(0.01, 0.2),
                    rng.range(0.01, 0.2),
                    rng.range(0.01, 0.2),
                );
                let b = Aabb::new(c - h, c + h);
                let (e, x) = (estimate.measure(&b), exact.measure(&b));
                assert!(
                    (e - x).abs() <= 0.01 * x,
                    "{measure:?} {b:?}: {e} against {x}"
                );
                let hinted = estimate.measure4_hinted(&Aabb4::splat(&b), estimate.hint(&b));
                assert_eq!(hinted.to_array()[0], e);
            }
            let behind = Aabb::new(Vec3::new(-1.0, -1.0, -3.0), Vec3::new(1.0, 1.0, -2.0));
            let aside = Aabb::new(Vec3::new(30.0, -1.0, 5.0), Vec3::new(31.0, 1.0, 6.0));
            assert_eq!(estimate.measure(&behind), 0.0);
            assert_eq!(estimate.measure(&aside), 0.0);
            let around = Aabb::new(Vec3::splat(-1.0), Vec3::splat(1.0));
            assert_eq!(estimate.measure(&around), estimate.window_measure());
        }
    }

    #[test]
    fn boxes_are_cut_at_the_far_plane() {
        use crate::influence::InfluenceArea;
        use crate::test_scenes::hit_fraction;
        let a = PointArea::new(
            Vec3::ZERO,
            Vec3::new(0.1, -0.05, 1.0),
            60.0,
            50.0,
            0.5,
            10.0,
        )
        .unwrap();
        for m in [
            PerspectiveMeasure::SolidAngle,
            PerspectiveMeasure::ImagePlane,
        ] {
            let pah = PahPerspective::for_area(&a, m);
            let f = a.frustum().frame.forward;
            let influence = InfluenceArea::from(a);
            // Boxes about the axis whose far faces lie past the far plane.
            for (centre, half, depth) in [(8.0, 1.0, 3.0), (9.5, 2.5, 1.0), (6.0, 0.5, 8.0)] {
                let lo = f * centre - Vec3::splat(half);
                let whole = Aabb::new(lo, lo + Vec3::new(2.0 * half, 2.0 * half, depth));
                let m_whole = pah.measure(&whole);
                // The same box cut by the far plane, sampled: the fraction of window directions
                // whose ray meets the box before depth 10, times the window's measure.
                let mut rays = RaySampler::new(influence, 9).distribution(match m {
                    PerspectiveMeasure::SolidAngle => PointDistribution::SolidAngle,
                    PerspectiveMeasure::ImagePlane => PointDistribution::ImagePlane,
                });
                let fraction = hit_fraction(&mut rays, &influence, &whole, 200_000);
                let sampled = pah.window_measure() * fraction;
                assert!(
                    (m_whole - sampled).abs() <= 0.02 * sampled,
                    "{m:?} {whole:?}: {m_whole} against {sampled} sampled"
                );
            }
            let past = Aabb::new(f * 12.0 - Vec3::ONE, f * 12.0 + Vec3::ONE);
            assert_eq!(pah.measure(&past), 0.0, "{m:?}");
        }
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
                    // Far boxes take the far-field rule: within about 1.2e-4 (`far_field4`).
                    assert!(
                        (fast - hull).abs() <= 2.5e-4 * hull.max(1e-3),
                        "{m:?} {b:?}: {fast} vs {hull}"
                    );
                    checked += 1;
                }
            }
        }
        assert!(checked > 2000, "the fast path ran {checked} times");
    }

    #[test]
    fn the_frustum_depth_and_a_zero_near_do_not_cut_boxes_beyond_near() {
        // A frustum's far distance bounds where its rays go, not what its measure may ignore: a
        // cut floored relative to `far` would zero every box of a scene 0.3 from the eye.
        let eye = Vec3::new(-0.017, 0.11, 0.3);
        let area = |near: f32, far: f32| PointArea::new(eye, -Vec3::Z, 60.0, 60.0, near, far);
        let mut rng = crate::random::Pcg32::new(9);
        for m in [
            PerspectiveMeasure::SolidAngle,
            PerspectiveMeasure::ImagePlane,
        ] {
            let reference = PahPerspective::for_area(&area(0.01, 1.0).unwrap(), m);
            for far in [1e5, 1e10, 1e17] {
                let deep = PahPerspective::for_area(&area(0.01, far).unwrap(), m);
                let zero = PahPerspective::for_area(&area(0.0, far).unwrap(), m);
                for _ in 0..500 {
                    // Boxes around the scene, some straddling the window or holding the eye.
                    let lo = eye
                        + Vec3::new(
                            rng.range(-0.2, 0.1),
                            rng.range(-0.2, 0.1),
                            rng.range(-0.4, 0.05),
                        );
                    let hi = lo + Vec3::splat(rng.range(0.001, 0.3));
                    let b = Aabb::new(lo, hi);
                    let r = reference.measure(&b);
                    assert_eq!(deep.measure(&b), r, "far {far}, {b:?}");
                    let z = zero.measure(&b);
                    assert!(z.is_finite() && z >= 0.0, "{z} for {b:?}");
                    // From the eye instead of 0.01 in front of it: the same where the box lies
                    // wholly beyond 0.01, never less.
                    if b.max.z < eye.z - 0.01 {
                        assert!((z - r).abs() <= 1e-5 * r.max(1e-3), "{z} vs {r}: {b:?}");
                    }
                    assert!(z >= r * (1.0 - 1e-5), "{z} vs {r}: {b:?}");
                }
            }
        }
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
                // Boxes inside the window, straddling it or the near plane, behind the eye,
                // small and far (the far-field rule's), and empty, mixed in one group of four:
                // each lane's rule is its own, so the groups agree with one box at a time.
                let lanes: [Aabb; 4] = core::array::from_fn(|_| {
                    if rng.range(0.0, 1.0) < 0.1 {
                        return Aabb::EMPTY;
                    }
                    if rng.range(0.0, 1.0) < 0.3 {
                        let lo = Vec3::new(rng.range(-2.0, 2.0), rng.range(-2.0, 2.0), 30.0);
                        return Aabb::new(lo, lo + Vec3::splat(rng.range(0.01, 0.3)));
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

    /// The image-plane area of the box `lo..hi` (eye-relative, in front of the eye) in f64: each
    /// face turned towards the eye projected through `frame` and measured by the shoelace formula.
    fn image_plane_f64(lo: [f64; 3], hi: [f64; 3], frame: &Frame) -> f64 {
        let axis = |v: Vec3| [v.x, v.y, v.z].map(f64::from);
        let (r, u, f) = (axis(frame.right), axis(frame.up), axis(frame.forward));
        let dot = |p: [f64; 3], q: [f64; 3]| p[0] * q[0] + p[1] * q[1] + p[2] * q[2];
        crate::geometry::front_faces_f64(lo, hi)
            .map(|face| {
                let p = face.map(|c| (dot(c, r) / dot(c, f), dot(c, u) / dot(c, f)));
                let twice: f64 = (0..4)
                    .map(|i| p[i].0 * p[(i + 1) % 4].1 - p[i].1 * p[(i + 1) % 4].0)
                    .sum();
                0.5 * twice.abs()
            })
            .sum()
    }

    #[test]
    fn far_boxes_at_the_threshold_match_the_f64_measure() {
        // Boxes whose half-diagonal is 90-100% of the far-field limit, inside an oblique, wide
        // frustum: flat, long and cubic, so some faces are seen edge-on. Both measures' far rule
        // (solid angle, and the image plane's own `1 / z^3` weight) against the exact measure
        // in f64 (the f32 paths lose more than the rule does on flat boxes).
        let area = PointArea::new(
            Vec3::new(0.3, -0.2, 0.1),
            Vec3::new(0.3, 0.2, 1.0),
            110.0,
            90.0,
            0.1,
            100.0,
        )
        .unwrap();
        let mut rng = crate::random::Pcg32::new(21);
        for m in [
            PerspectiveMeasure::SolidAngle,
            PerspectiveMeasure::ImagePlane,
        ] {
            let pah = PahPerspective::for_area(&area, m);
            let (mut worst, mut checked) = (0.0f64, 0);
            for _ in 0..4000 {
                let c = Vec3::new(
                    rng.range(-8.0, 8.0),
                    rng.range(-8.0, 8.0),
                    rng.range(1.0, 12.0),
                );
                let power = if rng.range(0.0, 1.0) < 0.5 { 1.0 } else { 4.0 };
                let shape = Vec3::new(
                    libm::powf(rng.range(0.0, 1.0), power),
                    libm::powf(rng.range(0.0, 1.0), power),
                    libm::powf(rng.range(0.0, 1.0), power),
                )
                .normalize_or_zero();
                let rel = c - pah.eye;
                let reach = match m {
                    PerspectiveMeasure::SolidAngle => rel.length(),
                    PerspectiveMeasure::ImagePlane => rel.dot(pah.frame.forward),
                };
                let h = shape * (reach * FAR_FIELD.sqrt() * rng.range(0.9, 0.999));
                let b = Aabb::new(c - h, c + h);
                let (fast, inside) = pah.front_faces4(&Aabb4::splat(&b));
                if inside.to_bitmask() != 0b1111 || h.length() == 0.0 {
                    continue;
                }
                let lo = (b.min - pah.eye).to_array().map(f64::from);
                let hi = (b.max - pah.eye).to_array().map(f64::from);
                let exact = match m {
                    PerspectiveMeasure::SolidAngle => crate::geometry::box_solid_angle_f64(lo, hi),
                    PerspectiveMeasure::ImagePlane => image_plane_f64(lo, hi, &pah.frame),
                };
                let fast = f64::from(fast.to_array()[0]);
                worst = worst.max((fast - exact).abs() / exact);
                checked += 1;
            }
            assert!(checked > 1000, "{m:?}: {checked} far boxes");
            // About 1.2e-4 from the rule, a little more from f32 rounding; the plain midpoint rule
            // is off by up to 1.3e-2 at this size.
            assert!(worst <= 1.5e-4, "{m:?}: worst relative error {worst}");
            assert!(worst > 1e-5, "{m:?}: worst relative error {worst}");
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
