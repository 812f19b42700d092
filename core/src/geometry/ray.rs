//! Rays as parametric segments `origin + t * dir`, `t` in `[t_min, t_max]`.

use core::fmt;

use glam::Vec3;

use super::Aabb;

/// Why a ray could not be made.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum RayError {
    /// The origin has a NaN or infinite coordinate.
    NonFiniteOrigin,
    /// The direction has a NaN or infinite component.
    NonFiniteDirection,
    /// The direction is the zero vector: the ray goes nowhere.
    ZeroDirection,
    /// `t_min` or `t_max` is NaN.
    NanSegment,
}

impl fmt::Display for RayError {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        f.write_str(match self {
            RayError::NonFiniteOrigin => "ray origin has a NaN or infinite coordinate",
            RayError::NonFiniteDirection => "ray direction has a NaN or infinite component",
            RayError::ZeroDirection => "ray direction is the zero vector",
            RayError::NanSegment => "ray t_min or t_max is NaN",
        })
    }
}

impl core::error::Error for RayError {}

/// A ray segment. `t` is measured in units of `dir`, which is not normalised: hit distances are
/// parametric, as a renderer that passes a light sample's unnormalised direction with `t_max = 1`
/// expects. A segment with `t_min > t_max` is empty and hits nothing.
///
/// Make rays with [`Ray::new`] or [`Ray::segment`]: the private fields ([`Ray::anchor`]) are
/// derived from the origin and the direction, so change a ray's `origin` or `dir` by making a new
/// one. A part of a ray, `Ray::segment(ray.origin, ray.dir, lo, hi)`, keeps its anchor and so its
/// answers.
///
/// ```
/// use rdbvh_core::{Ray, Triangle, Vec3};
///
/// let wall = Triangle::new(Vec3::new(-1.0, -1.0, 2.0), Vec3::new(1.0, -1.0, 2.0), Vec3::new(0.0, 1.0, 2.0));
/// // A shadow segment toward a light at z = 4, in units of the unnormalised offset.
/// let (p, light) = (Vec3::ZERO, Vec3::new(0.0, 0.0, 4.0));
/// let shadow = Ray::segment(p, light - p, 0.0, 1.0 - 1e-4)?;
/// assert_eq!(wall.intersect(&shadow, shadow.t_max).map(|h| h.t), Some(0.5));
/// // A zero or non-finite direction is an error, not a ray.
/// assert!(Ray::new(p, Vec3::ZERO).is_err());
/// # Ok::<(), Box<dyn std::error::Error>>(())
/// ```
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Ray {
    /// Where the ray starts (at `t = 0`).
    pub origin: Vec3,
    /// The direction, not necessarily of unit length.
    pub dir: Vec3,
    /// `1 / dir` per component, with zero components made `+0` first so that each infinite inverse
    /// is `+inf` and the slab test can pick its near planes from the signs alone.
    pub inv_dir: Vec3,
    /// Start of the segment.
    pub t_min: f32,
    /// End of the segment (may be `+inf`).
    pub t_max: f32,
    /// The ray's anchor: the point of its line nearest the world origin, when that lies ahead of
    /// the origin (`t > 0`) and nearer the world origin than the ray's origin, else the origin
    /// itself. See [`Ray::anchor`].
    pub(crate) anchor: Vec3,
    /// The ray parameter of [`Ray::anchor`] (0 when the anchor is the origin).
    pub(crate) anchor_t: f32,
    /// `dot(origin, dir) + (anchor_t |dir|^2 + |anchor| |dir|) / 2`: a triangle at `p` is
    /// measured from the anchor when `dot(p, dir)` exceeds it (see [`Ray::measures_from_anchor`];
    /// rounding matters only where the two points err about alike).
    pub(crate) anchor_split: f32,
    /// `|dir|^2` in f64, where no finite f32 direction's square overflows or underflows: the
    /// triangle tests' determinant check (`determinant_is_noise`) needs it for every hit. Kept
    /// here (the anchor computes it anyway) because, left to each test, LLVM hoisted it into the
    /// 4-wide traversal's set-up, where every ray computed it, hit or not.
    pub(crate) dir_len_sq: f64,
}

