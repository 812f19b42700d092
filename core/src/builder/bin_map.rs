//! The map from a doubled centroid coordinate to its bin along one axis, and the exact
//! coordinate threshold of each bin boundary that the partition classifies by.

use super::binning::BIN_BYTES;

/// Maps a doubled centroid coordinate to its bin along one axis.
#[derive(Clone, Copy, Debug)]
pub(super) struct BinMap {
    pub(super) min: f32,
    pub(super) scale: f32,
    pub(super) last: f32,
}

impl BinMap {
    /// `None` when the range has no extent (no plane can separate the centroids).
    #[inline]
    pub(super) fn new(min: f32, max: f32, bins: u32) -> Option<Self> {
        let extent = max - min;
        // The scale is shrunk by a few ulps so the largest centroid maps inside the last bin.
        let scale = bins as f32 * (1.0 - 4.0 * f32::EPSILON) / extent;
        // The binning pass multiplies the scale by the bin size (`BinJob`): that product must
        // stay finite too, or it would put every centroid above `min` in the last bin while the
        // partition classifies by this scale. Only centroid extents below 2e-37 per bin have no
        // map (no plane then separates them, as for coincident centroids).
        (extent > 0.0 && (scale * BIN_BYTES).is_finite()).then_some(Self {
            min,
            scale,
            last: (bins - 1) as f32,
        })
    }

    #[inline(always)]
    pub(super) fn bin(&self, c: f32) -> usize {
        // `as usize` saturates (NaN to 0), and the clamp keeps rounding inside the bins.
        ((c - self.min) * self.scale).clamp(0.0, self.last) as usize
    }

    /// The smallest coordinate `t` with `self.bin(t) >= bin`, for `1 <= bin <= last`: then
    /// `self.bin(c) < bin` exactly when `c < t`, because every step of [`BinMap::bin`] (a
    /// subtraction, a multiplication by a positive scale, a clamp, a truncation) is monotone in
    /// `c`. The partition classifies a primitive with one comparison instead of recomputing its
    /// bin, and still exactly as the bins counted it.
    pub(super) fn threshold(&self, bin: usize) -> f32 {
        // Floats in their total order as integers: `key` is monotone, so is `at_least`.
        let key = |x: f32| {
            let b = x.to_bits() as i32;
            i64::from(b ^ (((b >> 31) as u32) >> 1) as i32)
        };
        let from_key = |k: i64| {
            let k = k as i32;
            f32::from_bits((k ^ (((k >> 31) as u32) >> 1) as i32) as u32)
        };
        let at_least = |k: i64| self.bin(from_key(k)) >= bin;
        // bin(-inf) = 0 < bin <= last = bin(+inf): the boundary lies between.
        let (floor, ceil) = (key(f32::NEG_INFINITY), key(f32::INFINITY));
        // Start at the plane's position and gallop to a bracket: the estimate is off by the
        // rounding of `min + bin / scale`, which cancellation can make many ulps of the result.
        let k0 = key(self.min + bin as f32 / self.scale).clamp(floor, ceil);
        let (mut lo, mut hi) = if at_least(k0) {
            (k0 - 1, k0)
        } else {
            (k0, k0 + 1)
        };
        let mut step = 1;
        while lo > floor && at_least(lo) {
            hi = lo;
            lo = (lo - step).max(floor);
            step *= 2;
        }
        while hi < ceil && !at_least(hi) {
            lo = hi;
            hi = (hi + step).min(ceil);
            step *= 2;
        }
        // Invariant: !at_least(lo) (or lo = floor), at_least(hi).
        while hi - lo > 1 {
            let mid = lo + (hi - lo) / 2;
            if at_least(mid) {
                hi = mid;
            } else {
                lo = mid;
            }
        }
        from_key(hi)
    }
}
