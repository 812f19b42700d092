//! The composite scene: influence areas with local BVHs, an area lookup, and a fallback BVH.

use alloc::vec::Vec;
use core::fmt;

use super::{AreaList, AreaLookup, BreakEven, Octree};
use crate::builder::{BuildArena, BuildOptions, Preset, PresetError, ReinsertConfig};
use crate::bvh::{Bvh, Hit, Traversable, TraversalStats, WideBvh};
use crate::geometry::{Ray, Triangle};
use crate::heuristics::CostConstants;
use crate::influence::InfluenceArea;

/// How far before an area's exit the fallback search starts, relative to the exit distance: the
/// local BVH has already answered everything up to the exit, and the overlap keeps a hit exactly
/// at the boundary from falling between the two searches under rounding.
const EXIT_OVERLAP: f32 = 1e-5;

/// How a [`TopLevel`] is built.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct TopLevelOptions {
    /// How every local BVH is built: the `pah` preset by default (binned SAH pricing its cuts
    /// with the area's PAH), whose local trees cost less per ray on average than `sah`'s or
    /// `full`'s (measured: benches/RESULTS.md, section Heuristic quality (SAH/PAH cost of the
    /// presets)). Its reinsertion runs under the preset's model.
    pub local: BuildOptions,
    /// How the fallback BVH is built: `sah` (the default) or `standard`, which needs no area (the
    /// thesis's fallback was SAH + LSPH).
    pub fallback: BuildOptions,
    /// How many affine areas a query tries before falling back (the thesis used 1).
    pub max_tries: u32,
}

impl Default for TopLevelOptions {
    fn default() -> Self {
        Self {
            local: BuildOptions::new(Preset::Pah),
            fallback: BuildOptions::new(Preset::Sah),
            max_tries: 1,
        }
    }
}

impl TopLevelOptions {
    /// The same options with `parallel` set for the local and the fallback builds: with the
    /// `rayon` feature, the local BVHs build side by side with the fallback BVH, which is itself
    /// threaded. The scene is the same.
    pub fn parallel(self, parallel: bool) -> Self {
        Self {
            local: BuildOptions {
                parallel,
                ..self.local
            },
            fallback: BuildOptions {
                parallel,
                ..self.fallback
            },
            ..self
        }
    }

    /// The same options with `reinsert` for the local and the fallback builds.
    pub fn reinsert(self, reinsert: Option<ReinsertConfig>) -> Self {
        Self {
            local: BuildOptions {
                reinsert,
                ..self.local
            },
            fallback: BuildOptions {
                reinsert,
                ..self.fallback
            },
            ..self
        }
    }
}

/// Why a scene could not be built.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum TopLevelError {
    /// A local BVH failed to build.
    Local {
        /// The area.
        area: u32,
        /// Why.
        error: PresetError,
    },
    /// The fallback BVH failed to build.
    Fallback(PresetError),
}

impl fmt::Display for TopLevelError {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        match self {
            TopLevelError::Local { area, error } => write!(f, "local BVH of area {area}: {error}"),
            TopLevelError::Fallback(e) => write!(f, "fallback BVH: {e}"),
        }
    }
}

impl core::error::Error for TopLevelError {}

/// What one query through the scene did.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub struct TopLevelStats {
    /// Affine areas whose local BVH was traversed.
    pub tries: u32,
    /// The area whose local BVH answered, if one did.
    pub answered_by: Option<u32>,
    /// True when the fallback BVH was traversed.
    pub fell_back: bool,
    /// Work in local BVHs.
    pub local: TraversalStats,
    /// Work in the fallback BVH.
    pub fallback: TraversalStats,
}

impl TopLevelStats {
    /// Total cost: local plus fallback work.
    pub fn cost(&self, k: CostConstants) -> f32 {
        self.local.cost(k) + self.fallback.cost(k)
    }
}

