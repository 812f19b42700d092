//! The `thesis` structure: the thesis's own top level (influence areas with PAH local BVHs, an
//! octree over the areas, a fallback BVH), its areas made from the renderer's lights.
//!
//! # Areas
//!
//! - A **point light** radiates every way, and one frustum covers less than a half-space, so it
//!   gets six: one per face of the cube around it (90 x 90 degrees each, apex at the light,
//!   `near` 0, `far` where the scene's bounds end along the face's axis). Together they cover
//!   every receiver, and each face's local BVH is priced by the perspective PAH from the light.
//! - A **spot light** whose cone fits in 120 degrees gets one frustum along its axis whose square
//!   window holds the cone; a wider spot gets the six faces of a point light.
//! - A **quad light** and a **cluster of emissive triangles** get an oriented box (`PlaneArea`):
//!   the light's rectangle in its frame, swept along its normal to the scene's bounds. Emissive
//!   triangles emit from both faces, so a cluster gets a box on each side.
//!
//! # Queries
//!
//! The thesis's areas describe rays *leaving* the light; a shadow segment runs from a receiver
//! *toward* it, so the structure reads affinity backwards: a segment is affine to an area when
//! its origin is inside and its reversed direction is the area's direction there (within the
//! thesis's 1 degree for a frustum, whose shadow segments are radial to rounding; for a box, any
//! segment that ends inside it, since segments toward an area light converge rather than run
//! parallel, and a box is convex, so the whole segment is inside). Tracing the reversed segment
//! instead would change the triangle tests' rounding, and the answers must be the global BVH's
//! bit for bit. The rest is [`TopLevel::any_hit`]'s rule: the first affine area's local BVH
//! answers the segment up to where it leaves the area (`t_exit`), and the fallback BVH the rest
//! from just before `t_exit`; the local BVH holds every triangle the area touches (the exact,
//! conservative separating-axis test), so every answer is the global BVH's. The fallback BVH is
//! the global BVH itself: building another SAH tree would only add build time.

use rayon::prelude::*;
use rdbvh_core::builder::BuildArena;
use rdbvh_core::bvh::{TraversalStats, WideBvh8};
use rdbvh_core::geometry::{Aabb, Frame, Ray, Triangle};
use rdbvh_core::influence::{InfluenceArea, PlaneArea, PointArea, DEFAULT_AFFINITY_DEG};
use rdbvh_core::toplevel::{
    AreaLookup, Octree, TopLevel, TopLevelError, TopLevelOptions, DEFAULT_OCTREE_LEVELS,
};
use rdbvh_core::Vec3;

use super::light_structure::{light_groups, Group};
use super::{Light, RenderError};

/// How far before an area's exit the fallback search starts, relative to the exit distance (as
/// in [`TopLevel::any_hit`]): a hit at the boundary cannot fall between the two searches.
const EXIT_OVERLAP: f32 = 1e-5;

/// The widest spot cone (full angle, degrees) that gets one frustum; wider ones get six.
const MAX_SPOT_FRUSTUM_DEG: f32 = 120.0;

/// Areas and far planes reach this share of the scene's diagonal past its bounds, so that a
/// receiver on the bounds is inside.
const REACH_PAD: f32 = 1e-3;

/// The thesis's structure over the renderer's lights.
#[derive(Clone, Debug)]
pub struct ThesisStructure {
    top: TopLevel<Octree, WideBvh8>,
    cos_point: f32,
}

/// What the structure's areas are and hold, for the report.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub struct ThesisSummary {
    /// Frustums (point and spot lights).
    pub point_areas: usize,
    /// Oriented boxes (quad lights, emissive clusters).
    pub plane_areas: usize,
    /// Triangles over every local BVH (a triangle in two areas counts twice).
    pub local_triangles: u64,
}

