//! The wide traversals compiled for AVX2, for the run-time dispatch of [`super::dispatch`]: 8
//! child lanes in one `__m256` register ([`Avx8`]), and entry points whose code (the walk, the
//! inlined 4-wide triangle tests) is generated with AVX2, BMI and LZCNT enabled.
//!
//! The arithmetic is the portable path's, operation for operation: a separate multiply and add
//! (no fused multiply-add, which rounds once and would move hits off the scalar test's and brute
//! force's answers), the same operand order in `max`/`min` (so NaN lanes keep the accumulator),
//! the same comparison. Only the encoding and the register width change, so the answers and the
//! statistics are identical bit for bit.

use core::arch::x86_64::{
    __m256, _mm256_add_ps, _mm256_andnot_ps, _mm256_cmp_ps, _mm256_loadu_ps, _mm256_max_ps,
    _mm256_min_ps, _mm256_movemask_ps, _mm256_mul_ps, _mm256_set1_ps, _mm256_storeu_ps,
    _mm256_sub_ps, _CMP_LE_OQ,
};
use core::ops::{Add, Mul, Sub};

use super::wide::{WideBvh8, WideBvhN};
use super::wide_traverse::{
    wide_stack, ChildLanes, Counters, Lanes, LeafVisitor, PendingArray, Width,
};
use super::Hit;
use crate::geometry::{Ray, Triangle4};

/// Eight child lanes in one AVX register.
///
/// Crate-private on purpose: its methods execute AVX instructions, so a value may only exist
/// inside the entry points below, which run only once [`super::dispatch`] has seen AVX2 on the
/// CPU. That is what makes the `unsafe` blocks of its methods sound.
#[derive(Clone, Copy)]
#[repr(transparent)]
pub(crate) struct Avx8(__m256);

impl Add for Avx8 {
    type Output = Self;
    #[inline(always)]
    fn add(self, rhs: Self) -> Self {
        // SAFETY: AVX is present (see `Avx8`).
        Self(unsafe { _mm256_add_ps(self.0, rhs.0) })
    }
}

impl Sub for Avx8 {
    type Output = Self;
    #[inline(always)]
    fn sub(self, rhs: Self) -> Self {
        // SAFETY: AVX is present (see `Avx8`).
        Self(unsafe { _mm256_sub_ps(self.0, rhs.0) })
    }
}

impl Mul for Avx8 {
    type Output = Self;
    #[inline(always)]
    fn mul(self, rhs: Self) -> Self {
        // SAFETY: AVX is present (see `Avx8`).
        Self(unsafe { _mm256_mul_ps(self.0, rhs.0) })
    }
}

impl ChildLanes<8> for Avx8 {
    #[inline(always)]
    fn splat(v: f32) -> Self {
        // SAFETY: AVX is present (see `Avx8`).
        Self(unsafe { _mm256_set1_ps(v) })
    }
    #[inline(always)]
    fn load(row: [f32; 8]) -> Self {
        // SAFETY: AVX is present (see `Avx8`); the load reads the array's 32 bytes, unaligned.
        Self(unsafe { _mm256_loadu_ps(row.as_ptr()) })
    }
    /// `vmaxps(t, acc)` returns its second operand when either is NaN: the accumulator, as the
    /// portable path's `maxps` halves do.
    #[inline(always)]
    fn keep_max(self, t: Self) -> Self {
        // SAFETY: AVX is present (see `Avx8`).
        Self(unsafe { _mm256_max_ps(t.0, self.0) })
    }
    #[inline(always)]
    fn keep_min(self, t: Self) -> Self {
        // SAFETY: AVX is present (see `Avx8`).
        Self(unsafe { _mm256_min_ps(t.0, self.0) })
    }
    #[inline(always)]
    fn abs(self) -> Self {
        // SAFETY: AVX is present (see `Avx8`). Clears the sign bit, as `f32x8::abs` does.
        Self(unsafe { _mm256_andnot_ps(_mm256_set1_ps(-0.0), self.0) })
    }
    #[inline(always)]
    fn le_bitmask(self, other: Self) -> u32 {
        // SAFETY: AVX is present (see `Avx8`). Ordered: false for NaN, as `simd_le` is.
        unsafe { _mm256_movemask_ps(_mm256_cmp_ps::<_CMP_LE_OQ>(self.0, other.0)) as u32 }
    }
    #[inline(always)]
    fn to_array(self) -> [f32; 8] {
        let mut out = [0.0; 8];
        // SAFETY: AVX is present (see `Avx8`); the store writes the array's 32 bytes, unaligned.
        unsafe { _mm256_storeu_ps(out.as_mut_ptr(), self.0) };
        out
    }
}

