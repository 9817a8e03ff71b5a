//! The random numbers of light transport.
//!
//! Two samplers ([`Sampler`]), both keyed by the seed, the pixel and the sample index
//! only, so a pixel's sample `s` draws the same numbers however the image is split
//! among threads and however many samples were taken before it: images are the same
//! bit for bit for a seed and sample count, on any thread count and in any batches.
//!
//! - `independent`: one PCG32 generator per pixel and sample (O'Neill, "PCG: a family
//!   of simple fast space-efficient statistically good algorithms for random number
//!   generation", 2014; `rand_pcg::Pcg32`), its stream the pixel and its state a hash
//!   of the seed and the sample index;
//! - `sobol`: the path's first dimensions from an Owen-scrambled Sobol sequence
//!   (Burley, "Practical Hash-based Owen Scrambling", JCGT 9(4), 2020, through the
//!   `sobol_burley` crate), padded in pairs as pbrt-v4's `PaddedSobolSampler` pads
//!   them: each pair of dimensions is the first two dimensions of its own
//!   scrambled and shuffled sequence, seeded by the seed, the pixel and the pair, so
//!   the 2^k first samples of a pixel put one point in each elementary interval of
//!   every pair (the pixel jitter among them) and pairs are independent. The numbers
//!   past [`SOBOL_DIMS`], and those a window ([`Rng::window`]) does not cover, come
//!   from the pixel's PCG32 generator as in `independent`.
//!
//! The dimensions a path reads ([`dims`]): the pixel jitter, two reserved for a lens,
//! then a block of [`dims::EVENT`] per scattering event.

use rand_core::Rng as _;
use rand_pcg::Pcg32;

use glint_core::RenderError;

/// SplitMix64's finaliser (Steele, Lea and Flood, "Fast splittable pseudorandom number
/// generators", OOPSLA 2014): a bijection of `u64` that spreads nearby inputs.
#[inline]
pub(crate) fn mix64(mut z: u64) -> u64 {
    z = z.wrapping_add(0x9E37_79B9_7F4A_7C15);
    z = (z ^ (z >> 30)).wrapping_mul(0xBF58_476D_1CE4_E5B9);
    z = (z ^ (z >> 27)).wrapping_mul(0x94D0_49BB_1331_11EB);
    z ^ (z >> 31)
}

/// Where a path takes its random numbers from (a scene's `lighting.sampler`).
#[derive(
    Clone, Copy, Debug, Default, PartialEq, Eq, Hash, serde::Serialize, serde::Deserialize,
)]
#[serde(rename_all = "lowercase")]
pub enum Sampler {
    /// Owen-scrambled Sobol points for the first dimensions of a path (pixel jitter,
    /// the first events' free paths, light transmittance, choices and directions),
    /// independent numbers after: less noise for the same samples.
    #[default]
    Sobol,
    /// Independent (PCG32) numbers for every dimension.
    Independent,
}

impl Sampler {
    /// Every sampler, the default first.
    pub const ALL: [Sampler; 2] = [Sampler::Sobol, Sampler::Independent];

    /// The name scenes and the command line use.
    pub fn name(self) -> &'static str {
        match self {
            Sampler::Sobol => "sobol",
            Sampler::Independent => "independent",
        }
    }
}

impl std::str::FromStr for Sampler {
    type Err = RenderError;
    fn from_str(s: &str) -> Result<Self, Self::Err> {
        Sampler::ALL
            .into_iter()
            .find(|m| m.name() == s)
            .ok_or_else(|| {
                RenderError::Parameter(format!(
                    "unknown sampler '{s}': expected sobol or independent"
                ))
            })
    }
}

