//! The solid angle of axis-aligned boxes seen from a point, four boxes at a time: the measure of
//! perspective PAH with directions uniform over the sphere.

use wide::f32x4;

/// The solid angles of four boxes seen from the origin; lane `j` spans `lo[k][j]..hi[k][j]` on
/// axis `k`, in coordinates relative to the eye.
///
/// Precondition, per lane: the box lies in an open half-space whose boundary passes through the
/// origin (for perspective PAH: wholly beyond the near plane), so it does not contain the eye and
/// subtends less than a hemisphere. Lanes that break it get an unspecified finite or NaN value;
/// callers mask them.
///
/// Seen from outside, the faces turned towards the eye (one per axis at most: the one at the
/// minimum when the eye is below the slab, at the maximum when above) tile the silhouette. A
/// face is two triangles, and a triangle `a b c` subtends `2 atan2(|a . (b x c)|, |a||b||c| +
/// (a . b)|c| + (a . c)|b| + (b . c)|a|)` (Van Oosterom and Strackee 1983). Half angles add as
/// the arguments of a complex product, and the whole box's half angle is below pi, so the
/// product of all six triangles' numbers never wraps: one `atan2` per box. Unlike sums of corner
/// arctangents, nothing cancels for small, far boxes. The box is first scaled by its largest
/// coordinate's power of two (the angle is scale-free), so the cubed lengths and the product stay
/// far from overflow and underflow at any scene scale.
#[inline(always)]
pub fn box_solid_angle4(lo: &[f32x4; 3], hi: &[f32x4; 3]) -> f32x4 {
    let zero = f32x4::ZERO;
    let c = scaled(lo, hi);
    let sq: [[f32x4; 2]; 3] = core::array::from_fn(|k| [c[k][0] * c[k][0], c[k][1] * c[k][1]]);
    let (mut re, mut im) = (f32x4::ONE, zero);
    for k in 0..3 {
        let Face {
            a1,
            a2,
            below,
            visible,
        } = facing(&c, k);
        if visible.to_bitmask() == 0 {
            continue;
        }
        let d = below.select(c[k][0], -c[k][1]);
        let d2 = d * d;
        let (u1, u2, v1, v2) = (c[a1][0], c[a1][1], c[a2][0], c[a2][1]);
        let (u11, u22, v11, v22) = (sq[a1][0], sq[a1][1], sq[a2][0], sq[a2][1]);
        // The lengths of the face's corners c00, c10, c11, c01 (c10 at u2, v1).
        let (l00, l10) = ((d2 + u11 + v11).sqrt(), (d2 + u22 + v11).sqrt());
        let (l11, l01) = ((d2 + u22 + v22).sqrt(), (d2 + u11 + v22).sqrt());
        let (uu, vv) = (u1 * u2, v1 * v2);
        // Dot products of the corners c00, c10, c11, c01.
        let p00_10 = d2 + uu + v11;
        let p00_11 = d2 + uu + vv;
        let p10_11 = d2 + u22 + vv;
        let p00_01 = d2 + u11 + vv;
        let p11_01 = d2 + uu + v22;
        // |a . (b x c)| of both triangles (c00, c10, c11) and (c00, c11, c01): twice their area in
        // the face's plane times its distance.
        let n = d * (u2 - u1) * (v2 - v1);
        let da = l00 * l10 * l11 + p00_10 * l11 + p00_11 * l10 + p10_11 * l00;
        let db = l00 * l11 * l01 + p00_11 * l01 + p00_01 * l11 + p11_01 * l00;
        // (da + i n)(db + i n), then into the running product; hidden faces multiply by 1.
        let (fr, fi) = (da * db - n * n, n * (da + db));
        let (fr, fi) = (visible.select(fr, f32x4::ONE), visible.select(fi, zero));
        (re, im) = (re * fr - im * fi, re * fi + im * fr);
    }
    // The half angle lies in [0, pi): a rounding-negative imaginary part is +0, so atan2 gives
    // 0 or pi, never -pi.
    let im = im.simd_gt(zero).select(im, zero);
    im.atan2(re) * f32x4::splat(2.0)
}

