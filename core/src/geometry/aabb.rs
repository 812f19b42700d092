//! Axis-aligned bounding boxes and the robust ray/box slab test.

use glam::Vec3;

use super::Ray;

/// `t_far` widened by the slab padding: the bound a traversal compares entry distances against.
#[inline]
pub(crate) fn pad_far(t_far: f32) -> f32 {
    t_far + t_far.abs() * SLAB_PAD
}

/// Relative padding of the slab test's interval: `2 * gamma(3)` in the notation of Ize, "Robust BVH
/// Ray Traversal" (JCGT 2013). It keeps a box test conservative under the rounding of the slab
/// products, so a triangle lying exactly on a box face (an axis-aligned wall) is never culled.
const SLAB_PAD: f32 = 2.0 * (3.0 * f32::EPSILON * 0.5) / (1.0 - 3.0 * f32::EPSILON * 0.5);

/// An axis-aligned bounding box. An *empty* box has `min > max` on some axis; [`Aabb::EMPTY`] is
/// the identity of [`Aabb::union`].
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Aabb {
    /// Lower corner.
    pub min: Vec3,
    /// Upper corner.
    pub max: Vec3,
}

impl Default for Aabb {
    fn default() -> Self {
        Self::EMPTY
    }
}

impl Aabb {
    /// The empty box: `min = +inf`, `max = -inf`, so growing it by anything gives that thing.
    pub const EMPTY: Aabb = Aabb {
        min: Vec3::splat(f32::INFINITY),
        max: Vec3::splat(f32::NEG_INFINITY),
    };

    /// A box from its corners (not checked: use [`Aabb::is_valid`]).
    #[inline]
    pub const fn new(min: Vec3, max: Vec3) -> Self {
        Self { min, max }
    }

    /// The smallest box holding every point of `points`.
    pub fn from_points(points: &[Vec3]) -> Self {
        points.iter().fold(Self::EMPTY, |b, &p| b.grown(p))
    }

    /// This box grown to hold `p`.
    #[inline]
    pub fn grown(self, p: Vec3) -> Self {
        Self {
            min: self.min.min(p),
            max: self.max.max(p),
        }
    }

    /// The smallest box holding both boxes.
    #[inline]
    pub fn union(self, other: Aabb) -> Self {
        Self {
            min: self.min.min(other.min),
            max: self.max.max(other.max),
        }
    }

    /// The overlap of both boxes (empty if they are disjoint).
    #[inline]
    pub fn intersection(self, other: Aabb) -> Self {
        Self {
            min: self.min.max(other.min),
            max: self.max.min(other.max),
        }
    }

    /// True when `min > max` on some axis (or a coordinate is NaN).
    #[inline]
    pub fn is_empty(&self) -> bool {
        !(self.min.x <= self.max.x && self.min.y <= self.max.y && self.min.z <= self.max.z)
    }

    /// True when the box is non-empty and every coordinate is finite.
    #[inline]
    pub fn is_valid(&self) -> bool {
        !self.is_empty() && self.min.is_finite() && self.max.is_finite()
    }

    /// `max - min`, clamped at zero so an empty box has no extent.
    #[inline]
    pub fn extent(&self) -> Vec3 {
        (self.max - self.min).max(Vec3::ZERO)
    }

    /// The box centre.
    #[inline]
    pub fn center(&self) -> Vec3 {
        (self.min + self.max) * 0.5
    }

    /// Half the surface area: `xy + yz + zx`. SAH only ever uses ratios of areas, so the factor 2
    /// is dropped; zero for an empty box.
    #[inline]
    pub fn half_area(&self) -> f32 {
        let e = self.extent();
        e.x * e.y + e.y * e.z + e.z * e.x
    }

    /// The full surface area.
    #[inline]
    pub fn surface_area(&self) -> f32 {
        2.0 * self.half_area()
    }

    /// The axis (0 = x, 1 = y, 2 = z) with the largest extent; ties go to the lower axis.
    #[inline]
    pub fn largest_axis(&self) -> usize {
        let e = self.extent();
        if e.x >= e.y && e.x >= e.z {
            0
        } else if e.y >= e.z {
            1
        } else {
            2
        }
    }

    /// This box grown by a relative `2^-19` of its largest coordinate magnitude on every side.
    ///
    /// BVH nodes store these: a ray/triangle test rounds its hit point by a few ulps of the
    /// coordinates involved, which can put a hit a hair outside the triangle's exact box (a ray
    /// starting on a vertex, or grazing a face). The padding, far above those ulps and far below
    /// any geometric feature, makes every box test admit every hit the triangle test reports, so
    /// traversals agree with the brute-force oracle. A parent's padding is never smaller than its
    /// children's, so nesting is kept.
    #[inline]
    pub fn padded(self) -> Self {
        if self.is_empty() {
            return self;
        }
        let m = self.min.abs().max(self.max.abs()).max_element();
        let pad = Vec3::splat(m * (1.0 / 524_288.0) + f32::MIN_POSITIVE);
        Self {
            min: self.min - pad,
            max: self.max + pad,
        }
    }

    /// True when `other` lies inside this box (boundaries included).
    #[inline]
    pub fn contains_box(&self, other: &Aabb) -> bool {
        self.min.cmple(other.min).all() && self.max.cmpge(other.max).all()
    }

    /// True when `p` lies inside this box (boundaries included).
    #[inline]
    pub fn contains_point(&self, p: Vec3) -> bool {
        self.min.cmple(p).all() && self.max.cmpge(p).all()
    }

