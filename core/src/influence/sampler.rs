//! Deterministic ray samplers: the rays each influence area models, for measuring costs and for
//! testing estimates against measurements.

use core::f32::consts::PI;

use glam::Vec3;

use super::{InfluenceArea, PlaneArea, PointArea};
use crate::geometry::Ray;
use crate::random::Pcg32;

/// How a point area draws its directions. The perspective PAH measure that matches the sampler is
/// [`crate::heuristics::PerspectiveMeasure::SolidAngle`] for `SolidAngle` and
/// [`crate::heuristics::PerspectiveMeasure::ImagePlane`] for `ImagePlane`; `YawPitch` (the thesis's
/// sampler) matches neither, which is why its estimates drift at wide fields of view.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum PointDistribution {
    /// Yaw and pitch uniform in angle within the fields of view, as the thesis sampled. Near the
    /// corners some of these directions leave the rectangular frustum.
    YawPitch,
    /// Uniform in solid angle over the frustum's rectangular pyramid (exact inversion).
    SolidAngle,
    /// Uniform on the image plane `z = 1` of the frustum.
    ImagePlane,
}

/// Draws rays for an influence area from a seed.
///
/// - plane areas: origins uniform on the light rectangle, direction the normal, optionally jittered
///   uniformly in solid angle within a cone;
/// - point areas: directions by [`PointDistribution`], origins at the eye or, as the thesis did, on
///   the near plane.
#[derive(Clone, Debug)]
pub struct RaySampler {
    area: InfluenceArea,
    rng: Pcg32,
    distribution: PointDistribution,
    from_near: bool,
    cos_jitter: f32,
}

impl RaySampler {
    /// A sampler for `area` with seed `seed`: for point areas, the thesis's yaw/pitch sampler
    /// starting on the near plane; for plane areas, exactly parallel rays.
    pub fn new(area: InfluenceArea, seed: u64) -> Self {
        Self {
            area,
            rng: Pcg32::new(seed),
            distribution: PointDistribution::YawPitch,
            from_near: true,
            cos_jitter: 1.0,
        }
    }

    /// Sets the point-area direction distribution.
    pub fn distribution(mut self, d: PointDistribution) -> Self {
        self.distribution = d;
        self
    }

    /// Point areas: start rays on the near plane (`true`, the thesis) or at the eye.
    pub fn from_near(mut self, yes: bool) -> Self {
        self.from_near = yes;
        self
    }

    /// Plane areas: jitter directions uniformly within a cone of this half-angle (degrees, clamped
    /// to `[0, 90]`) around the normal.
    pub fn jitter_deg(mut self, deg: f32) -> Self {
        self.cos_jitter = libm::cosf(deg.clamp(0.0, 90.0).to_radians());
        self
    }

    /// The next ray (segment `[0, inf)`).
    pub fn sample(&mut self) -> Ray {
        let (origin, dir) = match self.area {
            InfluenceArea::Plane(a) => self.plane(&a),
            InfluenceArea::Point(a) => self.point(&a),
        };
        // Origins and directions are finite and directions unit by construction.
        Ray::new(origin, dir)
            .unwrap_or_else(|_| Ray::unchecked(origin, Vec3::Z, 0.0, f32::INFINITY))
    }

    fn plane(&mut self, a: &PlaneArea) -> (Vec3, Vec3) {
        let u = self.rng.range(-1.0, 1.0) * a.half_width;
        let v = self.rng.range(-1.0, 1.0) * a.half_height;
        let origin = a.center + a.frame.right * u + a.frame.up * v;
        let mut dir = a.frame.forward;
        if self.cos_jitter < 1.0 {
            let cos_t = self.rng.range(self.cos_jitter, 1.0);
            let sin_t = libm::sqrtf((1.0 - cos_t * cos_t).max(0.0));
            let phi = self.rng.range(0.0, 2.0 * PI);
            dir = a.frame.to_world(Vec3::new(
                sin_t * libm::cosf(phi),
                sin_t * libm::sinf(phi),
                cos_t,
            ));
        }
        (origin, dir)
    }

