//! Binning a node in parts: the hook a threaded host uses to spread the binning of the top
//! nodes, whose passes over every primitive would otherwise run on one thread.
//!
//! A bin keeps a count and the bounds of its primitives; counts add and bounds merge by min and
//! max, all exact in any order, so bins filled over parts of a node and merged equal the bins of
//! one pass, bit for bit, and the build makes the same tree whatever the parts.

use core::ops::Range;

use wide::{f32x4, i32x4};

use super::arena::{Bin, PrimRef};
use super::config::MAX_BINS;

/// The bins of one node along the three axes.
#[derive(Clone, Debug)]
pub struct NodeBins {
    pub(crate) bins: [[Bin; MAX_BINS as usize]; 3],
}

impl NodeBins {
    /// Adds the primitives binned in `other` (another part of the same node).
    pub fn merge(&mut self, other: &NodeBins) {
        for (mine, theirs) in self.bins.iter_mut().zip(&other.bins) {
            for (a, b) in mine.iter_mut().zip(theirs) {
                a.merge(b);
            }
        }
    }
}

/// One node's binning pass: its primitives and the map from a centroid to its bin on each axis.
/// Bin any parts of [`BinJob::len`] slots with [`BinJob::bin_range`] and merge them.
#[derive(Clone, Copy, Debug)]
pub struct BinJob<'a> {
    pub(crate) refs: &'a [PrimRef],
    /// The bin maps' lower ends, per axis lane.
    min: f32x4,
    /// The bin maps' scales times the size of a bin.
    scale_bytes: f32x4,
    /// The bin maps' last bins times the size of a bin.
    last_bytes: f32x4,
}

/// The size of a [`Bin`] as a float: a power of two, so scaling by it is exact.
pub(crate) const BIN_BYTES: f32 = {
    assert!(core::mem::size_of::<Bin>().is_power_of_two());
    core::mem::size_of::<Bin>() as f32
};

impl<'a> BinJob<'a> {
    /// The binning of `refs` by the builder's bin maps `(min, scale, last)`, one per axis lane; an axis that is not binned has all three 0.
    #[inline(always)]
    pub(crate) fn new(refs: &'a [PrimRef], min: f32x4, scale: f32x4, last: f32x4) -> Self {
        let bytes = f32x4::splat(BIN_BYTES);
        Self {
            refs,
            min,
            scale_bytes: scale * bytes,
            last_bytes: last * bytes,
        }
    }
}

impl BinJob<'_> {
    /// The node's primitive count.
    pub fn len(&self) -> usize {
        self.refs.len()
    }

    /// True for a node without primitives.
    pub fn is_empty(&self) -> bool {
        self.refs.is_empty()
    }

    /// Bins the node's slots `range` (counted from the node's first slot) into fresh bins.
    pub fn bin_range(&self, range: Range<usize>) -> NodeBins {
        let empty = || NodeBins {
            bins: [[Bin::EMPTY; MAX_BINS as usize]; 3],
        };
        let (mut out, mut odd) = (empty(), empty());
        self.bin_into_dual(&self.refs[range], &mut out.bins, &mut odd.bins);
        out.merge(&odd);
        out
    }

    /// [`BinJob::bin_into`] with even slots into `even` and odd ones into `odd`: two independent
    /// chains of bin updates instead of one.
    #[inline(always)]
    pub(crate) fn bin_into_dual(
        &self,
        refs: &[PrimRef],
        even: &mut [[Bin; MAX_BINS as usize]; 3],
        odd: &mut [[Bin; MAX_BINS as usize]; 3],
    ) {
        let mut pairs = refs.chunks_exact(2);
        for pair in &mut pairs {
            self.bin_one(&pair[0], even);
            self.bin_one(&pair[1], odd);
        }
        self.bin_into(pairs.remainder(), even);
    }

    /// The byte offsets of a primitive's bins on the three axes (lane 3 is junk).
    ///
    /// The bin index is `trunc(clamp((c - min) * scale, 0, last))`, as the builder's `BinMap`
    /// computes it; here the scale and the clamp are both multiplied by the bin size `B`, a power
    /// of two, and the truncation's low bits are masked off: `trunc(B x) & !(B - 1) = B trunc(x)`
    /// for `x >= 0`, and `round(a * (B s)) = B round(a s)` because scaling by a power of two is
    /// exact (outside the subnormal range, where both give bin 0, and overflow, where the clamp
    /// gives the last bin to both). So the offsets are exactly `B` times the bin indices, with no
    /// per-axis shift.
    #[inline(always)]
    pub(crate) fn offsets(&self, lo: f32x4, hi: f32x4) -> BinOffsets {
        BinOffsets::new(
            ((lo + hi - self.min) * self.scale_bytes)
                .fast_max(f32x4::ZERO)
                .fast_min(self.last_bytes)
                .fast_trunc_int(),
        )
    }

    /// Grows `bins` by `refs` along all three axes. An axis that is not binned has scale 0, so
    /// its primitives all land in bin 0, which the builder ignores.
    #[inline(always)]
    pub(crate) fn bin_into(&self, refs: &[PrimRef], bins: &mut [[Bin; MAX_BINS as usize]; 3]) {
        for r in refs {
            self.bin_one(r, bins);
        }
    }

    /// Grows `bins` by one primitive along all three axes.
    #[inline(always)]
    fn bin_one(&self, r: &PrimRef, bins: &mut [[Bin; MAX_BINS as usize]; 3]) {
        let [bx, by, bz] = bins;
        let (lo, hi) = (r.lo4(), r.hi4());
        let at = self.offsets(lo, hi);
        at.bin(bx, 0).grow(lo, hi);
        at.bin(by, 1).grow(lo, hi);
        at.bin(bz, 2).grow(lo, hi);
    }
}

