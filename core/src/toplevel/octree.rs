//! An octree over influence areas: constant-time "which areas contain this origin".

use alloc::vec;
use alloc::vec::Vec;

use glam::{Vec3, Vec3A};

use super::AreaLookup;
use crate::geometry::Aabb;
use crate::influence::InfluenceArea;

/// The thesis's default number of levels.
pub const DEFAULT_OCTREE_LEVELS: u32 = 5;

/// The most levels an octree may have (8^10 cells at the finest level is far past useful).
pub const MAX_OCTREE_LEVELS: u32 = 10;

/// An octree node: an inner node's eight children sit at `first..first + 8` (child `i` has the
/// upper half along x when `i & 1`, along y when `i & 2`, along z when `i & 4`); a leaf lists the
/// areas overlapping its cell at `areas[first..first + count]`.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
struct OctNode {
    first: u32,
    /// `u32::MAX` for an inner node.
    count: u32,
}

const INNER: u32 = u32::MAX;

/// What an octree build produced.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub struct OctreeStats {
    /// Levels actually used (the root alone is level 1).
    pub levels: u32,
    /// Nodes.
    pub nodes: u32,
    /// Leaves.
    pub leaves: u32,
    /// Area references stored in the leaves.
    pub references: u32,
    /// Bytes of the node and reference arrays.
    pub bytes: usize,
}

/// An octree over the bounds of a set of influence areas, in flat arrays. A cell stops splitting
/// when every area either covers it entirely or misses it (so its list is exact everywhere in it),
/// or at the maximum level; a leaf lists every area that overlaps its cell by the exact
/// separating-axis test, so the lookup is conservative: a point inside an area always finds it.
#[derive(Clone, Debug, PartialEq)]
pub struct Octree {
    bounds: Aabb,
    nodes: Vec<OctNode>,
    areas: Vec<u32>,
    stats: OctreeStats,
    max_levels: u32,
}

impl Octree {
    /// Builds an octree of at most `max_levels` levels (1 to [`MAX_OCTREE_LEVELS`], clamped) over
    /// `areas`.
    pub fn build(areas: &[InfluenceArea], max_levels: u32) -> Self {
        let max_levels = max_levels.clamp(1, MAX_OCTREE_LEVELS);
        // Every point an area contains, up to its containment tolerance, must fall inside the
        // root cell (a plane area's rays start on its light face, which can round outside the
        // corners' box).
        let bounds = areas.iter().fold(Aabb::EMPTY, |b, a| {
            b.union(a.polytope().containment_bounds())
        });
        let mut tree = Octree {
            bounds,
            nodes: vec![OctNode { first: 0, count: 0 }],
            areas: Vec::new(),
            stats: OctreeStats::default(),
            max_levels,
        };
        if areas.is_empty() || bounds.is_empty() {
            tree.finish(1);
            return tree;
        }
        // Work list of (node, cell, level, candidate areas as a range of `scratch`).
        let mut scratch: Vec<u32> = (0..areas.len() as u32).collect();
        let mut stack = vec![(0usize, bounds, 1u32, 0usize, areas.len())];
        let mut deepest = 1;
        while let Some((node, cell, level, start, end)) = stack.pop() {
            deepest = deepest.max(level);
            let mut overlapping = Vec::new();
            let mut partial = false;
            for &a in &scratch[start..end] {
                let area = &areas[a as usize];
                if area.overlaps_aabb(&cell) {
                    overlapping.push(a);
                    partial |= !covers(area, &cell);
                }
            }
            if !partial || level >= max_levels {
                tree.nodes[node] = OctNode {
                    first: tree.areas.len() as u32,
                    count: overlapping.len() as u32,
                };
                tree.areas.extend_from_slice(&overlapping);
                continue;
            }
            let first = tree.nodes.len();
            tree.nodes[node] = OctNode {
                first: first as u32,
                count: INNER,
            };
            tree.nodes
                .extend(core::iter::repeat_n(OctNode { first: 0, count: 0 }, 8));
            let s = scratch.len();
            scratch.extend_from_slice(&overlapping);
            for child in 0..8 {
                stack.push((
                    first + child,
                    child_cell(&cell, child),
                    level + 1,
                    s,
                    scratch.len(),
                ));
            }
        }
        tree.finish(deepest);
        tree
    }

    fn finish(&mut self, levels: u32) {
        let leaves = self.nodes.iter().filter(|n| n.count != INNER).count() as u32;
        self.stats = OctreeStats {
            levels,
            nodes: self.nodes.len() as u32,
            leaves,
            references: self.areas.len() as u32,
            bytes: self.nodes.len() * core::mem::size_of::<OctNode>() + self.areas.len() * 4,
        };
    }

    /// Levels, node and leaf counts, memory.
    pub fn stats(&self) -> OctreeStats {
        self.stats
    }

    /// The root cell.
    pub fn bounds(&self) -> Aabb {
        self.bounds
    }

