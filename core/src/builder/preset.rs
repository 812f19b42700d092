//! Presets: the thesis's named heuristic pairs, and the state of the art, as ready builders.

use core::fmt;

use super::{BinSpace, BuildConfig, Builder, CutEvaluation, ThesisCut};
use crate::bvh::MAX_DEPTH;
use crate::heuristics::{
    AllAxes, AxisChooser, CostConstants, CostModel, LeafSize, LongestAxis, PahOrtho,
    PahPerspective, PerspectiveMeasure, Sah, SahTermination, Spfh, Termination,
};
use crate::influence::{InfluenceArea, PointArea};
use crate::BuildError;

/// A named builder. The thesis's four pairs plus binned SAH and binned PAH over all axes.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash)]
pub enum Preset {
    /// Binned SAH over all three axes: the real state of the art, and the fallback BVH.
    Sah,
    /// SAH + LSPH: the thesis's "standard".
    Standard,
    /// SAH + SPFH: the thesis's "facing".
    Facing,
    /// PAH + LSPH: the thesis's "longest".
    Longest,
    /// PAH + SPFH: the thesis's "full".
    Full,
    /// PAH over all three axes: `sah`'s builder (every axis binned, the cheapest cut of all,
    /// exhaustive small nodes) pricing with the area's PAH instead of SAH. Not one of the
    /// thesis's pairs: SPFH and LSPH save sweeps by trusting one axis, this prices all three, so
    /// its trees have the lowest PAH cost of the presets, for about the build time of `full`
    /// (measured: benches/RESULTS.md, section Heuristic quality (SAH/PAH cost of the presets)).
    Pah,
}

impl Preset {
    /// Every preset, in a fixed order.
    pub const ALL: [Preset; 6] = [
        Preset::Sah,
        Preset::Standard,
        Preset::Facing,
        Preset::Longest,
        Preset::Full,
        Preset::Pah,
    ];

    /// The preset's name: `sah`, `standard`, `facing`, `longest`, `full` or `pah`.
    pub fn name(self) -> &'static str {
        match self {
            Preset::Sah => "sah",
            Preset::Standard => "standard",
            Preset::Facing => "facing",
            Preset::Longest => "longest",
            Preset::Full => "full",
            Preset::Pah => "pah",
        }
    }

    /// The preset of a name (as [`Preset::name`] spells it, case-insensitive).
    pub fn from_name(name: &str) -> Option<Preset> {
        Preset::ALL
            .into_iter()
            .find(|p| p.name().eq_ignore_ascii_case(name))
    }

    /// The thesis's capitalised name for result rows (`Full`, `Longest`, `Facing`, `Standard`,
    /// and this project's `Sah` and `Pah`).
    pub fn thesis_name(self) -> &'static str {
        match self {
            Preset::Sah => "Sah",
            Preset::Standard => "Standard",
            Preset::Facing => "Facing",
            Preset::Longest => "Longest",
            Preset::Full => "Full",
            Preset::Pah => "Pah",
        }
    }

    /// True when the preset needs an influence area (it uses PAH or SPFH).
    pub fn needs_area(self) -> bool {
        matches!(
            self,
            Preset::Facing | Preset::Longest | Preset::Full | Preset::Pah
        )
    }

    /// True when the preset prices splits with PAH.
    pub fn uses_pah(self) -> bool {
        matches!(self, Preset::Longest | Preset::Full | Preset::Pah)
    }
}

impl fmt::Display for Preset {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        f.write_str(self.name())
    }
}

/// Settings shared by every preset.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct PresetOptions {
    /// Bins (candidate planes + 1) per axis.
    pub bins: u32,
    /// Largest leaf the termination rule may keep.
    pub max_leaf: u32,
    /// Cost constants.
    pub constants: CostConstants,
    /// How perspective PAH measures a projection (point areas).
    pub perspective: PerspectiveMeasure,
    /// Price a point area's splits by the perspective PAH's centre estimate
    /// ([`PahPerspective::estimated`]), an opt-in stand-in: about 1.3-1.5x an SAH build's time
    /// instead of 2x, for a PAH cost within about 1% of the exact build's on the bunny and Sponza;
    /// off by default. Reinsertion and cost reports keep the exact measure.
    pub perspective_estimate: bool,
    /// Reproduce the thesis's builder: candidate planes uniformly over the node box, leaves split
    /// down to `max_leaf` by size alone (no cost-based termination).
    pub thesis_mode: bool,
    /// The cut evaluation's thresholds; its quality threshold applies to SPFH presets, and
    /// [`ThesisCut::LSPH`]'s to LSPH ones unless changed in `lsph_quality_threshold`.
    pub cut: ThesisCut,
    /// The quality threshold for LSPH presets.
    pub lsph_quality_threshold: f32,
    /// Hard depth bound, at most [`crate::bvh::MAX_DEPTH`] (the thesis's `max_levels` is clamped
    /// to it).
    pub max_depth: u32,
}

