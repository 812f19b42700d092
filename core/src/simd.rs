//! 4-wide helpers over `wide::f32x4`: four boxes as structure-of-arrays lanes, so one instruction
//! prices four candidate splits or tests four child boxes.

use wide::f32x4;

use crate::geometry::Aabb;

/// Four boxes, one per lane: `min[k]` holds the four boxes' lower bound on axis `k`.
#[derive(Clone, Copy, Debug)]
pub struct Aabb4 {
    /// Lower corners per axis.
    pub min: [f32x4; 3],
    /// Upper corners per axis.
    pub max: [f32x4; 3],
}

impl Aabb4 {
    /// Four boxes from SoA slices: lane `j` is box `start + j`. Each slice needs `start + 4`
    /// entries.
    #[inline(always)]
    pub fn load(min: &[[f32; 4]; 3], max: &[[f32; 4]; 3]) -> Self {
        Self {
            min: [
                f32x4::from(min[0]),
                f32x4::from(min[1]),
                f32x4::from(min[2]),
            ],
            max: [
                f32x4::from(max[0]),
                f32x4::from(max[1]),
                f32x4::from(max[2]),
            ],
        }
    }

    /// Four boxes, box `j` in lane `j`.
    #[inline(always)]
    pub fn from_boxes(b: [Aabb; 4]) -> Self {
        Self {
            min: core::array::from_fn(|k| f32x4::from(b.map(|b| b.min[k]))),
            max: core::array::from_fn(|k| f32x4::from(b.map(|b| b.max[k]))),
        }
    }

    /// The same box in all four lanes: lets a scalar query share a 4-wide code path.
    #[inline(always)]
    pub fn splat(b: &Aabb) -> Self {
        Self {
            min: [
                f32x4::splat(b.min.x),
                f32x4::splat(b.min.y),
                f32x4::splat(b.min.z),
            ],
            max: [
                f32x4::splat(b.max.x),
                f32x4::splat(b.max.y),
                f32x4::splat(b.max.z),
            ],
        }
    }

    /// Box `j` (0 to 3) as an [`Aabb`].
    #[inline]
    pub fn lane(&self, j: usize) -> Aabb {
        let (lo, hi) = (
            [
                self.min[0].to_array(),
                self.min[1].to_array(),
                self.min[2].to_array(),
            ],
            [
                self.max[0].to_array(),
                self.max[1].to_array(),
                self.max[2].to_array(),
            ],
        );
        Aabb::new(
            glam::Vec3::new(lo[0][j], lo[1][j], lo[2][j]),
            glam::Vec3::new(hi[0][j], hi[1][j], hi[2][j]),
        )
    }

    /// The lanes that hold an empty box (a lower bound above the upper one on some axis), as
    /// a mask: sweeps pad their last group of four with empty boxes.
    #[inline(always)]
    pub fn empty(&self) -> f32x4 {
        self.min[0].simd_gt(self.max[0])
            | self.min[1].simd_gt(self.max[1])
            | self.min[2].simd_gt(self.max[2])
    }

    /// Extents per axis, clamped at zero (empty lanes have none).
    #[inline(always)]
    pub fn extent(&self) -> [f32x4; 3] {
        let z = f32x4::ZERO;
        [
            (self.max[0] - self.min[0]).fast_max(z),
            (self.max[1] - self.min[1]).fast_max(z),
            (self.max[2] - self.min[2]).fast_max(z),
        ]
    }

    /// Half surface areas `xy + yz + zx`, four at a time.
    #[inline(always)]
    pub fn half_area(&self) -> f32x4 {
        let [x, y, z] = self.extent();
        x * y + y * z + z * x
    }
}

#[cfg(test)]
mod tests {
    use glam::Vec3;

    use super::*;

    #[test]
    fn lanes_round_trip_and_areas_match_scalar() {
        let boxes = [
            Aabb::new(Vec3::ZERO, Vec3::new(1.0, 2.0, 3.0)),
            Aabb::new(Vec3::splat(-1.0), Vec3::splat(1.0)),
            Aabb::EMPTY,
            Aabb::new(Vec3::new(0.5, 0.5, 0.5), Vec3::new(0.5, 4.0, 1.5)),
        ];
        let min = core::array::from_fn(|k| core::array::from_fn(|j| boxes[j].min[k]));
        let max = core::array::from_fn(|k| core::array::from_fn(|j| boxes[j].max[k]));
        let b4 = Aabb4::load(&min, &max);
        let areas = b4.half_area().to_array();
        for j in 0..4 {
            assert_eq!(b4.lane(j), boxes[j]);
            assert_eq!(areas[j], boxes[j].half_area());
        }
    }
}
