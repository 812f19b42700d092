//! Cube-map cells: a direction's face and face coordinates, and a cell's cone of directions as
//! four planes through the light.

use glam::{DVec3, Vec3};

/// The cube map's faces: `+x, -x, +y, -y, +z, -z`.
pub(crate) const FACES: usize = 6;

/// How far a cell's cone is widened, in face coordinates (which span `[-1, 1]`): the cell a
/// lookup computes in f32 then holds the segment's true direction, at a face's edges too.
pub(crate) const FACE_MARGIN: f64 = 1e-3;

/// How far outside a spot's cone a cell must lie, in radians, to be dark.
pub(crate) const CONE_MARGIN: f64 = 1e-3;

/// The face of direction `d` (finite, non-zero) and its face coordinates `(u, v)` in `[-1, 1]`:
/// the major axis `k` (ties to the lower axis), its sign, and the other two axes in cyclic order
/// divided by `|d_k|`.
#[inline(always)]
pub(crate) fn face_coords(d: Vec3) -> (usize, f32, f32) {
    let a = d.abs();
    let k = if a.x >= a.y && a.x >= a.z {
        0
    } else if a.y >= a.z {
        1
    } else {
        2
    };
    let (ua, va) = ((k + 1) % 3, (k + 2) % 3);
    let inv = 1.0 / a[k];
    let face = 2 * k + usize::from(d[k] < 0.0);
    (face, d[ua] * inv, d[va] * inv)
}

/// A rectangle of face coordinates on one face: the directions of one cell, or of a quadtree
/// node of cells.
#[derive(Clone, Copy, Debug, PartialEq)]
pub(crate) struct CellRect {
    pub face: usize,
    pub u: (f64, f64),
    pub v: (f64, f64),
}

impl CellRect {
    /// The whole face.
    pub fn face(face: usize) -> Self {
        Self {
            face,
            u: (-1.0, 1.0),
            v: (-1.0, 1.0),
        }
    }

    /// Quadrant `q` (bit 0: upper half in `u`, bit 1: upper half in `v`).
    pub fn quadrant(&self, q: usize) -> Self {
        let half = |(lo, hi): (f64, f64), upper: bool| {
            let mid = 0.5 * (lo + hi);
            if upper {
                (mid, hi)
            } else {
                (lo, mid)
            }
        };
        Self {
            face: self.face,
            u: half(self.u, q & 1 != 0),
            v: half(self.v, q & 2 != 0),
        }
    }

    /// The face's axis, its sign and the two coordinate axes.
    fn axes(&self) -> (usize, f64, usize, usize) {
        let k = self.face / 2;
        let sign = if self.face.is_multiple_of(2) {
            1.0
        } else {
            -1.0
        };
        (k, sign, (k + 1) % 3, (k + 2) % 3)
    }

    /// The direction with face coordinates `(u, v)` (not unit length).
    pub fn direction(&self, u: f64, v: f64) -> DVec3 {
        let (k, sign, a, b) = self.axes();
        let mut d = DVec3::ZERO;
        d[k] = sign;
        d[a] = u;
        d[b] = v;
        d
    }

    /// The inward normals `n` of the widened cell's four side planes through the apex: a
    /// direction `d` is in the cell when `n . d >= 0` for all four.
    pub fn side_normals(&self) -> [DVec3; 4] {
        let (k, sign, a, b) = self.axes();
        let axis = |i: usize| {
            let mut e = DVec3::ZERO;
            e[i] = 1.0;
            e
        };
        let (ek, ea, eb) = (axis(k) * sign, axis(a), axis(b));
        let (u0, u1) = (self.u.0 - FACE_MARGIN, self.u.1 + FACE_MARGIN);
        let (v0, v1) = (self.v.0 - FACE_MARGIN, self.v.1 + FACE_MARGIN);
        [ea - ek * u0, ek * u1 - ea, eb - ek * v0, ek * v1 - eb]
    }

    /// The widened cell's four corner directions (unit length): its cone's extreme rays.
    pub fn corners(&self) -> [DVec3; 4] {
        let (u0, u1) = (self.u.0 - FACE_MARGIN, self.u.1 + FACE_MARGIN);
        let (v0, v1) = (self.v.0 - FACE_MARGIN, self.v.1 + FACE_MARGIN);
        [(u0, v0), (u1, v0), (u0, v1), (u1, v1)].map(|(u, v)| self.direction(u, v).normalize())
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::random::Pcg32;

    /// Every direction lies inside the cell that its face coordinates name, by the planes.
    #[test]
    fn face_coordinates_agree_with_the_cell_planes() {
        let mut rng = Pcg32::new(11);
        for _ in 0..20_000 {
            let d = Vec3::new(
                rng.range(-1.0, 1.0),
                rng.range(-1.0, 1.0),
                rng.range(-1.0, 1.0),
            );
            if d == Vec3::ZERO {
                continue;
            }
            let (face, u, v) = face_coords(d);
            assert!((-1.0..=1.0).contains(&u) && (-1.0..=1.0).contains(&v));
            let (u, v) = (f64::from(u), f64::from(v));
            let g = 8.0;
            let i = ((u + 1.0) * 0.5 * g).floor().clamp(0.0, g - 1.0);
            let j = ((v + 1.0) * 0.5 * g).floor().clamp(0.0, g - 1.0);
            let cell = CellRect {
                face,
                u: (i * 2.0 / g - 1.0, (i + 1.0) * 2.0 / g - 1.0),
                v: (j * 2.0 / g - 1.0, (j + 1.0) * 2.0 / g - 1.0),
            };
            for n in cell.side_normals() {
                assert!(n.dot(d.as_dvec3()) >= 0.0, "{d} outside its cell {cell:?}");
            }
        }
    }

    #[test]
    fn ties_go_to_the_lower_axis_and_signs_pick_the_face() {
        assert_eq!(face_coords(Vec3::new(1.0, 1.0, 1.0)).0, 0);
        assert_eq!(face_coords(Vec3::new(-1.0, 1.0, 0.5)).0, 1);
        assert_eq!(face_coords(Vec3::new(0.0, -2.0, 1.0)).0, 3);
        assert_eq!(face_coords(Vec3::new(0.0, 0.0, -1.0)).0, 5);
        let (_, u, v) = face_coords(Vec3::new(0.5, 0.25, 2.0));
        assert_eq!((u, v), (0.25, 0.125));
    }
}
