//! Building a light buffer: per cube-map face, a quadtree of cells refined while that splits the
//! triangles the cells reach, and for each leaf a small wide BVH over the scene BVH's leaves that
//! hold those triangles, boxed by their clipped parts ([`super::cell_tree`]).

use alloc::vec;
use alloc::vec::Vec;

use glam::DVec3;

use super::buffer::{LightBuffer, LightBufferOptions, LightBufferStats, CLEAR, DARK};
use super::cell::{CellRect, CONE_MARGIN, FACES};
use super::cell_tree::{CellTreeBuilder, SceneLeaves};
use super::clip::{vertices_f64, Region};
use super::source::{LightSource, MARGIN};
use crate::bvh::WideBvh8;
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
    scene: SceneLeaves,
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
    forest: WideBvh8,
    stats: LightBufferStats,
}

impl<'a> LightBufferBuilder<'a> {
    /// Checks the scene and the options for a light buffer of `source` over `tris` and `scene`
    /// (an 8-wide BVH over exactly `tris`, whose leaves the buffer's trees will name). Fails on
    /// a triangle with a NaN or infinite coordinate, a `scene` over other triangles, or options
    /// out of range.
    pub fn new(
        tris: &'a [Triangle],
        scene: &WideBvh8,
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
            scene: SceneLeaves::new(scene, tris.len())?,
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
            forest: WideBvh8::default(),
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
        let mut leaf = Leaf::new();
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
            end_box: self.source.end_box(self.margin as f32),
            source: self.source,
            resolution: self.resolution,
            grid: vec![DARK; FACES * r * r],
            forests: vec![WideBvh8::default(); FACES],
            margin: self.margin as f32,
            scene_size: self.scene.size,
            stats: LightBufferStats::default(),
        };
        let mut seen = [false; FACES];
        for face in faces {
            if face.grid.len() != r * r || core::mem::replace(&mut seen[face.face], true) {
                return Err(BuildError::InvalidConfig(
                    "light buffer faces from another build or given twice",
                ));
            }
            out.grid[face.face * r * r..(face.face + 1) * r * r].copy_from_slice(&face.grid);
            out.forests[face.face] = face.forest;
            let (s, f) = (&mut out.stats, face.stats);
            s.trees += f.trees;
            s.clear_cells += f.clear_cells;
            s.dark_cells += f.dark_cells;
            s.references += f.references;
        }
        if seen.contains(&false) {
            return Err(BuildError::InvalidConfig("light buffer face missing"));
        }
        out.stats.memory_bytes =
            out.grid.len() * 4 + out.forests.iter().map(|f| f.memory_bytes()).sum::<usize>();
        Ok(out)
    }
}

