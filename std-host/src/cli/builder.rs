//! The builder options shared by every command that builds a BVH, and the timed build itself.

use std::time::Instant;

use clap::builder::PossibleValue;
use clap::{value_parser, Args, ValueEnum};
use rdbvh_core::builder::{
    parallel, reinsert, BuildArena, BuildConfig, BuildOptions, Builder, Preset, PresetOptions,
    ReinsertConfig, ReinsertStats, SpatialBuilder, SpatialSplits, MAX_BINS,
};
use rdbvh_core::bvh::Bvh;
use rdbvh_core::geometry::Triangle;
use rdbvh_core::heuristics::{AxisChooser, Sah, SahTermination};
use rdbvh_core::influence::InfluenceArea;
use rdbvh_core::BuildError;
use serde::Serialize;

use super::error::CliError;

/// Which split axes the binned SAH builder tries.
#[derive(Clone, Copy, Debug, PartialEq, Eq, ValueEnum, Serialize)]
#[serde(rename_all = "lowercase")]
pub enum BuilderKind {
    /// All three axes, keeping the cheapest split: the usual binned SAH builder.
    Sah,
    /// The longest axis only (LSPH): the thesis's "standard" builder.
    Lsph,
    /// All three axes with spatial splits (SBVH, Stich et al. 2009): a node may also be cut
    /// through its triangles, a straddling triangle going to both sides clipped, up to half as
    /// many references again. Lower SAH cost on scenes of long triangles; builds on one thread.
    Sbvh,
}

impl BuilderKind {
    /// The name used on the command line and in reports.
    pub fn name(self) -> &'static str {
        match self {
            BuilderKind::Sah => "sah",
            BuilderKind::Lsph => "lsph",
            BuilderKind::Sbvh => "sbvh",
        }
    }
}

/// A preset name on the command line: `sah`, `standard`, `facing`, `longest`, `full` or `pah`.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct PresetArg(pub Preset);

impl ValueEnum for PresetArg {
    fn value_variants<'a>() -> &'a [Self] {
        &[
            PresetArg(Preset::Sah),
            PresetArg(Preset::Standard),
            PresetArg(Preset::Facing),
            PresetArg(Preset::Longest),
            PresetArg(Preset::Full),
            PresetArg(Preset::Pah),
        ]
    }

    fn to_possible_value(&self) -> Option<PossibleValue> {
        let help = match self.0 {
            Preset::Sah => "binned SAH over all three axes (no area needed)",
            Preset::Standard => {
                "SAH + longest axis (LSPH) with the thesis's cut rule, the thesis's standard \
                 (no area needed)"
            }
            Preset::Facing => "SAH + splitting plane facing (SPFH); needs --areas",
            Preset::Longest => "PAH + LSPH; needs --areas",
            Preset::Full => "PAH + SPFH, the thesis's full method; needs --areas",
            Preset::Pah => "PAH with sah's builder (all three axes priced); needs --areas",
        };
        Some(PossibleValue::new(self.0.name()).help(help))
    }
}

/// The name of the axis chooser a preset uses, as the `builder` report key spells it.
pub fn chooser_name(preset: Preset) -> &'static str {
    match preset {
        Preset::Sah | Preset::Pah => "sah",
        Preset::Standard | Preset::Longest => "lsph",
        Preset::Facing | Preset::Full => "spfh",
    }
}