/// Influence areas, their local BVHs, an area lookup `L` and the fallback BVH.
///
/// A query finds the candidate areas of its origin, tries up to `max_tries` affine ones, and
/// traverses each one's local BVH over the part of the segment inside the area, `[t_min, t_exit]`.
/// A local hit is accepted only there (a closer triangle just outside the area cannot exist: the
/// segment up to `t_exit` lies inside the area, and every triangle meeting the area is in its
/// local BVH by the conservative test of [`InfluenceArea::takes_triangle`]). Otherwise the
/// fallback BVH answers the rest of the segment. Every answer equals the brute-force one.
///
/// The trees `T` are binary [`Bvh`]s as built; [`TopLevel::widen`] turns every one into a
/// [`WideBvh`] (4-wide nodes, the faster traversal) with the same answers.
///
/// ```
/// use rdbvh_core::toplevel::DEFAULT_OCTREE_LEVELS;
/// use rdbvh_core::{brute_force, InfluenceArea, PlaneArea, Ray, TopLevel, TopLevelOptions, Triangle, Vec3};
///
/// // A floor of 200 triangles at y = 0.
/// let tris: Vec<Triangle> = (0..100)
///     .flat_map(|i| {
///         let o = Vec3::new((i % 10) as f32, 0.0, (i / 10) as f32);
///         [Triangle::new(o, o + Vec3::X, o + Vec3::Z), Triangle::new(o + Vec3::X, o + Vec3::X + Vec3::Z, o + Vec3::Z)]
///     })
///     .collect();
/// // An area light's parallel rays: a 2 x 2 window at y = 5, shining down (-y) for 6 units.
/// let area: InfluenceArea = PlaneArea::new(Vec3::new(5.0, 5.0, 5.0), -Vec3::Y, 1.0, 1.0, 6.0)?.into();
/// let options = TopLevelOptions::default(); // local BVH: the area's PAH; fallback: SAH
/// let scene = TopLevel::with_octree(&tris, vec![area], &options, DEFAULT_OCTREE_LEVELS)?;
///
/// // A ray of the light's: its area's local BVH answers it.
/// let shadow = Ray::new(Vec3::new(5.2, 4.9, 5.3), -Vec3::Y)?;
/// assert!((scene.closest_hit(&shadow, &tris).unwrap().t - 4.9).abs() < 1e-5);
/// // Any other ray: the fallback BVH. Both answer as brute force does.
/// let other = Ray::new(Vec3::new(-1.0, 1.0, 2.5), Vec3::new(1.0, -0.5, 0.0))?;
/// assert_eq!(scene.closest_hit(&other, &tris), brute_force::closest_hit(&other, &tris));
/// assert!(scene.any_hit(&shadow, &tris));
/// # Ok::<(), Box<dyn std::error::Error>>(())
/// ```
#[derive(Clone, Debug)]
pub struct TopLevel<L: AreaLookup = Octree, T: Traversable = Bvh> {
    areas: Vec<InfluenceArea>,
    local: Vec<T>,
    fallback: T,
    lookup: L,
    max_tries: u32,
}

impl TopLevel<Octree> {
    /// A scene over `tris` with an octree of `levels` levels.
    pub fn with_octree(
        tris: &[Triangle],
        areas: Vec<InfluenceArea>,
        options: &TopLevelOptions,
        levels: u32,
    ) -> Result<Self, TopLevelError> {
        Self::build(tris, areas, options, |a| Octree::build(a, levels))
    }
}

impl TopLevel<AreaList> {
    /// A scene over `tris` with the naive area list.
    pub fn with_list(
        tris: &[Triangle],
        areas: Vec<InfluenceArea>,
        options: &TopLevelOptions,
    ) -> Result<Self, TopLevelError> {
        Self::build(tris, areas, options, |a| AreaList::new(a.len()))
    }
}

