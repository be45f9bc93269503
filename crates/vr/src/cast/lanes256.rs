//! Eight and sixteen f32 lanes in AVX registers ([`Y8`]: one `__m256`, [`Y16`]: two): the
//! lane types of the set-up kernel on CPUs with AVX2 but without AVX-512F (Hunt et al. 2018,
//! §5.5: one pixel's 16 subsamples per 16-lane packet, `cast/setup/mod.rs`), and of the
//! per-tile triangle set-up there (`cast/setup/tile.rs`). Their portable twin is
//! [`crate::cast::lanes16::V16`] (four SSE registers); [`crate::cast::lanes512::Z16`] is the
//! AVX-512 form.
//!
//! **Invariant:** every operation is the same IEEE operation per lane as [`V16`]'s (glam's
//! `Vec4` on each quarter) and scalar f32's: `vaddps` / `vsubps` / `vmulps` / `vdivps` /
//! `vsqrtps` round like their SSE forms, no fused multiply-add (the entry points enable no FMA
//! and Rust never contracts); comparisons are ordered (false on NaN) except `ne` (`NEQ_UQ`,
//! true on NaN, as `cmpneqps`); `max_or_rhs` / `min_or_rhs` are `vmaxps` / `vminps`, which
//! return the second operand when either is NaN or both are zeros, exactly `a > b ? a : b` /
//! `a < b ? a : b`; `select` is `vblendvps` on masks whose lanes are all ones or all zeros (every
//! mask comes from a compare or their AND / OR), the same bits as `Vec4::select`'s bitwise
//! blend; the horizontal reductions run [`V16`]'s select tree on the same quarters (quarter
//! pairs first, then the lanes of one quarter). So the set-up kernel gives bit-identical
//! buffers with any of the lane types (tested here lane by lane and in `tests/cast.rs` on
//! whole casts).
//!
//! **Safety contract.** The methods execute AVX and AVX2 instructions; a value of [`Y8`] or
//! [`Y16`] must only exist inside code that runs after [`crate::cast::isa::avx2_detected`]
//! returned true (the entry points are `cast/setup/mod.rs`'s `run_setup_avx2*` and
//! `cast/setup/tile.rs`'s `setup_tile_avx2`, `unsafe`, called after the check). The types are
//! crate-private for that reason. The methods are `#[inline(always)]` and free of closures, so
//! inside those `#[target_feature(enable = "avx2,...")]` entry points every intrinsic compiles
//! to one instruction (an intrinsic cannot be inlined into a closure, which has no target
//! features of its own).

#![cfg(target_arch = "x86_64")]

use std::arch::x86_64::*;
use std::ops::{Add, Div, Mul, Sub};

use glam::Vec4;
use parallax_core::simd::Lanes;

use crate::cast::lanes16::LaneReduce;

/// Eight lanes in one `__m256` (module docs: only inside AVX2 code).
#[derive(Clone, Copy, Debug)]
pub(crate) struct Y8(__m256);

/// The mask of [`Y8`]: every lane all ones (true) or all zeros.
#[derive(Clone, Copy, Debug)]
pub(crate) struct YM8(__m256);

/// Sixteen lanes in two `__m256`: lane `i` is lane `i % 8` of half `i / 8`.
#[derive(Clone, Copy, Debug)]
pub(crate) struct Y16([__m256; 2]);

/// The mask of [`Y16`] (as [`YM8`], per half).
#[derive(Clone, Copy, Debug)]
pub(crate) struct YM16([__m256; 2]);

/// `a < b ? a : b` of the two quarters of `h` (`minps`): the first step of [`V16`]'s `hmin`
/// tree on a quarter pair.
#[inline(always)]
fn quarter_min(h: __m256) -> Vec4 {
    // SAFETY: module docs (AVX detected wherever a lane value exists).
    unsafe {
        Vec4::from(_mm_min_ps(
            _mm256_castps256_ps128(h),
            _mm256_extractf128_ps::<1>(h),
        ))
    }
}

/// `a > b ? a : b` of the two quarters of `h` (`maxps`), as [`quarter_min`].
#[inline(always)]
fn quarter_max(h: __m256) -> Vec4 {
    // SAFETY: module docs.
    unsafe {
        Vec4::from(_mm_max_ps(
            _mm256_castps256_ps128(h),
            _mm256_extractf128_ps::<1>(h),
        ))
    }
}

