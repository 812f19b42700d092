//! Plane influence areas: an oriented box of parallel rays in front of a planar light.

use glam::Vec3;

use super::error::{cos_tolerance, finite3, positive, window_measurable};
use super::{AreaError, DEFAULT_AFFINITY_DEG, MAX_AREA_COORDINATE};
use crate::geometry::{Aabb, Frame, Obb, Polytope, Ray, Triangle};

/// An oriented box: the light rectangle (centre `center`, half extents `half_width` along
/// `frame.right` and `half_height` along `frame.up`) swept `depth` along the ray direction
/// `frame.forward`.
///
/// ```
/// use rdbvh_core::{PlaneArea, Ray, Vec3};
///
/// // A 2 x 2 area light at y = 5 facing down, its parallel rays followed 6 units.
/// let area = PlaneArea::new(Vec3::new(0.0, 5.0, 0.0), -Vec3::Y, 1.0, 1.0, 6.0)?;
/// assert!(area.contains(Vec3::new(0.5, 2.0, -0.5)));
/// // Affine: starts inside and travels (almost) the area's way.
/// assert!(area.is_affine(&Ray::new(Vec3::new(0.5, 4.0, 0.0), -Vec3::Y)?));
/// assert!(!area.is_affine(&Ray::new(Vec3::new(0.5, 4.0, 0.0), Vec3::X)?));
/// // A degenerate window is an error naming its key.
/// assert!(PlaneArea::new(Vec3::ZERO, -Vec3::Y, 0.0, 1.0, 6.0).is_err());
/// # Ok::<(), Box<dyn std::error::Error>>(())
/// ```
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct PlaneArea {
    /// Centre of the light rectangle.
    pub center: Vec3,
    /// Look-at frame of the normal (`forward` is the ray direction).
    pub frame: Frame,
    /// Half extent along `frame.right`.
    pub half_width: f32,
    /// Half extent along `frame.up`.
    pub half_height: f32,
    /// How far the box reaches along `frame.forward`.
    pub depth: f32,
    obb: Obb,
    polytope: Polytope,
    cos_tolerance: f32,
}

impl PlaneArea {
    /// A plane area from the keys of an `experiments.toml` entry; `normal` need not be unit length.
    /// Errors for NaN or infinite values, a zero normal and non-positive extents.
    pub fn new(
        center: Vec3,
        normal: Vec3,
        half_width: f32,
        half_height: f32,
        depth: f32,
    ) -> Result<Self, AreaError> {
        let center = finite3(center, "center")?;
        let normal = finite3(normal, "normal")?;
        let frame = Frame::look_at(normal).ok_or(AreaError::ZeroDirection("normal"))?;
        let half_width = positive(half_width, "half_width")?;
        let half_height = positive(half_height, "half_height")?;
        let depth = positive(depth, "depth")?;
        window_measurable((half_width, "half_width"), (half_height, "half_height"))?;
        let obb = Obb::new(
            center + frame.forward * (0.5 * depth),
            frame,
            Vec3::new(half_width, half_height, 0.5 * depth),
        )
        .ok_or(AreaError::NotFinite("center"))?;
        let polytope = obb.polytope();
        if !polytope.is_finite() {
            // Finite inputs near f32::MAX can still overflow the box's corners and planes.
            return Err(AreaError::NotFinite("center"));
        }
        if polytope.scale > MAX_AREA_COORDINATE {
            // The key of the largest term of the reach (an extent before the centre on a tie).
            let terms = [
                (depth, "depth"),
                (half_width, "half_width"),
                (half_height, "half_height"),
                (center.abs().max_element(), "center"),
            ];
            let (_, key) =
                terms.into_iter().fold(
                    (f32::NEG_INFINITY, "depth"),
                    |a, b| if b.0 > a.0 { b } else { a },
                );
            return Err(AreaError::TooLarge(key));
        }
        Ok(Self {
            center,
            frame,
            half_width,
            half_height,
            depth,
            obb,
            polytope,
            cos_tolerance: cos_tolerance(DEFAULT_AFFINITY_DEG)?,
        })
    }

    /// The same area with another affinity tolerance, in degrees (`[0, 180)`).
    pub fn with_tolerance_deg(mut self, deg: f32) -> Result<Self, AreaError> {
        self.cos_tolerance = cos_tolerance(deg)?;
        Ok(self)
    }

    /// The area's box.
    pub fn obb(&self) -> &Obb {
        &self.obb
    }

    /// The area as a polytope (planes, corners, separating axes).
    pub fn polytope(&self) -> &Polytope {
        &self.polytope
    }

    /// Area of the light rectangle.
    pub fn window_area(&self) -> f32 {
        4.0 * self.half_width * self.half_height
    }

    /// True when `p` is inside the box.
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

