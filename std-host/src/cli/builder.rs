//! The builder options shared by every command that builds a BVH, and the timed build itself.

use std::time::Instant;

use clap::{value_parser, Args, ValueEnum};
use rdbvh_core::build::{BuildArena, BuildConfig, BuildStats, Builder, MAX_BINS};
use rdbvh_core::bvh::Bvh;
use rdbvh_core::geometry::Triangle;
use rdbvh_core::heuristics::{AxisChooser, Sah, SahTermination};
use rdbvh_core::BuildError;
use serde::Serialize;

/// Which split axes the binned SAH builder tries.
#[derive(Clone, Copy, Debug, PartialEq, Eq, ValueEnum, Serialize)]
#[serde(rename_all = "lowercase")]
pub enum BuilderKind {
    /// All three axes, keeping the cheapest split: the usual binned SAH builder.
    Sah,
    /// The longest axis only (LSPH): the thesis's "standard" builder.
    Lsph,
}

impl BuilderKind {
    /// The name used on the command line and in reports.
    pub fn name(self) -> &'static str {
        match self {
            BuilderKind::Sah => "sah",
            BuilderKind::Lsph => "lsph",
        }
    }
}

/// How to build the BVH.
#[derive(Args, Clone, Copy, Debug, PartialEq, Eq)]
pub struct BuilderArgs {
    /// Split axes: `sah` tries all three, `lsph` only the longest one.
    #[arg(long, value_enum, default_value_t = BuilderKind::Sah)]
    pub builder: BuilderKind,
    /// Centroid bins per axis; each bin boundary is a candidate split plane.
    #[arg(long, value_name = "N", default_value_t = BuildConfig::default().bins,
          value_parser = value_parser!(u32).range(2..=i64::from(MAX_BINS)))]
    pub bins: u32,
    /// Largest leaf the SAH termination may keep when splitting would not be cheaper.
    #[arg(long, value_name = "N", default_value_t = SahTermination::default().max_leaf,
          value_parser = value_parser!(u32).range(1..))]
    pub max_leaf: u32,
}

impl Default for BuilderArgs {
    fn default() -> Self {
        Self {
            builder: BuilderKind::Sah,
            bins: BuildConfig::default().bins,
            max_leaf: SahTermination::default().max_leaf,
        }
    }
}

/// A BVH with what its build reported and how long it took.
#[derive(Clone, Debug)]
pub struct BuiltBvh {
    /// The BVH.
    pub bvh: Bvh,
    /// The builder's counters.
    pub stats: BuildStats,
    /// Wall-clock seconds of loading the arena and building, not counting allocation: the
    /// arena and output are sized first, as a renderer that rebuilds every frame would keep them.
    pub seconds: f64,
}

impl BuiltBvh {
    /// Millions of triangles per second of build time.
    pub fn mtris_per_s(&self, triangles: usize) -> f64 {
        triangles as f64 / self.seconds.max(1e-9) / 1e6
    }
}

impl BuilderArgs {
    /// Builds a BVH over `triangles` (single-threaded, as the core's builder is).
    pub fn build(&self, triangles: &[Triangle]) -> Result<BuiltBvh, BuildError> {
        // Only the bins and the leaf size change: each builder keeps the rest of its own
        // configuration (LSPH evaluates its first axis only, which a default config would undo).
        match self.builder {
            BuilderKind::Sah => timed_build(&self.apply(Builder::sah()), triangles),
            BuilderKind::Lsph => timed_build(&self.apply(Builder::lsph()), triangles),
        }
    }

    fn apply<A>(&self, mut b: Builder<A, Sah, SahTermination>) -> Builder<A, Sah, SahTermination> {
        b.config.bins = self.bins;
        b.termination.max_leaf = self.max_leaf;
        b
    }
}

fn timed_build<A: AxisChooser>(
    builder: &Builder<A, Sah, SahTermination>,
    triangles: &[Triangle],
) -> Result<BuiltBvh, BuildError> {
    let mut arena = BuildArena::with_capacity(triangles.len());
    let mut bvh = Bvh::with_capacity(triangles.len());
    let start = Instant::now();
    arena.load_triangles(triangles)?;
    let stats = builder.build_into(&mut arena, &mut bvh)?;
    let seconds = start.elapsed().as_secs_f64();
    Ok(BuiltBvh {
        bvh,
        stats,
        seconds,
    })
}

#[cfg(test)]
mod tests {
    use super::*;
    use rdbvh_core::Vec3;

    #[test]
    fn both_builders_cover_every_triangle() {
        let tris: Vec<Triangle> = (0..100)
            .map(|i| {
                let o = Vec3::new(i as f32, (i % 7) as f32, (i % 3) as f32);
                Triangle::new(o, o + Vec3::X, o + Vec3::Y)
            })
            .collect();
        for builder in [BuilderKind::Sah, BuilderKind::Lsph] {
            let args = BuilderArgs {
                builder,
                max_leaf: 2,
                ..BuilderArgs::default()
            };
            let built = args.build(&tris).unwrap();
            built
                .bvh
                .validate(tris.len(), |id| tris[id as usize].bounds())
                .unwrap();
            assert_eq!(built.stats.nodes as usize, built.bvh.nodes().len());
            assert!(built.bvh.nodes().iter().all(|n| n.count <= 2));
        }
    }

    #[test]
    fn lsph_keeps_its_own_cut_evaluation() {
        let args = BuilderArgs {
            builder: BuilderKind::Lsph,
            bins: 8,
            max_leaf: 3,
        };
        let b = args.apply(Builder::lsph());
        assert_eq!(b.config.cut, Builder::lsph().config.cut);
        assert_eq!((b.config.bins, b.termination.max_leaf), (8, 3));
        // And the two builders really differ on a scene where the longest axis is a poor choice.
        let tris = crate::scene::thesis_random_triangles(0, 1000);
        let sah = BuilderArgs::default().build(&tris).unwrap().bvh;
        let lsph = BuilderArgs {
            builder: BuilderKind::Lsph,
            ..BuilderArgs::default()
        }
        .build(&tris)
        .unwrap()
        .bvh;
        assert_ne!(sah.nodes(), lsph.nodes());
    }
}
