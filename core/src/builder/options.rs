//! One way to build: a [`BuildOptions`] (a preset, its settings, what the tree is for, reinsertion
//! and threads) handed to one of three calls that differ only in who owns the memory.

use super::{
    reinsert, BuildArena, BuildStats, Builder, Clock, NoClock, Preset, PresetError, PresetOptions,
    PresetVisitor, ReinsertConfig, ReinsertStats,
};
use crate::bvh::Bvh;
use crate::geometry::Triangle;
use crate::heuristics::{AreaPah, AxisChooser, CostModel, Sah, Termination};
use crate::influence::InfluenceArea;
use crate::BuildError;

/// How to build a BVH.
///
/// - [`BuildOptions::build`]: from triangles, allocating what it needs;
/// - [`BuildOptions::build_loaded`]: from a [`BuildArena`] the caller loaded (a subset of the
///   scene, say);
/// - [`BuildOptions::build_into`]: into the caller's arena and tree, on the calling thread, with
///   no allocation when both were sized up front: the `no_std` renderer's path.
///
/// Each gives the same tree for the same options, threaded or not.
///
/// ```
/// use rdbvh_core::builder::{BuildOptions, Preset};
/// use rdbvh_core::geometry::{Ray, Triangle};
/// use rdbvh_core::Vec3;
///
/// let tris: Vec<Triangle> = (0..64)
///     .map(|i| {
///         let o = Vec3::new((i % 8) as f32, (i / 8) as f32, 3.0);
///         Triangle::new(o, o + Vec3::X * 0.9, o + Vec3::Y * 0.9)
///     })
///     .collect();
/// let options = BuildOptions {
///     reinsert: Some(Default::default()),
///     ..BuildOptions::new(Preset::Sah)
/// };
/// let bvh = options.build(&tris, None)?;
/// let ray = Ray::new(Vec3::new(2.2, 3.2, 0.0), Vec3::Z)?;
/// assert_eq!(bvh.closest_hit(&ray, &tris).map(|h| h.triangle), Some(26));
/// # Ok::<(), Box<dyn std::error::Error>>(())
/// ```
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct BuildOptions {
    /// Which chooser, cost model and termination rule build the tree. PAH and SPFH presets need
    /// the influence area the build is given.
    pub preset: Preset,
    /// Bins, leaf size, cost constants and the thesis's settings.
    pub settings: PresetOptions,
    /// The tree is only to be collapsed to 4-wide nodes ([`crate::bvh::WideBvh::from_binary`]):
    /// nodes of at most four primitives stay leaves ([`Builder::for_wide`]), the same wide tree
    /// for about a fifth less build work.
    pub for_wide: bool,
    /// Improve the built tree by reinsertion under the preset's own model (the area's PAH for the
    /// PAH presets, SAH for the others), or not. Reinsertion allocates its scratch.
    pub reinsert: Option<ReinsertConfig>,
    /// Build on every thread of the current rayon pool. Needs the crate's `rayon` feature; without
    /// it, or in [`BuildOptions::build_into`], the build runs on the calling thread. The tree is
    /// the same either way.
    pub parallel: bool,
}

impl Default for BuildOptions {
    /// Binned SAH with the project's settings, on one thread, no reinsertion.
    fn default() -> Self {
        Self::new(Preset::Sah)
    }
}

impl BuildOptions {
    /// `preset` with the project's default settings, on one thread, no reinsertion.
    pub fn new(preset: Preset) -> Self {
        Self {
            preset,
            settings: PresetOptions::default(),
            for_wide: false,
            reinsert: None,
            parallel: false,
        }
    }

    /// `preset` with `settings`, on one thread, no reinsertion.
    pub fn with_settings(preset: Preset, settings: PresetOptions) -> Self {
        Self {
            settings,
            ..Self::new(preset)
        }
    }

    /// `preset` with the thesis's settings ([`PresetOptions::thesis`]).
    pub fn thesis(preset: Preset) -> Self {
        Self {
            settings: PresetOptions::thesis(),
            ..Self::new(preset)
        }
    }

    /// Builds over `tris` (triangle `i` gets id `i`), for `area` when the preset needs one.
    pub fn build(
        &self,
        tris: &[Triangle],
        area: Option<&InfluenceArea>,
    ) -> Result<Bvh, PresetError> {
        let mut arena = BuildArena::with_capacity(tris.len());
        #[cfg(feature = "rayon")]
        if self.parallel {
            super::parallel::load_triangles(&mut arena, tris)?;
            return self.build_loaded(&mut arena, area);
        }
        arena.load_triangles(tris)?;
        self.build_loaded(&mut arena, area)
    }