macro_rules! binop8 {
    ($tr:ident, $f:ident, $intr:ident) => {
        impl $tr for Y8 {
            type Output = Y8;
            #[inline(always)]
            fn $f(self, o: Y8) -> Y8 {
                // SAFETY: module docs.
                Y8(unsafe { $intr(self.0, o.0) })
            }
        }
        impl $tr for Y16 {
            type Output = Y16;
            #[inline(always)]
            fn $f(self, o: Y16) -> Y16 {
                // SAFETY: module docs.
                Y16(unsafe { [$intr(self.0[0], o.0[0]), $intr(self.0[1], o.0[1])] })
            }
        }
    };
}
binop8!(Add, add, _mm256_add_ps);
binop8!(Sub, sub, _mm256_sub_ps);
binop8!(Mul, mul, _mm256_mul_ps);
binop8!(Div, div, _mm256_div_ps);

macro_rules! cmp8 {
    ($f:ident, $pred:ident) => {
        #[inline(always)]
        fn $f(self, o: Self) -> YM8 {
            // SAFETY: module docs.
            YM8(unsafe { _mm256_cmp_ps::<$pred>(self.0, o.0) })
        }
    };
}

macro_rules! cmp16 {
    ($f:ident, $pred:ident) => {
        #[inline(always)]
        fn $f(self, o: Self) -> YM16 {
            // SAFETY: module docs.
            YM16(unsafe {
                [
                    _mm256_cmp_ps::<$pred>(self.0[0], o.0[0]),
                    _mm256_cmp_ps::<$pred>(self.0[1], o.0[1]),
                ]
            })
        }
    };
}

impl Lanes for Y8 {
    const N: usize = 8;
    type M = YM8;
    #[inline(always)]
    fn splat(x: f32) -> Self {
        // SAFETY: module docs.
        Y8(unsafe { _mm256_set1_ps(x) })
    }
    #[inline(always)]
    fn from_fn(mut f: impl FnMut(usize) -> f32) -> Self {
        let mut a = [0.0f32; 8];
        for (i, x) in a.iter_mut().enumerate() {
            *x = f(i);
        }
        // SAFETY: module docs; `a` holds 8 f32.
        Y8(unsafe { _mm256_loadu_ps(a.as_ptr()) })
    }
    #[inline(always)]
    fn get(self, i: usize) -> f32 {
        // SAFETY: `__m256` is 32 bytes of 8 f32 in lane order.
        unsafe { std::mem::transmute::<__m256, [f32; 8]>(self.0)[i] }
    }
    #[inline(always)]
    fn sqrt(self) -> Self {
        // SAFETY: module docs.
        Y8(unsafe { _mm256_sqrt_ps(self.0) })
    }
    cmp8!(lt, _CMP_LT_OQ);
    cmp8!(gt, _CMP_GT_OQ);
    cmp8!(le, _CMP_LE_OQ);
    cmp8!(ge, _CMP_GE_OQ);
    cmp8!(eq, _CMP_EQ_OQ);
    cmp8!(ne, _CMP_NEQ_UQ);
    #[inline(always)]
    fn max_or_rhs(self, o: Self) -> Self {
        // SAFETY: module docs. VMAXPS returns the second operand if either is NaN or both are
        // zeros: `self > o ? self : o`.
        Y8(unsafe { _mm256_max_ps(self.0, o.0) })
    }
    #[inline(always)]
    fn min_or_rhs(self, o: Self) -> Self {
        // SAFETY: module docs (VMINPS: as VMAXPS).
        Y8(unsafe { _mm256_min_ps(self.0, o.0) })
    }
    #[inline(always)]
    fn and(a: YM8, b: YM8) -> YM8 {
        // SAFETY: module docs.
        YM8(unsafe { _mm256_and_ps(a.0, b.0) })
    }
    #[inline(always)]
    fn or(a: YM8, b: YM8) -> YM8 {
        // SAFETY: module docs.
        YM8(unsafe { _mm256_or_ps(a.0, b.0) })
    }
    #[inline(always)]
    fn bits(m: YM8) -> u32 {
        // SAFETY: module docs (the lanes' sign bits: all ones or all zeros per lane).
        unsafe { _mm256_movemask_ps(m.0) as u32 }
    }
    #[inline(always)]
    fn sign_bits(self) -> u32 {
        // SAFETY: module docs.
        unsafe { _mm256_movemask_ps(self.0) as u32 }
    }
    #[inline(always)]
    fn select(m: YM8, a: Self, b: Self) -> Self {
        // SAFETY: module docs (lanes of `m` from `a`, the others from `b`).
        Y8(unsafe { _mm256_blendv_ps(b.0, a.0, m.0) })
    }
}

