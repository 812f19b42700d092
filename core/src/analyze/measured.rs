//! Measured cost: trace a ray set through a scene structure and through its fallback BVH alone.

use crate::bvh::{AllHitStats, TraversalStats};
use crate::geometry::{Ray, Triangle};
use crate::heuristics::CostConstants;
use crate::toplevel::{AreaLookup, TopLevel, TopLevelStats};

/// What the all-hit walk did through the structure for one ray.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub struct StructureAllHit {
    /// Work in the local BVH (over the part of the segment inside the area).
    pub local: AllHitStats,
    /// Work in the fallback BVH (over the rest of the segment), when the ray fell back.
    pub fallback: AllHitStats,
    /// True when the local BVH found no triangle and the fallback BVH was walked.
    pub fell_back: bool,
}

/// The all-hit walk through the structure, as the thesis measured its "real cost": the first
/// affine candidate area (origin inside, direction within the tolerance) has its local BVH walked
/// over `[t_min, t_exit]` with no early exit; if no triangle there is hit, the fallback BVH is
/// walked over the rest of the segment.
pub fn structure_all_hit<L: AreaLookup>(
    scene: &TopLevel<L>,
    ray: &Ray,
    tris: &[Triangle],
) -> StructureAllHit {
    let mut out = StructureAllHit::default();
    let mut searched_to = ray.t_min;
    let affine = scene.lookup().candidates(ray.origin).iter().find_map(|&a| {
        let area = scene.areas().get(a as usize)?;
        if !area.is_affine(ray) {
            return None;
        }
        // `is_affine` has already found the origin inside (with its tolerance); the clipped
        // entry of a ray starting on the area's boundary (a light's rectangle, a frustum's near
        // plane) may round a hair past `t_min`, so only the exit is taken from the clip.
        let (_, t1) = area.polytope().clip_ray(ray)?;
        Some((a, t1))
    });
    if let Some((a, t_exit)) = affine {
        let segment = Ray {
            t_max: t_exit.min(ray.t_max),
            ..*ray
        };
        if let Some(bvh) = scene.local_bvhs().get(a as usize) {
            out.local = bvh.all_hit(&segment, tris);
        }
        if out.local.hits > 0 {
            return out;
        }
        searched_to = t_exit.min(ray.t_max);
    }
    out.fell_back = true;
    let rest = Ray {
        t_min: searched_to,
        ..*ray
    };
    out.fallback = scene.fallback().all_hit(&rest, tris);
    out
}

/// Sums of measured costs over a ray set; [`RayCostSums::add`] one ray at a time (or
/// [`RayCostSums::merge`] partial sums from several threads), then [`RayCostSums::finish`].
#[derive(Clone, Copy, Debug, Default, PartialEq)]
pub struct RayCostSums {
    rays: u64,
    all_structure: f64,
    all_local: f64,
    all_fallback_part: f64,
    fell_back: u64,
    all_fallback_alone: f64,
    isect_structure: f64,
    isect_local: f64,
    closest_structure: f64,
    closest_local: f64,
    closest_fallback_alone: f64,
    closest_local_answers: u64,
    any_structure: f64,
    any_fallback_alone: f64,
}

