//! The build skeleton: choose axes, bin, sweep, then stop or split. Heuristics are type parameters.

use super::apply_split::*;
use super::arena::{Bin, BuildArena, Task};
use super::bin_map::*;
use super::binning::{BinJob, NodeBinner, SerialBinner};
use super::config::{BinSpace, BuildConfig, CutEvaluation};
use super::cut::*;
use super::exhaustive::cheapest_bipartition;
use super::profile::{Clock, NoClock, PhaseProfile};
use super::sweep::*;
use crate::bvh::{Bvh, BvhNode, WideBvh};
use alloc::vec::Vec;

use wide::f32x4;

use crate::geometry::{Aabb, Triangle};
use crate::heuristics::{
    AllAxes, AxisChooser, AxisOrder, CostModel, LongestAxis, MinLeaf, Sah, SahTermination,
    Termination,
};
use crate::BuildError;

/// A subtree left for a separate build by [`Builder::build_top`]: the placeholder leaf `node`
/// over primitive slots `start..start + count`, at depth `depth`.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Subtree {
    /// The placeholder node.
    pub node: u32,
    /// First primitive slot.
    pub start: u32,
    /// Number of primitives.
    pub count: u32,
    /// Depth of the subtree's root in the whole tree.
    pub depth: u32,
    /// The root's measure under the builder's cost model, as its parent's split priced it (`None`
    /// where the split did not price it under that model). A node's split is priced relative to
    /// its own measure, and the whole build takes it from the parent's sweep rather than
    /// measuring again (a perspective PAH measure costs hundreds of instructions); a subtree
    /// built with the same value is exactly the whole build's.
    pub measure: Option<f32>,
}

/// Takes the subtrees [`Builder::build_top_into`] leaves, in the order the single-threaded build
/// would reach them, each with the arena holding its primitives (slots `start..start + count`).
pub trait SubtreeSink {
    /// Takes one subtree.
    fn take(&mut self, job: Subtree, arena: &BuildArena);
}

/// Records the subtrees, to build once the top is done.
impl SubtreeSink for Vec<Subtree> {
    fn take(&mut self, job: Subtree, _arena: &BuildArena) {
        self.push(job);
    }
}

/// No subtrees left for later: every node is built.
const NO_JOBS: Option<&mut Vec<Subtree>> = None;

/// What a build produced, besides the BVH.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub struct BuildStats {
    /// Nodes written.
    pub nodes: u32,
    /// Leaves among them.
    pub leaves: u32,
    /// Depth of the deepest node.
    pub max_depth: u32,
    /// Nodes split at their object median because the heuristic could not separate them
    /// (all centroids equal, a zero-measure node) or the depth budget ran short.
    pub median_splits: u32,
    /// Time and calls of the orientation choice and the candidate pricing.
    pub profile: PhaseProfile,
}

/// A top-down binned builder (Wald 2007) with pluggable axis choice `A`, cost model `C` and
/// termination rule `T`.
///
/// Per node: `A` names the axes to try; the node's centroids are binned along them in one pass;
/// a prefix and a suffix sweep over the bins price every bin boundary as
/// `C_trav + C_isect * (m(L) n_L + m(R) n_R) / m(parent)` with `m` from `C`; `T` compares the best
/// price with the leaf's `C_isect * n`. O(n) work per level, no allocation, no recursion on the call
/// stack. The depth bound of [`BuildConfig::max_depth`] always holds: when
/// `depth + ceil(log2 n)` reaches it, or when no binned plane separates a node that must split, the
/// node is split at its object median instead.
///
/// The presets ([`super::BuildOptions`]) name the usual combinations; a builder of your own
/// mixes any chooser, cost model and termination, here the orthographic PAH of rays travelling
/// down `-y` with the longest-axis (LSPH) chooser:
///
/// ```
/// use rdbvh_core::builder::BuildConfig;
/// use rdbvh_core::heuristics::{LongestAxis, PahOrtho, SahTermination};
/// use rdbvh_core::{Builder, Ray, Triangle, Vec3};
///
/// let tris: Vec<Triangle> = (0..100)
///     .map(|i| {
///         let o = Vec3::new((i % 10) as f32, (i / 10) as f32 * 0.1, (i / 10) as f32);
///         Triangle::new(o, o + Vec3::X, o + Vec3::Z)
///     })
///     .collect();
/// let down = PahOrtho::new(-Vec3::Y).expect("a direction");
/// let builder = Builder::new(LongestAxis, down, SahTermination::default(), BuildConfig::default());
/// let bvh = builder.build(&tris)?;
/// let ray = Ray::new(Vec3::new(4.2, 5.0, 6.3), -Vec3::Y)?;
/// assert_eq!(bvh.closest_hit(&ray, &tris).map(|h| h.triangle), Some(64));
/// # Ok::<(), Box<dyn std::error::Error>>(())
/// ```
#[derive(Clone, Copy, Debug, Default, PartialEq)]
pub struct Builder<A = AllAxes, C = Sah, T = SahTermination> {
    /// Which axes each node tries.
    pub axes: A,
    /// The hit measure that prices splits.
    pub cost: C,
    /// When a node becomes a leaf.
    pub termination: T,
    /// Bins, cost constants and depth bound.
    pub config: BuildConfig,
}