impl<L: AreaLookup> TopLevel<L> {
    /// Builds the local BVHs, the fallback BVH and the lookup. With
    /// [`BuildOptions::parallel`] set (and the `rayon` feature), the local BVHs build on rayon's
    /// threads beside the fallback BVH; the scene is the same.
    pub fn build(
        tris: &[Triangle],
        areas: Vec<InfluenceArea>,
        options: &TopLevelOptions,
        lookup: impl FnOnce(&[InfluenceArea]) -> L,
    ) -> Result<Self, TopLevelError> {
        let local_build = |i: usize, area: &InfluenceArea| {
            let fail = |error: PresetError| TopLevelError::Local {
                area: i as u32,
                error,
            };
            let ids: Vec<u32> = area.triangles_in(tris).collect();
            let mut arena = BuildArena::with_capacity(ids.len());
            arena
                .load_triangle_subset(tris, ids)
                .map_err(|e| fail(e.into()))?;
            options
                .local
                .build_loaded(&mut arena, Some(area))
                .map_err(fail)
        };
        let fallback_build = || {
            options
                .fallback
                .build(tris, None)
                .map_err(TopLevelError::Fallback)
        };
        let threaded = options.local.parallel || options.fallback.parallel;
        let (local, fallback) = side_by_side(
            threaded,
            || map_areas(threaded, &areas, local_build),
            fallback_build,
        );
        let lookup = lookup(&areas);
        Ok(Self {
            areas,
            local: local?,
            fallback: fallback?,
            lookup,
            max_tries: options.max_tries,
        })
    }

    /// The same scene with every local and the fallback BVH collapsed to 4-wide nodes
    /// ([`WideBvh::from_binary`], each with its own copy of its triangles from `tris`, the array
    /// the scene was built over): same areas, lookup and answers, faster queries.
    pub fn widen(self, tris: &[Triangle]) -> TopLevel<L, WideBvh> {
        TopLevel {
            areas: self.areas,
            local: self
                .local
                .iter()
                .map(|b| WideBvh::from_binary(b, tris))
                .collect(),
            fallback: WideBvh::from_binary(&self.fallback, tris),
            lookup: self.lookup,
            max_tries: self.max_tries,
        }
    }
}

impl<L: AreaLookup, T: Traversable> TopLevel<L, T> {
    /// Assembles a scene from parts built elsewhere (a threaded host builds the local BVHs in
    /// parallel). `None` unless there is one local BVH per area. The caller vouches that each
    /// local BVH holds every triangle overlapping its area (as [`TopLevel::build`] selects them):
    /// the exactness of the queries rests on it.
    pub fn from_parts(
        areas: Vec<InfluenceArea>,
        local: Vec<T>,
        fallback: T,
        lookup: L,
        max_tries: u32,
    ) -> Option<Self> {
        (areas.len() == local.len()).then_some(Self {
            areas,
            local,
            fallback,
            lookup,
            max_tries,
        })
    }

    /// The influence areas.
    pub fn areas(&self) -> &[InfluenceArea] {
        &self.areas
    }

    /// The local BVH of each area.
    pub fn local_bvhs(&self) -> &[T] {
        &self.local
    }

    /// How many triangles each area's local BVH holds.
    pub fn triangles_per_area(&self) -> Vec<u32> {
        self.local.iter().map(|b| b.prim_count() as u32).collect()
    }

    /// The fallback BVH.
    pub fn fallback(&self) -> &T {
        &self.fallback
    }

    /// The area lookup.
    pub fn lookup(&self) -> &L {
        &self.lookup
    }

    /// Bytes of every BVH, the lookup and the areas.
    pub fn memory_bytes(&self) -> usize {
        self.local.iter().map(T::memory_bytes).sum::<usize>()
            + self.fallback.memory_bytes()
            + self.lookup.memory_bytes()
            + self.areas.len() * core::mem::size_of::<InfluenceArea>()
    }