    /// Builds over the primitives loaded in `arena`, for `area` when the preset needs one.
    pub fn build_loaded(
        &self,
        arena: &mut BuildArena,
        area: Option<&InfluenceArea>,
    ) -> Result<Bvh, PresetError> {
        #[cfg(feature = "rayon")]
        if self.parallel {
            let threaded = Threaded {
                arena,
                for_wide: self.for_wide,
            };
            let mut bvh = self.preset.with_builder(area, &self.settings, threaded)??;
            self.improve(area, &mut bvh);
            return Ok(bvh);
        }
        let mut bvh = Bvh::with_capacity(arena.len());
        self.build_into(arena, area, &mut bvh)?;
        Ok(bvh)
    }

    /// Builds over the primitives loaded in `arena` into `out` (its content replaced), on the
    /// calling thread. Allocates nothing when `out` was made with [`Bvh::with_capacity`] for at
    /// least as many primitives and [`BuildOptions::reinsert`] is `None`.
    pub fn build_into(
        &self,
        arena: &mut BuildArena,
        area: Option<&InfluenceArea>,
        out: &mut Bvh,
    ) -> Result<BuildStats, PresetError> {
        self.build_into_profiled(arena, area, out, &NoClock)
    }

    /// [`BuildOptions::build_into`], timing the build's phases with `clock` into
    /// [`BuildStats::profile`] (reinsertion is not timed).
    pub fn build_into_profiled(
        &self,
        arena: &mut BuildArena,
        area: Option<&InfluenceArea>,
        out: &mut Bvh,
        clock: &impl Clock,
    ) -> Result<BuildStats, PresetError> {
        let into = IntoArena {
            arena,
            out: &mut *out,
            clock,
            for_wide: self.for_wide,
        };
        let stats = self.preset.with_builder(area, &self.settings, into)??;
        self.improve(area, out);
        Ok(stats)
    }

    /// Improves `bvh`, built with these options for `area`, by reinsertion under the preset's own
    /// model (as [`BuildOptions::reinsert`] does after a build), with `config`.
    pub fn reinsert_with(
        &self,
        area: Option<&InfluenceArea>,
        bvh: &mut Bvh,
        config: &ReinsertConfig,
    ) -> ReinsertStats {
        match area {
            Some(a) if self.preset.uses_pah() => {
                reinsert(bvh, &AreaPah::new(a, self.settings.perspective), config)
            }
            _ => reinsert(bvh, &Sah, config),
        }
    }

    /// Applies [`BuildOptions::reinsert`], if set.
    fn improve(&self, area: Option<&InfluenceArea>, bvh: &mut Bvh) {
        if let Some(config) = &self.reinsert {
            self.reinsert_with(area, bvh, config);
        }
    }
}

/// Builds a preset's builder into the caller's arena and tree, on the calling thread.
struct IntoArena<'a, K> {
    arena: &'a mut BuildArena,
    out: &'a mut Bvh,
    clock: &'a K,
    for_wide: bool,
}

impl<K: Clock> PresetVisitor for IntoArena<'_, K> {
    type Output = Result<BuildStats, BuildError>;
    fn visit<A, C, T>(self, builder: Builder<A, C, T>) -> Self::Output
    where
        A: AxisChooser + Send + Sync,
        C: CostModel + Send + Sync,
        T: Termination + Send + Sync,
    {
        if self.for_wide {
            builder
                .for_wide()
                .build_into_profiled(self.arena, self.out, self.clock)
        } else {
            builder.build_into_profiled(self.arena, self.out, self.clock)
        }
    }
}

/// Builds a preset's builder on every thread of the current rayon pool.
#[cfg(feature = "rayon")]
struct Threaded<'a> {
    arena: &'a mut BuildArena,
    for_wide: bool,
}

#[cfg(feature = "rayon")]
impl PresetVisitor for Threaded<'_> {
    type Output = Result<Bvh, BuildError>;
    fn visit<A, C, T>(self, builder: Builder<A, C, T>) -> Self::Output
    where
        A: AxisChooser + Send + Sync,
        C: CostModel + Send + Sync,
        T: Termination + Send + Sync,
    {
        if self.for_wide {
            super::parallel::build_loaded(&builder.for_wide(), self.arena)
        } else {
            super::parallel::build_loaded(&builder, self.arena)
        }
    }
}