impl Builder {
    /// Binned SAH over all three axes with SAH termination: the state of the art.
    pub fn sah() -> Self {
        Self::default()
    }
}

impl Builder<LongestAxis> {
    /// Binned SAH over the longest axis only (LSPH): the thesis's "standard" builder.
    pub fn lsph() -> Self {
        Builder {
            axes: LongestAxis,
            cost: Sah,
            termination: SahTermination::default(),
            config: BuildConfig {
                cut: CutEvaluation::FirstAxis,
                ..BuildConfig::default()
            },
        }
    }
}

impl<A: AxisChooser, C: CostModel, T: Termination> Builder<A, C, T> {
    /// A builder from its three strategies and its settings.
    pub fn new(axes: A, cost: C, termination: T, config: BuildConfig) -> Self {
        Self {
            axes,
            cost,
            termination,
            config,
        }
    }

    /// The same builder with other settings.
    pub fn with_config(self, config: BuildConfig) -> Self {
        Self { config, ..self }
    }

    /// The same builder with another termination rule.
    pub fn with_termination<T2: Termination>(self, termination: T2) -> Builder<A, C, T2> {
        Builder {
            axes: self.axes,
            cost: self.cost,
            termination,
            config: self.config,
        }
    }

    /// The same builder for a tree that will only be collapsed into a [`WideBvh`]: nodes of at
    /// most [`WideBvh::ONE_BLOCK`] primitives are leaves at once ([`MinLeaf`]), since the collapse
    /// makes each such subtree one leaf block anyway. Every larger node splits as before, so
    /// [`WideBvh::from_binary`] gives the same nodes as for this builder's tree, with the same
    /// triangles in each leaf (a leaf of two blocks may group them otherwise), for about a fifth
    /// less build work (measured: benches/RESULTS.md, section Build speed (single and multi
    /// thread)). [`crate::builder::reinsert`] can only move this tree's small leaves as units:
    /// reinsert the full build's tree when the wide tree is to be improved.
    pub fn for_wide(self) -> Builder<A, C, MinLeaf<T>> {
        Builder {
            axes: self.axes,
            cost: self.cost,
            termination: MinLeaf {
                inner: self.termination,
                min_leaf: WideBvh::ONE_BLOCK,
            },
            config: self.config,
        }
    }

    /// Builds a BVH over `tris` (triangle `i` gets id `i`), allocating its own arena and output.
    pub fn build(&self, tris: &[Triangle]) -> Result<Bvh, BuildError> {
        let mut arena = BuildArena::with_capacity(tris.len());
        arena.load_triangles(tris)?;
        let mut bvh = Bvh::with_capacity(tris.len());
        self.build_into(&mut arena, &mut bvh)?;
        Ok(bvh)
    }
    /// Builds a BVH over the primitives loaded in `arena`, writing it into `out` (whose previous
    /// content is replaced). Allocates nothing when `out` was made with
    /// [`Bvh::with_capacity`] for at least as many primitives; otherwise it grows `out` once,
    /// before the build starts. An empty arena gives an empty BVH.
    pub fn build_into(
        &self,
        arena: &mut BuildArena,
        out: &mut Bvh,
    ) -> Result<BuildStats, BuildError> {
        self.build_range(arena, out, (0, None), 0, NO_JOBS, &NoClock, &SerialBinner)
    }

    /// [`Builder::build_into`], timing its phases with `clock` into [`BuildStats::profile`].
    pub fn build_into_profiled(
        &self,
        arena: &mut BuildArena,
        out: &mut Bvh,
        clock: &impl Clock,
    ) -> Result<BuildStats, BuildError> {
        self.build_range(arena, out, (0, None), 0, NO_JOBS, clock, &SerialBinner)
    }

    /// [`Builder::build_into`] for the subtree `job` of a larger build (the arena loaded with its
    /// primitives): its root sits at the job's depth, so the depth bound and every depth-dependent
    /// decision are those of the whole build, and takes the job's measure, so the result is
    /// exactly the subtree the whole build would make from these primitives.
    pub fn build_subtree_into(
        &self,
        arena: &mut BuildArena,
        out: &mut Bvh,
        job: &Subtree,
    ) -> Result<BuildStats, BuildError> {
        let root = (job.depth, job.measure);
        self.build_range(arena, out, root, 0, NO_JOBS, &NoClock, &SerialBinner)
    }

