//! Eight f32 lanes for the single-ray triangle test over the two blocks of a leaf at once
//! (Woop et al. 2013's watertight test, `tri4.rs`): [`A8`], one AVX register, inside the AVX2
//! traversal kernel, and its portable twin `parallax_core::simd::F8` (plain `[f32; 8]` loops)
//! in the portable kernel. A leaf of five to eight triangles (two `Tri4` blocks) is tested by
//! one 8-lane pass instead of two 4-lane ones (`Tri4Ray::intersect2`).
//!
//! | lane type | where | registers per row |
//! |---|---|---|
//! | [`A8`] | `closest8_avx2` (after AVX2 detection) | one `__m256` |
//! | `F8` | `closest8_portable` (the twin) | plain loops |
//!
//! **Invariant:** every operation is the same IEEE operation per lane as `F8`'s, `Vec4`'s and
//! scalar f32's: `vaddps` / `vsubps` / `vmulps` / `vdivps` / `vsqrtps` round like their scalar
//! forms, no fused multiply-add; comparisons are ordered (false on NaN) except `ne` (`NEQ_UQ`,
//! true on NaN); `max_or_rhs` / `min_or_rhs` are `vmaxps` / `vminps` (the second operand when
//! either is NaN or both are zeros). So a pair test computes, lane by lane, the bits of the two
//! 4-lane tests (`tests` below; `tests/simd_twins.rs` on whole scenes).
//!
//! **Safety contract.** [`A8`]'s methods execute AVX instructions; a value of [`A8`] exists only
//! inside code that runs after AVX2 was detected (made only by the `Pair8` implementation of the
//! AVX2 node test, itself made only after detection). The methods are `#[inline(always)]` and
//! free of closures, so inside the `#[target_feature(enable = "avx2")]` kernel every intrinsic
//! compiles to one instruction (an intrinsic is not inlined into a closure, which has no target
//! features of its own).

use std::ops::{Add, Div, Mul, Sub};

use glam::Vec4;
use parallax_core::simd::{F8, Lanes};

/// A lane type for the 8-lane pair test: loads one row of two blocks (`tri4.rs`).
pub(crate) trait Pair8: Lanes {
    /// Lanes `0..4` from `lo`, `4..8` from `hi`.
    fn halves(lo: &Vec4, hi: &Vec4) -> Self;
    fn to_array(self) -> [f32; 8];
}

impl Pair8 for F8 {
    #[inline(always)]
    fn halves(lo: &Vec4, hi: &Vec4) -> Self {
        let (l, h) = (lo.to_array(), hi.to_array());
        F8([l[0], l[1], l[2], l[3], h[0], h[1], h[2], h[3]])
    }
    #[inline(always)]
    fn to_array(self) -> [f32; 8] {
        self.0
    }
}

#[cfg(target_arch = "x86_64")]
pub(crate) use avx::A8;

#[cfg(target_arch = "x86_64")]
mod avx {
    use super::*;
    use std::arch::x86_64::*;

    /// Eight lanes in one `__m256` (module docs: only inside AVX2 code).
    #[derive(Clone, Copy, Debug)]
    pub(crate) struct A8(__m256);

    /// The mask of [`A8`]: all bits set in a true lane.
    #[derive(Clone, Copy, Debug)]
    pub(crate) struct AM8(__m256);

    macro_rules! binop {
        ($tr:ident, $f:ident, $intr:ident) => {
            impl $tr for A8 {
                type Output = A8;
                #[inline(always)]
                fn $f(self, o: A8) -> A8 {
                    // SAFETY: module docs (AVX2 detected wherever an `A8` exists).
                    A8(unsafe { $intr(self.0, o.0) })
                }
            }
        };
    }
    binop!(Add, add, _mm256_add_ps);
    binop!(Sub, sub, _mm256_sub_ps);
    binop!(Mul, mul, _mm256_mul_ps);
    binop!(Div, div, _mm256_div_ps);

    macro_rules! cmp {
        ($f:ident, $pred:ident) => {
            #[inline(always)]
            fn $f(self, o: Self) -> AM8 {
                // SAFETY: module docs.
                AM8(unsafe { _mm256_cmp_ps::<$pred>(self.0, o.0) })
            }
        };
    }

