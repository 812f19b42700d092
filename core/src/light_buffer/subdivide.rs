//! Building a light buffer: per cube-map face, a quadtree of cells refined while that splits the
//! triangles the cells reach, and a small wide BVH over each leaf's triangles, boxed by their
//! clipped parts.

use alloc::vec;
use alloc::vec::Vec;

use glam::DVec3;

use super::buffer::{LightBuffer, LightBufferOptions, LightBufferStats, CLEAR, DARK};
use super::cell::{CellRect, CONE_MARGIN, FACES};
use super::clip::Region;
use super::source::{LightSource, MARGIN};
use crate::build::{BuildArena, Builder};
use crate::bvh::{Bvh, WideBvh};
use crate::geometry::Triangle;
use crate::BuildError;

/// The deepest `max_level` allowed: 6 faces of 256 x 256 cells, 1.5 MiB of grid.
const MAX_LEVEL: u32 = 8;

/// Children that keep on average more than this share of their parent's triangles do not pay for
/// their trees: the parent stays a leaf (an area light's cells near the light reach the same
/// triangles whatever their size).
const SPLIT_GAIN: f64 = 0.8;

/// A quadtree node still to decide: its directions, its level and position on its level's grid,
/// and the triangles its region reaches.
struct Task {
    rect: CellRect,
    level: u32,
    i: u32,
    j: u32,
    refs: Vec<u32>,
}

pub(super) fn build(
    tris: &[Triangle],
    source: LightSource,
    options: &LightBufferOptions,
) -> Result<LightBuffer, BuildError> {
    if options.max_level > MAX_LEVEL {
        return Err(BuildError::InvalidConfig("light buffer max_level above 8"));
    }
    if !(options.reference_budget >= 0.0) {
        return Err(BuildError::InvalidConfig(
            "light buffer reference_budget is negative or NaN",
        ));
    }
    if u32::try_from(tris.len()).is_err() {
        return Err(BuildError::TooManyPrimitives);
    }
    if let Some(index) = tris.iter().position(|t| !t.is_finite()) {
        return Err(BuildError::InvalidPrimitive {
            index: index as u32,
        });
    }
    let scale = tris
        .iter()
        .fold(source.bounds.min.abs().max(source.bounds.max.abs()), |m, t| {
            m.max(t.v0.abs()).max(t.v1.abs()).max(t.v2.abs())
        })
        .max_element();
    let margin = MARGIN * f64::from(scale).max(f64::from(f32::MIN_POSITIVE));
    let resolution = 1u32 << options.max_level;
    let r = resolution as usize;
    let budget = (options.reference_budget as f64 * tris.len() as f64) as usize;
    let mut out = LightBuffer {
        source,
        resolution,
        grid: vec![DARK; FACES * r * r],
        trees: Vec::new(),
        margin: margin as f32,
        stats: LightBufferStats::default(),
    };
    let all: Vec<u32> = (0..tris.len() as u32).collect();
    // References held by finished leaves and pending tasks.
    let mut held = 0usize;
    let mut leaf = Leaf::default();
    for face in 0..FACES {
        let rect = CellRect::face(face);
        if is_dark(&rect, &out.source) {
            out.stats.dark_cells += 1;
            continue;
        }
        let refs = reached(&all, tris, &Region::new(&rect, &out.source, margin));
        held += refs.len();
        let mut stack = vec![Task {
            rect,
            level: 0,
            i: 0,
            j: 0,
            refs,
        }];
        while let Some(task) = stack.pop() {
            let children = if task.level < options.max_level
                && task.refs.len() > options.leaf_triangles as usize
            {
                split(&task, tris, &out.source, margin)
            } else {
                None
            };
            let grown = children.as_ref().map_or(0, |c| {
                c.iter().map(|t| t.refs.len()).sum::<usize>()
            });
            let pays = (grown as f64) < SPLIT_GAIN * 4.0 * task.refs.len() as f64;
            match children {
                Some(children) if pays && held - task.refs.len() + grown <= budget.max(held) => {
                    held = held - task.refs.len() + grown;
                    for child in children.into_iter().rev() {
                        if is_dark(&child.rect, &out.source) {
                            held -= child.refs.len();
                            out.stats.dark_cells += 1;
                        } else {
                            stack.push(child);
                        }
                    }
                }
                _ => leaf.finish(&task, tris, margin, options.max_level, &mut out)?,
            }
        }
    }
    out.stats.memory_bytes = out.grid.len() * 4
        + out.trees.len() * core::mem::size_of::<WideBvh>()
        + out.trees.iter().map(WideBvh::memory_bytes).sum::<usize>();
    Ok(out)
}