    /// The top of a build, for threaded builders: like [`Builder::build_into`], but a node of at
    /// most `cutoff` primitives is not processed; it stays a leaf over its slot range in `out` and
    /// is recorded in `jobs`, in the order the single-threaded build would have reached it. Build
    /// each job's primitives ([`BuildArena::prim`]) with [`Builder::build_subtree_into`] at the
    /// job's depth and graft the results to get the single-threaded tree.
    pub fn build_top(
        &self,
        arena: &mut BuildArena,
        out: &mut Bvh,
        cutoff: u32,
        jobs: &mut Vec<Subtree>,
    ) -> Result<BuildStats, BuildError> {
        self.build_top_with(arena, out, cutoff, jobs, &SerialBinner)
    }

    /// [`Builder::build_top`] with the binning passes offered to `binner` first: a threaded host
    /// bins the large top nodes on several threads. The result does not depend on the binner.
    pub fn build_top_with(
        &self,
        arena: &mut BuildArena,
        out: &mut Bvh,
        cutoff: u32,
        jobs: &mut Vec<Subtree>,
        binner: &impl NodeBinner,
    ) -> Result<BuildStats, BuildError> {
        jobs.clear();
        self.build_top_into(arena, out, cutoff, jobs, binner)
    }

    /// [`Builder::build_top_with`] handing each subtree to `sink` the moment the top leaves it,
    /// with the arena its primitives are in: a threaded host copies them out and starts building
    /// the subtree while the top goes on, so the top's partitions do not run alone. The top
    /// never touches a handed-over subtree's slots again.
    pub fn build_top_into(
        &self,
        arena: &mut BuildArena,
        out: &mut Bvh,
        cutoff: u32,
        sink: &mut impl SubtreeSink,
        binner: &impl NodeBinner,
    ) -> Result<BuildStats, BuildError> {
        self.build_range(arena, out, (0, None), cutoff, Some(sink), &NoClock, binner)
    }

    #[allow(clippy::too_many_arguments)]
    /// The build loop from a root at `root.0`'s depth with `root.1`'s known measure.
    fn build_range(
        &self,
        arena: &mut BuildArena,
        out: &mut Bvh,
        (depth, measure): (u32, Option<f32>),
        cutoff: u32,
        mut jobs: Option<&mut impl SubtreeSink>,
        clock: &impl Clock,
        binner: &impl NodeBinner,
    ) -> Result<BuildStats, BuildError> {
        self.config.validate()?;
        let n = arena.len();
        out.nodes.clear();
        out.prim_indices.clear();
        out.max_depth = 0;
        let mut stats = BuildStats::default();
        if n == 0 {
            return Ok(stats);
        }
        out.nodes.reserve(2 * n - 1);
        out.prim_indices.reserve(n);

        out.nodes.push(BvhNode::leaf(arena.bounds, 0, n as u32));
        arena.tasks.clear();
        let mut task = Task {
            node: 0,
            bounds: arena.bounds,
            start: 0,
            count: n as u32,
            depth,
            centroids: arena.centroids,
            measure,
        };
        loop {
            stats.max_depth = stats.max_depth.max(task.depth);
            let deferred = match jobs.as_deref_mut() {
                Some(jobs) if task.count <= cutoff => {
                    let job = Subtree {
                        node: task.node,
                        start: task.start,
                        count: task.count,
                        depth: task.depth,
                        measure: task.measure,
                    };
                    jobs.take(job, arena);
                    true
                }
                _ => false,
            };
            let decided = if deferred {
                None
            } else {
                self.split(arena, &task, &mut stats, clock, binner)
            };
            match decided {
                None => stats.leaves += u32::from(!deferred),
                Some((left, right, measures)) => {
                    let l = out.nodes.len() as u32;
                    out.nodes[task.node as usize].left_first = l;
                    out.nodes[task.node as usize].count = 0;
                    out.nodes.push(BvhNode::leaf(left.0, task.start, left.1));
                    out.nodes
                        .push(BvhNode::leaf(right.0, task.start + left.1, right.1));
                    let depth = task.depth + 1;
                    arena.tasks.push(Task {
                        node: l + 1,
                        bounds: right.0,
                        start: task.start + left.1,
                        count: right.1,
                        depth,
                        centroids: right.2,
                        measure: measures.map(|m| m[1]),
                    });
                    task = Task {
                        node: l,
                        bounds: left.0,
                        start: task.start,
                        count: left.1,
                        depth,
                        centroids: left.2,
                        measure: measures.map(|m| m[0]),
                    };
                    continue;
                }
            }
            match arena.tasks.pop() {
                Some(next) => task = next,
                None => break,
            }
        }
        out.prim_indices.extend(arena.refs.ids());
        out.max_depth = stats.max_depth;
        stats.nodes = out.nodes.len() as u32;
        Ok(stats)
    }

