//! What a composite structure needs of a hierarchy: one trait over the binary and the 4-wide
//! BVH, so a [`crate::toplevel::TopLevel`]'s local and fallback trees can be either, statically
//! dispatched.

use super::{Bvh, Hit, Lanes, TraversalStats, WideBvhN, Width};
use crate::geometry::{Ray, Triangle, Triangle4};

/// Closest-hit and any-hit queries over the triangles a hierarchy was built from, with the work
/// counted, and its size. Implemented by [`Bvh`] and [`super::WideBvh`] (and `WideBvh8`); both answer exactly as brute
/// force does, so a scene answers the same with either.
pub trait Traversable {
    /// The closest hit on `[ray.t_min, ray.t_max]`, adding the work to `stats`.
    fn closest_hit_with_stats(
        &self,
        ray: &Ray,
        tris: &[Triangle],
        stats: &mut TraversalStats,
    ) -> Option<Hit>;

    /// True when anything is hit on the segment, adding the work to `stats`.
    fn any_hit_with_stats(&self, ray: &Ray, tris: &[Triangle], stats: &mut TraversalStats) -> bool;

    /// The closest hit, without counting (the implementations' counters then compile away).
    fn closest_hit(&self, ray: &Ray, tris: &[Triangle]) -> Option<Hit> {
        self.closest_hit_with_stats(ray, tris, &mut TraversalStats::default())
    }

    /// True when anything is hit, without counting.
    fn any_hit(&self, ray: &Ray, tris: &[Triangle]) -> bool {
        self.any_hit_with_stats(ray, tris, &mut TraversalStats::default())
    }

    /// How many primitives the hierarchy holds.
    fn prim_count(&self) -> usize;

    /// Bytes of its arrays.
    fn memory_bytes(&self) -> usize;
}

impl Traversable for Bvh {
    #[inline]
    fn closest_hit_with_stats(
        &self,
        ray: &Ray,
        tris: &[Triangle],
        stats: &mut TraversalStats,
    ) -> Option<Hit> {
        Bvh::closest_hit_with_stats(self, ray, tris, stats)
    }

    #[inline]
    fn any_hit_with_stats(&self, ray: &Ray, tris: &[Triangle], stats: &mut TraversalStats) -> bool {
        Bvh::any_hit_with_stats(self, ray, tris, stats)
    }

    #[inline]
    fn closest_hit(&self, ray: &Ray, tris: &[Triangle]) -> Option<Hit> {
        Bvh::closest_hit(self, ray, tris)
    }

    #[inline]
    fn any_hit(&self, ray: &Ray, tris: &[Triangle]) -> bool {
        Bvh::any_hit(self, ray, tris)
    }

    fn prim_count(&self) -> usize {
        self.prim_indices().len()
    }

    fn memory_bytes(&self) -> usize {
        Bvh::memory_bytes(self)
    }
}

/// The wide tree answers from its own copy of the triangles (made by [`WideBvhN::from_binary`]
/// from the array the scene passes here), so it ignores `tris`.
impl<const W: usize> Traversable for WideBvhN<W>
where
    Width<W>: Lanes<W>,
{
    #[inline]
    fn closest_hit_with_stats(
        &self,
        ray: &Ray,
        _tris: &[Triangle],
        stats: &mut TraversalStats,
    ) -> Option<Hit> {
        WideBvhN::closest_hit_with_stats(self, ray, stats)
    }

    #[inline]
    fn any_hit_with_stats(
        &self,
        ray: &Ray,
        _tris: &[Triangle],
        stats: &mut TraversalStats,
    ) -> bool {
        WideBvhN::any_hit_with_stats(self, ray, stats)
    }

    #[inline]
    fn closest_hit(&self, ray: &Ray, _tris: &[Triangle]) -> Option<Hit> {
        WideBvhN::closest_hit(self, ray)
    }

    #[inline]
    fn any_hit(&self, ray: &Ray, _tris: &[Triangle]) -> bool {
        WideBvhN::any_hit(self, ray)
    }

    fn prim_count(&self) -> usize {
        self.triangles()
            .iter()
            .flat_map(|b| b.id)
            .filter(|&id| id != Triangle4::UNUSED_ID)
            .count()
    }

    fn memory_bytes(&self) -> usize {
        WideBvhN::memory_bytes(self)
    }
}
