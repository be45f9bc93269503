//! Sixteen f32 lanes in one AVX-512 register ([`Z16`]): the lane type of the 16-ray set-up
//! kernel on CPUs with AVX-512F (Hunt et al. 2018, §5.5: one pixel's 16 subsamples per packet,
//! `cast/setup/mod.rs`). Its portable twin is [`crate::cast::lanes16::V16`] (four SSE
//! registers), which every other CPU runs.
//!
//! **Invariant:** every operation is the same IEEE operation per lane as [`V16`]'s (and scalar
//! f32's): `vaddps` / `vsubps` / `vmulps` / `vdivps` / `vsqrtps` round like their SSE forms, no
//! fused multiply-add; comparisons are ordered (false on NaN) except `ne` (`NEQ_UQ`, true on
//! NaN); `max_or_rhs` / `min_or_rhs` are `vmaxps` / `vminps`, which return the second operand
//! when either is NaN or both are zeros, exactly `a > b ? a : b` / `a < b ? a : b`; the
//! horizontal reductions run [`V16`]'s tree, its first two steps by quarter swaps in the
//! register (the same operands in the same order). So the set-up kernel
//! gives bit-identical buffers with either lane type (tested here lane by lane and in
//! `tests/cast.rs` on whole casts).
//!
//! **Safety contract.** The methods execute AVX-512F instructions; a value of [`Z16`] must only
//! exist inside code that runs after `is_x86_feature_detected!("avx512f")` returned true (the
//! one entry point is `cast/setup/mod.rs`'s `run_setup_avx512`, `unsafe`, called after the
//! check). The type is crate-private for that reason. The methods are `#[inline(always)]` and
//! free of closures, so inside that `#[target_feature(enable = "avx512f")]` entry point every
//! intrinsic compiles to one instruction (an intrinsic cannot be inlined into a closure, which
//! has no target features of its own).

#![cfg(target_arch = "x86_64")]

use std::arch::x86_64::*;
use std::ops::{Add, Div, Mul, Sub};

use parallax_core::simd::Lanes;

#[cfg(doc)]
use crate::cast::lanes16::V16;
use crate::cast::lanes16::{LaneReduce, hmax_of_quarters, hmin_of_quarters};

/// Sixteen lanes in one `__m512` (module docs: only inside AVX-512F code).
#[derive(Clone, Copy, Debug)]
pub(crate) struct Z16(__m512);

/// The mask of [`Z16`]: bit `i` = lane `i` (an AVX-512 `k` register).
#[derive(Clone, Copy, Debug)]
pub(crate) struct K16(u16);

macro_rules! binop {
    ($tr:ident, $f:ident, $intr:ident) => {
        impl $tr for Z16 {
            type Output = Z16;
            #[inline(always)]
            fn $f(self, o: Z16) -> Z16 {
                // SAFETY: module docs (AVX-512F detected wherever a `Z16` exists).
                Z16(unsafe { $intr(self.0, o.0) })
            }
        }
    };
}
binop!(Add, add, _mm512_add_ps);
binop!(Sub, sub, _mm512_sub_ps);
binop!(Mul, mul, _mm512_mul_ps);
binop!(Div, div, _mm512_div_ps);

macro_rules! cmp {
    ($f:ident, $pred:ident) => {
        #[inline(always)]
        fn $f(self, o: Self) -> K16 {
            // SAFETY: module docs.
            K16(unsafe { _mm512_cmp_ps_mask::<$pred>(self.0, o.0) })
        }
    };
}

impl Z16 {
    /// The first two steps of [`V16`]'s reduction tree in the register (`q` the quarters):
    /// `f(f(q0, q1), f(q2, q3))` as one SSE register, `f` = `vminps` / `vmaxps` (`op`), by two
    /// quarter swaps instead of a round trip through memory. The same operands in the same
    /// order as `lanes16::qmin` / `qmax`, so the same bits.
    #[inline(always)]
    fn quarter_tree(self, op: unsafe fn(__m512, __m512) -> __m512) -> glam::Vec4 {
        // SAFETY: module docs; `op` is `_mm512_min_ps` or `_mm512_max_ps` (inlined: a call of
        // an intrinsic through a known function pointer is resolved at compile time).
        unsafe {
            let v = self.0;
            // [q1, q0, q3, q2]: quarter 0 of `m` is f(q0, q1), quarter 2 f(q2, q3).
            let m = op(v, _mm512_shuffle_f32x4::<0b10_11_00_01>(v, v));
            // [m2, m3, m0, m1]: quarter 0 of `r` is f(m0, m2).
            let r = op(m, _mm512_shuffle_f32x4::<0b01_00_11_10>(m, m));
            glam::Vec4::from(_mm512_castps512_ps128(r))
        }
    }
}

