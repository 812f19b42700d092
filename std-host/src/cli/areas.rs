//! The influence areas a command works with: read from `--areas`, kept when they apply to the
//! scene, and the triangles each one reaches.

use std::path::Path;

use rayon::prelude::*;
use rdbvh_core::geometry::Triangle;
use rdbvh_core::influence::InfluenceArea;

use super::CliError;
use crate::areas::{read_areas, AreaEntry};
use crate::scene::Scene;

/// The entries of the area file at `path` that apply to `scene` (all of an `[[area]]` file; the
/// ones whose `file` names the scene in a `[[config]]` file such as `experiments.toml`).
pub fn load_areas(path: &Path, scene: &Scene) -> Result<Vec<AreaEntry>, CliError> {
    let file = read_areas(path)?;
    let entries = file.for_scene(&scene.name)?;
    Ok(entries.into_iter().cloned().collect())
}

/// Ids of the triangles that overlap `area`, by the exact separating-axis test (a triangle that
/// crosses the area with no vertex inside it is included), in id order.
pub fn overlapping(triangles: &[Triangle], area: &InfluenceArea) -> Vec<u32> {
    let bounds = area.bounds();
    (0..triangles.len() as u32)
        .into_par_iter()
        .filter(|&i| {
            let t = &triangles[i as usize];
            // The box test rejects most triangles cheaply; the SAT test is exact.
            !t.bounds().intersection(bounds).is_empty() && area.overlaps_triangle(t)
        })
        .collect()
}

/// `plane` or `point`, as area files spell the kind.
pub fn kind_name(area: &InfluenceArea) -> &'static str {
    match area {
        InfluenceArea::Plane(_) => "plane",
        InfluenceArea::Point(_) => "point",
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use rdbvh_core::influence::PlaneArea;
    use rdbvh_core::Vec3;

    #[test]
    fn overlap_is_exact_not_by_vertex() {
        // A long triangle crossing the box with every vertex outside it, and one far away.
        let area: InfluenceArea = PlaneArea::new(Vec3::ZERO, Vec3::Z, 1.0, 1.0, 2.0)
            .unwrap()
            .into();
        let crossing = Triangle::new(
            Vec3::new(-10.0, 0.0, 1.0),
            Vec3::new(10.0, -0.5, 1.0),
            Vec3::new(10.0, 0.5, 1.0),
        );
        let away = Triangle::new(
            Vec3::new(5.0, 5.0, 1.0),
            Vec3::new(6.0, 5.0, 1.0),
            Vec3::new(5.0, 6.0, 1.0),
        );
        assert!(!area.contains(crossing.v0) && !area.contains(crossing.v1));
        assert_eq!(overlapping(&[away, crossing, away], &area), vec![1]);
        assert_eq!(kind_name(&area), "plane");
    }
}