/// The largest squared ratio of a box's half-diagonal to its centre's distance from the eye (or,
/// for image-plane measures, its depth) below which [`far_field4`] is used: half-diagonal at most
/// 8% of the distance, relative error at most about `1.2e-4` (see there).
pub const FAR_FIELD: f32 = 0.08 * 0.08;

/// A face turned towards the eye, as [`far_field4`]'s rule sees it.
#[derive(Clone, Copy, Debug)]
pub struct FarFace {
    /// The face's centre, eye-relative (and scaled by a power of two: the rules are scale-free).
    pub centre: [f32x4; 3],
    /// The two axes of the face's plane.
    pub axes: [usize; 2],
    /// The squares of the face's half extents along `axes`.
    pub half_sq: [f32x4; 2],
}

/// A box's projected measure far from the eye, four boxes at a time: each face turned towards the
/// eye by the midpoint rule with its second-order correction, `area * d * w`, where `d` is the
/// face's distance from the eye along its normal and `w` what `weight` gives for the face: the
/// integrand `1 / rho^3` at the face's centre, `rho` the centre's distance (solid angle) or depth
/// (image plane), times `1 + (a^2 f_uu + b^2 f_vv) / (6 f)` for half extents `a, b` (the Taylor
/// terms of second order averaged over the face; the first-order ones average to zero). Same
/// precondition as [`box_solid_angle4`].
///
/// Error: what is left is of fourth order in `a / rho` and `b / rho`, largest on faces seen
/// edge-on (about `3 (a^4 + b^4) / rho^4` relative). Within [`FAR_FIELD`] it is at most about
/// `1.2e-4` relative (the uncorrected midpoint rule: `1.3e-2`), which is what the exact formula's
/// f32 rounding allows for a cost estimate anyway, at one square root and one division per face
/// instead of an `atan2` and four square roots.
#[inline(always)]
pub fn far_field4(lo: &[f32x4; 3], hi: &[f32x4; 3], weight: impl Fn(&FarFace) -> f32x4) -> f32x4 {
    let zero = f32x4::ZERO;
    let half = f32x4::splat(0.5);
    let c = scaled(lo, hi);
    let mid: [f32x4; 3] = core::array::from_fn(|k| (c[k][0] + c[k][1]) * half);
    let half_extent: [f32x4; 3] = core::array::from_fn(|k| (c[k][1] - c[k][0]) * half);
    let mut total = zero;
    for k in 0..3 {
        let Face {
            a1,
            a2,
            below,
            visible,
        } = facing(&c, k);
        if visible.to_bitmask() == 0 {
            continue;
        }
        let plane = below.select(c[k][0], c[k][1]);
        let mut centre = mid;
        centre[k] = plane;
        let (a, b) = (half_extent[a1], half_extent[a2]);
        let face = FarFace {
            centre,
            axes: [a1, a2],
            half_sq: [a * a, b * b],
        };
        // The area is 4 a b.
        let term = (a * b * f32x4::splat(4.0)) * plane.abs() * weight(&face);
        total += visible.select(term, zero);
    }
    total
}

/// [`far_field4`] for solid angles: `1 / rho^3` at `rho = |centre|`, whose second derivative along
/// an in-plane axis `u` is `(15 u^2 / rho^2 - 3) / rho^2` times itself.
#[inline(always)]
pub fn box_solid_angle_far4(lo: &[f32x4; 3], hi: &[f32x4; 3]) -> f32x4 {
    far_field4(lo, hi, |f| {
        let p = &f.centre;
        let r2 = p[0] * p[0] + p[1] * p[1] + p[2] * p[2];
        let r = r2.sqrt();
        let inv_r3 = f32x4::ONE / (r2 * r);
        let inv_r2 = inv_r3 * r;
        let [u, v] = f.axes.map(|a| p[a] * p[a]);
        let [a2, b2] = f.half_sq;
        let five = f32x4::splat(5.0);
        let curve = (five * (a2 * u + b2 * v) * inv_r2 - (a2 + b2)) * inv_r2 * f32x4::splat(0.5);
        inv_r3 * (f32x4::ONE + curve)
    })
}

