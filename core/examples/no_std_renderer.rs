//! The core used the way a `no_std` renderer uses it: memory sized once up front in buffers the
//! caller owns, then builds and traversals that allocate nothing, checked by a counting allocator
//! and against the brute-force oracle.
//!
//! `cargo run --release -p rdbvh-core --example no_std_renderer`
//!
//! The example itself runs on a host (examples link `std`), but the renderer part uses only what
//! a bare-metal target has: `core`, the crate's API and `libm`, with the triangles in a fixed
//! array and the image in a fixed byte buffer. It:
//!
//! 1. allocates, once, a [`BuildArena`] and a [`Bvh`] sized for the largest scene it will hold;
//! 2. builds into them ([`BuildArena::load_triangles`], [`Builder::build_into`]): no allocation;
//! 3. renders a small ASCII image of a sphere on a floor beside a box, one closest-hit camera ray
//!    and one any-hit shadow ray per pixel: no allocation;
//! 4. moves the sphere, rebuilds into the same arena and tree, and renders again: no allocation.
//!
//! A global allocator counts every allocation, and the example fails if steps 2 to 4 make any,
//! or if any pixel's answers differ from [`brute_force`]'s. It prints the two frames side by side
//! and what the build and the traversals did.
//!
//! Which calls allocate:
//! - [`BuildArena::with_capacity`] (32 bytes per primitive plus about 4.75 KiB of bins) and
//!   [`Bvh::with_capacity`] (68 bytes per primitive) allocate, once; their `try_` forms report a
//!   failed allocation instead of aborting, for a heap sized from untrusted data.
//! - [`Builder::build`] allocates its own arena and tree: a convenience for hosts.
//! - [`rdbvh_core::bvh::WideBvh::from_binary`] allocates the 4-wide tree and its copy of the
//!   triangles: collapse once, not per frame.
//!
//! Which do not: loading an arena within its capacity, [`Builder::build_into`] into a tree made
//! with [`Bvh::with_capacity`] for at least as many primitives, and every traversal
//! (`closest_hit`, `any_hit` and their `_with_stats` forms, binary and 4-wide), whose stacks are
//! fixed arrays sized by the build's depth bound.

use std::alloc::{GlobalAlloc, Layout, System};
use std::error::Error;
use std::sync::atomic::{AtomicUsize, Ordering};

use rdbvh_core::brute_force;
use rdbvh_core::builder::{BuildArena, Builder};
use rdbvh_core::bvh::{Bvh, TraversalStats};
use rdbvh_core::geometry::{Ray, Triangle};
use rdbvh_core::Vec3;

/// Image size of one frame, in characters (a character is about twice as tall as wide).
const WIDTH: usize = 48;
const HEIGHT: usize = 22;
/// Sphere tessellation: segments around, and from pole to pole.
const SLICES: usize = 24;
const STACKS: usize = 12;
/// Floor cells per side.
const FLOOR: usize = 10;
/// Triangles in the scene: the sphere (one per segment at the poles, two elsewhere), the floor,
/// the box. A bare-metal renderer knows its largest scene and sizes every buffer from it.
const TRIS: usize = 2 * SLICES * (STACKS - 1) + 2 * FLOOR * FLOOR + 12;
/// Brightness ramp, dark to bright.
const RAMP: &[u8] = b" .:-=+*#%@";

/// Counts allocations (and reallocations) made through the global allocator, and their bytes.
struct CountingAllocator;

static ALLOCATIONS: AtomicUsize = AtomicUsize::new(0);
static BYTES: AtomicUsize = AtomicUsize::new(0);

fn count(bytes: usize) {
    ALLOCATIONS.fetch_add(1, Ordering::Relaxed);
    BYTES.fetch_add(bytes, Ordering::Relaxed);
}

// SAFETY: every call forwards to `System` with the caller's arguments unchanged, so `System`'s
// guarantees hold; the counter is only an atomic add.
unsafe impl GlobalAlloc for CountingAllocator {
    unsafe fn alloc(&self, layout: Layout) -> *mut u8 {
        count(layout.size());
        // SAFETY: the caller's contract for `alloc` is `System::alloc`'s.
        unsafe { System.alloc(layout) }
    }

    unsafe fn alloc_zeroed(&self, layout: Layout) -> *mut u8 {
        count(layout.size());
        // SAFETY: as for `alloc`.
        unsafe { System.alloc_zeroed(layout) }
    }

    unsafe fn realloc(&self, ptr: *mut u8, layout: Layout, new_size: usize) -> *mut u8 {
        count(new_size);
        // SAFETY: `ptr` came from this allocator, that is from `System`, with `layout`.
        unsafe { System.realloc(ptr, layout, new_size) }
    }