    /// Decides one node: `None` for a leaf, or the two children after partitioning the node's
    /// slots in place, with their measures under the builder's model when the split priced them
    /// under it.
    fn split(
        &self,
        arena: &mut BuildArena,
        task: &Task,
        stats: &mut BuildStats,
        clock: &impl Clock,
        binner: &impl NodeBinner,
    ) -> Option<(Child, Child, Option<[f32; 2]>)> {
        let (count, bounds) = (task.count, &task.bounds);
        if task.depth >= self.config.max_depth || count <= 1 {
            return None;
        }
        if self.termination.must_stop(count, task.depth) {
            return None;
        }
        // The depth budget: a node that could not finish with halving splits alone takes them now.
        if task.depth + ceil_log2(count) >= self.config.max_depth {
            stats.median_splits += 1;
            let (l, r) = median_split(&mut arena.refs, task);
            return Some((l, r, None));
        }
        let parent = task.measure.unwrap_or_else(|| self.cost.measure(bounds));
        let modelled = parent > 0.0 && parent.is_finite();
        let chosen = if modelled {
            self.choose(
                &self.cost,
                parent,
                arena,
                task,
                &mut stats.profile,
                clock,
                binner,
            )
            .map(|(s, how)| (s, how, s.cut.weighted / parent))
        } else {
            // No modelled ray reaches this node (a PAH node outside the light window): SAH, the
            // uniform-ray model, still orders its subtree sensibly for every other ray.
            let parent = Sah.measure(bounds);
            (parent > 0.0 && parent.is_finite())
                .then(|| self.choose(&Sah, parent, arena, task, &mut stats.profile, clock, binner))
                .flatten()
                .map(|(s, how)| (s, how, s.cut.weighted / parent))
        };
        let k = self.config.constants;
        let leaf_cost = k.intersection * count as f32;
        let Some((best, how, relative)) = chosen else {
            // No plane separates the centroids.
            if self
                .termination
                .prefer_leaf(count, leaf_cost, f32::INFINITY)
            {
                return None;
            }
            stats.median_splits += 1;
            let (l, r) = median_split(&mut arena.refs, task);
            return Some((l, r, None));
        };
        let split_cost = k.traversal + k.intersection * relative;
        if self.termination.prefer_leaf(count, leaf_cost, split_cost) {
            return None;
        }
        let (l, r) = match how {
            Partition::Plane(map) => partition(arena, task, &best, &map),
            Partition::Mask(mask) => partition_mask(arena, task, &best, mask),
        };
        // The children's boxes are the cut's, so its measures are theirs; under the SAH stand-in
        // they are SAH's, not the model's, and the children measure themselves.
        let measures = modelled.then_some([best.cut.measure_left, best.cut.measure_right]);
        Some((l, r, measures))
    }

    /// Bins for a node of `count` primitives. Centroid bins adapt to small nodes (`count / 2`
    /// bins, at least 4): a sweep's cost grows with its bins, small nodes are most of the tree,
    /// and bins for more than half the centroids mostly add empty or near-duplicate boundaries
    /// (the SAH cost moves by 0.02%; measured: benches/RESULTS.md, section Build speed (single and
    /// multi thread)). Node-box planes stay as configured, as the thesis placed them.
    #[inline]
    fn bins_for(&self, count: u32) -> u32 {
        match self.config.bin_space {
            BinSpace::Centroids => self.config.bins.min((count / 2).max(4)),
            BinSpace::NodeBox => self.config.bins,
        }
    }

    /// True when a node of `count` primitives prices every bipartition
    /// ([`BuildConfig::exhaustive_max`]).
    #[inline]
    fn exhaustive(&self, count: u32) -> bool {
        count <= self.config.exhaustive_max
            && self.config.cut == CutEvaluation::BestOfAxes
            && self.config.bin_space == BinSpace::Centroids
    }

    /// The axes a node's cut evaluation sweeps: those the chooser names, its first only, or all
    /// three (the thesis's last resort, SAH on the longest axis, needs it whatever the chooser said).
    fn swept_axes(&self, order: &AxisOrder) -> [bool; 3] {
        let mut swept = [false; 3];
        match self.config.cut {
            CutEvaluation::BestOfAxes => order.iter().for_each(|(a, _)| swept[a] = true),
            CutEvaluation::FirstAxis => {
                if let Some((a, _)) = order.iter().next() {
                    swept[a] = true;
                }
            }
            CutEvaluation::Thesis(_) => swept = [true; 3],
        }
        swept
    }