impl ThesisStructure {
    /// Builds the areas of `lights` over `triangles`, their local BVHs (the `pah` preset, the
    /// default of [`TopLevelOptions`]) on the current rayon pool, and the octree; `global` becomes
    /// the fallback BVH.
    pub fn build(
        triangles: &[Triangle],
        lights: &[Light],
        global: WideBvh8,
    ) -> Result<Self, RenderError> {
        let scene = triangles
            .iter()
            .fold(Aabb::EMPTY, |b, t| b.union(t.bounds()));
        let groups = light_groups(triangles, lights);
        let areas: Vec<InfluenceArea> = groups.iter().flat_map(|g| areas_of(g, scene)).collect();
        let options = TopLevelOptions::default().local;
        let built = areas
            .par_iter()
            .enumerate()
            .map(|(i, area)| {
                let ids: Vec<u32> = area.triangles_in(triangles).collect();
                if ids.is_empty() {
                    return Ok(None);
                }
                let fail = |error| TopLevelError::Local {
                    area: i as u32,
                    error,
                };
                let mut arena = BuildArena::with_capacity(ids.len());
                arena
                    .load_triangle_subset(triangles, ids)
                    .map_err(|e| fail(e.into()))?;
                let bvh = options.build_loaded(&mut arena, Some(area)).map_err(fail)?;
                Ok(Some(WideBvh8::from_binary(&bvh, triangles)))
            })
            .collect::<Result<Vec<_>, TopLevelError>>()
            .map_err(RenderError::Thesis)?;
        // An area that touches no triangle has nothing to answer locally: it goes, and its
        // segments use the fallback BVH.
        let (areas, local): (Vec<_>, Vec<_>) = areas
            .into_iter()
            .zip(built)
            .filter_map(|(a, b)| Some((a, b?)))
            .unzip();
        let lookup = Octree::build(&areas, DEFAULT_OCTREE_LEVELS);
        let top = TopLevel::from_parts(areas, local, global, lookup, 1)
            .expect("one local BVH per area by construction");
        Ok(Self {
            top,
            cos_point: DEFAULT_AFFINITY_DEG.to_radians().cos(),
        })
    }

    /// The fallback BVH (the global BVH).
    pub fn fallback(&self) -> &WideBvh8 {
        self.top.fallback()
    }

    /// The areas and what their local BVHs hold.
    pub fn summary(&self) -> ThesisSummary {
        let areas = self.top.areas();
        let point_areas = areas
            .iter()
            .filter(|a| matches!(a, InfluenceArea::Point(_)))
            .count();
        ThesisSummary {
            point_areas,
            plane_areas: areas.len() - point_areas,
            local_triangles: self
                .top
                .triangles_per_area()
                .iter()
                .map(|&n| u64::from(n))
                .sum(),
        }
    }

    /// True when `ray`, a shadow segment toward a light, is affine to `area` read backwards
    /// (see the module's doc).
    #[inline]
    fn toward(&self, area: &InfluenceArea, ray: &Ray) -> bool {
        match area {
            InfluenceArea::Point(a) => {
                let Some(d) = ray.dir.try_normalize() else {
                    return false;
                };
                (-d).dot(a.direction_at(ray.origin)) >= self.cos_point && a.contains(ray.origin)
            }
            InfluenceArea::Plane(a) => {
                ray.dir.dot(a.frame.forward) < 0.0
                    && a.contains(ray.origin)
                    && a.contains(ray.at(ray.t_max))
            }
        }
    }

    /// Whether anything blocks the shadow segment `ray`, exactly as the global BVH says,
    /// counting tests in `stats` (the octree lookup counts as one inner node).
    #[inline]
    pub fn occluded_counted(&self, ray: &Ray, stats: &mut TraversalStats) -> bool {
        stats.inner_nodes += 1;
        let mut searched_to = ray.t_min;
        let areas = self.top.areas();
        for &a in self.top.lookup().candidates(ray.origin) {
            let area = &areas[a as usize];
            if !self.toward(area, ray) {
                continue;
            }
            // As in `TopLevel::any_hit`: the local BVH answers the part inside the area, and
            // only if the segment starts inside it (to the containment tolerance).
            let Some((t0, t1)) = area.polytope().clip_ray(ray) else {
                continue;
            };
            let scale = area.polytope().scale.max(ray.origin.abs().max_element());
            if t0 > ray.t_min + 1e-5 * scale / ray.dir.length() {
                continue;
            }
            let mut segment = *ray;
            segment.t_max = t1;
            if self.top.local_bvhs()[a as usize].any_hit_with_stats(&segment, stats) {
                return true;
            }
            // The clip ended at the segment's own end, inside the area: the local BVH searched
            // all of it, and nothing is left for the fallback.
            if t1 >= ray.t_max {
                return false;
            }
            searched_to = t1 - t1.abs() * EXIT_OVERLAP;
            // The thesis tries one affine area.
            break;
        }
        let mut rest = *ray;
        rest.t_min = searched_to;
        self.top.fallback().any_hit_with_stats(&rest, stats)
    }