impl LaneReduce for Y8 {
    const AVX2: bool = true;
    // (No closures here: they would not be compiled with the caller's AVX2 features.)
    #[inline(always)]
    fn hmin4([a, b, c, d]: [Self; 4]) -> Vec4 {
        let q = [
            quarter_min(a.0),
            quarter_min(b.0),
            quarter_min(c.0),
            quarter_min(d.0),
        ];
        crate::cast::lanes16::hmin_of_quarters(q)
    }
    #[inline(always)]
    fn hmax4([a, b, c, d]: [Self; 4]) -> Vec4 {
        let q = [
            quarter_max(a.0),
            quarter_max(b.0),
            quarter_max(c.0),
            quarter_max(d.0),
        ];
        crate::cast::lanes16::hmax_of_quarters(q)
    }
    #[inline(always)]
    fn load16(a: &[f32; 16]) -> Self {
        // SAFETY: module docs; `a` holds 16 f32.
        Y8(unsafe { _mm256_loadu_ps(a.as_ptr()) })
    }
    #[inline(always)]
    fn load_n(a: &[f32]) -> Self {
        let a: &[f32; 8] = a[..8].try_into().expect("8 lanes");
        // SAFETY: module docs; `a` holds 8 f32.
        Y8(unsafe { _mm256_loadu_ps(a.as_ptr()) })
    }
    #[inline(always)]
    fn transpose8(rows: [Self; 8], out: &mut [[f32; 8]; 16]) {
        // SAFETY: module docs (AVX); unpacks, shuffles and lane permutes move bits only; each
        // store writes the 8 f32 of one `out[l]`.
        unsafe {
            let r = [
                rows[0].0, rows[1].0, rows[2].0, rows[3].0, rows[4].0, rows[5].0, rows[6].0,
                rows[7].0,
            ];
            let t0 = _mm256_unpacklo_ps(r[0], r[1]);
            let t1 = _mm256_unpackhi_ps(r[0], r[1]);
            let t2 = _mm256_unpacklo_ps(r[2], r[3]);
            let t3 = _mm256_unpackhi_ps(r[2], r[3]);
            let t4 = _mm256_unpacklo_ps(r[4], r[5]);
            let t5 = _mm256_unpackhi_ps(r[4], r[5]);
            let t6 = _mm256_unpacklo_ps(r[6], r[7]);
            let t7 = _mm256_unpackhi_ps(r[6], r[7]);
            let s0 = _mm256_shuffle_ps::<0x44>(t0, t2);
            let s1 = _mm256_shuffle_ps::<0xEE>(t0, t2);
            let s2 = _mm256_shuffle_ps::<0x44>(t1, t3);
            let s3 = _mm256_shuffle_ps::<0xEE>(t1, t3);
            let s4 = _mm256_shuffle_ps::<0x44>(t4, t6);
            let s5 = _mm256_shuffle_ps::<0xEE>(t4, t6);
            let s6 = _mm256_shuffle_ps::<0x44>(t5, t7);
            let s7 = _mm256_shuffle_ps::<0xEE>(t5, t7);
            let c = [
                _mm256_permute2f128_ps::<0x20>(s0, s4),
                _mm256_permute2f128_ps::<0x20>(s1, s5),
                _mm256_permute2f128_ps::<0x20>(s2, s6),
                _mm256_permute2f128_ps::<0x20>(s3, s7),
                _mm256_permute2f128_ps::<0x31>(s0, s4),
                _mm256_permute2f128_ps::<0x31>(s1, s5),
                _mm256_permute2f128_ps::<0x31>(s2, s6),
                _mm256_permute2f128_ps::<0x31>(s3, s7),
            ];
            for (o, c) in out.iter_mut().zip(c) {
                _mm256_storeu_ps(o.as_mut_ptr(), c);
            }
        }
    }
    #[inline(always)]
    fn hmin(self) -> f32 {
        quarter_min(self.0).hmin()
    }
    #[inline(always)]
    fn hmax(self) -> f32 {
        quarter_max(self.0).hmax()
    }
    #[inline(always)]
    fn write(self, out: &mut [f32]) {
        assert!(out.len() >= 8);
        // SAFETY: module docs; `out` holds at least 8 f32.
        unsafe { _mm256_storeu_ps(out.as_mut_ptr(), self.0) }
    }
    #[inline(always)]
    fn set_u32(m: YM8, v: u32, out: &mut [u32]) {
        assert!(out.len() >= 8);
        // SAFETY: module docs (AVX2); `out` holds at least 8 u32, only the lanes of `m` (sign
        // bit set) are stored.
        unsafe {
            _mm256_maskstore_epi32(
                out.as_mut_ptr() as *mut i32,
                _mm256_castps_si256(m.0),
                _mm256_set1_epi32(v as i32),
            )
        }
    }
}