    /// Bins the node along the axes the cut evaluation needs, then applies it with `model` (or,
    /// for a tiny node, prices every bipartition). Returns the split and how to partition by it.
    #[allow(clippy::too_many_arguments)]
    fn choose<M: CostModel>(
        &self,
        model: &M,
        parent: f32,
        arena: &mut BuildArena,
        task: &Task,
        profile: &mut PhaseProfile,
        clock: &impl Clock,
        binner: &impl NodeBinner,
    ) -> Option<(Split, Partition)> {
        let bounds = &task.bounds;
        let t0 = clock.now_ns();
        let order = self.axes.order(bounds);
        profile.choose_ns += clock.now_ns() - t0;
        profile.choose_calls += 1;
        if self.exhaustive(task.count) {
            let t0 = clock.now_ns();
            let slots = arena.refs.slots(task.start as usize, task.count as usize);
            let hint = model.hint(bounds);
            let found = cheapest_bipartition(slots, &mut arena.subsets, model, hint);
            profile.cost_ns += clock.now_ns() - t0;
            profile.cost_calls += 1;
            // The axis means nothing to a mask partition.
            let (cut, mask) = found?;
            return Some((Split { axis: 0, cut }, Partition::Mask(mask)));
        }
        let nb = self.bins_for(task.count);
        let (cut, largest) = (self.config.cut, bounds.largest_axis());
        if task.count == 2 && self.config.bin_space == BinSpace::Centroids {
            // Every separating axis prices the same split and the walk keeps the first, so one
            // axis suffices. No binning needed.
            let t0 = clock.now_ns();
            let mut found = None;
            let split = walk(cut, &order, parent, largest, |axis, sah| {
                if sah {
                    return split_pair(&Sah, arena, task, axis, nb)
                        .map(|c| c.priced_under(model, 0));
                }
                found = found.or_else(|| split_pair(model, arena, task, axis, nb));
                found
            });
            profile.cost_ns += clock.now_ns() - t0;
            profile.cost_calls += 1;
            return split.and_then(|s| Some((s, Partition::Plane(pair_map(task, s.axis, nb)?))));
        }
        let maps = self.bin(arena, task, bounds, self.swept_axes(&order), nb, binner);
        // The bins past `nb` up to a multiple of four are empty (see `bin`).
        let nb = (nb as usize).next_multiple_of(4);
        let BuildArena { bins, sweep, .. } = arena;
        // Every candidate box lies inside the node: what the model can settle for all of them
        // (say, that they are inside the light's window) it settles once here.
        let hint = model.hint(bounds);
        let split = walk(cut, &order, parent, largest, |axis, sah| {
            maps[axis]?;
            let t0 = clock.now_ns();
            let bins = &bins[axis][..nb];
            let cut = if sah {
                sweep_axis(bins, sweep, &Sah, 0).map(|c| c.priced_under(model, hint))
            } else {
                sweep_axis(bins, sweep, model, hint)
            };
            profile.cost_ns += clock.now_ns() - t0;
            profile.cost_calls += 1;
            cut
        })?;
        Some((split, Partition::Plane(maps[split.axis]?)))
    }

