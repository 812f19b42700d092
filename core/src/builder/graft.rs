//! Grafting separately built subtrees into the top of a build: the assembly step of threaded
//! builds, which gives exactly the single-threaded tree.

use alloc::vec::Vec;
use core::mem::MaybeUninit;

use super::Subtree;
use crate::bvh::{Bvh, BvhNode};

/// Why subtrees could not be grafted.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum GraftError {
    /// `jobs` and `subtrees` differ in length.
    CountMismatch,
    /// A subtree does not cover its job's primitives, or its job is not a leaf of the top.
    BadSubtree {
        /// Index of the job.
        job: usize,
    },
    /// The top is not a tree a build made: a walk from its root does not reach each of its
    /// nodes exactly once.
    BadTop,
}

impl core::fmt::Display for GraftError {
    fn fmt(&self, f: &mut core::fmt::Formatter<'_>) -> core::fmt::Result {
        match self {
            GraftError::CountMismatch => f.write_str("one subtree per job is needed"),
            GraftError::BadSubtree { job } => write!(f, "subtree {job} does not match its job"),
            GraftError::BadTop => f.write_str("the top is not a tree from a build"),
        }
    }
}

impl core::error::Error for GraftError {}

impl Bvh {
    /// Replaces each job's placeholder leaf in `top` (from [`super::Builder::build_top`]) with the
    /// subtree built for it (with [`super::Builder::build_subtree_into`] for the job, over its
    /// slots in slot order), then lays the nodes out in the order the single-threaded builder
    /// allocates them, so the result equals `build_into`'s tree node for node.
    pub fn graft(top: Bvh, jobs: &[Subtree], subtrees: &[Bvh]) -> Result<Bvh, GraftError> {
        Self::graft_with(top, jobs, subtrees, |blocks| {
            blocks.into_iter().for_each(GraftBlock::copy)
        })
    }

    /// [`Bvh::graft`] with the copying of the subtrees handed to `run`, for threaded hosts: `run`
    /// gets one [`GraftBlock`] per job, each writing its own part of the new tree, and calls
    /// [`GraftBlock::copy`] on every one, on any thread and in any order; the tree is the same
    /// (a block `run` drops is copied after it returns). The copies are nearly all of a graft's
    /// work: the top is a few hundred nodes.
    pub fn graft_with<R>(
        top: Bvh,
        jobs: &[Subtree],
        subtrees: &[Bvh],
        run: R,
    ) -> Result<Bvh, GraftError>
    where
        R: FnOnce(Vec<GraftBlock<'_>>),
    {
        if jobs.len() != subtrees.len() {
            return Err(GraftError::CountMismatch);
        }
        let top_nodes = top.nodes;
        let mut prim_indices = top.prim_indices;
        let mut max_depth = top.max_depth;
        // Which job, if any, each top node is the placeholder of.
        let mut job_of = alloc::vec![u32::MAX; top_nodes.len()];
        let mut total = top_nodes.len();
        for (j, (job, sub)) in jobs.iter().zip(subtrees).enumerate() {
            let bad = GraftError::BadSubtree { job: j };
            let (start, count) = (job.start as usize, job.count as usize);
            let placeholder = top_nodes.get(job.node as usize).ok_or(bad)?;
            let slot = &mut job_of[job.node as usize];
            if !placeholder.is_leaf()
                || sub.prim_indices.len() != count
                || sub.nodes.is_empty()
                || *slot != u32::MAX
            {
                return Err(bad);
            }
            *slot = j as u32;
            prim_indices
                .get_mut(start..start + count)
                .ok_or(bad)?
                .copy_from_slice(&sub.prim_indices);
            max_depth = max_depth.max(sub.max_depth);
            total += sub.nodes.len() - 1;
        }
        // The new tree is written once, node by node, into uninitialised memory: zeroing it
        // first would write every node and take every page fault on one thread, where the blocks'
        // writes spread them over all threads.
        let mut nodes: Vec<BvhNode> = Vec::with_capacity(total);
        let out = &mut nodes.spare_capacity_mut()[..total];
        let placed = canonical_layout(&top_nodes, &job_of, jobs, subtrees, out)?;
        let mut copied = alloc::vec![false; placed.len()];
        run(blocks(out, &placed, &mut copied, jobs, subtrees));
        // A block `run` left out is copied here, so every node is written whatever the host did.
        let missed = placed.iter().zip(&copied).filter(|(_, &done)| !done);
        let missed: Vec<(u32, u32)> = missed.map(|(p, _)| *p).collect();
        let mut ignored = alloc::vec![false; missed.len()];
        blocks(out, &missed, &mut ignored, jobs, subtrees)
            .into_iter()
            .for_each(GraftBlock::copy);
        // SAFETY: `canonical_layout` wrote every top node and job root, exactly the slots outside
        // the job blocks (it checked that they and the blocks add up to `total`), and every block
        // was copied, by `run` or just above.
        unsafe { nodes.set_len(total) };
        Ok(Bvh {
            nodes,
            prim_indices,
            max_depth,
        })
    }
}

/// One job's subtree to copy into a grafted tree ([`Bvh::graft_with`]): every node after its
/// root (the root is placed with the top), moved to its place in the whole tree.
#[derive(Debug)]
pub struct GraftBlock<'a> {
    dst: &'a mut [MaybeUninit<BvhNode>],
    src: &'a [BvhNode],
    start: u32,
    offset: u32,
    copied: &'a mut bool,
}