/// Mean measured costs per ray. "All-hit" is the thesis's real cost (every node whose box the
/// segment touches, no early exit); "closest-hit" and "any-hit" are real ordered traversals.
/// "Structure" means through the scene (local BVH, then the fallback when it misses), "local"
/// the local BVHs' part of that (the thesis's "without fallback"), "fallback alone" the same
/// rays through the fallback BVH only.
#[derive(Clone, Copy, Debug, Default, PartialEq)]
pub struct RayCosts {
    /// Rays traced.
    pub rays: u64,
    /// All-hit cost through the structure ("Real cost with fallback").
    pub all_hit_structure: f32,
    /// All-hit cost of the local part only ("Real cost without fallback").
    pub all_hit_local: f32,
    /// Mean all-hit cost in the fallback BVH over the rays that fell back ("Only fallback cost").
    pub all_hit_fallback_when_fell_back: f32,
    /// All-hit cost of the rays through the fallback BVH alone ("Fallback BVH cost").
    pub all_hit_fallback_alone: f32,
    /// Inner nodes plus triangles the all-hit walk touched through the structure
    /// ("Intersections with fallback").
    pub intersections_structure: f32,
    /// The same, local part only ("Intersections without fallback").
    pub intersections_local: f32,
    /// Share of rays whose local all-hit walk hit a triangle ("Hit percentage").
    pub local_hit_rate: f32,
    /// Closest-hit cost through the structure.
    pub closest_hit_structure: f32,
    /// Closest-hit cost of the local part only.
    pub closest_hit_local: f32,
    /// Closest-hit cost through the fallback BVH alone.
    pub closest_hit_fallback_alone: f32,
    /// Share of rays whose closest hit the local BVH answered.
    pub closest_hit_local_rate: f32,
    /// Any-hit cost through the structure.
    pub any_hit_structure: f32,
    /// Any-hit cost through the fallback BVH alone.
    pub any_hit_fallback_alone: f32,
}

impl RayCostSums {
    /// Traces `ray` every way and adds its costs under constants `k`.
    pub fn add<L: AreaLookup>(
        &mut self,
        scene: &TopLevel<L>,
        ray: &Ray,
        tris: &[Triangle],
        k: CostConstants,
    ) {
        let fallback = scene.fallback();
        self.rays += 1;
        let s = structure_all_hit(scene, ray, tris);
        let isect = |a: &AllHitStats| f64::from(a.inner_nodes) + f64::from(a.triangles);
        self.all_local += f64::from(s.local.cost(k));
        self.all_structure += f64::from(s.local.cost(k)) + f64::from(s.fallback.cost(k));
        self.isect_local += isect(&s.local);
        self.isect_structure += isect(&s.local) + isect(&s.fallback);
        if s.fell_back {
            self.fell_back += 1;
            self.all_fallback_part += f64::from(s.fallback.cost(k));
        }
        self.all_fallback_alone += f64::from(fallback.all_hit(ray, tris).cost(k));

        let mut st = TopLevelStats::default();
        scene.closest_hit_with_stats(ray, tris, &mut st);
        self.closest_structure += f64::from(st.cost(k));
        self.closest_local += f64::from(st.local.cost(k));
        if st.answered_by.is_some() {
            self.closest_local_answers += 1;
        }
        let mut g = TraversalStats::default();
        fallback.closest_hit_with_stats(ray, tris, &mut g);
        self.closest_fallback_alone += f64::from(g.cost(k));

        let mut st = TopLevelStats::default();
        scene.any_hit_with_stats(ray, tris, &mut st);
        self.any_structure += f64::from(st.cost(k));
        let mut g = TraversalStats::default();
        fallback.any_hit_with_stats(ray, tris, &mut g);
        self.any_fallback_alone += f64::from(g.cost(k));
    }

    /// Adds another set of sums.
    pub fn merge(&mut self, o: &RayCostSums) {
        self.rays += o.rays;
        self.all_structure += o.all_structure;
        self.all_local += o.all_local;
        self.all_fallback_part += o.all_fallback_part;
        self.fell_back += o.fell_back;
        self.all_fallback_alone += o.all_fallback_alone;
        self.isect_structure += o.isect_structure;
        self.isect_local += o.isect_local;
        self.closest_structure += o.closest_structure;
        self.closest_local += o.closest_local;
        self.closest_fallback_alone += o.closest_fallback_alone;
        self.closest_local_answers += o.closest_local_answers;
        self.any_structure += o.any_structure;
        self.any_fallback_alone += o.any_fallback_alone;
    }