    /// The local segments a query searches before the fallback BVH: for each of up to
    /// `max_tries` affine candidate areas (the origin is inside), the area and where the segment
    /// leaves it. This is the structure's per-ray overhead (the lookup, the affinity test and the
    /// clip), public so that it can be measured and a caller can see which area a ray goes to.
    #[inline]
    pub fn affine_segments<'a>(&'a self, ray: &'a Ray) -> impl Iterator<Item = (u32, f32)> + 'a {
        self.lookup
            .candidates(ray.origin)
            .iter()
            .filter_map(move |&a| {
                let area = &self.areas[a as usize];
                // The local BVH answers only the part of the segment inside the area. A segment
                // reaching back before the origin (t_min < 0) skips the area. The slack admits
                // rays starting exactly on the light face or near plane, whose clipped entry
                // rounds a hair past t_min, within the triangle selection's tolerance.
                // An origin strictly inside enters at t_min itself: no slack to work out.
                let (t0, t1) = area.affine_clip(ray)?;
                if t0 <= ray.t_min {
                    return Some((a, t1));
                }
                let scale = area.polytope().scale.max(ray.origin.abs().max_element());
                let slack = 1e-5 * scale / ray.dir.length();
                (t0 <= ray.t_min + slack).then_some((a, t1))
            })
            .take(self.max_tries as usize)
    }

    /// The closest hit, exactly as brute force finds it.
    pub fn closest_hit(&self, ray: &Ray, tris: &[Triangle]) -> Option<Hit> {
        self.closest(ray, tris, &mut ())
    }

    /// [`TopLevel::closest_hit`], recording what it did in `stats`.
    pub fn closest_hit_with_stats(
        &self,
        ray: &Ray,
        tris: &[Triangle],
        stats: &mut TopLevelStats,
    ) -> Option<Hit> {
        self.closest(ray, tris, stats)
    }

    /// True when anything is hit on the segment, exactly as brute force says.
    pub fn any_hit(&self, ray: &Ray, tris: &[Triangle]) -> bool {
        self.any(ray, tris, &mut ())
    }

    /// [`TopLevel::any_hit`], recording what it did in `stats`.
    pub fn any_hit_with_stats(
        &self,
        ray: &Ray,
        tris: &[Triangle],
        stats: &mut TopLevelStats,
    ) -> bool {
        self.any(ray, tris, stats)
    }

    /// The closest-hit query, recording into `log` (`()` records nothing, and its counting
    /// compiles away, as the trees' own does).
    #[inline]
    fn closest(&self, ray: &Ray, tris: &[Triangle], log: &mut impl QueryLog) -> Option<Hit> {
        let mut searched_to = ray.t_min;
        for (a, t_exit) in self.affine_segments(ray) {
            let segment = Ray {
                t_max: t_exit.min(ray.t_max),
                ..*ray
            };
            if let Some(hit) = log.closest(&self.local[a as usize], &segment, tris, true) {
                log.answered_by(a);
                return Some(hit);
            }
            searched_to = searched_to.max(t_exit - t_exit.abs() * EXIT_OVERLAP);
            // The segment ends inside the area, past the overlap: the local BVH searched all of
            // it, and the fallback would search an empty segment.
            if searched_to >= ray.t_max {
                return None;
            }
        }
        let rest = Ray {
            t_min: searched_to,
            ..*ray
        };
        log.closest(&self.fallback, &rest, tris, false)
    }

    /// The any-hit query, recording into `log`.
    #[inline]
    fn any(&self, ray: &Ray, tris: &[Triangle], log: &mut impl QueryLog) -> bool {
        let mut searched_to = ray.t_min;
        for (a, t_exit) in self.affine_segments(ray) {
            let segment = Ray {
                t_max: t_exit.min(ray.t_max),
                ..*ray
            };
            if log.any(&self.local[a as usize], &segment, tris, true) {
                log.answered_by(a);
                return true;
            }
            searched_to = searched_to.max(t_exit - t_exit.abs() * EXIT_OVERLAP);
            if searched_to >= ray.t_max {
                return false;
            }
        }
        let rest = Ray {
            t_min: searched_to,
            ..*ray
        };
        log.any(&self.fallback, &rest, tris, false)
    }