/// The 8-wide lanes of the AVX2 entry points: [`Avx8`] and the portable path's stack.
pub(crate) struct Avx2Lanes8;

impl Lanes<8> for Avx2Lanes8 {
    type V = Avx8;
    type Pending = PendingArray<{ wide_stack(8) }>;
}

/// Whether 4-wide trees take the AVX2 entry points too: no. Their lanes stay `f32x4` (one SSE
/// register either way), so all AVX2 brings them is VEX encoding and BMI in the walk and the
/// triangle tests, and `peers` measured that within noise (-1.4% to +2.4%, bunny and Sponza,
/// best of 3-4 interleaved runs), against +6-15% for 8-wide trees. The entry points still
/// compile for them, and the tests compare them too.
pub(crate) const WIDE4: bool = false;

impl<const W: usize> WideBvhN<W> {
    /// This tree as the 8-wide type, when `W` is 8.
    #[inline(always)]
    fn as_wide8(&self) -> Option<&WideBvh8> {
        // SAFETY: with `W == 8` the two are the same type.
        (W == 8).then(|| unsafe { &*(self as *const Self).cast::<WideBvh8>() })
    }
}

// The entry points: one per query, each a whole traversal inlined into a function compiled with
// AVX2. FMA is enabled for the code generator's freedom only: nothing here asks for a fused
// operation, and LLVM contracts a multiply and an add only under fast-math flags, which Rust never
// sets.

/// [`WideBvhN::closest_walk`] compiled for AVX2, 8-wide on [`Avx8`].
///
/// # Safety
///
/// The CPU must have AVX2, FMA, BMI1, BMI2, LZCNT and POPCNT (see [`super::dispatch`]).
#[target_feature(enable = "avx,avx2,fma,bmi1,bmi2,lzcnt,popcnt")]
pub(crate) unsafe fn closest<const W: usize>(
    bvh: &WideBvhN<W>,
    ray: &Ray,
    stats: &mut impl Counters,
) -> Option<Hit>
where
    Width<W>: Lanes<W>,
{
    match bvh.as_wide8() {
        Some(bvh) => bvh.closest_walk::<Avx2Lanes8>(ray, stats),
        None => bvh.closest_walk::<Width<W>>(ray, stats),
    }
}

/// [`WideBvhN::walk`] from `root` with an any-hit visitor and leaves in `tris`, compiled for
/// AVX2.
///
/// # Safety
///
/// As for [`closest`].
#[target_feature(enable = "avx,avx2,fma,bmi1,bmi2,lzcnt,popcnt")]
pub(crate) unsafe fn any<const W: usize>(
    bvh: &WideBvhN<W>,
    root: u32,
    tris: &[Triangle4],
    ray: &Ray,
    stats: &mut impl Counters,
) -> bool
where
    Width<W>: Lanes<W>,
{
    match bvh.as_wide8() {
        Some(bvh) => bvh.any_walk::<Avx2Lanes8>(root, tris, ray, stats),
        None => bvh.any_walk::<Width<W>>(root, tris, ray, stats),
    }
}

/// [`WideBvhN::walk_in`] from node `root` over the blocks `tris` with the caller's visitor,
/// compiled for AVX2.
///
/// # Safety
///
/// As for [`closest`].
#[target_feature(enable = "avx,avx2,fma,bmi1,bmi2,lzcnt,popcnt")]
pub(crate) unsafe fn traverse<const W: usize, V: LeafVisitor>(
    bvh: &WideBvhN<W>,
    root: u32,
    tris: &[Triangle4],
    ray: &Ray,
    visitor: &mut V,
    stats: &mut impl Counters,
) -> bool
where
    Width<W>: Lanes<W>,
{
    match bvh.as_wide8() {
        Some(bvh) => bvh.walk_in::<Avx2Lanes8, V>(root, tris, ray, visitor, stats),
        None => bvh.walk_in::<Width<W>, V>(root, tris, ray, visitor, stats),
    }
}

