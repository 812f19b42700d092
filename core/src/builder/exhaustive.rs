//! Exhaustive splits for the smallest nodes: every bipartition of a node's primitives priced, not
//! only the axis-aligned ones.
//!
//! Most nodes of a binned build are tiny, and a binned node's price is fixed costs: three bin
//! maps, clearing the bins, a pass, three sweeps of at least four bins, a partition. A node of
//! `n <= 6` primitives has only `2^(n-1) - 1` bipartitions (7 for four primitives): the boxes of
//! all `2^n - 1` subsets take one union each, and pricing both sides of every bipartition takes
//! `2^(n-1) / 4` four-wide measures per side, fewer than three sweeps. The split found is the
//! cheapest of all, so never more expensive than the best binned split (each of those is one of
//! these bipartitions). Ties go to the most balanced, then the lowest mask, so the tree is a
//! function of the input alone.
//!
//! The default is four primitives: fewer build instructions than three or five
//! (measured: benches/RESULTS.md, section Build speed (single and multi thread)).

use super::arena::{lanes_to_aabb, soa, Bin, PrimRef};
use super::config::MAX_EXHAUSTIVE;
use super::cut::Cut;
use super::keys::cheapest_lane;
use crate::heuristics::CostModel;
use crate::simd::Aabb4;
use wide::f32x4;

/// Room for the boxes of every subset of [`MAX_EXHAUSTIVE`] primitives.
pub(crate) const SUBSETS: usize = 1 << MAX_EXHAUSTIVE;

/// The masks of the bipartitions of `n` primitives (the last one always right), most balanced
/// first, then by value: of equally priced splits (identical primitives, say) the most balanced
/// wins, so such subtrees stay as shallow as median splits make them.
const ORDER: [[u8; SUBSETS / 2]; MAX_EXHAUSTIVE as usize + 1] = {
    let mut order = [[0; SUBSETS / 2]; MAX_EXHAUSTIVE as usize + 1];
    let mut n = 2;
    while n <= MAX_EXHAUSTIVE as usize {
        let mut next = 0;
        // Imbalance |n_left - n_right| = |2 popcount - n|, smallest first.
        let mut imbalance = 0;
        while imbalance <= n {
            let mut mask = 1;
            while mask < 1 << (n - 1) {
                let left = (mask as u32).count_ones() as usize;
                if left.abs_diff(n - left) == imbalance {
                    order[n][next] = mask as u8;
                    next += 1;
                }
                mask += 1;
            }
            imbalance += 1;
        }
        n += 1;
    }
    order
};