/// The anchor of the line `origin + t dir`: `(t_a, origin + t_a dir, split, |dir|^2)` with `t_a`
/// the parameter of the point nearest the world origin, or `(0, origin, ..)` when that point is
/// not ahead (`t_a <= 0`) or no nearer the world origin than the ray's origin; `split` is
/// [`Ray::anchor_split`], `|dir|^2` in f64 [`Ray::dir_len_sq`].
///
/// Computed in f64 and rounded once: `t_a` to f32 first, then the point at that very `t_a`, so the
/// anchor lies on the ray to the rounding of its own coordinates (in f32 `origin + t_a dir` would
/// be off the line by the rounding of the origin's coordinates, the error the anchor removes).
fn anchor_of(origin: Vec3, dir: Vec3) -> (f32, Vec3, f32, f64) {
    let o = origin.to_array().map(f64::from);
    let d = dir.to_array().map(f64::from);
    let dot = |a: [f64; 3], b: [f64; 3]| a[0] * b[0] + a[1] * b[1] + a[2] * b[2];
    // For a finite, non-zero `d`, `d . d` is positive and finite in f64 (as are all these
    // products of f32 values); the quotient can still exceed f32's range along a tiny direction,
    // where the anchor would not be a point: then, as for NaN from a bad ray, there is none.
    let (od, dd) = (dot(o, d), dot(d, d));
    let t = (-od / dd) as f32;
    if !(t > 0.0 && t.is_finite()) {
        return (0.0, origin, od as f32, dd);
    }
    let at = |k: usize| (o[k] + d[k] * f64::from(t)) as f32;
    let anchor = Vec3::new(at(0), at(1), at(2));
    // Rounded to f32, the anchor lies off the line by up to half an ulp of its coordinates,
    // about 2^-24 |a|, while the origin lies on it exactly: measured from the anchor, a test
    // errs by about 2^-24 (|a| + |p - a|) for a triangle at `p`, from the origin by about
    // 2^-24 |p - o|. Along the line the anchor wins past `t_a / 2 + |a| / (2 |d|)`, and never
    // when the anchor is as far from the world origin as from the ray's origin (a ray started
    // near a far scene, crossing it sideways): then the ray has no anchor.
    let a = anchor.to_array().map(f64::from);
    let (anchor_len, dir_len) = (libm::sqrt(dot(a, a)), libm::sqrt(dd));
    if anchor_len >= f64::from(t) * dir_len {
        return (0.0, origin, od as f32, dd);
    }
    let split = od + (f64::from(t) * dd + anchor_len * dir_len) * 0.5;
    (t, anchor, split as f32, dd)
}

impl Ray {
    /// A ray over `[0, +inf)`.
    pub fn new(origin: Vec3, dir: Vec3) -> Result<Self, RayError> {
        Self::segment(origin, dir, 0.0, f32::INFINITY)
    }

    /// A ray over `[t_min, t_max]`. NaN anywhere and a zero direction are errors; an empty segment
    /// (`t_min > t_max`) is valid and hits nothing.
    pub fn segment(origin: Vec3, dir: Vec3, t_min: f32, t_max: f32) -> Result<Self, RayError> {
        if !origin.is_finite() {
            return Err(RayError::NonFiniteOrigin);
        }
        if !dir.is_finite() {
            return Err(RayError::NonFiniteDirection);
        }
        if dir == Vec3::ZERO {
            return Err(RayError::ZeroDirection);
        }
        if t_min.is_nan() || t_max.is_nan() {
            return Err(RayError::NanSegment);
        }
        Ok(Self::unchecked(origin, dir, t_min, t_max))
    }

