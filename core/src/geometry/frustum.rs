//! View frustums: the shape of a point influence area.

use glam::Vec3;

use super::{Frame, Plane, PlaneLanes, Polytope};

/// A truncated rectangular pyramid with apex `eye`: local points `(x, y, z)` of the frame with
/// `near <= z <= far`, `|x| <= z tan_x`, `|y| <= z tan_y`.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Frustum {
    /// Apex (the point light's position).
    pub eye: Vec3,
    /// `forward` is the view direction; `right` and `up` span the image plane.
    pub frame: Frame,
    /// `tan(fov_x / 2)`.
    pub tan_x: f32,
    /// `tan(fov_y / 2)`.
    pub tan_y: f32,
    /// Distance of the near plane along `forward`.
    pub near: f32,
    /// Distance of the far plane along `forward`.
    pub far: f32,
}

impl Frustum {
    /// A frustum; `None` unless `eye` is finite, both half-angle tangents are finite and positive,
    /// and `0 <= near < far < inf`.
    pub fn new(
        eye: Vec3,
        frame: Frame,
        tan_x: f32,
        tan_y: f32,
        near: f32,
        far: f32,
    ) -> Option<Self> {
        let ok = eye.is_finite()
            && tan_x.is_finite()
            && tan_x > 0.0
            && tan_y.is_finite()
            && tan_y > 0.0
            && near >= 0.0
            && near < far
            && far.is_finite();
        ok.then_some(Self {
            eye,
            frame,
            tan_x,
            tan_y,
            near,
            far,
        })
    }

    /// True when direction `d` (any length) leaves the eye through the window: within both fields
    /// of view and in front of the eye.
    pub fn sees_direction(&self, d: Vec3) -> bool {
        let l = self.frame.to_local(d);
        l.z > 0.0 && l.x.abs() <= self.tan_x * l.z && l.y.abs() <= self.tan_y * l.z
    }

    /// The frustum as a polytope: near, far and four side planes; 8 corners; 5 face normals; 6
    /// edge directions (`right`, `up`, and the four corner rays).
    pub fn polytope(&self) -> Polytope {
        let f = &self.frame;
        let local = |x: f32, y: f32, z: f32| self.eye + f.to_world(Vec3::new(x, y, z));
        let vertices = core::array::from_fn(|i| {
            let z = if i & 4 == 0 { self.near } else { self.far };
            let sx = if i & 1 == 0 { -1.0 } else { 1.0 };
            let sy = if i & 2 == 0 { -1.0 } else { 1.0 };
            local(sx * z * self.tan_x, sy * z * self.tan_y, z)
        });
        let side = |nx: f32, ny: f32, t: f32| f.to_world(Vec3::new(nx, ny, -t));
        let normals = [
            side(1.0, 0.0, self.tan_x),
            side(-1.0, 0.0, self.tan_x),
            side(0.0, 1.0, self.tan_y),
            side(0.0, -1.0, self.tan_y),
        ];
        let planes = [
            Plane::through(self.eye + f.forward * self.near, -f.forward),
            Plane::through(self.eye + f.forward * self.far, f.forward),
            Plane::through(self.eye, normals[0]),
            Plane::through(self.eye, normals[1]),
            Plane::through(self.eye, normals[2]),
            Plane::through(self.eye, normals[3]),
        ];
        let corner =
            |sx: f32, sy: f32| f.to_world(Vec3::new(sx * self.tan_x, sy * self.tan_y, 1.0));
        let scale = vertices
            .iter()
            .fold(0.0f32, |m: f32, v: &Vec3| m.max(v.abs().max_element()));
        Polytope {
            planes,
            vertices,
            face_normals: [f.forward, normals[0], normals[1], normals[2], normals[3]],
            face_count: 5,
            edges: [
                f.right,
                f.up,
                corner(-1.0, -1.0),
                corner(1.0, -1.0),
                corner(-1.0, 1.0),
                corner(1.0, 1.0),
            ],
            edge_count: 6,
            scale,
            normal_lengths: Polytope::lengths_of(&planes),
            lanes: PlaneLanes::new(&planes, &Polytope::lengths_of(&planes)),
        }
    }
}
