//! The render's random numbers: one deterministic stream per (image, pass, pixel, sample),
//! derived by hashing those coordinates with the scene seed, so results do not depend on threads.
//!
//! | `render.sampler` | the numbers of one pixel's samples |
//! |---|---|
//! | `"sobol"` (default) | the first [`SOBOL_DIMENSIONS`] draws of each sample are an Owen-scrambled Sobol sequence over the pixel's samples (Burley 2020, the `sobol_burley` crate): 4-D sets, each shuffled and scrambled with its own seed (Burley's padding), the pixel's hash as the seed; later draws, and samples past 2¹⁶, are independent |
//! | `"independent"` | every draw independent (SplitMix64) |
//!
//! Owen scrambling keeps every draw uniform on [0, 1), so each sample is an unbiased estimate
//! either way; the samples of one pixel are stratified against each other instead of
//! independent, which lowers the error of their mean (docs/native.md, "The sampler"). The 24 bits
//! of a Sobol value are completed to 53 with independent low bits.

use crate::noise::mix64;
use crate::rng::SplitMix64;

/// How many draws of each sample come from the Sobol sequence (33 four-dimensional sets: the
/// pixel position, then [`VERTEX_DIMENSIONS`] for each of the path's first four vertices).
pub const SOBOL_DIMENSIONS: u32 = 2 + 4 * VERTEX_DIMENSIONS + 2;

/// The block of dimensions of one path vertex: the segment that reaches it from
/// [`Sampler::segment`], its surface from [`Sampler::surface`] (`SURFACE_AT` in).
pub const VERTEX_DIMENSIONS: u32 = 32;
const SURFACE_AT: u32 = 20;

/// One pixel sample's stream of uniform numbers.
#[derive(Debug, Clone)]
pub struct Sampler {
    stream: SplitMix64,
    /// `Some` for a Sobol sample: its index within the pixel, the pixel's scramble seed, the
    /// next dimension and the current 4-D set's values.
    sobol: Option<Sobol>,
}

#[derive(Debug, Clone)]
struct Sobol {
    index: u32,
    seed: u64,
    dim: u32,
    /// The 4-D set held in `set` (`u32::MAX`: none yet).
    held: u32,
    set: [f32; 4],
}

fn pixel_hash(seed: u64, image: u64, pass: u64, pixel: u64) -> u64 {
    let mut h = mix64(seed ^ 0x005E_ED0F_9053);
    for k in [image, pass, pixel] {
        h = mix64(h ^ k);
    }
    h
}

impl Sampler {
    /// The independent stream of one sample of one pixel (`render.sampler = "independent"`).
    pub fn new(seed: u64, image: u64, pass: u64, pixel: u64, sample: u64) -> Sampler {
        Sampler {
            stream: SplitMix64(mix64(pixel_hash(seed, image, pass, pixel) ^ sample)),
            sobol: None,
        }
    }

    /// The stream of sample `sample` of one pixel under `kind`: with
    /// [`crate::model::SamplerKind::Sobol`], the samples of one block (`first` on) share one
    /// scrambled Sobol sequence in their first [`SOBOL_DIMENSIONS`] draws, the block's first
    /// sample at its index 0. Blocks are scrambled independently: the fresh samples a noise
    /// target adds after a pixel's pilot (`first` = the pilot's count) are independent of the
    /// pilot that chose how many there are, so their mean stays unbiased. The independent
    /// stream depends on `sample` alone.
    pub fn for_sample(
        kind: crate::model::SamplerKind,
        seed: u64,
        image: u64,
        pass: usize,
        pixel: u64,
        first: u32,
        sample: u64,
    ) -> Sampler {
        let (pass, first) = (pass as u64, first as u64);
        let h = pixel_hash(seed, image, pass, pixel);
        let mut s = Sampler {
            stream: SplitMix64(mix64(h ^ sample)),
            sobol: None,
        };
        let index = sample.wrapping_sub(first);
        if kind == crate::model::SamplerKind::Sobol && sample >= first && index < (1 << 16) {
            let mut scramble = mix64(h ^ 0x50B0_1000);
            if first > 0 {
                scramble = mix64(scramble ^ first);
            }
            s.sobol = Some(Sobol {
                index: index as u32,
                seed: scramble,
                dim: 0,
                held: u32::MAX,
                set: [0.0; 4],
            });
        }
        s
    }

    /// The draws of the segment that reaches vertex `depth` start at their own block of
    /// dimensions, so that the same decision of every sample of a pixel reads the same Sobol
    /// dimension whatever the earlier vertices drew. Never moves back: no dimension is read
    /// twice in one sample.
    #[inline]
    pub fn segment(&mut self, depth: u32) {
        self.skip_to(2 + depth.saturating_mul(VERTEX_DIMENSIONS));
    }

    /// The draws at the surface ending the segment of vertex `depth` (see [`Sampler::segment`]).
    #[inline]
    pub fn surface(&mut self, depth: u32) {
        self.skip_to((2 + depth.saturating_mul(VERTEX_DIMENSIONS)).saturating_add(SURFACE_AT));
    }