/// The four children of `task` with the triangles each reaches, or `None` below the finest level.
fn split(task: &Task, tris: &[Triangle], source: &LightSource, margin: f64) -> Option<[Task; 4]> {
    Some(core::array::from_fn(|q| {
        let rect = task.rect.quadrant(q);
        Task {
            rect,
            level: task.level + 1,
            i: 2 * task.i + (q & 1) as u32,
            j: 2 * task.j + (q >> 1) as u32,
            refs: reached(&task.refs, tris, &Region::new(&rect, source, margin)),
        }
    }))
}

/// The ids among `refs` whose triangles reach into `region`.
fn reached(refs: &[u32], tris: &[Triangle], region: &Region) -> Vec<u32> {
    refs.iter()
        .copied()
        .filter(|&id| region.clipped_bounds(&tris[id as usize]).is_some())
        .collect()
}

/// True when the light sends no light into any direction of `rect`: all of it behind a one-sided
/// light's plane, or all of it outside a spot's cone, by [`CONE_MARGIN`] (an angle).
fn is_dark(rect: &CellRect, source: &LightSource) -> bool {
    let corners = rect.corners();
    if let Some((n, _)) = source.front {
        // A linear function over a convex cone is largest on one of its extreme rays.
        let sin_margin = libm::sin(CONE_MARGIN);
        if corners.iter().all(|c| n.dot(*c) < -sin_margin) {
            return true;
        }
    }
    if let Some(cone) = source.cone {
        let centre = rect
            .direction(0.5 * (rect.u.0 + rect.u.1), 0.5 * (rect.v.0 + rect.v.1))
            .normalize();
        // The farthest direction of a convex spherical quadrilateral from a point inside it is
        // one of its corners.
        let radius = corners
            .iter()
            .map(|c| angle(centre, *c))
            .fold(0.0, f64::max);
        if angle(centre, cone.axis) - radius > cone.half_angle + CONE_MARGIN {
            return true;
        }
    }
    false
}

/// The angle between two unit vectors, accurate at small angles too.
fn angle(a: DVec3, b: DVec3) -> f64 {
    libm::atan2(a.cross(b).length(), a.dot(b))
}

/// Buffers reused by every leaf's tree build.
#[derive(Default)]
struct Leaf {
    local: Vec<Triangle>,
}

impl Leaf {
    /// Makes `task` a leaf: its grid cells name a new tree over the triangles it reaches (boxed
    /// by their parts inside its region), or [`CLEAR`] when it reaches none.
    fn finish(
        &mut self,
        task: &Task,
        tris: &[Triangle],
        margin: f64,
        max_level: u32,
        out: &mut LightBuffer,
    ) -> Result<(), BuildError> {
        let slot = if task.refs.is_empty() {
            out.stats.clear_cells += 1;
            CLEAR
        } else {
            let region = Region::new(&task.rect, &out.source, margin);
            let mut arena = BuildArena::with_capacity(task.refs.len());
            self.local.clear();
            for &id in &task.refs {
                let tri = &tris[id as usize];
                if let Some(bounds) = region.clipped_bounds(tri) {
                    arena.push(self.local.len() as u32, bounds)?;
                    self.local.push(*tri);
                }
            }
            let mut bvh = Bvh::with_capacity(self.local.len());
            Builder::sah()
                .for_wide()
                .build_into(&mut arena, &mut bvh)?;
            out.stats.trees += 1;
            out.stats.references += self.local.len();
            out.trees.push(WideBvh::from_binary(&bvh, &self.local));
            (out.trees.len() - 1) as u32
        };
        let span = 1u32 << (max_level - task.level);
        let r = out.resolution as usize;
        let face = task.rect.face;
        for j in task.j * span..(task.j + 1) * span {
            let row = (face * r + j as usize) * r;
            for i in task.i * span..(task.i + 1) * span {
                out.grid[row + i as usize] = slot;
            }
        }
        Ok(())
    }
}