impl GraftBlock<'_> {
    /// Copies the block into the tree.
    pub fn copy(self) {
        for (dst, n) in self.dst.iter_mut().zip(self.src) {
            dst.write(place(n, self.start, self.offset));
        }
        *self.copied = true;
    }

    /// Nodes in the block.
    pub fn len(&self) -> usize {
        self.dst.len()
    }

    /// True for a subtree that is a single leaf.
    pub fn is_empty(&self) -> bool {
        self.dst.is_empty()
    }
}

/// Cuts `nodes` into the disjoint blocks of the jobs `placed` (job index and offset, by
/// increasing offset, as [`canonical_layout`] returns them), each flagging `copied` when done.
fn blocks<'a>(
    nodes: &'a mut [MaybeUninit<BvhNode>],
    placed: &[(u32, u32)],
    copied: &'a mut [bool],
    jobs: &[Subtree],
    subtrees: &'a [Bvh],
) -> Vec<GraftBlock<'a>> {
    let mut out = Vec::with_capacity(placed.len());
    let (mut rest, mut at) = (nodes, 0usize);
    for (&(j, offset), copied) in placed.iter().zip(copied) {
        let src = &subtrees[j as usize].nodes[1..];
        let (_, tail) = core::mem::take(&mut rest).split_at_mut(offset as usize - at);
        let (dst, tail) = tail.split_at_mut(src.len());
        (rest, at) = (tail, offset as usize + src.len());
        out.push(GraftBlock {
            dst,
            src,
            start: jobs[j as usize].start,
            offset,
            copied,
        });
    }
    out
}

/// A subtree node moved into the whole tree: local node `i >= 1` goes to `offset + i - 1`, local
/// slot `s` to `start + s`.
#[inline]
fn place(n: &BvhNode, start: u32, offset: u32) -> BvhNode {
    BvhNode {
        left_first: if n.is_leaf() {
            n.left_first + start
        } else {
            n.left_first - 1 + offset
        },
        ..*n
    }
}

