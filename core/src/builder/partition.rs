//! Partitioning a node's primitives by its split, without a branch on the primitives' sides.
//!
//! The split's sweep already counted the primitives going left, `n_left`, so the result is known
//! in advance: the first `n_left` slots must hold the left ones. The primitives that are out of
//! place are the right-goers among the first `n_left` slots and as many left-goers among the
//! rest; swapping the k-th of the first (from the front) with the k-th of the second (from the
//! back) gives exactly the permutation of Hoare's scheme, which scans from both ends and swaps
//! the pairs it stops at. Hoare's scans branch on every primitive's side, and the sides of a
//! node's primitives are as good as random to the branch predictor, so those branches mispredict
//! often.
//!
//! Here each side is scanned in blocks of [`BLOCK`] slots, writing the offset of every slot and
//! advancing a count by whether it is misplaced (no branch), then the misplaced pairs are
//! swapped (a branch per pair, not per primitive); in the spirit of BlockQuicksort (Edelkamp and
//! Weiss, 2016). The children's centroid bounds are then gathered by one streaming pass over
//! each side, branch-free too; min and max are exact in any order, so they are the bounds Hoare's
//! scheme gathered as it went.

use wide::f32x4;

use super::arena::PrimRef;

/// Slots per block of a scan: offsets fit a byte.
const BLOCK: usize = 64;

/// Puts the left-goers of `front ++ back` in `front`, where `front` is as long as their number,
/// by swapping the k-th right-goer of `front` with the k-th left-goer of `back` from its end:
/// Hoare's permutation. Returns false when `front.len()` is not the number of left-goers (the
/// misplaced primitives of one side are left without partners).
pub(crate) fn swap_misplaced(
    front: &mut [PrimRef],
    back: &mut [PrimRef],
    goes_left: impl Fn(&PrimRef) -> bool,
) -> bool {
    let (mut front_offsets, mut back_offsets) = ([0u8; BLOCK], [0u8; BLOCK]);
    // Slots scanned so far: front[..front_scanned], back[back_scanned..].
    let (mut front_scanned, mut back_scanned) = (0, back.len());
    // The current blocks: where they start, their misplaced slots found and taken.
    let (mut front_base, mut front_found, mut front_taken) = (0, 0, 0);
    let (mut back_base, mut back_found, mut back_taken) = (0, 0, 0);
    loop {
        if front_taken == front_found && front_scanned < front.len() {
            let block = &front[front_scanned..front.len().min(front_scanned + BLOCK)];
            (front_base, front_found, front_taken) = (front_scanned, 0, 0);
            for (k, r) in block.iter().enumerate() {
                front_offsets[front_found] = k as u8;
                front_found += usize::from(!goes_left(r));
            }
            front_scanned += block.len();
        }
        if back_taken == back_found && back_scanned > 0 {
            // Scanned from its end, so offsets count back from `back_base`.
            let block = &back[back_scanned.saturating_sub(BLOCK)..back_scanned];
            (back_base, back_found, back_taken) = (back_scanned, 0, 0);
            for (k, r) in block.iter().rev().enumerate() {
                back_offsets[back_found] = k as u8;
                back_found += usize::from(goes_left(r));
            }
            back_scanned -= block.len();
        }
        let pairs = (front_found - front_taken).min(back_found - back_taken);
        for _ in 0..pairs {
            let i = front_base + usize::from(front_offsets[front_taken]);
            let j = back_base - 1 - usize::from(back_offsets[back_taken]);
            core::mem::swap(&mut front[i], &mut back[j]);
            front_taken += 1;
            back_taken += 1;
        }
        // Both sides are scanned to their ends (one pass over the node, as Hoare's scans make):
        // a misplaced slot left over on one side once the other is through means the count
        // was wrong.
        let front_done = front_taken == front_found && front_scanned == front.len();
        let back_done = back_taken == back_found && back_scanned == 0;
        if front_done && back_done {
            return true;
        }
        if (front_done && back_taken < back_found) || (back_done && front_taken < front_found) {
            return false;
        }
    }
}

