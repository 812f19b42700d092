//! The thesis's sibling overlap: how much the two children of a node overlap, in 3D or in the
//! light's projection, averaged over the top levels of the tree.

use alloc::vec::Vec;

use glam::{Vec2, Vec3};

use crate::bvh::Bvh;
use crate::geometry::{
    clip_convex, orthographic_silhouette, perspective_silhouette, windowed_silhouette, Aabb,
    ConvexPolygon, Frame, MAX_POLY,
};
use crate::influence::InfluenceArea;

use super::{Analysis, NodeView};

/// The levels the thesis reported overlap at ("Overlapping % culled 4", ..., "100").
pub const THESIS_LEVELS: [u32; 5] = [4, 7, 10, 15, 100];

/// Where sibling boxes are compared.
#[derive(Clone, Copy, Debug, PartialEq)]
pub enum OverlapSpace {
    /// In 3D: the volume of the children's intersection over the smaller child's volume.
    Volume,
    /// Orthographic projection along a plane area's rays, onto its light plane: the area of the
    /// intersection of the two projections over the smaller projection. With a window, both
    /// projections are first clipped to the light rectangle `[lo, hi]` (in `(right, up)`
    /// coordinates about `origin`).
    Ortho {
        /// The point boxes are taken relative to before they are projected (the light's centre):
        /// a small window far from the world origin keeps its precision.
        origin: Vec3,
        /// Projection axes.
        right: Vec3,
        /// Projection axes.
        up: Vec3,
        /// The light rectangle, when culling.
        window: Option<(Vec2, Vec2)>,
    },
    /// Perspective projection from a point area's eye onto its image plane `z = 1` (boxes cut at
    /// the near plane first), measured by image-plane area. With culling, clipped to the fields of
    /// view `[-tan_x, tan_x] x [-tan_y, tan_y]`.
    Perspective {
        /// The eye.
        eye: Vec3,
        /// The view frame.
        frame: Frame,
        /// Near-plane distance.
        near: f32,
        /// Far-plane distance: with culling, boxes are cut there too (rays stop there).
        far: f32,
        /// Half fields of view as tangents, when culling.
        window: Option<Vec2>,
    },
}

impl OverlapSpace {
    /// The projection of `area`'s rays: orthographic for a plane area, perspective for a point
    /// area; `culled` clips projections to the light's window.
    pub fn projected(area: &InfluenceArea, culled: bool) -> Self {
        match area {
            InfluenceArea::Plane(a) => {
                let h = Vec2::new(a.half_width, a.half_height);
                OverlapSpace::Ortho {
                    origin: a.center,
                    right: a.frame.right,
                    up: a.frame.up,
                    window: culled.then_some((-h, h)),
                }
            }
            InfluenceArea::Point(a) => {
                let f = a.frustum();
                OverlapSpace::Perspective {
                    eye: f.eye,
                    frame: f.frame,
                    near: f.near,
                    far: f.far,
                    window: culled.then_some(Vec2::new(f.tan_x, f.tan_y)),
                }
            }
        }
    }

    /// `(measure(a), measure(b), measure(a ∩ b))`.
    pub fn measures(&self, a: &Aabb, b: &Aabb) -> (f32, f32, f32) {
        match *self {
            OverlapSpace::Volume => {
                let vol = |x: &Aabb| {
                    if x.is_empty() {
                        0.0
                    } else {
                        let e = x.extent();
                        e.x * e.y * e.z
                    }
                };
                (vol(a), vol(b), vol(&a.intersection(*b)))
            }
            OverlapSpace::Ortho {
                origin,
                right,
                up,
                window,
            } => {
                let project = |x: &Aabb| {
                    let relative = Aabb::new(x.min - origin, x.max - origin);
                    let hull = orthographic_silhouette(&relative, right, up);
                    match window {
                        Some((lo, hi)) => hull.clip_to_rect(lo, hi),
                        None => hull,
                    }
                };
                let (pa, pb) = (project(a), project(b));
                (pa.area(), pb.area(), convex_intersection_area(&pa, &pb))
            }
            OverlapSpace::Perspective {
                eye,
                frame,
                near,
                far,
                window,
            } => {
                let project = |x: &Aabb| match window {
                    Some(t) => windowed_silhouette(x, eye, &frame, (near, far), t),
                    None => perspective_silhouette(x, eye, &frame, near),
                };
                let (pa, pb) = (project(a), project(b));
                (pa.area(), pb.area(), convex_intersection_area(&pa, &pb))
            }
        }
    }
}

