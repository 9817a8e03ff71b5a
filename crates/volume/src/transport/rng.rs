//! The random numbers of light transport: one PCG32 generator per pixel and sample
//! (O'Neill, "PCG: a family of simple fast space-efficient statistically good
//! algorithms for random number generation", 2014; `rand_pcg::Pcg32`), its stream
//! the pixel and its state a hash of the seed and the sample index. A pixel's sample
//! `s` therefore draws the same numbers however the image is split among threads and
//! however many samples were taken before it: images are the same bit for bit for a
//! seed and sample count, on any thread count and in any batches.

use rand_core::Rng as _;
use rand_pcg::Pcg32;

/// SplitMix64's finaliser (Steele, Lea and Flood, "Fast splittable pseudorandom number
/// generators", OOPSLA 2014): a bijection of `u64` that spreads nearby inputs.
#[inline]
pub(crate) fn mix64(mut z: u64) -> u64 {
    z = z.wrapping_add(0x9E37_79B9_7F4A_7C15);
    z = (z ^ (z >> 30)).wrapping_mul(0xBF58_476D_1CE4_E5B9);
    z = (z ^ (z >> 27)).wrapping_mul(0x94D0_49BB_1331_11EB);
    z ^ (z >> 31)
}

/// Uniform numbers for one path.
pub(crate) struct Rng(Pcg32);

impl Rng {
    /// The generator of sample `sample` of pixel (or other stream) `stream`, for
    /// `seed`.
    #[inline]
    pub(crate) fn new(seed: u64, stream: u64, sample: u64) -> Rng {
        Rng(Pcg32::new(mix64(seed ^ mix64(sample)), stream))
    }

    /// Uniform in `[0, 1)`, 24 bits.
    #[inline(always)]
    pub(crate) fn uniform(&mut self) -> f32 {
        (self.0.next_u32() >> 8) as f32 * (1.0 / 16_777_216.0)
    }

    /// Exponential with mean 1: `-ln(1 - u)`, finite.
    #[inline(always)]
    pub(crate) fn exponential(&mut self) -> f32 {
        -(-self.uniform()).ln_1p()
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn streams_and_samples_differ_and_repeat() {
        let draw = |seed, stream, sample| {
            let mut r = Rng::new(seed, stream, sample);
            [r.uniform(), r.uniform(), r.uniform()]
        };
        assert_eq!(draw(1, 2, 3), draw(1, 2, 3));
        assert_ne!(draw(1, 2, 3), draw(1, 2, 4));
        assert_ne!(draw(1, 2, 3), draw(1, 3, 3));
        assert_ne!(draw(1, 2, 3), draw(2, 2, 3));
        // Uniform: the mean of many draws is 1/2, of the exponential 1.
        let mut r = Rng::new(7, 0, 0);
        let n = 200_000;
        let (mut u, mut e) = (0.0f64, 0.0f64);
        for _ in 0..n {
            u += f64::from(r.uniform());
            e += f64::from(r.exponential());
        }
        assert!((u / n as f64 - 0.5).abs() < 0.005, "{}", u / n as f64);
        assert!((e / n as f64 - 1.0).abs() < 0.01, "{}", e / n as f64);
    }
}
