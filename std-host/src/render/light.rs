//! The renderer's lights and how next event estimation samples them: point, spot and quad lights
//! from a lights file, and the scene's emissive triangles.

use std::f64::consts::PI;

use glam::DVec3;
use rdbvh_core::geometry::Triangle;
use rdbvh_core::light_buffer::{LightSource, LightSourceError};
use rdbvh_core::Vec3;

use crate::scene::Scene;

/// A light. Point, spot and quad lights are not geometry: camera rays do not see them and they
/// occlude nothing. An emissive triangle is a scene triangle and emits from both faces, because
/// the winding of OBJ files is rarely consistent enough to pick one.
#[derive(Clone, Copy, Debug, PartialEq)]
pub enum Light {
    /// Light from one point in every direction; `intensity` is the radiant intensity (RGB).
    Point {
        /// Where the light is.
        position: Vec3,
        /// Radiant intensity per colour channel.
        intensity: Vec3,
    },
    /// A point light with a hard-edged cone: `intensity` inside, nothing outside.
    Spot {
        /// Where the light is.
        position: Vec3,
        /// The cone's axis, of unit length.
        direction: Vec3,
        /// The cone's half-angle in radians, in (0, pi/2].
        half_angle: f32,
        /// `cos(half_angle)`: a receiver is lit when the direction to it is this close to the axis.
        cos_half_angle: f32,
        /// Radiant intensity per colour channel.
        intensity: Vec3,
    },
    /// A one-sided parallelogram `corner + s edge1 + t edge2`, `s, t` in [0, 1], emitting
    /// `radiance` toward `edge1 x edge2`.
    Quad {
        /// One corner.
        corner: Vec3,
        /// The first edge from the corner.
        edge1: Vec3,
        /// The second edge from the corner.
        edge2: Vec3,
        /// Emitted radiance per colour channel.
        radiance: Vec3,
    },
    /// Scene triangle `triangle`, whose material emits `radiance` (its MTL `Ke`) from both faces.
    Emissive {
        /// The triangle's id in the scene.
        triangle: u32,
        /// Emitted radiance per colour channel.
        radiance: Vec3,
    },
}

/// A point on a light seen from a receiver, as next event estimation uses it.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct LightSample {
    /// The point on the light; the shadow ray ends just before it.
    pub target: Vec3,
    /// The light arriving at the receiver from the sample, divided by the sample's density:
    /// `I / r^2` for a point light, `L cos_light A / r^2` for an area light sampled uniformly by
    /// area. The receiver's BRDF, its cosine and the light's selection probability are not in it.
    pub weight: Vec3,
}

/// Rec. 709 luminance of a linear RGB colour.
pub fn luminance(c: Vec3) -> f32 {
    0.2126 * c.x + 0.7152 * c.y + 0.0722 * c.z
}

impl Light {
    /// The light's emitted power in luminance (watts, up to the unit of the file's numbers): the
    /// weight by which next event estimation chooses it. Point `4 pi I`, spot
    /// `2 pi (1 - cos) I`, quad `pi A L`, emissive triangle `2 pi A L` (both faces). In f64,
    /// where no finite light's power overflows (an area squares its coordinates' scale).
    pub fn power(&self, triangles: &[Triangle]) -> f64 {
        let luminance = |c: Vec3| f64::from(luminance(c));
        // Twice the area of the triangle (a, a + e1, a + e2).
        let parallelogram = |e1: DVec3, e2: DVec3| e1.cross(e2).length();
        match *self {
            Light::Point { intensity, .. } => 4.0 * PI * luminance(intensity),
            Light::Spot {
                cos_half_angle,
                intensity,
                ..
            } => 2.0 * PI * (1.0 - f64::from(cos_half_angle)) * luminance(intensity),
            Light::Quad {
                edge1,
                edge2,
                radiance,
                ..
            } => PI * parallelogram(edge1.as_dvec3(), edge2.as_dvec3()) * luminance(radiance),
            Light::Emissive { triangle, radiance } => {
                let t = &triangles[triangle as usize];
                let (v0, v1, v2) = (t.v0.as_dvec3(), t.v1.as_dvec3(), t.v2.as_dvec3());
                PI * parallelogram(v1 - v0, v2 - v0) * luminance(radiance)
            }
        }
    }