impl Default for PresetOptions {
    /// This project's defaults: 16 centroid bins, SAH termination up to 8 triangles per leaf,
    /// `C_trav = C_isect = 1`, solid-angle perspective PAH, the thesis's cut thresholds.
    fn default() -> Self {
        Self {
            bins: 16,
            max_leaf: 8,
            constants: CostConstants::default(),
            perspective: PerspectiveMeasure::SolidAngle,
            perspective_estimate: false,
            thesis_mode: false,
            cut: ThesisCut::SPFH,
            lsph_quality_threshold: ThesisCut::LSPH.quality_threshold,
            max_depth: MAX_DEPTH,
        }
    }
}

impl PresetOptions {
    /// The thesis's settings (`experiments.toml`): 40 candidate planes over the node box, at most 2
    /// triangles per leaf with no cost-based termination, 1.0 per inner node counted twice and 1.2
    /// per triangle.
    pub fn thesis() -> Self {
        Self {
            bins: 41,
            max_leaf: 2,
            constants: CostConstants::THESIS,
            perspective: PerspectiveMeasure::SolidAngle,
            perspective_estimate: false,
            thesis_mode: true,
            cut: ThesisCut::SPFH,
            lsph_quality_threshold: ThesisCut::LSPH.quality_threshold,
            max_depth: MAX_DEPTH,
        }
    }

    /// The perspective PAH a build over point area `a` prices its splits with.
    fn perspective_pah(&self, a: &PointArea) -> PahPerspective {
        let exact = PahPerspective::for_area(a, self.perspective);
        if self.perspective_estimate {
            exact.estimated()
        } else {
            exact
        }
    }

    fn config(&self, cut: CutEvaluation) -> BuildConfig {
        BuildConfig {
            bins: self.bins,
            constants: self.constants,
            cut,
            bin_space: if self.thesis_mode {
                BinSpace::NodeBox
            } else {
                BinSpace::Centroids
            },
            max_depth: self.max_depth.min(MAX_DEPTH),
            ..BuildConfig::default()
        }
    }
}

/// Why a preset could not build.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum PresetError {
    /// The preset uses PAH or SPFH and no influence area was given.
    NeedsArea(Preset),
    /// The build itself failed.
    Build(BuildError),
}

impl fmt::Display for PresetError {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        match self {
            PresetError::NeedsArea(p) => write!(
                f,
                "preset `{p}` uses PAH or SPFH and needs an influence area"
            ),
            PresetError::Build(e) => e.fmt(f),
        }
    }
}

impl core::error::Error for PresetError {}

impl From<BuildError> for PresetError {
    fn from(e: BuildError) -> Self {
        PresetError::Build(e)
    }
}

impl Preset {
    /// Hands `visitor` the builder this preset names for `area` and `options`, statically
    /// dispatched: how [`super::BuildOptions`] runs a preset on one thread or on every thread,
    /// and how a caller runs one its own way, without a second copy of which chooser, cost
    /// model and termination each preset takes. `area` is required for `facing`, `longest`,
    /// `full` and `pah`.
    pub fn with_builder<V: PresetVisitor>(
        self,
        area: Option<&InfluenceArea>,
        options: &PresetOptions,
        visitor: V,
    ) -> Result<V::Output, PresetError> {
        let lsph = CutEvaluation::Thesis(ThesisCut {
            quality_threshold: options.lsph_quality_threshold,
            ..options.cut
        });
        let spfh = CutEvaluation::Thesis(options.cut);
        let area = match (self.needs_area(), area) {
            (true, None) => return Err(PresetError::NeedsArea(self)),
            (_, a) => a,
        };
        Ok(match (self, area) {
            (Preset::Sah, _) => run(
                AllAxes,
                Sah,
                options,
                options.config(CutEvaluation::BestOfAxes),
                visitor,
            ),
            (Preset::Standard, _) => run(LongestAxis, Sah, options, options.config(lsph), visitor),
            (Preset::Facing, Some(a)) => run(
                Spfh::for_area(a),
                Sah,
                options,
                options.config(spfh),
                visitor,
            ),
            (Preset::Longest, Some(InfluenceArea::Plane(a))) => run(
                LongestAxis,
                PahOrtho::for_area(a),
                options,
                options.config(lsph),
                visitor,
            ),
            (Preset::Longest, Some(InfluenceArea::Point(a))) => run(
                LongestAxis,
                options.perspective_pah(a),
                options,
                options.config(lsph),
                visitor,
            ),
            (Preset::Full, Some(area @ InfluenceArea::Plane(a))) => run(
                Spfh::for_area(area),
                PahOrtho::for_area(a),
                options,
                options.config(spfh),
                visitor,
            ),
            (Preset::Full, Some(area @ InfluenceArea::Point(a))) => run(
                Spfh::for_area(area),
                options.perspective_pah(a),
                options,
                options.config(spfh),
                visitor,
            ),
            (Preset::Pah, Some(InfluenceArea::Plane(a))) => run(
                AllAxes,
                PahOrtho::for_area(a),
                options,
                options.config(CutEvaluation::BestOfAxes),
                visitor,
            ),
            (Preset::Pah, Some(InfluenceArea::Point(a))) => run(
                AllAxes,
                options.perspective_pah(a),
                options,
                options.config(CutEvaluation::BestOfAxes),
                visitor,
            ),
            (_, None) => return Err(PresetError::NeedsArea(self)),
        })
    }
}

