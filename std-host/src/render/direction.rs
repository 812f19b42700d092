//! Unit directions from vectors of any finite size: a camera's view and up, a spot's axis, a
//! triangle's normal.
//!
//! `Vec3::normalize` squares the vector, so past about 1.8e19 the square overflows f32 and below
//! about 1e-19 it underflows, and a perfectly good direction normalises to zero or to
//! infinities. Only the direction matters here, so such a vector is scaled by its largest
//! component first. Other vectors are not, so that their rays keep their bits.

use rdbvh_core::Vec3;

/// `v` normalised, or zero for the zero vector (`v` finite).
pub(crate) fn unit(v: Vec3) -> Vec3 {
    in_range(v).normalize_or_zero()
}

/// `v`, or `v` over its largest component where its squared length is not a normal f32: the
/// same direction, with a square f32 can hold.
pub(crate) fn in_range(v: Vec3) -> Vec3 {
    let squared = v.length_squared();
    if squared.is_finite() && squared >= f32::MIN_POSITIVE {
        return v;
    }
    let largest = v.abs().max_element();
    if largest == 0.0 {
        v
    } else {
        v / largest
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn every_finite_direction_normalises() {
        for s in [1.0, 3e37, 1e20, 1e-20, 1e-37] {
            let v = Vec3::new(3.0, -4.0, 0.0) * s;
            assert!(
                unit(v).abs_diff_eq(Vec3::new(0.6, -0.8, 0.0), 1e-6),
                "{s}: {}",
                unit(v)
            );
        }
        assert_eq!(unit(Vec3::ZERO), Vec3::ZERO);
        // An ordinary vector keeps `normalize`'s bits.
        let v = Vec3::new(0.3, 1.7, -2.9);
        assert_eq!(unit(v), v.normalize());
        assert_eq!(in_range(v), v);
    }
}