#[cfg(test)]
mod tests {
    use alloc::vec::Vec;

    use glam::Vec3;

    use super::*;
    use crate::builder::Builder;
    use crate::bvh::{HitCount, SimdLevel, TraversalStats, WideBvh};
    use crate::geometry::Triangle;
    use crate::random::Pcg32;

    /// A hit as bits, so that the comparison is exact (`-0.0` against `0.0`, NaN included).
    fn bits(h: Option<Hit>) -> Option<(u32, u32, u32, u32)> {
        h.map(|h| (h.t.to_bits(), h.triangle, h.u.to_bits(), h.v.to_bits()))
    }

    /// A soup with axis-aligned walls (rays along their planes give NaN slab lanes) and a box of
    /// quads, so that rays start inside boxes and hit faces that share edges.
    fn scene(n: usize, seed: u64) -> Vec<Triangle> {
        let mut tris = crate::test_scenes::soup(n, seed, -10.0, 10.0, 1.5);
        let c = |x, y, z| Vec3::new(x, y, z);
        tris.push(Triangle::new(
            c(-20.0, -20.0, 0.0),
            c(20.0, -20.0, 0.0),
            c(0.0, 20.0, 0.0),
        ));
        tris.push(Triangle::new(
            c(4.0, -20.0, -20.0),
            c(4.0, 20.0, -20.0),
            c(4.0, 0.0, 20.0),
        ));
        for k in 0..3 {
            for s in [-6.0, 6.0] {
                let mut q = [
                    c(-6.0, -6.0, 0.0),
                    c(6.0, -6.0, 0.0),
                    c(6.0, 6.0, 0.0),
                    c(-6.0, 6.0, 0.0),
                ];
                for p in &mut q {
                    *p = p.with_z(s);
                    *p = Vec3::new(p[(3 - k) % 3], p[(4 - k) % 3], p[(5 - k) % 3]);
                }
                tris.push(Triangle::new(q[0], q[1], q[2]));
                tris.push(Triangle::new(q[0], q[2], q[3]));
            }
        }
        tris
    }

    /// Random rays: from outside and inside the scene, with zero direction components, along the
    /// walls' planes, and segments with `t_min > 0` and a finite `t_max`.
    fn rays(count: usize, seed: u64) -> Vec<Ray> {
        let mut rng = Pcg32::new(seed);
        let mut out = Vec::with_capacity(count);
        for i in 0..count {
            let mut v = |s: f32| Vec3::new(rng.range(-s, s), rng.range(-s, s), rng.range(-s, s));
            let mut o = v(if i % 2 == 0 { 14.0 } else { 5.0 });
            let mut d = v(1.0);
            match i % 7 {
                0 => d.y = 0.0,
                1 => (d.x, d.z) = (0.0, -0.0),
                2 => (o.z, d.z) = (0.0, 0.0),
                3 => (o.x, d.x) = (4.0, 0.0),
                4 => (o.x, o.y) = (6.0, -6.0),
                _ => {}
            }
            let (t_min, t_max) = match i % 5 {
                0 => (rng.range(0.0, 8.0), f32::INFINITY),
                1 => (rng.range(0.0, 4.0), rng.range(4.0, 20.0)),
                _ => (0.0, f32::INFINITY),
            };
            if let Ok(r) = Ray::segment(o, d, t_min, t_max) {
                out.push(r);
            }
        }
        out
    }

    fn cpu_has_avx2() -> bool {
        !cfg!(miri) && super::super::dispatch::cpu_has_avx2()
    }