impl Lanes for Y16 {
    const N: usize = 16;
    type M = YM16;
    #[inline(always)]
    fn splat(x: f32) -> Self {
        // SAFETY: module docs.
        let h = unsafe { _mm256_set1_ps(x) };
        Y16([h, h])
    }
    #[inline(always)]
    fn from_fn(mut f: impl FnMut(usize) -> f32) -> Self {
        let mut a = [0.0f32; 16];
        for (i, x) in a.iter_mut().enumerate() {
            *x = f(i);
        }
        Self::load16(&a)
    }
    #[inline(always)]
    fn get(self, i: usize) -> f32 {
        // SAFETY: two `__m256` are 64 bytes of 16 f32 in lane order.
        unsafe { std::mem::transmute::<[__m256; 2], [f32; 16]>(self.0)[i] }
    }
    #[inline(always)]
    fn sqrt(self) -> Self {
        // SAFETY: module docs.
        Y16(unsafe { [_mm256_sqrt_ps(self.0[0]), _mm256_sqrt_ps(self.0[1])] })
    }
    cmp16!(lt, _CMP_LT_OQ);
    cmp16!(gt, _CMP_GT_OQ);
    cmp16!(le, _CMP_LE_OQ);
    cmp16!(ge, _CMP_GE_OQ);
    cmp16!(eq, _CMP_EQ_OQ);
    cmp16!(ne, _CMP_NEQ_UQ);
    #[inline(always)]
    fn max_or_rhs(self, o: Self) -> Self {
        // SAFETY: module docs (VMAXPS: `self > o ? self : o`).
        Y16(unsafe {
            [
                _mm256_max_ps(self.0[0], o.0[0]),
                _mm256_max_ps(self.0[1], o.0[1]),
            ]
        })
    }
    #[inline(always)]
    fn min_or_rhs(self, o: Self) -> Self {
        // SAFETY: module docs (VMINPS: `self < o ? self : o`).
        Y16(unsafe {
            [
                _mm256_min_ps(self.0[0], o.0[0]),
                _mm256_min_ps(self.0[1], o.0[1]),
            ]
        })
    }
    #[inline(always)]
    fn and(a: YM16, b: YM16) -> YM16 {
        // SAFETY: module docs.
        YM16(unsafe { [_mm256_and_ps(a.0[0], b.0[0]), _mm256_and_ps(a.0[1], b.0[1])] })
    }
    #[inline(always)]
    fn or(a: YM16, b: YM16) -> YM16 {
        // SAFETY: module docs.
        YM16(unsafe { [_mm256_or_ps(a.0[0], b.0[0]), _mm256_or_ps(a.0[1], b.0[1])] })
    }
    #[inline(always)]
    fn bits(m: YM16) -> u32 {
        // SAFETY: module docs.
        unsafe { _mm256_movemask_ps(m.0[0]) as u32 | (_mm256_movemask_ps(m.0[1]) as u32) << 8 }
    }
    #[inline(always)]
    fn sign_bits(self) -> u32 {
        // SAFETY: module docs.
        unsafe {
            _mm256_movemask_ps(self.0[0]) as u32 | (_mm256_movemask_ps(self.0[1]) as u32) << 8
        }
    }
    #[inline(always)]
    fn select(m: YM16, a: Self, b: Self) -> Self {
        // SAFETY: module docs (lanes of `m` from `a`, the others from `b`).
        Y16(unsafe {
            [
                _mm256_blendv_ps(b.0[0], a.0[0], m.0[0]),
                _mm256_blendv_ps(b.0[1], a.0[1], m.0[1]),
            ]
        })
    }
}

