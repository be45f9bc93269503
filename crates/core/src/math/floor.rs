//! `floor` of an f32 as an i32 without the libm call: the x86-64 baseline (SSE2) has no
//! rounding instruction, so `f32::floor` is a library call in hot loops. Shared by the view
//! warp's resampling and the reprojection's footprints.
//!
//! **Invariants:** [`floor_i32`]`(f) == f.floor() as i32` for every `|f| <` [`FLOOR_EXACT`];
//! [`floor_i64`]`(f) == f.floor() as i64` for every `f` (NaN and infinities included, with
//! `as`'s saturation). Tested against `f32::floor`, including -0.0, tiny and near-bound
//! values.

/// Bound under which [`floor_i32`] is exact (2^23: every f32 at or above it is an integer).
pub const FLOOR_EXACT: f32 = 8_388_608.0;

/// `f.floor() as i32` for `|f| <` [`FLOOR_EXACT`], without the libm call and the saturating
/// conversion.
#[inline(always)]
pub fn floor_i32(f: f32) -> i32 {
    debug_assert!(f.abs() < FLOOR_EXACT);
    // SAFETY: |f| < 2^23 is finite and in i32's range.
    let t: i32 = unsafe { f.to_int_unchecked() };
    // Truncation rounds negative non-integers up: step down (t is exact in f32).
    t - ((t as f32) > f) as i32
}

/// `f.floor() as i64` for every `f32` (NaN: 0, out of range: saturated, as `as` does), without
/// the libm call: [`floor_i32`] below [`FLOOR_EXACT`], where the rest of the f32s are already
/// integers (or NaN or infinite) and `as` alone gives the same value.
#[inline(always)]
pub fn floor_i64(f: f32) -> i64 {
    if f.abs() < FLOOR_EXACT {
        floor_i32(f) as i64
    } else {
        f as i64
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn floor_i32_is_exact() {
        let mut v = vec![
            0.0f32,
            -0.0,
            0.5,
            -0.5,
            1.0,
            -1.0,
            0.999_999_9,
            -0.999_999_9,
            1e-30,
            -1e-30,
            8_388_607.5,
            -8_388_607.5,
            8_388_607.0,
            -8_388_607.0,
        ];
        let mut x = 0x1234_5678u32;
        for _ in 0..100_000 {
            x ^= x << 13;
            x ^= x >> 17;
            x ^= x << 5;
            let f = f32::from_bits(x);
            if f.abs() < FLOOR_EXACT {
                v.push(f);
            }
            v.push((x % 20_000) as f32 * 0.013 - 130.0);
        }
        for &f in &v {
            assert_eq!(floor_i64(f), f.floor() as i64, "{f}");
        }
        for f in [
            f32::NAN,
            f32::INFINITY,
            f32::NEG_INFINITY,
            FLOOR_EXACT,
            -FLOOR_EXACT,
            8_388_609.0,
            -8_388_609.0,
            1e19,
            -1e19,
            f32::MAX,
            f32::MIN,
        ] {
            assert_eq!(floor_i64(f), f.floor() as i64, "{f}");
        }
        for f in v {
            let want = f.floor();
            assert_eq!(floor_i32(f), want as i32, "{f}");
            // The fraction, as the resampling uses it (-0.0 only for f = -0.0).
            let (a, b) = (f - floor_i32(f) as f32, f - want);
            assert!(a.to_bits() == b.to_bits() || (a == 0.0 && b == 0.0), "{f}");
        }
    }
}