/// The cheapest bipartition of `prims` (2 to [`MAX_EXHAUSTIVE`] of them) under `model` for a node
/// whose hint is `hint`, and the mask of the primitives (by position) that go left. The last
/// primitive always goes right, so each bipartition is tried once; ties go to the earliest in
/// [`ORDER`]. `subsets` is scratch. `None` when no bipartition has a finite price.
///
/// Inlined into the builder: returned through memory, the cut (two boxes and four prices) would
/// be read back at once after the call, waiting on its own stores.
#[inline(always)]
pub(crate) fn cheapest_bipartition<M: CostModel>(
    prims: &[PrimRef],
    subsets: &mut [Bin; SUBSETS],
    model: &M,
    hint: u32,
) -> Option<(Cut, u32)> {
    let n = prims.len();
    debug_assert!((2..=MAX_EXHAUSTIVE as usize).contains(&n));
    if let [a, b] = prims {
        return pair(a, b, model, hint);
    }
    let all = (1usize << n) - 1;
    for (k, p) in prims.iter().enumerate() {
        subsets[1 << k] = Bin {
            min: p.lo4(),
            max: p.hi4(),
            count: 1,
        };
    }
    // Each subset is a smaller one (its lowest member removed) plus that member, computed before.
    for s in 3..=all {
        let low = s & s.wrapping_neg();
        if s != low {
            let mut b = subsets[s ^ low];
            b.merge(&subsets[low]);
            subsets[s] = b;
        }
    }
    // The bipartitions in `ORDER`, four at a time; lanes past the last repeat it (a duplicate
    // never wins a strict comparison), so every lane prices a real bipartition.
    let (order, last) = (&ORDER[n], (1 << (n - 1)) - 2);
    let inf = f32x4::splat(f32::INFINITY);
    let (mut best_w, mut best_at) = (inf, f32x4::ZERO);
    let (mut best_ml, mut best_mr) = (inf, inf);
    for first in (0..=last).step_by(4) {
        let at: [usize; 4] = core::array::from_fn(|k| (first + k).min(last));
        let masks = at.map(|i| usize::from(order[i]));
        let (left, n_left) = gather(subsets, masks);
        let (right, n_right) = gather(subsets, masks.map(|m| all ^ m));
        let ml = model.measure4_hinted(&left, hint);
        let mr = model.measure4_hinted(&right, hint);
        let w = ml * n_left + mr * n_right;
        let better = w.simd_lt(best_w);
        best_w = better.select(w, best_w);
        best_at = better.select(f32x4::from(at.map(|i| i as f32)), best_at);
        best_ml = better.select(ml, best_ml);
        best_mr = better.select(mr, best_mr);
    }
    // Across lanes: the lowest price, ties to the earliest in `ORDER`; NaN never wins.
    let (weighted, at, won) = cheapest_lane(best_w, best_at)?;
    let mask = order[at] as usize;
    let (l, r) = (&subsets[mask], &subsets[all ^ mask]);
    let cut = Cut {
        at: mask,
        left: lanes_to_aabb(l.min, l.max),
        right: lanes_to_aabb(r.min, r.max),
        n_left: l.count,
        n_right: r.count,
        measure_left: best_ml.to_array()[won],
        measure_right: best_mr.to_array()[won],
        weighted,
    };
    Some((cut, mask as u32))
}

/// The boxes of subsets `masks` as SoA lanes, with their counts.
#[inline(always)]
fn gather(subsets: &[Bin; SUBSETS], masks: [usize; 4]) -> (Aabb4, f32x4) {
    // Masks are below `SUBSETS` by construction; the mask elides the bounds checks.
    let bins = masks.map(|m| &subsets[m & (SUBSETS - 1)]);
    (
        soa(bins.map(|b| b.min), bins.map(|b| b.max)),
        f32x4::from(bins.map(|b| b.count as f32)),
    )
}

/// The one bipartition of two primitives, one four-wide measure.
#[inline(always)]
fn pair<M: CostModel>(a: &PrimRef, b: &PrimRef, model: &M, hint: u32) -> Option<(Cut, u32)> {
    let m = model
        .measure4_hinted(
            &soa(
                [a.lo4(), b.lo4(), a.lo4(), b.lo4()],
                [a.hi4(), b.hi4(), a.hi4(), b.hi4()],
            ),
            hint,
        )
        .to_array();
    let weighted = m[0] + m[1];
    weighted.is_finite().then(|| {
        let cut = Cut {
            at: 1,
            left: lanes_to_aabb(a.lo4(), a.hi4()),
            right: lanes_to_aabb(b.lo4(), b.hi4()),
            n_left: 1,
            n_right: 1,
            measure_left: m[0],
            measure_right: m[1],
            weighted,
        };
        (cut, 1)
    })
}

