//! The thesis's random scene recipe: `v0 ~ U[0,10]^3`, `v1 = v0 + U[-1,1]^3`,
//! `v2 = v1 + U[-1,1]^3`, drawn from `std::mt19937` seeded with 1.
//!
//! Regenerated here rather than shipped, so the main job needs no download. Checked against the
//! thesis's files: `Random100.obj` is the first 100 triangles of the stream, and `Random1000.obj` is
//! the 1000 that follow (the thesis generated Random100 first with the same generator), both equal
//! to the last printed digit.

use rdbvh_core::geometry::{Aabb, Triangle};
use rdbvh_core::Vec3;

use super::{Mt19937, Scene, BUILTIN_PREFIX};

/// The seed of the thesis's random scenes.
pub const THESIS_SEED: u32 = 1;

/// Triangles `skip..skip + count` of the thesis's random stream.
///
/// Coordinates are drawn x, y, z in turn, `v0` then the two offsets, each as
/// [`Mt19937::uniform_f32`]; the sums are `f32` additions, as in the C++ code.
pub fn thesis_random_triangles(skip: usize, count: usize) -> Vec<Triangle> {
    let mut rng = Mt19937::new(THESIS_SEED);
    let point = |rng: &mut Mt19937, lo: f32, hi: f32| {
        let x = rng.uniform_f32(lo, hi);
        let y = rng.uniform_f32(lo, hi);
        let z = rng.uniform_f32(lo, hi);
        Vec3::new(x, y, z)
    };
    let next = |rng: &mut Mt19937| {
        let v0 = point(rng, 0.0, 10.0);
        let v1 = v0 + point(rng, -1.0, 1.0);
        let v2 = v1 + point(rng, -1.0, 1.0);
        Triangle::new(v0, v1, v2)
    };
    for _ in 0..skip {
        next(&mut rng);
    }
    (0..count).map(|_| next(&mut rng)).collect()
}

/// A scene of triangles `skip..skip + count` of the thesis's stream, with no materials.
pub(super) fn random_scene(name: &str, skip: usize, count: usize) -> Scene {
    let triangles = thesis_random_triangles(skip, count);
    let bounds = triangles
        .iter()
        .fold(Aabb::EMPTY, |b, t| b.union(t.bounds()));
    Scene {
        name: format!("{BUILTIN_PREFIX}{name}"),
        material: vec![u32::MAX; triangles.len()],
        emissive: vec![false; triangles.len()],
        materials: Vec::new(),
        bounds,
        warnings: Vec::new(),
        material_files: Vec::new(),
        view: None,
        triangles,
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use std::path::Path;

    #[test]
    fn first_triangle_of_the_stream() {
        let t = thesis_random_triangles(0, 1)[0];
        // The first line of Random100.obj, printed with 9 significant digits.
        let printed: Vec<f32> = "9.97184849 9.32557392 1.28124452"
            .split(' ')
            .map(|x| x.parse().unwrap())
            .collect();
        assert_eq!(t.v0, Vec3::from_slice(&printed));
        assert!(t.v0.cmpge(Vec3::ZERO).all() && t.v0.cmple(Vec3::splat(10.0)).all());
    }

    #[test]
    fn skipping_continues_the_stream() {
        let all = thesis_random_triangles(0, 30);
        assert_eq!(thesis_random_triangles(10, 20), all[10..]);
    }

    /// The thesis's files, when `../shared` is checked out beside the workspace.
    #[test]
    fn matches_the_thesis_files() {
        let dir = Path::new(concat!(
            env!("CARGO_MANIFEST_DIR"),
            "/../../shared/scenes/thesis"
        ));
        if !dir.is_dir() {
            assert!(
                std::env::var("CI").as_deref() != Ok("true"),
                "CI=true but {} is missing",
                dir.display()
            );
            eprintln!(
                "skipped: {} not found (no ../shared checkout)",
                dir.display()
            );
            return;
        }
        for (file, skip, count) in [("Random100.obj", 0, 100), ("Random1000.obj", 100, 1000)] {
            let reference = Scene::load(dir.join(file)).unwrap();
            let ours = thesis_random_triangles(skip, count);
            assert_eq!(reference.triangles.len(), count, "{file}");
            for (i, (a, b)) in ours.iter().zip(&reference.triangles).enumerate() {
                for (p, q) in [(a.v0, b.v0), (a.v1, b.v1), (a.v2, b.v2)] {
                    assert!((p - q).abs().max_element() <= 1e-4, "{file} triangle {i}");
                }
                // Nine printed digits read back as the same f32, so the match is in fact exact.
                assert_eq!(a, b, "{file} triangle {i}");
            }
        }
    }
}