/// The area of the intersection of two convex polygons (counter-clockwise, as
/// [`ConvexPolygon::hull`] makes them): `a` clipped by each edge of `b`.
pub fn convex_intersection_area(a: &ConvexPolygon, b: &ConvexPolygon) -> f32 {
    const CAP: usize = 2 * MAX_POLY + 8;
    let (pa, pb) = (a.points(), b.points());
    if pa.len() < 3 || pb.len() < 3 {
        return 0.0;
    }
    let mut poly = [Vec2::ZERO; CAP];
    let mut len = pa.len();
    poly[..len].copy_from_slice(pa);
    let mut next = [Vec2::ZERO; CAP];
    for i in 0..pb.len() {
        let (e0, e1) = (pb[i], pb[(i + 1) % pb.len()]);
        let edge = e1 - e0;
        // Inside is to the left of a counter-clockwise edge.
        let n = clip_convex(&poly[..len], &mut next, |p: Vec2| edge.perp_dot(p - e0));
        poly[..n].copy_from_slice(&next[..n]);
        len = n;
        if len < 3 {
            return 0.0;
        }
    }
    let mut twice = 0.0;
    for i in 0..len {
        twice += poly[i].perp_dot(poly[(i + 1) % len]);
    }
    0.5 * twice.abs()
}

/// The thesis's sibling overlap. For every inner node, `overlap(left, right) / min(measure(left),
/// measure(right))` in the chosen [`OverlapSpace`]; for each level `L`, the mean of that ratio
/// over the inner nodes of depth `< L` (the root has depth 0), so level 100 is the whole tree.
/// Pairs whose smaller child measures zero (flat boxes in 3D, boxes outside the window when
/// culling) have no defined ratio and are left out of the mean.
#[derive(Clone, Debug)]
pub struct SiblingOverlap {
    space: OverlapSpace,
    levels: Vec<u32>,
    sums: Vec<f64>,
    pairs: Vec<u32>,
}

/// What [`SiblingOverlap`] found, per level.
#[derive(Clone, Debug, Default, PartialEq)]
pub struct OverlapReport {
    /// The levels.
    pub levels: Vec<u32>,
    /// Mean overlap ratio over the inner nodes above each level (0 when none counted).
    pub mean: Vec<f32>,
    /// How many sibling pairs each mean is over.
    pub pairs: Vec<u32>,
}

impl OverlapReport {
    /// The mean at level `level`, if it was measured.
    pub fn at(&self, level: u32) -> Option<f32> {
        self.levels
            .iter()
            .position(|&l| l == level)
            .map(|i| self.mean[i])
    }
}

impl SiblingOverlap {
    /// Overlap in `space` at the thesis's levels 4, 7, 10, 15 and 100.
    pub fn new(space: OverlapSpace) -> Self {
        Self::at_levels(space, &THESIS_LEVELS)
    }

    /// Overlap in `space` at the given levels.
    pub fn at_levels(space: OverlapSpace, levels: &[u32]) -> Self {
        Self {
            space,
            levels: levels.to_vec(),
            sums: alloc::vec![0.0; levels.len()],
            pairs: alloc::vec![0; levels.len()],
        }
    }
}

impl Analysis for SiblingOverlap {
    type NodeData = ();
    type Output = OverlapReport;

    fn visit(&mut self, v: &NodeView<'_>, _: Option<&()>) {
        if v.node.is_leaf() || !self.levels.iter().any(|&l| v.depth < l) {
            return;
        }
        let nodes = v.bvh.nodes();
        let l = v.node.left_first as usize;
        let (Some(a), Some(b)) = (nodes.get(l), nodes.get(l + 1)) else {
            return;
        };
        let (ma, mb, mo) = self.space.measures(&a.bounds(), &b.bounds());
        let smaller = ma.min(mb);
        if smaller.is_nan() || smaller <= 0.0 || !mo.is_finite() {
            return;
        }
        let ratio = f64::from((mo / smaller).clamp(0.0, 1.0));
        for (i, &level) in self.levels.iter().enumerate() {
            if v.depth < level {
                self.sums[i] += ratio;
                self.pairs[i] += 1;
            }
        }
    }

