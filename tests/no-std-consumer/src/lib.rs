//! A bare-metal consumer of `rdbvh-core`: no `std`, its own panic handler, a bump allocator over a
//! static buffer, and one C entry point that builds a BVH over a few triangles and traces rays
//! through it. It links only if the core's build and traversal compile without `std`, and it
//! cannot pass as an empty crate: the entry point calls the builder and both traversals.
#![no_std]

extern crate alloc;

use core::alloc::{GlobalAlloc, Layout};
use core::cell::UnsafeCell;
use core::sync::atomic::{AtomicUsize, Ordering};

use rdbvh_core::brute_force;
use rdbvh_core::builder::{BuildArena, Builder};
use rdbvh_core::bvh::Bvh;
use rdbvh_core::geometry::{Ray, Triangle};
use rdbvh_core::Vec3;

/// Bytes the bump allocator can hand out.
const HEAP_SIZE: usize = 64 * 1024;

/// A bump allocator over a static buffer: allocation moves a cursor, freeing does nothing. Enough
/// for one build on a microcontroller; returns null (an allocation error) when the buffer is spent.
struct Bump {
    heap: UnsafeCell<[u8; HEAP_SIZE]>,
    next: AtomicUsize,
}

// SAFETY: the cursor is advanced atomically, so no two allocations share bytes.
unsafe impl Sync for Bump {}

// SAFETY: every returned block lies inside `heap`, is aligned as asked, and is never handed out
// twice; `dealloc` is a no-op, which `GlobalAlloc` allows.
unsafe impl GlobalAlloc for Bump {
    unsafe fn alloc(&self, layout: Layout) -> *mut u8 {
        let base = self.heap.get() as usize;
        let mut current = self.next.load(Ordering::Relaxed);
        loop {
            let start = (base + current).next_multiple_of(layout.align()) - base;
            let Some(end) = start.checked_add(layout.size()).filter(|&e| e <= HEAP_SIZE) else {
                return core::ptr::null_mut();
            };
            match self.next.compare_exchange_weak(
                current,
                end,
                Ordering::Relaxed,
                Ordering::Relaxed,
            ) {
                Ok(_) => return (base + start) as *mut u8,
                Err(seen) => current = seen,
            }
        }
    }

    unsafe fn dealloc(&self, _ptr: *mut u8, _layout: Layout) {}
}

#[global_allocator]
static ALLOCATOR: Bump = Bump {
    heap: UnsafeCell::new([0; HEAP_SIZE]),
    next: AtomicUsize::new(0),
};

#[panic_handler]
fn panic(_info: &core::panic::PanicInfo) -> ! {
    loop {
        core::hint::spin_loop();
    }
}

/// Result bits of [`rdbvh_demo`].
pub const CLOSEST_OK: u32 = 1;
/// The any-hit query agreed with the oracle.
pub const ANY_OK: u32 = 2;
/// The arena build agreed with the allocating build.
pub const ARENA_OK: u32 = 4;

/// Builds a BVH over a small staircase of quads, traces a fan of rays with closest hit and any
/// hit, and compares every answer with the brute-force oracle. Returns the `*_OK` bits of the
/// checks that passed (7 when all did), or 0 when a build failed.
#[no_mangle]
pub extern "C" fn rdbvh_demo() -> u32 {
    let mut tris = [Triangle::new(Vec3::ZERO, Vec3::ZERO, Vec3::ZERO); 16];
    for (i, pair) in tris.chunks_exact_mut(2).enumerate() {
        let z = 1.0 + i as f32;
        let x = i as f32 - 4.0;
        let (a, b, c, d) = (
            Vec3::new(x, -1.0, z),
            Vec3::new(x + 1.5, -1.0, z),
            Vec3::new(x + 1.5, 1.0, z),
            Vec3::new(x, 1.0, z),
        );
        pair[0] = Triangle::new(a, b, c);
        pair[1] = Triangle::new(a, c, d);
    }
    let Ok(bvh) = Builder::sah().build(&tris) else {
        return 0;
    };
    let mut arena = BuildArena::with_capacity(tris.len());
    let mut again = Bvh::with_capacity(tris.len());
    if arena.load_triangles(&tris).is_err()
        || Builder::lsph().build_into(&mut arena, &mut again).is_err()
    {
        return 0;
    }

    let mut result = CLOSEST_OK | ANY_OK | ARENA_OK;
    for i in 0..64 {
        let a = i as f32 * 0.1;
        let dir = Vec3::new(libm_free_sin(a), 0.1, 1.0);
        let Ok(ray) = Ray::segment(Vec3::new(0.0, 0.0, -1.0), dir, 0.0, 6.0) else {
            return 0;
        };
        let expect = brute_force::closest_hit(&ray, &tris);
        if bvh.closest_hit(&ray, &tris) != expect {
            result &= !CLOSEST_OK;
        }
        if bvh.any_hit(&ray, &tris) != brute_force::any_hit(&ray, &tris) {
            result &= !ANY_OK;
        }
        if again.closest_hit(&ray, &tris) != expect {
            result &= !ARENA_OK;
        }
    }
    result
}

/// A rough `sin` without `std` or `libm`, to fan the rays: a cubic on `[-pi/2, pi/2]` is plenty.
fn libm_free_sin(x: f32) -> f32 {
    use core::f32::consts::{FRAC_PI_2, PI, TAU};
    let x = (x % TAU) - PI;
    let x = if x > FRAC_PI_2 {
        PI - x
    } else if x < -FRAC_PI_2 {
        -PI - x
    } else {
        x
    };
    x - x * x * x / 6.0
}
