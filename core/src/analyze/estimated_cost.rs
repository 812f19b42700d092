//! Estimated cost under a hit measure: SAH, or PAH for an influence area.

use crate::bvh::Bvh;
use crate::heuristics::{CostConstants, CostModel, Sah};

use super::{Analysis, NodeView};

/// The estimated cost of a tree under the hit measure `M`:
/// `sum over inner nodes of C_trav m(n) + sum over leaves of C_isect count m(n)`, divided by a
/// total measure. With [`Sah`] and the root as total it is the SAH cost; with a PAH model and its
/// window's measure as total it is the expected cost per ray of the area's distribution (rays that
/// miss the root cost nothing), the thesis's "Estimated PAH cost". Same numbers as
/// [`Bvh::estimated_cost_over`], as an analysis that runs in the same walk as the others.
#[derive(Clone, Debug)]
pub struct EstimatedCost<M> {
    model: M,
    k: CostConstants,
    total: Option<f32>,
    sum: f64,
    root: f64,
}

/// What [`EstimatedCost`] found.
#[derive(Clone, Copy, Debug, Default, PartialEq)]
pub struct EstimatedCostReport {
    /// Expected cost per ray of the distribution: the sum over the total measure (over the
    /// root's measure when no total was given). Zero for an empty tree or a zero total.
    pub per_ray: f32,
    /// Expected cost of a ray that hits the root: the sum over the root's measure.
    pub relative_to_root: f32,
    /// The root's measure.
    pub root_measure: f32,
    /// The total measure used for `per_ray`.
    pub total_measure: f32,
}

impl EstimatedCost<Sah> {
    /// The SAH cost (relative to the root).
    pub fn sah(k: CostConstants) -> Self {
        Self::new(Sah, k, None)
    }
}

impl<M: CostModel> EstimatedCost<M> {
    /// The cost under `model` over `total` (the root's measure when `None`).
    pub fn new(model: M, k: CostConstants, total: Option<f32>) -> Self {
        Self {
            model,
            k,
            total,
            sum: 0.0,
            root: 0.0,
        }
    }

    /// The cost under `model` per ray of a distribution of measure `total` (a window's measure).
    pub fn over(model: M, k: CostConstants, total: f32) -> Self {
        Self::new(model, k, Some(total))
    }
}

fn ratio(sum: f64, total: f64) -> f32 {
    if total > 0.0 && total.is_finite() {
        (sum / total) as f32
    } else {
        0.0
    }
}

impl<M: CostModel> Analysis for EstimatedCost<M> {
    type NodeData = ();
    type Output = EstimatedCostReport;

    fn visit(&mut self, v: &NodeView<'_>, _: Option<&()>) {
        let m = f64::from(self.model.measure(&v.node.bounds()));
        if v.index == 0 {
            self.root = m;
        }
        self.sum += if v.node.is_leaf() {
            m * f64::from(self.k.intersection) * f64::from(v.node.count)
        } else {
            m * f64::from(self.k.traversal)
        };
    }

    fn finish(self, _: &Bvh) -> EstimatedCostReport {
        let total = self.total.map_or(self.root, f64::from);
        EstimatedCostReport {
            per_ray: ratio(self.sum, total),
            relative_to_root: ratio(self.sum, self.root),
            root_measure: self.root as f32,
            total_measure: total as f32,
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::analyze::analyze;
    use crate::analyze::analyzer::tests::small_tree;
    use crate::heuristics::PahOrtho;
    use glam::Vec3;

    #[test]
    fn sah_by_hand() {
        // Half areas (xy + yz + zx with y = z = 1): root 4+1+4 = 9, node 1: 5, leaves 3 each.
        // C_trav = 2, C_isect = 1.2: inner 2*(9+5) = 28, leaves 1.2*(3+3+3) = 10.8; over 9.
        let bvh = small_tree();
        let k = CostConstants::THESIS;
        let r = analyze(&bvh, EstimatedCost::sah(k));
        assert!((r.per_ray - 38.8 / 9.0).abs() < 1e-5, "{r:?}");
        assert!((r.relative_to_root - r.per_ray).abs() < 1e-6);
        assert!((r.per_ray - bvh.estimated_cost(&Sah, k)).abs() < 1e-5);
    }

    #[test]
    fn pah_over_window_by_hand() {
        // Rays along +z: a box measures its xy extent. Root 4, node 1: 2, leaves 1 each.
        // Inner 1*(4+2) + leaves 1*(1+1+1) = 9; over a window of 18 -> 0.5; over the root -> 2.25.
        let bvh = small_tree();
        let pah = PahOrtho::new(Vec3::Z).unwrap();
        let r = analyze(
            &bvh,
            EstimatedCost::over(pah, CostConstants::default(), 18.0),
        );
        assert!((r.per_ray - 0.5).abs() < 1e-6, "{r:?}");
        assert!((r.relative_to_root - 2.25).abs() < 1e-6);
        let none = analyze(
            &bvh,
            EstimatedCost::over(pah, CostConstants::default(), 0.0),
        );
        assert_eq!(none.per_ray, 0.0);
    }
}