/// How to build the BVH: either `--builder` (the plain binned SAH builders) or `--preset` (the
/// thesis's named heuristic pairs, built by `rdbvh-core`'s presets), not both.
#[derive(Args, Clone, Copy, Debug, Default, PartialEq, Eq)]
pub struct BuilderArgs {
    /// The plain SAH builder: `sah` tries all three axes, `lsph` only the longest one, `sbvh`
    /// all three with spatial splits [default: sah].
    #[arg(long, value_enum, conflicts_with = "preset")]
    pub builder: Option<BuilderKind>,
    /// Build with a named preset instead of --builder.
    #[arg(long, value_name = "NAME")]
    pub preset: Option<PresetArg>,
    /// Build as the thesis did (presets only, including trace's local BVHs): candidate planes
    /// uniform over the node box, 41 bins, leaves split down to 2 triangles by size alone.
    #[arg(long, conflicts_with = "builder")]
    pub thesis_mode: bool,
    /// Centroid bins per axis; each bin boundary is a candidate split plane
    /// [default: 16, or 41 with --thesis-mode].
    #[arg(long, value_name = "N",
          value_parser = value_parser!(u32).range(2..=i64::from(MAX_BINS)))]
    pub bins: Option<u32>,
    /// Largest leaf the termination may keep (with --thesis-mode: the leaf size it splits down
    /// to) [default: 8, or 2 with --thesis-mode].
    #[arg(long, value_name = "N", value_parser = value_parser!(u32).range(1..))]
    pub max_leaf: Option<u32>,
    /// Improve the built tree by reinsertion (Bittner et al. 2013): move the largest subtrees to
    /// where they cost least, under SAH (under the area's PAH for the PAH presets; with --areas,
    /// every local BVH and the fallback). Same leaves, never a higher cost; Crytek Sponza's SAH
    /// cost falls 17% and its rays trace about 1.2x faster, for about half the build's time more.
    #[arg(long)]
    pub reinsert: bool,
    /// With a point area (PAH presets): price splits by the perspective PAH's centre estimate
    /// (each face turned towards the light at its own distance, expanded about the box's
    /// centre) instead of the exact solid angle: about 1.3-1.5x the SAH build's time instead of
    /// 2x, for a PAH cost within a few percent of the exact build's (reported costs stay exact).
    #[arg(long)]
    pub perspective_estimate: bool,
}

/// A BVH with what its build reported and how long it took.
#[derive(Clone, Debug)]
pub struct BuiltBvh {
    /// The BVH.
    pub bvh: Bvh,
    /// Wall-clock seconds of loading the arena and building on every thread. The arena is sized
    /// first, as a renderer that rebuilds every frame would keep it; the threaded build
    /// allocates its tree and its jobs' arenas as it goes.
    pub seconds: f64,
    /// With --reinsert: what reinsertion did, and its wall-clock seconds (not in `seconds`).
    pub reinsert: Option<(ReinsertStats, f64)>,
}

impl BuiltBvh {
    /// Millions of triangles per second of build time.
    pub fn mtris_per_s(&self, triangles: usize) -> f64 {
        triangles as f64 / self.seconds.max(1e-9) / 1e6
    }
}

impl BuilderArgs {
    /// Plain binned SAH over `kind`'s axes with default settings.
    pub fn plain(kind: BuilderKind) -> Self {
        Self {
            builder: Some(kind),
            ..Self::default()
        }
    }

    /// The preset `preset` with default settings.
    pub fn with_preset(preset: Preset) -> Self {
        Self {
            preset: Some(PresetArg(preset)),
            ..Self::default()
        }
    }

    /// The chosen preset, if --preset was given.
    pub fn preset(&self) -> Option<Preset> {
        self.preset.map(|p| p.0)
    }

    /// The plain builder's kind (sah unless --builder said otherwise).
    pub fn kind(&self) -> BuilderKind {
        self.builder.unwrap_or(BuilderKind::Sah)
    }