    impl Lanes for A8 {
        const N: usize = 8;
        type M = AM8;
        #[inline(always)]
        fn splat(x: f32) -> Self {
            // SAFETY: module docs.
            A8(unsafe { _mm256_set1_ps(x) })
        }
        #[inline(always)]
        fn from_fn(mut f: impl FnMut(usize) -> f32) -> Self {
            let a = [f(0), f(1), f(2), f(3), f(4), f(5), f(6), f(7)];
            // SAFETY: module docs; `a` holds 8 f32.
            A8(unsafe { _mm256_loadu_ps(a.as_ptr()) })
        }
        #[inline(always)]
        fn get(self, i: usize) -> f32 {
            self.to_array()[i]
        }
        #[inline(always)]
        fn sqrt(self) -> Self {
            // SAFETY: module docs.
            A8(unsafe { _mm256_sqrt_ps(self.0) })
        }
        cmp!(lt, _CMP_LT_OQ);
        cmp!(gt, _CMP_GT_OQ);
        cmp!(le, _CMP_LE_OQ);
        cmp!(ge, _CMP_GE_OQ);
        cmp!(eq, _CMP_EQ_OQ);
        cmp!(ne, _CMP_NEQ_UQ);
        #[inline(always)]
        fn max_or_rhs(self, o: Self) -> Self {
            // SAFETY: module docs. VMAXPS returns the second operand if either is NaN or both
            // are zeros: `self > o ? self : o`.
            A8(unsafe { _mm256_max_ps(self.0, o.0) })
        }
        #[inline(always)]
        fn min_or_rhs(self, o: Self) -> Self {
            // SAFETY: module docs (VMINPS: as VMAXPS).
            A8(unsafe { _mm256_min_ps(self.0, o.0) })
        }
        #[inline(always)]
        fn and(a: AM8, b: AM8) -> AM8 {
            // SAFETY: module docs.
            AM8(unsafe { _mm256_and_ps(a.0, b.0) })
        }
        #[inline(always)]
        fn or(a: AM8, b: AM8) -> AM8 {
            // SAFETY: module docs.
            AM8(unsafe { _mm256_or_ps(a.0, b.0) })
        }
        #[inline(always)]
        fn bits(m: AM8) -> u32 {
            // SAFETY: module docs.
            unsafe { _mm256_movemask_ps(m.0) as u32 }
        }
        #[inline(always)]
        fn sign_bits(self) -> u32 {
            // SAFETY: module docs (`vmovmskps`: the sign bits).
            unsafe { _mm256_movemask_ps(self.0) as u32 }
        }
        #[inline(always)]
        fn select(m: AM8, a: Self, b: Self) -> Self {
            // SAFETY: module docs (the mask lanes are all ones or all zeros).
            A8(unsafe { _mm256_blendv_ps(b.0, a.0, m.0) })
        }
    }

    impl Pair8 for A8 {
        #[inline(always)]
        fn halves(lo: &Vec4, hi: &Vec4) -> Self {
            // SAFETY: module docs; `Vec4` is 16 f32-aligned bytes (`__m128` on x86_64).
            unsafe {
                let l = _mm_load_ps(lo as *const Vec4 as *const f32);
                let h = _mm_load_ps(hi as *const Vec4 as *const f32);
                A8(_mm256_insertf128_ps::<1>(_mm256_castps128_ps256(l), h))
            }
        }
        #[inline(always)]
        fn to_array(self) -> [f32; 8] {
            // SAFETY: `__m256` is 8 f32 in lane order.
            unsafe { std::mem::transmute::<__m256, [f32; 8]>(self.0) }
        }
    }

    impl A8 {
        /// An `A8` for the tests.
        ///
        /// # Safety
        /// The CPU must support AVX2.
        #[cfg(test)]
        pub unsafe fn from_array(a: [f32; 8]) -> Self {
            // SAFETY: caller.
            A8(unsafe { _mm256_loadu_ps(a.as_ptr()) })
        }
    }
}

#[cfg(all(test, target_arch = "x86_64"))]
mod tests {
    use super::*;
    use parallax_core::simd::assert_lanes_match_scalar;

    #[test]
    fn a8_matches_scalar() {
        if !std::is_x86_feature_detected!("avx2") {
            return;
        }
        let special = [
            0.0,
            -0.0,
            1.0,
            -1.0,
            f32::INFINITY,
            f32::NEG_INFINITY,
            f32::NAN,
            -f32::NAN,
            1e-30,
            -3.5,
            2.0,
            f32::MIN_POSITIVE,
        ];
        let n = special.len();
        for s in 0..n * n {
            let xs: Vec<f32> = (0..8).map(|i| special[(s + i) % n]).collect();
            let ys: Vec<f32> = (0..8).map(|i| special[(s / n + 3 * i) % n]).collect();
            // SAFETY: AVX2 detected above.
            let (a, b) = unsafe {
                (
                    A8::from_array(xs.clone().try_into().unwrap()),
                    A8::from_array(ys.clone().try_into().unwrap()),
                )
            };
            assert_lanes_match_scalar(a, b, &xs, &ys);
        }
    }
}