    /// [`Ray::segment`] without its checks, for callers that hold finite values by construction.
    pub(crate) fn unchecked(origin: Vec3, dir: Vec3, t_min: f32, t_max: f32) -> Self {
        // `-0.0 + 0.0 == +0.0`: canonical zero components give `+inf` inverses.
        let canonical = dir + Vec3::ZERO;
        let (anchor_t, anchor, anchor_split, dir_len_sq) = anchor_of(origin, dir);
        Self {
            origin,
            dir,
            inv_dir: Vec3::ONE / canonical,
            t_min,
            t_max,
            anchor,
            anchor_t,
            anchor_split,
            dir_len_sq,
        }
    }

    /// True when a triangle at `p` is better measured from the ray's anchor than from its
    /// origin: when `|p - a| + |a| < |p - o|` along the line (the anchor's own rounding, about
    /// 2^-24 `|a|`, counts against it), which for `a = o + t_a d` is
    /// `dot(p - o, d) > (t_a |d|^2 + |a| |d|) / 2`: one dot product against a split fixed per
    /// ray.
    #[inline(always)]
    pub(crate) fn measures_from_anchor(&self, p: Vec3) -> bool {
        p.dot(self.dir) > self.anchor_split
    }

    /// The ray's second point to measure triangles from, and its ray parameter: the point of
    /// its line nearest the world origin when that lies ahead of the origin and nearer the world
    /// origin than the ray's origin, else the origin and 0.
    ///
    /// Moller-Trumbore's edge decisions carry an f32 error proportional to the distance between
    /// the point it measures from and the triangle. Measured from the origin, a ray from 1e8
    /// units away decides within 8 units of a 12-unit triangle's edges: noise. The anchor is
    /// never farther from the world origin than any point of the ray ahead of it, hits included,
    /// so measured from it the error is that of the scene's own coordinates, wherever the ray
    /// starts. But the anchor, rounded to f32, lies off the line by up to half an ulp of its own
    /// coordinates, while the origin lies on it exactly: a ray started near a triangle is better
    /// measured from its origin. Each triangle test measures from the point whose error at the
    /// triangle's first vertex is the smaller (`Ray::measures_from_anchor`), and a hit's `t`
    /// is that point's plus the test's own. A ray whose anchor is as far from the world origin
    /// as from the ray's origin (started near a far scene and crossing it sideways) has none.
    /// Both depend on the origin and the direction alone, so every structure and the
    /// brute-force oracle, given the same ray (or a segment of it), decide alike.
    #[inline]
    pub fn anchor(&self) -> (f32, Vec3) {
        (self.anchor_t, self.anchor)
    }

    /// The point at parameter `t`.
    #[inline]
    pub fn at(&self, t: f32) -> Vec3 {
        self.origin + self.dir * t
    }

    /// The box's near and far corners for this ray: per axis, `min` is near when the inverse
    /// direction is non-negative.
    #[inline]
    pub fn near_far(&self, b: &Aabb) -> (Vec3, Vec3) {
        let pos = self.inv_dir.cmpge(Vec3::ZERO);
        (
            Vec3::select(pos, b.min, b.max),
            Vec3::select(pos, b.max, b.min),
        )
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn rejects_bad_rays() {
        assert_eq!(
            Ray::new(Vec3::ZERO, Vec3::ZERO),
            Err(RayError::ZeroDirection)
        );
        assert_eq!(
            Ray::new(Vec3::ZERO, Vec3::new(f32::NAN, 0.0, 1.0)),
            Err(RayError::NonFiniteDirection)
        );
        assert_eq!(
            Ray::new(Vec3::splat(f32::INFINITY), Vec3::X),
            Err(RayError::NonFiniteOrigin)
        );
        assert_eq!(
            Ray::segment(Vec3::ZERO, Vec3::X, f32::NAN, 1.0),
            Err(RayError::NanSegment)
        );
    }

    #[test]
    fn negative_zero_gives_positive_infinite_inverse() {
        let r = Ray::new(Vec3::ZERO, Vec3::new(-0.0, 1.0, 0.0)).unwrap();
        assert_eq!(r.inv_dir.x, f32::INFINITY);
        assert_eq!(r.inv_dir.z, f32::INFINITY);
        assert_eq!(r.inv_dir.y, 1.0);
    }
}
