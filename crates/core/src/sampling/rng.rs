//! Seeded per-pixel random streams: PCG32 (O'Neill 2014, "PCG: A family of simple fast
//! space-efficient statistically good algorithms for random number generation", the
//! `pcg32` = PCG-XSH-RR 64/32 member) keyed by a SplitMix64 hash (Steele et al. 2014) of
//! `(seed, x, y, sample_index)`.
//!
//! Every pixel sample owns its stream, so an image is bit-identical whatever the thread count
//! or the order in which tiles are rendered.

use glam::Vec2;

const PCG_MULT: u64 = 6_364_136_223_846_793_005;

/// The largest `f32` below 1.0 (`1 - 2^-24`).
pub const ONE_MINUS_EPSILON: f32 = 1.0 - f32::EPSILON / 2.0;

/// SplitMix64 finaliser (Steele, Lea, Flood 2014): a bijective 64-bit mixer with full
/// avalanche, used to turn structured keys (pixel coordinates) into well-spread states.
#[inline]
pub fn splitmix64(mut z: u64) -> u64 {
    z = z.wrapping_add(0x9E37_79B9_7F4A_7C15);
    z = (z ^ (z >> 30)).wrapping_mul(0xBF58_476D_1CE4_E5B9);
    z = (z ^ (z >> 27)).wrapping_mul(0x94D0_49BB_1331_11EB);
    z ^ (z >> 31)
}

/// A 32-bit integer hash (the PCG-RXS-M-XS 32/32 output permutation as used by Jarzynski &
/// Olano 2020, "Hash Functions for GPU Rendering", `pcg_hash`).
#[inline]
pub fn pcg_hash(v: u32) -> u32 {
    let state = v.wrapping_mul(747_796_405).wrapping_add(2_891_336_453);
    let word = ((state >> ((state >> 28) + 4)) ^ state).wrapping_mul(277_803_737);
    (word >> 22) ^ word
}

/// PCG32 generator: 64-bit LCG state, odd increment selecting the stream, XSH-RR output.
#[derive(Clone, Debug, PartialEq, Eq)]
pub struct Rng {
    state: u64,
    inc: u64,
}

impl Rng {
    /// A generator on stream `stream` started from `seed` (the reference `pcg32_srandom_r`).
    pub fn new(seed: u64, stream: u64) -> Self {
        let mut rng = Self {
            state: 0,
            inc: (stream << 1) | 1,
        };
        rng.next_u32();
        rng.state = rng.state.wrapping_add(seed);
        rng.next_u32();
        rng
    }

    /// The stream of one pixel sample: `(seed, x, y, sample_index)` is hashed with
    /// SplitMix64 into a start state and a stream selector, so neighbouring pixels and
    /// consecutive sample indices get unrelated sequences.
    pub fn for_pixel(seed: u64, x: u32, y: u32, sample_index: u32) -> Self {
        let key = splitmix64(seed ^ splitmix64(((x as u64) << 32) | y as u64));
        let key = splitmix64(key ^ sample_index as u64);
        Self::new(key, splitmix64(key ^ 0xA076_1D64_78BD_642F))
    }

    /// The next uniformly distributed 32-bit word.
    #[inline]
    pub fn next_u32(&mut self) -> u32 {
        let old = self.state;
        self.state = old.wrapping_mul(PCG_MULT).wrapping_add(self.inc);
        let xorshifted = (((old >> 18) ^ old) >> 27) as u32;
        let rot = (old >> 59) as u32;
        xorshifted.rotate_right(rot)
    }

    /// A uniform float in `[0, 1)`: the top 24 bits scaled by `2^-24`, so 1.0 is never
    /// returned and every value is exactly representable.
    #[inline]
    pub fn next_f32(&mut self) -> f32 {
        (self.next_u32() >> 8) as f32 * (1.0 / (1u32 << 24) as f32)
    }

    /// Two uniform floats in `[0, 1)^2`.
    #[inline]
    pub fn next_vec2(&mut self) -> Vec2 {
        let a = self.next_f32();
        Vec2::new(a, self.next_f32())
    }