    fn finish(self, _: &Bvh) -> OverlapReport {
        let mean = self
            .sums
            .iter()
            .zip(&self.pairs)
            .map(|(&s, &n)| {
                if n > 0 {
                    (s / f64::from(n)) as f32
                } else {
                    0.0
                }
            })
            .collect();
        OverlapReport {
            levels: self.levels,
            mean,
            pairs: self.pairs,
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::analyze::analyze;
    use crate::bvh::BvhNode;
    use crate::influence::{PlaneArea, PointArea};
    use alloc::vec;

    fn bx(min: [f32; 3], max: [f32; 3]) -> Aabb {
        Aabb::new(Vec3::from(min), Vec3::from(max))
    }

    /// Root over two leaves with the given boxes.
    fn pair(a: Aabb, b: Aabb) -> Bvh {
        let node = |x: Aabb, left_first: u32, count: u32| BvhNode {
            min: x.min.to_array(),
            left_first,
            max: x.max.to_array(),
            count,
        };
        Bvh {
            nodes: vec![node(a.union(b), 1, 0), node(a, 0, 1), node(b, 1, 1)],
            prim_indices: vec![0, 1],
            max_depth: 1,
        }
    }

    #[test]
    fn polygon_intersection_by_hand() {
        let sq = |x0: f32, y0: f32, s: f32| {
            ConvexPolygon::hull(&[
                Vec2::new(x0, y0),
                Vec2::new(x0 + s, y0),
                Vec2::new(x0 + s, y0 + s),
                Vec2::new(x0, y0 + s),
            ])
        };
        assert!(
            (convex_intersection_area(&sq(0.0, 0.0, 2.0), &sq(1.0, 1.0, 2.0)) - 1.0).abs() < 1e-6
        );
        assert!(
            (convex_intersection_area(&sq(0.0, 0.0, 4.0), &sq(1.0, 1.0, 1.0)) - 1.0).abs() < 1e-6
        );
        assert_eq!(
            convex_intersection_area(&sq(0.0, 0.0, 1.0), &sq(5.0, 5.0, 1.0)),
            0.0
        );
    }

    #[test]
    fn volume_and_ortho_overlap_by_hand() {
        // Boxes [0,2]^3 and [1,3]x[0,2]x[5,7]: disjoint in 3D (z), but seen along z their
        // projections [0,2]x[0,2] and [1,3]x[0,2] overlap by half.
        let bvh = pair(bx([0.0; 3], [2.0; 3]), bx([1.0, 0.0, 5.0], [3.0, 2.0, 7.0]));
        let vol = analyze(&bvh, SiblingOverlap::new(OverlapSpace::Volume));
        assert_eq!(vol.at(4), Some(0.0));
        assert_eq!(vol.pairs, vec![1; 5]);
        let area: InfluenceArea =
            PlaneArea::new(Vec3::new(1.5, 1.0, -1.0), Vec3::Z, 10.0, 10.0, 20.0)
                .unwrap()
                .into();
        let proj = analyze(
            &bvh,
            SiblingOverlap::new(OverlapSpace::projected(&area, false)),
        );
        assert!((proj.at(4).unwrap() - 0.5).abs() < 1e-5, "{proj:?}");
        // A window covering only x in [0.5, 1.5] (centre 1, half width 0.5) leaves
        // [0.5,1.5] and [1,1.5] (times the y range): the smaller is inside the larger -> 1.
        let narrow: InfluenceArea =
            PlaneArea::new(Vec3::new(1.0, 1.0, -1.0), Vec3::Z, 0.5, 5.0, 20.0)
                .unwrap()
                .into();
        let culled = analyze(
            &bvh,
            SiblingOverlap::new(OverlapSpace::projected(&narrow, true)),
        );
        assert!((culled.at(100).unwrap() - 1.0).abs() < 1e-5, "{culled:?}");
        // Level 1 counts the root's pair (depth 0 < 1); level 0 would count nothing.
        let none = analyze(&bvh, SiblingOverlap::at_levels(OverlapSpace::Volume, &[0]));
        assert_eq!(none.pairs, vec![0]);
    }

    #[test]
    fn perspective_overlap_by_hand() {
        // From the origin looking down +z, boxes at depth [1, 1] x ... : two unit squares in the
        // plane z = 1 (thin boxes), x in [0,1] and [0.5,1.5]: half overlap on the image plane.
        let area: InfluenceArea = PointArea::new(Vec3::ZERO, Vec3::Z, 150.0, 150.0, 0.1, 10.0)
            .unwrap()
            .into();
        let bvh = pair(
            bx([0.0, 0.0, 1.0], [1.0, 1.0, 1.0]),
            bx([0.5, 0.0, 1.0], [1.5, 1.0, 1.0]),
        );
        let r = analyze(
            &bvh,
            SiblingOverlap::new(OverlapSpace::projected(&area, true)),
        );
        assert!((r.at(4).unwrap() - 0.5).abs() < 1e-4, "{r:?}");
    }
}
