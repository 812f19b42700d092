//! Shadow segments answered together, in the order the structure answers fastest.
//!
//! The integrator traces a batch of paths first, keeping each vertex's shadow segment and what
//! the vertex adds to its path's radiance when the segment is clear ([`PathBatch`]). The
//! structure then answers the batch's segments in its own order ([`Structure::occluded_batch`]):
//! `lights` takes them cell by cell of its light buffers, so that the segments of one cell walk
//! one small tree while it is in the caches, where taken as the paths make them each would find
//! it evicted by the camera and bounce rays traced in between. Last, each path's radiance is
//! summed in the path's own order, the same additions of the same values as when each segment
//! is answered where it is made: the image is the same bit for bit.

use rdbvh_core::bvh::TraversalStats;
use rdbvh_core::geometry::Ray;
use rdbvh_core::Vec3;

use super::integrator::{Gate, PathObserver, PathSink};
use super::{ShadowRay, Structure};

/// Node and triangle tests summed over shadow segments.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub struct ShadowTests {
    /// Inner nodes visited (a light buffer's cell lookup counts as one).
    pub nodes: u64,
    /// Ray/triangle tests.
    pub triangles: u64,
}

impl ShadowTests {
    /// One query's tests.
    pub fn of(stats: &TraversalStats) -> Self {
        Self {
            nodes: u64::from(stats.inner_nodes),
            triangles: u64::from(stats.triangles),
        }
    }

    /// Adds one query's tests.
    #[inline]
    pub fn add(&mut self, stats: &TraversalStats) {
        self.nodes += u64::from(stats.inner_nodes);
        self.triangles += u64::from(stats.triangles);
    }
}

/// A term that no segment gates (a camera ray's emission).
const UNGATED: u32 = u32::MAX;

/// The order a structure answers a batch in, and its scratch: kept from batch to batch, so
/// that answering allocates nothing once the first batches have run.
#[derive(Clone, Debug, Default)]
pub struct BatchOrder {
    /// Per segment, the light buffer cell that answers it, or [`NO_CELL`].
    pub(super) cells: Vec<u32>,
    /// Per segment, its sort key (a cell over all buffers; the last key for no cell).
    pub(super) keys: Vec<u32>,
    /// Per light buffer, the key of its first cell.
    pub(super) bases: Vec<u32>,
    /// Per key, where its segments start in `order`.
    starts: Vec<u32>,
    /// Segment indices in the order to answer them, each with its cell.
    pub(super) order: Vec<(u32, u32)>,
}

/// A segment no light buffer cell answers.
pub(super) const NO_CELL: u32 = u32::MAX;

impl BatchOrder {
    /// Groups the segments by key, keeping their order within a key (a counting sort over
    /// `key_count` keys): `keys` must hold one key below `key_count` per segment, `cells` one
    /// cell.
    pub(super) fn sort_by_keys(&mut self, key_count: usize) {
        self.starts.clear();
        self.starts.resize(key_count + 1, 0);
        for &k in &self.keys {
            self.starts[k as usize + 1] += 1;
        }
        for k in 1..self.starts.len() {
            self.starts[k] += self.starts[k - 1];
        }
        self.order.clear();
        self.order.resize(self.keys.len(), (0, NO_CELL));
        for (i, (&k, &cell)) in self.keys.iter().zip(&self.cells).enumerate() {
            let slot = &mut self.starts[k as usize];
            self.order[*slot as usize] = (i as u32, cell);
            *slot += 1;
        }
    }
}

/// A batch of paths whose shadow segments are not answered yet.
#[derive(Clone, Debug, Default)]
pub struct PathBatch {
    /// The segments, in the order the paths made them, each with its answer once given.
    pub segments: Vec<ShadowRay>,
    /// The segments' node and triangle tests, once answered.
    pub tests: ShadowTests,
    /// The segments answered so far: the first ones.
    answered: usize,
    /// Every segment's answer, by its index: the radiance reads them, not the segments.
    answers: Vec<bool>,
    /// What each vertex adds, in each path's order, and the segment that must be clear for it
    /// ([`UNGATED`] for none).
    terms: Vec<(Vec3, u32)>,
    /// Per path, the end of its terms in `terms`.
    path_ends: Vec<u32>,
    order: BatchOrder,
}

impl PathBatch {
    /// Empties the batch, keeping its memory.
    pub fn clear(&mut self) {
        self.segments.clear();
        self.tests = ShadowTests::default();
        self.answers.clear();
        self.answered = 0;
        self.terms.clear();
        self.path_ends.clear();
    }

    /// Ends the current path: the terms since the last end are its.
    pub(super) fn end_path(&mut self) {
        self.path_ends.push(self.terms.len() as u32);
    }

    /// Answers the deferred segments not answered yet through `structure`, together, in the
    /// order it answers fastest ([`Structure::occluded_batch_counted`]), adding their tests to
    /// `tests`.
    pub fn answer(&mut self, structure: &Structure) {
        let (first, n) = (self.answered, self.segments.len());
        if first >= n {
            return;
        }
        debug_assert_eq!(
            n,
            self.answers.len(),
            "deferred and answered segments mixed"
        );
        structure.occluded_batch_counted(
            &self.segments[first..],
            &mut self.answers[first..],
            &mut self.tests,
            &mut self.order,
        );
        for (s, &a) in self.segments[first..]
            .iter_mut()
            .zip(&self.answers[first..])
        {
            s.occluded = a;
        }
        self.answered = n;
    }

    /// Each path's radiance, in path order, once the batch is answered: its terms summed in
    /// order from zero, each gated one only where its segment is clear.
    pub fn radiance(&self) -> impl Iterator<Item = Vec3> + '_ {
        let mut start = 0;
        self.path_ends.iter().map(move |&end| {
            let mut radiance = Vec3::ZERO;
            for &(value, gate) in &self.terms[start as usize..end as usize] {
                if gate == UNGATED || !self.answers[gate as usize] {
                    radiance += value;
                }
            }
            start = end;
            radiance
        })
    }
}

impl PathSink for PathBatch {
    /// Keeps the segment for [`PathBatch::answer`].
    #[inline(always)]
    fn segment(
        &mut self,
        light: usize,
        ray: Ray,
        _: &Structure,
        _: &mut impl PathObserver,
    ) -> Gate {
        self.segments.push(ShadowRay {
            light: light as u32,
            ray,
            occluded: false,
        });
        self.answers.push(false);
        Gate::Pending((self.answers.len() - 1) as u32)
    }

    #[inline(always)]
    fn term(&mut self, value: Vec3, gate: Gate) {
        let gate = match gate {
            Gate::Open | Gate::Answered { occluded: false } => UNGATED,
            Gate::Answered { occluded: true } => return,
            Gate::Pending(segment) => segment,
        };
        self.terms.push((value, gate));
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn keys_group_segments_in_order() {
        let mut order = BatchOrder::default();
        order.keys.extend([2, 0, 2, 1, 0, 3, 2]);
        order.cells.extend([20, 0, 21, 10, 1, 30, 22]);
        order.sort_by_keys(4);
        let expect = [(1, 0), (4, 1), (3, 10), (0, 20), (2, 21), (6, 22), (5, 30)];
        assert_eq!(order.order, expect);
        order.keys.clear();
        order.cells.clear();
        order.sort_by_keys(4);
        assert!(order.order.is_empty());
    }
}
