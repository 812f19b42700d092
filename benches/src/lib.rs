//! Shared pieces of the rdbvh benchmarks: scenes, deterministic ray sets, and adapters that build and
//! trace rdbvh and its Rust peers (`obvhs` 0.4, `bvh` 0.13, `parry3d` 0.31) on the same triangles
//! and the same rays.
//!
//! Every library gets its input in its own native format, converted once outside the timed region,
//! so a benchmark times the build or the traversal and nothing else. Every library also answers
//! the same two questions per ray (the closest hit distance, and whether anything is hit), and
//! [`agreement`] checks those answers against rdbvh before any timing is trusted: a fast
//! traversal that returns the wrong triangle measures nothing.
//!
//! Rays have unit directions, so a hit distance means the same thing in every library (`bvh`
//! normalises directions; rdbvh's `t` is in units of the direction).

use std::path::{Path, PathBuf};

use glam::Vec3;
use rdbvh_core::builder::{BuildArena, Builder};
use rdbvh_core::bvh::Bvh;
use rdbvh_core::geometry::{Aabb, Ray, Triangle};

pub mod areas;
pub mod compare;
pub mod peers;

/// A rayon pool of one thread. Single-threaded measurements run inside it, so a library whose
/// build follows the current pool (obvhs with its `parallel` feature) builds on one thread.
pub fn single_thread_pool() -> rayon::ThreadPool {
    rayon::ThreadPoolBuilder::new()
        .num_threads(1)
        .thread_name(|_| "bench-1t".into())
        .build()
        .expect("a one-thread rayon pool")
}

/// CPU time consumed so far by the calling thread, in seconds (`CLOCK_THREAD_CPUTIME_ID`): on a
/// machine shared with other work, it leaves out the time the scheduler gave to other processes.
pub fn thread_cpu_seconds() -> f64 {
    let mut ts = libc::timespec {
        tv_sec: 0,
        tv_nsec: 0,
    };
    // SAFETY: `ts` is a valid, writable timespec; the clock id is a constant Linux supports.
    let rc = unsafe { libc::clock_gettime(libc::CLOCK_THREAD_CPUTIME_ID, &mut ts) };
    if rc != 0 {
        return 0.0;
    }
    ts.tv_sec as f64 + ts.tv_nsec as f64 * 1e-9
}

/// Where the shared test scenes live: `../shared/scenes` beside the project's checkout.
pub const SCENES_DIR: &str = concat!(env!("CARGO_MANIFEST_DIR"), "/../../shared/scenes");

/// The scenes the benchmarks run on: the Stanford bunny (69,451 triangles, one compact closed-ish
/// object) and Crytek Sponza (262,267 triangles, an architectural interior with large and tiny
/// triangles mixed).
pub const BENCH_SCENES: [&str; 2] = ["bunny", "sponza_crytek"];

/// The scenes directory, or why it cannot be used. Benchmarks skip (and say why) rather than fail
/// when `../shared` is absent: a checkout without the reference data can still build and run the
/// rest.
pub fn scenes_dir() -> Result<PathBuf, String> {
    let dir = Path::new(SCENES_DIR);
    if dir.is_dir() {
        Ok(dir.to_path_buf())
    } else {
        Err(format!(
            "{} is missing: put the shared scenes beside the checkout to run the benchmarks",
            dir.display()
        ))
    }
}

/// A scene's triangles, loaded with the host crate's OBJ loader (the same path the CLI takes), so
/// the benchmarks see exactly the triangles a user's build sees.
pub fn load_scene(name: &str) -> Result<Vec<Triangle>, String> {
    let path = scenes_dir()?.join(format!("{name}.obj"));
    let scene = rdbvh::scene::Scene::load(&path)
        .map_err(|e| format!("cannot load {}: {e}", path.display()))?;
    if scene.triangles.is_empty() {
        return Err(format!("{} has no triangles", path.display()));
    }
    Ok(scene.triangles)
}

/// A scene named on a command line: a path (or a built-in scene such as `builtin:room`) is opened
/// as given, a bare name is one of `../shared`'s scenes ([`load_scene`]).
pub fn open_scene(scene: &str) -> Result<Vec<Triangle>, String> {
    let named = !scene.contains('/') && !scene.contains(':') && !scene.ends_with(".obj");
    if named {
        return load_scene(scene);
    }
    rdbvh::scene::Scene::open(scene)
        .map(|s| s.triangles)
        .map_err(|e| format!("cannot load {scene}: {e}"))
}

