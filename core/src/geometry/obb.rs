//! Oriented bounding boxes: the shape of a plane influence area.

use glam::Vec3;

use super::{Frame, Plane, PlaneLanes, Polytope};

/// A box with its own orthonormal frame: centre, axes (`right`, `up`, `forward`) and half extents
/// along them.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Obb {
    /// Centre of the box.
    pub center: Vec3,
    /// The box's axes.
    pub frame: Frame,
    /// Half extents along `right`, `up`, `forward`.
    pub half: Vec3,
}

impl Obb {
    /// A box; `None` unless the centre is finite and every half extent is finite and positive.
    pub fn new(center: Vec3, frame: Frame, half: Vec3) -> Option<Self> {
        (center.is_finite() && half.is_finite() && half.min_element() > 0.0).then_some(Self {
            center,
            frame,
            half,
        })
    }

    /// The box as a polytope: 6 planes, 8 corners, 3 face normals, 3 edge directions.
    pub fn polytope(&self) -> Polytope {
        let axes = [self.frame.right, self.frame.up, self.frame.forward];
        let h = self.half;
        let vertices = core::array::from_fn(|i| {
            let sx = if i & 1 == 0 { -h.x } else { h.x };
            let sy = if i & 2 == 0 { -h.y } else { h.y };
            let sz = if i & 4 == 0 { -h.z } else { h.z };
            self.center + axes[0] * sx + axes[1] * sy + axes[2] * sz
        });
        let planes = core::array::from_fn(|i| {
            let (axis, sign) = (axes[i / 2], if i % 2 == 0 { 1.0 } else { -1.0 });
            Plane::through(self.center + axis * (sign * h[i / 2]), axis * sign)
        });
        let scale = vertices
            .iter()
            .fold(0.0f32, |m: f32, v: &Vec3| m.max(v.abs().max_element()));
        Polytope {
            planes,
            vertices,
            face_normals: [axes[0], axes[1], axes[2], Vec3::ZERO, Vec3::ZERO],
            face_count: 3,
            edges: [
                axes[0],
                axes[1],
                axes[2],
                Vec3::ZERO,
                Vec3::ZERO,
                Vec3::ZERO,
            ],
            edge_count: 3,
            scale,
            normal_lengths: Polytope::lengths_of(&planes),
            lanes: PlaneLanes::new(&planes, &Polytope::lengths_of(&planes)),
        }
    }
}
