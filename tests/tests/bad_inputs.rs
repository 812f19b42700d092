//! The bad-input catalogue: every input a user can get wrong gets a typed error with a clear
//! message, or a documented answer that these tests pin down. None panics. Open core bugs found
//! while writing it (and by the fuzz targets in `fuzz/`) are `#[ignore = "CORE BUG: ..."]` tests
//! at the end, so `cargo test -p rdbvh-tests --release -- --ignored` lists what still fails.

use std::path::Path;

use rdbvh::scene::{MaterialFiles, Scene as ObjScene, SceneError as ObjError};
use rdbvh_core::brute_force;
use rdbvh_core::builder::{BuildArena, BuildConfig, BuildOptions, Builder, Preset, PresetOptions};
use rdbvh_core::bvh::{Bvh, WideBvh};
use rdbvh_core::geometry::{Ray, RayError, Triangle};
use rdbvh_core::influence::{AreaError, InfluenceArea, PlaneArea, PointArea, RaySampler};
use rdbvh_core::toplevel::{TopLevel, TopLevelOptions};
use rdbvh_core::{BuildError, Vec3};
use rdbvh_tests::{camera_rays, check_rays, check_structure, interior_rays, scene_bounds};

fn obj(text: &str) -> Result<ObjScene, ObjError> {
    ObjScene::from_obj_str_with(text, Path::new("bad.obj"), MaterialFiles::None)
}

/// The error's message: one line naming the file.
fn message(e: &ObjError) -> String {
    let m = e.to_string();
    assert!(!m.contains('\n'), "{m:?}");
    assert!(m.contains("bad.obj"), "{m:?}");
    m
}

const TRIANGLE: &str = "v 0 0 0\nv 1 0 0\nv 0 1 0\n";

#[test]
fn empty_obj_has_no_triangles() {
    for text in ["", "\n\n", "# only a comment\n", "o empty\ng nothing\n"] {
        let e = obj(text).unwrap_err();
        assert!(matches!(e, ObjError::NoTriangles { .. }), "{text:?}: {e:?}");
        assert!(message(&e).contains("no triangles"));
    }
}

#[test]
fn vertices_without_faces_have_no_triangles() {
    for text in [TRIANGLE.to_string(), format!("{TRIANGLE}l 1 2 3\np 1\n")] {
        let e = obj(&text).unwrap_err();
        assert!(matches!(e, ObjError::NoTriangles { .. }), "{text:?}: {e:?}");
    }
    // A face of two vertices is no triangle either.
    let e = obj(&format!("{TRIANGLE}f 1 2\n")).unwrap_err();
    assert!(
        matches!(e, ObjError::NoTriangles { .. } | ObjError::Malformed { .. }),
        "{e:?}"
    );
}

#[test]
fn faces_referencing_missing_vertices_name_the_line() {
    for (face, index) in [("f 1 2 4", 4), ("f 1 2 -4", -4), ("f -1 -2 -9", -9)] {
        let e = obj(&format!("{TRIANGLE}{face}\n")).unwrap_err();
        match &e {
            ObjError::MissingVertex {
                line,
                index: i,
                defined,
                ..
            } => {
                assert_eq!((*line, *i, *defined), (4, index, 3), "{face}");
            }
            other => panic!("{face}: {other:?}"),
        }
        let m = message(&e);
        assert!(m.contains("line 4"), "{m}");
    }
    // A face before any vertex.
    let e = obj("f 1 2 3\nv 0 0 0\nv 1 0 0\nv 0 1 0\n").unwrap_err();
    assert!(
        matches!(e, ObjError::MissingVertex { line: 1, .. }),
        "{e:?}"
    );
}