/// The first steps of [`Y16`]'s `hmin` tree: quarters 0 and 1, 2 and 3, then the two.
#[inline(always)]
fn qmin16(x: Y16) -> Vec4 {
    Lanes::min_or_rhs(quarter_min(x.0[0]), quarter_min(x.0[1]))
}

/// The first steps of [`Y16`]'s `hmax` tree.
#[inline(always)]
fn qmax16(x: Y16) -> Vec4 {
    Lanes::max_or_rhs(quarter_max(x.0[0]), quarter_max(x.0[1]))
}

impl LaneReduce for Y16 {
    /// Eight runs per interval test: one `Y8` register per axis and bound.
    const RUN_GROUP: usize = 8;
    #[inline(always)]
    fn hmin4([a, b, c, d]: [Self; 4]) -> Vec4 {
        let q = [qmin16(a), qmin16(b), qmin16(c), qmin16(d)];
        crate::cast::lanes16::hmin_of_quarters(q)
    }
    #[inline(always)]
    fn hmax4([a, b, c, d]: [Self; 4]) -> Vec4 {
        let q = [qmax16(a), qmax16(b), qmax16(c), qmax16(d)];
        crate::cast::lanes16::hmax_of_quarters(q)
    }
    #[inline(always)]
    fn load16(a: &[f32; 16]) -> Self {
        // SAFETY: module docs; `a` holds 16 f32.
        Y16(unsafe {
            [
                _mm256_loadu_ps(a.as_ptr()),
                _mm256_loadu_ps(a.as_ptr().add(8)),
            ]
        })
    }
    #[inline(always)]
    fn load_n(a: &[f32]) -> Self {
        let a: &[f32; 16] = a[..16].try_into().expect("16 lanes");
        Self::load16(a)
    }
    #[inline(always)]
    fn hmin(self) -> f32 {
        // V16's tree: quarters 0 and 1, 2 and 3, then the two, then one quarter's lanes.
        let (a, b) = (quarter_min(self.0[0]), quarter_min(self.0[1]));
        Lanes::min_or_rhs(a, b).hmin()
    }
    #[inline(always)]
    fn hmax(self) -> f32 {
        let (a, b) = (quarter_max(self.0[0]), quarter_max(self.0[1]));
        Lanes::max_or_rhs(a, b).hmax()
    }
    #[inline(always)]
    fn write(self, out: &mut [f32]) {
        assert!(out.len() >= 16);
        // SAFETY: module docs; `out` holds at least 16 f32.
        unsafe {
            _mm256_storeu_ps(out.as_mut_ptr(), self.0[0]);
            _mm256_storeu_ps(out.as_mut_ptr().add(8), self.0[1]);
        }
    }
    #[inline(always)]
    fn set_u32(m: YM16, v: u32, out: &mut [u32]) {
        assert!(out.len() >= 16);
        // SAFETY: module docs (AVX2); `out` holds at least 16 u32, only the lanes of `m` are
        // stored.
        unsafe {
            let p = out.as_mut_ptr() as *mut i32;
            let x = _mm256_set1_epi32(v as i32);
            _mm256_maskstore_epi32(p, _mm256_castps_si256(m.0[0]), x);
            _mm256_maskstore_epi32(p.add(8), _mm256_castps_si256(m.0[1]), x);
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    use crate::cast::isa::avx2_detected;
    use crate::cast::lanes16::V16;
    use crate::cast::lanes16::tests::{A, B, same};

    /// Every lane operation, the masks' bits, the reductions and the writes of `L` equal
    /// [`V16`]'s on the lanes `0..L::N` of `A` and `B` (rotated by `r`).
    fn check<L: LaneReduce>(r: usize) {
        let xa: [f32; 16] = std::array::from_fn(|i| A[(i + r) % 16]);
        let xb: [f32; 16] = std::array::from_fn(|i| B[(i + 3 * r) % 16]);
        let (a, b) = (L::from_fn(|i| xa[i]), L::from_fn(|i| xb[i]));
        let (p, q) = (V16::from_fn(|i| xa[i]), V16::from_fn(|i| xb[i]));
        parallax_core::simd::assert_lanes_match_scalar(a, b, &xa, &xb);
        let n = L::N;
        let lanes = |y: L, v: V16, what: &str| {
            for i in 0..n {
                assert!(same(y.get(i), v.get(i)), "{what} lane {i} ({n} lanes)");
            }
        };
        lanes(a + b, p + q, "add");
        lanes(a - b, p - q, "sub");
        lanes(a * b, p * q, "mul");
        lanes(a / b, p / q, "div");
        lanes(a.sqrt(), p.sqrt(), "sqrt");
        lanes(a.max_or_rhs(b), p.max_or_rhs(q), "max");
        lanes(a.min_or_rhs(b), p.min_or_rhs(q), "min");
        lanes(
            L::select(a.lt(b), a, b),
            V16::select(p.lt(q), p, q),
            "select",
        );
        lanes(L::load16(&xa), p, "load16");
        lanes(L::load_n(&xa), p, "load_n");
        let low = (1u32 << n) - 1;
        for (y, v) in [
            (a.lt(b), p.lt(q)),
            (a.gt(b), p.gt(q)),
            (a.le(b), p.le(q)),
            (a.ge(b), p.ge(q)),
            (a.eq(b), p.eq(q)),
            (a.ne(b), p.ne(q)),
        ] {
            assert_eq!(L::bits(y), V16::bits(v) & low);
        }
        assert_eq!(a.sign_bits(), p.sign_bits() & low);
        // The reductions: `V16`'s tree on the same sixteen lanes, NaNs and signed zeros
        // included (eight lanes: the tree of the first two quarters).
        if n == 16 {
            assert!(same(a.hmin(), p.hmin()), "hmin {xa:?}");
            assert!(same(a.hmax(), p.hmax()), "hmax {xa:?}");
        } else {
            let q = p.0;
            let min = Lanes::min_or_rhs(q[0], q[1]).hmin();
            let max = Lanes::max_or_rhs(q[0], q[1]).hmax();
            assert!(same(a.hmin(), min), "hmin {xa:?}");
            assert!(same(a.hmax(), max), "hmax {xa:?}");
        }
        // Four reductions at once: each register's own reduction, bit for bit.
        let four = [a, b, a * b, a - b];
        let (mn, mx) = (L::hmin4(four), L::hmax4(four));
        for k in 0..4 {
            assert!(same(mn[k], four[k].hmin()), "hmin4 {xa:?} {xb:?}");
            assert!(same(mx[k], four[k].hmax()), "hmax4 {xa:?} {xb:?}");
        }
        let (mut x, mut y) = ([0.0f32; 16], [0.0f32; 16]);
        a.write(&mut x);
        p.write(&mut y);
        assert_eq!(x[..n].iter().map(|v| v.to_bits()).collect::<Vec<_>>(), {
            y[..n].iter().map(|v| v.to_bits()).collect::<Vec<_>>()
        });
        // The transpose: lane `l` of row `k` at `out[l][k]`, bit for bit (NaN payloads and
        // signed zeros of `A` / `B`), the rows past `N` untouched.
        let rows: [L; 8] = std::array::from_fn(|k| {
            L::from_fn(|i| {
                if k % 2 == 0 {
                    xa[(i + k) % 16]
                } else {
                    xb[(i + 5 * k) % 16]
                }
            })
        });
        let mut out = [[f32::from_bits(0x7fc0_1234); 8]; 16];
        L::transpose8(rows, &mut out);
        for (l, o) in out.iter().enumerate() {
            for (k, row) in rows.iter().enumerate() {
                let want = if l < n {
                    row.get(l).to_bits()
                } else {
                    0x7fc0_1234
                };
                assert_eq!(
                    o[k].to_bits(),
                    want,
                    "transpose8 lane {l} row {k} ({n} lanes)"
                );
            }
        }
        let (mut s, mut t) = ([7u32; 16], [7u32; 16]);
        L::set_u32(a.lt(b), 42, &mut s);
        V16::set_u32(p.lt(q), 42, &mut t);
        assert_eq!(s[..n], t[..n]);
        assert!(s[n..].iter().all(|&v| v == 7));
    }

    #[target_feature(enable = "avx2")]
    fn check_all() {
        for r in 0..16 {
            check::<Y8>(r);
            check::<Y16>(r);
        }
    }

    /// Every lane of every operation equals the portable twin's (NaNs, infinities, signed
    /// zeros), and both reductions follow its select tree.
    #[test]
    fn avx2_lanes_equal_the_portable_lanes() {
        if avx2_detected() {
            // SAFETY: detected.
            unsafe { check_all() };
        } else {
            eprintln!("AVX2 not detected: the AVX2 lanes are not tested on this CPU");
        }
    }
}