    #[inline]
    fn skip_to(&mut self, dim: u32) {
        if let Some(s) = &mut self.sobol {
            s.dim = s.dim.max(dim);
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
        if let Some(s) = &mut self.sobol
            && s.dim < SOBOL_DIMENSIONS
        {
            let (set, k) = (s.dim / 4, s.dim % 4);
            if set != s.held {
                // Burley's padding: every 4-D set is the Sobol sequence's first four
                // dimensions, shuffled and scrambled with the set's own seed.
                let set_seed = mix64(s.seed ^ set as u64) as u32;
                s.set = sobol_burley::sample_4d(s.index, 0, set_seed);
                s.held = set;
            }
            s.dim += 1;
            // A multiple of 2⁻²⁴ below 1, plus independent low bits: uniform on [0, 1).
            let x = s.set[k as usize] as f64 + self.stream.next_f64() * (1.0 / (1u64 << 24) as f64);
            return x.min(1.0 - f64::EPSILON / 2.0);
        }
        self.stream.next_f64()
    }

    #[inline]
    pub fn next2(&mut self) -> (f64, f64) {
        (self.next(), self.next())
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::model::SamplerKind;

    /// A smooth 2-D integrand over a pixel's samples: the Sobol means must be far closer to
    /// the exact value than independent ones, over many pixels, and every draw stays in [0, 1).
    #[test]
    fn sobol_stratifies_a_pixels_samples_and_stays_uniform() {
        let f = |u: f64, v: f64| (u * 3.0).sin() * v * v + u; // ∫∫ = (1 − cos 3)/9 + 1/2
        let exact = (1.0 - 3f64.cos()) / 9.0 + 0.5;
        let n = 64u64;
        let err = |kind: SamplerKind| {
            let mut e2 = 0.0;
            for pixel in 0..200 {
                let mut m = 0.0;
                for s in 0..n {
                    let mut r = Sampler::for_sample(kind, 3, 0, 1, pixel, 0, s);
                    // Pass one 4-D set so that dimensions 4 and 5 come from the second set.
                    for _ in 0..4 {
                        let x = r.next();
                        assert!((0.0..1.0).contains(&x));
                    }
                    let (u, v) = r.next2();
                    m += f(u, v);
                }
                e2 += (m / n as f64 - exact).powi(2);
            }
            (e2 / 200.0).sqrt()
        };
        let (sobol, independent) = (err(SamplerKind::Sobol), err(SamplerKind::Independent));
        eprintln!("RMS error of 64-sample means: Sobol {sobol:.2e}, independent {independent:.2e}");
        assert!(
            sobol < independent / 8.0,
            "RMS error of 64-sample means: Sobol {sobol:.2e}, independent {independent:.2e}"
        );
        // Unbiased: the mean over pixels of the Sobol estimate is the integral.
        let mut total = 0.0;
        for pixel in 0..400u64 {
            for s in 0..16 {
                let mut r = Sampler::for_sample(SamplerKind::Sobol, 9, 2, 0, pixel, 0, s);
                let (u, v) = r.next2();
                total += f(u, v);
            }
        }
        assert!((total / 6400.0 - exact).abs() < 3e-3, "{}", total / 6400.0);
    }

    /// A block after the first (a noise target's fresh samples) is its own scrambled sequence:
    /// it starts at index 0 of a different scramble, not where the first block left off.
    #[test]
    fn each_block_of_samples_is_scrambled_on_its_own() {
        let first = |block: u32, sample: u64| {
            Sampler::for_sample(SamplerKind::Sobol, 4, 0, 0, 9, block, sample).next()
        };
        let continued = Sampler::for_sample(SamplerKind::Sobol, 4, 0, 0, 9, 0, 16).next();
        assert_ne!(first(16, 16), continued);
        // Within a block the samples still stratify: 16 samples put one in each sixteenth.
        let mut bins = [0; 16];
        for s in 16..32 {
            bins[(first(16, s) * 16.0) as usize] += 1;
        }
        assert_eq!(bins, [1; 16]);
    }

    #[test]
    fn past_the_sobol_dimensions_and_samples_draws_are_independent_and_deterministic() {
        let draw = |sample| {
            let mut r = Sampler::for_sample(SamplerKind::Sobol, 1, 0, 0, 5, 0, sample);
            (0..SOBOL_DIMENSIONS + 3)
                .map(|_| r.next())
                .collect::<Vec<_>>()
        };
        assert_eq!(draw(7), draw(7));
        assert_ne!(draw(7), draw(8));
        // Sample 2¹⁶ and on: the independent stream.
        let mut a = Sampler::for_sample(SamplerKind::Sobol, 1, 0, 0, 5, 0, 1 << 16);
        let mut b = Sampler::new(1, 0, 0, 5, 1 << 16);
        assert_eq!(a.next(), b.next());
    }
}
