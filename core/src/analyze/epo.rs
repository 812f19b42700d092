//! End-point overlap (Aila, Karras and Laine 2013): how much geometry outside a node's subtree
//! lies inside its box, weighted by what visiting the node costs.

use alloc::vec::Vec;

use glam::Vec3;

use crate::bvh::Bvh;
use crate::geometry::{Aabb, Triangle};
use crate::heuristics::CostConstants;

use super::{Analysis, NodeView};

/// Most vertices of a triangle clipped by a box: each of the six planes adds at most one.
const MAX_CLIPPED: usize = 3 + 6;

/// The area of the part of `t` inside the box `b` (exact: the triangle is clipped by the six
/// planes of the box, Sutherland-Hodgman, and the clipped polygon's area summed as a fan).
pub fn clipped_triangle_area(t: &Triangle, b: &Aabb) -> f32 {
    let mut poly = [Vec3::ZERO; MAX_CLIPPED + 1];
    poly[..3].copy_from_slice(&[t.v0, t.v1, t.v2]);
    let mut len = 3;
    let mut next = [Vec3::ZERO; MAX_CLIPPED + 1];
    for axis in 0..3 {
        for (bound, sign) in [(b.max[axis], 1.0f32), (b.min[axis], -1.0)] {
            let inside = |p: Vec3| sign * p[axis] <= sign * bound;
            let mut n = 0;
            for i in 0..len {
                let (a, c) = (poly[i], poly[(i + 1) % len]);
                let (ia, ic) = (inside(a), inside(c));
                if ia && n < next.len() {
                    next[n] = a;
                    n += 1;
                }
                if ia != ic && n < next.len() {
                    let t = (bound - a[axis]) / (c[axis] - a[axis]);
                    let mut q = a + (c - a) * t;
                    q[axis] = bound;
                    next[n] = q;
                    n += 1;
                }
            }
            poly[..n].copy_from_slice(&next[..n]);
            len = n;
            if len < 3 {
                return 0.0;
            }
        }
    }
    let mut twice = Vec3::ZERO;
    for i in 1..len - 1 {
        twice += (poly[i] - poly[0]).cross(poly[i + 1] - poly[0]);
    }
    0.5 * twice.length()
}

/// End-point overlap: `EPO = sum over nodes n of c(n) A_out(n) / A_total`, where `A_out(n)` is the
/// area of the parts of triangles *not* in `n`'s subtree that lie inside `n`'s box (clipped
/// exactly), `c(n)` is `C_trav` for an inner node and `C_isect * count` for a leaf, and
/// `A_total` the area of every triangle in the tree. A ray ending on such a surface must still
/// visit `n` although `n` cannot hold its hit, so EPO predicts the cost of closest-hit traversal
/// where SAH (which assumes rays pass through) does not.
///
/// The triangles near a node are found by walking the tree itself with the node's box, skipping
/// the node's own subtree.
#[derive(Clone, Debug)]
pub struct Epo<'t> {
    tris: &'t [Triangle],
    k: CostConstants,
    sum: f64,
    stack: Vec<u32>,
}

/// What [`Epo`] found.
#[derive(Clone, Copy, Debug, Default, PartialEq)]
pub struct EpoReport {
    /// The normalised end-point overlap.
    pub epo: f32,
    /// The unnormalised sum `sum c(n) A_out(n)`.
    pub weighted_area: f32,
    /// Total area of the tree's triangles.
    pub total_area: f32,
}

impl<'t> Epo<'t> {
    /// EPO of a tree built over `tris` (indexed by primitive id), with cost constants `k`.
    pub fn new(tris: &'t [Triangle], k: CostConstants) -> Self {
        Self {
            tris,
            k,
            sum: 0.0,
            stack: Vec::new(),
        }
    }

    /// `A_out` of node `skip` with box `b`.
    fn outside_area(&mut self, bvh: &Bvh, skip: u32, b: &Aabb) -> f64 {
        let nodes = bvh.nodes();
        let mut area = 0.0f64;
        self.stack.clear();
        self.stack.push(0);
        while let Some(i) = self.stack.pop() {
            if i == skip {
                continue;
            }
            let Some(n) = nodes.get(i as usize) else {
                continue;
            };
            if n.bounds().intersection(*b).is_empty() {
                continue;
            }
            if n.is_leaf() {
                for &id in bvh.leaf_prims(n) {
                    if let Some(t) = self.tris.get(id as usize) {
                        if !t.bounds().intersection(*b).is_empty() {
                            area += f64::from(clipped_triangle_area(t, b));
                        }
                    }
                }
            } else if n.left_first > i {
                self.stack.push(n.left_first);
                self.stack.push(n.left_first + 1);
            }
        }
        area
    }
}