/// Byte offsets of bins in a `[Bin; MAX_BINS]`, one per axis lane. The offsets are masked to
/// multiples of the bin size below `MAX_BINS` bins in one vector `pand` for all three axes, so
/// the per-axis accesses need no mask and no bounds check (see [`BinJob::offsets`]).
#[derive(Clone, Copy, Debug)]
pub(crate) struct BinOffsets([u32; 4]);

impl BinOffsets {
    /// The offsets from truncated byte-scaled coordinates `t` (any values: they are masked into
    /// range, `t & !(size_of::<Bin>() - 1)` for `t` in range).
    #[inline(always)]
    pub(crate) fn new(t: i32x4) -> Self {
        const { assert!(MAX_BINS.is_power_of_two()) };
        let bin = core::mem::size_of::<Bin>() as i32;
        Self(bytemuck::cast(
            t & i32x4::splat((MAX_BINS as i32 - 1) * bin),
        ))
    }

    /// The offsets, lane by lane.
    #[cfg(test)]
    pub(crate) fn lanes(self) -> [u32; 4] {
        self.0
    }

    /// The bin of lane `axis` in `bins`.
    #[inline(always)]
    pub(crate) fn bin(self, bins: &mut [Bin; MAX_BINS as usize], axis: usize) -> &mut Bin {
        let off = self.0[axis] as usize;
        debug_assert!(
            off < core::mem::size_of_val(bins) && off.is_multiple_of(core::mem::size_of::<Bin>())
        );
        // SAFETY: `new`'s mask made every lane `k * size_of::<Bin>()` with `k < MAX_BINS`, so `off` is
        // the offset of element `k` of `bins`: in bounds and aligned, and the exclusive borrow of
        // `bins` covers the returned one.
        unsafe { &mut *bins.as_mut_ptr().byte_add(off) }
    }
}

/// Who bins a node's primitives. The builder asks before each binning pass; a threaded host
/// answers for large nodes by binning parts on several threads ([`BinJob::bin_range`]) and
/// merging them ([`NodeBins::merge`]). Bins from parts are exactly the one-pass bins, so the tree
/// does not depend on the answer.
pub trait NodeBinner {
    /// The bins of the whole `job`, or `None` to let the builder bin it in one pass.
    fn bin(&self, job: &BinJob<'_>) -> Option<NodeBins>;
}

/// Every node binned in one pass on the calling thread: the single-threaded build.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub struct SerialBinner;

impl NodeBinner for SerialBinner {
    #[inline(always)]
    fn bin(&self, _job: &BinJob<'_>) -> Option<NodeBins> {
        None
    }
}