impl Lanes for Z16 {
    const N: usize = 16;
    type M = K16;
    #[inline(always)]
    fn splat(x: f32) -> Self {
        // SAFETY: module docs.
        Z16(unsafe { _mm512_set1_ps(x) })
    }
    #[inline(always)]
    fn from_fn(mut f: impl FnMut(usize) -> f32) -> Self {
        let mut a = [0.0f32; 16];
        for (i, x) in a.iter_mut().enumerate() {
            *x = f(i);
        }
        // SAFETY: module docs; `a` holds 16 f32.
        Z16(unsafe { _mm512_loadu_ps(a.as_ptr()) })
    }
    #[inline(always)]
    fn get(self, i: usize) -> f32 {
        // SAFETY: as `quarters`.
        unsafe { std::mem::transmute::<__m512, [f32; 16]>(self.0)[i] }
    }
    #[inline(always)]
    fn sqrt(self) -> Self {
        // SAFETY: module docs.
        Z16(unsafe { _mm512_sqrt_ps(self.0) })
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
        Z16(unsafe { _mm512_max_ps(self.0, o.0) })
    }
    #[inline(always)]
    fn min_or_rhs(self, o: Self) -> Self {
        // SAFETY: module docs (VMINPS: as VMAXPS).
        Z16(unsafe { _mm512_min_ps(self.0, o.0) })
    }
    #[inline(always)]
    fn and(a: K16, b: K16) -> K16 {
        K16(a.0 & b.0)
    }
    #[inline(always)]
    fn or(a: K16, b: K16) -> K16 {
        K16(a.0 | b.0)
    }
    #[inline(always)]
    fn bits(m: K16) -> u32 {
        m.0 as u32
    }
    #[inline(always)]
    fn sign_bits(self) -> u32 {
        // SAFETY: module docs. Signed compare of the bit patterns with zero: the sign bits.
        unsafe {
            _mm512_cmplt_epi32_mask(_mm512_castps_si512(self.0), _mm512_setzero_si512()) as u32
        }
    }
    #[inline(always)]
    fn select(m: K16, a: Self, b: Self) -> Self {
        // SAFETY: module docs (lanes of `m` from `a`, the others from `b`).
        Z16(unsafe { _mm512_mask_blend_ps(m.0, b.0, a.0) })
    }
}