    unsafe fn dealloc(&self, ptr: *mut u8, layout: Layout) {
        // SAFETY: `ptr` came from `System` with `layout`.
        unsafe { System.dealloc(ptr, layout) }
    }
}

#[global_allocator]
static GLOBAL: CountingAllocator = CountingAllocator;

/// Allocations and bytes allocated so far.
fn allocations() -> (usize, usize) {
    (
        ALLOCATIONS.load(Ordering::Relaxed),
        BYTES.load(Ordering::Relaxed),
    )
}

/// One rendered frame and what its traversals did.
struct Frame {
    image: [[u8; WIDTH]; HEIGHT],
    camera: TraversalStats,
    shadow: TraversalStats,
    /// Pixels whose camera ray hit, and of those, how many are in shadow.
    hits: u32,
    shadowed: u32,
}

fn main() -> Result<(), Box<dyn Error>> {
    // Start-up: the only allocations. A bare-metal build takes them from its own heap (see
    // tests/no-std-consumer, a bump allocator over a static buffer).
    let start = allocations();
    let mut arena = BuildArena::with_capacity(TRIS);
    let mut bvh = Bvh::with_capacity(TRIS);
    let (count, bytes) = allocations();
    let setup = (count - start.0, bytes - start.1);
    let mut tris = [Triangle::new(Vec3::ZERO, Vec3::ZERO, Vec3::ZERO); TRIS];
    let builder = Builder::sah();
    let light = Vec3::new(-5.0, 7.0, -1.0);

    let mut frames = [Frame::new(), Frame::new()];
    let mut node_counts = [0; 2];
    let before = allocations();
    for (i, (frame, sphere_x)) in frames.iter_mut().zip([-1.4, 0.6]).enumerate() {
        scene(Vec3::new(sphere_x, 1.3, 0.5), &mut tris);
        // Loading clears the arena and keeps its memory; the build writes into `bvh`'s nodes.
        arena.load_triangles(&tris)?;
        let stats = builder.build_into(&mut arena, &mut bvh)?;
        node_counts[i] = stats.nodes;
        frame.render(&bvh, &tris, light)?;
    }
    let made = allocations().0 - before.0;
    if made != 0 {
        return Err(format!("building and rendering made {made} allocations").into());
    }

    for y in 0..HEIGHT {
        let left = std::str::from_utf8(&frames[0].image[y])?;
        let right = std::str::from_utf8(&frames[1].image[y])?;
        println!("|{left}|{right}|");
    }
    let pixels = (WIDTH * HEIGHT) as f64;
    for (i, f) in frames.iter().enumerate() {
        println!(
            "frame {i}: {} nodes; camera rays {:.1} nodes and {:.1} triangles each, shadow rays \
             {:.1} and {:.1} ({} of {} surface pixels in shadow)",
            node_counts[i],
            f64::from(f.camera.inner_nodes) / pixels,
            f64::from(f.camera.triangles) / pixels,
            f64::from(f.shadow.inner_nodes) / f64::from(f.hits.max(1)),
            f64::from(f.shadow.triangles) / f64::from(f.hits.max(1)),
            f.shadowed,
            f.hits
        );
    }
    println!(
        "{TRIS} triangles; arena and tree sized once ({} allocations, {:.1} KiB); 2 builds and \
         {} rays made 0 allocations; every pixel equals brute force",
        setup.0,
        setup.1 as f64 / 1024.0,
        frames
            .iter()
            .map(|f| WIDTH * HEIGHT + f.hits as usize)
            .sum::<usize>()
    );
    Ok(())
}

impl Frame {
    fn new() -> Self {
        Self {
            image: [[b' '; WIDTH]; HEIGHT],
            camera: TraversalStats::default(),
            shadow: TraversalStats::default(),
            hits: 0,
            shadowed: 0,
        }
    }