/// The bounds of `tris`.
pub fn bounds(tris: &[Triangle]) -> Aabb {
    tris.iter().fold(Aabb::EMPTY, |b, t| b.union(t.bounds()))
}

/// A small, fixed-seed PRNG (SplitMix64): the ray sets must be identical on every machine and in
/// every run, with no dependency whose stream could change between versions.
#[derive(Clone, Debug)]
pub struct SplitMix64(u64);

impl SplitMix64 {
    /// A generator from `seed`.
    pub fn new(seed: u64) -> Self {
        Self(seed)
    }

    /// The next 64 random bits.
    pub fn next_u64(&mut self) -> u64 {
        self.0 = self.0.wrapping_add(0x9E37_79B9_7F4A_7C15);
        let mut z = self.0;
        z = (z ^ (z >> 30)).wrapping_mul(0xBF58_476D_1CE4_E5B9);
        z = (z ^ (z >> 27)).wrapping_mul(0x94D0_49BB_1331_11EB);
        z ^ (z >> 31)
    }

    /// Uniform in `[0, 1)`, from the top 24 bits (every value exactly representable).
    pub fn next_f32(&mut self) -> f32 {
        (self.next_u64() >> 40) as f32 * (1.0 / (1u64 << 24) as f32)
    }
}

/// Which ray set a measurement uses.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum RayKind {
    /// Primary rays of a pinhole camera: coherent, neighbours visit nearly the same nodes.
    Camera,
    /// Origins uniform in the scene's box, directions uniform on the sphere: incoherent, like
    /// secondary rays, and they start inside the geometry.
    Random,
    /// Shadow segments ([`shadow_rays`]): from the camera rays' first hits, lifted off the
    /// surface, to a point light inside the scene ([`shadow_light`]), ending just short of it.
    Shadow,
}

impl RayKind {
    /// The name used in benchmark ids and the results table.
    pub fn name(self) -> &'static str {
        match self {
            RayKind::Camera => "camera",
            RayKind::Random => "random",
            RayKind::Shadow => "shadow",
        }
    }
}

/// Camera image side: 256 x 256 = 65,536 rays, enough that a pass takes milliseconds (well above
/// timer resolution) and small enough that criterion's samples fit the time budget on 2 cores.
pub const CAMERA_SIDE: u32 = 256;
/// Random rays per set, the same count as the camera set.
pub const RANDOM_RAYS: usize = 65_536;
/// The seed of the random ray set.
pub const RANDOM_SEED: u64 = 0x5EED_2026_1122;

/// Primary rays of a `side` x `side` pinhole camera outside `b`, looking at its centre.
///
/// The eye sits on a fixed oblique direction at 1.5 times the radius of the box's bounding sphere,
/// so it is outside the box for every scene, and the square field of view is the narrowest that
/// holds the box's eight corners: the scene's box just fills the image whatever its units, so few
/// rays are spent on empty background.
pub fn camera_rays(b: &Aabb, side: u32) -> Vec<Ray> {
    let center = b.center();
    let radius = (0.5 * (b.max - b.min).length()).max(f32::MIN_POSITIVE);
    let back = Vec3::new(0.35, 0.45, 1.0).normalize();
    let eye = center + back * (1.5 * radius);
    let forward = -back;
    let right = forward.cross(Vec3::Y).normalize();
    let up = right.cross(forward);
    // Tangent of the half field of view: the largest image-plane coordinate of a corner.
    let half = (0..8)
        .map(|i| {
            let corner = Vec3::select(
                glam::BVec3::new(i & 1 != 0, i & 2 != 0, i & 4 != 0),
                b.max,
                b.min,
            );
            let v = corner - eye;
            let depth = v.dot(forward);
            (v.dot(right) / depth).abs().max((v.dot(up) / depth).abs())
        })
        .fold(f32::MIN_POSITIVE, f32::max);
    pinhole_rays(eye, forward, half, side)
}