    fn point(&mut self, a: &PointArea) -> (Vec3, Vec3) {
        let f = a.frustum();
        let local = match self.distribution {
            PointDistribution::YawPitch => {
                let yaw = self.rng.range(-0.5, 0.5) * a.fov_x_deg.to_radians();
                let pitch = self.rng.range(-0.5, 0.5) * a.fov_y_deg.to_radians();
                let cp = libm::cosf(pitch);
                Vec3::new(
                    cp * libm::sinf(yaw),
                    libm::sinf(pitch),
                    cp * libm::cosf(yaw),
                )
            }
            PointDistribution::ImagePlane => Vec3::new(
                self.rng.range(-f.tan_x, f.tan_x),
                self.rng.range(-f.tan_y, f.tan_y),
                1.0,
            ),
            PointDistribution::SolidAngle => {
                let (x, y) = solid_angle_rectangle(f.tan_x, f.tan_y, &mut self.rng);
                Vec3::new(x, y, 1.0)
            }
        }
        .normalize();
        let dir = f.frame.to_world(local);
        let origin = if self.from_near {
            f.eye + dir * (f.near / local.z)
        } else {
            f.eye
        };
        (origin, dir)
    }
}

impl Iterator for RaySampler {
    type Item = Ray;
    fn next(&mut self) -> Option<Ray> {
        Some(self.sample())
    }
}

/// A point `(x, y)` of the rectangle `[-tx, tx] x [-ty, ty]` on the plane `z = 1`, drawn with
/// density proportional to the solid angle it subtends, `(1 + x^2 + y^2)^(-3/2)`, by inverting
/// the marginal in `x` and the conditional in `y` in closed form:
/// - `F(x)` is proportional to `atan(ty x / sqrt(1 + ty^2 + x^2))`, so with `g = tan(theta)`,
///   `theta` uniform, `x = g sqrt(1 + ty^2) / sqrt(ty^2 - g^2)`;
/// - given `x` (`a^2 = 1 + x^2`), `F(y)` is proportional to `y / sqrt(a^2 + y^2)`, so with `s`
///   uniform, `y = a s / sqrt(1 - s^2)`.
fn solid_angle_rectangle(tx: f32, ty: f32, rng: &mut Pcg32) -> (f32, f32) {
    let theta0 = libm::atanf(tx * ty / libm::sqrtf(1.0 + tx * tx + ty * ty));
    let g = libm::tanf(rng.range(-theta0, theta0));
    let x = (g * libm::sqrtf(1.0 + ty * ty)
        / libm::sqrtf((ty * ty - g * g).max(f32::MIN_POSITIVE)))
    .clamp(-tx, tx);
    let a = libm::sqrtf(1.0 + x * x);
    let s_max = ty / libm::sqrtf(a * a + ty * ty);
    let s = rng.range(-s_max, s_max);
    let y = (a * s / libm::sqrtf((1.0 - s * s).max(f32::MIN_POSITIVE))).clamp(-ty, ty);
    (x, y)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn plane_rays_start_on_the_light_and_are_affine() {
        let a = PlaneArea::new(
            Vec3::new(1.0, 2.0, 3.0),
            Vec3::new(1.0, 0.0, 1.0),
            2.0,
            1.0,
            5.0,
        )
        .unwrap();
        let mut s = RaySampler::new(a.into(), 7);
        for _ in 0..1000 {
            let r = s.sample();
            let local = a.frame.to_local(r.origin - a.center);
            assert!(local.x.abs() <= 2.0 + 1e-5 && local.y.abs() <= 1.0 + 1e-5);
            assert!(local.z.abs() < 1e-5);
            assert!(a.is_affine(&r));
        }
    }

    #[test]
    fn point_rays_are_radial_and_inside() {
        let a = PointArea::new(
            Vec3::ZERO,
            Vec3::new(0.3, -0.2, 1.0),
            130.0,
            90.0,
            1.0,
            50.0,
        )
        .unwrap();
        for d in [PointDistribution::SolidAngle, PointDistribution::ImagePlane] {
            let mut s = RaySampler::new(a.into(), 3).distribution(d);
            for _ in 0..2000 {
                let r = s.sample();
                assert!(a.is_affine(&r), "{d:?} {r:?}");
            }
        }
    }

    #[test]
    fn solid_angle_sampler_matches_density() {
        // The fraction of samples with x > tx / 2 equals that sub-rectangle's share of the solid
        // angle, computed with the same closed form the sampler inverts.
        let (tx, ty) = (2.0f32, 1.0f32);
        let omega = |x0: f32, x1: f32| {
            let f = |x: f32| libm::atanf(ty * x / libm::sqrtf(1.0 + ty * ty + x * x));
            f(x1) - f(x0)
        };
        let expect = omega(tx / 2.0, tx) / omega(-tx, tx);
        let mut rng = Pcg32::new(11);
        let n = 200_000;
        let hits = (0..n)
            .filter(|_| solid_angle_rectangle(tx, ty, &mut rng).0 > tx / 2.0)
            .count();
        assert!(
            (hits as f32 / n as f32 - expect).abs() < 0.005,
            "{} vs {expect}",
            hits as f32 / n as f32
        );
    }
}