impl Analysis for Epo<'_> {
    type NodeData = ();
    type Output = EpoReport;

    fn visit(&mut self, v: &NodeView<'_>, _: Option<&()>) {
        if v.index == 0 {
            // Every triangle is in the root's subtree.
            return;
        }
        let cost = if v.node.is_leaf() {
            f64::from(self.k.intersection) * f64::from(v.node.count)
        } else {
            f64::from(self.k.traversal)
        };
        let b = v.node.bounds();
        self.sum += cost * self.outside_area(v.bvh, v.index, &b);
    }

    fn finish(self, bvh: &Bvh) -> EpoReport {
        let total: f64 = bvh
            .prim_indices()
            .iter()
            .filter_map(|&id| self.tris.get(id as usize))
            .map(|t| f64::from(t.area()))
            .sum();
        EpoReport {
            epo: if total > 0.0 {
                (self.sum / total) as f32
            } else {
                0.0
            },
            weighted_area: self.sum as f32,
            total_area: total as f32,
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::analyze::analyze;
    use crate::bvh::BvhNode;
    use alloc::vec;

    fn tri(a: [f32; 3], b: [f32; 3], c: [f32; 3]) -> Triangle {
        Triangle::new(Vec3::from(a), Vec3::from(b), Vec3::from(c))
    }

    #[test]
    fn clipping_by_hand() {
        // A right triangle of legs 2 in z = 0.5, clipped to the unit cube: the unit square's part
        // under the hypotenuse x + y <= 2 is the whole square.
        let t = tri([0.0, 0.0, 0.5], [2.0, 0.0, 0.5], [0.0, 2.0, 0.5]);
        let unit = Aabb::new(Vec3::ZERO, Vec3::ONE);
        assert!((clipped_triangle_area(&t, &unit) - 1.0).abs() < 1e-6);
        // Half of it: x <= 1 cuts a trapezoid of area 2 - 0.5 = 1.5, then y <= 1 ...
        let wide = Aabb::new(Vec3::ZERO, Vec3::new(1.0, 5.0, 1.0));
        assert!((clipped_triangle_area(&t, &wide) - 1.5).abs() < 1e-6);
        let away = Aabb::new(Vec3::splat(3.0), Vec3::splat(4.0));
        assert_eq!(clipped_triangle_area(&t, &away), 0.0);
        // Entirely inside: its own area.
        let big = Aabb::new(Vec3::splat(-1.0), Vec3::splat(3.0));
        assert!((clipped_triangle_area(&t, &big) - 2.0).abs() < 1e-6);
    }

    #[test]
    fn epo_by_hand() {
        // Two unit squares' worth: triangle 0 spans x in [0, 2] (area 2, in leaf A = [0,2]^2),
        // triangle 1 is small in [1.5, 2.5] x [0, 1] (area 0.5, leaf B). Leaf B's box overlaps
        // triangle 0 where x >= 1.5: the part of the triangle (0,0)-(2,0)-(0,2) with x >= 1.5 is
        // the corner triangle of legs 0.5: area 0.125. Leaf A's box [0,2]x[0,2] holds the part of
        // triangle 1 with x <= 2: the triangle (1.5,0)-(2.5,0)-(1.5,1) cut at x = 2 keeps
        // 0.5 - 0.5*0.5*0.5 = 0.375.
        let tris = [
            tri([0.0, 0.0, 0.0], [2.0, 0.0, 0.0], [0.0, 2.0, 0.0]),
            tri([1.5, 0.0, 0.0], [2.5, 0.0, 0.0], [1.5, 1.0, 0.0]),
        ];
        let leaf = |i: u32, b: Aabb| BvhNode {
            min: b.min.to_array(),
            left_first: i,
            max: b.max.to_array(),
            count: 1,
        };
        let a = tris[0].bounds();
        let b = tris[1].bounds();
        let root = a.union(b);
        let bvh = Bvh {
            nodes: vec![
                BvhNode {
                    min: root.min.to_array(),
                    left_first: 1,
                    max: root.max.to_array(),
                    count: 0,
                },
                leaf(0, a),
                leaf(1, b),
            ],
            prim_indices: vec![0, 1],
            max_depth: 1,
        };
        let k = CostConstants {
            traversal: 1.0,
            intersection: 2.0,
        };
        let r = analyze(&bvh, Epo::new(&tris, k));
        let expect = 2.0 * (0.125 + 0.375) / 2.5;
        assert!((r.epo - expect).abs() < 1e-5, "{r:?} vs {expect}");
        assert!((r.total_area - 2.5).abs() < 1e-6);
    }
}
