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
    pub(crate) min: f32x4,
    pub(crate) scale: f32x4,
    pub(crate) last: f32x4,
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
            self.bin_into(&pair[..1], even);
            self.bin_into(&pair[1..], odd);
        }
        self.bin_into(pairs.remainder(), even);
    }

    /// The byte offsets of a primitive's bins on the three axes (lane 3 is junk).
    #[inline(always)]
    pub(crate) fn offsets(&self, lo: f32x4, hi: f32x4) -> BinOffsets {
        BinOffsets::new(
            ((lo + hi - self.min) * self.scale)
                .fast_max(f32x4::ZERO)
                .fast_min(self.last)
                .fast_trunc_int(),
        )
    }

    /// Grows `bins` by `refs` along all three axes. An axis that is not binned has scale 0, so
    /// its primitives all land in bin 0, which the builder ignores.
    #[inline(always)]
    pub(crate) fn bin_into(&self, refs: &[PrimRef], bins: &mut [[Bin; MAX_BINS as usize]; 3]) {
        let [bx, by, bz] = bins;
        for r in refs {
            let (lo, hi) = (r.lo4(), r.hi4());
            let at = self.offsets(lo, hi);
            at.bin(bx, 0).grow(lo, hi);
            at.bin(by, 1).grow(lo, hi);
            at.bin(bz, 2).grow(lo, hi);
        }
    }
}

/// Byte offsets of bins in a `[Bin; MAX_BINS]`, one per axis lane. The bin indices are masked to
/// `MAX_BINS - 1` in one vector `pand` for all three axes, so the per-axis accesses need no mask
/// and no bounds check, only the shift by the bin size: measured with callgrind on the bunny's
/// SAH build, binning went from 46 to 42 instructions per primitive with the 64-byte bins.
#[derive(Clone, Copy, Debug)]
pub(crate) struct BinOffsets([u32; 4]);

impl BinOffsets {
    /// The offsets of bin indices `i` (any values: they are masked into range).
    #[inline(always)]
    pub(crate) fn new(i: i32x4) -> Self {
        const { assert!(MAX_BINS.is_power_of_two()) };
        let i = i & i32x4::splat(MAX_BINS as i32 - 1);
        let off = i * i32x4::splat(core::mem::size_of::<Bin>() as i32);
        Self(bytemuck::cast(off))
    }

    /// The bin of lane `axis` in `bins`.
    #[inline(always)]
    pub(crate) fn bin(self, bins: &mut [Bin; MAX_BINS as usize], axis: usize) -> &mut Bin {
        let off = self.0[axis] as usize;
        debug_assert!(off < core::mem::size_of_val(bins) && off % core::mem::size_of::<Bin>() == 0);
        // SAFETY: `new` made every lane `k * size_of::<Bin>()` with `k < MAX_BINS`, so `off` is
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
