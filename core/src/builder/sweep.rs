//! Sweeps: the cheapest boundary of a binned axis under a cost model, SoA lanes priced four at a
//! time, and the two-level bin pair of the dual binning.

use super::arena::{Bin, BuildArena, Sweep, Task};
use super::bin_map::*;
use super::cut::*;
use super::keys::cheapest_lane;
use crate::heuristics::CostModel;
use crate::simd::Aabb4;
use wide::f32x4;

/// The cheapest boundary of one binned axis under `model`. A suffix and a prefix pass write the
/// boxes and counts on both sides of every boundary into SoA scratch lanes; the boundaries are
/// then priced four at a time with [`CostModel::measure4`]. O(bins), no allocation.
///
/// The usual bin counts get a copy each with the count a constant, so the passes unroll without
/// bounds checks; most nodes are small, and there this loop overhead is most of the sweep.
pub(super) fn sweep_axis<M: CostModel>(
    bins: &[Bin],
    sweep: &mut Sweep,
    model: &M,
    hint: u32,
) -> Option<Cut> {
    match bins.len() {
        4 => sweep_bins::<M, 4>(bins[..4].try_into().ok()?, sweep, model, hint),
        8 => sweep_bins::<M, 8>(bins[..8].try_into().ok()?, sweep, model, hint),
        12 => sweep_bins::<M, 12>(bins[..12].try_into().ok()?, sweep, model, hint),
        16 => sweep_bins::<M, 16>(bins[..16].try_into().ok()?, sweep, model, hint),
        _ => sweep_any(bins, sweep, model, hint),
    }
}

#[inline(always)]
pub(super) fn sweep_bins<M: CostModel, const NB: usize>(
    bins: &[Bin; NB],
    sweep: &mut Sweep,
    model: &M,
    hint: u32,
) -> Option<Cut> {
    sweep_any(bins, sweep, model, hint)
}

#[inline(always)]
pub(super) fn sweep_any<M: CostModel>(
    bins: &[Bin],
    sweep: &mut Sweep,
    model: &M,
    hint: u32,
) -> Option<Cut> {
    let nb = bins.len();
    // Boundary i (1..nb) separates bins[..i] from bins[i..]; lanes past nb - 1 get empty sides.
    let mut acc = Bin::EMPTY;
    for i in (1..nb).rev() {
        acc.merge(&bins[i]);
        sweep.right.set(i, &acc);
    }
    acc = Bin::EMPTY;
    for i in 1..nb {
        acc.merge(&bins[i - 1]);
        sweep.left.set(i, &acc);
    }
    // Lanes past the last boundary, up to the end of its group of four: empty on both sides, so
    // they price as +inf (no primitive on the right) and never hold a box left by an earlier,
    // wider sweep, which a reused arena and a fresh one (a threaded job's) would not share.
    for i in nb..=(nb - 1).div_ceil(4) * 4 {
        sweep.left.set(i, &Bin::EMPTY);
        sweep.right.set(i, &Bin::EMPTY);
    }
    // The cheapest boundary per lane, then across lanes. Boundaries with an empty side, and the
    // padding lanes past the last boundary (count 0), price as +inf. Strict `<` keeps the first
    // of equal prices in each lane, and the final reduction the lowest boundary among them, so
    // ties always go to the lowest boundary.
    let inf = f32x4::splat(f32::INFINITY);
    let zero = f32x4::ZERO;
    let (mut best_w, mut best_i) = (inf, f32x4::splat(-1.0));
    let (mut best_ml, mut best_mr) = (zero, zero);
    let mut index = f32x4::from([1.0, 2.0, 3.0, 4.0]);
    for i in (1..nb).step_by(4) {
        let (ml, nl) = sweep.left.lanes(i, model, hint);
        let (mr, nr) = sweep.right.lanes(i, model, hint);
        let valid = nl.simd_gt(zero) & nr.simd_gt(zero);
        let w = valid.select(ml * nl + mr * nr, inf);
        let better = w.simd_lt(best_w);
        best_w = better.select(w, best_w);
        best_i = better.select(index, best_i);
        best_ml = better.select(ml, best_ml);
        best_mr = better.select(mr, best_mr);
        index += f32x4::splat(4.0);
    }
    // The cheapest lane, ties to the lowest boundary; NaN and infinite prices never win.
    let (weighted, at, won) = cheapest_lane(best_w, best_i)?;
    Some(Cut {
        at,
        left: sweep.left.bounds(at),
        right: sweep.right.bounds(at),
        n_left: sweep.left.count[at],
        n_right: sweep.right.count[at],
        measure_left: best_ml.to_array()[won],
        measure_right: best_mr.to_array()[won],
        weighted,
    })
}

/// The split of a two-primitive node, without binning or sweeping, and the very split they would
/// choose: the two centroids fall in bins `a <= b` (normally the first and the last), every
/// boundary between them splits them alike at the same price, and the sweep keeps the lowest,
/// `a + 1`. Among the `axes` in the order they would be swept, the first that separates the
/// centroids wins (a later axis prices the same split no lower); `None` when `axis` does not
/// separate them, which includes centroids that differ but share a bin (at extreme coordinates
/// the extent overflows and the bin scale rounds to zero: the sweep finds no split there either).
/// Half the nodes a SAH build prices hold two primitives. The price comes from
/// [`CostModel::measure4`], like the sweep's, so it is bit for bit the sweep's.
pub(super) fn split_pair<M: CostModel>(
    model: &M,
    arena: &BuildArena,
    task: &Task,
    axis: usize,
    nb: u32,
) -> Option<Cut> {
    let map = pair_map(task, axis, nb)?;
    let s = task.start as usize;
    let (mut left, mut right) = (s, s + 1);
    if arena.refs.centroid2_axis(s, axis) > arena.refs.centroid2_axis(s + 1, axis) {
        (left, right) = (right, left);
    }
    let (bin_left, bin_right) = (
        map.bin(arena.refs.centroid2_axis(left, axis)),
        map.bin(arena.refs.centroid2_axis(right, axis)),
    );
    if bin_left >= bin_right {
        return None;
    }
    let (left, right) = (arena.refs.bounds(left), arena.refs.bounds(right));
    let m = model
        .measure4(&Aabb4::from_boxes([left, right, right, right]))
        .to_array();
    Some(Cut {
        at: bin_left + 1,
        left,
        right,
        n_left: 1,
        n_right: 1,
        measure_left: m[0],
        measure_right: m[1],
        weighted: m[0] * 1.0 + m[1] * 1.0,
    })
}

/// The bin map of a two-primitive node along `axis`, as [`Builder::bin`] makes it, or `None`
/// where the centroids coincide.
pub(super) fn pair_map(task: &Task, axis: usize, nb: u32) -> Option<BinMap> {
    let (lo, hi) = (task.centroids.min[axis], task.centroids.max[axis]);
    (hi > lo).then(|| BinMap::new(lo, hi, nb)).flatten()
}

/// `ceil(log2(n))` for `n >= 1`.
#[inline]
pub(super) fn ceil_log2(n: u32) -> u32 {
    32 - (n.max(1) - 1).leading_zeros()
}