/// The dimension layout of a path's numbers under [`Sampler::Sobol`].
pub(crate) mod dims {
    /// The pixel jitter: x, y.
    pub(crate) const JITTER: u32 = 0;
    /// Reserved for a thin lens's two numbers (a point of the aperture).
    #[allow(dead_code)]
    pub(crate) const LENS: u32 = 2;
    /// The first dimension of the first scattering event's block.
    pub(crate) const FIRST_EVENT: u32 = 4;
    /// Dimensions per scattering event.
    pub(crate) const EVENT: u32 = 10;
    /// In an event's block: the free path's first tentative collision (distance,
    /// acceptance), a window for delta tracking.
    pub(crate) const FREE_PATH: u32 = 0;
    /// The first light's transmittance: its first tentative collision, a window for
    /// ratio tracking.
    pub(crate) const TRANSMIT: u32 = 2;
    /// The surface-or-medium choice and the lobe-or-diffuse choice.
    pub(crate) const CHOOSE: u32 = 4;
    /// The choice of lobe or diffuse cosine (`Bsdf::sample`'s `u[0]`).
    pub(crate) const LOBE: u32 = 5;
    /// The scattered direction (`Bsdf::sample`'s `u[1]`, `u[2]`).
    pub(crate) const DIRECTION: u32 = 6;
    /// Russian roulette.
    pub(crate) const ROULETTE: u32 = 8;
    /// The environment map's two numbers of event `k` are dimensions
    /// `ENV_LIGHT + 2k`, `ENV_LIGHT + 2k + 1`: a pair of their own, outside the event
    /// blocks, so scenes without a map draw what they drew before ([`Rng::light_dim`]).
    ///
    /// [`Rng::light_dim`]: super::Rng::light_dim
    pub(crate) const ENV_LIGHT: u32 = 1 << 12;
    /// Area light `l`'s two numbers at event `k` are dimensions `AREA_LIGHT + 2(4k +
    /// l)` and the next: pairs of their own past the environment map's, for the first
    /// four events and four lights ([`Rng::area_dim`]).
    ///
    /// [`Rng::area_dim`]: super::Rng::area_dim
    pub(crate) const AREA_LIGHT: u32 = ENV_LIGHT + 8;

    /// The first dimension of event `k`'s block (events counted from 0).
    #[inline(always)]
    pub(crate) fn event(k: u32) -> u32 {
        FIRST_EVENT.saturating_add(k.saturating_mul(EVENT))
    }
}

/// Dimensions drawn from the Sobol sequence; later ones are independent: the first
/// four events' blocks (Burley's paper and pbrt-v4 pad the same way; past a few
/// bounces Russian roulette has ended most paths and stratification gains little).
pub const SOBOL_DIMS: u32 = dims::FIRST_EVENT + 4 * dims::EVENT;

/// The Sobol part of a path's numbers: the pixel's scramble key and the sample.
#[derive(Clone, Copy)]
struct Sobol {
    key: u64,
    index: u32,
    /// The window of dimensions [`Rng::uniform`] reads: `next..end`.
    next: u32,
    end: u32,
}

impl Sobol {
    /// Dimension `d` (below [`SOBOL_DIMS`]) of the sample.
    #[inline]
    fn get(&self, d: u32) -> f32 {
        let pair_seed = mix64(self.key ^ mix64(u64::from(d >> 1))) as u32;
        sobol_burley::sample(self.index, d & 1, pair_seed)
    }
}

/// Uniform numbers for one path: independent ([`Rng::new`]), or the first dimensions
/// from a Sobol sequence ([`Rng::for_path`]).
pub(crate) struct Rng {
    pcg: Pcg32,
    sobol: Option<Sobol>,
}

impl Rng {
    /// The independent generator of sample `sample` of pixel (or other stream)
    /// `stream`, for `seed`.
    #[inline]
    pub(crate) fn new(seed: u64, stream: u64, sample: u64) -> Rng {
        Rng {
            pcg: Pcg32::new(mix64(seed ^ mix64(sample)), stream),
            sobol: None,
        }
    }

    /// The numbers of sample `sample` (below [`crate::transport::MAX_SPP`]) of pixel
    /// `pixel` for `seed` under `sampler`. Under [`Sampler::Independent`] it is
    /// [`Rng::new`], and every call draws the next independent number.
    #[inline]
    pub(crate) fn for_path(sampler: Sampler, seed: u64, pixel: u64, sample: u32) -> Rng {
        let mut rng = Rng::new(seed, pixel, u64::from(sample));
        if sampler == Sampler::Sobol && sample < (1 << 16) {
            rng.sobol = Some(Sobol {
                key: mix64(mix64(seed) ^ pixel.wrapping_mul(0xD1B5_4A32_D192_ED03)),
                index: sample,
                next: 0,
                end: 0,
            });
        }
        rng
    }

