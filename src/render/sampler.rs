//! Counter-based random numbers: every (image, pass, pixel, sample) has its own stream derived
//! by hashing its coordinates with the scene seed, so results do not depend on threads.

use crate::mesh::mix64;

/// A SplitMix64 stream.
#[derive(Debug, Clone)]
pub struct Sampler {
    state: u64,
}

impl Sampler {
    /// The stream of one sample of one pixel.
    pub fn new(seed: u64, image: u64, pass: u64, pixel: u64, sample: u64) -> Sampler {
        let mut h = mix64(seed ^ 0x005E_ED0F_9053);
        for k in [image, pass, pixel, sample] {
            h = mix64(h ^ k);
        }
        Sampler { state: h }
    }

    #[inline]
    pub fn next_u64(&mut self) -> u64 {
        self.state = self.state.wrapping_add(0x9E37_79B9_7F4A_7C15);
        let mut z = self.state;
        z = (z ^ (z >> 30)).wrapping_mul(0xBF58_476D_1CE4_E5B9);
        z = (z ^ (z >> 27)).wrapping_mul(0x94D0_49BB_1331_11EB);
        z ^ (z >> 31)
    }

    /// Uniform in [0, 1).
    #[inline]
    #[allow(clippy::should_implement_trait)]
    pub fn next(&mut self) -> f64 {
        (self.next_u64() >> 11) as f64 * (1.0 / (1u64 << 53) as f64)
    }

    #[inline]
    pub fn next2(&mut self) -> (f64, f64) {
        (self.next(), self.next())
    }
}