#[test]
fn huge_and_zero_indices_are_errors() {
    for face in [
        "f 1 2 4294967296",
        "f 1 2 99999999999999999999999",
        "f 1 2 -99999999999999999999999",
        "f 0 1 2",
        "f 1 2 x",
        "f 1/99 2/1 3/1",
        "f 1//99 2//1 3//1",
    ] {
        let e = obj(&format!("{TRIANGLE}{face}\n")).unwrap_err();
        assert!(
            matches!(
                e,
                ObjError::MissingVertex { line: 4, .. } | ObjError::Malformed { .. }
            ),
            "{face}: {e:?}"
        );
        message(&e);
    }
}

#[test]
fn nan_and_infinite_coordinates_are_errors() {
    for v in ["nan 0 0", "0 inf 0", "0 0 -inf", "1e39 0 0", "0 -1e39 0"] {
        let text = format!("v {v}\nv 1 0 0\nv 0 1 0\nf 1 2 3\n");
        let e = obj(&text).unwrap_err();
        assert!(
            matches!(
                e,
                ObjError::NonFiniteVertex {
                    triangle: 0,
                    corner: 0,
                    ..
                } | ObjError::Malformed { .. }
            ),
            "{v}: {e:?}"
        );
        message(&e);
    }
    // In the core: the first triangle with a NaN or infinite coordinate is named.
    for bad in [f32::NAN, f32::INFINITY, f32::NEG_INFINITY] {
        let mut tris = vec![Triangle::new(Vec3::ZERO, Vec3::X, Vec3::Y); 3];
        tris[1].v2.z = bad;
        let e = Builder::sah().build(&tris).unwrap_err();
        assert_eq!(e, BuildError::InvalidPrimitive { index: 1 });
        assert!(e.to_string().contains("primitive 1"), "{e}");
        let e = TopLevel::with_list(&tris, vec![], &TopLevelOptions::default()).unwrap_err();
        assert!(e.to_string().contains("primitive 1"), "{e}");
    }
}

#[test]
fn non_utf8_obj_is_an_io_error() {
    let bytes: &[u8] = b"v 0 0 0\nv 1 0 0\nv 0 1 0\nf 1 2 3\n\xff\xfe\n";
    let e =
        ObjScene::from_obj_reader(bytes, Path::new("bad.obj"), MaterialFiles::None).unwrap_err();
    assert!(matches!(e, ObjError::Io { .. }), "{e:?}");
    message(&e);
}

#[test]
fn malformed_mtl_is_a_warning_not_an_error() {
    let files = [("m.mtl", "newmtl a\nKd 1\nKe\nNs nope\n")];
    let scene = ObjScene::from_obj_str_with(
        &format!("mtllib m.mtl\nmtllib missing.mtl\n{TRIANGLE}usemtl a\nf 1 2 3\n"),
        Path::new("bad.obj"),
        MaterialFiles::Memory(&files),
    )
    .unwrap();
    assert_eq!(scene.triangles.len(), 1);
    assert!(!scene.warnings.is_empty());
    for w in &scene.warnings {
        assert!(!w.to_string().contains('\n'));
    }
}

/// Every builder and preset over `tris`: valid trees that agree with brute force on `rays`.
fn every_build_agrees(tris: &[Triangle], rays: &[Ray]) {
    let area: InfluenceArea = PlaneArea::new(Vec3::new(0.0, 0.0, -5.0), Vec3::Z, 5.0, 5.0, 20.0)
        .unwrap()
        .into();
    let mut trees = vec![
        Builder::sah().build(tris).unwrap(),
        Builder::lsph().build(tris).unwrap(),
    ];
    for options in [PresetOptions::default(), PresetOptions::thesis()] {
        for preset in Preset::ALL {
            let mut arena = BuildArena::with_capacity(tris.len());
            arena.load_triangles(tris).unwrap();
            let mut bvh = Bvh::with_capacity(tris.len());
            BuildOptions::with_settings(preset, options)
                .build_into(&mut arena, Some(&area), &mut bvh)
                .unwrap();
            trees.push(bvh);
        }
    }
    for bvh in &trees {
        check_structure(bvh, tris);
        check_rays(bvh, tris, rays);
        let wide = WideBvh::from_binary(bvh, tris);
        for ray in rays {
            assert_eq!(wide.closest_hit(ray), brute_force::closest_hit(ray, tris));
        }
    }
}

