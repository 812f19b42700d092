//! The projected area heuristic for parallel rays: orthographic projected area, with window
//! culling to the light rectangle.

use glam::{Vec2, Vec3};
use wide::f32x4;

use crate::geometry::{orthographic_silhouette, orthographic_slab_silhouette, Aabb, Frame};
use crate::influence::PlaneArea;
use crate::simd::Aabb4;

use super::CostModel;

/// The light rectangle in its own `(right, up)` coordinates about its centre `origin`: boxes are
/// taken relative to the centre before they are projected, so a small window far from the world
/// origin keeps its precision (projected world coordinates round at `|centre| * 2^-24`). The
/// rays start on it and stop `depth` along `frame.forward`: only a box's part in that slab counts.
#[derive(Clone, Copy, Debug, PartialEq)]
struct Window {
    origin: Vec3,
    frame: Frame,
    depth: f32,
    lo: Vec2,
    hi: Vec2,
}

/// PAH for parallel rays of direction `d`: a box of extents `e` projects orthographically to the
/// area `|d.x| e.y e.z + |d.y| e.x e.z + |d.z| e.x e.y` (one visible face per axis, times its
/// `|cos|`). Linear in the face areas, so it bins exactly like SAH and costs the same: three
/// multiplies and two adds. Averaged over all directions it is `SA / 4` (Cauchy), so SAH is the
/// isotropic case. For a cone of directions the weights are `E|d_k|` over the cone.
///
/// With a window (from a [`PlaneArea`]) only the part of the projection inside the light rectangle
/// counts, since rays start only there, and only the part of the box between the light's plane
/// and its depth, where the rays run: boxes inside both take the closed form, boxes outside
/// either measure zero, and only boxes straddling a border pay for an exact hull clip (cut to
/// the slab in 3D first when they straddle one of its planes).
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct PahOrtho {
    weights: Vec3,
    window: Option<Window>,
}

impl PahOrtho {
    /// Parallel rays along `dir` (any length), no window. `None` for a zero or non-finite `dir`.
    pub fn new(dir: Vec3) -> Option<Self> {
        let d = dir.try_normalize()?;
        Some(Self {
            weights: d.abs(),
            window: None,
        })
    }

    /// Rays from a distribution whose mean absolute direction components are `weights`
    /// (`E|d_k|`), no window. `None` unless the weights are finite, non-negative and not all zero.
    pub fn from_weights(weights: Vec3) -> Option<Self> {
        (weights.is_finite() && weights.min_element() >= 0.0 && weights.max_element() > 0.0)
            .then_some(Self {
                weights,
                window: None,
            })
    }

    /// The rays of a plane area: its normal, culled to its light rectangle.
    pub fn for_area(area: &PlaneArea) -> Self {
        let h = Vec2::new(area.half_width, area.half_height);
        Self {
            weights: area.frame.forward.abs(),
            window: Some(Window {
                origin: area.center,
                frame: area.frame,
                depth: area.depth,
                lo: -h,
                hi: h,
            }),
        }
    }

    /// The same model without window culling.
    pub fn unculled(self) -> Self {
        Self {
            window: None,
            ..self
        }
    }

    /// The measure of the whole window (its area), or `None` without a window.
    pub fn window_measure(&self) -> Option<f32> {
        self.window.map(|w| {
            let e = w.hi - w.lo;
            e.x * e.y
        })
    }

    /// The closed-form projected area, ignoring the window.
    #[inline]
    pub fn projected_area(&self, b: &Aabb) -> f32 {
        let e = b.extent();
        let w = self.weights;
        w.x * e.y * e.z + w.y * e.x * e.z + w.z * e.x * e.y
    }

    /// The closed-form projected areas of four boxes, ignoring the window (zero for empty lanes:
    /// their extents clamp at zero).
    #[inline(always)]
    fn projected_area4(&self, b: &Aabb4) -> f32x4 {
        let [ex, ey, ez] = b.extent();
        let w = self.weights;
        f32x4::splat(w.x) * ey * ez + f32x4::splat(w.y) * ex * ez + f32x4::splat(w.z) * ex * ey
    }

    /// [`CostModel::measure4`] as a call, for the sweeps of nodes that straddle the window.
    #[inline(never)]
    fn measure4_out_of_line(&self, b: &Aabb4) -> f32x4 {
        self.measure4(b)
    }

