//! Low-discrepancy points: radical inverse / Halton, the 2-D Sobol (0,2)-sequence with
//! hash-based Owen scrambling, Cranley-Patterson rotation, and the R2 sequence.
//!
//! * Halton 1964; radical inverse as in pbrt-v4 §8.6.1.
//! * Sobol 1967; the first two dimensions form a (0,2)-sequence in base 2: van der Corput
//!   and the Sobol matrix `v_i = v_{i-1} ^ (v_{i-1} >> 1)` (Kollig & Keller 2002,
//!   "Efficient multidimensional sampling", `sobol2`).
//! * Owen 1995 nested uniform scrambling, approximated by the Laine-Karras hash on
//!   bit-reversed values (Burley 2020, "Practical Hash-based Owen Scrambling", §3-4).
//! * Cranley & Patterson 1976 toroidal shift.
//! * Roberts 2018, "The unreasonable effectiveness of quasirandom sequences" (R2, based on
//!   the plastic number).

use glam::Vec2;

use super::rng::{ONE_MINUS_EPSILON, pcg_hash};

/// `u32` fixed point (value / 2^32) -> `f32` in `[0, 1)`, truncating to 24 bits so that
/// dyadic intervals of up to 2^-24 are preserved exactly.
#[inline]
pub fn u32_to_unit(bits: u32) -> f32 {
    (bits >> 8) as f32 * (1.0 / (1u32 << 24) as f32)
}

/// Base-2 radical inverse (van der Corput) as 32-bit fixed point: the bits of `index`
/// mirrored about the binary point.
#[inline]
pub fn van_der_corput_bits(index: u32) -> u32 {
    index.reverse_bits()
}

/// The radical inverse of `index` in `base` (`base >= 2`), in `[0, 1)`.
pub fn radical_inverse(index: u32, base: u32) -> f32 {
    if base == 2 {
        return u32_to_unit(van_der_corput_bits(index));
    }
    let base = base.max(2) as u64;
    // Digits reversed as an integer over base^digits: both fit in u64 (base^digits <=
    // index * base < 2^64), and one division gives the correctly rounded value.
    let mut i = index as u64;
    let mut reversed = 0u64;
    let mut base_n = 1u64;
    while i > 0 {
        let next = i / base;
        reversed = reversed * base + (i - next * base);
        base_n *= base;
        i = next;
    }
    ((reversed as f64 / base_n as f64) as f32).min(ONE_MINUS_EPSILON)
}

/// The Halton sequence in one dimension: the radical inverse of `index` in `base`.
#[inline]
pub fn halton(index: u32, base: u32) -> f32 {
    radical_inverse(index, base)
}

/// 2-D Halton points (bases 2 and 3).
#[inline]
pub fn halton_2d(index: u32) -> Vec2 {
    Vec2::new(radical_inverse(index, 2), radical_inverse(index, 3))
}

/// Second Sobol dimension as 32-bit fixed point: XOR of the direction numbers selected by
/// the set bits of `index` (Kollig & Keller 2002).
#[inline]
pub fn sobol_dim1_bits(mut index: u32) -> u32 {
    let mut r = 0u32;
    let mut v = 1u32 << 31;
    while index != 0 {
        if index & 1 != 0 {
            r ^= v;
        }
        index >>= 1;
        v ^= v >> 1;
    }
    r
}

/// The Laine-Karras permutation (Burley 2020, listing 2, with Burley's improved constants):
/// each output bit depends only on the same and lower input bits, so applied to bit-reversed
/// values it is a nested uniform (Owen) scramble.
#[inline]
fn laine_karras(mut x: u32, seed: u32) -> u32 {
    x = x.wrapping_add(seed);
    x ^= x.wrapping_mul(0x6c50_b47c);
    x ^= x.wrapping_mul(0xb82f_1e52);
    x ^= x.wrapping_mul(0xc7af_e638);
    x ^= x.wrapping_mul(0x8d22_f6e6);
    x
}