    /// Bins the node's primitives along the `axes` flagged, in one pass over its slots. Returns
    /// the bin map of each binned axis (`None` where no plane can separate the centroids).
    fn bin(
        &self,
        arena: &mut BuildArena,
        task: &Task,
        bounds: &Aabb,
        axes: [bool; 3],
        nb: u32,
        binner: &impl NodeBinner,
    ) -> [Option<BinMap>; 3] {
        let maps: [Option<BinMap>; 3] = core::array::from_fn(|axis| {
            if !axes[axis] {
                return None;
            }
            let (lo, hi) = match self.config.bin_space {
                BinSpace::Centroids => (task.centroids.min[axis], task.centroids.max[axis]),
                // Doubled like the centroids they classify.
                BinSpace::NodeBox => (2.0 * bounds.min[axis], 2.0 * bounds.max[axis]),
            };
            // A node box with extent but coincident centroids cannot be split by any plane.
            (task.centroids.max[axis] > task.centroids.min[axis])
                .then(|| BinMap::new(lo, hi, nb))
                .flatten()
        });
        for (bins, map) in arena.bins.iter_mut().zip(&maps) {
            if map.is_some() {
                // Up to a multiple of four: empty bins past the last add boundaries with an
                // empty side, which never win, and let the sweep run with a constant length.
                bins[..(nb as usize).next_multiple_of(4)].fill(Bin::EMPTY);
            }
        }
        // All three axes' bin indices in one 4-wide evaluation; an axis that is not binned gets
        // scale 0, so bin 0, and is skipped. The arithmetic is `BinMap::bin`'s, lane by lane, so
        // the partition classifies every primitive exactly as the bins counted it.
        let lane = |f: fn(&BinMap) -> f32| {
            f32x4::from([
                maps[0].as_ref().map_or(0.0, f),
                maps[1].as_ref().map_or(0.0, f),
                maps[2].as_ref().map_or(0.0, f),
                0.0,
            ])
        };
        let (min, scale, last) = (lane(|m| m.min), lane(|m| m.scale), lane(|m| m.last));
        let active = [maps[0].is_some(), maps[1].is_some(), maps[2].is_some()];
        let slots = arena.refs.slots(task.start as usize, task.count as usize);
        let job = BinJob::new(slots, min, scale, last);
        if let Some(parts) = binner.bin(&job) {
            arena.bins = parts.bins;
        } else if active == [true; 3] {
            // The common case (every axis has extent): no per-primitive branch.
            if slots.len() >= DUAL_BINNING_MIN {
                let nbp = (nb as usize).next_multiple_of(4);
                for bins in &mut arena.bins2 {
                    bins[..nbp].fill(Bin::EMPTY);
                }
                job.bin_into_dual(slots, &mut arena.bins, &mut arena.bins2);
                for (mine, theirs) in arena.bins.iter_mut().zip(&arena.bins2) {
                    for (a, b) in mine[..nbp].iter_mut().zip(&theirs[..nbp]) {
                        a.merge(b);
                    }
                }
            } else {
                job.bin_into(slots, &mut arena.bins);
            }
        } else {
            let [bx, by, bz] = &mut arena.bins;
            let bins = [bx, by, bz];
            for r in slots {
                let (lo, hi) = (r.lo4(), r.hi4());
                let at = job.offsets(lo, hi);
                for axis in 0..3 {
                    if active[axis] {
                        at.bin(bins[axis], axis).grow(lo, hi);
                    }
                }
            }
        }
        maps
    }
}

#[cfg(test)]
mod tests {
    use alloc::vec::Vec;

    use glam::Vec3;

    use super::*;
    use crate::brute_force;
    use crate::geometry::Ray;
    use crate::heuristics::LeafSize;

    fn soup(n: usize, seed: u64) -> Vec<Triangle> {
        crate::test_scenes::soup(n, seed, 0.0, 10.0, 1.0)
    }

    fn check_against_brute_force<A: AxisChooser, C: CostModel, T: Termination>(
        builder: &Builder<A, C, T>,
        tris: &[Triangle],
    ) {
        let bvh = builder.build(tris).unwrap();
        bvh.validate(tris.len(), |i| tris[i as usize].bounds())
            .unwrap();
        let mut rng = crate::random::Pcg32::new(99);
        let mut v = |a: f32, b: f32| Vec3::new(rng.range(a, b), rng.range(a, b), rng.range(a, b));
        for _ in 0..300 {
            let o = v(-1.0, 11.0);
            let d = v(-1.0, 1.0);
            let Ok(ray) = Ray::new(o, d) else { continue };
            let expect = brute_force::closest_hit(&ray, tris);
            assert_eq!(bvh.closest_hit(&ray, tris), expect);
            assert_eq!(bvh.any_hit(&ray, tris), expect.is_some());
            assert_eq!(
                bvh.all_hit(&ray, tris).hits,
                brute_force::hit_count(&ray, tris)
            );
        }
    }

    #[test]
    fn sah_and_lsph_agree_with_brute_force() {
        let tris = soup(500, 7);
        check_against_brute_force(&Builder::sah(), &tris);
        check_against_brute_force(&Builder::lsph(), &tris);
        let thesis = Builder::new(
            AllAxes,
            Sah,
            LeafSize { max_leaf: 2 },
            BuildConfig::default(),
        );
        check_against_brute_force(&thesis, &tris);
    }

    #[test]
    fn empty_and_single() {
        let bvh = Builder::sah().build(&[]).unwrap();
        assert!(bvh.nodes().is_empty());
        let ray = Ray::new(Vec3::ZERO, Vec3::X).unwrap();
        assert!(bvh.closest_hit(&ray, &[]).is_none());
        assert!(!bvh.any_hit(&ray, &[]));
        let one = soup(1, 3);
        let bvh = Builder::sah().build(&one).unwrap();
        assert_eq!(bvh.nodes().len(), 1);
        bvh.validate(1, |i| one[i as usize].bounds()).unwrap();
    }