    /// Renders the frame: per pixel a camera ray (closest hit), and from its hit a shadow ray to
    /// the light (any hit), shaded by the cosine to the light. Allocates nothing; fails when an
    /// answer differs from brute force.
    fn render(&mut self, bvh: &Bvh, tris: &[Triangle], light: Vec3) -> Result<(), &'static str> {
        let eye = Vec3::new(0.0, 3.5, -6.5);
        let forward = (Vec3::new(0.7, 0.3, 1.0) - eye).normalize();
        let right = Vec3::Y.cross(forward).normalize();
        let up = forward.cross(right);
        let (tan_x, tan_y) = (0.55, 0.5);
        for (y, row) in self.image.iter_mut().enumerate() {
            for (x, pixel) in row.iter_mut().enumerate() {
                let u = (2.0 * (x as f32 + 0.5) / WIDTH as f32 - 1.0) * tan_x;
                let v = (1.0 - 2.0 * (y as f32 + 0.5) / HEIGHT as f32) * tan_y;
                let ray = Ray::new(eye, forward + right * u + up * v).map_err(|_| "bad ray")?;
                let hit = bvh.closest_hit_with_stats(&ray, tris, &mut self.camera);
                if hit != brute_force::closest_hit(&ray, tris) {
                    return Err("a camera ray's closest hit differs from brute force");
                }
                let Some(hit) = hit else {
                    *pixel = b' ';
                    continue;
                };
                self.hits += 1;
                let p = ray.at(hit.t);
                let t = &tris[hit.triangle as usize];
                let mut n = (t.v1 - t.v0).cross(t.v2 - t.v0).normalize_or_zero();
                if n.dot(ray.dir) > 0.0 {
                    n = -n;
                }
                // Parametric shadow segment: t = 1 is the light; t_min keeps it off its triangle.
                let shadow =
                    Ray::segment(p, light - p, 1e-4, 1.0 - 1e-4).map_err(|_| "bad shadow ray")?;
                let blocked = bvh.any_hit_with_stats(&shadow, tris, &mut self.shadow);
                if blocked != brute_force::any_hit(&shadow, tris) {
                    return Err("a shadow ray's any hit differs from brute force");
                }
                self.shadowed += u32::from(blocked);
                let lit = if blocked {
                    0.0
                } else {
                    n.dot((light - p).normalize()).max(0.0)
                };
                let brightness = 0.12 + 0.88 * lit;
                let level = (brightness * (RAMP.len() - 1) as f32 + 0.5) as usize;
                *pixel = RAMP[level.clamp(1, RAMP.len() - 1)];
            }
        }
        Ok(())
    }
}

/// Writes the scene into `out` (exactly [`TRIS`] triangles): a sphere at `center`, a floor and
/// a box.
fn scene(center: Vec3, out: &mut [Triangle; TRIS]) {
    let mut w = Writer { out, len: 0 };
    let radius = 1.3;
    let point = |i: usize, j: usize| {
        let theta = core::f32::consts::PI * j as f32 / STACKS as f32;
        let phi = core::f32::consts::TAU * i as f32 / SLICES as f32;
        let (st, ct) = (libm::sinf(theta), libm::cosf(theta));
        center + radius * Vec3::new(st * libm::cosf(phi), ct, st * libm::sinf(phi))
    };
    for j in 0..STACKS {
        for i in 0..SLICES {
            let (a, b) = (point(i, j), point(i + 1, j));
            let (c, d) = (point(i + 1, j + 1), point(i, j + 1));
            if j > 0 {
                w.push(Triangle::new(a, b, c));
            }
            if j + 1 < STACKS {
                w.push(Triangle::new(a, c, d));
            }
        }
    }
    let cell = 16.0 / FLOOR as f32;
    for j in 0..FLOOR {
        for i in 0..FLOOR {
            let c = Vec3::new(-8.0 + cell * i as f32, 0.0, -9.0 + cell * j as f32);
            w.quad(c, Vec3::X * cell, Vec3::Z * cell);
        }
    }
    let (lo, size) = (Vec3::new(2.2, 0.0, 1.0), Vec3::new(1.6, 2.4, 1.6));
    let (x, y, z) = (size.x * Vec3::X, size.y * Vec3::Y, size.z * Vec3::Z);
    let hi = lo + size;
    for (c, u, v) in [
        (lo, x, y),
        (lo, z, x),
        (lo, y, z),
        (hi, -y, -x),
        (hi, -x, -z),
        (hi, -z, -y),
    ] {
        w.quad(c, u, v);
    }
    assert_eq!(w.len, TRIS, "TRIS must count the scene's triangles");
}

/// Appends triangles to a fixed array.
struct Writer<'a> {
    out: &'a mut [Triangle; TRIS],
    len: usize,
}

impl Writer<'_> {
    fn push(&mut self, t: Triangle) {
        self.out[self.len] = t;
        self.len += 1;
    }

    /// The parallelogram from `c` along `u` and `v`, as two triangles.
    fn quad(&mut self, c: Vec3, u: Vec3, v: Vec3) {
        self.push(Triangle::new(c, c + u, c + u + v));
        self.push(Triangle::new(c, c + u + v, c + v));
    }
}