#[test]
fn empty_scene_builds_an_empty_tree_that_hits_nothing() {
    let bvh = Builder::sah().build(&[]).unwrap();
    assert!(bvh.is_empty());
    bvh.validate(0, |_| unreachable!()).unwrap();
    let ray = Ray::new(Vec3::ZERO, Vec3::X).unwrap();
    assert_eq!(bvh.closest_hit(&ray, &[]), None);
    assert!(!bvh.any_hit(&ray, &[]));
    assert_eq!(bvh.all_hit(&ray, &[]).hits, 0);
    let scene = TopLevel::with_octree(&[], vec![], &TopLevelOptions::default(), 5).unwrap();
    assert_eq!(scene.closest_hit(&ray, &[]), None);
}

#[test]
fn all_degenerate_triangles_build_and_are_never_hit() {
    let mut tris = Vec::new();
    for i in 0..200 {
        let p = Vec3::new(i as f32 * 0.1, (i % 7) as f32, 0.0);
        tris.push(Triangle::new(p, p, p)); // a point
        tris.push(Triangle::new(p, p + Vec3::X, p + 2.0 * Vec3::X)); // a segment
    }
    let bounds = scene_bounds(&tris);
    let mut rays = camera_rays(&bounds, 300, 1);
    rays.extend(interior_rays(&bounds, 300, 2));
    // Rays exactly through the points and along the segments.
    rays.extend(
        tris.iter()
            .filter_map(|t| Ray::new(t.v0 - Vec3::Z, Vec3::Z).ok()),
    );
    rays.extend(
        tris.iter()
            .filter_map(|t| Ray::new(t.v0 - Vec3::X, Vec3::X).ok()),
    );
    every_build_agrees(&tris, &rays);
    assert!(rays.iter().all(|r| !brute_force::any_hit(r, &tris)));
}

#[test]
fn identical_triangles_build_and_the_lowest_id_wins() {
    let t = Triangle::new(
        Vec3::new(-1.0, -1.0, 2.0),
        Vec3::new(1.0, -1.0, 2.0),
        Vec3::Y * 1.0 + Vec3::Z * 2.0,
    );
    let tris = vec![t; 1000];
    let rays = camera_rays(&scene_bounds(&tris), 200, 3);
    every_build_agrees(&tris, &rays);
    let hit = Builder::sah()
        .build(&tris)
        .unwrap()
        .closest_hit(&Ray::new(Vec3::ZERO, Vec3::Z).unwrap(), &tris)
        .unwrap();
    assert_eq!(hit.triangle, 0, "ties go to the lowest triangle id");
}

#[test]
fn one_triangle_is_one_leaf() {
    let tris = [Triangle::new(Vec3::ZERO, Vec3::X, Vec3::Y)];
    let bvh = Builder::sah().build(&tris).unwrap();
    assert_eq!(bvh.nodes().len(), 1);
    assert_eq!(bvh.max_depth(), 0);
    let rays = camera_rays(&scene_bounds(&tris), 200, 4);
    every_build_agrees(&tris, &rays);
}