    #[test]
    fn identical_triangles_split_by_median_within_depth() {
        let tri = soup(1, 5)[0];
        let tris = alloc::vec![tri; 1000];
        let b = Builder::new(
            AllAxes,
            Sah,
            LeafSize { max_leaf: 1 },
            BuildConfig::default(),
        );
        let bvh = b.build(&tris).unwrap();
        bvh.validate(tris.len(), |i| tris[i as usize].bounds())
            .unwrap();
        assert_eq!(bvh.leaf_count(), 1000);
        assert!(bvh.max_depth() <= 10, "depth {}", bvh.max_depth());
    }

    /// Two triangles near +-f32::MAX whose doubled centroids overflow to +-inf, so the bin scale
    /// rounds to zero and both fall in bin 0: the two-primitive shortcut must not assume they sit
    /// in the first and the last bin (a `build_query` fuzz case).
    #[test]
    fn two_primitives_sharing_a_bin_are_not_split_by_it() {
        // Thin in y and z, so the node's surface area stays finite while the centroids'
        // extent (6e38) does not.
        let at = |x: f32| {
            Triangle::new(
                Vec3::new(x, 0.0, 0.0),
                Vec3::new(x, 1e-3, 0.0),
                Vec3::new(x, 0.0, 1e-3),
            )
        };
        // The larger centroid first, so a wrong split would show in the boxes.
        let tris = [at(1.5e38), at(-1.5e38)];
        for bvh in [Builder::sah().build(&tris), Builder::lsph().build(&tris)] {
            let bvh = bvh.unwrap();
            bvh.validate(tris.len(), |i| tris[i as usize].bounds())
                .unwrap();
            for x in [1.5e38f32, -1.5e38] {
                let ray = Ray::new(Vec3::new(x, 2e-4, -1.0), Vec3::Z).unwrap();
                assert_eq!(
                    bvh.closest_hit(&ray, &tris),
                    crate::brute_force::closest_hit(&ray, &tris)
                );
            }
        }
    }

    #[test]
    fn geometric_progression_respects_depth_bound() {
        // Each triangle twice as far as the previous: SAH peels one off per level.
        let tris: Vec<Triangle> = (0..60)
            .map(|i| {
                let x = 1.5f32.powi(i);
                Triangle::new(
                    Vec3::new(x, 0.0, 0.0),
                    Vec3::new(x, 1.0, 0.0),
                    Vec3::new(x, 0.0, 1.0),
                )
            })
            .collect();
        for max_depth in [6, 8, 64] {
            let config = BuildConfig {
                max_depth,
                ..BuildConfig::default()
            };
            let b = Builder::new(AllAxes, Sah, LeafSize { max_leaf: 1 }, config);
            let bvh = b.build(&tris).unwrap();
            bvh.validate(tris.len(), |i| tris[i as usize].bounds())
                .unwrap();
            assert!(bvh.max_depth() <= max_depth);
        }
    }

    #[test]
    fn rejects_nan_and_bad_config() {
        let mut tris = soup(3, 1);
        tris[1].v2.y = f32::NAN;
        assert_eq!(
            Builder::sah().build(&tris),
            Err(BuildError::InvalidPrimitive { index: 1 })
        );
        let bad = Builder::sah().with_config(BuildConfig {
            bins: 1,
            ..BuildConfig::default()
        });
        assert!(matches!(
            bad.build(&soup(3, 1)),
            Err(BuildError::InvalidConfig(_))
        ));
    }

    #[test]
    fn threshold_classifies_like_the_bins() {
        let mut rng = crate::random::Pcg32::new(5);
        for round in 0..2000 {
            // Offsets far from the origin make `min + bin / scale` cancel badly.
            let offset = [0.0, 1e3, -1e5, 3e7][round % 4];
            let lo = offset + rng.range(-10.0, 10.0);
            let hi = lo + rng.range(1e-4, 20.0);
            let nb = 2 + (round as u32 % 15);
            let Some(map) = BinMap::new(lo, hi, nb) else {
                continue;
            };
            for bin in 1..nb as usize {
                let t = map.threshold(bin);
                assert!(map.bin(t) >= bin && map.bin(t.next_down()) < bin);
                for _ in 0..20 {
                    let c = lo + rng.range(0.0, 1.0) * (hi - lo);
                    assert_eq!(c < t, map.bin(c) < bin, "{map:?} bin {bin} c {c} t {t}");
                }
            }
        }
    }

