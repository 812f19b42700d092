//! A cell's region of space (the cell's cone swept over the light's surface, and the light's
//! front side) as half-spaces, and the part of a triangle inside it by polygon clipping in f64.

use glam::{DVec3, Vec3};

use super::cell::CellRect;
use super::source::LightSource;
use crate::geometry::{Aabb, Triangle};

/// At most four side planes and the front plane.
const MAX_PLANES: usize = 5;

/// A triangle clipped by five planes has at most eight vertices; room for more, in case rounding
/// bends the polygon (the clip then stops early with a box that is only larger).
const MAX_CLIPPED: usize = 16;

/// A triangle's vertices in f64, where every decision of the build is made.
#[inline]
pub(crate) fn vertices_f64(tri: &Triangle) -> [DVec3; 3] {
    [tri.v0, tri.v1, tri.v2].map(Vec3::as_dvec3)
}

/// Where a triangle lies against a region ([`Region::side`]).
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
enum Side {
    Outside,
    Inside,
    Straddles,
}

/// Points `x` with `n . x >= c` for each plane `(n, c)`: a convex superset of every point that a
/// segment whose direction lies in the cell can reach from the light's surface.
#[derive(Clone, Copy, Debug)]
pub(crate) struct Region {
    planes: [(DVec3, f64); MAX_PLANES],
    count: usize,
    /// The length by which the region and the clipped boxes are grown.
    margin: f64,
}

impl Region {
    /// The region of `cell` for `source`, every plane moved out by `margin` (a length). The
    /// cone's side plane `n . d >= 0` swept over the source is `n . x >= min_s n . s`, the
    /// source's support: the Minkowski sum lies inside, exactly for a point light.
    pub fn new(cell: &CellRect, source: &LightSource, margin: f64) -> Self {
        let mut planes = [(DVec3::ZERO, 0.0); MAX_PLANES];
        for (slot, n) in planes.iter_mut().zip(cell.side_normals()) {
            *slot = (n, source.support_min(n) - margin * n.length());
        }
        let mut count = 4;
        if let Some((n, lowest)) = source.front {
            planes[count] = (n, lowest - margin);
            count += 1;
        }
        Self {
            planes,
            count,
            margin,
        }
    }

    /// Where `tri`'s vertices lie against the region's planes: [`Side::Outside`] when all three
    /// are outside one plane (the triangle misses the region), [`Side::Inside`] when all are
    /// inside every plane, else [`Side::Straddles`] (it may still miss near a corner).
    #[inline]
    fn side(&self, verts: &[DVec3; 3]) -> Side {
        let mut inside = true;
        for &(n, c) in &self.planes[..self.count] {
            let d = verts.map(|v| n.dot(v) >= c);
            if d == [false; 3] {
                return Side::Outside;
            }
            inside &= d == [true; 3];
        }
        if inside {
            Side::Inside
        } else {
            Side::Straddles
        }
    }

    /// False when all of `verts` lie outside plane `plane` (index into the planes as
    /// [`Region::new`] orders them: the cell's four sides as `CellRect::side_normals` gives them,
    /// then the front).
    #[inline]
    pub fn reaches_plane(&self, plane: usize, verts: &[DVec3; 3]) -> bool {
        let (n, c) = self.planes[plane];
        verts.iter().any(|v| n.dot(*v) >= c)
    }

    /// True unless [`Region::side`] proves `tri` outside: a triangle that might reach the region
    /// (one that misses it near a corner costs a little time, never an answer).
    #[inline]
    pub fn may_reach(&self, tri: &Triangle) -> bool {
        self.side(&vertices_f64(tri)) != Side::Outside
    }