    /// Dimension `d` of the path (the next independent number where it has no Sobol
    /// part or `d` is past [`SOBOL_DIMS`]).
    #[inline]
    pub(crate) fn dim(&mut self, d: u32) -> f32 {
        match self.sobol {
            Some(s) if d < SOBOL_DIMS => s.get(d),
            _ => self.pcg_uniform(),
        }
    }

    /// Number `i` (0 or 1) of the environment map's pair at event `event` (counted
    /// from 0): from the Sobol sequence for the first four events (a pair of its own,
    /// [`dims::ENV_LIGHT`]; no independent number is drawn), else independent.
    #[inline]
    pub(crate) fn light_dim(&mut self, event: u32, i: u32) -> f32 {
        match self.sobol {
            Some(s) if event < 4 => s.get(dims::ENV_LIGHT + 2 * event + i),
            _ => self.pcg_uniform(),
        }
    }

    /// Number `i` (0 or 1) of area light `light`'s pair at event `event` (both counted
    /// from 0): from the Sobol sequence for the first four events and lights (a pair
    /// of its own, [`dims::AREA_LIGHT`]), else independent.
    #[inline]
    pub(crate) fn area_dim(&mut self, event: u32, light: u32, i: u32) -> f32 {
        match self.sobol {
            Some(s) if event < 4 && light < 4 => {
                s.get(dims::AREA_LIGHT + 2 * (4 * event + light) + i)
            }
            _ => self.pcg_uniform(),
        }
    }

    /// Lets the next `len` calls of [`Rng::uniform`] (and [`Rng::exponential`]) read
    /// dimensions `first..first + len`, for a tracking loop whose first numbers have a
    /// place in the layout; [`Rng::close`] ends the window early.
    #[inline]
    pub(crate) fn window(&mut self, first: u32, len: u32) {
        if let Some(s) = &mut self.sobol {
            s.next = first;
            s.end = first.saturating_add(len).min(SOBOL_DIMS);
        }
    }

    /// Ends the window: [`Rng::uniform`] draws independent numbers again.
    #[inline]
    pub(crate) fn close(&mut self) {
        if let Some(s) = &mut self.sobol {
            s.end = s.next;
        }
    }

    #[inline(always)]
    fn pcg_uniform(&mut self) -> f32 {
        (self.pcg.next_u32() >> 8) as f32 * (1.0 / 16_777_216.0)
    }