    /// The name of the split-axis chooser: `sah`, `lsph` or `spfh`.
    pub fn chooser_name(&self) -> &'static str {
        match self.preset() {
            Some(p) => chooser_name(p),
            None => self.kind().name(),
        }
    }

    /// The preset settings: the project's defaults or the thesis's, then --bins and --max-leaf.
    pub fn preset_options(&self) -> PresetOptions {
        let mut o = if self.thesis_mode {
            PresetOptions::thesis()
        } else {
            PresetOptions::default()
        };
        if let Some(bins) = self.bins {
            o.bins = bins;
        }
        if let Some(max_leaf) = self.max_leaf {
            o.max_leaf = max_leaf;
        }
        o.perspective_estimate = self.perspective_estimate;
        o
    }

    /// Bins per axis of the build.
    pub fn bins(&self) -> u32 {
        match self.preset() {
            Some(_) => self.preset_options().bins,
            None => self.bins.unwrap_or(BuildConfig::default().bins),
        }
    }

    /// The largest leaf of the build.
    pub fn max_leaf(&self) -> u32 {
        match self.preset() {
            Some(_) => self.preset_options().max_leaf,
            None => self.max_leaf.unwrap_or(SahTermination::default().max_leaf),
        }
    }

    /// A usage error when the preset needs an influence area and `has_area` is false, or when
    /// --thesis-mode or --perspective-estimate has no preset to apply to, so the command can say
    /// so before loading anything.
    pub fn check_area(&self, has_area: bool) -> Result<(), CliError> {
        if self.thesis_mode && self.preset().is_none() {
            return Err(CliError::Usage(
                "--thesis-mode applies to presets: give --preset NAME".into(),
            ));
        }
        if self.perspective_estimate && self.preset().is_none() {
            return Err(CliError::Usage(
                "--perspective-estimate applies to the PAH presets over a point area: give \
                 --preset NAME and --areas AREAS.toml"
                    .into(),
            ));
        }
        match self.preset() {
            Some(p) if p.needs_area() && !has_area => Err(CliError::Usage(format!(
                "preset `{p}` uses PAH or SPFH, which need the rays' influence area: give \
                 --areas AREAS.toml (or use --preset sah or standard)"
            ))),
            _ => Ok(()),
        }
    }

    /// Builds a BVH over all `triangles` on every thread (the single-threaded build's tree).
    pub fn build(&self, triangles: &[Triangle]) -> Result<BuiltBvh, CliError> {
        self.build_over(triangles, None, None)
    }

    /// Builds a BVH over all `triangles` that is only to be traced through its 4-wide collapse
    /// (`WideBvh::from_binary`). Without --reinsert the builder is made `for_wide`: the same wide
    /// nodes, and nodes of at most four triangles left unsplit (about a fifth of the build's
    /// work). With --reinsert the full tree is built, as reinsertion improves its collapse more.
    pub fn build_for_wide(&self, triangles: &[Triangle]) -> Result<BuiltBvh, CliError> {
        self.build_with(triangles, None, None, !self.reinsert)
    }

    /// Builds a BVH over the triangles of `triangles` whose ids `subset` lists (all when
    /// `None`), for the influence area `area` when the preset needs one, on every thread of the
    /// current rayon pool ([`rdbvh_core::builder::parallel`]: the single-threaded build's tree, node
    /// for node).
    pub fn build_over(
        &self,
        triangles: &[Triangle],
        subset: Option<&[u32]>,
        area: Option<&InfluenceArea>,
    ) -> Result<BuiltBvh, CliError> {
        self.build_with(triangles, subset, area, false)
    }

    /// [`BuilderArgs::build_over`], with the builder made `for_wide` when `for_wide` is true.
    fn build_with(
        &self,
        triangles: &[Triangle],
        subset: Option<&[u32]>,
        area: Option<&InfluenceArea>,
        for_wide: bool,
    ) -> Result<BuiltBvh, CliError> {
        self.check_area(area.is_some())?;
        parallel::start_pool();
        let start = Instant::now();
        let mut bvh = match (self.preset(), self.kind()) {
            // The SBVH keeps its references in its own buffer, not an arena.
            (None, BuilderKind::Sbvh) => {
                let builder = SpatialBuilder::new(self.spatial_splits());
                match subset {
                    Some(ids) => builder.build_subset(triangles, ids)?,
                    None => builder.build(triangles)?,
                }
            }
            (preset, kind) => {
                let n = subset.map_or(triangles.len(), <[u32]>::len);
                let mut arena = BuildArena::with_capacity(n);
                match subset {
                    Some(ids) => arena.load_triangle_subset(triangles, ids.iter().copied())?,
                    None => parallel::load_triangles(&mut arena, triangles)?,
                }
                match preset {
                    Some(p) => BuildOptions {
                        for_wide,
                        parallel: true,
                        ..BuildOptions::with_settings(p, self.preset_options())
                    }
                    .build_loaded(&mut arena, area)?,
                    // Only the bins and the leaf size change: each builder keeps the rest of its
                    // own configuration (LSPH evaluates its first axis only, which a default
                    // config would undo).
                    None if kind == BuilderKind::Lsph => {
                        build_plain(self.apply(Builder::lsph()), &mut arena, for_wide)?
                    }
                    None => build_plain(self.apply(Builder::sah()), &mut arena, for_wide)?,
                }
            }
        };
        let seconds = start.elapsed().as_secs_f64();
        let reinsert = self.reinsert.then(|| {
            let start = Instant::now();
            let config = ReinsertConfig::default();
            let stats = match self.preset() {
                Some(p) => BuildOptions::with_settings(p, self.preset_options())
                    .reinsert_with(area, &mut bvh, &config),
                None => reinsert(&mut bvh, &Sah, &config),
            };
            (stats, start.elapsed().as_secs_f64())
        });
        Ok(BuiltBvh {
            bvh,
            seconds,
            reinsert,
        })
    }

    /// The SBVH settings: the defaults with --bins (object and spatial bins) and --max-leaf.
    fn spatial_splits(&self) -> SpatialSplits {
        let mut splits = SpatialSplits::default();
        if let Some(bins) = self.bins {
            (splits.object_bins, splits.spatial_bins) = (bins, bins);
        }
        splits.max_leaf = self.max_leaf();
        splits
    }

    fn apply<A: AxisChooser>(
        &self,
        mut b: Builder<A, Sah, SahTermination>,
    ) -> Builder<A, Sah, SahTermination> {
        b.config.bins = self.bins();
        b.termination.max_leaf = self.max_leaf();
        b
    }
}

