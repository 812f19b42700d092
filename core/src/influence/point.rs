//! Point influence areas: a frustum of radial rays in front of a point or spot light.

use glam::Vec3;

use super::error::{cos_tolerance, finite3, window_measurable};
use super::{AreaError, DEFAULT_AFFINITY_DEG, MAX_AREA_COORDINATE};
use crate::geometry::{Aabb, Frame, Frustum, Polytope, Ray, Triangle};

/// How close to the eye, relative to the coordinates' magnitude, an origin counts as the eye
/// itself for [`PointArea::is_affine`]: `1024 f32::EPSILON`. Beyond it the origin's rounding
/// turns the direction from the eye by at most 1/1024 radian (0.06 degrees), well inside the
/// affinity tolerance.
const EYE_ROUNDING: f32 = 1024.0 * f32::EPSILON;

/// A frustum with apex at the light (`eye`), looking along `frame.forward`, full fields of view
/// `fov_x_deg` (along `frame.right`) and `fov_y_deg` (along `frame.up`), cut at `near` and `far`.
///
/// ```
/// use rdbvh_core::{PointArea, Ray, Vec3};
///
/// // A spot light at y = 5 looking down with a 90 x 90 degree cone, from 0.1 to 10 units.
/// let area = PointArea::new(Vec3::new(0.0, 5.0, 0.0), -Vec3::Y, 90.0, 90.0, 0.1, 10.0)?;
/// assert!(area.contains(Vec3::new(1.0, 2.0, 1.0)));
/// // Affine: starts inside and travels radially, away from the eye.
/// let radial = Vec3::new(0.3, -1.0, 0.2);
/// assert!(area.is_affine(&Ray::new(Vec3::new(0.0, 5.0, 0.0) + radial, radial)?));
/// assert!(!area.is_affine(&Ray::new(Vec3::new(0.0, 5.0, 0.0) + radial, Vec3::X)?));
/// # Ok::<(), Box<dyn std::error::Error>>(())
/// ```
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct PointArea {
    /// Field of view along `right`, in degrees.
    pub fov_x_deg: f32,
    /// Field of view along `up`, in degrees.
    pub fov_y_deg: f32,
    frustum: Frustum,
    polytope: Polytope,
    cos_tolerance: f32,
}