/// What to do with the builder a preset names: [`Preset::with_builder`] calls `visit` once with
/// it. The bounds hold for every preset's parts, so a visitor may share the builder across
/// threads.
pub trait PresetVisitor {
    /// What the visit returns.
    type Output;
    /// Runs the preset's builder.
    fn visit<A, C, T>(self, builder: Builder<A, C, T>) -> Self::Output
    where
        A: AxisChooser + Send + Sync,
        C: CostModel + Send + Sync,
        T: Termination + Send + Sync;
}

/// The builder of a (chooser, cost model) pair with the options' termination rule, handed to
/// `visitor`: one monomorphised build per pair.
fn run<A, C, V>(
    axes: A,
    cost: C,
    options: &PresetOptions,
    config: BuildConfig,
    visitor: V,
) -> V::Output
where
    A: AxisChooser + Send + Sync,
    C: CostModel + Send + Sync,
    V: PresetVisitor,
{
    if options.thesis_mode {
        let stop = LeafSize {
            max_leaf: options.max_leaf,
        };
        visitor.visit(Builder::new(axes, cost, stop, config))
    } else {
        let stop = SahTermination {
            max_leaf: options.max_leaf,
        };
        visitor.visit(Builder::new(axes, cost, stop, config))
    }
}

#[cfg(test)]
mod tests {
    use alloc::vec::Vec;

    use glam::Vec3;

    use super::*;
    use crate::brute_force;
    use crate::builder::{BuildArena, BuildOptions};
    use crate::bvh::Bvh;
    use crate::geometry::Triangle;
    use crate::heuristics::AreaPah;
    use crate::influence::{PlaneArea, PointArea, RaySampler};

    fn soup(n: usize) -> Vec<Triangle> {
        crate::test_scenes::soup(n, 1, 0.0, 10.0, 1.0)
    }

    #[test]
    fn every_preset_on_both_area_kinds_agrees_with_brute_force() {
        let tris = soup(400);
        let areas: [InfluenceArea; 2] = [
            PlaneArea::new(
                Vec3::new(3.5, 5.0, -4.0),
                Vec3::new(0.259, 0.0, 0.966),
                6.5,
                5.0,
                20.0,
            )
            .unwrap()
            .into(),
            PointArea::new(
                Vec3::new(10.0, 12.0, -3.0),
                Vec3::new(-0.55, -0.9, 1.0),
                60.0,
                60.0,
                1.0,
                20.0,
            )
            .unwrap()
            .into(),
        ];
        for options in [PresetOptions::default(), PresetOptions::thesis()] {
            for area in &areas {
                for preset in Preset::ALL {
                    let mut arena = BuildArena::with_capacity(tris.len());
                    arena.load_triangles(&tris).unwrap();
                    let mut bvh = Bvh::with_capacity(tris.len());
                    BuildOptions::with_settings(preset, options)
                        .build_into(&mut arena, Some(area), &mut bvh)
                        .unwrap();
                    bvh.validate(tris.len(), |i| tris[i as usize].bounds())
                        .unwrap();
                    if options.thesis_mode {
                        assert!(bvh.nodes().iter().all(|n| n.count <= 2), "{preset}");
                    }
                    let mut rays = RaySampler::new(*area, 3);
                    for _ in 0..200 {
                        let r = rays.sample();
                        assert_eq!(
                            bvh.closest_hit(&r, &tris),
                            brute_force::closest_hit(&r, &tris)
                        );
                    }
                }
            }
        }
    }