/// Primary rays of a `side` x `side` pinhole camera at `eye` looking along the unit `forward`
/// (not vertical), the half field of view's tangent `half`, row by row from the top left. Rays
/// whose direction is not finite are skipped.
pub fn pinhole_rays(eye: Vec3, forward: Vec3, half: f32, side: u32) -> Vec<Ray> {
    let right = forward.cross(Vec3::Y).normalize();
    let up = right.cross(forward);
    let mut rays = Vec::with_capacity((side * side) as usize);
    for y in 0..side {
        for x in 0..side {
            let sx = ((x as f32 + 0.5) / side as f32 * 2.0 - 1.0) * half;
            let sy = (1.0 - (y as f32 + 0.5) / side as f32 * 2.0) * half;
            let dir = (forward + right * sx + up * sy).normalize();
            rays.extend(Ray::new(eye, dir).ok());
        }
    }
    rays
}

/// `n` rays with origins uniform in `b` and directions uniform on the unit sphere, from `seed`.
/// An axis of `b` thinner than 1e-3 of its widest is widened to that about its centre: in a flat
/// scene's box every origin would lie on the geometry's plane, and each ray would measure only
/// the libraries' rules for a hit at distance zero.
pub fn random_rays(b: &Aabb, n: usize, seed: u64) -> Vec<Ray> {
    let mut rng = SplitMix64::new(seed);
    let thinnest = 1e-3 * (b.max - b.min).max_element();
    let pad = (Vec3::splat(thinnest) - (b.max - b.min)).max(Vec3::ZERO) * 0.5;
    let b = &Aabb::new(b.min - pad, b.max + pad);
    let extent = b.max - b.min;
    let mut rays = Vec::with_capacity(n);
    while rays.len() < n {
        let o = b.min + extent * Vec3::new(rng.next_f32(), rng.next_f32(), rng.next_f32());
        // Uniform on the sphere: z uniform in [-1, 1], azimuth uniform (Archimedes).
        let z = 2.0 * rng.next_f32() - 1.0;
        let phi = core::f32::consts::TAU * rng.next_f32();
        let s = (1.0 - z * z).max(0.0).sqrt();
        let d = Vec3::new(s * phi.cos(), s * phi.sin(), z);
        if let Ok(ray) = Ray::new(o, d) {
            rays.push(ray);
        }
    }
    rays
}

/// The ray set of `kind` for the scene `tris` with bounds `b` (the shadow set traces the camera
/// set first to find the surface points it starts from).
pub fn ray_set(tris: &[Triangle], b: &Aabb, kind: RayKind) -> Vec<Ray> {
    match kind {
        RayKind::Camera => camera_rays(b, CAMERA_SIDE),
        RayKind::Random => random_rays(b, RANDOM_RAYS, RANDOM_SEED),
        RayKind::Shadow => shadow_rays(tris, b, &camera_rays(b, CAMERA_SIDE)),
    }
}

/// Where the shadow rays' point light sits: above the centre of the scene's box by 40% of its
/// height, so that it is inside the box, below its top, and (in an interior like Sponza) in the
/// open space of the room rather than in a wall.
pub fn shadow_light(b: &Aabb) -> Vec3 {
    b.center() + Vec3::Y * (0.4 * (b.max.y - b.min.y))
}

/// How far short of the light a shadow segment ends, in units of the segment (`t_max = 1 - this`):
/// a renderer stops just before the light so that the light's own geometry, if any, does not
/// shadow it.
pub const SHADOW_T_GAP: f32 = 1e-4;

/// Shadow segments as a renderer traces them after its primary rays: for each of `camera`'s rays
/// that hits `tris`, the first hit point, moved off the surface along the triangle's normal (on
/// the camera's side) by `1e-5` of the box diagonal so that the segment does not hit its own
/// triangle, to [`shadow_light`]; `dir` is the unnormalised offset to the light and
/// `t` runs over `[0, 1 - SHADOW_T_GAP]`, the way renderers pass light samples. Points whose surface
/// faces away from the light are left out, as a renderer skips them (no light arrives).
pub fn shadow_rays(tris: &[Triangle], b: &Aabb, camera: &[Ray]) -> Vec<Ray> {
    let bvh = rdbvh_build(tris);
    let light = shadow_light(b);
    let lift = 1e-5 * (b.max - b.min).length();
    camera
        .iter()
        .filter_map(|ray| {
            let hit = bvh.closest_hit(ray, tris)?;
            let t = &tris[hit.triangle as usize];
            let mut n = (t.v1 - t.v0).cross(t.v2 - t.v0).normalize_or_zero();
            if n.dot(ray.dir) > 0.0 {
                n = -n;
            }
            let p = ray.origin + ray.dir * hit.t + n * lift;
            let to_light = light - p;
            if n == Vec3::ZERO || n.dot(to_light) <= 0.0 {
                return None;
            }
            Ray::segment(p, to_light, 0.0, 1.0 - SHADOW_T_GAP).ok()
        })
        .collect()
}

