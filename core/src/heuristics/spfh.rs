//! The splitting plane facing heuristic: split along the plane most parallel to the rays.

use glam::Vec3;

use super::axis::sort_by_quality;
use super::{AxisChooser, AxisOrder};
use crate::geometry::Aabb;
use crate::influence::InfluenceArea;

/// SPFH: a plane whose normal is axis `k` is parallel to rays of direction `v` when `v_k` is
/// small, and such a plane rarely sends one ray into both children. Each axis is rated
/// `quality_k = (1 - |v_k| / |v|_1)^2` and tried in that order; `v` is the area's ray direction at
/// the node: the normal for parallel rays, eye to node centre for radial rays.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Spfh {
    dir: Vec3,
    eye: Option<Vec3>,
}

impl Spfh {
    /// Parallel rays along `dir`.
    pub fn parallel(dir: Vec3) -> Self {
        Self { dir, eye: None }
    }

    /// Radial rays from `eye`.
    pub fn radial(eye: Vec3) -> Self {
        Self {
            dir: Vec3::Z,
            eye: Some(eye),
        }
    }

    /// The rays of an influence area.
    pub fn for_area(area: &InfluenceArea) -> Self {
        match area {
            InfluenceArea::Plane(a) => Self::parallel(a.frame.forward),
            InfluenceArea::Point(a) => Self::radial(a.eye()),
        }
    }

    /// The three qualities for ray direction `v` (all 1 for a zero `v`, where no plane faces the
    /// rays better than another).
    pub fn qualities(v: Vec3) -> Vec3 {
        let a = v.abs();
        let l1 = a.x + a.y + a.z;
        if !(l1 > 0.0 && l1.is_finite()) {
            return Vec3::ONE;
        }
        let q = Vec3::ONE - a / l1;
        q * q
    }
}

impl AxisChooser for Spfh {
    #[inline]
    fn order(&self, node: &Aabb) -> AxisOrder {
        let v = match self.eye {
            Some(eye) => node.center() - eye,
            None => self.dir,
        };
        let q = Self::qualities(v);
        let mut axes = [(0, q.x), (1, q.y), (2, q.z)];
        sort_by_quality(&mut axes);
        AxisOrder::new(&axes)
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn axes(s: &Spfh, node: &Aabb) -> [usize; 3] {
        let o = s.order(node);
        let mut it = o.iter().map(|(a, _)| a);
        core::array::from_fn(|_| it.next().unwrap())
    }

    #[test]
    fn parallel_rays_along_z_split_x_or_y_first() {
        let node = Aabb::new(Vec3::ZERO, Vec3::ONE);
        assert_eq!(axes(&Spfh::parallel(Vec3::Z), &node), [0, 1, 2]);
        assert_eq!(
            axes(&Spfh::parallel(Vec3::new(0.0, -3.0, 0.0)), &node),
            [0, 2, 1]
        );
        // Mostly along x, a little along z: the y plane is the most parallel, then z, then x.
        assert_eq!(
            axes(&Spfh::parallel(Vec3::new(1.0, 0.0, 0.27)), &node),
            [1, 2, 0]
        );
        let q = Spfh::qualities(Vec3::new(1.0, 0.0, 1.0));
        assert!((q - Vec3::new(0.25, 1.0, 0.25)).length() < 1e-6);
    }

    #[test]
    fn radial_rays_use_eye_to_centre() {
        let s = Spfh::radial(Vec3::ZERO);
        let above = Aabb::new(Vec3::new(-1.0, 9.0, -1.0), Vec3::new(1.0, 11.0, 1.0));
        assert_eq!(axes(&s, &above)[2], 1, "rays run along y: split y last");
        let right = Aabb::new(Vec3::new(9.0, -1.0, -1.0), Vec3::new(11.0, 1.0, 1.0));
        assert_eq!(axes(&s, &right)[2], 0);
    }
}