/// The whole tree laid out as the single-threaded builder allocates it, in one pass: root first;
/// splitting a node appends its two children; the left subtree is finished before the right one
/// is opened. A job's subtree is built without interruption there, so its nodes after its root
/// form one block, in the subtree's own order, placed when the walk over the top reaches the
/// job. Only the top nodes are walked and written into `out` (sized for the whole tree), with
/// each job's root; returns where each job's block goes, `(job, offset)` by increasing offset,
/// for [`GraftBlock::copy`]. Fails on a top whose walk does not reach each of its nodes once (a
/// node outside it, a cycle, nodes no walk reaches), which would leave `out` partly unwritten.
fn canonical_layout(
    top: &[BvhNode],
    job_of: &[u32],
    jobs: &[Subtree],
    subtrees: &[Bvh],
    out: &mut [MaybeUninit<BvhNode>],
) -> Result<Vec<(u32, u32)>, GraftError> {
    let mut placed = Vec::with_capacity(jobs.len());
    if top.is_empty() {
        return (out.is_empty()).then_some(placed).ok_or(GraftError::BadTop);
    }
    let mut next = 1usize;
    let mut visited = 0usize;
    // (top index, new index) of nodes whose subtrees are not laid out yet.
    let mut pending: Vec<(u32, u32)> = Vec::new();
    let mut current = (0u32, 0u32);
    loop {
        let (old, new) = (current.0 as usize, current.1 as usize);
        visited += 1;
        let node = top.get(old).ok_or(GraftError::BadTop)?;
        let j = job_of[old];
        let placed_node = if j != u32::MAX {
            let (job, sub) = (&jobs[j as usize], &subtrees[j as usize]);
            let offset = next as u32;
            placed.push((j, offset));
            next += sub.nodes.len() - 1;
            place(&sub.nodes[0], job.start, offset)
        } else if !node.is_leaf() {
            let l_new = next as u32;
            next += 2;
            pending.push((node.left_first.wrapping_add(1), l_new + 1));
            BvhNode {
                left_first: l_new,
                ..*node
            }
        } else {
            *node
        };
        if visited > top.len() || next > out.len() {
            return Err(GraftError::BadTop);
        }
        out[new].write(placed_node);
        if !node.is_leaf() && j == u32::MAX {
            current = (node.left_first, next as u32 - 2);
            continue;
        }
        match pending.pop() {
            Some(p) => current = p,
            None => break,
        }
    }
    // Each top node visited once and the blocks after them: every slot of `out` written once.
    if visited != top.len() || next != out.len() {
        return Err(GraftError::BadTop);
    }
    Ok(placed)
}

#[cfg(test)]
mod tests {
    use alloc::vec::Vec;

    use glam::Vec3;

    use super::*;
    use crate::builder::{BuildArena, BuildConfig, Builder};
    use crate::geometry::Triangle;
    use crate::heuristics::{
        AllAxes, AxisChooser, CostModel, PahPerspective, PerspectiveMeasure, SahTermination,
        Termination,
    };
    use crate::influence::PointArea;

    /// The top of `builder`'s build over `tris` with subtrees of at most `cutoff` primitives,
    /// its jobs and their subtrees.
    fn top_and_subtrees<A: AxisChooser, C: CostModel, T: Termination>(
        builder: &Builder<A, C, T>,
        tris: &[Triangle],
        cutoff: u32,
    ) -> (Bvh, Vec<Subtree>, Vec<Bvh>) {
        let mut arena = BuildArena::with_capacity(tris.len());
        arena.load_triangles(tris).unwrap();
        let mut top = Bvh::default();
        let mut jobs = Vec::new();
        builder
            .build_top(&mut arena, &mut top, cutoff, &mut jobs)
            .unwrap();
        let subtrees: Vec<Bvh> = jobs
            .iter()
            .map(|job| {
                let mut local = BuildArena::with_capacity(job.count as usize);
                for slot in job.start..job.start + job.count {
                    let (id, b) = arena.prim(slot as usize).unwrap();
                    local.push(id, b).unwrap();
                }
                let mut out = Bvh::default();
                builder
                    .build_subtree_into(&mut local, &mut out, job)
                    .unwrap();
                out
            })
            .collect();
        (top, jobs, subtrees)
    }

    /// Grafts with the blocks copied in reverse order and every third one dropped by the host
    /// (the graft copies those itself).
    fn graft_shuffled(top: Bvh, jobs: &[Subtree], subtrees: &[Bvh]) -> Result<Bvh, GraftError> {
        Bvh::graft_with(top, jobs, subtrees, |blocks| {
            let kept = blocks.into_iter().rev().enumerate();
            kept.filter(|(i, _)| i % 3 != 1).for_each(|(_, b)| b.copy());
        })
    }

    fn check_graft<A: AxisChooser, C: CostModel, T: Termination>(
        builder: &Builder<A, C, T>,
        tris: &[Triangle],
    ) {
        let whole = builder.build(tris).unwrap();
        for cutoff in [1, 7, 100, 1000, 5000] {
            let (top, jobs, subtrees) = top_and_subtrees(builder, tris, cutoff);
            let shuffled = graft_shuffled(top.clone(), &jobs, &subtrees).unwrap();
            assert!(shuffled == whole, "cutoff {cutoff}, blocks out of order");
            let grafted = Bvh::graft(top, &jobs, &subtrees).unwrap();
            assert!(grafted == whole, "cutoff {cutoff}");
        }
    }