/// rdbvh's binned SAH build, single-threaded: allocates its arena and output per build, as the
/// peers' builders do.
pub fn rdbvh_build(tris: &[Triangle]) -> Bvh {
    Builder::sah()
        .build(tris)
        .expect("scene triangles are finite")
}

/// rdbvh's allocation-free build path: the arena and the output are sized once and reused, which
/// is how a renderer rebuilding every frame would call it. Reported beside [`rdbvh_build`] so the
/// cost of the allocations is visible.
pub struct RdbvhReuse {
    arena: BuildArena,
    bvh: Bvh,
}

impl RdbvhReuse {
    /// Memory for builds over up to `n` triangles.
    pub fn with_capacity(n: usize) -> Self {
        Self {
            arena: BuildArena::with_capacity(n),
            bvh: Bvh::with_capacity(n),
        }
    }

    /// Loads `tris` (computing their boxes, as every peer's build does) and builds into the
    /// reused output.
    pub fn build(&mut self, tris: &[Triangle]) -> &Bvh {
        self.arena
            .load_triangles(tris)
            .expect("scene triangles are finite");
        Builder::sah()
            .build_into(&mut self.arena, &mut self.bvh)
            .expect("valid default config");
        &self.bvh
    }
}

/// One library's answers on one ray set, for [`agreement`].
#[derive(Clone, Debug, Default)]
pub struct Answers {
    /// Closest hit distance per ray, `None` on a miss.
    pub closest: Vec<Option<f32>>,
    /// Any-hit answer per ray.
    pub any: Vec<bool>,
    /// Per ray, the smallest distance [`T_TOLERANCE`] is taken of when closest hits are compared
    /// ([`Answers::scaled_to`]); empty: `1e-3` for every ray.
    pub floor: Vec<f32>,
}

impl Answers {
    /// These answers as the reference for `rays` over a scene whose box has diagonal
    /// `diagonal`: two closest hits then agree within [`T_TOLERANCE`] of the larger distance or
    /// of a tenth of the diagonal (in the ray's units), whichever is larger. Correct
    /// single-precision tests differ by rounding that scales with the coordinates, not with the
    /// hit's distance: near a ray's origin, on thin triangles, a few ulps of a coordinate are
    /// many of `t`.
    pub fn scaled_to(mut self, rays: &[Ray], diagonal: f32) -> Self {
        self.floor = rays
            .iter()
            .map(|r| 0.1 * diagonal / r.dir.length())
            .collect();
        self
    }

    pub(crate) fn floor(&self, i: usize) -> f32 {
        self.floor.get(i).copied().unwrap_or(1e-3)
    }
}

/// How far two closest-hit distances may differ and still agree: relative, since the scenes come
/// in metres (bunny) and centimetres (Sponza), with an absolute floor for hits near the origin.
/// Different but correct triangle tests differ by a few ulps on the same triangle; a distance
/// further apart means another triangle was reported.
pub const T_TOLERANCE: f32 = 1e-4;

/// The share of rays on which two libraries agree.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Agreement {
    /// Rays compared.
    pub rays: usize,
    /// Share of rays with the same closest-hit answer: both miss, or both hit at distances within
    /// [`T_TOLERANCE`].
    pub closest: f64,
    /// Share of rays with the same any-hit answer.
    pub any: f64,
}

/// The minimum agreement the benchmarks accept. Not 100%: the libraries' triangle tests differ
/// in their edge rules (a ray through a shared edge or a vertex may hit both neighbours in one
/// library and neither in another), and camera rays through a closed mesh's edges do occur.
pub const MIN_AGREEMENT: f64 = 0.999;

