//! How well an area lookup (the octree, or the naive list) approximates the influence areas.

use glam::Vec3;

use crate::geometry::Aabb;
use crate::influence::InfluenceArea;
use crate::random::Pcg32;
use crate::toplevel::AreaLookup;

/// The containment error of an area lookup, from sampled points.
#[derive(Clone, Copy, Debug, Default, PartialEq)]
pub struct Containment {
    /// Points sampled.
    pub samples: u32,
    /// (point, candidate area) pairs where the area contains the point.
    pub true_positives: u32,
    /// (point, candidate area) pairs where it does not: the lookup's cells are coarser than the
    /// areas, so a query will test (and reject) an area that cannot hold the origin.
    pub false_positives: u32,
    /// (point, area) pairs where an area contains the point but the lookup did not name it. A
    /// conservative lookup has none.
    pub false_negatives: u32,
}

impl Containment {
    /// The thesis's error: false positives over true positives (0 when there are no true
    /// positives and no false ones; infinite when there are only false ones).
    pub fn error(&self) -> f32 {
        match (self.false_positives, self.true_positives) {
            (0, _) => 0.0,
            (_, 0) => f32::INFINITY,
            (fp, tp) => fp as f32 / tp as f32,
        }
    }
}

/// Samples `samples` points uniformly in `bounds` (usually the octree's root cell or the union of
/// the areas' bounds) with seed `seed`, and counts, for each, which candidates of `lookup` contain
/// it and which areas it missed.
pub fn containment<L: AreaLookup>(
    lookup: &L,
    areas: &[InfluenceArea],
    bounds: &Aabb,
    samples: u32,
    seed: u64,
) -> Containment {
    let mut out = Containment::default();
    if bounds.is_empty() || !bounds.is_valid() {
        return out;
    }
    let mut rng = Pcg32::new(seed);
    for _ in 0..samples {
        let p = Vec3::new(
            rng.range(bounds.min.x, bounds.max.x),
            rng.range(bounds.min.y, bounds.max.y),
            rng.range(bounds.min.z, bounds.max.z),
        );
        out.samples += 1;
        let candidates = lookup.candidates(p);
        for &a in candidates {
            match areas.get(a as usize) {
                Some(area) if area.contains(p) => out.true_positives += 1,
                _ => out.false_positives += 1,
            }
        }
        for (i, area) in areas.iter().enumerate() {
            if area.contains(p) && !candidates.contains(&(i as u32)) {
                out.false_negatives += 1;
            }
        }
    }
    out
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::influence::PlaneArea;
    use crate::toplevel::{AreaList, Octree};
    use alloc::vec;

    #[test]
    fn error_by_hand_and_octree_is_conservative() {
        // An axis-aligned unit box area is exactly one octree cell: no error at any depth.
        let aligned: InfluenceArea =
            PlaneArea::new(Vec3::new(0.5, 0.5, 0.0), Vec3::Z, 0.5, 0.5, 1.0)
                .unwrap()
                .into();
        let tree = Octree::build(&[aligned], 3);
        let c = containment(&tree, &[aligned], &tree.bounds(), 500, 1);
        assert_eq!(c.samples, 500);
        assert_eq!((c.false_positives, c.false_negatives), (0, 0));
        assert_eq!(c.error(), 0.0);
        // A tilted area inside a bigger sampling box: the list names it everywhere, so its false
        // positives are the sampled points outside it; the octree has fewer, and no misses.
        let tilted: InfluenceArea =
            PlaneArea::new(Vec3::ZERO, Vec3::new(1.0, 1.0, 1.0), 1.0, 1.0, 2.0)
                .unwrap()
                .into();
        let areas = vec![tilted];
        let bounds = tilted.bounds();
        let list = containment(&AreaList::new(1), &areas, &bounds, 2000, 7);
        assert_eq!(list.true_positives + list.false_positives, 2000);
        let tree = Octree::build(&areas, 5);
        let oct = containment(&tree, &areas, &bounds, 2000, 7);
        assert_eq!(oct.false_negatives, 0);
        assert_eq!(oct.true_positives, list.true_positives);
        assert!(oct.error() < list.error(), "{oct:?} vs {list:?}");
        let c = Containment {
            samples: 4,
            true_positives: 4,
            false_positives: 1,
            false_negatives: 0,
        };
        assert!((c.error() - 0.25).abs() < 1e-6);
    }
}