    /// A point of the light for the receiver at `origin`, from two uniform numbers `u, v`;
    /// `None` when the light sends the receiver nothing (outside a spot's cone, behind a quad).
    #[inline]
    pub fn sample(
        &self,
        triangles: &[Triangle],
        origin: Vec3,
        u: f32,
        v: f32,
    ) -> Option<LightSample> {
        match *self {
            Light::Point {
                position,
                intensity,
            } => {
                let d2 = (position - origin).length_squared();
                Some(LightSample {
                    target: position,
                    weight: intensity / d2,
                })
            }
            Light::Spot {
                position,
                direction,
                cos_half_angle,
                intensity,
                ..
            } => {
                let to_receiver = origin - position;
                let d2 = to_receiver.length_squared();
                (direction.dot(to_receiver) >= cos_half_angle * d2.sqrt()).then(|| LightSample {
                    target: position,
                    weight: intensity / d2,
                })
            }
            Light::Quad {
                corner,
                edge1,
                edge2,
                radiance,
            } => {
                let target = corner + edge1 * u + edge2 * v;
                let normal = edge1.cross(edge2);
                let to_receiver = origin - target;
                // cos_light * area = n_unnormalised . w / |w|.
                let cos_area = normal.dot(to_receiver);
                (cos_area > 0.0).then(|| {
                    let d2 = to_receiver.length_squared();
                    LightSample {
                        target,
                        weight: radiance * (cos_area / (d2 * d2.sqrt())),
                    }
                })
            }
            Light::Emissive { triangle, radiance } => {
                let t = &triangles[triangle as usize];
                // Uniform by area (Shirley 1990): b0 = 1 - sqrt(u), b1 = v sqrt(u).
                let su = u.sqrt();
                let (b1, b2) = (v * su, 1.0 - su);
                let target = t.v0 + (t.v1 - t.v0) * b1 + (t.v2 - t.v0) * b2;
                let normal = (t.v1 - t.v0).cross(t.v2 - t.v0) * 0.5;
                let to_receiver = origin - target;
                let d2 = to_receiver.length_squared();
                let cos_area = normal.dot(to_receiver).abs();
                Some(LightSample {
                    target,
                    weight: radiance * (cos_area / (d2 * d2.sqrt())),
                })
            }
        }
    }

    /// The light as a light buffer's source: the point, the cone, or the quad's corners with its
    /// front (an emissive triangle emits from both faces, so it has none).
    pub fn source(&self, triangles: &[Triangle]) -> Result<LightSource, LightSourceError> {
        match *self {
            Light::Point { position, .. } => LightSource::point(position),
            Light::Spot {
                position,
                direction,
                half_angle,
                ..
            } => LightSource::spot(position, direction, half_angle),
            Light::Quad {
                corner,
                edge1,
                edge2,
                ..
            } => LightSource::polygon(
                &[
                    corner,
                    corner + edge1,
                    corner + edge2,
                    corner + edge1 + edge2,
                ],
                Some(edge1.cross(edge2)),
            ),
            Light::Emissive { triangle, .. } => {
                let t = &triangles[triangle as usize];
                LightSource::polygon(&[t.v0, t.v1, t.v2], None)
            }
        }
    }
}

/// The scene's emissive triangles as lights, in triangle order.
pub fn emissive_lights(scene: &Scene) -> Vec<Light> {
    scene
        .emissive_triangles()
        .map(|triangle| Light::Emissive {
            triangle,
            radiance: Vec3::from(
                scene.materials[scene.material[triangle as usize] as usize].emission,
            ),
        })
        .collect()
}

/// The lights with the distribution that next event estimation draws them from: in proportion
/// to [`Light::power`].
#[derive(Clone, Debug)]
pub struct LightSet {
    lights: Vec<Light>,
    /// Cumulative probabilities, the last one 1.
    cdf: Vec<f32>,
    /// Each light's probability.
    pmf: Vec<f32>,
}

impl LightSet {
    /// The lights of positive power among `lights`, or `None` when none has any.
    pub fn new(lights: Vec<Light>, triangles: &[Triangle]) -> Option<Self> {
        let lights: Vec<Light> = lights
            .into_iter()
            .filter(|l| l.power(triangles) > 0.0)
            .collect();
        let powers: Vec<f64> = lights.iter().map(|l| l.power(triangles)).collect();
        let total: f64 = powers.iter().sum();
        if !(total > 0.0 && total.is_finite()) {
            return None;
        }
        let mut sum = 0.0;
        let cdf = powers
            .iter()
            .map(|p| {
                sum += p;
                (sum / total) as f32
            })
            .collect();
        let pmf = powers.iter().map(|p| (p / total) as f32).collect();
        Some(Self { lights, cdf, pmf })
    }