    /// The break-even measurement for area `area` over `rays`: its local hit rate, the local and
    /// fallback closest-hit costs, and the cost through the structure. `None` when the scene has
    /// no area `area`.
    pub fn break_even(
        &self,
        area: usize,
        rays: impl IntoIterator<Item = Ray>,
        tris: &[Triangle],
        k: CostConstants,
    ) -> Option<BreakEven> {
        if area >= self.areas.len() {
            return None;
        }
        let mut out = BreakEven::default();
        let (mut hits, mut local, mut global, mut structure) = (0u32, 0f64, 0f64, 0f64);
        for ray in rays {
            out.rays += 1;
            let mut s = TopLevelStats::default();
            self.closest_hit_with_stats(&ray, tris, &mut s);
            if s.answered_by == Some(area as u32) {
                hits += 1;
            }
            local += f64::from(s.local.cost(k));
            structure += f64::from(s.cost(k));
            let mut g = TraversalStats::default();
            self.fallback.closest_hit_with_stats(&ray, tris, &mut g);
            global += f64::from(g.cost(k));
        }
        if out.rays > 0 {
            let n = f64::from(out.rays);
            out.hit_rate = hits as f32 / out.rays as f32;
            out.cost_local = (local / n) as f32;
            out.cost_global = (global / n) as f32;
            out.cost_structure = (structure / n) as f32;
        }
        Some(out)
    }

    /// Keeps only the areas `keep` accepts (by index), rebuilding the lookup: for dropping the
    /// areas whose [`BreakEven`] says they do not pay off.
    pub fn retain_areas(&mut self, keep: impl Fn(usize) -> bool) {
        let mask: Vec<bool> = (0..self.areas.len()).map(keep).collect();
        retain_by_mask(&mut self.areas, &mask);
        retain_by_mask(&mut self.local, &mask);
        self.lookup = self.lookup.rebuilt(&self.areas);
    }
}

/// Where a scene query records what it did: [`TopLevelStats`], or `()` for nothing.
trait QueryLog {
    /// A tree's closest hit on `ray`: an affine area's local tree (`local`) or the fallback's.
    fn closest<T: Traversable>(
        &mut self,
        t: &T,
        ray: &Ray,
        tris: &[Triangle],
        local: bool,
    ) -> Option<Hit>;
    /// A tree's any hit on `ray`, as [`QueryLog::closest`].
    fn any<T: Traversable>(&mut self, t: &T, ray: &Ray, tris: &[Triangle], local: bool) -> bool;
    /// Area `area`'s local tree answered.
    fn answered_by(&mut self, area: u32);
}

impl QueryLog for () {
    #[inline(always)]
    fn closest<T: Traversable>(
        &mut self,
        t: &T,
        ray: &Ray,
        tris: &[Triangle],
        _: bool,
    ) -> Option<Hit> {
        t.closest_hit(ray, tris)
    }
    #[inline(always)]
    fn any<T: Traversable>(&mut self, t: &T, ray: &Ray, tris: &[Triangle], _: bool) -> bool {
        t.any_hit(ray, tris)
    }
    #[inline(always)]
    fn answered_by(&mut self, _: u32) {}
}

impl TopLevelStats {
    /// The counters of a local tree's try, or of the fallback, noting which.
    fn tree(&mut self, local: bool) -> &mut TraversalStats {
        if local {
            self.tries += 1;
            &mut self.local
        } else {
            self.fell_back = true;
            &mut self.fallback
        }
    }
}

impl QueryLog for TopLevelStats {
    fn closest<T: Traversable>(
        &mut self,
        t: &T,
        ray: &Ray,
        tris: &[Triangle],
        local: bool,
    ) -> Option<Hit> {
        t.closest_hit_with_stats(ray, tris, self.tree(local))
    }
    fn any<T: Traversable>(&mut self, t: &T, ray: &Ray, tris: &[Triangle], local: bool) -> bool {
        t.any_hit_with_stats(ray, tris, self.tree(local))
    }
    fn answered_by(&mut self, area: u32) {
        self.answered_by = Some(area);
    }
}

/// Runs `a` and `b` on rayon's threads when `threaded` (and the `rayon` feature) say so, else
/// one after the other.
fn side_by_side<A: Send, B: Send>(
    threaded: bool,
    a: impl FnOnce() -> A + Send,
    b: impl FnOnce() -> B + Send,
) -> (A, B) {
    #[cfg(feature = "rayon")]
    if threaded {
        return rayon::join(a, b);
    }
    let _ = threaded;
    (a(), b())
}

