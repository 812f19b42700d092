//! A closed room lit by an emissive ceiling light, with boxes inside: a Cornell-box-like scene
//! with the two properties the ray-distribution heuristics care about, an area light whose shadow
//! rays converge on a small rectangle, and occluders between that light and the surfaces.

use rdbvh_core::geometry::{Aabb, Triangle};
use rdbvh_core::Vec3;

use super::{Material, Scene, View, BUILTIN_PREFIX};

/// Edge length of the room, which spans `[0, ROOM_SIZE]^3` with `y` up.
pub const ROOM_SIZE: f32 = 10.0;

/// Quads per wall edge: the walls are tessellated so the BVH has real work to do.
const WALL_SUBDIVISIONS: u32 = 8;

/// Material ids of the room, indices into its material list.
const WHITE: u32 = 0;
const RED: u32 = 1;
const GREEN: u32 = 2;
const LIGHT: u32 = 3;
const BOX: u32 = 4;

/// The built-in room: six tessellated walls (closed, so every ray from inside hits something), a
/// 2 x 2 emissive quad 0.02 below the ceiling's centre (the only emissive triangles), a tall box,
/// a short box and a small cube, the boxes rotated about `y` so no face is axis-aligned.
pub fn room() -> Scene {
    let mut b = Build::default();
    let s = ROOM_SIZE;
    let (x, y, z) = (Vec3::X * s, Vec3::Y * s, Vec3::Z * s);
    b.quad(Vec3::ZERO, x, z, WALL_SUBDIVISIONS, WHITE); // floor
    b.quad(y, x, z, WALL_SUBDIVISIONS, WHITE); // ceiling
    b.quad(z, x, y, WALL_SUBDIVISIONS, WHITE); // back wall
    b.quad(Vec3::ZERO, x, y, WALL_SUBDIVISIONS, WHITE); // front wall (closes the room)
    b.quad(Vec3::ZERO, z, y, WALL_SUBDIVISIONS, RED); // left wall
    b.quad(x, z, y, WALL_SUBDIVISIONS, GREEN); // right wall
    let light_y = s - 0.02;
    b.quad(
        Vec3::new(4.0, light_y, 4.0),
        Vec3::X * 2.0,
        Vec3::Z * 2.0,
        1,
        LIGHT,
    );
    b.cuboid(Vec3::new(3.3, 3.0, 6.5), Vec3::new(1.5, 3.0, 1.5), 0.3, BOX);
    b.cuboid(Vec3::new(6.8, 1.5, 3.5), Vec3::splat(1.5), -0.31, BOX);
    b.cuboid(Vec3::new(8.3, 0.5, 7.8), Vec3::splat(0.5), 0.7, BOX);

    let materials = vec![
        material("white", [0.73; 3], [0.0; 3]),
        material("red", [0.63, 0.065, 0.05], [0.0; 3]),
        material("green", [0.14, 0.45, 0.091], [0.0; 3]),
        material("light", [0.78; 3], [17.0, 12.0, 4.0]),
        material("box", [0.73; 3], [0.0; 3]),
    ];
    let emissive = b
        .material
        .iter()
        .map(|&m| materials[m as usize].is_emissive())
        .collect();
    Scene {
        name: format!("{BUILTIN_PREFIX}room"),
        bounds: b
            .triangles
            .iter()
            .fold(Aabb::EMPTY, |acc, t| acc.union(t.bounds())),
        triangles: b.triangles,
        material: b.material,
        emissive,
        materials,
        warnings: Vec::new(),
        material_files: Vec::new(),
        // From inside, by the front wall, looking at the back wall over the boxes: the room is
        // closed, and a camera framing it from outside would see only its unlit outer walls.
        view: Some(View {
            eye: Vec3::new(5.0, 5.0, 0.3),
            look_at: Vec3::new(5.0, 4.0, 10.0),
        }),
    }
}

/// A material with the Cornell box's colours (`diffuse`) and `emission`.
fn material(name: &str, diffuse: [f32; 3], emission: [f32; 3]) -> Material {
    Material {
        name: name.to_string(),
        diffuse,
        emission,
    }
}