    /// The box of the part of `tri` inside the region, grown by the margin and kept within the
    /// triangle's own box; `None` when no part of it is inside.
    pub fn clipped_bounds(&self, tri: &Triangle) -> Option<Aabb> {
        let verts = vertices_f64(tri);
        match self.side(&verts) {
            Side::Outside => return None,
            Side::Inside => return Some(tri.bounds()),
            Side::Straddles => {}
        }
        let planes = &self.planes[..self.count];
        // Two buffers in turn: each plane clips `poly` into `next`, then they swap roles.
        let mut buffers = [[DVec3::ZERO; MAX_CLIPPED]; 2];
        let [mut poly, mut next] = buffers.each_mut();
        poly[..3].copy_from_slice(&verts);
        let mut len = 3;
        for &(n, c) in planes {
            if len + 1 > MAX_CLIPPED / 2 {
                break;
            }
            let mut out = 0;
            for i in 0..len {
                let (a, b) = (poly[i], poly[(i + 1) % len]);
                let (da, db) = (n.dot(a) - c, n.dot(b) - c);
                if da >= 0.0 {
                    next[out] = a;
                    out += 1;
                }
                if (da >= 0.0) != (db >= 0.0) {
                    let t = da / (da - db);
                    next[out] = a + (b - a) * t;
                    out += 1;
                }
            }
            if out == 0 {
                return None;
            }
            len = out;
            core::mem::swap(&mut poly, &mut next);
        }
        let (mut lo, mut hi) = (poly[0], poly[0]);
        for &p in &poly[1..len] {
            lo = lo.min(p);
            hi = hi.max(p);
        }
        let grow = DVec3::splat(self.margin);
        let own = tri.bounds();
        let lo = (lo - grow).as_vec3().max(own.min);
        let hi = (hi + grow).as_vec3().min(own.max);
        Some(Aabb::new(lo.min(hi), hi.max(lo)))
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn tri(a: [f32; 3], b: [f32; 3], c: [f32; 3]) -> Triangle {
        Triangle::new(Vec3::from(a), Vec3::from(b), Vec3::from(c))
    }

    /// A point light at the origin, the +z face's centre cell: a triangle across it is cut to
    /// the cell's cone, one beside it is dropped, one behind the light is dropped.
    #[test]
    fn clipping_keeps_the_part_inside_the_cone() {
        let source = LightSource::point(Vec3::ZERO).unwrap();
        let cell = CellRect {
            face: 4,
            u: (-0.25, 0.25),
            v: (-0.25, 0.25),
        };
        let region = Region::new(&cell, &source, 1e-4);
        let wide = tri([-10.0, -10.0, 4.0], [10.0, -10.0, 4.0], [0.0, 10.0, 4.0]);
        let b = region.clipped_bounds(&wide).unwrap();
        assert!(b.min.x > -1.01 && b.max.x < 1.01, "{b:?}");
        assert!(b.min.y > -1.01 && b.max.y < 1.01, "{b:?}");
        let beside = tri([3.0, 3.0, 4.0], [5.0, 3.0, 4.0], [4.0, 5.0, 4.0]);
        assert!(region.clipped_bounds(&beside).is_none());
        let behind = tri([-1.0, -1.0, -4.0], [1.0, -1.0, -4.0], [0.0, 1.0, -4.0]);
        assert!(region.clipped_bounds(&behind).is_none());
    }

    /// An area light widens the cone by its own extent: the triangle beside the point light's
    /// cell is reachable from a 8-unit-wide light.
    #[test]
    fn an_area_light_sweeps_the_cone_over_its_surface() {
        let corners = [
            Vec3::new(-4.0, -4.0, 0.0),
            Vec3::new(4.0, -4.0, 0.0),
            Vec3::new(4.0, 4.0, 0.0),
            Vec3::new(-4.0, 4.0, 0.0),
        ];
        let source = LightSource::polygon(&corners, Some(Vec3::Z)).unwrap();
        let cell = CellRect {
            face: 4,
            u: (-0.25, 0.25),
            v: (-0.25, 0.25),
        };
        let region = Region::new(&cell, &source, 1e-4);
        let beside = tri([3.0, 3.0, 4.0], [5.0, 3.0, 4.0], [4.0, 5.0, 4.0]);
        assert!(region.clipped_bounds(&beside).is_some());
        let below = tri([-1.0, -1.0, -0.5], [1.0, -1.0, -0.5], [0.0, 1.0, -0.5]);
        assert!(
            region.clipped_bounds(&below).is_none(),
            "behind a one-sided light"
        );
    }
}