    /// The lower and upper corners, in window coordinates `(right, up, forward)`, of `b`'s
    /// span: along each axis of the light's frame it spans the centre's coordinate +- the sum
    /// of `|axis_k| e_k / 2`.
    #[inline]
    fn window_span(w: &Window, b: &Aabb) -> (Vec3, Vec3) {
        let (lo, hi) = (b.min - w.origin, b.max - w.origin);
        let (c, h) = ((lo + hi) * 0.5, b.extent() * 0.5);
        let f = &w.frame;
        let centre = Vec3::new(c.dot(f.right), c.dot(f.up), c.dot(f.forward));
        let half = Vec3::new(
            h.dot(f.right.abs()),
            h.dot(f.up.abs()),
            h.dot(f.forward.abs()),
        );
        (centre - half, centre + half)
    }

    /// Whether a span from [`Self::window_span`] lies inside the window and the slab, and
    /// whether it lies wholly outside either.
    #[inline]
    fn inside_outside(w: &Window, (lo, hi): (Vec3, Vec3)) -> (bool, bool) {
        let (wlo, whi) = (w.lo.extend(0.0), w.hi.extend(w.depth));
        (
            lo.cmpge(wlo).all() && hi.cmple(whi).all(),
            hi.cmple(wlo).any() || lo.cmpge(whi).any(),
        )
    }

    /// The exact projected area of `b` inside the window `w`: hull of the eight projected
    /// corners (of the box cut to the slab, when it reaches past either of its planes), clipped
    /// to the rectangle.
    fn clipped_area(w: &Window, b: &Aabb) -> f32 {
        let relative = Aabb::new(b.min - w.origin, b.max - w.origin);
        let (lo, hi) = Self::window_span(w, b);
        let hull = if lo.z < 0.0 || hi.z > w.depth {
            orthographic_slab_silhouette(&relative, &w.frame, w.depth)
        } else {
            orthographic_silhouette(&relative, w.frame.right, w.frame.up)
        };
        hull.clip_to_rect(w.lo, w.hi).area()
    }
}

impl CostModel for PahOrtho {
    #[inline]
    fn measure(&self, b: &Aabb) -> f32 {
        if b.is_empty() {
            return 0.0;
        }
        let full = self.projected_area(b);
        let Some(w) = &self.window else {
            return full;
        };
        match Self::inside_outside(w, Self::window_span(w, b)) {
            (true, _) => full,
            (_, true) => 0.0,
            _ => Self::clipped_area(w, b),
        }
    }

    /// Four boxes in one closed-form evaluation; with a window, the lanes whose projection is not
    /// entirely inside it are measured one by one. Always inlined: the sweep calls it per group
    /// of four boundaries, and a call would pass the 96-byte box group through memory.
    #[inline(always)]
    fn measure4(&self, b: &Aabb4) -> f32x4 {
        let full = self.projected_area4(b);
        let Some(win) = &self.window else {
            return full;
        };
        let [ex, ey, ez] = b.extent();
        let half = f32x4::splat(0.5);
        let o = [win.origin.x, win.origin.y, win.origin.z].map(f32x4::splat);
        let c: [f32x4; 3] =
            core::array::from_fn(|k| ((b.min[k] - o[k]) + (b.max[k] - o[k])) * half);
        let h = [ex * half, ey * half, ez * half];
        let dot = |v: &[f32x4; 3], a: Vec3| {
            v[0] * f32x4::splat(a.x) + v[1] * f32x4::splat(a.y) + v[2] * f32x4::splat(a.z)
        };
        let f = &win.frame;
        let (cx, hx) = (dot(&c, f.right), dot(&h, f.right.abs()));
        let (cy, hy) = (dot(&c, f.up), dot(&h, f.up.abs()));
        let (cz, hz) = (dot(&c, f.forward), dot(&h, f.forward.abs()));
        let (lo_x, lo_y) = (f32x4::splat(win.lo.x), f32x4::splat(win.lo.y));
        let (hi_x, hi_y) = (f32x4::splat(win.hi.x), f32x4::splat(win.hi.y));
        let depth = f32x4::splat(win.depth);
        let inside = (cx - hx).simd_ge(lo_x)
            & (cx + hx).simd_le(hi_x)
            & (cy - hy).simd_ge(lo_y)
            & (cy + hy).simd_le(hi_y)
            & (cz - hz).simd_ge(f32x4::ZERO)
            & (cz + hz).simd_le(depth);
        if inside.all() {
            return full;
        }
        // Empty lanes (sweep padding) and projections wholly outside the window measure zero
        // here too; only lanes straddling the window's border take the hull clip.
        let outside = (cx + hx).simd_le(lo_x)
            | (cx - hx).simd_ge(hi_x)
            | (cy + hy).simd_le(lo_y)
            | (cy - hy).simd_ge(hi_y)
            | (cz + hz).simd_le(f32x4::ZERO)
            | (cz - hz).simd_ge(depth)
            | b.empty();
        let zeroed = outside.select(f32x4::ZERO, full);
        let straddling = !(inside | outside).to_bitmask() & 0b1111;
        if straddling == 0 {
            return zeroed;
        }
        let mut out = zeroed.to_array();
        for (j, m) in out.iter_mut().enumerate() {
            if straddling & (1 << j) != 0 {
                *m = self.measure(&b.lane(j));
            }
        }
        f32x4::from(out)
    }

