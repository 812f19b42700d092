//! The thesis's cut evaluation: a priced candidate cut, and which axes' cuts a node considers
//! (best of all axes, the first axis only, or the thesis's quality and ratio thresholds with its
//! SAH on the longest axis as the last resort).

use super::config::CutEvaluation;
use crate::geometry::Aabb;
use crate::heuristics::{AxisOrder, CostModel};
use crate::simd::Aabb4;

/// One side of a split: its bounds, primitive count and (doubled) centroid bounds.
pub(super) type Child = (Aabb, u32, Aabb);

/// A priced candidate split, with what pricing it under any other cost model needs: the cheapest
/// bin boundary of a sweep along one axis, or the cheapest bipartition of a tiny node
/// ([`super::exhaustive`]).
#[derive(Clone, Copy, Debug)]
pub(crate) struct Cut {
    /// Where it cuts: the first bin of the right side, or the bipartition's mask.
    pub at: usize,
    pub left: Aabb,
    pub right: Aabb,
    pub n_left: u32,
    pub n_right: u32,
    /// `m(L)` and `m(R)` under the model the cut is priced with, kept from the sweep: a
    /// perspective PAH measure costs hundreds of instructions, so it is never taken twice.
    pub measure_left: f32,
    pub measure_right: f32,
    /// `m(L) n_L + m(R) n_R` under that model.
    pub weighted: f32,
}

impl Cut {
    /// The same cut priced under `model` instead of the model that found it: both sides in
    /// one 4-wide evaluation, with what `model` settled for the node (`hint`, 0 for nothing).
    #[inline]
    pub(crate) fn priced_under(self, model: &impl CostModel, hint: u32) -> Cut {
        let (l, r) = (self.left, self.right);
        let m = model
            .measure4_hinted(&Aabb4::from_boxes([l, r, l, r]), hint)
            .to_array();
        let (ml, mr) = (m[0], m[1]);
        Cut {
            measure_left: ml,
            measure_right: mr,
            weighted: ml * self.n_left as f32 + mr * self.n_right as f32,
            ..self
        }
    }

    /// The thesis's cut ratio `(m(L) + m(R)) / m(parent)` under the model that chose the cut.
    #[inline]
    pub(super) fn ratio(&self, parent: f32) -> f32 {
        (self.measure_left + self.measure_right) / parent
    }
}

/// A node's chosen split: the axis and the cut along it.
#[derive(Clone, Copy, Debug)]
pub(super) struct Split {
    pub(super) axis: usize,
    pub(super) cut: Cut,
}

/// Applies the cut evaluation `cut` to a node whose chooser ranked the axes `order`.
/// `sweep(axis, false)` is the cheapest cut along `axis` under the node's model (`None` where
/// nothing separates the primitives); `sweep(axis, true)` the cheapest under SAH, re-priced under
/// the node's model: the thesis's last resort. Ties go to the earlier axis.
pub(super) fn walk(
    cut: CutEvaluation,
    order: &AxisOrder,
    parent: f32,
    largest: usize,
    mut sweep: impl FnMut(usize, bool) -> Option<Cut>,
) -> Option<Split> {
    let mut best: Option<Split> = None;
    let mut consider = |axis: usize, best: &mut Option<Split>| {
        if let Some(cut) = sweep(axis, false) {
            if best.is_none_or(|b| cut.weighted < b.cut.weighted) {
                *best = Some(Split { axis, cut });
            }
        }
    };
    match cut {
        CutEvaluation::BestOfAxes => order.iter().for_each(|(a, _)| consider(a, &mut best)),
        CutEvaluation::FirstAxis => {
            if let Some((a, _)) = order.iter().next() {
                consider(a, &mut best);
            }
        }
        CutEvaluation::Thesis(thesis) => {
            // Cut ratios come from the measures each cut keeps from its sweep.
            for (i, (axis, quality)) in order.iter().enumerate() {
                if i > 0 && quality < thesis.quality_threshold {
                    break;
                }
                consider(axis, &mut best);
                if best.is_some_and(|b| b.cut.ratio(parent) <= thesis.excellent_ratio) {
                    return best;
                }
            }
            return match best {
                Some(b) if b.cut.ratio(parent) <= thesis.acceptable_ratio => Some(b),
                // Not even acceptable: SAH on the longest axis, the thesis's last resort.
                _ => sweep(largest, true)
                    .map(|cut| Split { axis: largest, cut })
                    .or(best),
            };
        }
    }
    best
}