    /// Uniform in `[0, 1)`: the window's next dimension, else an independent number
    /// (24 bits).
    #[inline(always)]
    pub(crate) fn uniform(&mut self) -> f32 {
        if let Some(s) = &mut self.sobol {
            if s.next < s.end {
                let d = s.next;
                s.next += 1;
                return s.get(d);
            }
        }
        self.pcg_uniform()
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

    /// Whether the points put exactly one in each elementary interval of `2^a x 2^b`
    /// cells, for every `a + b = k` (`2^k` points): a (0, k, 2)-net in base 2.
    fn is_net(points: &[[f32; 2]], k: u32) -> bool {
        (0..=k).all(|a| {
            let b = k - a;
            let mut seen = vec![false; 1 << k];
            points.iter().all(|p| {
                let i = (p[0] * (1u32 << a) as f32) as usize;
                let j = (p[1] * (1u32 << b) as f32) as usize;
                !std::mem::replace(&mut seen[(i << b) | j], true)
            })
        })
    }

    #[test]
    fn sobol_pairs_are_stratified_per_pixel_and_independent_numbers_are_not() {
        let k = 6;
        let pair = |sampler, seed, pixel, d: u32| -> Vec<[f32; 2]> {
            (0..1u32 << k)
                .map(|s| {
                    let mut r = Rng::for_path(sampler, seed, pixel, s);
                    [r.dim(d), r.dim(d + 1)]
                })
                .collect()
        };
        let direction = dims::event(2) + dims::DIRECTION;
        for (seed, pixel) in [(0, 0), (3, 77), (u64::MAX, 1 << 40)] {
            for d in [dims::JITTER, dims::LENS, direction] {
                let points = pair(Sampler::Sobol, seed, pixel, d);
                assert!(is_net(&points, k), "seed {seed}, pixel {pixel}, dims {d}");
                // Every prefix of 2^j samples too (progressive rendering).
                assert!(is_net(&points[..8], 3));
            }
            // Other pixels and pairs are scrambled otherwise.
            assert_ne!(
                pair(Sampler::Sobol, seed, pixel, 0),
                pair(Sampler::Sobol, seed, pixel + 1, 0)
            );
            assert_ne!(
                pair(Sampler::Sobol, seed, pixel, 0),
                pair(Sampler::Sobol, seed, pixel, 2)
            );
        }
        assert!(!is_net(&pair(Sampler::Independent, 0, 0, 0), k));
        // A window's numbers are the dimensions' own, then independent ones.
        let mut a = Rng::for_path(Sampler::Sobol, 5, 9, 13);
        let mut b = Rng::for_path(Sampler::Sobol, 5, 9, 13);
        a.window(dims::event(1) + dims::FREE_PATH, 2);
        let (x, y) = (a.uniform(), a.uniform());
        assert_eq!(x, b.dim(dims::event(1)));
        assert_eq!(y, b.dim(dims::event(1) + 1));
        assert_eq!(a.uniform(), b.uniform(), "past the window: the pixel's PCG");
        // Past the Sobol dimensions: independent numbers, as the generator draws them.
        let mut c = Rng::for_path(Sampler::Sobol, 5, 9, 13);
        let mut d = Rng::new(5, 9, 13);
        assert_eq!(c.dim(SOBOL_DIMS), d.uniform());
    }

    #[test]
    fn area_light_pairs_are_stratified_and_their_own() {
        // Each light's pair at each of the first four events is a (0, 2)-net of its
        // own (not the map's pair of that event, nor another light's); past four
        // events the numbers are the pixel's independent ones.
        let k = 6;
        let pairs = |f: &dyn Fn(&mut Rng) -> [f32; 2]| -> Vec<[f32; 2]> {
            (0..1u32 << k)
                .map(|s| f(&mut Rng::for_path(Sampler::Sobol, 7, 21, s)))
                .collect()
        };
        let env = pairs(&|r| [r.light_dim(1, 0), r.light_dim(1, 1)]);
        let mut seen = vec![env];
        for event in 0..4 {
            for light in 0..4 {
                let p = pairs(&|r| [r.area_dim(event, light, 0), r.area_dim(event, light, 1)]);
                assert!(is_net(&p, k), "event {event}, light {light}");
                assert!(!seen.contains(&p), "event {event}, light {light}");
                seen.push(p);
            }
        }
        let mut a = Rng::for_path(Sampler::Sobol, 7, 21, 3);
        let mut b = Rng::new(7, 21, 3);
        assert_eq!(a.area_dim(4, 0, 0), b.uniform());
    }

    #[test]
    fn sobol_numbers_are_uniform() {
        // The mean of each dimension over one pixel's samples, and of a whole block's
        // numbers over many pixels, is 1/2 (and the exponential's 1).
        let (mut u, mut e, mut n) = (0.0f64, 0.0f64, 0u32);
        for pixel in 0..64u64 {
            for s in 0..64u32 {
                let mut r = Rng::for_path(Sampler::Sobol, 1, pixel, s);
                for d in 0..SOBOL_DIMS {
                    u += f64::from(r.dim(d));
                }
                r.window(dims::event(0), 2);
                e += f64::from(r.exponential());
                n += 1;
            }
        }
        let u = u / f64::from(n * SOBOL_DIMS);
        let e = e / f64::from(n);
        assert!((u - 0.5).abs() < 0.002, "{u}");
        assert!((e - 1.0).abs() < 0.02, "{e}");
    }
}