/// `f` over every area in order, on rayon's threads when `threaded` (and the `rayon` feature) say
/// so; the first error stops it.
fn map_areas<R: Send, E: Send>(
    threaded: bool,
    areas: &[InfluenceArea],
    f: impl Fn(usize, &InfluenceArea) -> Result<R, E> + Sync + Send,
) -> Result<Vec<R>, E> {
    #[cfg(feature = "rayon")]
    if threaded {
        use rayon::prelude::*;
        return areas.par_iter().enumerate().map(|(i, a)| f(i, a)).collect();
    }
    let _ = threaded;
    areas.iter().enumerate().map(|(i, a)| f(i, a)).collect()
}

fn retain_by_mask<T>(v: &mut Vec<T>, mask: &[bool]) {
    let mut keep = mask.iter();
    v.retain(|_| keep.next().copied().unwrap_or(false));
}

#[cfg(test)]
mod tests {
    use glam::Vec3;

    use super::*;
    use crate::brute_force;
    use crate::influence::{PlaneArea, PointArea, RaySampler};
    use crate::random::Pcg32;

    fn soup(n: usize, seed: u64) -> Vec<Triangle> {
        crate::test_scenes::soup(n, seed, 0.0, 10.0, 1.5)
    }

    fn areas() -> Vec<InfluenceArea> {
        alloc::vec![
            PlaneArea::new(Vec3::new(5.0, 5.0, 2.0), Vec3::Z, 3.0, 3.0, 4.0)
                .unwrap()
                .into(),
            PointArea::new(
                Vec3::new(5.0, 12.0, 5.0),
                Vec3::new(0.0, -1.0, 0.1),
                60.0,
                60.0,
                1.0,
                8.0
            )
            .unwrap()
            .into(),
        ]
    }

    #[test]
    fn queries_equal_brute_force_for_affine_and_other_rays() {
        let tris = soup(800, 2);
        let options = TopLevelOptions::default();
        let octree = TopLevel::with_octree(&tris, areas(), &options, 5).unwrap();
        let list = TopLevel::with_list(&tris, areas(), &options).unwrap();
        let wide = octree.clone().widen(&tris);
        assert_eq!(wide.triangles_per_area(), octree.triangles_per_area());
        let mut rng = Pcg32::new(4);
        let (mut local_answers, mut wide_local_answers) = (0, 0);
        for (i, area) in areas().into_iter().enumerate() {
            let mut sampler = RaySampler::new(area, i as u64);
            for j in 0..2000 {
                let mut ray = sampler.sample();
                if j % 3 == 1 {
                    // Almost affine: a little off the area's direction.
                    ray = Ray::new(ray.origin, ray.dir + Vec3::splat(0.02)).unwrap();
                } else if j % 3 == 2 {
                    let d = Vec3::new(
                        rng.range(-1.0, 1.0),
                        rng.range(-1.0, 1.0),
                        rng.range(-1.0, 1.0),
                    );
                    let Ok(r) = Ray::new(ray.origin + Vec3::Z, d) else {
                        continue;
                    };
                    ray = r;
                }
                let expect = brute_force::closest_hit(&ray, &tris);
                let mut s = TopLevelStats::default();
                assert_eq!(octree.closest_hit_with_stats(&ray, &tris, &mut s), expect);
                local_answers += usize::from(s.answered_by.is_some());
                let mut w = TopLevelStats::default();
                assert_eq!(wide.closest_hit_with_stats(&ray, &tris, &mut w), expect);
                wide_local_answers += usize::from(w.answered_by.is_some());
                assert_eq!(wide.any_hit(&ray, &tris), expect.is_some());
                assert_eq!(list.closest_hit(&ray, &tris), expect);
                assert_eq!(octree.any_hit(&ray, &tris), expect.is_some());
                assert_eq!(list.any_hit(&ray, &tris), expect.is_some());
            }
        }
        assert!(
            local_answers > 500,
            "local BVHs answered only {local_answers} rays"
        );
        // The same areas answer, whichever trees they hold.
        assert_eq!(wide_local_answers, local_answers);
    }

