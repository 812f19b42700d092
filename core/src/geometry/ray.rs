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
        // `-0.0 + 0.0 == +0.0`: canonical zero components give `+inf` inverses.
        let canonical = dir + Vec3::ZERO;
        Ok(Self {
            origin,
            dir,
            inv_dir: Vec3::ONE / canonical,
            t_min,
            t_max,
        })
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