    /// The lights, in the order their indices refer to.
    pub fn lights(&self) -> &[Light] {
        &self.lights
    }

    /// The light for a uniform number `u` in [0, 1), and its probability.
    #[inline]
    pub fn choose(&self, u: f32) -> (usize, f32) {
        let i = self
            .cdf
            .partition_point(|&c| c <= u)
            .min(self.lights.len() - 1);
        (i, self.pmf[i])
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn quad() -> Light {
        Light::Quad {
            corner: Vec3::new(-1.0, 2.0, -1.0),
            edge1: Vec3::new(0.0, 0.0, 2.0),
            edge2: Vec3::new(2.0, 0.0, 0.0),
            radiance: Vec3::ONE,
        }
    }

    #[test]
    fn quad_emits_toward_edge1_cross_edge2_only() {
        // edge1 x edge2 = z x x = y: the quad at y = 2 lights what is above it.
        assert!(quad()
            .sample(&[], Vec3::new(0.0, 3.0, 0.0), 0.5, 0.5)
            .is_some());
        assert!(quad().sample(&[], Vec3::ZERO, 0.5, 0.5).is_none());
    }

    #[test]
    fn quad_sample_weight_is_the_solid_angle_integrand() {
        // Straight above the centre at distance 1: L cos A / r^2 = 1 * 1 * 4 / 1.
        let s = quad()
            .sample(&[], Vec3::new(0.0, 3.0, 0.0), 0.5, 0.5)
            .unwrap();
        assert_eq!(s.target, Vec3::new(0.0, 2.0, 0.0));
        assert!(
            (s.weight - Vec3::splat(4.0)).length() < 1e-5,
            "{}",
            s.weight
        );
    }

    #[test]
    fn spot_lights_its_cone_only() {
        let spot = Light::Spot {
            position: Vec3::ZERO,
            direction: Vec3::NEG_Y,
            half_angle: 0.5,
            cos_half_angle: 0.5f32.cos(),
            intensity: Vec3::ONE,
        };
        assert!(spot
            .sample(&[], Vec3::new(0.0, -2.0, 0.5), 0.0, 0.0)
            .is_some());
        assert!(spot
            .sample(&[], Vec3::new(0.0, -2.0, 2.0), 0.0, 0.0)
            .is_none());
        assert!(spot
            .sample(&[], Vec3::new(0.0, 2.0, 0.0), 0.0, 0.0)
            .is_none());
    }

    #[test]
    fn emissive_samples_lie_on_the_triangle_and_cover_it_uniformly() {
        let t = Triangle::new(Vec3::ZERO, Vec3::X, Vec3::Y);
        let light = Light::Emissive {
            triangle: 0,
            radiance: Vec3::ONE,
        };
        let mut below_diagonal_half = 0;
        let n = 40;
        for i in 0..n {
            for j in 0..n {
                let (u, v) = ((i as f32 + 0.5) / n as f32, (j as f32 + 0.5) / n as f32);
                let p = light.sample(&[t], Vec3::Z, u, v).unwrap().target;
                assert!(p.x >= 0.0 && p.y >= 0.0 && p.x + p.y <= 1.0 + 1e-6, "{p}");
                below_diagonal_half += usize::from(p.x + p.y < std::f32::consts::FRAC_1_SQRT_2);
            }
        }
        // The part with x + y < 1/sqrt(2) has half the triangle's area.
        let share = below_diagonal_half as f32 / (n * n) as f32;
        assert!((share - 0.5).abs() < 0.03, "{share}");
    }

    #[test]
    fn lights_are_chosen_by_power() {
        let point = |i: f32| Light::Point {
            position: Vec3::ZERO,
            intensity: Vec3::splat(i),
        };
        let set = LightSet::new(vec![point(1.0), point(0.0), point(3.0)], &[]).unwrap();
        assert_eq!(set.lights().len(), 2, "the dark light is dropped");
        assert_eq!(set.choose(0.0), (0, 0.25));
        assert_eq!(set.choose(0.2499), (0, 0.25));
        assert_eq!(set.choose(0.25), (1, 0.75));
        assert_eq!(set.choose(0.999_999_94), (1, 0.75));
        assert!(LightSet::new(vec![point(0.0)], &[]).is_none());
    }
}