    /// The binning pass computes byte offsets from byte-scaled maps; they must be exactly the
    /// bin size times `BinMap::bin`, which the partition's threshold reproduces.
    #[test]
    fn bin_offsets_match_the_bin_map() {
        let mut rng = crate::random::Pcg32::new(17);
        let bin_bytes = core::mem::size_of::<Bin>() as u32;
        for round in 0..3000 {
            let offset = [0.0, 1e3, -1e5, 3e7, 1e30][round % 5];
            let lo = offset + rng.range(-10.0, 10.0);
            let hi = [lo + rng.range(1e-4, 20.0), lo + 1e-30, f32::MAX][round % 3];
            // Every seventh case, a range near the smallest normal floats, where the scale is
            // finite but the byte-scaled one would overflow, so binning and partition could put a
            // subnormal centroid in different bins (`fuzz/regressions/build_query/`).
            let (lo, hi) = if round % 7 == 6 {
                let lo = [0.0, 1e-38, -2e-38, 1e-40][round % 4];
                (lo, lo + [1e-36, 1e-37, 2.35e-38, 1e-39][(round / 7) % 4])
            } else {
                (lo, hi)
            };
            let nb = 2 + (round as u32 % 63);
            let Some(map) = BinMap::new(lo, hi, nb) else {
                continue;
            };
            let job = BinJob::new(
                &[],
                f32x4::splat(map.min),
                f32x4::splat(map.scale),
                f32x4::splat(map.last),
            );
            for k in 0..40 {
                let c = match k {
                    0 => lo,
                    1 => hi,
                    2 => map.threshold(1 + round % (nb as usize - 1)),
                    3 => map.threshold(1 + round % (nb as usize - 1)).next_down(),
                    _ => lo + rng.range(0.0, 1.0) * (hi - lo),
                };
                // The centroid is `lo + hi` of the box: pass it as `lo` with a zero `hi`.
                let at = job.offsets(f32x4::splat(c), f32x4::ZERO);
                let expect = map.bin(c) as u32 * bin_bytes;
                assert_eq!(at.lanes()[0], expect, "{map:?} c {c}");
            }
        }
    }

    #[test]
    fn median_selection_orders_around_nth() {
        let tris = soup(257, 11);
        let mut arena = BuildArena::with_capacity(tris.len());
        arena.load_triangles(&tris).unwrap();
        let n = tris.len();
        select_nth(&mut arena.refs, 0, n, n / 2, 0);
        let pivot = arena.refs.centroid2_axis(n / 2, 0);
        assert!((0..n / 2).all(|i| arena.refs.centroid2_axis(i, 0) <= pivot));
        assert!((n / 2..n).all(|i| arena.refs.centroid2_axis(i, 0) >= pivot));
    }

    #[test]
    fn a_sweep_prices_the_same_whatever_an_earlier_sweep_left() {
        // Stale lanes past the last boundary must not change a price, or a fresh arena (a
        // threaded job's) and a reused one (the single-threaded build's) would build different
        // trees. Emptied padding and a per-lane rule choice each keep this passing.
        use crate::heuristics::{PahPerspective, PerspectiveMeasure};
        use crate::influence::PointArea;
        let area = PointArea::new(Vec3::ZERO, Vec3::Z, 60.0, 60.0, 0.1, 1e4).unwrap();
        let pah = PahPerspective::for_area(&area, PerspectiveMeasure::SolidAngle);
        // Four bins 1e3 ahead: each candidate box is far-field but the node is not, so each
        // lane decides; and a box near the eye (exact) to leave behind.
        let bins: [Bin; 4] = core::array::from_fn(|i| {
            let lo = Vec3::new(i as f32 * 4.975 - 9.95, -0.01, 1e3);
            let hi = lo + Vec3::new(4.975, 0.02, 0.02);
            let mut b = Bin::EMPTY;
            b.grow(
                f32x4::from(lo.extend(0.0).to_array()),
                f32x4::from(hi.extend(0.0).to_array()),
            );
            b.count = 1;
            b
        });
        let mut near = Bin::EMPTY;
        near.grow(
            f32x4::from([-1.0, -1.0, 1.0, 0.0]),
            f32x4::from([1.0, 1.0, 3.0, 0.0]),
        );
        let node = bins.iter().fold(Aabb::EMPTY, |b, bin| {
            let (lo, hi) = (bin.min.to_array(), bin.max.to_array());
            b.union(Aabb::new(
                Vec3::from_slice(&lo[..3]),
                Vec3::from_slice(&hi[..3]),
            ))
        });
        let hint = pah.hint(&node);
        let mut fresh = BuildArena::with_capacity(0);
        let mut reused = BuildArena::with_capacity(0);
        for i in 0..=crate::builder::MAX_BINS as usize {
            reused.sweep.left.set(i, &near);
            reused.sweep.right.set(i, &near);
        }
        let a = sweep_axis(&bins, &mut fresh.sweep, &pah, hint).unwrap();
        let b = sweep_axis(&bins, &mut reused.sweep, &pah, hint).unwrap();
        let bits = |c: &Cut| [c.weighted, c.measure_left, c.measure_right].map(f32::to_bits);
        assert_eq!((a.at, bits(&a)), (b.at, bits(&b)));
    }
}
