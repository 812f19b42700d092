//! Applying a node's chosen split to its primitive slots: by the bin boundary, by a bipartition
//! mask, or at the median when no plane separates the centroids.

use super::arena::{lanes_to_aabb, BuildArena, PrimRefs, Task};
use super::bin_map::*;
use super::cut::*;
use super::exhaustive::partition_by_mask;
use super::partition::{centroid_bounds, swap_misplaced};
use crate::geometry::Aabb;

/// How a node's slots are partitioned by its split.
#[derive(Clone, Copy, Debug)]
pub(super) enum Partition {
    /// By the split's bin boundary along its axis, under this bin map.
    Plane(BinMap),
    /// The primitives (by slot, from the node's first) whose bits are set go left.
    Mask(u32),
}

/// Partitions the node's slots in place by the split's bin boundary. The child boxes come from
/// the bins; the children's centroid bounds from the slots each side ends up with.
pub(super) fn partition(
    arena: &mut BuildArena,
    task: &Task,
    split: &Split,
    map: &BinMap,
) -> (Child, Child) {
    // Finding the threshold costs a few dozen bin evaluations: small nodes classify by bin.
    let at = split.cut.at;
    if task.count <= THRESHOLD_MIN_COUNT {
        partition_by(arena, task, split, |c| map.bin(c) < at)
    } else {
        let threshold = map.threshold(at);
        partition_by(arena, task, split, |c| c < threshold)
    }
}

/// Partitions a node of at most [`super::MAX_EXHAUSTIVE`] slots by the mask of its exhaustive split.
pub(super) fn partition_mask(
    arena: &mut BuildArena,
    task: &Task,
    split: &Split,
    mask: u32,
) -> (Child, Child) {
    let slots = arena
        .refs
        .slots_mut(task.start as usize, task.count as usize);
    let [(l_lo, l_hi), (r_lo, r_hi)] = partition_by_mask(slots, mask);
    let cut = &split.cut;
    (
        (cut.left, cut.n_left, lanes_to_aabb(l_lo, l_hi)),
        (cut.right, cut.n_right, lanes_to_aabb(r_lo, r_hi)),
    )
}

/// Nodes of at least this size are binned into two sets of bins, even and odd slots apart, then
/// merged: neighbouring primitives of a mesh often fall in the same bins, and growing one bin
/// twice in a row waits on the store of the first growth.
pub(super) const DUAL_BINNING_MIN: usize = 256;

/// Nodes above this size partition by [`BinMap::threshold`].
pub(super) const THRESHOLD_MIN_COUNT: u32 = 16;

/// [`partition`] with the classification `goes_left` of a doubled centroid coordinate: the first
/// `n_left` slots take the left-goers ([`swap_misplaced`], Hoare's permutation without a branch
/// per primitive), then each side's centroid bounds are gathered in a pass of its own.
#[inline(always)]
pub(super) fn partition_by(
    arena: &mut BuildArena,
    task: &Task,
    split: &Split,
    goes_left: impl Fn(f32) -> bool,
) -> (Child, Child) {
    let (axis, cut) = (split.axis, &split.cut);
    let slots = arena
        .refs
        .slots_mut(task.start as usize, task.count as usize);
    let (front, back) = slots.split_at_mut(cut.n_left as usize);
    let paired = swap_misplaced(front, back, |r| goes_left(r.centroid2_axis(axis)));
    // The sweep counted the left-goers with the same classification.
    debug_assert!(paired, "the partition disagrees with the bins");
    let ((l_lo, l_hi), (r_lo, r_hi)) = (centroid_bounds(front), centroid_bounds(back));
    (
        (cut.left, cut.n_left, lanes_to_aabb(l_lo, l_hi)),
        (cut.right, cut.n_right, lanes_to_aabb(r_lo, r_hi)),
    )
}

/// Splits the node's slots at their object median along the widest centroid axis (or in index
/// order when all centroids coincide), in place and in O(n) expected time. Both halves get at
/// least one slot, so depth grows by one while the node halves.
pub(super) fn median_split(refs: &mut PrimRefs, task: &Task) -> (Child, Child) {
    let start = task.start as usize;
    let end = start + task.count as usize;
    let mid = start + task.count as usize / 2;
    let axis = task.centroids.largest_axis();
    if task.centroids.extent()[axis] > 0.0 {
        select_nth(refs, start, end, mid, axis);
    }
    let gather = |from: usize, to: usize| {
        (from..to).fold((Aabb::EMPTY, Aabb::EMPTY), |(b, c), i| {
            let pb = refs.bounds(i);
            (b.union(pb), c.grown(pb.min + pb.max))
        })
    };
    let (lb, lc) = gather(start, mid);
    let (rb, rc) = gather(mid, end);
    ((lb, (mid - start) as u32, lc), (rb, (end - mid) as u32, rc))
}

/// Quickselect over slots `[lo, hi)`: afterwards slot `nth` holds the centroid that would be there
/// in sorted order along `axis`, with no larger one before it and no smaller one after it.
/// Iterative, with a median-of-three pivot; equal keys are spread over both sides by the Hoare
/// scheme, so all-equal input still halves.
pub(super) fn select_nth(
    refs: &mut PrimRefs,
    mut lo: usize,
    mut hi: usize,
    nth: usize,
    axis: usize,
) {
    while hi - lo > 1 {
        if hi - lo == 2 {
            if refs.centroid2_axis(lo, axis) > refs.centroid2_axis(lo + 1, axis) {
                refs.swap(lo, lo + 1);
            }
            return;
        }
        let mid = lo + (hi - lo) / 2;
        let (a, b, c) = (
            refs.centroid2_axis(lo, axis),
            refs.centroid2_axis(mid, axis),
            refs.centroid2_axis(hi - 1, axis),
        );
        let pivot = a.max(b.min(c)).min(b.max(c));
        // Hoare partition: [lo, j] <= pivot <= [j + 1, hi).
        let (mut i, mut j) = (lo, hi - 1);
        loop {
            while refs.centroid2_axis(i, axis) < pivot {
                i += 1;
            }
            while refs.centroid2_axis(j, axis) > pivot {
                j -= 1;
            }
            if i >= j {
                break;
            }
            refs.swap(i, j);
            i += 1;
            j -= 1;
        }
        if nth <= j {
            hi = j + 1;
        } else {
            lo = j + 1;
        }
    }
}
