//! The brute-force oracle: every query answered by testing every triangle. Every acceleration
//! structure in this crate is tested against it.

use crate::bvh::Hit;
use crate::geometry::{Ray, Triangle};

/// The closest hit over all triangles, with the same tie rule as the BVH traversals
/// ([`Hit::is_closer_than`]).
pub fn closest_hit(ray: &Ray, tris: &[Triangle]) -> Option<Hit> {
    let mut best: Option<Hit> = None;
    for (id, tri) in tris.iter().enumerate() {
        let t_max = best.map_or(ray.t_max, |h| h.t);
        if let Some(h) = tri.intersect(ray, t_max) {
            let hit = Hit {
                t: h.t,
                triangle: id as u32,
                u: h.u,
                v: h.v,
            };
            if best.is_none_or(|b| hit.is_closer_than(&b)) {
                best = Some(hit);
            }
        }
    }
    best
}

/// True when any triangle is hit on `[ray.t_min, ray.t_max]`.
pub fn any_hit(ray: &Ray, tris: &[Triangle]) -> bool {
    tris.iter().any(|t| t.intersect(ray, ray.t_max).is_some())
}

/// How many triangles the segment hits.
pub fn hit_count(ray: &Ray, tris: &[Triangle]) -> u32 {
    tris.iter()
        .filter(|t| t.intersect(ray, ray.t_max).is_some())
        .count() as u32
}
