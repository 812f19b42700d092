//! Projections of boxes onto planes: the silhouettes PAH measures and the analyzer overlaps.

use glam::{Vec2, Vec3};

use super::{Aabb, ConvexPolygon, Frame, MAX_POLY};

/// Corner `i` of a box: the upper bound on x when `i & 1`, on y when `i & 2`, on z when `i & 4`.
#[inline]
pub fn box_corner(b: &Aabb, i: usize) -> Vec3 {
    Vec3::new(
        if i & 1 == 0 { b.min.x } else { b.max.x },
        if i & 2 == 0 { b.min.y } else { b.max.y },
        if i & 4 == 0 { b.min.z } else { b.max.z },
    )
}

/// The orthographic silhouette of `b` on the plane spanned by the orthonormal `right` and `up`:
/// the hull of the eight projected corners, in `(right, up)` coordinates.
pub fn orthographic_silhouette(b: &Aabb, right: Vec3, up: Vec3) -> ConvexPolygon {
    let corners: [Vec2; 8] = core::array::from_fn(|i| {
        let p = box_corner(b, i);
        Vec2::new(p.dot(right), p.dot(up))
    });
    ConvexPolygon::hull(&corners)
}

/// The perspective silhouette, on the image plane `z = 1` of `frame` with its eye at `eye`, of the
/// part of `b` at least `near > 0` in front of the eye. The silhouette of a convex body from a
/// point in front of it is the hull of its projected vertices: the box's corners beyond the near
/// plane and the points where its 12 edges cross it, at most 14 points.
pub fn perspective_silhouette(b: &Aabb, eye: Vec3, frame: &Frame, near: f32) -> ConvexPolygon {
    let local: [Vec3; 8] = core::array::from_fn(|i| frame.to_local(box_corner(b, i) - eye));
    let mut pts = [Vec2::ZERO; MAX_POLY];
    let mut n = 0;
    let project = |p: Vec3| Vec2::new(p.x / p.z, p.y / p.z);
    for p in &local {
        if p.z >= near {
            pts[n] = project(*p);
            n += 1;
        }
    }
    if n < 8 {
        // Edges join corners differing in one bit; those crossing the near plane contribute
        // their crossing point (at most 6 of them for a plane cutting a box).
        for i in 0..8usize {
            for bit in [1usize, 2, 4] {
                let j = i | bit;
                if j == i {
                    continue;
                }
                let (a, c) = (local[i], local[j]);
                if (a.z < near) != (c.z < near) && n < MAX_POLY {
                    let t = (near - a.z) / (c.z - a.z);
                    let mut q = a + (c - a) * t;
                    q.z = near;
                    pts[n] = project(q);
                    n += 1;
                }
            }
        }
    }
    ConvexPolygon::hull(&pts[..n])
}
