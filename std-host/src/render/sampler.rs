//! Counter-based random numbers: each number is a hash of (seed, pixel, sample, dimension), so
//! a pixel's paths do not depend on which thread renders it, in which tile, or in what order. The
//! image is therefore the same for a seed whatever the thread count.

/// The random numbers of one sample of one pixel, addressed by dimension.
#[derive(Clone, Copy, Debug)]
pub struct Sampler {
    key: u64,
}

/// Dimensions of the pixel jitter; each path vertex then takes [`DIMS_PER_VERTEX`] from
/// [`vertex_dim`] on, so that every structure consumes the same numbers for the same path.
pub const DIM_PIXEL_X: u32 = 0;
/// See [`DIM_PIXEL_X`].
pub const DIM_PIXEL_Y: u32 = 1;
/// Numbers per path vertex: light choice, two for the light sample, two for the bounce
/// direction, one for Russian roulette.
pub const DIMS_PER_VERTEX: u32 = 6;

/// The first dimension of path vertex `depth` (0 for the camera ray's hit).
pub const fn vertex_dim(depth: u32) -> u32 {
    2 + DIMS_PER_VERTEX * depth
}

impl Sampler {
    /// The numbers of sample `sample` of pixel `pixel` (row-major index) under `seed`.
    pub fn new(seed: u64, pixel: u64, sample: u32) -> Self {
        let key = mix(mix(mix(seed) ^ pixel) ^ u64::from(sample));
        Self { key }
    }

    /// Dimension `dim` of this sample: a number in `[0, 1)` with 24 random bits, so that every
    /// value is exact in `f32` and below 1.
    #[inline]
    pub fn get(&self, dim: u32) -> f32 {
        let h = mix(self.key ^ u64::from(dim).wrapping_mul(0xD1B5_4A32_D192_ED03));
        (h >> 40) as f32 * (1.0 / (1u64 << 24) as f32)
    }
}

/// SplitMix64's finaliser (Steele, Lea and Flood 2014): a bijection whose every output bit
/// depends on every input bit.
#[inline]
fn mix(x: u64) -> u64 {
    let mut z = x.wrapping_add(0x9E37_79B9_7F4A_7C15);
    z = (z ^ (z >> 30)).wrapping_mul(0xBF58_476D_1CE4_E5B9);
    z = (z ^ (z >> 27)).wrapping_mul(0x94D0_49BB_1331_11EB);
    z ^ (z >> 31)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn numbers_are_in_unit_interval_and_depend_on_every_counter() {
        let s = Sampler::new(7, 12, 3);
        let x = s.get(0);
        assert!((0.0..1.0).contains(&x));
        assert_eq!(x, Sampler::new(7, 12, 3).get(0));
        for other in [
            Sampler::new(8, 12, 3).get(0),
            Sampler::new(7, 13, 3).get(0),
            Sampler::new(7, 12, 4).get(0),
            s.get(1),
        ] {
            assert_ne!(x, other);
        }
    }

    #[test]
    fn numbers_look_uniform() {
        // Mean and variance of 100k numbers, against 1/2 and 1/12, within 1 %.
        let n = 100_000u32;
        let xs: Vec<f64> = (0..n)
            .map(|i| f64::from(Sampler::new(1, u64::from(i), 0).get(5)))
            .collect();
        let mean = xs.iter().sum::<f64>() / f64::from(n);
        let var = xs.iter().map(|x| (x - mean) * (x - mean)).sum::<f64>() / f64::from(n);
        assert!((mean - 0.5).abs() < 0.005, "{mean}");
        assert!((var - 1.0 / 12.0).abs() < 0.001, "{var}");
    }
}