/// Hash-based Owen scrambling of a 32-bit fixed-point coordinate (Burley 2020, §4). The map
/// is a bijection that sends every dyadic interval `[k/2^m, (k+1)/2^m)` onto another one of
/// the same length, so it preserves the (t,m,s)-net property of the points it scrambles.
#[inline]
pub fn owen_scramble_bits(bits: u32, seed: u32) -> u32 {
    laine_karras(bits.reverse_bits(), seed).reverse_bits()
}

/// Point `index` of the 2-D Sobol (0,2)-sequence, Owen-scrambled by `scramble` (e.g. a hash
/// of the pixel; 0 still scrambles — use [`sobol_2d_unscrambled`] for the raw points).
/// Every prefix of length `2^k` is a (0,k,2)-net: one point in each elementary interval of
/// area `2^-k`.
#[inline]
pub fn sobol_2d(index: u32, scramble: u32) -> Vec2 {
    let s0 = pcg_hash(scramble);
    let s1 = pcg_hash(s0 ^ 0x9e37_79b9);
    Vec2::new(
        u32_to_unit(owen_scramble_bits(van_der_corput_bits(index), s0)),
        u32_to_unit(owen_scramble_bits(sobol_dim1_bits(index), s1)),
    )
}

/// Point `index` of the unscrambled 2-D Sobol (0,2)-sequence (point 0 is the origin).
#[inline]
pub fn sobol_2d_unscrambled(index: u32) -> Vec2 {
    Vec2::new(
        u32_to_unit(van_der_corput_bits(index)),
        u32_to_unit(sobol_dim1_bits(index)),
    )
}

/// Cranley-Patterson rotation: `p + offset` modulo 1 in each coordinate. Cheaper than Owen
/// scrambling; keeps the lattice structure but not the elementary-interval property.
#[inline]
pub fn cranley_patterson(p: Vec2, offset: Vec2) -> Vec2 {
    let wrap = |v: f32| {
        let f = v - v.floor();
        if f >= 1.0 { 0.0 } else { f }
    };
    Vec2::new(wrap(p.x + offset.x), wrap(p.y + offset.y))
}

/// Point `index` of Roberts' R2 sequence: `frac(0.5 + index * (1/g, 1/g^2))` with `g` the
/// plastic number (the real root of `x^3 = x + 1`). Evaluated in 64-bit fixed point, so it
/// stays exact for every `u32` index.
#[inline]
pub fn r2(index: u32) -> Vec2 {
    // 2^64 / g and 2^64 / g^2, g = 1.32471795724474602596...
    const A1: u64 = 0xC13F_A9A9_02A6_328F;
    const A2: u64 = 0x91E1_0DA5_C79E_7B1C;
    const HALF: u64 = 1 << 63;
    let x = HALF.wrapping_add(A1.wrapping_mul(index as u64));
    let y = HALF.wrapping_add(A2.wrapping_mul(index as u64));
    Vec2::new(u32_to_unit((x >> 32) as u32), u32_to_unit((y >> 32) as u32))
}

#[cfg(test)]
mod tests {
    use super::*;

    /// True when `points` has exactly one point in every elementary interval
    /// `[a/2^i, (a+1)/2^i) x [b/2^j, (b+1)/2^j)` with `i + j = k`.
    fn is_0k2_net(points: &[Vec2], k: u32) -> bool {
        assert_eq!(points.len(), 1 << k);
        for i in 0..=k {
            let j = k - i;
            let mut seen = vec![false; 1 << k];
            for p in points {
                let a = (p.x * (1u32 << i) as f32) as usize;
                let b = (p.y * (1u32 << j) as f32) as usize;
                let cell = (b << i) | a;
                if seen[cell] {
                    return false;
                }
                seen[cell] = true;
            }
        }
        true
    }