/// Whether two closest-hit answers agree: both miss, or both hit within [`T_TOLERANCE`] of the
/// larger distance or of `floor` (see [`Answers::scaled_to`]).
pub fn same_closest(a: Option<f32>, b: Option<f32>, floor: f32) -> bool {
    match (a, b) {
        (None, None) => true,
        (Some(x), Some(y)) => (x - y).abs() <= T_TOLERANCE * x.abs().max(y.abs()).max(floor),
        _ => false,
    }
}

/// Compares `peer`'s answers with `reference`'s (rdbvh's), ray by ray.
pub fn agreement(reference: &Answers, peer: &Answers) -> Agreement {
    assert_eq!(reference.closest.len(), peer.closest.len());
    assert_eq!(reference.any.len(), peer.any.len());
    let rays = reference.closest.len();
    let closest = (0..rays)
        .filter(|&i| same_closest(reference.closest[i], peer.closest[i], reference.floor(i)))
        .count();
    let any = reference
        .any
        .iter()
        .zip(&peer.any)
        .filter(|(a, b)| a == b)
        .count();
    let share = |k: usize| {
        if rays == 0 {
            1.0
        } else {
            k as f64 / rays as f64
        }
    };
    Agreement {
        rays,
        closest: share(closest),
        any: share(any),
    }
}

/// The rays on which `peer`'s closest-hit or any-hit answer differs from `reference`'s (as
/// [`agreement`] counts them), in order.
pub fn disagreements(reference: &Answers, peer: &Answers) -> Vec<usize> {
    (0..reference.closest.len())
        .filter(|&i| {
            !same_closest(reference.closest[i], peer.closest[i], reference.floor(i))
                || reference.any[i] != peer.any[i]
        })
        .collect()
}

#[cfg(test)]
mod tests {
    use super::*;

    fn cube() -> Aabb {
        Aabb::new(Vec3::splat(-1.0), Vec3::new(3.0, 1.0, 2.0))
    }

    #[test]
    fn random_rays_in_a_flat_box_start_off_its_plane() {
        let flat = Aabb::new(Vec3::new(0.0, 0.0, 2.0), Vec3::new(60.0, 30.0, 2.0));
        let rays = random_rays(&flat, 1000, 3);
        assert!(rays.iter().all(|r| (r.origin.z - 2.0).abs() <= 0.03 + 1e-6));
        assert!(rays.iter().filter(|r| r.origin.z == 2.0).count() < 10);
        // A box that is not flat is not widened: its rays start inside it.
        let b = cube();
        let rays = random_rays(&b, 100, 7);
        assert!(rays
            .iter()
            .all(|r| r.origin.cmpge(b.min).all() && r.origin.cmple(b.max).all()));
    }

    #[test]
    fn ray_sets_are_deterministic_and_sized() {
        let b = cube();
        assert_eq!(random_rays(&b, 100, 7), random_rays(&b, 100, 7));
        assert_ne!(random_rays(&b, 100, 7), random_rays(&b, 100, 8));
        assert_eq!(camera_rays(&b, 16).len(), 256);
    }

    #[test]
    fn random_rays_start_inside_with_unit_directions() {
        let b = cube();
        for r in random_rays(&b, 1000, 1) {
            assert!(r.origin.cmpge(b.min).all() && r.origin.cmple(b.max).all());
            assert!((r.dir.length() - 1.0).abs() < 1e-5);
        }
    }

    #[test]
    fn camera_is_outside_and_sees_the_centre() {
        let b = cube();
        let rays = camera_rays(&b, 15);
        let eye = rays[0].origin;
        assert!(!(eye.cmpge(b.min).all() && eye.cmple(b.max).all()));
        // The middle pixel looks straight at the centre.
        let mid = rays[7 * 15 + 7];
        let to_center = (b.center() - eye).normalize();
        assert!(mid.dir.dot(to_center) > 0.9999);
    }

    #[test]
    fn agreement_counts_tolerance_and_misses() {
        let a = Answers {
            closest: vec![None, Some(1.0), Some(100.0), Some(2.0)],
            any: vec![false, true, true, true],
            floor: Vec::new(),
        };
        let b = Answers {
            closest: vec![None, Some(1.00001), Some(100.5), None],
            any: vec![false, true, true, false],
            floor: Vec::new(),
        };
        let g = agreement(&a, &b);
        assert_eq!(g.rays, 4);
        assert_eq!(g.closest, 0.5);
        assert_eq!(g.any, 0.75);
    }
}