#[test]
fn billion_unit_scene_beside_a_micro_one() {
    let mut tris = Vec::new();
    for i in 0..50 {
        let s = i as f32;
        // A billion-unit wall...
        tris.push(Triangle::new(
            Vec3::new(-1e9 + s * 1e7, -1e9, 5e8),
            Vec3::new(1e9, -1e9 + s * 1e7, 5e8),
            Vec3::new(0.0, 1e9, 5e8 + s * 1e6),
        ));
        // ...and a micrometre-sized cluster at the origin.
        let o = Vec3::new(s * 1e-6, 0.0, 0.0);
        tris.push(Triangle::new(o, o + Vec3::X * 1e-6, o + Vec3::Y * 1e-6));
    }
    let mut rays = camera_rays(&scene_bounds(&tris), 200, 5);
    rays.extend(camera_rays(&scene_bounds(&tris[1..2]), 200, 6));
    rays.extend(camera_rays(&scene_bounds(&tris[..1]), 200, 7));
    let rays: Vec<Ray> = rays
        .into_iter()
        .filter(|r| rdbvh_tests::known_core_bug(r, &tris).is_none())
        .collect();
    every_build_agrees(&tris, &rays);
}

#[test]
fn build_config_out_of_range_is_an_error() {
    let tris = [Triangle::new(Vec3::ZERO, Vec3::X, Vec3::Y)];
    for config in [
        BuildConfig {
            bins: 1,
            ..BuildConfig::default()
        },
        BuildConfig {
            bins: 65,
            ..BuildConfig::default()
        },
        BuildConfig {
            max_depth: 0,
            ..BuildConfig::default()
        },
        BuildConfig {
            max_depth: 65,
            ..BuildConfig::default()
        },
    ] {
        let e = Builder::sah().with_config(config).build(&tris).unwrap_err();
        assert!(
            matches!(e, BuildError::InvalidConfig(_)),
            "{config:?}: {e:?}"
        );
        assert!(e.to_string().starts_with("invalid build configuration"));
    }
}

#[test]
fn areas_with_zero_or_negative_extents_are_errors() {
    let c = Vec3::ZERO;
    for (hw, hh, depth, key) in [
        (0.0, 1.0, 1.0, "half_width"),
        (-1.0, 1.0, 1.0, "half_width"),
        (1.0, 0.0, 1.0, "half_height"),
        (1.0, 1.0, -0.0, "depth"),
        (1.0, 1.0, -5.0, "depth"),
    ] {
        let e = PlaneArea::new(c, Vec3::Z, hw, hh, depth).unwrap_err();
        assert_eq!(e, AreaError::NotPositive(key));
        assert_eq!(e.to_string(), format!("`{key}` must be positive"));
    }
    assert_eq!(
        PlaneArea::new(c, Vec3::ZERO, 1.0, 1.0, 1.0).unwrap_err(),
        AreaError::ZeroDirection("normal")
    );
    assert_eq!(
        PlaneArea::new(c, Vec3::Z, f32::NAN, 1.0, 1.0).unwrap_err(),
        AreaError::NotFinite("half_width")
    );
    // Point areas: near must be >= 0 and below far.
    for (near, far) in [(-1.0, 5.0), (5.0, 5.0), (6.0, 5.0)] {
        let e = PointArea::new(c, Vec3::Z, 60.0, 60.0, near, far).unwrap_err();
        assert_eq!(e, AreaError::NearFar, "near {near} far {far}");
    }
    assert_eq!(
        PointArea::new(c, Vec3::Z, 60.0, 60.0, 0.0, 5.0).map(|_| ()),
        Ok(()),
        "near = 0 (rays from the eye) is allowed"
    );
}

#[test]
fn fields_of_view_of_0_and_180_degrees_are_errors() {
    for (fx, fy, key) in [
        (0.0, 60.0, "fov_x_deg"),
        (180.0, 60.0, "fov_x_deg"),
        (60.0, 0.0, "fov_y_deg"),
        (60.0, 180.0, "fov_y_deg"),
        (-10.0, 60.0, "fov_x_deg"),
        (360.0, 60.0, "fov_x_deg"),
    ] {
        let e = PointArea::new(Vec3::ZERO, Vec3::Z, fx, fy, 0.1, 10.0).unwrap_err();
        assert_eq!(e, AreaError::FieldOfView(key), "{fx} {fy}");
        assert!(e.to_string().contains("strictly between 0 and 180"));
    }
    // Just inside the range is a valid, very wide or very narrow frustum.
    for fov in [0.01, 179.9] {
        let a = PointArea::new(Vec3::ZERO, Vec3::Z, fov, fov, 0.1, 10.0).unwrap();
        assert!(a.contains(Vec3::new(0.0, 0.0, 5.0)));
    }
    assert_eq!(
        PointArea::new(Vec3::ZERO, Vec3::Z, 60.0, 60.0, 0.1, 10.0)
            .unwrap()
            .with_tolerance_deg(180.0)
            .unwrap_err(),
        AreaError::Tolerance
    );
}