    /// `pah` is `sah`'s builder with the area's PAH as its cost model, nothing else: the same
    /// tree as assembling that builder by hand, for both kinds of area.
    #[test]
    fn pah_is_the_sah_builder_pricing_with_the_areas_pah() {
        let tris = soup(600);
        let plane = PlaneArea::new(Vec3::new(5.0, 12.0, 5.0), -Vec3::Y, 6.0, 6.0, 20.0).unwrap();
        let point =
            PointArea::new(Vec3::new(5.0, 15.0, 5.0), -Vec3::Y, 70.0, 70.0, 0.5, 30.0).unwrap();
        let o = PresetOptions::default();
        let config = o.config(CutEvaluation::BestOfAxes);
        let stop = SahTermination {
            max_leaf: o.max_leaf,
        };
        let by_hand = [
            Builder::new(AllAxes, PahOrtho::for_area(&plane), stop, config).build(&tris),
            Builder::new(
                AllAxes,
                PahPerspective::for_area(&point, o.perspective),
                stop,
                config,
            )
            .build(&tris),
        ];
        let sah = Builder::new(AllAxes, Sah, stop, config)
            .build(&tris)
            .unwrap();
        for (area, expected) in [InfluenceArea::from(plane), point.into()]
            .iter()
            .zip(by_hand)
        {
            let mut arena = BuildArena::with_capacity(tris.len());
            arena.load_triangles(&tris).unwrap();
            let mut bvh = Bvh::with_capacity(tris.len());
            BuildOptions::with_settings(Preset::Pah, o)
                .build_into(&mut arena, Some(area), &mut bvh)
                .unwrap();
            assert_eq!(bvh, expected.unwrap());
            // And the model changed the tree: it is not `sah`'s.
            assert_ne!(bvh, sah);
        }
        assert_eq!(
            BuildOptions::with_settings(Preset::Pah, o).build_into(
                &mut BuildArena::with_capacity(1),
                None,
                &mut Bvh::default()
            ),
            Err(PresetError::NeedsArea(Preset::Pah))
        );
    }

    /// PAH's estimate of a built tree equals the all-hit cost of the rays it models.
    #[test]
    fn pah_estimate_matches_measured_all_hit_cost() {
        let tris = soup(2000);
        let areas: [InfluenceArea; 2] = [
            PlaneArea::new(
                Vec3::new(3.5, 5.0, -4.0),
                Vec3::new(0.259, 0.0, 0.966),
                6.5,
                5.0,
                20.0,
            )
            .unwrap()
            .into(),
            PointArea::new(
                Vec3::new(5.0, 5.0, -4.0),
                Vec3::new(0.1, 0.05, 1.0),
                130.0,
                100.0,
                1.0,
                40.0,
            )
            .unwrap()
            .into(),
        ];
        for area in &areas {
            let inside: Vec<u32> = (0..tris.len() as u32)
                .filter(|&i| area.overlaps_triangle(&tris[i as usize]))
                .collect();
            let mut arena = BuildArena::with_capacity(tris.len());
            arena
                .load_triangle_subset(&tris, inside.iter().copied())
                .unwrap();
            let mut bvh = Bvh::with_capacity(tris.len());
            let o = PresetOptions::thesis();
            BuildOptions::with_settings(Preset::Full, o)
                .build_into(&mut arena, Some(area), &mut bvh)
                .unwrap();
            let pah = AreaPah::new(area, o.perspective);
            let estimate = bvh.estimated_cost_over(&pah, o.constants, pah.window_measure());
            let mut rays = RaySampler::new(*area, 17)
                .distribution(crate::influence::PointDistribution::SolidAngle);
            let n = 100_000;
            let measured: f64 = (0..n)
                .map(|_| f64::from(bvh.all_hit(&rays.sample(), &tris).cost(o.constants)))
                .sum::<f64>()
                / f64::from(n);
            let err = (f64::from(estimate) - measured).abs() / measured;
            assert!(
                err < 0.02,
                "{area:?}: estimate {estimate}, measured {measured}, error {err}"
            );
        }
    }

    #[test]
    fn presets_needing_an_area_say_so() {
        let mut arena = BuildArena::with_capacity(4);
        arena.load_triangles(&soup(4)).unwrap();
        let mut bvh = Bvh::default();
        let o = PresetOptions::default();
        assert_eq!(
            BuildOptions::with_settings(Preset::Full, o).build_into(&mut arena, None, &mut bvh),
            Err(PresetError::NeedsArea(Preset::Full))
        );
        assert!(BuildOptions::with_settings(Preset::Standard, o)
            .build_into(&mut arena, None, &mut bvh)
            .is_ok());
        assert_eq!(Preset::from_name("FULL"), Some(Preset::Full));
        assert_eq!(Preset::from_name("nope"), None);
    }
}