    /// The means (all zero for no rays).
    pub fn finish(&self) -> RayCosts {
        if self.rays == 0 {
            return RayCosts::default();
        }
        let n = self.rays as f64;
        let mean = |x: f64| (x / n) as f32;
        RayCosts {
            rays: self.rays,
            all_hit_structure: mean(self.all_structure),
            all_hit_local: mean(self.all_local),
            all_hit_fallback_when_fell_back: if self.fell_back > 0 {
                (self.all_fallback_part / self.fell_back as f64) as f32
            } else {
                0.0
            },
            all_hit_fallback_alone: mean(self.all_fallback_alone),
            intersections_structure: mean(self.isect_structure),
            intersections_local: mean(self.isect_local),
            local_hit_rate: ((self.rays - self.fell_back) as f64 / n) as f32,
            closest_hit_structure: mean(self.closest_structure),
            closest_hit_local: mean(self.closest_local),
            closest_hit_fallback_alone: mean(self.closest_fallback_alone),
            closest_hit_local_rate: (self.closest_local_answers as f64 / n) as f32,
            any_hit_structure: mean(self.any_structure),
            any_hit_fallback_alone: mean(self.any_fallback_alone),
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::influence::{InfluenceArea, PlaneArea};
    use crate::toplevel::TopLevelOptions;
    use alloc::vec;
    use glam::Vec3;

    fn quad(z: f32, x0: f32) -> [Triangle; 2] {
        let p = |x: f32, y: f32| Vec3::new(x, y, z);
        [
            Triangle::new(p(x0, 0.0), p(x0 + 1.0, 0.0), p(x0 + 1.0, 1.0)),
            Triangle::new(p(x0, 0.0), p(x0 + 1.0, 1.0), p(x0, 1.0)),
        ]
    }

    #[test]
    fn measured_costs_by_hand() {
        // A unit quad at z = 1 under a plane area covering exactly it, rays along +z, and a second
        // quad at z = 5 beyond the area (depth 2) that only the fallback sees.
        let mut tris = vec![];
        tris.extend(quad(1.0, 0.0));
        tris.extend(quad(5.0, 3.0));
        let area: InfluenceArea = PlaneArea::new(Vec3::new(0.5, 0.5, 0.0), Vec3::Z, 0.5, 0.5, 2.0)
            .unwrap()
            .into();
        let scene = TopLevel::with_list(&tris, vec![area], &TopLevelOptions::default()).unwrap();
        assert_eq!(scene.triangles_per_area(), &[2]);
        let k = CostConstants::default();
        let mut sums = RayCostSums::default();
        // Ray 1 hits the near quad inside the area; ray 2 starts outside the area (no local
        // BVH) and goes to the fallback.
        let hit = Ray::new(Vec3::new(0.25, 0.75, 0.0), Vec3::Z).unwrap();
        let miss = Ray::new(Vec3::new(3.5, 0.5, 0.0), Vec3::Z).unwrap();
        sums.add(&scene, &hit, &tris, k);
        sums.add(&scene, &miss, &tris, k);
        let r = sums.finish();
        assert_eq!(r.rays, 2);
        assert!((r.local_hit_rate - 0.5).abs() < 1e-6);
        assert!((r.closest_hit_local_rate - 0.5).abs() < 1e-6);
        // The first ray's structure cost is local only; the second's is fallback only.
        let one = structure_all_hit(&scene, &hit, &tris);
        assert!(!one.fell_back && one.local.hits >= 1 && one.fallback == AllHitStats::default());
        let two = structure_all_hit(&scene, &miss, &tris);
        assert!(two.fell_back && two.local == AllHitStats::default() && two.fallback.hits >= 1);
        let expect = (one.local.cost(k) + two.fallback.cost(k)) / 2.0;
        assert!((r.all_hit_structure - expect).abs() < 1e-5);
        assert!((r.all_hit_local - one.local.cost(k) / 2.0).abs() < 1e-5);
        assert!((r.all_hit_fallback_when_fell_back - two.fallback.cost(k)).abs() < 1e-5);
        assert!(r.all_hit_fallback_alone > 0.0 && r.closest_hit_fallback_alone > 0.0);
        assert!(r.any_hit_structure > 0.0);
        let mut merged = RayCostSums::default();
        merged.merge(&sums);
        assert_eq!(merged.finish(), r);
        assert_eq!(RayCostSums::default().finish(), RayCosts::default());
    }
}
