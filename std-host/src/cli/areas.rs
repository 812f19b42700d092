//! The influence areas a command works with: read from `--areas`, kept when they apply to the
//! scene, and the triangles each one reaches.

use std::path::Path;

use rayon::prelude::*;
use rdbvh_core::geometry::Triangle;
use rdbvh_core::influence::InfluenceArea;

use super::error::CliError;
use crate::areas::{read_areas, AreaEntry};
use crate::scene::Scene;

/// The entries of the area file at `path` that apply to `scene` (all of an `[[area]]` file; the
/// ones whose `file` names the scene in a `[[config]]` file such as `experiments.toml`).
pub fn load_areas(path: &Path, scene: &Scene) -> Result<Vec<AreaEntry>, CliError> {
    let file = read_areas(path)?;
    let entries = file.for_scene(&scene.name)?;
    Ok(entries.into_iter().cloned().collect())
}

/// Ids of the triangles that `area` takes into its local BVH, in id order: the scene
/// structure's own test ([`InfluenceArea::takes_triangle`]: a separating-axis test, so a
/// triangle that crosses the area with no vertex inside it is included), as
/// [`InfluenceArea::triangles_in`] but on all threads, so `build`, `analyze`, `trace` and
/// `experiment` report the same triangles for the same area.
pub fn overlapping(triangles: &[Triangle], area: &InfluenceArea) -> Vec<u32> {
    let bounds = area.bounds().padded();
    (0..triangles.len() as u32)
        .into_par_iter()
        .filter(|&i| area.takes_triangle(&bounds, &triangles[i as usize]))
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

    #[test]
    fn build_selects_what_the_scene_structure_selects() {
        // Found by black-box testing: `build` prefiltered by the area's exact box and the scene
        // structure by its padded box, so a 179-degree frustum (corners near 1e7, so a padding
        // of about 20 units) gave `build` 439 triangles and `analyze`/`trace` 1005.
        use rdbvh_core::influence::PointArea;
        let eye = Vec3::splat(5.0);
        let area: InfluenceArea = PointArea::new(eye, Vec3::Y, 179.0, 179.0, 1e-3, 1e5)
            .unwrap()
            .into();
        let mut rng = rdbvh_core::random::Pcg32::new(3);
        let tris: Vec<Triangle> = (0..400)
            .map(|_| {
                let a = Vec3::new(
                    rng.range(0.0, 10.0),
                    rng.range(-20.0, 10.0),
                    rng.range(0.0, 10.0),
                );
                Triangle::new(a, a + Vec3::X, a + Vec3::Z)
            })
            .collect();
        let structure: Vec<u32> = area.triangles_in(&tris).collect();
        assert_eq!(overlapping(&tris, &area), structure);
        // The test is conservative: everything the area touches is taken (these triangles lie
        // in planes y = const, so y >= 5 means inside the upward frustum's half-space).
        assert!(tris
            .iter()
            .enumerate()
            .filter(|(_, t)| t.v0.y >= eye.y + 1.0)
            .all(|(i, _)| structure.contains(&(i as u32))));
    }
}