    /// Every query of a `W`-wide tree, baseline against AVX2, bit for bit with statistics.
    fn agree<const W: usize>(wide: &WideBvhN<W>, rays: &[Ray]) -> u32
    where
        Width<W>: Lanes<W>,
    {
        // The same rays moved onto a plane of some child's box with a zero direction component
        // along it: there the slab values are NaN (`0 * inf`), which both paths must ignore.
        let mut rng = Pcg32::new(7);
        let on_planes: Vec<Ray> = rays
            .iter()
            .filter_map(|r| {
                let node = &wide.nodes[rng.next_u32() as usize % wide.nodes.len()];
                let b = node.child_bounds(rng.next_u32() as usize % node.arity());
                let k = rng.next_u32() as usize % 3;
                let (mut o, mut d) = (r.origin, r.dir);
                o[k] = if rng.next_u32() & 1 == 0 {
                    b.min[k]
                } else {
                    b.max[k]
                };
                d[k] = 0.0;
                Ray::segment(o, d, r.t_min, r.t_max).ok()
            })
            .collect();
        let mut hits = 0;
        for (i, r) in rays.iter().chain(&on_planes).enumerate() {
            let (mut s0, mut s1) = (TraversalStats::default(), TraversalStats::default());
            let base = wide.closest_from_root(r, &mut s0);
            // SAFETY: the caller checked the CPU.
            let avx = unsafe { closest(wide, r, &mut s1) };
            assert_eq!(bits(base), bits(avx), "closest, ray {i}: {r:?}");
            assert_eq!(s0, s1, "closest stats, ray {i}");
            hits += u32::from(base.is_some());

            let (mut s0, mut s1) = (TraversalStats::default(), TraversalStats::default());
            let base = wide.any_from_root(0, wide.triangles(), r, &mut s0);
            // SAFETY: as above.
            let avx = unsafe { any(wide, 0, wide.triangles(), r, &mut s1) };
            assert_eq!((base, s0), (avx, s1), "any, ray {i}");

            let (mut s0, mut s1) = (TraversalStats::default(), TraversalStats::default());
            let (mut c0, mut c1) = (HitCount::new(r), HitCount::new(r));
            wide.walk::<Width<W>, _>(0, r, &mut c0, &mut s0);
            // SAFETY: as above.
            unsafe { traverse(wide, 0, wide.triangles(), r, &mut c1, &mut s1) };
            assert_eq!((c0.hits, s0), (c1.hits, s1), "all hits, ray {i}");
        }
        hits
    }

    #[test]
    fn avx2_entry_points_agree_with_the_baseline_bit_for_bit() {
        if !cpu_has_avx2() {
            return;
        }
        for (n, seed) in [(1, 1), (7, 2), (90, 3), (800, 4), (3000, 5)] {
            let tris = scene(n, seed);
            let bvh = Builder::sah().build(&tris).unwrap();
            let rays = rays(if n > 1000 { 6000 } else { 3000 }, seed + 100);
            let hits = agree(&WideBvh8::from_binary(&bvh, &tris), &rays);
            agree(&WideBvh::from_binary(&bvh, &tris), &rays);
            assert!(
                hits > rays.len() as u32 / 10,
                "{hits} of {} rays hit",
                rays.len()
            );
        }
    }

    #[test]
    fn set_simd_level_switches_and_answers_stay() {
        let tris = scene(500, 9);
        let bvh = Builder::sah().build(&tris).unwrap();
        let wide = WideBvh8::from_binary(&bvh, &tris);
        let rays = rays(500, 10);
        let answers = |w: &WideBvh8| -> Vec<_> {
            rays.iter()
                .map(|r| (bits(w.closest_hit(r)), w.any_hit(r), w.all_hit(r)))
                .collect()
        };
        let before = super::super::simd_level();
        assert_eq!(
            super::super::set_simd_level(SimdLevel::Baseline),
            SimdLevel::Baseline
        );
        let base = answers(&wide);
        let avx = super::super::set_simd_level(SimdLevel::Avx2);
        assert_eq!(
            avx == SimdLevel::Avx2,
            cfg!(feature = "std") && cpu_has_avx2()
        );
        assert_eq!(answers(&wide), base);
        super::super::set_simd_level(before);
    }
}