impl LaneReduce for Z16 {
    const RUN_GROUP: usize = 16;
    #[inline(always)]
    fn load16(a: &[f32; 16]) -> Self {
        // SAFETY: module docs; `a` holds 16 f32.
        Z16(unsafe { _mm512_loadu_ps(a.as_ptr()) })
    }
    #[inline(always)]
    fn load_n(a: &[f32]) -> Self {
        let a: &[f32; 16] = a[..16].try_into().expect("16 lanes");
        Self::load16(a)
    }
    #[inline(always)]
    fn hmin(self) -> f32 {
        LaneReduce::hmin(self.quarter_tree(_mm512_min_ps))
    }
    #[inline(always)]
    fn hmax(self) -> f32 {
        LaneReduce::hmax(self.quarter_tree(_mm512_max_ps))
    }
    #[inline(always)]
    fn hmin4([a, b, c, d]: [Self; 4]) -> glam::Vec4 {
        // (No closure: module docs.)
        let f = _mm512_min_ps;
        let q = [
            a.quarter_tree(f),
            b.quarter_tree(f),
            c.quarter_tree(f),
            d.quarter_tree(f),
        ];
        hmin_of_quarters(q)
    }
    #[inline(always)]
    fn hmax4([a, b, c, d]: [Self; 4]) -> glam::Vec4 {
        let f = _mm512_max_ps;
        let q = [
            a.quarter_tree(f),
            b.quarter_tree(f),
            c.quarter_tree(f),
            d.quarter_tree(f),
        ];
        hmax_of_quarters(q)
    }
    #[inline(always)]
    fn write(self, out: &mut [f32]) {
        assert!(out.len() >= 16);
        // SAFETY: module docs; `out` holds at least 16 f32.
        unsafe { _mm512_storeu_ps(out.as_mut_ptr(), self.0) }
    }
    #[inline(always)]
    fn set_u32(m: K16, v: u32, out: &mut [u32]) {
        assert!(out.len() >= 16);
        // SAFETY: module docs; `out` holds at least 16 u32, only the lanes of `m` are stored.
        unsafe {
            _mm512_mask_storeu_epi32(
                out.as_mut_ptr() as *mut i32,
                m.0,
                _mm512_set1_epi32(v as i32),
            )
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::cast::lanes16::V16;

    use crate::cast::lanes16::tests::{A, B, same};

    #[target_feature(enable = "avx512f")]
    fn check() {
        let (a, b) = (Z16::from_fn(|i| A[i]), Z16::from_fn(|i| B[i]));
        let (p, q) = (V16::from_fn(|i| A[i]), V16::from_fn(|i| B[i]));
        let both = |z: Z16, v: V16, what: &str| {
            for i in 0..16 {
                assert!(same(z.get(i), v.get(i)), "{what} lane {i}");
            }
        };
        both(a + b, p + q, "add");
        both(a - b, p - q, "sub");
        both(a * b, p * q, "mul");
        both(a / b, p / q, "div");
        both(a.sqrt(), p.sqrt(), "sqrt");
        both(a.max_or_rhs(b), p.max_or_rhs(q), "max");
        both(a.min_or_rhs(b), p.min_or_rhs(q), "min");
        both(
            Z16::select(a.lt(b), a, b),
            V16::select(p.lt(q), p, q),
            "select",
        );
        assert_eq!(Z16::bits(a.lt(b)), V16::bits(p.lt(q)));
        assert_eq!(Z16::bits(a.gt(b)), V16::bits(p.gt(q)));
        assert_eq!(Z16::bits(a.le(b)), V16::bits(p.le(q)));
        assert_eq!(Z16::bits(a.ge(b)), V16::bits(p.ge(q)));
        assert_eq!(Z16::bits(a.eq(b)), V16::bits(p.eq(q)));
        assert_eq!(Z16::bits(a.ne(b)), V16::bits(p.ne(q)));
        assert_eq!(
            Z16::bits(Z16::and(a.le(b), a.ge(b))),
            V16::bits(V16::and(p.le(q), p.ge(q)))
        );
        assert_eq!(
            Z16::bits(Z16::or(a.lt(b), a.eq(b))),
            V16::bits(V16::or(p.lt(q), p.eq(q)))
        );
        // Reductions over NaN-free lanes.
        let c = Z16::from_fn(|i| if A[i].is_nan() { 0.5 } else { A[i] });
        let r = V16::from_fn(|i| if A[i].is_nan() { 0.5 } else { A[i] });
        assert!(same(c.hmin(), r.hmin()));
        assert!(same(c.hmax(), r.hmax()));
        // Signed zeros decide which operand a reduction step returns: the same tree.
        let zs = |k: usize| {
            Z16::from_fn(|i| {
                if (i * 7 + k).is_multiple_of(3) {
                    -0.0
                } else {
                    0.0
                }
            })
        };
        let vs = |k: usize| {
            V16::from_fn(|i| {
                if (i * 7 + k).is_multiple_of(3) {
                    -0.0
                } else {
                    0.0
                }
            })
        };
        for k in 0..3 {
            assert!(same(zs(k).hmin(), vs(k).hmin()) && same(zs(k).hmax(), vs(k).hmax()));
        }
        let four = |f: fn(usize) -> f32| {
            let z = [0, 1, 2, 3].map(|k| Z16::from_fn(|i| f(16 * k + i)));
            let v = [0, 1, 2, 3].map(|k| V16::from_fn(|i| f(16 * k + i)));
            let (a, b) = (Z16::hmin4(z), V16::hmin4(v));
            let (c, d) = (Z16::hmax4(z), V16::hmax4(v));
            for k in 0..4 {
                assert!(same(a[k], b[k]) && same(c[k], d[k]), "hmin4 / hmax4 {k}");
            }
        };
        four(|j| {
            if A[j % 16].is_nan() {
                B[j % 16]
            } else {
                A[j % 16] * (j / 16) as f32
            }
        });
        four(|j| if j % 5 == 0 { -0.0 } else { 0.0 });
        let (mut x, mut y) = ([0.0f32; 16], [0.0f32; 16]);
        c.write(&mut x);
        r.write(&mut y);
        assert_eq!(x.map(f32::to_bits), y.map(f32::to_bits));
    }

    /// Every lane of every operation equals the portable twin's (NaNs, infinities, signed zeros).
    #[test]
    fn avx512_lanes_equal_the_portable_lanes() {
        if std::is_x86_feature_detected!("avx512f") {
            // SAFETY: detected.
            unsafe { check() };
        }
    }
}
