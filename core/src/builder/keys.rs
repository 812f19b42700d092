//! Floats as integer keys, so that the cheapest of several priced candidates, ties to the first,
//! is one integer minimum: no branch on which price is lower, which the branch predictor cannot
//! guess (the build compares such prices at every node).

use wide::{f32x4, i32x4};

/// A float's bits, mapped so that unsigned order is [`f32::total_cmp`]'s order.
#[inline(always)]
pub(crate) fn ordered(x: f32) -> u32 {
    let b = x.to_bits();
    if b >> 31 == 1 {
        !b
    } else {
        b | 1 << 31
    }
}

/// The inverse of [`ordered`].
#[inline(always)]
pub(crate) fn unordered(k: u32) -> f32 {
    f32::from_bits(if k >> 31 == 1 { k & !(1 << 31) } else { !k })
}

/// The lane of the lowest finite price in `price`, ties to the lowest `rank` then the first lane,
/// as `(price, rank, lane)`; `None` when no price is finite. Ranks are whole numbers below 2^29
/// (a lane priced infinite or NaN may carry any rank: it never wins). A NaN price never wins, and
/// `-0` ties with `0`, as comparing with `<` has it.
#[inline(always)]
pub(crate) fn cheapest_lane(price: f32x4, rank: f32x4) -> Option<(f32, usize, usize)> {
    // NaN as +inf, -0 as +0 (x + 0 is x for every other x).
    let price = price
        .simd_eq(price)
        .select(price + f32x4::ZERO, f32x4::splat(f32::INFINITY));
    // Total order as signed integers, four lanes at once: a negative float's magnitude bits
    // flipped, so that more negative sorts lower.
    let bits: i32x4 = bytemuck::cast(price);
    let sign: i32x4 = bits >> 31_i32;
    let ordered = (bits ^ (sign & i32x4::splat(i32::MAX))).to_array();
    let rank = rank.fast_trunc_int().to_array();
    let key = |l: usize| {
        i64::from(ordered[l]) << 32 | i64::from(rank[l] as u32 & 0x1fff_ffff) << 2 | l as i64
    };
    let lane = (key(0).min(key(1)).min(key(2).min(key(3))) & 3) as usize;
    let p = price.to_array()[lane];
    p.is_finite().then_some((p, rank[lane] as usize, lane))
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn ordered_bits_sort_as_total_cmp() {
        let xs = [
            f32::NEG_INFINITY,
            -3.5,
            -f32::MIN_POSITIVE,
            -0.0,
            0.0,
            1e-40,
            f32::MIN_POSITIVE,
            1.0,
            2.5e30,
            f32::INFINITY,
        ];
        for a in xs {
            assert_eq!(unordered(ordered(a)).to_bits(), a.to_bits());
            for b in xs {
                assert_eq!(ordered(a).cmp(&ordered(b)), a.total_cmp(&b), "{a} {b}");
            }
        }
    }

    /// The same lane as comparing with `<` lane by lane, ties to the lower rank.
    #[test]
    fn the_cheapest_lane_is_the_first_lowest_by_rank() {
        fn by_comparison(p: [f32; 4], r: [f32; 4]) -> Option<(f32, usize, usize)> {
            let (mut best, mut at, mut won) = (f32::INFINITY, f32::INFINITY, 0);
            for l in 0..4 {
                if p[l] < best || (p[l] == best && r[l] < at) {
                    (best, at, won) = (p[l], r[l], l);
                }
            }
            best.is_finite().then_some((best, at as usize, won))
        }
        let values = [
            0.0,
            -0.0,
            1.0,
            2.5,
            -1.0,
            -3.0,
            f32::NEG_INFINITY,
            f32::INFINITY,
            f32::NAN,
            -f32::NAN,
            1e-40,
        ];
        let mut rng = crate::random::Pcg32::new(3);
        for _ in 0..20_000 {
            let mut pick = |n: usize| rng.next_u32() as usize % n;
            let p: [f32; 4] = core::array::from_fn(|_| values[pick(values.len())]);
            let r: [f32; 4] = core::array::from_fn(|_| pick(6) as f32);
            // The same lane, rank and price (a winning -0 comes back as 0).
            let unsigned = |(p, r, l): (f32, usize, usize)| (p.abs(), r, l);
            let got = cheapest_lane(f32x4::from(p), f32x4::from(r)).map(unsigned);
            assert_eq!(got, by_comparison(p, r).map(unsigned), "{p:?} {r:?}");
        }
    }
}