    /// A uniform integer in `[0, bound)` (Lemire's nearly-divisionless rejection); `bound`
    /// must be non-zero.
    #[inline]
    pub fn next_bounded(&mut self, bound: u32) -> u32 {
        debug_assert!(bound > 0);
        let threshold = bound.wrapping_neg() % bound;
        loop {
            let m = self.next_u32() as u64 * bound as u64;
            if (m as u32) >= threshold {
                return (m >> 32) as u32;
            }
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn matches_reference_pcg32() {
        // First outputs of the reference pcg32-demo: pcg32_srandom_r(&rng, 42u, 54u).
        let mut rng = Rng::new(42, 54);
        let expected = [
            0xa15c02b7, 0x7b47f409, 0xba1d3330, 0x83d2f293, 0xbfa4784b, 0xcbed606e,
        ];
        for e in expected {
            assert_eq!(rng.next_u32(), e);
        }
    }

    #[test]
    fn per_pixel_streams_are_deterministic_and_distinct() {
        let a: Vec<u32> = {
            let mut r = Rng::for_pixel(7, 10, 20, 3);
            (0..8).map(|_| r.next_u32()).collect()
        };
        let b: Vec<u32> = {
            let mut r = Rng::for_pixel(7, 10, 20, 3);
            (0..8).map(|_| r.next_u32()).collect()
        };
        assert_eq!(a, b);
        for (s, x, y, i) in [
            (8, 10, 20, 3),
            (7, 11, 20, 3),
            (7, 10, 21, 3),
            (7, 10, 20, 4),
        ] {
            let mut r = Rng::for_pixel(s, x, y, i);
            let c: Vec<u32> = (0..8).map(|_| r.next_u32()).collect();
            assert_ne!(
                a, c,
                "stream ({s},{x},{y},{i}) repeats the reference stream"
            );
        }
        // Swapping x and y must not give the same stream.
        let mut r = Rng::for_pixel(7, 20, 10, 3);
        assert_ne!(a[0], r.next_u32());
    }

    #[test]
    fn f32_is_in_unit_interval_and_uniform() {
        // Chi-square over 100 bins with 200 000 samples: 99 dof, mean 99, sd ~14; the 1e-6
        // quantile is ~180.
        let mut rng = Rng::for_pixel(1, 2, 3, 4);
        let mut bins = [0u32; 100];
        let n = 200_000;
        for _ in 0..n {
            let u = rng.next_f32();
            assert!((0.0..1.0).contains(&u));
            bins[(u * 100.0) as usize] += 1;
        }
        let expected = n as f64 / 100.0;
        let chi2: f64 = bins
            .iter()
            .map(|&c| (c as f64 - expected).powi(2) / expected)
            .sum();
        assert!(chi2 < 180.0, "chi2 = {chi2}");
    }

    #[test]
    fn first_values_across_pixels_are_uniform() {
        // The first draw of many neighbouring pixels must itself be uniform (hash quality).
        let mut bins = [0u32; 64];
        for y in 0..256 {
            for x in 0..256 {
                let u = Rng::for_pixel(0, x, y, 0).next_f32();
                bins[(u * 64.0) as usize] += 1;
            }
        }
        let expected = 65536.0 / 64.0;
        let chi2: f64 = bins
            .iter()
            .map(|&c| (c as f64 - expected).powi(2) / expected)
            .sum();
        // 63 dof: the 1e-6 quantile is ~130.
        assert!(chi2 < 130.0, "chi2 = {chi2}");
    }

    #[test]
    fn next_f32_never_returns_one() {
        let max = (u32::MAX >> 8) as f32 * (1.0 / (1u32 << 24) as f32);
        assert!(max < 1.0);
        assert_eq!(max, ONE_MINUS_EPSILON);
    }

    #[test]
    fn bounded_is_in_range_and_covers() {
        let mut rng = Rng::new(3, 5);
        let mut seen = [false; 7];
        for _ in 0..1000 {
            let v = rng.next_bounded(7);
            assert!(v < 7);
            seen[v as usize] = true;
        }
        assert!(seen.iter().all(|&s| s));
    }
}