impl PointArea {
    /// A point area from the keys of an `experiments.toml` entry; `direction` need not be unit
    /// length. Fields of view must be strictly between 0 and 180 degrees, `0 <= near < far`.
    pub fn new(
        eye: Vec3,
        direction: Vec3,
        fov_x_deg: f32,
        fov_y_deg: f32,
        near: f32,
        far: f32,
    ) -> Result<Self, AreaError> {
        let eye = finite3(eye, "eye")?;
        let direction = finite3(direction, "direction")?;
        let frame = Frame::look_at(direction).ok_or(AreaError::ZeroDirection("direction"))?;
        let tan_half = |deg: f32, key: &'static str| {
            if !deg.is_finite() {
                return Err(AreaError::NotFinite(key));
            }
            if !(deg > 0.0 && deg < 180.0) {
                return Err(AreaError::FieldOfView(key));
            }
            let t = libm::tanf((0.5 * deg).to_radians());
            (t.is_finite() && t > 0.0)
                .then_some(t)
                .ok_or(AreaError::FieldOfView(key))
        };
        let tan_x = tan_half(fov_x_deg, "fov_x_deg")?;
        let tan_y = tan_half(fov_y_deg, "fov_y_deg")?;
        if !near.is_finite() {
            return Err(AreaError::NotFinite("near"));
        }
        if !far.is_finite() {
            return Err(AreaError::NotFinite("far"));
        }
        let frustum =
            Frustum::new(eye, frame, tan_x, tan_y, near, far).ok_or(AreaError::NearFar)?;
        // After every check of a value alone: a window too small to measure is derived from two.
        window_measurable((tan_x, "fov_x_deg"), (tan_y, "fov_y_deg"))?;
        let polytope = frustum.polytope();
        if !polytope.is_finite() {
            // Finite inputs near f32::MAX can still overflow the frustum's corners and planes.
            return Err(AreaError::NotFinite("eye"));
        }
        if polytope.scale > MAX_AREA_COORDINATE {
            return Err(AreaError::TooLarge("far"));
        }
        Ok(Self {
            fov_x_deg,
            fov_y_deg,
            frustum,
            polytope,
            cos_tolerance: cos_tolerance(DEFAULT_AFFINITY_DEG)?,
        })
    }

    /// The same area with another affinity tolerance, in degrees (`[0, 180)`).
    pub fn with_tolerance_deg(mut self, deg: f32) -> Result<Self, AreaError> {
        self.cos_tolerance = cos_tolerance(deg)?;
        Ok(self)
    }

    /// The area's frustum.
    pub fn frustum(&self) -> &Frustum {
        &self.frustum
    }

    /// The light position.
    pub fn eye(&self) -> Vec3 {
        self.frustum.eye
    }

    /// The area as a polytope (planes, corners, separating axes).
    pub fn polytope(&self) -> &Polytope {
        &self.polytope
    }

    /// True when `p` is inside the frustum.
    pub fn contains(&self, p: Vec3) -> bool {
        self.polytope.contains(p)
    }

    /// Exact overlap with a box.
    pub fn overlaps_aabb(&self, b: &Aabb) -> bool {
        self.polytope.overlaps_aabb(b)
    }

    /// Exact overlap with a triangle (never by vertex containment).
    pub fn overlaps_triangle(&self, t: &Triangle) -> bool {
        self.polytope.overlaps_triangle(t)
    }

    /// Where the segment leaves the frustum, if it is inside it somewhere.
    pub fn exit(&self, ray: &Ray) -> Option<f32> {
        self.polytope.clip_ray(ray).map(|(_, t1)| t1)
    }

    /// The radial direction at `p`: from the eye to `p` (the view direction at the eye itself).
    pub fn direction_at(&self, p: Vec3) -> Vec3 {
        (p - self.frustum.eye)
            .try_normalize()
            .unwrap_or(self.frustum.frame.forward)
    }

    /// Affinity: the origin is inside and the direction is within the tolerance of the radial
    /// direction from the eye to the origin. At the eye itself, to rounding (the rays of an area
    /// whose `near` is 0 or tiny start there), the direction from the eye means nothing: a ray
    /// that leaves the eye through the window is radial.
    pub fn is_affine(&self, ray: &Ray) -> bool {
        self.radial(ray) && self.contains(ray.origin)
    }

    /// The part of the segment inside the frustum when the ray is affine
    /// ([`PointArea::is_affine`]), else `None`: the affinity test and the clip in one pass over
    /// the frustum's planes.
    #[inline]
    pub fn affine_clip(&self, ray: &Ray) -> Option<(f32, f32)> {
        if !self.radial(ray) {
            return None;
        }
        self.polytope.clip_ray_from_inside(ray)
    }

    /// The direction half of affinity: within the tolerance of the radial direction.
    #[inline]
    fn radial(&self, ray: &Ray) -> bool {
        let Some(d) = ray.dir.try_normalize() else {
            return false;
        };
        let f = &self.frustum;
        let offset = ray.origin - f.eye;
        let rounding = EYE_ROUNDING
            * f.eye
                .abs()
                .max_element()
                .max(ray.origin.abs().max_element());
        let radial = match offset.try_normalize() {
            Some(r) if offset.abs().max_element() > rounding => r,
            _ if f.sees_direction(d) => d,
            _ => return false,
        };
        d.dot(radial) >= self.cos_tolerance
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn area() -> PointArea {
        PointArea::new(Vec3::new(5.0, 5.0, -4.0), Vec3::Z, 90.0, 60.0, 1.0, 20.0).unwrap()
    }

    #[test]
    fn frustum_containment() {
        let a = area();
        assert!(a.contains(Vec3::new(5.0, 5.0, -2.0)));
        assert!(!a.contains(Vec3::new(5.0, 5.0, -3.5)), "before near");
        assert!(!a.contains(Vec3::new(5.0, 5.0, 16.5)), "past far");
        // 90 degrees horizontally: |x| <= z; 60 vertically: |y| <= z tan 30.
        assert!(a.contains(Vec3::new(5.0 + 9.9, 5.0, 6.0)));
        assert!(!a.contains(Vec3::new(5.0 + 10.2, 5.0, 6.0)));
        assert!(a.contains(Vec3::new(5.0, 5.0 + 5.7, 6.0)));
        assert!(!a.contains(Vec3::new(5.0, 5.0 + 5.9, 6.0)));
    }

    #[test]
    fn radial_affinity() {
        let a = area();
        let o = Vec3::new(6.0, 5.5, 0.0);
        let radial = Ray::new(o, (o - a.eye()) * 2.0).unwrap();
        assert!(a.is_affine(&radial));
        assert!(!a.is_affine(&Ray::new(o, Vec3::Z).unwrap()));
        let t = a.exit(&radial).unwrap();
        assert!((radial.at(t).z - 16.0).abs() < 1e-3);
    }

    #[test]
    fn rays_from_the_eye_are_radial_when_near_is_zero_or_tiny() {
        let eye = Vec3::new(-0.017, 0.11, 0.3);
        for near in [0.0, 1e-8, 1e-7] {
            let a = PointArea::new(eye, -Vec3::Z, 60.0, 60.0, near, 1.0).unwrap();
            // Origins where the sampler puts them: on the near plane, rounded.
            for i in 0..200 {
                let (x, y) = ((i % 20) as f32 / 19.0 - 0.5, (i / 20) as f32 / 9.0 - 0.5);
                let d = Vec3::new(x, y, -1.0);
                let r = Ray::new(eye + d * near, d).unwrap();
                assert!(a.is_affine(&r), "near {near}, direction {d}");
            }
            // Leaving the eye outside the window (or backwards) is not radial to this area.
            for d in [Vec3::new(0.9, 0.0, -1.0), Vec3::Z, Vec3::X] {
                assert!(!a.is_affine(&Ray::new(eye, d).unwrap()), "{d}");
            }
        }
        // With a real near plane the eye is outside the area.
        let a = PointArea::new(eye, -Vec3::Z, 60.0, 60.0, 0.01, 1.0).unwrap();
        assert!(!a.is_affine(&Ray::new(eye, -Vec3::Z).unwrap()));
    }

    #[test]
    fn rejects_degenerate_parameters() {
        let (e, d) = (Vec3::ZERO, Vec3::Z);
        assert_eq!(
            PointArea::new(e, d, 0.0, 60.0, 1.0, 2.0),
            Err(AreaError::FieldOfView("fov_x_deg"))
        );
        assert_eq!(
            PointArea::new(e, d, 60.0, 180.0, 1.0, 2.0),
            Err(AreaError::FieldOfView("fov_y_deg"))
        );
        assert_eq!(
            PointArea::new(e, d, 60.0, 60.0, 2.0, 2.0),
            Err(AreaError::NearFar)
        );
        assert_eq!(
            PointArea::new(e, d, 60.0, 60.0, -1.0, 2.0),
            Err(AreaError::NearFar)
        );
        assert_eq!(
            PointArea::new(e, Vec3::ZERO, 60.0, 60.0, 1.0, 2.0),
            Err(AreaError::ZeroDirection("direction"))
        );
        assert_eq!(
            PointArea::new(e, d, f32::NAN, 60.0, 1.0, 2.0),
            Err(AreaError::NotFinite("fov_x_deg"))
        );
        assert!(PointArea::new(e, d, 179.9, 1e-3, 0.0, 1.0).is_ok());
    }
}