    /// The entry distance of the ray segment `[ray.t_min, t_max]` into this box, or `None` when it
    /// misses. Boundaries count as inside, also for rays parallel to a face (zero direction
    /// components); the interval is padded after Ize so rounding never culls a box the ray touches.
    #[inline]
    pub fn intersect(&self, ray: &Ray, t_max: f32) -> Option<f32> {
        let (t_near, t_far) = self.slab_interval(ray, t_max);
        (t_near <= t_far).then_some(t_near)
    }

    /// The padded slab interval `(t_near, t_far)`; the ray misses when `t_near > t_far`.
    ///
    /// The near plane of each axis is chosen from the sign of the inverse direction, so no per-axis
    /// min/max is needed. A zero direction component gives an infinite inverse; an origin exactly on
    /// that slab's boundary then gives `0 * inf = NaN` for one plane, and the reduction, which keeps
    /// its accumulator when a value is NaN, drops it: the right answer (the ray runs along the
    /// face).
    #[inline]
    pub fn slab_interval(&self, ray: &Ray, t_max: f32) -> (f32, f32) {
        let (near, far) = ray.near_far(self);
        let tn = (near - ray.origin) * ray.inv_dir;
        let tf = (far - ray.origin) * ray.inv_dir;
        let t_near = max_keep(max_keep(max_keep(ray.t_min, tn.x), tn.y), tn.z);
        let t_far = min_keep(min_keep(min_keep(t_max, tf.x), tf.y), tf.z);
        (t_near - t_near.abs() * SLAB_PAD, pad_far(t_far))
    }
}

/// `max(acc, t)` that keeps `acc` when `t` is NaN: one `maxss`, where `f32::max` needs extra
/// instructions to be NaN-symmetric. The accumulator is never NaN.
#[inline(always)]
fn max_keep(acc: f32, t: f32) -> f32 {
    if t > acc {
        t
    } else {
        acc
    }
}

/// `min(acc, t)` that keeps `acc` when `t` is NaN.
#[inline(always)]
fn min_keep(acc: f32, t: f32) -> f32 {
    if t < acc {
        t
    } else {
        acc
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn unit() -> Aabb {
        Aabb::new(Vec3::ZERO, Vec3::ONE)
    }

    #[test]
    fn empty_is_identity_of_union() {
        let b = unit();
        assert_eq!(Aabb::EMPTY.union(b), b);
        assert!(Aabb::EMPTY.is_empty());
        assert_eq!(Aabb::EMPTY.half_area(), 0.0);
    }

    #[test]
    fn half_area_of_box() {
        let b = Aabb::new(Vec3::ZERO, Vec3::new(1.0, 2.0, 3.0));
        assert_eq!(b.half_area(), 2.0 + 6.0 + 3.0);
        assert_eq!(b.largest_axis(), 2);
    }

    #[test]
    fn slab_hits_and_misses() {
        let r = Ray::new(Vec3::new(0.5, 0.5, -1.0), Vec3::Z).unwrap();
        let t = unit().intersect(&r, f32::INFINITY).unwrap();
        assert!((t - 1.0).abs() < 1e-6);
        let r = Ray::new(Vec3::new(1.5, 0.5, -1.0), Vec3::Z).unwrap();
        assert!(unit().intersect(&r, f32::INFINITY).is_none());
        // The segment ends before the box.
        let r = Ray::new(Vec3::new(0.5, 0.5, -1.0), Vec3::Z).unwrap();
        assert!(unit().intersect(&r, 0.5).is_none());
    }

    #[test]
    fn axis_parallel_ray_on_every_face_hits() {
        // Rays running exactly along each face of the box, with +0 and -0 direction components.
        for &(o, d) in &[
            (Vec3::new(0.0, 0.5, -1.0), Vec3::new(0.0, 0.0, 1.0)),
            (Vec3::new(1.0, 0.5, -1.0), Vec3::new(0.0, 0.0, 1.0)),
            (Vec3::new(1.0, 0.5, -1.0), Vec3::new(-0.0, -0.0, 1.0)),
            (Vec3::new(0.0, 0.0, -1.0), Vec3::new(-0.0, 0.0, 1.0)),
            (Vec3::new(0.5, 1.0, 2.0), Vec3::new(0.0, -0.0, -1.0)),
        ] {
            let r = Ray::new(o, d).unwrap();
            assert!(unit().intersect(&r, f32::INFINITY).is_some(), "{o:?} {d:?}");
        }
        // Just outside a face it misses.
        let r = Ray::new(Vec3::new(1.0001, 0.5, -1.0), Vec3::Z).unwrap();
        assert!(unit().intersect(&r, f32::INFINITY).is_none());
    }

    #[test]
    fn flat_box_is_hit() {
        let flat = Aabb::new(Vec3::new(0.0, 0.0, 2.0), Vec3::new(1.0, 1.0, 2.0));
        let r = Ray::new(Vec3::new(0.3, 0.7, 0.0), Vec3::Z).unwrap();
        assert!(flat.intersect(&r, f32::INFINITY).is_some());
    }

    #[test]
    fn origin_inside_enters_at_t_min() {
        let r = Ray::new(Vec3::splat(0.5), Vec3::X).unwrap();
        assert_eq!(unit().intersect(&r, f32::INFINITY), Some(0.0));
    }
}