/// Triangles and their materials, as they are emitted.
#[derive(Default)]
struct Build {
    triangles: Vec<Triangle>,
    material: Vec<u32>,
}

impl Build {
    /// The parallelogram `origin + a * [0,1] + b * [0,1]` as `n x n` quads, two triangles each.
    fn quad(&mut self, origin: Vec3, a: Vec3, b: Vec3, n: u32, material: u32) {
        let at = |i: u32, j: u32| origin + a * (i as f32 / n as f32) + b * (j as f32 / n as f32);
        for i in 0..n {
            for j in 0..n {
                let (p00, p10, p11, p01) = (at(i, j), at(i + 1, j), at(i + 1, j + 1), at(i, j + 1));
                self.triangles.push(Triangle::new(p00, p10, p11));
                self.triangles.push(Triangle::new(p00, p11, p01));
                self.material.extend([material, material]);
            }
        }
    }

    /// A box with centre `c` and half extents `h`, turned by `angle` radians about `y`.
    fn cuboid(&mut self, c: Vec3, h: Vec3, angle: f32, material: u32) {
        let (sin, cos) = angle.sin_cos();
        // The box's axes after the turn, scaled to full edge lengths.
        let ax = Vec3::new(cos, 0.0, -sin) * (2.0 * h.x);
        let ay = Vec3::Y * (2.0 * h.y);
        let az = Vec3::new(sin, 0.0, cos) * (2.0 * h.z);
        let o = c - (ax + ay + az) * 0.5;
        self.quad(o, ax, az, 1, material); // bottom
        self.quad(o + ay, ax, az, 1, material); // top
        self.quad(o, ax, ay, 1, material); // front
        self.quad(o + az, ax, ay, 1, material); // back
        self.quad(o, az, ay, 1, material); // left
        self.quad(o + ax, az, ay, 1, material); // right
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use rdbvh_core::brute_force;
    use rdbvh_core::geometry::Ray;

    #[test]
    fn light_is_the_only_emissive_part() {
        let s = room();
        assert_eq!(s.emissive_count(), 2);
        assert_eq!(s.len(), 6 * 2 * 64 + 2 + 3 * 12);
        for id in s.emissive_triangles() {
            let t = s.triangles[id as usize];
            assert!(t.v0.y > ROOM_SIZE - 0.1 && t.v0.y < ROOM_SIZE);
            assert_eq!(s.materials[s.material[id as usize] as usize].name, "light");
        }
        assert_eq!(s.bounds, Aabb::new(Vec3::ZERO, Vec3::splat(ROOM_SIZE)));
    }

    #[test]
    fn room_is_closed() {
        // Rays from inside in many directions, including axis-parallel ones and ones aimed at wall
        // seams and corners, all hit something.
        let s = room();
        let origin = Vec3::new(1.0, 8.0, 1.0);
        let mut dirs = vec![Vec3::X, -Vec3::X, Vec3::Y, -Vec3::Y, Vec3::Z, -Vec3::Z];
        dirs.push(Vec3::splat(ROOM_SIZE) - origin);
        dirs.push(Vec3::new(0.0, ROOM_SIZE, 0.0) - origin);
        for i in 0..200 {
            let a = i as f32 * 0.61;
            let b = i as f32 * 0.37;
            dirs.push(Vec3::new(a.cos() * b.sin(), b.cos(), a.sin() * b.sin()));
        }
        for d in dirs {
            let ray = Ray::new(origin, d).unwrap();
            assert!(
                brute_force::closest_hit(&ray, &s.triangles).is_some(),
                "{d:?}"
            );
        }
    }

    #[test]
    fn boxes_shadow_the_floor() {
        let s = room();
        // Straight up from the floor under the tall box: the box blocks the light.
        let ray = Ray::segment(Vec3::new(3.3, 0.0, 6.5), Vec3::Y, 1e-3, 9.0).unwrap();
        let hit = brute_force::closest_hit(&ray, &s.triangles).unwrap();
        assert_eq!(s.material[hit.triangle as usize], BOX);
    }
}
