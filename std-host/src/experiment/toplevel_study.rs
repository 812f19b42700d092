//! The top-level structure's studies: octree levels against containment error and lookup time
//! (the thesis's Figure 11), and the octree against the naive list as areas multiply.

use std::time::Instant;

use rdbvh_core::analyze::containment;
use rdbvh_core::geometry::Aabb;
use rdbvh_core::influence::InfluenceArea;
use rdbvh_core::random::Pcg32;
use rdbvh_core::toplevel::{AreaList, AreaLookup, Octree};
use rdbvh_core::Vec3;

/// Points sampled per containment measurement.
const CONTAINMENT_SAMPLES: u32 = 20_000;
/// Queries per lookup-time measurement.
const LOOKUP_QUERIES: u32 = 100_000;

/// One octree depth's numbers, over every scene's set of areas.
#[derive(Clone, Debug, PartialEq)]
pub struct LevelRow {
    /// Maximum levels.
    pub levels: u32,
    /// False positives over true positives, summed over the scenes.
    pub error: f64,
    /// Mean nanoseconds per "first area containing this point" query.
    pub lookup_ns: f64,
    /// Mean microseconds to build.
    pub build_us: f64,
    /// Mean leaves.
    pub leaves: f64,
    /// Mean bytes.
    pub bytes: f64,
}

/// One area count's numbers.
#[derive(Clone, Debug, PartialEq)]
pub struct CountRow {
    /// Areas.
    pub areas: usize,
    /// Nanoseconds per query with the octree.
    pub octree_ns: f64,
    /// Nanoseconds per query with the list.
    pub list_ns: f64,
    /// The octree's containment error.
    pub octree_error: f64,
}

fn union(areas: &[InfluenceArea]) -> Aabb {
    areas.iter().fold(Aabb::EMPTY, |b, a| b.union(a.bounds()))
}

fn points(bounds: &Aabb, n: u32, seed: u64) -> Vec<Vec3> {
    let mut rng = Pcg32::new(seed);
    (0..n)
        .map(|_| {
            Vec3::new(
                rng.range(bounds.min.x, bounds.max.x),
                rng.range(bounds.min.y, bounds.max.y),
                rng.range(bounds.min.z, bounds.max.z),
            )
        })
        .collect()
}

/// Nanoseconds per query: the lookup's candidates, then the first that really contains the point
/// (what a scene query does before its affinity test).
fn lookup_ns<L: AreaLookup>(lookup: &L, areas: &[InfluenceArea], pts: &[Vec3]) -> f64 {
    let start = Instant::now();
    let mut found = 0usize;
    for &p in pts {
        if lookup
            .candidates(p)
            .iter()
            .any(|&a| areas.get(a as usize).is_some_and(|x| x.contains(p)))
        {
            found += 1;
        }
    }
    std::hint::black_box(found);
    start.elapsed().as_secs_f64() * 1e9 / pts.len().max(1) as f64
}

/// Octree levels 1 to `max_levels` over each set of areas (one set per scene).
pub fn octree_levels(sets: &[Vec<InfluenceArea>], max_levels: u32) -> Vec<LevelRow> {
    let sets: Vec<&Vec<InfluenceArea>> = sets.iter().filter(|s| !s.is_empty()).collect();
    if sets.is_empty() {
        return Vec::new();
    }
    (1..=max_levels)
        .map(|levels| {
            let (mut fp, mut tp) = (0u64, 0u64);
            let (mut ns, mut us, mut leaves, mut bytes) = (0.0, 0.0, 0.0, 0.0);
            for (i, areas) in sets.iter().enumerate() {
                let start = Instant::now();
                let tree = Octree::build(areas, levels);
                us += start.elapsed().as_secs_f64() * 1e6;
                let bounds = union(areas);
                let c = containment(&tree, areas, &bounds, CONTAINMENT_SAMPLES, i as u64 + 1);
                fp += u64::from(c.false_positives);
                tp += u64::from(c.true_positives);
                let pts = points(&bounds, LOOKUP_QUERIES, 99 + i as u64);
                ns += lookup_ns(&tree, areas, &pts);
                let s = tree.stats();
                leaves += f64::from(s.leaves);
                bytes += s.bytes as f64;
            }
            let n = sets.len() as f64;
            LevelRow {
                levels,
                error: if tp > 0 { fp as f64 / tp as f64 } else { 0.0 },
                lookup_ns: ns / n,
                build_us: us / n,
                leaves: leaves / n,
                bytes: bytes / n,
            }
        })
        .collect()
}

/// The octree (of `levels` levels) against the list over the first 1, 2, 4, ... of `areas`.
pub fn octree_vs_list(areas: &[InfluenceArea], levels: u32) -> Vec<CountRow> {
    let mut counts: Vec<usize> = std::iter::successors(Some(1usize), |&n| Some(n * 2))
        .take_while(|&n| n < areas.len())
        .collect();
    if !areas.is_empty() {
        counts.push(areas.len());
    }
    counts
        .into_iter()
        .map(|n| {
            let set = &areas[..n];
            let bounds = union(set);
            let pts = points(&bounds, LOOKUP_QUERIES, n as u64);
            let tree = Octree::build(set, levels);
            let list = AreaList::new(n);
            let c = containment(&tree, set, &bounds, CONTAINMENT_SAMPLES, 5);
            CountRow {
                areas: n,
                octree_ns: lookup_ns(&tree, set, &pts),
                list_ns: lookup_ns(&list, set, &pts),
                octree_error: f64::from(c.error()),
            }
        })
        .collect()
}