    /// 1 when the node's projection lies inside the window and the node inside the slab: then
    /// so does every box inside it.
    fn hint(&self, node: &Aabb) -> u32 {
        match &self.window {
            Some(w) if !node.is_empty() => {
                u32::from(Self::inside_outside(w, Self::window_span(w, node)).0)
            }
            _ => 0,
        }
    }

    /// With the whole node inside the window, the closed form alone (zero for empty lanes).
    /// Otherwise the window test, out of line: only the few nodes straddling the window's border
    /// take it, and inlined it would slow every sweep loop.
    #[inline(always)]
    fn measure4_hinted(&self, b: &Aabb4, hint: u32) -> f32x4 {
        if hint == 0 {
            return self.measure4_out_of_line(b);
        }
        self.projected_area4(b)
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::random::Pcg32;

    fn random_box(rng: &mut Pcg32) -> Aabb {
        let a = Vec3::new(
            rng.range(-5.0, 5.0),
            rng.range(-5.0, 5.0),
            rng.range(-5.0, 5.0),
        );
        let e = Vec3::new(
            rng.range(0.0, 3.0),
            rng.range(0.0, 3.0),
            rng.range(0.0, 3.0),
        );
        Aabb::new(a, a + e)
    }

    #[test]
    fn small_windows_far_from_the_origin_keep_their_precision() {
        // A window a few 1e-7 across, 0.3 from the origin, where projected world coordinates
        // round at 3e-8: a box covering it measures the whole window, one beside it nothing, one
        // over half of it half, whatever the window's size.
        for half in [1e-2f32, 1e-6, 3e-7, 1e-7, 1e-8, 1e-10, 1e-15] {
            let centre = Vec3::new(-0.017, 0.30, -0.002);
            let area = PlaneArea::new(centre, -Vec3::Y, half, half, 0.3).unwrap();
            let pah = PahOrtho::for_area(&area);
            let window = pah.window_measure().unwrap();
            assert_eq!(window, 4.0 * half * half);
            let covering = Aabb::new(Vec3::new(-0.1, 0.0, -0.1), Vec3::new(0.1, 0.2, 0.1));
            // Past the window's edge, or the next f32 past its centre when the window is
            // narrower than f32's spacing there.
            let beside = Aabb::new(
                Vec3::new((centre.x + 2.0 * half).max(centre.x.next_up()), 0.0, -0.1),
                Vec3::new(0.1, 0.2, 0.1),
            );
            // The window's right is world -x or +x: either way this box covers one half of it.
            let halfway = Aabb::new(Vec3::new(centre.x, 0.0, -0.1), Vec3::new(0.1, 0.2, 0.1));
            let four = Aabb4::from_boxes([covering, beside, halfway, covering]);
            for (j, m) in pah.measure4(&four).to_array().into_iter().enumerate() {
                assert_eq!(m, pah.measure(&four.lane(j)), "lane {j}");
            }
            assert!(
                (pah.measure(&covering) / window - 1.0).abs() < 1e-5,
                "{half}"
            );
            assert_eq!(pah.measure(&beside), 0.0, "{half}");
            let h = pah.measure(&halfway) / window;
            assert!((h - 0.5).abs() < 0.05, "{half}: {h}");
        }
    }

    #[test]
    fn closed_form_equals_hull_of_projected_corners() {
        let mut rng = Pcg32::new(5);
        for _ in 0..500 {
            let n = Vec3::new(
                rng.range(-1.0, 1.0),
                rng.range(-1.0, 1.0),
                rng.range(-1.0, 1.0),
            );
            // The light 100 units behind the boxes, its slab 1,000 deep: all of them inside it.
            let back = -n.normalize_or_zero() * 100.0;
            let Ok(area) = PlaneArea::new(back, n, 1e4, 1e4, 1e3) else {
                continue;
            };
            let pah = PahOrtho::for_area(&area);
            let b = random_box(&mut rng);
            let w = pah.window.unwrap();
            let hull = PahOrtho::clipped_area(&w, &b);
            let closed = pah.projected_area(&b);
            assert!(
                (hull - closed).abs() <= 1e-4 * closed.max(1.0),
                "{hull} vs {closed}"
            );
        }
    }

    /// Rays start on the light's plane and stop at its depth: a box reaching across either plane
    /// measures as its part between them, as sampled rays find it; a box behind the light or past
    /// its depth, nothing.
    #[test]
    fn boxes_are_cut_to_the_slab_the_rays_cross() {
        use crate::influence::{InfluenceArea, RaySampler};
        use crate::test_scenes::hit_fraction;
        let area = PlaneArea::new(
            Vec3::new(-1.0, 2.0, 0.5),
            Vec3::new(1.0, -0.7, 0.4),
            6.0,
            5.0,
            4.0,
        )
        .unwrap();
        let pah = PahOrtho::for_area(&area);
        let f = area.frame.forward;
        let boxes = [
            // Across the light's plane, across the far end, across both.
            Aabb::new(
                area.center - Vec3::splat(1.5),
                area.center + Vec3::splat(1.0),
            ),
            Aabb::new(
                area.center + f * 4.0 - Vec3::ONE,
                area.center + f * 4.0 + Vec3::ONE,
            ),
            Aabb::new(
                area.center - Vec3::splat(3.0),
                area.center + f * 4.0 + Vec3::ONE,
            ),
        ];
        let influence = InfluenceArea::from(area);
        for b in boxes {
            let mut rays = RaySampler::new(influence, 4);
            let fraction = hit_fraction(&mut rays, &influence, &b, 200_000);
            let sampled = pah.window_measure().unwrap() * fraction;
            let m = pah.measure(&b);
            assert!(
                (m - sampled).abs() <= 0.02 * sampled,
                "{b:?}: {m} against {sampled}"
            );
            let four = pah.measure4(&Aabb4::splat(&b)).to_array()[0];
            assert_eq!(four, m, "{b:?}");
        }
        let behind = Aabb::new(area.center - f * 3.0 - Vec3::ONE, area.center - f * 3.0);
        let past = Aabb::new(area.center + f * 5.0, area.center + f * 5.0 + Vec3::ONE);
        assert_eq!(pah.measure(&behind), 0.0);
        assert_eq!(pah.measure(&past), 0.0);
    }

    #[test]
    fn mean_over_directions_is_a_quarter_of_surface_area() {
        let b = Aabb::new(Vec3::ZERO, Vec3::new(1.0, 2.0, 3.0));
        let mut rng = Pcg32::new(9);
        let n = 100_000;
        let mut sum = 0.0f64;
        for _ in 0..n {
            // Uniform on the sphere: z uniform, azimuth uniform.
            let z = rng.range(-1.0, 1.0);
            let phi = rng.range(0.0, core::f32::consts::TAU);
            let r = libm::sqrtf(1.0 - z * z);
            let d = Vec3::new(r * libm::cosf(phi), r * libm::sinf(phi), z);
            sum += f64::from(PahOrtho::new(d).unwrap().measure(&b));
        }
        let mean = sum / f64::from(n);
        let expect = f64::from(b.surface_area()) / 4.0;
        assert!((mean - expect).abs() < 0.01 * expect, "{mean} vs {expect}");
    }

    #[test]
    fn window_culling() {
        let area = PlaneArea::new(Vec3::ZERO, Vec3::Z, 1.0, 1.0, 10.0).unwrap();
        let pah = PahOrtho::for_area(&area);
        let inside = Aabb::new(Vec3::new(-0.5, -0.5, 1.0), Vec3::new(0.5, 0.5, 2.0));
        assert!((pah.measure(&inside) - 1.0).abs() < 1e-6);
        let outside = Aabb::new(Vec3::new(2.0, 2.0, 1.0), Vec3::new(3.0, 3.0, 2.0));
        assert_eq!(pah.measure(&outside), 0.0);
        // Half of this box's 2 x 1 projection lies inside the 2 x 2 window.
        let straddle = Aabb::new(Vec3::new(0.0, -0.5, 1.0), Vec3::new(2.0, 0.5, 2.0));
        assert!((pah.measure(&straddle) - 1.0).abs() < 1e-5);
        assert_eq!(pah.window_measure(), Some(4.0));
    }
}
