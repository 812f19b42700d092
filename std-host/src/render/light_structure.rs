//! The `lights` structure's light buffers: which lights get one, and building them.
//!
//! Point, spot and quad lights get a buffer each. Emissive triangles are grouped, per material,
//! into clusters no wider than [`CLUSTER_EXTENT`] of the scene's diagonal (a window pane, a lamp),
//! and each cluster gets one buffer over the box of its triangles: a buffer per triangle would
//! repeat the same cells thousands of times over a tessellated light. At most
//! [`MAX_LIGHT_BUFFERS`] buffers are built, for the most powerful lights; the rest use the
//! global BVH.

use rayon::prelude::*;
use rdbvh_core::bvh::WideBvh8;
use rdbvh_core::geometry::{Aabb, Triangle};
use rdbvh_core::light_buffer::{LightBuffer, LightBufferBuilder, LightBufferOptions, LightSource};
use rdbvh_core::Vec3;

use super::structure::NO_BUFFER;
use super::{Light, RenderError};

/// The most light buffers a structure builds. Each costs about one BVH build over the scene.
pub const MAX_LIGHT_BUFFERS: usize = 32;

/// The widest cluster of emissive triangles, as a fraction of the scene's diagonal.
pub const CLUSTER_EXTENT: f32 = 0.25;

/// The most clusters formed before the remaining emissive triangles go without a buffer, which
/// bounds the clustering's quadratic search.
const MAX_CLUSTERS: usize = 4096;

/// A group of lights that share one buffer (or, for `thesis`, one set of influence areas).
pub(super) struct Group {
    pub(super) lights: Vec<u32>,
    /// The emissive triangles' vertices, three a triangle.
    pub(super) points: Vec<Vec3>,
    bounds: Aabb,
    /// The group's emissive material (none for a light from the lights file).
    material: Option<Vec3>,
    pub(super) power: f64,
    /// The light from the lights file, whose own source (cone, front) is kept.
    pub(super) single: Option<Light>,
}

/// The light buffers for `lights` over `triangles` and their global BVH `global`, built on the
/// current rayon pool (every face of every buffer in parallel), and per light the index of its
/// buffer or `NO_BUFFER`.
pub(super) fn light_buffers(
    triangles: &[Triangle],
    global: &WideBvh8,
    lights: &[Light],
) -> Result<(Vec<LightBuffer>, Vec<u32>), RenderError> {
    let groups = light_groups(triangles, lights);
    build_buffers(
        triangles,
        global,
        &groups.iter().collect::<Vec<_>>(),
        lights.len(),
    )
}

/// The groups that may get a buffer: every light from the lights file, emissive triangles
/// clustered, the [`MAX_LIGHT_BUFFERS`] most powerful.
pub(super) fn light_groups(triangles: &[Triangle], lights: &[Light]) -> Vec<Group> {
    let mut groups = group(triangles, lights);
    groups.sort_by(|a, b| b.power.total_cmp(&a.power));
    groups.truncate(MAX_LIGHT_BUFFERS);
    groups
}

/// The buffers of `groups` over `triangles` and their global BVH `global` (whose leaves the
/// buffers' trees name), built on the current rayon pool (every face of every buffer in
/// parallel), and per light (of `light_count`) the index of its buffer or `NO_BUFFER`.
pub(super) fn build_buffers(
    triangles: &[Triangle],
    global: &WideBvh8,
    groups: &[&Group],
    light_count: usize,
) -> Result<(Vec<LightBuffer>, Vec<u32>), RenderError> {
    let options = LightBufferOptions::default();
    let builders = groups
        .iter()
        .map(|g| {
            let source = match &g.single {
                Some(light) => light.source(triangles)?,
                None => LightSource::polygon(&g.points, None)?,
            };
            Ok(LightBufferBuilder::new(
                triangles, global, source, &options,
            )?)
        })
        .collect::<Result<Vec<_>, RenderError>>()?;
    let faces = (0..builders.len() * LightBufferBuilder::FACES)
        .into_par_iter()
        .map(|i| builders[i / LightBufferBuilder::FACES].face(i % LightBufferBuilder::FACES))
        .collect::<Result<Vec<_>, _>>()?;
    let mut faces = faces.into_iter();
    let buffers = builders
        .into_iter()
        .map(|b| b.finish(faces.by_ref().take(LightBufferBuilder::FACES)))
        .collect::<Result<Vec<_>, _>>()?;
    let mut buffer_of = vec![NO_BUFFER; light_count];
    for (b, g) in groups.iter().enumerate() {
        for &l in &g.lights {
            buffer_of[l as usize] = b as u32;
        }
    }
    Ok((buffers, buffer_of))
}

