//! Grafting separately built subtrees into the top of a build: the assembly step of threaded
//! builds, which gives exactly the single-threaded tree.

use alloc::vec::Vec;

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
}

impl core::fmt::Display for GraftError {
    fn fmt(&self, f: &mut core::fmt::Formatter<'_>) -> core::fmt::Result {
        match self {
            GraftError::CountMismatch => f.write_str("one subtree per job is needed"),
            GraftError::BadSubtree { job } => write!(f, "subtree {job} does not match its job"),
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
        Ok(Bvh {
            nodes: canonical_layout(&top_nodes, &job_of, jobs, subtrees, total),
            prim_indices,
            max_depth,
        })
    }
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
/// job: only the top nodes are walked, and each subtree is one block copy.
fn canonical_layout(
    top: &[BvhNode],
    job_of: &[u32],
    jobs: &[Subtree],
    subtrees: &[Bvh],
    total: usize,
) -> Vec<BvhNode> {
    let mut out: Vec<BvhNode> = alloc::vec![bytemuck::Zeroable::zeroed(); total];
    if top.is_empty() {
        return out;
    }
    out[0] = top[0];
    let mut next = 1usize;
    // (top index, new index) of nodes whose subtrees are not laid out yet.
    let mut pending: Vec<(u32, u32)> = Vec::new();
    let mut current = (0u32, 0u32);
    loop {
        let (old, new) = (current.0 as usize, current.1 as usize);
        let j = job_of[old];
        if j != u32::MAX {
            let (job, sub) = (&jobs[j as usize], &subtrees[j as usize]);
            let offset = next as u32;
            out[new] = place(&sub.nodes[0], job.start, offset);
            let block = &mut out[next..next + sub.nodes.len() - 1];
            for (dst, n) in block.iter_mut().zip(&sub.nodes[1..]) {
                *dst = place(n, job.start, offset);
            }
            next += sub.nodes.len() - 1;
        } else if !top[old].is_leaf() {
            let l_old = top[old].left_first as usize;
            let l_new = next as u32;
            out[next] = top[l_old];
            out[next + 1] = top[l_old + 1];
            next += 2;
            out[new].left_first = l_new;
            pending.push((l_old as u32 + 1, l_new + 1));
            current = (l_old as u32, l_new);
            continue;
        }
        match pending.pop() {
            Some(p) => current = p,
            None => break,
        }
    }
    debug_assert_eq!(next, total);
    out
}

#[cfg(test)]
mod tests {
    use alloc::vec::Vec;

    use glam::Vec3;

    use super::*;
    use crate::build::{BuildArena, BuildConfig, Builder};
    use crate::geometry::Triangle;
    use crate::heuristics::{
        AllAxes, AxisChooser, CostModel, PahPerspective, PerspectiveMeasure, SahTermination,
        Termination,
    };
    use crate::influence::PointArea;

    fn check_graft<A: AxisChooser, C: CostModel, T: Termination>(
        builder: &Builder<A, C, T>,
        tris: &[Triangle],
    ) {
        let whole = builder.build(tris).unwrap();
        for cutoff in [1, 7, 100, 1000, 5000] {
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

    #[test]
    fn mismatched_jobs_are_errors() {
        assert_eq!(
            Bvh::graft(Bvh::default(), &[], &[Bvh::default()]),
            Err(GraftError::CountMismatch)
        );
    }
}