/// Reorders `slots` so the primitives whose bit is set in `mask` come first, each side in its
/// previous order, and returns each side's doubled-centroid bounds as `(lo, hi)` lanes.
pub(crate) fn partition_by_mask(slots: &mut [PrimRef], mask: u32) -> [(f32x4, f32x4); 2] {
    let n = slots.len();
    debug_assert!(n <= MAX_EXHAUSTIVE as usize);
    let mut copy = [PrimRef::ZERO; MAX_EXHAUSTIVE as usize];
    copy[..n].copy_from_slice(slots);
    let inf = f32x4::splat(f32::INFINITY);
    let mut centroids = [(inf, -inf); 2];
    let mut next = 0;
    for side in [0, 1] {
        for (k, p) in copy[..n].iter().enumerate() {
            if (mask >> k) & 1 != side {
                let c = p.lo4() + p.hi4();
                let (lo, hi) = &mut centroids[side as usize];
                (*lo, *hi) = (lo.fast_min(c), hi.fast_max(c));
                slots[next] = *p;
                next += 1;
            }
        }
    }
    centroids
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::geometry::Aabb;
    use crate::heuristics::Sah;
    use crate::random::Pcg32;
    use glam::Vec3;

    fn prim(id: u32, b: &Aabb) -> PrimRef {
        PrimRef::new(id, b)
    }

    #[test]
    fn order_lists_every_bipartition_once_most_balanced_first() {
        for (n, order) in ORDER.iter().enumerate().skip(2) {
            let count = (1 << (n - 1)) - 1;
            let masks = &order[..count];
            for mask in 1..=count {
                assert_eq!(masks.iter().filter(|&&m| m as usize == mask).count(), 1);
            }
            let imbalance = |m: u8| (m.count_ones() as usize).abs_diff(n - m.count_ones() as usize);
            assert!(masks.windows(2).all(|w| imbalance(w[0]) <= imbalance(w[1])));
        }
    }

    /// Against every bipartition priced one by one with the scalar measure.
    #[test]
    fn finds_the_cheapest_bipartition() {
        let mut rng = Pcg32::new(7);
        let mut subsets = [Bin::EMPTY; SUBSETS];
        for case in 0..300 {
            let n = 2 + case % (MAX_EXHAUSTIVE as usize - 1);
            let mut boxes: [Aabb; MAX_EXHAUSTIVE as usize] = core::array::from_fn(|_| {
                let p = Vec3::new(rng.next_f32(), rng.next_f32(), rng.next_f32()) * 10.0;
                let e = Vec3::new(rng.next_f32(), rng.next_f32(), rng.next_f32());
                Aabb::new(p, p + e)
            });
            // Every fifth case, identical boxes: all bipartitions tie.
            let identical = case % 5 == 0;
            if identical {
                boxes = [boxes[0]; MAX_EXHAUSTIVE as usize];
            }
            let boxes = &boxes[..n];
            let prims: [PrimRef; MAX_EXHAUSTIVE as usize] =
                core::array::from_fn(|k| prim(k as u32, &boxes[k.min(n - 1)]));
            let (cut, mask) = cheapest_bipartition(&prims[..n], &mut subsets, &Sah, 0).unwrap();
            let union = |m: usize| {
                (0..n)
                    .filter(|k| (m >> k) & 1 == 1)
                    .fold(Aabb::EMPTY, |b, k| b.union(boxes[k]))
            };
            let price = |m: usize| {
                let l = m.count_ones() as f32;
                let all = (1 << n) - 1;
                Sah.measure(&union(m)) * l + Sah.measure(&union(all ^ m)) * (n as f32 - l)
            };
            let best = (1..1usize << (n - 1))
                .map(price)
                .fold(f32::INFINITY, f32::min);
            assert!(mask & (1 << (n - 1)) == 0, "the last primitive goes right");
            assert!(
                (price(mask as usize) - best).abs() <= 1e-5 * best,
                "case {case}"
            );
            assert!((cut.weighted - best).abs() <= 1e-5 * best, "case {case}");
            assert_eq!(cut.left, union(mask as usize));
            assert_eq!(cut.n_left, mask.count_ones());
            assert_eq!(cut.n_left + cut.n_right, n as u32);
            if identical {
                assert!(
                    cut.n_left.abs_diff(cut.n_right) <= 1,
                    "ties go to the most balanced"
                );
            }
        }
    }
}
