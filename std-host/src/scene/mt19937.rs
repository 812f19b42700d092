//! The 32-bit Mersenne Twister (`std::mt19937`), so the thesis's C++ random scenes can be
//! regenerated bit for bit, and the C++ library's way of turning its output into floats.

/// `std::mt19937` (Matsumoto and Nishimura 1998) with the C++ standard's seeding.
#[derive(Clone, Debug)]
pub struct Mt19937 {
    state: [u32; Self::N],
    index: usize,
}

impl Mt19937 {
    const N: usize = 624;
    const M: usize = 397;
    /// `std::mt19937::default_seed`.
    pub const DEFAULT_SEED: u32 = 5489;

    /// A generator seeded as `std::mt19937 gen(seed)`.
    pub fn new(seed: u32) -> Self {
        let mut state = [0u32; Self::N];
        state[0] = seed;
        for i in 1..Self::N {
            let prev = state[i - 1];
            state[i] = 1_812_433_253u32
                .wrapping_mul(prev ^ (prev >> 30))
                .wrapping_add(i as u32);
        }
        Self {
            state,
            index: Self::N,
        }
    }

    /// The next 32-bit output (`gen()`).
    pub fn next_u32(&mut self) -> u32 {
        if self.index >= Self::N {
            self.twist();
        }
        let mut y = self.state[self.index];
        self.index += 1;
        y ^= y >> 11;
        y ^= (y << 7) & 0x9d2c_5680;
        y ^= (y << 15) & 0xefc6_0000;
        y ^ (y >> 18)
    }

    fn twist(&mut self) {
        for k in 0..Self::N {
            let y = (self.state[k] & 0x8000_0000) | (self.state[(k + 1) % Self::N] & 0x7fff_ffff);
            let mag = if y & 1 == 1 { 0x9908_b0df } else { 0 };
            self.state[k] = self.state[(k + Self::M) % Self::N] ^ (y >> 1) ^ mag;
        }
        self.index = 0;
    }

    /// libstdc++'s `std::generate_canonical<double, 53>(gen)`: two outputs make one double in
    /// `[0, 1)`, the second one the high word: `(x0 + x1 * 2^32) / 2^64`, clamped below 1.
    pub fn canonical_f64(&mut self) -> f64 {
        const TWO_32: f64 = 4_294_967_296.0;
        let x0 = f64::from(self.next_u32());
        let x1 = f64::from(self.next_u32());
        let r = (x0 + x1 * TWO_32) / (TWO_32 * TWO_32);
        if r >= 1.0 {
            // libstdc++ returns nextafter(1, 0) when rounding reached 1.
            1.0 - f64::EPSILON / 2.0
        } else {
            r
        }
    }

    /// `std::uniform_real_distribution<double>(a, b)(gen)` rounded to `f32`: `a + (b - a) * c` in
    /// double precision. This, not the `<float>` distribution (one output per number), is what
    /// reproduces the thesis's `Random100.obj` and `Random1000.obj` digit for digit.
    pub fn uniform_f32(&mut self, a: f32, b: f32) -> f32 {
        let (a, b) = (f64::from(a), f64::from(b));
        (a + (b - a) * self.canonical_f64()) as f32
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn ten_thousandth_output_of_default_seed() {
        // The C++ standard requires this value ([rand.predef]).
        let mut g = Mt19937::new(Mt19937::DEFAULT_SEED);
        let last = (0..10_000).map(|_| g.next_u32()).last();
        assert_eq!(last, Some(4_123_659_995));
    }

    #[test]
    fn seed_one() {
        let mut g = Mt19937::new(1);
        assert_eq!(g.next_u32(), 1_791_095_845);
        assert_eq!(g.next_u32(), 4_282_876_139);
    }

    #[test]
    fn canonical_in_unit_interval() {
        let mut g = Mt19937::new(7);
        for _ in 0..10_000 {
            let c = g.canonical_f64();
            assert!((0.0..1.0).contains(&c));
        }
    }
}