    /// [`ThesisStructure::occluded_counted`] without the counts kept.
    #[inline]
    pub fn occluded(&self, ray: &Ray) -> bool {
        self.occluded_counted(ray, &mut TraversalStats::default())
    }
}

/// The influence areas of one light group over a scene of bounds `scene`.
fn areas_of(g: &Group, scene: Aabb) -> Vec<InfluenceArea> {
    let pad = REACH_PAD * (scene.max - scene.min).length();
    match g.single {
        Some(Light::Point { position, .. }) => cube_faces(position, scene, pad),
        Some(Light::Spot {
            position,
            direction,
            half_angle,
            ..
        }) => {
            let fov = 2.0 * half_angle.to_degrees();
            if fov > MAX_SPOT_FRUSTUM_DEG {
                return cube_faces(position, scene, pad);
            }
            // A square window of half-angle `half_angle` holds the round cone; a degree more
            // keeps the cone's edge off the frustum's planes.
            frustum(position, direction, fov + 1.0, scene, pad)
                .into_iter()
                .collect()
        }
        Some(Light::Quad {
            corner,
            edge1,
            edge2,
            ..
        }) => {
            let points = [
                corner,
                corner + edge1,
                corner + edge2,
                corner + edge1 + edge2,
            ];
            plane_box(&points, edge1.cross(edge2), scene, pad)
                .into_iter()
                .collect()
        }
        Some(Light::Emissive { .. }) | None => {
            // The cluster's normal: its triangles' area-weighted normals, turned to agree with
            // the first (OBJ winding is not reliable); both sides emit.
            let tris = g.points.chunks_exact(3);
            let first = tris
                .clone()
                .map(|p| (p[1] - p[0]).cross(p[2] - p[0]))
                .find(|n| n.length_squared() > 0.0);
            let Some(first) = first else {
                return Vec::new();
            };
            let normal = tris
                .map(|p| (p[1] - p[0]).cross(p[2] - p[0]))
                .fold(Vec3::ZERO, |s, n| s + n * n.dot(first).signum());
            [normal, -normal]
                .into_iter()
                .filter_map(|n| plane_box(&g.points, n, scene, pad))
                .collect()
        }
    }
}

/// The six 90-degree frustums around `eye`, those that see part of the scene.
fn cube_faces(eye: Vec3, scene: Aabb, pad: f32) -> Vec<InfluenceArea> {
    [Vec3::X, -Vec3::X, Vec3::Y, -Vec3::Y, Vec3::Z, -Vec3::Z]
        .into_iter()
        .filter_map(|axis| frustum(eye, axis, 90.0, scene, pad))
        .collect()
}

/// A square frustum of `fov_deg` from `eye` along `dir`, from `near` 0 to the scene's far end,
/// or `None` when the scene is wholly behind it.
fn frustum(eye: Vec3, dir: Vec3, fov_deg: f32, scene: Aabb, pad: f32) -> Option<InfluenceArea> {
    let dir = dir.try_normalize()?;
    let far = corners(scene)
        .iter()
        .map(|c| (*c - eye).dot(dir))
        .fold(f32::NEG_INFINITY, f32::max);
    if far.is_nan() || far <= 0.0 {
        return None;
    }
    PointArea::new(eye, dir, fov_deg, fov_deg, 0.0, far + pad)
        .ok()
        .map(InfluenceArea::from)
}

/// An oriented box over the light `points`, facing `normal`, swept to the scene's far end along
/// it; `None` when the normal is zero or the scene is wholly behind the light.
fn plane_box(points: &[Vec3], normal: Vec3, scene: Aabb, pad: f32) -> Option<InfluenceArea> {
    let frame = Frame::look_at(normal)?;
    let local: Vec<Vec3> = points.iter().map(|p| frame.to_local(*p)).collect();
    let lo = local
        .iter()
        .fold(Vec3::splat(f32::INFINITY), |a, p| a.min(*p));
    let hi = local
        .iter()
        .fold(Vec3::splat(f32::NEG_INFINITY), |a, p| a.max(*p));
    // The window starts just behind the light's rearmost point, so every point of the light is
    // inside the box.
    let start = lo.z - pad;
    let centre = frame.to_world(Vec3::new(0.5 * (lo.x + hi.x), 0.5 * (lo.y + hi.y), start));
    let far = corners(scene)
        .iter()
        .map(|c| frame.to_local(*c).z)
        .fold(f32::NEG_INFINITY, f32::max);
    let depth = far + pad - start;
    if far.is_nan() || far <= hi.z {
        return None;
    }
    let half = |k: usize| 0.5 * (hi[k] - lo[k]) + pad;
    PlaneArea::new(centre, normal, half(0), half(1), depth)
        .ok()
        .map(InfluenceArea::from)
}