/// The face of the boxes on axis `k` that the eye sees, one per axis at most: the one at the
/// minimum where the eye is below the slab, at the maximum where above, none where inside it.
struct Face {
    /// The other two axes, in cyclic order.
    a1: usize,
    a2: usize,
    /// Lanes whose eye is below the slab (they see the face at the minimum).
    below: f32x4,
    /// Lanes that see a face on this axis at all.
    visible: f32x4,
}

/// The face on axis `k` of the scaled bounds `c` (`visible` is empty when no lane sees one).
#[inline(always)]
fn facing(c: &[[f32x4; 2]; 3], k: usize) -> Face {
    let below = c[k][0].simd_gt(f32x4::ZERO);
    Face {
        a1: (k + 1) % 3,
        a2: (k + 2) % 3,
        below,
        visible: below | c[k][1].simd_lt(f32x4::ZERO),
    }
}

/// The bounds scaled by the power of two of their largest magnitude (the exponent bits alone),
/// so scaling rounds nothing, differences of bounds keep every bit, and cubes of lengths stay far
/// from overflow and underflow at any scene scale. `[k][0]` the minimum on axis `k`, `[k][1]` the
/// maximum. Both measures here are scale-free.
#[inline(always)]
fn scaled(lo: &[f32x4; 3], hi: &[f32x4; 3]) -> [[f32x4; 2]; 3] {
    let largest = (0..3).fold(f32x4::splat(f32::MIN_POSITIVE), |m, k| {
        m.fast_max(lo[k].abs()).fast_max(hi[k].abs())
    });
    let scale = f32x4::ONE / (largest & f32x4::splat(f32::INFINITY));
    core::array::from_fn(|k| [lo[k] * scale, hi[k] * scale])
}

#[cfg(test)]
pub(crate) mod tests {
    use super::*;
    use crate::random::Pcg32;

    /// The solid angle of triangle `a b c` from the origin, in f64.
    fn triangle(a: [f64; 3], b: [f64; 3], c: [f64; 3]) -> f64 {
        let dot = |p: [f64; 3], q: [f64; 3]| p[0] * q[0] + p[1] * q[1] + p[2] * q[2];
        let len = |p: [f64; 3]| dot(p, p).sqrt();
        let cross = [
            b[1] * c[2] - b[2] * c[1],
            b[2] * c[0] - b[0] * c[2],
            b[0] * c[1] - b[1] * c[0],
        ];
        let num = dot(a, cross).abs();
        let den =
            len(a) * len(b) * len(c) + dot(a, b) * len(c) + dot(a, c) * len(b) + dot(b, c) * len(a);
        2.0 * num.atan2(den)
    }

    /// The faces of the box `lo..hi` turned towards the origin (one per axis at most), each as
    /// its corners in order around it, in f64.
    pub(crate) fn front_faces_f64(
        lo: [f64; 3],
        hi: [f64; 3],
    ) -> impl Iterator<Item = [[f64; 3]; 4]> {
        (0..3).filter_map(move |k| {
            let side = if lo[k] > 0.0 {
                lo[k]
            } else if hi[k] < 0.0 {
                hi[k]
            } else {
                return None;
            };
            let (a1, a2) = ((k + 1) % 3, (k + 2) % 3);
            Some([(lo, lo), (hi, lo), (hi, hi), (lo, hi)].map(|(u, v)| {
                let mut q = [0.0; 3];
                (q[k], q[a1], q[a2]) = (side, u[a1], v[a2]);
                q
            }))
        })
    }

    /// The box's solid angle in f64: every face turned towards the origin as two triangles.
    pub(crate) fn reference(lo: [f64; 3], hi: [f64; 3]) -> f64 {
        front_faces_f64(lo, hi)
            .map(|[c00, c10, c11, c01]| triangle(c00, c10, c11) + triangle(c00, c11, c01))
            .sum()
    }

