//! Orthonormal look-at frames, the convention `experiments.toml` specifies for influence areas.

use glam::Vec3;

/// An orthonormal frame: `forward` is the area's ray direction, `right` and `up` span the light
/// rectangle or the image plane.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Frame {
    /// Unit horizontal axis.
    pub right: Vec3,
    /// Unit vertical axis.
    pub up: Vec3,
    /// Unit view or ray direction.
    pub forward: Vec3,
}

impl Frame {
    /// The look-at frame with world up `(0, 1, 0)`: `f = normalize(dir)`,
    /// `right = normalize(f x up_world)`, `up = right x f`. When `f` is (anti)parallel to the world
    /// up, `right` is taken as `normalize(f x (0, 0, 1))`, a fixed choice so the frame is still
    /// deterministic. `None` when `dir` is zero or not finite.
    pub fn look_at(dir: Vec3) -> Option<Frame> {
        // Scaled by its largest component first: the squared length of a tiny direction (1e-22)
        // is subnormal, and normalising it directly gives a vector far from unit length.
        let largest = dir.abs().max_element();
        if !(largest > 0.0 && largest.is_finite()) {
            return None;
        }
        let forward = (dir / largest).try_normalize()?;
        let right = forward
            .cross(Vec3::Y)
            .try_normalize()
            .filter(|_| forward.cross(Vec3::Y).length_squared() > 1e-12)
            .or_else(|| forward.cross(Vec3::Z).try_normalize())?;
        let up = right.cross(forward);
        Some(Frame { right, up, forward })
    }

    /// World vector `v` in frame coordinates `(right, up, forward)`.
    #[inline]
    pub fn to_local(&self, v: Vec3) -> Vec3 {
        Vec3::new(v.dot(self.right), v.dot(self.up), v.dot(self.forward))
    }

    /// Frame coordinates back to a world vector.
    #[inline]
    pub fn to_world(&self, v: Vec3) -> Vec3 {
        self.right * v.x + self.up * v.y + self.forward * v.z
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn frame_is_orthonormal_and_right_handed_look_at() {
        for d in [
            Vec3::Z,
            Vec3::new(1.0, 0.0, 1.0),
            Vec3::new(-0.55, -0.9, 1.0),
            Vec3::Y,
            -Vec3::Y,
        ] {
            let f = Frame::look_at(d).unwrap();
            for (a, b) in [(f.right, f.up), (f.up, f.forward), (f.right, f.forward)] {
                assert!(a.dot(b).abs() < 1e-6);
            }
            for v in [f.right, f.up, f.forward] {
                assert!((v.length() - 1.0).abs() < 1e-6);
            }
            assert!((f.forward - d.normalize()).length() < 1e-6);
            let v = Vec3::new(0.3, -2.0, 5.0);
            assert!((f.to_world(f.to_local(v)) - v).length() < 1e-5);
        }
        // Looking down +z with world up y: right is -x (f x y = z x y = -x).
        let f = Frame::look_at(Vec3::Z).unwrap();
        assert!((f.right - Vec3::NEG_X).length() < 1e-6);
        assert!((f.up - Vec3::Y).length() < 1e-6);
        assert!(Frame::look_at(Vec3::ZERO).is_none());
        let tiny = Frame::look_at(Vec3::new(0.0, -4.5e-23, 1e-24)).unwrap();
        assert!((tiny.forward.length() - 1.0).abs() < 1e-6);
        assert!((tiny.right.length() - 1.0).abs() < 1e-6);
        assert!(Frame::look_at(Vec3::new(f32::NAN, 0.0, 1.0)).is_none());
    }
}
