//! SplitMix64: the one deterministic, platform-independent random stream of poser. The render
//! sampler (`poser::backend::native::sampler::Sampler`), the wave fields ([`crate::waves`])
//! and the benchmark point sets ([`crate::cases`], `poser bench projection`) all draw from
//! it, so the same seed gives the same numbers everywhere.

/// A SplitMix64 stream (Steele, Lea & Flood 2014) from a raw 64-bit state.
#[derive(Debug, Clone)]
pub struct SplitMix64(pub u64);

impl SplitMix64 {
    #[inline]
    pub fn next_u64(&mut self) -> u64 {
        self.0 = self.0.wrapping_add(0x9E37_79B9_7F4A_7C15);
        let mut z = self.0;
        z = (z ^ (z >> 30)).wrapping_mul(0xBF58_476D_1CE4_E5B9);
        z = (z ^ (z >> 27)).wrapping_mul(0x94D0_49BB_1331_11EB);
        z ^ (z >> 31)
    }

    /// Uniform in [0, 1), 53 random bits.
    #[inline]
    pub fn next_f64(&mut self) -> f64 {
        (self.next_u64() >> 11) as f64 * (1.0 / (1u64 << 53) as f64)
    }

    /// Two independent standard normal deviates from two uniforms (Box–Muller).
    #[inline]
    pub fn normal_pair(&mut self) -> (f64, f64) {
        let u1 = 1.0 - self.next_f64(); // (0, 1]: the logarithm stays finite
        let u2 = self.next_f64();
        let r = (-2.0 * u1.ln()).sqrt();
        let a = std::f64::consts::TAU * u2;
        (r * a.cos(), r * a.sin())
    }

    /// One standard normal deviate (the first of [`SplitMix64::normal_pair`]).
    #[inline]
    pub fn normal(&mut self) -> f64 {
        self.normal_pair().0
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn matches_the_reference_splitmix64_sequence() {
        // First outputs of SplitMix64 seeded with 1234567 (the reference C implementation).
        let mut r = SplitMix64(1234567);
        assert_eq!(r.next_u64(), 6457827717110365317);
        assert_eq!(r.next_u64(), 3203168211198807973);
        let x = SplitMix64(0).next_f64();
        assert!((0.0..1.0).contains(&x));
    }
}