    #[test]
    fn grafted_tree_equals_single_threaded_tree() {
        let tris = crate::test_scenes::soup(3000, 8, -10.0, 10.0, 0.5);
        check_graft(&Builder::sah(), &tris);
    }

    #[test]
    fn grafted_perspective_pah_tree_equals_single_threaded_tree() {
        let mut tris = crate::test_scenes::soup(3000, 8, -10.0, 10.0, 0.5);
        tris.extend(crate::test_scenes::soup(300, 9, -10.0, 10.0, 6.0));
        for eye in [Vec3::new(0.0, 14.0, 0.0), Vec3::new(1.0, 2.0, 0.5)] {
            let area = PointArea::new(eye, -Vec3::Y, 150.0, 150.0, 0.1, 30.0).unwrap();
            for measure in [
                PerspectiveMeasure::SolidAngle,
                PerspectiveMeasure::ImagePlane,
            ] {
                let pah = PahPerspective::for_area(&area, measure);
                let config = BuildConfig::default();
                check_graft(
                    &Builder::new(AllAxes, pah, SahTermination::default(), config),
                    &tris,
                );
            }
        }
    }

    #[test]
    fn a_subtree_build_takes_its_jobs_measure() {
        // The measure a job carries is the root's: its splits are priced relative to it. Four
        // overlapping triangles make one leaf (every split's children are as large as the
        // node); a root said to measure far more than its box makes a split look cheap.
        let tris: Vec<Triangle> = (0..4)
            .map(|i| {
                let d = 0.01 * i as f32;
                Triangle::new(
                    Vec3::new(d, 0.0, 0.0),
                    Vec3::new(1.0, 1.0 - d, 0.0),
                    Vec3::new(0.0, d, 1.0),
                )
            })
            .collect();
        let builder = Builder::sah();
        let whole = builder.build(&tris).unwrap();
        let mut arena = BuildArena::with_capacity(tris.len());
        let root = whole.bounds();
        let mut job = Subtree {
            node: 0,
            start: 0,
            count: tris.len() as u32,
            depth: 0,
            measure: None,
        };
        let mut sub = |job: &Subtree| {
            arena.load_triangles(&tris).unwrap();
            let mut out = Bvh::default();
            builder
                .build_subtree_into(&mut arena, &mut out, job)
                .unwrap();
            out
        };
        assert!(sub(&job) == whole && whole.leaf_count() == 1);
        job.measure = Some(1e3 * crate::heuristics::Sah.measure(&root));
        assert!(sub(&job).leaf_count() > whole.leaf_count());
    }

    /// The graft writes the new tree's nodes into uninitialised memory where its walk over the
    /// top puts them (the one unsafe step is declaring them all written): small enough for Miri.
    /// Blocks in any order, or dropped by the host, give the single-threaded tree; a top that is
    /// not a tree (a child outside it, a cycle, a node no walk reaches) is an error, not a tree
    /// with unwritten nodes.
    #[test]
    fn small_graft_writes_every_node_or_fails() {
        let tris = crate::test_scenes::soup(120, 3, -5.0, 5.0, 0.5);
        let builder = Builder::sah();
        let (top, jobs, subtrees) = top_and_subtrees(&builder, &tris, 20);
        assert!(jobs.len() >= 4);
        let whole = builder.build(&tris).unwrap();
        assert!(graft_shuffled(top.clone(), &jobs, &subtrees).unwrap() == whole);
        let inner = (0..top.nodes.len())
            .find(|&i| !top.nodes[i].is_leaf() && !jobs.iter().any(|j| j.node as usize == i))
            .expect("the top has an inner node");
        let n = top.nodes.len() as u32;
        for left_first in [n, n - 1, u32::MAX, 0] {
            let mut t = top.clone();
            t.nodes[inner].left_first = left_first;
            assert_eq!(
                graft_shuffled(t, &jobs, &subtrees),
                Err(GraftError::BadTop),
                "{left_first}"
            );
        }
        let mut unreachable = top.clone();
        unreachable.nodes.push(top.nodes[0]);
        assert_eq!(
            Bvh::graft(unreachable, &jobs, &subtrees),
            Err(GraftError::BadTop)
        );
    }

    #[test]
    fn mismatched_jobs_are_errors() {
        assert_eq!(
            Bvh::graft(Bvh::default(), &[], &[Bvh::default()]),
            Err(GraftError::CountMismatch)
        );
    }
}