    #[test]
    fn radical_inverse_known_values() {
        assert_eq!(radical_inverse(1, 2), 0.5);
        assert_eq!(radical_inverse(6, 2), 0.375); // 110 -> 0.011
        assert!((radical_inverse(1, 3) - 1.0 / 3.0).abs() < 1e-7);
        assert!((radical_inverse(5, 3) - 7.0 / 9.0).abs() < 1e-7); // 12_3 -> 0.21_3
        assert!(radical_inverse(u32::MAX, 3) < 1.0);
        assert!(radical_inverse(u32::MAX, 2) < 1.0);
        assert_eq!(halton_2d(0), Vec2::ZERO);
    }

    #[test]
    fn sobol_prefixes_are_0k2_nets() {
        for k in 0..=10 {
            let raw: Vec<Vec2> = (0..1u32 << k).map(sobol_2d_unscrambled).collect();
            assert!(is_0k2_net(&raw, k), "raw k={k}");
            for seed in [0u32, 1, 12345, 0xdead_beef] {
                let pts: Vec<Vec2> = (0..1u32 << k).map(|i| sobol_2d(i, seed)).collect();
                assert!(is_0k2_net(&pts, k), "scrambled seed={seed} k={k}");
            }
        }
        // A block [m 2^k, (m+1) 2^k) of the sequence is a net too.
        let pts: Vec<Vec2> = (64..128).map(|i| sobol_2d(i, 99)).collect();
        assert!(is_0k2_net(&pts, 6));
    }

    #[test]
    fn random_points_are_not_nets() {
        // The net check can fail: pseudo-random points are not stratified.
        let mut rng = crate::sampling::Rng::new(1, 1);
        let pts: Vec<Vec2> = (0..256).map(|_| rng.next_vec2()).collect();
        assert!(!is_0k2_net(&pts, 8));
    }

    #[test]
    fn scrambling_changes_points_and_stays_in_range() {
        let a: Vec<Vec2> = (0..16).map(|i| sobol_2d(i, 1)).collect();
        let b: Vec<Vec2> = (0..16).map(|i| sobol_2d(i, 2)).collect();
        assert_ne!(a, b);
        for i in 0..1000 {
            let p = sobol_2d(i, 7);
            assert!(p.cmpge(Vec2::ZERO).all() && p.cmplt(Vec2::ONE).all());
        }
    }

    #[test]
    fn halton_is_stratified_in_each_base() {
        // The first 3^4 base-3 values are exactly {k / 81}: one per interval of length 3^-4.
        let mut seen = [false; 81];
        for i in 0..81 {
            let v = halton(i, 3) * 81.0;
            let c = v.round() as usize;
            assert!((v - c as f32).abs() < 1e-4);
            assert!(!seen[c]);
            seen[c] = true;
        }
    }

    #[test]
    fn r2_matches_float_definition_and_is_well_spread() {
        let g = 1.324_717_957_244_746_f64;
        for n in [0u32, 1, 2, 17, 1000, 123_456] {
            let x = (0.5 + n as f64 / g).fract();
            let y = (0.5 + n as f64 / (g * g)).fract();
            let p = r2(n);
            assert!(
                (p.x as f64 - x).abs() < 1e-6 && (p.y as f64 - y).abs() < 1e-6,
                "{n}"
            );
        }
        // Minimum toroidal distance of the first 256 points: R2 keeps ~0.5/sqrt(N) (Roberts
        // 2018); uniform random points reach ~1/N. Threshold 0.25/sqrt(N).
        let pts: Vec<Vec2> = (0..256).map(r2).collect();
        let mut dmin = f32::MAX;
        for i in 0..pts.len() {
            for j in i + 1..pts.len() {
                let d = pts[i] - pts[j];
                let d = d - d.round(); // toroidal
                dmin = dmin.min(d.length());
            }
        }
        assert!(dmin > 0.25 / 16.0, "dmin = {dmin}");
    }

    #[test]
    fn cranley_patterson_wraps() {
        let p = cranley_patterson(Vec2::new(0.75, 0.1), Vec2::new(0.5, 0.95));
        assert!((p - Vec2::new(0.25, 0.05)).length() < 1e-6);
    }
}