/// The eight corners of `b`.
fn corners(b: Aabb) -> [Vec3; 8] {
    std::array::from_fn(|i| {
        Vec3::new(
            if i & 1 == 0 { b.min.x } else { b.max.x },
            if i & 2 == 0 { b.min.y } else { b.max.y },
            if i & 4 == 0 { b.min.z } else { b.max.z },
        )
    })
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::scene::Scene;
    use rdbvh_core::brute_force;
    use rdbvh_core::builder::Builder;
    use rdbvh_core::random::Pcg32;

    /// Shadow segments toward every light, from points on the room's triangles and inside it,
    /// answer exactly as brute force and the global BVH, and the local BVHs take most of them.
    #[test]
    fn shadow_answers_equal_brute_force_for_every_light_kind() {
        let scene = Scene::open("builtin:room").unwrap();
        let tris = &scene.triangles;
        let spot = |half_deg: f32| {
            let half_angle = half_deg.to_radians();
            Light::Spot {
                position: Vec3::new(2.0, 9.5, 3.0),
                direction: Vec3::new(0.2, -1.0, 0.1).normalize(),
                half_angle,
                cos_half_angle: half_angle.cos(),
                intensity: Vec3::ONE,
            }
        };
        let lights = [
            Light::Point {
                position: Vec3::new(5.0, 8.0, 5.0),
                intensity: Vec3::ONE,
            },
            spot(30.0),
            spot(80.0),
            Light::Quad {
                corner: Vec3::new(7.0, 9.9, 7.0),
                edge1: Vec3::new(1.0, 0.0, 0.0),
                edge2: Vec3::new(0.0, 0.0, 1.0),
                radiance: Vec3::ONE,
            },
        ];
        let global = WideBvh8::from_binary(&Builder::sah().build(tris).unwrap(), tris);
        let thesis = ThesisStructure::build(tris, &lights, global.clone()).unwrap();
        let summary = thesis.summary();
        // 6 faces + 1 narrow spot + 6 faces of the wide spot (those seeing the room) + 1 box.
        assert!(summary.point_areas >= 10, "{summary:?}");
        assert_eq!(summary.plane_areas, 1, "the quad faces -y: one box");
        let mut rng = Pcg32::new(11);
        let (mut local, mut total) = (0u32, 0u32);
        for i in 0..6000 {
            let origin = if i % 2 == 0 {
                let t = &tris[rng.next_u32() as usize % tris.len()];
                let (u, v) = (rng.range(0.0, 1.0), rng.range(0.0, 1.0));
                let (u, v) = if u + v > 1.0 {
                    (1.0 - u, 1.0 - v)
                } else {
                    (u, v)
                };
                t.v0 + (t.v1 - t.v0) * u + (t.v2 - t.v0) * v
            } else {
                Vec3::new(
                    rng.range(0.0, 10.0),
                    rng.range(0.0, 10.0),
                    rng.range(0.0, 10.0),
                )
            };
            let target = match lights[i % lights.len()] {
                Light::Point { position, .. } | Light::Spot { position, .. } => position,
                Light::Quad {
                    corner,
                    edge1,
                    edge2,
                    ..
                } => corner + edge1 * rng.range(0.0, 1.0) + edge2 * rng.range(0.0, 1.0),
                Light::Emissive { .. } => unreachable!(),
            };
            let Ok(ray) = Ray::segment(origin, target - origin, 0.0, 1.0 - 1e-4) else {
                continue;
            };
            let expect = brute_force::any_hit(&ray, tris);
            assert_eq!(global.any_hit(&ray), expect);
            let mut stats = TraversalStats::default();
            assert_eq!(thesis.occluded_counted(&ray, &mut stats), expect, "{ray:?}");
            let mut through_global = TraversalStats::default();
            global.any_hit_with_stats(&ray, &mut through_global);
            total += 1;
            local += u32::from(stats.inner_nodes < through_global.inner_nodes + 1);
        }
        assert!(
            local > total / 2,
            "{local} of {total} cheaper than the global BVH"
        );
    }
}