#[test]
fn rays_with_zero_or_nan_directions_are_errors() {
    let o = Vec3::ZERO;
    assert_eq!(Ray::new(o, Vec3::ZERO), Err(RayError::ZeroDirection));
    assert_eq!(Ray::new(o, -Vec3::ZERO), Err(RayError::ZeroDirection));
    for d in [
        Vec3::new(f32::NAN, 0.0, 1.0),
        Vec3::new(0.0, f32::INFINITY, 0.0),
    ] {
        assert_eq!(Ray::new(o, d), Err(RayError::NonFiniteDirection));
    }
    assert_eq!(
        Ray::new(Vec3::splat(f32::NAN), Vec3::X),
        Err(RayError::NonFiniteOrigin)
    );
    assert_eq!(
        Ray::segment(o, Vec3::X, 0.0, f32::NAN),
        Err(RayError::NanSegment)
    );
    for e in [
        RayError::ZeroDirection,
        RayError::NonFiniteDirection,
        RayError::NonFiniteOrigin,
        RayError::NanSegment,
    ] {
        assert!(e.to_string().starts_with("ray "), "{e}");
    }
    // A subnormal direction is a valid ray: it hits what lies ahead at a huge `t`, or nothing
    // when `t` overflows (never an infinite `t`).
    let tris = [Triangle::new(
        Vec3::new(-1.0, -1.0, 1.0),
        Vec3::new(1.0, -1.0, 1.0),
        Vec3::new(0.0, 1.0, 1.0),
    )];
    let ray = Ray::new(o, Vec3::new(0.0, 0.0, 1e-40)).unwrap();
    let bvh = Builder::sah().build(&tris).unwrap();
    let hit = brute_force::closest_hit(&ray, &tris);
    assert_eq!(bvh.closest_hit(&ray, &tris), hit);
    assert!(hit.is_none_or(|h| h.t.is_finite()));
}

#[test]
fn tmin_above_tmax_is_an_empty_segment_that_hits_nothing() {
    let tris: Vec<Triangle> = (0..100)
        .map(|i| {
            let z = i as f32;
            Triangle::new(
                Vec3::new(-1.0, -1.0, z),
                Vec3::new(1.0, -1.0, z),
                Vec3::new(0.0, 1.0, z),
            )
        })
        .collect();
    let bvh = Builder::sah().build(&tris).unwrap();
    let wide = WideBvh::from_binary(&bvh, &tris);
    let area: InfluenceArea = PlaneArea::new(Vec3::new(0.0, 0.0, -1.0), Vec3::Z, 2.0, 2.0, 200.0)
        .unwrap()
        .into();
    let scene = TopLevel::with_octree(&tris, vec![area], &TopLevelOptions::default(), 5).unwrap();
    for (t_min, t_max) in [(5.0, 4.0), (f32::INFINITY, 0.0), (0.0, f32::NEG_INFINITY)] {
        let ray = Ray::segment(Vec3::new(0.0, 0.0, -1.0), Vec3::Z, t_min, t_max).unwrap();
        assert!(area.is_affine(&ray) || t_min > 0.0 || t_max < 0.0);
        assert_eq!(brute_force::closest_hit(&ray, &tris), None);
        assert_eq!(bvh.closest_hit(&ray, &tris), None);
        assert!(!bvh.any_hit(&ray, &tris));
        assert_eq!(bvh.all_hit(&ray, &tris).hits, 0);
        assert_eq!(wide.closest_hit(&ray), None);
        assert_eq!(scene.closest_hit(&ray, &tris), None);
        assert!(!scene.any_hit(&ray, &tris));
    }
    // A zero-length segment `[t, t]` on a triangle hits it.
    let ray = Ray::segment(Vec3::new(0.0, 0.0, -1.0), Vec3::Z, 6.0, 6.0).unwrap();
    assert_eq!(bvh.closest_hit(&ray, &tris).map(|h| h.triangle), Some(5));
}

