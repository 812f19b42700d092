//! Split-axis choosers: which of the three axis-aligned plane orientations a node tries.

use crate::geometry::Aabb;

/// The axes a node tries, best first, each with a quality in `[0, 1]` (how good the chooser thinks
/// that orientation is; the all-axes chooser rates every axis 1).
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct AxisOrder {
    axes: [u8; 3],
    quality: [f32; 3],
    len: u8,
}

impl AxisOrder {
    /// An order from axes (each 0, 1 or 2) and their qualities, best first.
    ///
    /// # Panics
    /// Never: axes above 2 and entries past the third are ignored.
    pub fn new(entries: &[(usize, f32)]) -> Self {
        let mut order = AxisOrder {
            axes: [0; 3],
            quality: [0.0; 3],
            len: 0,
        };
        for &(axis, quality) in entries.iter().take(3) {
            if axis < 3 {
                order.axes[order.len as usize] = axis as u8;
                order.quality[order.len as usize] = quality;
                order.len += 1;
            }
        }
        order
    }

    /// The axes and qualities, best first.
    pub fn iter(&self) -> impl Iterator<Item = (usize, f32)> + '_ {
        (0..self.len as usize).map(|i| (self.axes[i] as usize, self.quality[i]))
    }

    /// How many axes are tried.
    pub fn len(&self) -> usize {
        self.len as usize
    }

    /// True when no axis is tried.
    pub fn is_empty(&self) -> bool {
        self.len == 0
    }
}

/// Chooses the split axes for a node from its bounds.
pub trait AxisChooser {
    /// The axes to try for a node with bounds `node`, best first.
    fn order(&self, node: &Aabb) -> AxisOrder;
}

/// Try all three axes and keep the cheapest split: the usual binned SAH builder.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub struct AllAxes;

impl AxisChooser for AllAxes {
    #[inline]
    fn order(&self, _node: &Aabb) -> AxisOrder {
        AxisOrder::new(&[(0, 1.0), (1, 1.0), (2, 1.0)])
    }
}

/// The longest splitting plane heuristic (LSPH): axes by decreasing extent, each rated by its
/// extent over the longest one. With [`crate::builder::CutEvaluation::FirstAxis`] only the longest
/// is tried; with the thesis's cut evaluation (threshold 0.99) the next one only when it is
/// nearly as long.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub struct LongestAxis;

impl AxisChooser for LongestAxis {
    #[inline]
    fn order(&self, node: &Aabb) -> AxisOrder {
        let e = node.extent();
        let longest = e.max_element();
        let quality = |k: usize| if longest > 0.0 { e[k] / longest } else { 1.0 };
        let mut axes = [(0, quality(0)), (1, quality(1)), (2, quality(2))];
        sort_by_quality(&mut axes);
        AxisOrder::new(&axes)
    }
}

/// Sorts three (axis, quality) pairs by decreasing quality; ties keep the lower axis first.
#[inline]
pub(crate) fn sort_by_quality(axes: &mut [(usize, f32); 3]) {
    // A stable three-element insertion sort: no allocation, NaN qualities sink to the end.
    for i in 1..3 {
        let mut j = i;
        while j > 0
            && (axes[j].1 > axes[j - 1].1 || (axes[j - 1].1.is_nan() && !axes[j].1.is_nan()))
        {
            axes.swap(j, j - 1);
            j -= 1;
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use glam::Vec3;

    #[test]
    fn longest_axis_picks_largest_extent() {
        let b = Aabb::new(Vec3::ZERO, Vec3::new(1.0, 3.0, 2.0));
        let axes: alloc::vec::Vec<_> = LongestAxis.order(&b).iter().collect();
        assert_eq!(axes, [(1, 1.0), (2, 2.0 / 3.0), (0, 1.0 / 3.0)]);
        assert_eq!(AllAxes.order(&b).len(), 3);
    }

    #[test]
    fn axis_order_ignores_bad_axes() {
        let o = AxisOrder::new(&[(5, 1.0), (2, 0.5)]);
        assert_eq!(o.iter().collect::<alloc::vec::Vec<_>>(), [(2, 0.5)]);
    }
}