    /// The leaf cell holding `p` and its area list (empty outside the root cell).
    pub fn leaf(&self, p: Vec3) -> (Aabb, &[u32]) {
        if !self.bounds.contains_point(p) {
            return (Aabb::EMPTY, &[]);
        }
        // The same cells as `child_cell`, bit for bit: the half at or above the centre, chosen
        // per axis with a select rather than rebuilt from the child index.
        // `Vec3A` keeps the three axes in one SIMD register: a level is a handful of instructions.
        let (mut lo, mut hi) = (Vec3A::from(self.bounds.min), Vec3A::from(self.bounds.max));
        let p = Vec3A::from(p);
        let mut node = self.nodes[0];
        while node.count == INNER {
            let mid = (lo + hi) * 0.5;
            let upper = p.cmpge(mid);
            lo = Vec3A::select(upper, mid, lo);
            hi = Vec3A::select(upper, hi, mid);
            node = self.nodes[node.first as usize + upper.bitmask() as usize];
        }
        let first = node.first as usize;
        let cell = Aabb {
            min: lo.into(),
            max: hi.into(),
        };
        (cell, &self.areas[first..first + node.count as usize])
    }
}

impl AreaLookup for Octree {
    #[inline]
    fn candidates(&self, p: Vec3) -> &[u32] {
        self.leaf(p).1
    }

    fn rebuilt(&self, areas: &[InfluenceArea]) -> Self {
        Octree::build(areas, self.max_levels)
    }

    fn memory_bytes(&self) -> usize {
        self.stats.bytes
    }
}

/// True when the area contains the whole cell: its eight corners (the area is convex).
fn covers(area: &InfluenceArea, cell: &Aabb) -> bool {
    (0..8).all(|i| {
        area.contains(Vec3::new(
            if i & 1 == 0 { cell.min.x } else { cell.max.x },
            if i & 2 == 0 { cell.min.y } else { cell.max.y },
            if i & 4 == 0 { cell.min.z } else { cell.max.z },
        ))
    })
}

/// Child `i` of a cell: the upper half along x when `i & 1`, y when `i & 2`, z when `i & 4`.
#[inline]
fn child_cell(cell: &Aabb, i: usize) -> Aabb {
    let mid = cell.center();
    let pick = |bit: usize, k: usize| {
        if i & bit == 0 {
            (cell.min[k], mid[k])
        } else {
            (mid[k], cell.max[k])
        }
    };
    let (x, y, z) = (pick(1, 0), pick(2, 1), pick(4, 2));
    Aabb::new(Vec3::new(x.0, y.0, z.0), Vec3::new(x.1, y.1, z.1))
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::influence::{PlaneArea, PointArea};
    use crate::random::Pcg32;

    fn areas() -> [InfluenceArea; 3] {
        [
            PlaneArea::new(Vec3::new(5.0, 5.0, -4.0), Vec3::Z, 5.0, 5.0, 20.0)
                .unwrap()
                .into(),
            PlaneArea::new(
                Vec3::new(-3.0, 5.0, -3.0),
                Vec3::new(1.0, 0.0, 1.0),
                7.0,
                5.0,
                20.0,
            )
            .unwrap()
            .into(),
            PointArea::new(
                Vec3::new(10.0, 12.0, -3.0),
                Vec3::new(-0.55, -0.9, 1.0),
                60.0,
                60.0,
                1.0,
                20.0,
            )
            .unwrap()
            .into(),
        ]
    }

    #[test]
    fn conservative_for_sampled_points() {
        let areas = areas();
        for levels in 1..=6 {
            let tree = Octree::build(&areas, levels);
            assert!(tree.stats().levels <= levels);
            let b = tree.bounds();
            let mut rng = Pcg32::new(levels as u64);
            for _ in 0..20_000 {
                let p = Vec3::new(
                    rng.range(b.min.x, b.max.x),
                    rng.range(b.min.y, b.max.y),
                    rng.range(b.min.z, b.max.z),
                );
                let (cell, list) = tree.leaf(p);
                assert!(cell.contains_point(p));
                for (i, a) in areas.iter().enumerate() {
                    if a.contains(p) {
                        assert!(
                            list.contains(&(i as u32)),
                            "levels {levels}: area {i} missing at {p}"
                        );
                    }
                }
            }
        }
    }

    #[test]
    fn finds_every_area_at_its_own_rays_origins() {
        // A plane area's rays start on its light face, which rounding can put a few ulps outside
        // the box of its corners (centre y 0.3, depth 1000: the box's top at 0.29999924): the
        // root cell must still hold them, or the lookup returns no candidate at all.
        let mut rng = Pcg32::new(5);
        let mut checked = 0;
        for i in 0..300 {
            let normal = Vec3::new(rng.range(-1.0, 1.0), -1.0, rng.range(-1.0, 1.0));
            let depth = [1.0, 20.0, 1e3, 1e4][i % 4];
            let half = rng.range(1e-3, 0.1);
            let centre = Vec3::new(rng.range(-0.1, 0.1), 0.3, rng.range(-0.1, 0.1));
            let area: InfluenceArea = PlaneArea::new(centre, normal, half, half, depth)
                .unwrap()
                .into();
            let tree = Octree::build(&[area], 5);
            let mut sampler = crate::influence::RaySampler::new(area, i as u64);
            for _ in 0..50 {
                let ray = sampler.sample();
                if area.contains(ray.origin) {
                    assert_eq!(tree.candidates(ray.origin), &[0], "area {i}: {area:?}");
                    checked += 1;
                }
            }
        }
        assert!(checked > 10_000, "{checked}");
    }

    #[test]
    fn empty_and_outside() {
        let tree = Octree::build(&[], 5);
        assert!(tree.candidates(Vec3::ZERO).is_empty());
        let tree = Octree::build(&areas(), 5);
        assert!(tree.candidates(Vec3::splat(1e6)).is_empty());
        assert!(tree.stats().leaves > 1);
    }
}