    #[test]
    fn matches_the_f64_triangle_sum_over_scales_and_positions() {
        let mut rng = Pcg32::new(5);
        for scale in [1e-20f32, 1e-3, 1.0, 1e3, 1e20] {
            for _ in 0..if cfg!(miri) { 4 } else { 400 } {
                // Boxes in front of the eye (z > 0), some small and far, some wide and close.
                let lanes: [([f32; 3], [f32; 3]); 4] = core::array::from_fn(|_| {
                    let size = if rng.range(0.0, 1.0) < 0.5 { 1e-3 } else { 5.0 };
                    let lo = [
                        rng.range(-4.0, 4.0),
                        rng.range(-4.0, 4.0),
                        rng.range(0.01, 30.0),
                    ];
                    let hi = core::array::from_fn(|k| lo[k] + size * rng.range(0.0, 1.0));
                    (lo.map(|x| x * scale), hi.map(|x: f32| x * scale))
                });
                let lo = core::array::from_fn(|k| f32x4::from(lanes.map(|l| l.0[k])));
                let hi = core::array::from_fn(|k| f32x4::from(lanes.map(|l| l.1[k])));
                let got = box_solid_angle4(&lo, &hi).to_array();
                for (j, (l, h)) in lanes.iter().enumerate() {
                    let expect = reference(l.map(f64::from), h.map(f64::from));
                    let err = (f64::from(got[j]) - expect).abs();
                    assert!(
                        err <= 1e-5 * expect + 1e-30,
                        "scale {scale} box {l:?}..{h:?}: {} vs {expect}",
                        got[j]
                    );
                }
            }
        }
    }

    #[test]
    fn far_field_stays_within_its_bound() {
        let mut rng = Pcg32::new(9);
        let mut worst = 0.0f64;
        for _ in 0..if cfg!(miri) { 40 } else { 4000 } {
            // A box whose half-diagonal is at most 8% of its centre's distance, in any direction
            // in front of the eye, with any aspect ratio.
            let dir = [
                rng.range(-1.0, 1.0),
                rng.range(-1.0, 1.0),
                rng.range(0.05, 1.0),
            ];
            let dist = rng.range(0.1, 1e3);
            let norm = (dir[0] * dir[0] + dir[1] * dir[1] + dir[2] * dir[2]).sqrt();
            let centre: [f32; 3] = core::array::from_fn(|k| dir[k] / norm * dist);
            // Any aspect ratio, flat and long boxes too (their edge-on faces err the most).
            let power = if rng.range(0.0, 1.0) < 0.5 { 1.0 } else { 4.0 };
            let shape: [f32; 3] = core::array::from_fn(|_| libm::powf(rng.range(0.0, 1.0), power));
            let len = (shape[0] * shape[0] + shape[1] * shape[1] + shape[2] * shape[2]).sqrt();
            // Most near the threshold, where the error is largest.
            let half_diag = dist * (FAR_FIELD.sqrt() * libm::powf(rng.range(0.01, 1.0), 0.2));
            let h: [f32; 3] = core::array::from_fn(|k| shape[k] / len * half_diag);
            let (l, u): ([f32; 3], [f32; 3]) = (
                core::array::from_fn(|k| centre[k] - h[k]),
                core::array::from_fn(|k| centre[k] + h[k]),
            );
            if l[2] <= 0.0 {
                continue;
            }
            let lo = l.map(f32x4::splat);
            let hi = u.map(f32x4::splat);
            let got = f64::from(box_solid_angle_far4(&lo, &hi).to_array()[0]);
            let expect = reference(l.map(f64::from), u.map(f64::from));
            worst = worst.max((got - expect).abs() / expect);
        }
        assert!(worst <= 1.5e-4, "worst relative error {worst}");
        // The bound is not vacuous: boxes near the threshold do show the rule's error (Miri runs
        // too few boxes to be sure to meet one).
        assert!(cfg!(miri) || worst > 1e-5, "worst relative error {worst}");
    }

    #[test]
    fn a_cube_face_on_is_a_sixth_of_the_sphere() {
        // Only the face at z = 1 is turned towards the eye, and it is one face of the cube
        // [-1, 1]^3 seen from that cube's centre: a sixth of the sphere.
        let lo = [f32x4::splat(-1.0), f32x4::splat(-1.0), f32x4::splat(1.0)];
        let hi = [f32x4::splat(1.0), f32x4::splat(1.0), f32x4::splat(3.0)];
        let got = box_solid_angle4(&lo, &hi).to_array()[0];
        assert!(
            (got - 4.0 * core::f32::consts::PI / 6.0).abs() < 1e-6,
            "{got}"
        );
    }
}