impl Group {
    /// The light's width: the diagonal of its emissive triangles' box, a quad's longer
    /// diagonal, 0 for a point or spot light.
    pub(super) fn extent(&self) -> f32 {
        match self.single {
            Some(Light::Quad { edge1, edge2, .. }) => {
                (edge1 + edge2).length().max((edge1 - edge2).length())
            }
            Some(_) => 0.0,
            None => (self.bounds.max - self.bounds.min).length(),
        }
    }
}

/// Every light from the lights file alone; emissive triangles clustered per material.
fn group(triangles: &[Triangle], lights: &[Light]) -> Vec<Group> {
    let scene = triangles
        .iter()
        .fold(Aabb::EMPTY, |b, t| b.union(t.bounds()));
    let limit = CLUSTER_EXTENT * (scene.max - scene.min).length();
    let mut groups: Vec<Group> = Vec::new();
    for (i, light) in lights.iter().enumerate() {
        let power = light.power(triangles);
        let Light::Emissive { triangle, radiance } = *light else {
            groups.push(Group {
                lights: vec![i as u32],
                points: Vec::new(),
                bounds: Aabb::EMPTY,
                material: None,
                power,
                single: Some(*light),
            });
            continue;
        };
        let t = &triangles[triangle as usize];
        let bounds = t.bounds();
        let fits = |g: &Group| {
            let u = g.bounds.union(bounds);
            g.material == Some(radiance) && (u.max - u.min).length() <= limit
        };
        let group = match groups.iter().position(fits) {
            Some(g) => &mut groups[g],
            None if groups.len() < MAX_CLUSTERS => {
                groups.push(Group {
                    lights: Vec::new(),
                    points: Vec::new(),
                    bounds: Aabb::EMPTY,
                    material: Some(radiance),
                    power: 0.0,
                    single: None,
                });
                groups.last_mut().expect("just pushed")
            }
            None => continue,
        };
        group.lights.push(i as u32);
        group.points.extend([t.v0, t.v1, t.v2]);
        group.bounds = group.bounds.union(bounds);
        group.power += power;
    }
    groups
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn emissive_triangles_cluster_by_material_and_distance() {
        let tri = |x: f32| {
            Triangle::new(
                Vec3::new(x, 0.0, 0.0),
                Vec3::new(x + 0.1, 0.0, 0.0),
                Vec3::new(x, 0.1, 0.0),
            )
        };
        // Two neighbours, one far away: the scene spans 10 units, clusters at most 2.5.
        let triangles = [tri(0.0), tri(0.2), tri(9.9)];
        let emissive = |t: u32, r: f32| Light::Emissive {
            triangle: t,
            radiance: Vec3::splat(r),
        };
        let lights = [
            emissive(0, 1.0),
            emissive(1, 1.0),
            emissive(2, 1.0),
            Light::Point {
                position: Vec3::ONE,
                intensity: Vec3::ONE,
            },
        ];
        let groups = group(&triangles, &lights);
        let members: Vec<Vec<u32>> = groups.iter().map(|g| g.lights.clone()).collect();
        assert_eq!(members, vec![vec![0, 1], vec![2], vec![3]]);
        // Another material does not join.
        let lights = [emissive(0, 1.0), emissive(1, 2.0)];
        assert_eq!(group(&triangles, &lights).len(), 2);
    }
}
