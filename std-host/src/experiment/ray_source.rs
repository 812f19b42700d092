//! Where a run's rays come from: the area's synthetic sampler, or rays a renderer recorded.

use std::borrow::Cow;
use std::path::PathBuf;

use rdbvh_core::geometry::Ray;
use rdbvh_core::influence::InfluenceArea;

use super::{sample_rays, RunSetup};

/// The rays that measure each area's local BVH.
#[derive(Clone, Debug, Default, PartialEq)]
pub enum RaySource {
    /// `rays_per_config` rays from the area's sampler (its window for a plane area, its eye for
    /// a point area), seeded by the configuration's position in the file.
    #[default]
    Sampled,
    /// Rays read from a file (`rdbvh render --record-rays` writes them): every area is measured
    /// on all of them, in file order, through the structure and through the fallback alone. The
    /// structure gives its local BVH the rays the area's affinity test accepts and the fallback
    /// the rest, so the comparison is the structure's on the renderer's own workload. (Filtering
    /// by affinity instead would drop every shadow ray toward a point light: they run toward the
    /// area's eye, not away from it.)
    Recorded {
        /// The file they came from, for messages and the report.
        path: PathBuf,
        /// Every ray of the file.
        rays: Vec<Ray>,
    },
}

impl RaySource {
    /// The rays for `area` (configuration `index`, counted from 0).
    pub fn rays_for(&self, area: &InfluenceArea, index: usize, setup: &RunSetup) -> Cow<'_, [Ray]> {
        match self {
            RaySource::Sampled => Cow::Owned(sample_rays(area, setup, index as u64 + 1)),
            RaySource::Recorded { rays, .. } => Cow::Borrowed(rays),
        }
    }

    /// How the report names the source.
    pub fn describe(&self, rays_per_config: u32) -> String {
        match self {
            RaySource::Sampled => format!("{rays_per_config} sampled rays per run"),
            RaySource::Recorded { path, rays } => format!(
                "the {} rays recorded in `{}` for every run",
                rays.len(),
                path.display()
            ),
        }
    }
}