/// Builds with a plain SAH builder on every thread, made [`Builder::for_wide`] when `for_wide`.
fn build_plain<A: AxisChooser + Sync>(
    builder: Builder<A, Sah, SahTermination>,
    arena: &mut BuildArena,
    for_wide: bool,
) -> Result<Bvh, BuildError> {
    if for_wide {
        parallel::build_loaded(&builder.for_wide(), arena)
    } else {
        parallel::build_loaded(&builder, arena)
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use rdbvh_core::bvh::WideBvh;
    use rdbvh_core::influence::PlaneArea;
    use rdbvh_core::Vec3;

    fn row(n: usize) -> Vec<Triangle> {
        (0..n)
            .map(|i| {
                let o = Vec3::new(i as f32, (i % 7) as f32, (i % 3) as f32);
                Triangle::new(o, o + Vec3::X, o + Vec3::Y)
            })
            .collect()
    }

    /// `trace`'s build collapses to the wide tree of the full build: a `for_wide` build without
    /// --reinsert (the same wide nodes, fewer binary ones), the full build with it.
    #[test]
    fn the_build_for_wide_collapses_as_the_full_build() {
        let mut tris = row(300);
        tris.extend(
            row(40)
                .iter()
                .map(|t| Triangle::new(t.v0, t.v1 * 3.0, t.v2 + Vec3::Z)),
        );
        let cases = [
            BuilderArgs::default(),
            BuilderArgs {
                builder: Some(BuilderKind::Lsph),
                max_leaf: Some(2),
                ..BuilderArgs::default()
            },
            BuilderArgs {
                preset: Some(PresetArg(Preset::Standard)),
                thesis_mode: true,
                ..BuilderArgs::default()
            },
            BuilderArgs {
                reinsert: true,
                ..BuilderArgs::default()
            },
        ];
        for args in cases {
            let (full, for_wide) = (
                args.build(&tris).unwrap(),
                args.build_for_wide(&tris).unwrap(),
            );
            let wide = |b: &BuiltBvh| WideBvh::from_binary(&b.bvh, &tris);
            assert_eq!(wide(&full).nodes(), wide(&for_wide).nodes(), "{args:?}");
            let smaller = for_wide.bvh.nodes().len() < full.bvh.nodes().len();
            assert_eq!(smaller, !args.reinsert, "{args:?}");
        }
    }

    #[test]
    fn both_builders_cover_every_triangle() {
        let tris = row(100);
        for builder in [BuilderKind::Sah, BuilderKind::Lsph] {
            let args = BuilderArgs {
                builder: Some(builder),
                max_leaf: Some(2),
                ..BuilderArgs::default()
            };
            let built = args.build(&tris).unwrap();
            built
                .bvh
                .validate(tris.len(), |id| tris[id as usize].bounds())
                .unwrap();
            // Built on every thread, the single-threaded builder's tree.
            let serial = match builder {
                BuilderKind::Sah => args.apply(Builder::sah()).build(&tris),
                BuilderKind::Lsph => args.apply(Builder::lsph()).build(&tris),
                BuilderKind::Sbvh => unreachable!("only the binned builders are listed"),
            };
            assert_eq!(built.bvh, serial.unwrap());
            assert!(built.bvh.nodes().iter().all(|n| n.count <= 2));
        }
    }

    /// `--builder sbvh` splits the long triangles of a scene, over all of it or a subset, and
    /// its trees answer as the plain build's do.
    #[test]
    fn sbvh_splits_long_triangles_and_answers_the_same() {
        let mut tris = row(200);
        tris.extend((0..20).map(|i| {
            let o = Vec3::new(0.0, i as f32 * 0.3, 0.5);
            Triangle::new(
                o,
                o + Vec3::new(200.0, 3.0, 2.0),
                o + Vec3::new(200.0, 3.2, 2.0),
            )
        }));
        let args = BuilderArgs::plain(BuilderKind::Sbvh);
        let sbvh = args.build(&tris).unwrap().bvh;
        sbvh.validate_split(tris.len(), |id| tris[id as usize].bounds())
            .unwrap();
        assert!(sbvh.prim_indices().len() > tris.len());
        let ids: Vec<u32> = (100..tris.len() as u32).collect();
        let subset = args.build_over(&tris, Some(&ids), None).unwrap().bvh;
        assert!(subset.prim_indices().iter().all(|&i| i >= 100));
        let plain = BuilderArgs::default().build(&tris).unwrap().bvh;
        for i in 0..200 {
            let o = Vec3::new(i as f32 + 0.3, (i % 7) as f32 + 0.2, -1.0);
            let ray = rdbvh_core::geometry::Ray::new(o, Vec3::new(0.01, 0.02, 1.0)).unwrap();
            assert_eq!(
                sbvh.closest_hit(&ray, &tris),
                plain.closest_hit(&ray, &tris)
            );
        }
    }

    #[test]
    fn lsph_keeps_its_own_cut_evaluation() {
        let args = BuilderArgs {
            builder: Some(BuilderKind::Lsph),
            bins: Some(8),
            max_leaf: Some(3),
            ..BuilderArgs::default()
        };
        let b = args.apply(Builder::lsph());
        assert_eq!(b.config.cut, Builder::lsph().config.cut);
        assert_eq!((b.config.bins, b.termination.max_leaf), (8, 3));
        // And the two builders really differ on a scene where the longest axis is a poor choice.
        let tris = crate::scene::thesis_random_triangles(0, 1000);
        let sah = BuilderArgs::default().build(&tris).unwrap().bvh;
        let lsph = BuilderArgs::plain(BuilderKind::Lsph)
            .build(&tris)
            .unwrap()
            .bvh;
        assert_ne!(sah.nodes(), lsph.nodes());
    }

    #[test]
    fn presets_build_subsets_and_thesis_mode_is_overridable() {
        let tris = row(200);
        let area: InfluenceArea =
            PlaneArea::new(Vec3::new(50.0, 3.0, -1.0), Vec3::Z, 20.0, 5.0, 5.0)
                .unwrap()
                .into();
        let ids: Vec<u32> = (0..200u32)
            .filter(|&i| area.overlaps_triangle(&tris[i as usize]))
            .collect();
        assert!(ids.len() > 10 && ids.len() < 100, "{}", ids.len());
        for preset in Preset::ALL {
            let mut args = BuilderArgs::with_preset(preset);
            args.thesis_mode = true;
            let built = args.build_over(&tris, Some(&ids), Some(&area)).unwrap();
            let mut leaves: Vec<u32> = built.bvh.prim_indices().to_vec();
            leaves.sort_unstable();
            assert_eq!(leaves, ids, "{preset}: exactly the subset");
            assert!(built.bvh.nodes().iter().all(|n| n.count <= 2), "{preset}");
        }
        let thesis = BuilderArgs {
            thesis_mode: true,
            max_leaf: Some(5),
            ..BuilderArgs::with_preset(Preset::Full)
        };
        let o = thesis.preset_options();
        assert!(o.thesis_mode);
        assert_eq!((o.bins, o.max_leaf), (PresetOptions::thesis().bins, 5));
        assert_eq!((thesis.bins(), thesis.max_leaf()), (o.bins, 5));
        assert_eq!(thesis.chooser_name(), "spfh");
        let d = BuilderArgs::default();
        assert_eq!((d.bins(), d.max_leaf(), d.chooser_name()), (16, 8, "sah"));
    }

    #[test]
    fn presets_that_need_an_area_say_so_before_building() {
        let tris = row(10);
        for preset in Preset::ALL {
            let args = BuilderArgs::with_preset(preset);
            match args.build(&tris) {
                Ok(_) => assert!(!preset.needs_area(), "{preset}"),
                Err(CliError::Usage(why)) => {
                    assert!(preset.needs_area(), "{preset}");
                    assert!(
                        why.contains("--areas") && why.contains(preset.name()),
                        "{why}"
                    );
                }
                Err(e) => panic!("{preset}: {e}"),
            }
        }
    }
}
