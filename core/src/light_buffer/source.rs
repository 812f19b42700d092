//! What a light buffer is built around: the light's surface (a point, or the convex hull of a
//! few points), and where the light sends light (everywhere, in front of a one-sided light's plane,
//! or inside a spot's cone).

use alloc::vec::Vec;
use core::fmt;

use glam::{DVec3, Vec3};
use wide::f32x4;

use crate::geometry::{Aabb, Ray};

/// The relative margin of every geometric decision the buffer makes: distances are grown by
/// `MARGIN` times the scene's coordinate scale. It dwarfs f32 rounding (about `6e-8` relative),
/// so rounding in the renderer's light sample, in the segment's end point or in the triangle test
/// can only keep a triangle that could have been dropped, never drop one that can be hit.
pub(crate) const MARGIN: f64 = 1e-4;

/// Why a light source is refused.
#[derive(Clone, Copy, Debug, PartialEq)]
pub enum LightSourceError {
    /// A position, point, normal or axis has a NaN or infinite coordinate.
    NonFinite,
    /// A polygon light with no point.
    NoPoints,
    /// A zero normal or spot axis.
    ZeroDirection,
    /// A spot's half-angle outside `(0, pi/2]` radians (a wider cone is not convex).
    ConeAngle(f32),
}

impl fmt::Display for LightSourceError {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        match self {
            LightSourceError::NonFinite => f.write_str("a light coordinate is NaN or infinite"),
            LightSourceError::NoPoints => f.write_str("a polygon light needs at least one point"),
            LightSourceError::ZeroDirection => f.write_str("a light normal or axis is zero"),
            LightSourceError::ConeAngle(a) => {
                write!(
                    f,
                    "a spot's half-angle must be in (0, pi/2] radians, got {a}"
                )
            }
        }
    }
}

impl core::error::Error for LightSourceError {}

/// A spot's cone: unit axis and half-angle.
#[derive(Clone, Copy, Debug, PartialEq)]
pub(crate) struct Cone {
    pub axis: DVec3,
    pub half_angle: f64,
}

/// A light's surface and the region it illuminates.
#[derive(Clone, Debug, PartialEq)]
pub struct LightSource {
    /// The points whose convex hull the buffer takes as the light's surface: the position of a
    /// point or spot light, the corners of an area light's box.
    pub(crate) support: Vec<DVec3>,
    /// The box of the light's points.
    pub(crate) bounds: Aabb,
    /// A one-sided light's unit normal and the least `normal . s` over its points: receivers lie
    /// where `normal . p` exceeds it.
    pub(crate) front: Option<(DVec3, f64)>,
    /// A spot's cone, apex at the single point.
    pub(crate) cone: Option<Cone>,
}

fn finite(v: Vec3) -> Result<DVec3, LightSourceError> {
    if v.is_finite() {
        Ok(v.as_dvec3())
    } else {
        Err(LightSourceError::NonFinite)
    }
}

fn unit(v: Vec3) -> Result<DVec3, LightSourceError> {
    let v = finite(v)?;
    let len = v.length();
    if len > 0.0 && len.is_finite() {
        Ok(v / len)
    } else {
        Err(LightSourceError::ZeroDirection)
    }
}

impl LightSource {
    /// A point light, which illuminates every direction.
    pub fn point(position: Vec3) -> Result<Self, LightSourceError> {
        let p = finite(position)?;
        Ok(Self {
            support: alloc::vec![p],
            bounds: Aabb::new(position, position),
            front: None,
            cone: None,
        })
    }

    /// A spot light: a point that illuminates the directions within `half_angle` radians of
    /// `axis`. Receivers outside the cone receive no shadow ray, so the buffer keeps nothing for
    /// the directions that leave it.
    pub fn spot(position: Vec3, axis: Vec3, half_angle: f32) -> Result<Self, LightSourceError> {
        if !(half_angle > 0.0 && half_angle <= core::f32::consts::FRAC_PI_2) {
            return Err(LightSourceError::ConeAngle(half_angle));
        }
        let mut s = Self::point(position)?;
        s.cone = Some(Cone {
            axis: unit(axis)?,
            half_angle: f64::from(half_angle),
        });
        Ok(s)
    }

