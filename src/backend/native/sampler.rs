//! Counter-based random numbers: every (image, pass, pixel, sample) has its own stream derived
//! by hashing its coordinates with the scene seed, so results do not depend on threads.

use crate::geometry::mesh::mix64;
use crate::rng::SplitMix64;

/// A SplitMix64 stream ([`crate::rng::SplitMix64`]) per pixel sample.
#[derive(Debug, Clone)]
pub struct Sampler {
    stream: SplitMix64,
}

impl Sampler {
    /// The stream of one sample of one pixel.
    pub fn new(seed: u64, image: u64, pass: u64, pixel: u64, sample: u64) -> Sampler {
        let mut h = mix64(seed ^ 0x005E_ED0F_9053);
        for k in [image, pass, pixel, sample] {
            h = mix64(h ^ k);
        }
        Sampler {
            stream: SplitMix64(h),
        }
    }

    #[inline]
    pub fn next_u64(&mut self) -> u64 {
        self.stream.next_u64()
    }

    /// Uniform in [0, 1).
    #[inline]
    #[allow(clippy::should_implement_trait)]
    pub fn next(&mut self) -> f64 {
        self.stream.next_f64()
    }

    #[inline]
    pub fn next2(&mut self) -> (f64, f64) {
        (self.next(), self.next())
    }
}