    /// Where the segment leaves the box, if it is inside it somewhere.
    pub fn exit(&self, ray: &Ray) -> Option<f32> {
        self.polytope.clip_ray(ray).map(|(_, t1)| t1)
    }

    /// Affinity: the origin is inside and the direction is within the tolerance of the normal.
    pub fn is_affine(&self, ray: &Ray) -> bool {
        self.along_rays(ray) && self.contains(ray.origin)
    }

    /// The part of the segment inside the box when the ray is affine ([`PlaneArea::is_affine`]),
    /// else `None`: the affinity test and the clip in one pass over the box's planes.
    #[inline]
    pub fn affine_clip(&self, ray: &Ray) -> Option<(f32, f32)> {
        if !self.along_rays(ray) {
            return None;
        }
        self.polytope.clip_ray_from_inside(ray)
    }

    /// The direction half of affinity: within the tolerance of the area's direction.
    #[inline]
    fn along_rays(&self, ray: &Ray) -> bool {
        let Some(d) = ray.dir.try_normalize() else {
            return false;
        };
        d.dot(self.frame.forward) >= self.cos_tolerance
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn area() -> PlaneArea {
        PlaneArea::new(Vec3::new(5.0, 5.0, -4.0), Vec3::Z, 5.0, 5.0, 20.0).unwrap()
    }

    #[test]
    fn a_reach_too_large_names_its_largest_term() {
        let c = Vec3::new(5.0, 5.0, -4.0);
        let too_large = |c: Vec3, w: f32, h: f32, d: f32| PlaneArea::new(c, Vec3::Z, w, h, d);
        for (made, key) in [
            (too_large(c, 1e30, 5.0, 20.0), "half_width"),
            (too_large(c, 5.0, 1e30, 20.0), "half_height"),
            (too_large(c, 5.0, 5.0, 1e30), "depth"),
            (
                too_large(Vec3::new(0.0, 1e19, 0.0), 5.0, 5.0, 20.0),
                "center",
            ),
        ] {
            assert_eq!(made, Err(AreaError::TooLarge(key)));
        }
    }

    #[test]
    fn box_spans_from_light_along_normal() {
        let a = area();
        assert!(a.contains(Vec3::new(5.0, 5.0, -3.9)));
        assert!(a.contains(Vec3::new(0.1, 9.9, 15.9)));
        assert!(!a.contains(Vec3::new(5.0, 5.0, -4.1)));
        assert!(!a.contains(Vec3::new(5.0, 5.0, 16.1)));
        assert!(!a.contains(Vec3::new(10.2, 5.0, 0.0)));
        assert_eq!(a.window_area(), 100.0);
    }

    #[test]
    fn affinity_and_exit() {
        let a = area();
        let r = Ray::new(Vec3::new(5.0, 5.0, 0.0), Vec3::Z * 3.0).unwrap();
        assert!(a.is_affine(&r));
        assert!((a.exit(&r).unwrap() - 16.0 / 3.0).abs() < 1e-4);
        let tilted = Ray::new(Vec3::new(5.0, 5.0, 0.0), Vec3::new(0.1, 0.0, 1.0)).unwrap();
        assert!(!a.is_affine(&tilted));
        assert!(a.with_tolerance_deg(10.0).unwrap().is_affine(&tilted));
        let outside = Ray::new(Vec3::new(50.0, 5.0, 0.0), Vec3::Z).unwrap();
        assert!(!a.is_affine(&outside));
    }

    #[test]
    fn rejects_degenerate_parameters() {
        let c = Vec3::ZERO;
        assert_eq!(
            PlaneArea::new(c, Vec3::ZERO, 1.0, 1.0, 1.0),
            Err(AreaError::ZeroDirection("normal"))
        );
        assert_eq!(
            PlaneArea::new(c, Vec3::Z, 0.0, 1.0, 1.0),
            Err(AreaError::NotPositive("half_width"))
        );
        assert_eq!(
            PlaneArea::new(c, Vec3::Z, 1.0, -1.0, 1.0),
            Err(AreaError::NotPositive("half_height"))
        );
        assert_eq!(
            PlaneArea::new(c, Vec3::Z, 1.0, 1.0, f32::NAN),
            Err(AreaError::NotFinite("depth"))
        );
        assert_eq!(
            PlaneArea::new(Vec3::splat(f32::INFINITY), Vec3::Z, 1.0, 1.0, 1.0),
            Err(AreaError::NotFinite("center"))
        );
        assert_eq!(area().with_tolerance_deg(180.0), Err(AreaError::Tolerance));
        // A window whose area underflows f32's normal range cannot be measured.
        assert_eq!(
            PlaneArea::new(c, Vec3::Z, 1e-16, 1e-15, 1.0),
            Err(AreaError::TooSmall("half_width"))
        );
        assert!(PlaneArea::new(c, Vec3::Z, 1e-15, 1e-15, 1.0).is_ok());
    }
}