    /// An area light on the convex hull of `points` (a quad's four corners, a triangle's three
    /// vertices, or every vertex of a group of emissive triangles). With `front`, the light is
    /// one-sided: it lights only the side its normal `front` points to.
    ///
    /// The buffer treats the light as the box of its points, the set its query accepts segment
    /// ends from: every segment it answers then lies in a cell's region, whatever the hull's
    /// shape. For the axis-aligned quads of most scenes the box is the quad itself.
    pub fn polygon(points: &[Vec3], front: Option<Vec3>) -> Result<Self, LightSourceError> {
        if points.is_empty() {
            return Err(LightSourceError::NoPoints);
        }
        for &p in points {
            finite(p)?;
        }
        let bounds = Aabb::from_points(points);
        let (lo, hi) = (bounds.min.as_dvec3(), bounds.max.as_dvec3());
        let support: Vec<DVec3> = (0..8)
            .map(|i| {
                DVec3::new(
                    if i & 1 == 0 { lo.x } else { hi.x },
                    if i & 2 == 0 { lo.y } else { hi.y },
                    if i & 4 == 0 { lo.z } else { hi.z },
                )
            })
            .collect();
        let front = match front {
            None => None,
            Some(n) => {
                let n = unit(n)?;
                // Measured from the box's lowest corner: a segment ending anywhere in the box
                // and starting in front stays in front.
                let lowest = support
                    .iter()
                    .map(|&s| n.dot(s))
                    .fold(f64::INFINITY, f64::min);
                Some((n, lowest))
            }
        };
        Ok(Self {
            support,
            bounds,
            front,
            cone: None,
        })
    }

    /// The box of the light's points.
    pub fn bounds(&self) -> Aabb {
        self.bounds
    }

    /// The least of `n . s` over the light's points.
    pub(crate) fn support_min(&self, n: DVec3) -> f64 {
        self.support
            .iter()
            .map(|&s| n.dot(s))
            .fold(f64::INFINITY, f64::min)
    }

    /// Where a segment the buffer answers may end: the light's box grown by `margin`, as the
    /// lower and upper corners in lanes 0 to 2 (lane 3 is 0 in both, as a segment's end has it
    /// in [`LightSource::ends_on_light`]).
    pub(crate) fn end_box(&self, margin: f32) -> (f32x4, f32x4) {
        let (lo, hi) = (self.bounds.min - margin, self.bounds.max + margin);
        (
            f32x4::from([lo.x, lo.y, lo.z, 0.0]),
            f32x4::from([hi.x, hi.y, hi.z, 0.0]),
        )
    }

    /// True when `ray` is a segment the buffer can answer: it ends on the light (`origin + dir`
    /// inside `end_box`, from [`LightSource::end_box`]) and, for a one-sided light, starts in
    /// front of it (within `margin`), since the cells keep nothing behind the light's plane. A
    /// spot's cone needs no test here: cells that leave it are dark as a whole, and a dark cell
    /// answers `None` by itself.
    #[inline(always)]
    pub(crate) fn ends_on_light(&self, ray: &Ray, (lo, hi): (f32x4, f32x4), margin: f32) -> bool {
        let (o, d) = (ray.origin, ray.dir);
        let end = f32x4::from([o.x + d.x, o.y + d.y, o.z + d.z, 0.0]);
        if !(lo.simd_le(end) & end.simd_le(hi)).all() {
            return false;
        }
        match self.front {
            Some((n, lowest)) => n.dot(o.as_dvec3()) >= lowest - f64::from(margin),
            None => true,
        }
    }
}