#[test]
fn scene_with_zero_areas_and_tiny_areas_uses_the_fallback() {
    let tris: Vec<Triangle> = (0..50)
        .map(|i| {
            let p = Vec3::new(i as f32 * 0.3, 0.0, 3.0);
            Triangle::new(p, p + Vec3::X, p + Vec3::Y)
        })
        .collect();
    let tiny: InfluenceArea = PlaneArea::new(Vec3::ZERO, Vec3::Z, 1e-6, 1e-6, 1e-6)
        .unwrap()
        .into();
    let rays = camera_rays(&scene_bounds(&tris), 300, 8);
    for areas in [vec![], vec![tiny]] {
        let scene =
            TopLevel::with_octree(&tris, areas.clone(), &TopLevelOptions::default(), 5).unwrap();
        let list = TopLevel::with_list(&tris, areas.clone(), &TopLevelOptions::default()).unwrap();
        let mut all = rays.clone();
        for a in &areas {
            all.extend(RaySampler::new(*a, 9).take(50));
        }
        for r in &all {
            let expect = brute_force::closest_hit(r, &tris);
            assert_eq!(scene.closest_hit(r, &tris), expect);
            assert_eq!(list.closest_hit(r, &tris), expect);
        }
    }
}

/// Regression (found by the `areas` fuzz target, fixed): `PlaneArea::new` and `PointArea::new`
/// accepted finite coordinates near `f32::MAX` whose box planes overflow (`offset = +-inf`), so the
/// area contains no point, not even its own centre, and every overlap test fails. Expected: a
/// typed `AreaError::NotFinite` (the derived geometry is not finite), as for NaN inputs.
#[test]
fn area_near_f32_max_is_an_error() {
    let c = Vec3::splat(-f32::MAX);
    match PlaneArea::new(c, Vec3::new(1.0, 0.0, 1.0), 13.0, 2.5, 5.5) {
        Err(e) => assert!(matches!(e, AreaError::NotFinite(_)), "{e:?}"),
        Ok(a) => {
            let v = a.polytope().vertices;
            let centre = v.iter().map(|&p| p * 0.125).sum::<Vec3>();
            assert!(
                a.contains(centre),
                "accepted, but contains not even its centre: {a:?}"
            );
        }
    }
}

/// Regression (found by the `areas` fuzz target, fixed): `Frame::look_at` normalised with
/// `try_normalize`, whose squared length is subnormal for a direction of length about `1e-22`,
/// so `forward` comes out with a length far from 1. The area's own parallel rays
/// (direction `forward`) are then not affine to it. Expected: an orthonormal frame (scale the
/// direction by its largest component first) or `AreaError::ZeroDirection`.
#[test]
fn tiny_direction_gives_a_unit_frame() {
    let normal = Vec3::new(0.0, -4.5e-23, 0.0);
    match PlaneArea::new(Vec3::ZERO, normal, 1.0, 1.0, 1.0) {
        Err(e) => assert_eq!(e, AreaError::ZeroDirection("normal")),
        Ok(a) => {
            let len = a.frame.forward.length();
            assert!((len - 1.0).abs() < 1e-4, "forward has length {len}");
            let ray = RaySampler::new(a.into(), 1).next().unwrap();
            assert!(a.is_affine(&ray), "{ray:?}");
        }
    }
}