    /// A scene fuzz case: a segment reaching back before its origin (t_min = -inf)
    /// leaves the area behind the light, where the local BVH has no triangles.
    #[test]
    fn segments_reaching_back_out_of_the_area_use_the_fallback() {
        let area: InfluenceArea = PlaneArea::new(Vec3::ZERO, Vec3::Z, 1.0, 1.0, 2.0)
            .unwrap()
            .into();
        let behind = Triangle::new(
            Vec3::new(-1.0, -1.0, -0.5),
            Vec3::new(1.0, -1.0, -0.5),
            Vec3::new(0.0, 1.0, -0.5),
        );
        let tris = [behind];
        let scene = TopLevel::with_octree(&tris, alloc::vec![area], &TopLevelOptions::default(), 5)
            .unwrap();
        let ray = Ray::segment(
            Vec3::new(0.1, 0.1, 0.5),
            Vec3::Z,
            f32::NEG_INFINITY,
            f32::INFINITY,
        )
        .unwrap();
        let expect = brute_force::closest_hit(&ray, &tris);
        assert!(expect.is_some_and(|h| (h.t + 1.0).abs() < 1e-6));
        assert_eq!(scene.closest_hit(&ray, &tris), expect);
        assert!(scene.any_hit(&ray, &tris));
        // From t_min = 0 the same ray is affine, answered locally, and misses.
        let forward = Ray::new(Vec3::new(0.1, 0.1, 0.5), Vec3::Z).unwrap();
        let mut stats = TopLevelStats::default();
        assert_eq!(
            scene.closest_hit_with_stats(&forward, &tris, &mut stats),
            None
        );
        assert_eq!(stats.tries, 1);
    }

    #[test]
    fn break_even_and_retain() {
        let tris = soup(800, 3);
        let mut scene =
            TopLevel::with_octree(&tris, areas(), &TopLevelOptions::default(), 5).unwrap();
        let rays: Vec<Ray> = RaySampler::new(scene.areas()[0], 1).take(2000).collect();
        let k = CostConstants::default();
        assert_eq!(scene.break_even(2, rays.iter().copied(), &tris, k), None);
        let be = scene.break_even(0, rays, &tris, k).unwrap();
        assert_eq!(be.rays, 2000);
        assert!(be.cost_global > 0.0 && be.cost_local > 0.0);
        assert!((0.0..=1.0).contains(&be.hit_rate));
        scene.retain_areas(|i| i == 1);
        assert_eq!(scene.areas().len(), 1);
        assert_eq!(scene.local_bvhs().len(), 1);
    }

    #[cfg(feature = "rayon")]
    #[test]
    fn threaded_scene_equals_single_threaded() {
        let mut tris = soup(5_000, 9);
        // Long triangles across the soup, so that reinsertion moves something.
        tris.extend((0..100).map(|i| {
            let y = i as f32 * 0.1;
            Triangle::new(
                Vec3::new(0.0, y, 0.0),
                Vec3::new(10.0, y, 10.0),
                Vec3::new(0.0, y + 0.1, 10.0),
            )
        }));
        let mut fallbacks = Vec::new();
        for reinsert in [None, Some(ReinsertConfig::default())] {
            let serial = TopLevelOptions::default().reinsert(reinsert);
            let threaded = serial.parallel(true);
            let a = TopLevel::with_octree(&tris, areas(), &threaded, 5).unwrap();
            let b = TopLevel::with_octree(&tris, areas(), &serial, 5).unwrap();
            assert_eq!(a.local_bvhs(), b.local_bvhs());
            assert_eq!(a.fallback(), b.fallback());
            fallbacks.push(a.fallback().clone());
        }
        // The option reaches the trees.
        assert!(fallbacks[0] != fallbacks[1], "reinsertion changed nothing");
    }
}