/// The bounds of the doubled centroids of `refs` as `(x, y, z, _)` lanes (lane 3 is junk), in two
/// interleaved chains so that each min and max need not wait for the one before.
pub(crate) fn centroid_bounds(refs: &[PrimRef]) -> (f32x4, f32x4) {
    let inf = f32x4::splat(f32::INFINITY);
    let (mut lo, mut hi, mut lo2, mut hi2) = (inf, -inf, inf, -inf);
    let mut pairs = refs.chunks_exact(2);
    for pair in &mut pairs {
        let (a, b) = (pair[0].centroid2_4(), pair[1].centroid2_4());
        (lo, hi) = (lo.fast_min(a), hi.fast_max(a));
        (lo2, hi2) = (lo2.fast_min(b), hi2.fast_max(b));
    }
    for r in pairs.remainder() {
        let c = r.centroid2_4();
        (lo, hi) = (lo.fast_min(c), hi.fast_max(c));
    }
    (lo.fast_min(lo2), hi.fast_max(hi2))
}

#[cfg(test)]
mod tests {
    use alloc::vec::Vec;

    use super::*;
    use crate::geometry::Aabb;
    use crate::random::Pcg32;
    use glam::Vec3;

    /// Hoare's scheme, the reference: scan from the front past left-goers, from the back past
    /// right-goers, swap the two slots the scans stopped at.
    fn hoare(slots: &mut [PrimRef], goes_left: impl Fn(&PrimRef) -> bool) -> usize {
        let (mut i, mut j) = (0, slots.len());
        loop {
            while i < j && goes_left(&slots[i]) {
                i += 1;
            }
            while j > i && !goes_left(&slots[j - 1]) {
                j -= 1;
            }
            if j - i < 2 {
                return i;
            }
            slots.swap(i, j - 1);
            i += 1;
            j -= 1;
        }
    }

    fn prims(n: usize, rng: &mut Pcg32) -> Vec<PrimRef> {
        (0..n as u32)
            .map(|id| {
                let lo = Vec3::new(
                    rng.range(-9.0, 9.0),
                    rng.range(-9.0, 9.0),
                    rng.range(-9.0, 9.0),
                );
                PrimRef::new(id, &Aabb::new(lo, lo + Vec3::splat(rng.range(0.0, 1.0))))
            })
            .collect()
    }

    /// The same permutation as Hoare's, for every split point and size around the block size,
    /// with all-left and all-right sides; and the same centroid bounds as a plain fold.
    #[test]
    fn the_permutation_is_hoares() {
        let mut rng = Pcg32::new(21);
        for n in [1, 2, 3, 17, 63, 64, 65, 127, 128, 129, 200, 1000] {
            let base = prims(n, &mut rng);
            for threshold in [-20.0, -3.0, 0.0, 0.5, 4.0, 20.0] {
                let goes_left = |r: &PrimRef| r.centroid2_axis(1) < threshold;
                let mut expected = base.clone();
                let n_left = hoare(&mut expected, goes_left);
                let mut got = base.clone();
                let (front, back) = got.split_at_mut(n_left);
                assert!(swap_misplaced(front, back, goes_left), "{n} {threshold}");
                assert!(got == expected, "{n} {threshold}");
                for side in [&got[..n_left], &got[n_left..]] {
                    let c = side.iter().map(PrimRef::centroid2_4);
                    let inf = f32x4::splat(f32::INFINITY);
                    let fold = c.fold((inf, -inf), |(lo, hi), c| (lo.fast_min(c), hi.fast_max(c)));
                    let (lo, hi) = centroid_bounds(side);
                    assert_eq!(lo.to_array()[..3], fold.0.to_array()[..3]);
                    assert_eq!(hi.to_array()[..3], fold.1.to_array()[..3]);
                }
            }
        }
    }

    /// A front of the wrong length (a count that disagrees with the classification) is reported,
    /// never a panic.
    #[test]
    fn a_wrong_count_is_reported() {
        let mut rng = Pcg32::new(5);
        let mut slots = prims(300, &mut rng);
        let goes_left = |r: &PrimRef| r.centroid2_axis(0) < 0.0;
        let n_left = slots.iter().filter(|r| goes_left(r)).count();
        for wrong in [n_left - 1, n_left + 1, 0, 300] {
            let (front, back) = slots.split_at_mut(wrong);
            assert!(!swap_misplaced(front, back, goes_left), "{wrong}");
        }
    }
}