/// The four children of `task` with the triangles each reaches. A child shares two side planes
/// and the front plane with its parent, so every triangle of `task` (none outside any of the
/// parent's planes) is tested against the child's two new side planes alone: the same triangles,
/// in the same order, as testing all of the child's planes.
fn split(task: &Task, tris: &[Triangle], source: &LightSource, margin: f64) -> [Task; 4] {
    let rects: [CellRect; 4] = core::array::from_fn(|q| task.rect.quadrant(q));
    // The new planes: `u` between children 0 and 1 (plane 1 of the lower half, plane 0 of the
    // upper), `v` between children 0 and 2 (plane 3 of the lower, plane 2 of the upper).
    let (lower, upper_u, upper_v) = (
        Region::new(&rects[0], source, margin),
        Region::new(&rects[1], source, margin),
        Region::new(&rects[2], source, margin),
    );
    let mut refs: [Vec<u32>; 4] = Default::default();
    for &id in &task.refs {
        let verts = vertices_f64(&tris[id as usize]);
        let u = [
            lower.reaches_plane(1, &verts),
            upper_u.reaches_plane(0, &verts),
        ];
        let v = [
            lower.reaches_plane(3, &verts),
            upper_v.reaches_plane(2, &verts),
        ];
        for (q, child) in refs.iter_mut().enumerate() {
            if u[q & 1] && v[q >> 1] {
                child.push(id);
            }
        }
    }
    let mut refs = refs.into_iter();
    core::array::from_fn(|q| Task {
        rect: rects[q],
        level: task.level + 1,
        i: 2 * task.i + (q & 1) as u32,
        j: 2 * task.j + (q >> 1) as u32,
        refs: refs.next().expect("four children"),
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

/// What every leaf's tree build reuses ([`CellTreeBuilder`]).
struct Leaf {
    tree: CellTreeBuilder,
}

impl Leaf {
    fn new() -> Self {
        Self {
            tree: CellTreeBuilder::new(),
        }
    }

    /// Makes `task` a leaf: its grid cells name a new tree over the scene leaves holding the
    /// triangles it reaches (boxed by their parts inside its region), or [`CLEAR`] when it
    /// reaches none.
    fn finish(
        &mut self,
        task: &Task,
        build: &LightBufferBuilder,
        out: &mut LightBufferFace,
    ) -> Result<(), BuildError> {
        let region = Region::new(&task.rect, &build.source, build.margin);
        let reached = task.refs.iter().filter_map(|&id| {
            region
                .clipped_bounds(&build.tris[id as usize])
                .map(|bounds| (id, bounds))
        });
        let slot = match self.tree.build(reached, &build.scene, &mut out.forest)? {
            None => {
                out.stats.clear_cells += 1;
                CLEAR
            }
            Some((root, triangles)) => {
                out.stats.trees += 1;
                out.stats.references += triangles;
                let light = build.source.bounds.center();
                out.forest
                    .order_children(root as usize, |b| -b.center().distance_squared(light));
                root
            }
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

#[cfg(test)]
mod tests {
    use glam::Vec3;

    use super::*;
    use crate::random::Pcg32;

    /// `split` tests only the children's new planes; testing all of each child's planes, as
    /// `reached` does, gives the same triangles in the same order, three levels down, for a
    /// point light and for a one-sided area light.
    #[test]
    fn split_reaches_what_the_full_region_test_reaches() {
        let mut rng = Pcg32::new(7);
        let mut v =
            |lo: f32, hi: f32| Vec3::new(rng.range(lo, hi), rng.range(lo, hi), rng.range(lo, hi));
        let tris: Vec<Triangle> = (0..3000)
            .map(|_| {
                let a = v(-10.0, 10.0);
                Triangle::new(a, a + v(-2.0, 2.0), a + v(-2.0, 2.0))
            })
            .collect();
        let quad = [
            Vec3::new(-1.0, -1.0, 0.5),
            Vec3::new(1.0, -1.0, 0.5),
            Vec3::new(1.0, 1.0, 0.5),
            Vec3::new(-1.0, 1.0, 0.5),
        ];
        let sources = [
            LightSource::point(Vec3::new(0.5, -0.25, 0.1)).unwrap(),
            LightSource::polygon(&quad, Some(Vec3::Z)).unwrap(),
        ];
        for source in &sources {
            for face in 0..FACES {
                let rect = CellRect::face(face);
                let refs = reached(
                    0..tris.len() as u32,
                    &tris,
                    &Region::new(&rect, source, 1e-3),
                );
                let mut tasks = vec![Task {
                    rect,
                    level: 0,
                    i: 0,
                    j: 0,
                    refs,
                }];
                for _ in 0..3 {
                    let mut next = Vec::new();
                    for task in &tasks {
                        for child in split(task, &tris, source, 1e-3) {
                            let full = reached(
                                task.refs.iter().copied(),
                                &tris,
                                &Region::new(&child.rect, source, 1e-3),
                            );
                            assert_eq!(child.refs, full, "face {face}, level {}", child.level);
                            next.push(child);
                        }
                    }
                    tasks = next;
                }
            }
        }
    }
}
