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
use crate::builder::{BuildArena, Builder};
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

/// A light buffer's build, one cube-map face at a time: [`LightBufferBuilder::face`] takes no
/// `&mut`, so a host may build the six faces on six threads and hand them to
/// [`LightBufferBuilder::finish`] in any order ([`LightBuffer::build`] builds them in turn).
#[derive(Clone, Debug)]
pub struct LightBufferBuilder<'a> {
    tris: &'a [Triangle],
    source: LightSource,
    options: LightBufferOptions,
    margin: f64,
    resolution: u32,
}

/// One face of a light buffer, from [`LightBufferBuilder::face`].
#[derive(Clone, Debug)]
pub struct LightBufferFace {
    face: usize,
    /// The face's `r * r` grid cells, roots indexing `forest`.
    grid: Vec<u32>,
    forest: WideBvh,
    stats: LightBufferStats,
}

impl<'a> LightBufferBuilder<'a> {
    /// Checks the scene and the options for a light buffer of `source` over `tris`. Fails on a
    /// triangle with a NaN or infinite coordinate or on options out of range.
    pub fn new(
        tris: &'a [Triangle],
        source: LightSource,
        options: &LightBufferOptions,
    ) -> Result<Self, BuildError> {
        if options.max_level > MAX_LEVEL {
            return Err(BuildError::InvalidConfig("light buffer max_level above 8"));
        }
        if options.reference_budget.is_nan() || options.reference_budget < 0.0 {
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
            .fold(
                source.bounds.min.abs().max(source.bounds.max.abs()),
                |m, t| m.max(t.v0.abs()).max(t.v1.abs()).max(t.v2.abs()),
            )
            .max_element();
        Ok(Self {
            tris,
            source,
            options: *options,
            margin: MARGIN * f64::from(scale).max(f64::from(f32::MIN_POSITIVE)),
            resolution: 1 << options.max_level,
        })
    }

    /// Faces of the cube map, each built by [`LightBufferBuilder::face`].
    pub const FACES: usize = FACES;

    /// Builds face `face` (below [`LightBufferBuilder::FACES`]): its quadtree, refined while the
    /// children split their parent's triangles and the face's references stay within
    /// `reference_budget` times the triangles the whole face reaches, and a tree per leaf.
    pub fn face(&self, face: usize) -> Result<LightBufferFace, BuildError> {
        if face >= FACES {
            return Err(BuildError::InvalidConfig("light buffer face index above 5"));
        }
        let r = self.resolution as usize;
        let mut out = LightBufferFace {
            face,
            grid: vec![DARK; r * r],
            forest: WideBvh::default(),
            stats: LightBufferStats::default(),
        };
        let rect = CellRect::face(face);
        if is_dark(&rect, &self.source) {
            out.stats.dark_cells += 1;
            return Ok(out);
        }
        let refs = reached(
            0..self.tris.len() as u32,
            self.tris,
            &Region::new(&rect, &self.source, self.margin),
        );
        // References held by finished leaves and pending tasks.
        let mut held = refs.len();
        let budget = (f64::from(self.options.reference_budget) * refs.len() as f64) as usize;
        let mut leaf = Leaf::default();
        let mut stack = vec![Task {
            rect,
            level: 0,
            i: 0,
            j: 0,
            refs,
        }];
        while let Some(task) = stack.pop() {
            let children = (task.level < self.options.max_level
                && task.refs.len() > self.options.leaf_triangles as usize)
                .then(|| split(&task, self.tris, &self.source, self.margin));
            let grown = children
                .as_ref()
                .map_or(0, |c| c.iter().map(|t| t.refs.len()).sum::<usize>());
            let pays = (grown as f64) < SPLIT_GAIN * 4.0 * task.refs.len() as f64;
            match children {
                Some(children) if pays && held - task.refs.len() + grown <= budget.max(held) => {
                    held = held - task.refs.len() + grown;
                    for child in children.into_iter().rev() {
                        if is_dark(&child.rect, &self.source) {
                            held -= child.refs.len();
                            out.stats.dark_cells += 1;
                        } else {
                            stack.push(child);
                        }
                    }
                }
                _ => leaf.finish(&task, self, &mut out)?,
            }
        }
        Ok(out)
    }

    /// The buffer of the six faces, given once each in any order.
    pub fn finish(
        self,
        faces: impl IntoIterator<Item = LightBufferFace>,
    ) -> Result<LightBuffer, BuildError> {
        let r = self.resolution as usize;
        let mut out = LightBuffer {
            source: self.source,
            resolution: self.resolution,
            grid: vec![DARK; FACES * r * r],
            forest: WideBvh::default(),
            margin: self.margin as f32,
            stats: LightBufferStats::default(),
        };
        let mut seen = [false; FACES];
        for face in faces {
            if face.grid.len() != r * r || core::mem::replace(&mut seen[face.face], true) {
                return Err(BuildError::InvalidConfig(
                    "light buffer faces from another build or given twice",
                ));
            }
            let base = out.forest.append(&face.forest).unwrap_or(0);
            let cells = &mut out.grid[face.face * r * r..(face.face + 1) * r * r];
            for (cell, &slot) in cells.iter_mut().zip(&face.grid) {
                *cell = if slot == DARK || slot == CLEAR {
                    slot
                } else {
                    slot + base
                };
            }
            let (s, f) = (&mut out.stats, face.stats);
            s.trees += f.trees;
            s.clear_cells += f.clear_cells;
            s.dark_cells += f.dark_cells;
            s.references += f.references;
        }
        if seen.contains(&false) {
            return Err(BuildError::InvalidConfig("light buffer face missing"));
        }
        out.stats.memory_bytes = out.grid.len() * 4 + out.forest.memory_bytes();
        Ok(out)
    }
}

/// The four children of `task` with the triangles each reaches.
fn split(task: &Task, tris: &[Triangle], source: &LightSource, margin: f64) -> [Task; 4] {
    core::array::from_fn(|q| {
        let rect = task.rect.quadrant(q);
        Task {
            rect,
            level: task.level + 1,
            i: 2 * task.i + (q & 1) as u32,
            j: 2 * task.j + (q >> 1) as u32,
            refs: reached(
                task.refs.iter().copied(),
                tris,
                &Region::new(&rect, source, margin),
            ),
        }
    })
}

/// The ids among `refs` whose triangles may reach into `region` ([`Region::may_reach`]; the
/// leaves clip them exactly).
fn reached(refs: impl Iterator<Item = u32>, tris: &[Triangle], region: &Region) -> Vec<u32> {
    refs.filter(|&id| region.may_reach(&tris[id as usize]))
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
        build: &LightBufferBuilder,
        out: &mut LightBufferFace,
    ) -> Result<(), BuildError> {
        let region = Region::new(&task.rect, &build.source, build.margin);
        let mut arena = BuildArena::with_capacity(task.refs.len());
        self.local.clear();
        for &id in &task.refs {
            let tri = &build.tris[id as usize];
            if let Some(bounds) = region.clipped_bounds(tri) {
                arena.push(self.local.len() as u32, bounds)?;
                self.local.push(*tri);
            }
        }
        let slot = if self.local.is_empty() {
            out.stats.clear_cells += 1;
            CLEAR
        } else {
            let mut bvh = Bvh::with_capacity(self.local.len());
            Builder::sah().for_wide().build_into(&mut arena, &mut bvh)?;
            out.stats.trees += 1;
            out.stats.references += self.local.len();
            let tree = WideBvh::from_binary(&bvh, &self.local);
            out.forest.append(&tree).unwrap_or(CLEAR)
        };
        let span = 1u32 << (build.options.max_level - task.level);
        let r = build.resolution as usize;
        for j in task.j * span..(task.j + 1) * span {
            let row = j as usize * r;
            for i in task.i * span..(task.i + 1) * span {
                out.grid[row + i as usize] = slot;
            }
        }
        Ok(())
    }
}
