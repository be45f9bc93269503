//! Sixteen f32 lanes, one per ray of a packet: the vector operations the packet traversal
//! (`packet8.rs`) is written in, for AVX-512 (one 512-bit register), AVX2 (two 256-bit
//! registers, `lanes16/avx2.rs`), both behind runtime detection (`packet_lanes.rs`), and a
//! portable twin (four glam `Vec4`s: SSE2 on x86_64, scalar elsewhere).
//!
//! Each operation is the same IEEE operation on every lane in both versions, so the two give
//! bit-identical results: `max(a, b)` / `min(a, b)` return `b` when either is NaN (`maxps` /
//! `minps` semantics, see `simd.rs`); comparisons are ordered (false on NaN) except `ne`
//! (true on NaN, as `cmpneq`); no fused multiply-add. A value of an implementing type is a
//! token: the AVX-512 one can only be made by [`Avx512::new`], which is `unsafe` and requires
//! AVX-512F (the AVX2 one likewise by `Avx2::new`), so the safe methods below never run where
//! the instructions do not exist.

use glam::{BVec4A, Vec4};
use parallax_core::Ray;

use crate::traverse8::{NodeTest8, Portable8, RayBoxes8};

// The SIMD lanes' `load_rays` (AVX-512 here, AVX2 in `lanes16/avx2.rs`) read a `Ray` as eight
// f32: origin, dir, t_min, t_max.
const _: () = assert!(std::mem::size_of::<Ray>() == 32);
const _: () = assert!(std::mem::offset_of!(Ray, origin) == 0);
const _: () = assert!(std::mem::offset_of!(Ray, dir) == 12);
const _: () = assert!(std::mem::offset_of!(Ray, t_min) == 24);
const _: () = assert!(std::mem::offset_of!(Ray, t_max) == 28);

#[cfg(target_arch = "x86_64")]
mod avx2;
#[cfg(target_arch = "x86_64")]
pub(crate) use avx2::Avx2;

/// Sixteen values aligned for one 512-bit load.
#[derive(Clone, Copy, Debug, PartialEq)]
#[repr(C, align(64))]
pub(crate) struct F16(pub [f32; 16]);

/// Sixteen u32 values (triangle indices) aligned for one 512-bit load.
#[derive(Clone, Copy, Debug, PartialEq)]
#[repr(C, align(64))]
pub(crate) struct U16(pub [u32; 16]);

/// The lane operations (module docs). Masks are `u32` with bit `i` = lane `i`.
pub(crate) trait Lanes16: Copy {
    type V: Copy;
    /// Whether a value of this type proves AVX2 (256-bit ops for the 8-lane interval test).
    const AVX2: bool;
    /// The single-ray node test of the same ISA (for rays the packet hands over).
    type Single: NodeTest8;
    fn single(self, rb: RayBoxes8) -> Self::Single;
    fn splat(self, x: f32) -> Self::V;
    fn load(self, a: &F16) -> Self::V;
    fn store(self, v: Self::V, a: &mut F16);
    fn add(self, a: Self::V, b: Self::V) -> Self::V;
    fn sub(self, a: Self::V, b: Self::V) -> Self::V;
    fn mul(self, a: Self::V, b: Self::V) -> Self::V;
    fn div(self, a: Self::V, b: Self::V) -> Self::V;
    /// `a > b ? a : b` (NaN in either gives `b`).
    fn max(self, a: Self::V, b: Self::V) -> Self::V;
    /// `a < b ? a : b` (NaN in either gives `b`).
    fn min(self, a: Self::V, b: Self::V) -> Self::V;
    fn le(self, a: Self::V, b: Self::V) -> u32;
    fn lt(self, a: Self::V, b: Self::V) -> u32;
    fn gt(self, a: Self::V, b: Self::V) -> u32;
    fn eq(self, a: Self::V, b: Self::V) -> u32;
    fn ne(self, a: Self::V, b: Self::V) -> u32;
    /// `m ? a : b` per lane.
    fn select(self, m: u32, a: Self::V, b: Self::V) -> Self::V;
    /// Lanes `i` of `m` with `idx[i] > x` (unsigned).
    fn gt_u32(self, m: u32, idx: &U16, x: u32) -> u32;
    /// The minimum of the lanes `m` of `v` (+inf when `m` is empty; no NaN in those lanes).
    fn hmin(self, m: u32, v: Self::V) -> f32;
    /// The maximum of the lanes `m` of `v` (-inf when `m` is empty; no NaN in those lanes).
    fn hmax(self, m: u32, v: Self::V) -> f32;
    /// Writes `x` into the lanes `m` of `a`.
    fn store_u32_masked(self, m: u32, a: &mut U16, x: u32);
    /// `|a|` (the sign bit cleared).
    fn abs(self, a: Self::V) -> Self::V;
    /// Lanes whose bits are equal (`-0.0 != 0.0`, a NaN equals itself).
    fn eq_bits(self, a: Self::V, b: Self::V) -> u32;
    /// Lanes where `a`, `b` and `c` have the same sign bit (`-0.0` and a NaN by their sign
    /// bits): for values that are neither zero nor NaN, "all three `< 0` or all `> 0`".
    fn same_sign(self, a: Self::V, b: Self::V, c: Self::V) -> u32;
    /// The fields of 16 rays, lane `i` = ray `i`: origin x, y, z, direction x, y, z, `t_min`,
    /// `t_max`.
    fn load_rays(self, rays: &[Ray; 16]) -> [Self::V; 8];
}

/// Field `k` of [`Lanes16::load_rays`] of `r`.
#[inline(always)]
fn ray_field(r: &Ray, k: usize) -> f32 {
    match k {
        0..3 => r.origin[k],
        3..6 => r.dir[k - 3],
        6 => r.t_min,
        _ => r.t_max,
    }
}

/// The portable twin.
#[derive(Clone, Copy, Debug)]
pub(crate) struct Portable16;

#[inline(always)]
fn bits4(m: u32) -> BVec4A {
    BVec4A::new(m & 1 != 0, m & 2 != 0, m & 4 != 0, m & 8 != 0)
}

macro_rules! per4 {
    ($a:ident, $b:ident, $f:expr) => {{
        let f = $f;
        [
            f($a[0], $b[0]),
            f($a[1], $b[1]),
            f($a[2], $b[2]),
            f($a[3], $b[3]),
        ]
    }};
}

macro_rules! cmp4 {
    ($a:ident, $b:ident, $f:expr) => {{
        let f = $f;
        let mut m = 0u32;
        for g in 0..4 {
            m |= f($a[g], $b[g]) << (4 * g);
        }
        m
    }};
}

impl Lanes16 for Portable16 {
    type V = [Vec4; 4];
    const AVX2: bool = false;
    type Single = Portable8;
    #[inline(always)]
    fn single(self, rb: RayBoxes8) -> Portable8 {
        Portable8(rb)
    }
    #[inline(always)]
    fn splat(self, x: f32) -> [Vec4; 4] {
        [Vec4::splat(x); 4]
    }
    #[inline(always)]
    fn load(self, a: &F16) -> [Vec4; 4] {
        std::array::from_fn(|g| Vec4::from_slice(&a.0[4 * g..4 * g + 4]))
    }
    #[inline(always)]
    fn store(self, v: [Vec4; 4], a: &mut F16) {
        for (g, vg) in v.iter().enumerate() {
            vg.write_to_slice(&mut a.0[4 * g..4 * g + 4]);
        }
    }
    #[inline(always)]
    fn add(self, a: [Vec4; 4], b: [Vec4; 4]) -> [Vec4; 4] {
        per4!(a, b, |x, y| x + y)
    }
    #[inline(always)]
    fn sub(self, a: [Vec4; 4], b: [Vec4; 4]) -> [Vec4; 4] {
        per4!(a, b, |x, y| x - y)
    }
    #[inline(always)]
    fn mul(self, a: [Vec4; 4], b: [Vec4; 4]) -> [Vec4; 4] {
        per4!(a, b, |x, y| x * y)
    }
    #[inline(always)]
    fn div(self, a: [Vec4; 4], b: [Vec4; 4]) -> [Vec4; 4] {
        per4!(a, b, |x, y| x / y)
    }
    #[inline(always)]
    fn max(self, a: [Vec4; 4], b: [Vec4; 4]) -> [Vec4; 4] {
        per4!(a, b, parallax_core::simd::max_or_rhs)
    }
    #[inline(always)]
    fn min(self, a: [Vec4; 4], b: [Vec4; 4]) -> [Vec4; 4] {
        per4!(a, b, parallax_core::simd::min_or_rhs)
    }
    #[inline(always)]
    fn le(self, a: [Vec4; 4], b: [Vec4; 4]) -> u32 {
        cmp4!(a, b, |x: Vec4, y| x.cmple(y).bitmask())
    }
    #[inline(always)]
    fn lt(self, a: [Vec4; 4], b: [Vec4; 4]) -> u32 {
        cmp4!(a, b, |x: Vec4, y| x.cmplt(y).bitmask())
    }
    #[inline(always)]
    fn gt(self, a: [Vec4; 4], b: [Vec4; 4]) -> u32 {
        cmp4!(a, b, |x: Vec4, y| x.cmpgt(y).bitmask())
    }
    #[inline(always)]
    fn eq(self, a: [Vec4; 4], b: [Vec4; 4]) -> u32 {
        cmp4!(a, b, |x: Vec4, y| x.cmpeq(y).bitmask())
    }
    #[inline(always)]
    fn ne(self, a: [Vec4; 4], b: [Vec4; 4]) -> u32 {
        cmp4!(a, b, |x: Vec4, y| x.cmpne(y).bitmask())
    }
    #[inline(always)]
    fn select(self, m: u32, a: [Vec4; 4], b: [Vec4; 4]) -> [Vec4; 4] {
        std::array::from_fn(|g| Vec4::select(bits4(m >> (4 * g)), a[g], b[g]))
    }
    #[inline(always)]
    fn gt_u32(self, m: u32, idx: &U16, x: u32) -> u32 {
        let mut out = 0;
        for i in 0..16 {
            out |= ((m >> i & 1 != 0 && idx.0[i] > x) as u32) << i;
        }
        out
    }
    #[inline(always)]
    fn hmin(self, m: u32, v: [Vec4; 4]) -> f32 {
        let mut a = F16([0.0; 16]);
        self.store(v, &mut a);
        (0..16)
            .filter(|i| m >> i & 1 != 0)
            .fold(f32::INFINITY, |b, i| b.min(a.0[i]))
    }
    #[inline(always)]
    fn hmax(self, m: u32, v: [Vec4; 4]) -> f32 {
        let mut a = F16([0.0; 16]);
        self.store(v, &mut a);
        (0..16)
            .filter(|i| m >> i & 1 != 0)
            .fold(f32::NEG_INFINITY, |b, i| b.max(a.0[i]))
    }
    #[inline(always)]
    fn store_u32_masked(self, m: u32, a: &mut U16, x: u32) {
        for i in 0..16 {
            if m >> i & 1 != 0 {
                a.0[i] = x;
            }
        }
    }
    #[inline(always)]
    fn abs(self, a: [Vec4; 4]) -> [Vec4; 4] {
        a.map(Vec4::abs)
    }
    #[inline(always)]
    fn eq_bits(self, a: [Vec4; 4], b: [Vec4; 4]) -> u32 {
        let (mut x, mut y) = (F16([0.0; 16]), F16([0.0; 16]));
        self.store(a, &mut x);
        self.store(b, &mut y);
        (0..16).fold(0, |m, i| {
            m | ((x.0[i].to_bits() == y.0[i].to_bits()) as u32) << i
        })
    }
    #[inline(always)]
    fn same_sign(self, a: [Vec4; 4], b: [Vec4; 4], c: [Vec4; 4]) -> u32 {
        let mut m = 0;
        for g in 0..4 {
            let (x, y, z) = (
                a[g].is_negative_bitmask(),
                b[g].is_negative_bitmask(),
                c[g].is_negative_bitmask(),
            );
            m |= (x & y & z | !(x | y | z) & 0xF) << (4 * g);
        }
        m
    }
    #[inline(always)]
    fn load_rays(self, rays: &[Ray; 16]) -> [[Vec4; 4]; 8] {
        std::array::from_fn(|k| self.load(&F16(std::array::from_fn(|i| ray_field(&rays[i], k)))))
    }
}

/// AVX-512F lanes (a token: see the module docs).
#[cfg(target_arch = "x86_64")]
#[derive(Clone, Copy, Debug)]
pub(crate) struct Avx512(());

#[cfg(target_arch = "x86_64")]
impl Avx512 {
    /// # Safety
    /// The CPU must support AVX-512F and AVX2.
    #[inline(always)]
    pub unsafe fn new() -> Self {
        Avx512(())
    }
}

#[cfg(target_arch = "x86_64")]
mod avx512 {
    use std::arch::x86_64::*;

    use parallax_core::Ray;

    use super::{Avx512, F16, Lanes16, U16};

    /// The permute indices of [`Lanes16::load_rays`]: per round, for the output that takes the
    /// bit `y` (0, 1) of the field number, lane `p` of it reads lane `idx & 15` of the pair's
    /// first (`idx < 16`) or second register. Register number / lane bits, most significant
    /// first (`i` the ray, `k` the field): loads `(i3 i2 i1) / (i0 k2 k1 k0)`; round 0 ->
    /// `(k2 i2 i1) / (i3 i0 k1 k0)`; round 1 -> `(k2 k1 i1) / (i3 i2 i0 k0)`; round 2 ->
    /// `(k2 k1 k0) / (i3 i2 i1 i0)`, i.e. register `k`, lane `i`.
    const TRANSPOSE: [[[i32; 16]; 2]; 3] = {
        let mut t = [[[0; 16]; 2]; 3];
        let mut y = 0;
        while y < 2 {
            let mut p = 0;
            while p < 16 {
                let [b0, b1, b2, b3] = [p & 1, (p >> 1) & 1, (p >> 2) & 1, p >> 3];
                t[0][y as usize][p as usize] = 16 * b3 + 8 * b2 + 4 * y + 2 * b1 + b0;
                t[1][y as usize][p as usize] = 16 * b2 + 8 * b3 + 4 * b1 + 2 * y + b0;
                t[2][y as usize][p as usize] = 16 * b1 + 8 * b3 + 4 * b2 + 2 * b0 + y;
                p += 1;
            }
            y += 1;
        }
        t
    };

    // SAFETY (every method): a value of `Avx512` exists only where AVX-512F was detected
    // (`Avx512::new`); loads and stores are of 64-byte aligned `F16` / `U16`.
    impl Lanes16 for Avx512 {
        type V = __m512;
        const AVX2: bool = true;
        type Single = crate::traverse8::Avx2Boxes8;
        #[inline(always)]
        fn single(self, rb: crate::traverse8::RayBoxes8) -> Self::Single {
            // SAFETY: AVX-512F and AVX2 were detected (`Avx512::new`).
            unsafe { crate::traverse8::Avx2Boxes8::new(rb) }
        }
        #[inline(always)]
        fn splat(self, x: f32) -> __m512 {
            unsafe { _mm512_set1_ps(x) }
        }
        #[inline(always)]
        fn load(self, a: &F16) -> __m512 {
            unsafe { _mm512_load_ps(a.0.as_ptr()) }
        }
        #[inline(always)]
        fn store(self, v: __m512, a: &mut F16) {
            unsafe { _mm512_store_ps(a.0.as_mut_ptr(), v) }
        }
        #[inline(always)]
        fn add(self, a: __m512, b: __m512) -> __m512 {
            unsafe { _mm512_add_ps(a, b) }
        }
        #[inline(always)]
        fn sub(self, a: __m512, b: __m512) -> __m512 {
            unsafe { _mm512_sub_ps(a, b) }
        }
        #[inline(always)]
        fn mul(self, a: __m512, b: __m512) -> __m512 {
            unsafe { _mm512_mul_ps(a, b) }
        }
        #[inline(always)]
        fn div(self, a: __m512, b: __m512) -> __m512 {
            unsafe { _mm512_div_ps(a, b) }
        }
        #[inline(always)]
        fn max(self, a: __m512, b: __m512) -> __m512 {
            // VMAXPS: "If only one value is a NaN ... the second operand ... is returned";
            // both NaN: the second too.
            unsafe { _mm512_max_ps(a, b) }
        }
        #[inline(always)]
        fn min(self, a: __m512, b: __m512) -> __m512 {
            unsafe { _mm512_min_ps(a, b) }
        }
        #[inline(always)]
        fn le(self, a: __m512, b: __m512) -> u32 {
            unsafe { _mm512_cmp_ps_mask::<_CMP_LE_OQ>(a, b) as u32 }
        }
        #[inline(always)]
        fn lt(self, a: __m512, b: __m512) -> u32 {
            unsafe { _mm512_cmp_ps_mask::<_CMP_LT_OQ>(a, b) as u32 }
        }
        #[inline(always)]
        fn gt(self, a: __m512, b: __m512) -> u32 {
            unsafe { _mm512_cmp_ps_mask::<_CMP_GT_OQ>(a, b) as u32 }
        }
        #[inline(always)]
        fn eq(self, a: __m512, b: __m512) -> u32 {
            unsafe { _mm512_cmp_ps_mask::<_CMP_EQ_OQ>(a, b) as u32 }
        }
        #[inline(always)]
        fn ne(self, a: __m512, b: __m512) -> u32 {
            unsafe { _mm512_cmp_ps_mask::<_CMP_NEQ_UQ>(a, b) as u32 }
        }
        #[inline(always)]
        fn select(self, m: u32, a: __m512, b: __m512) -> __m512 {
            unsafe { _mm512_mask_blend_ps(m as __mmask16, b, a) }
        }
        #[inline(always)]
        fn gt_u32(self, m: u32, idx: &U16, x: u32) -> u32 {
            unsafe {
                let v = _mm512_load_si512(idx.0.as_ptr() as *const _);
                _mm512_mask_cmpgt_epu32_mask(m as __mmask16, v, _mm512_set1_epi32(x as i32)) as u32
            }
        }
        #[inline(always)]
        fn hmin(self, m: u32, v: __m512) -> f32 {
            // The masked reduction fills unused lanes with `f32::MAX`, not +inf.
            let inf = unsafe { _mm512_set1_ps(f32::INFINITY) };
            unsafe { _mm512_reduce_min_ps(_mm512_mask_blend_ps(m as __mmask16, inf, v)) }
        }
        #[inline(always)]
        fn hmax(self, m: u32, v: __m512) -> f32 {
            let ninf = unsafe { _mm512_set1_ps(f32::NEG_INFINITY) };
            unsafe { _mm512_reduce_max_ps(_mm512_mask_blend_ps(m as __mmask16, ninf, v)) }
        }
        #[inline(always)]
        fn store_u32_masked(self, m: u32, a: &mut U16, x: u32) {
            unsafe {
                let p = a.0.as_mut_ptr() as *mut _;
                let v = _mm512_mask_mov_epi32(
                    _mm512_load_si512(p as *const _),
                    m as __mmask16,
                    _mm512_set1_epi32(x as i32),
                );
                _mm512_store_si512(p, v)
            }
        }
        #[inline(always)]
        fn abs(self, a: __m512) -> __m512 {
            unsafe { _mm512_abs_ps(a) }
        }
        #[inline(always)]
        fn eq_bits(self, a: __m512, b: __m512) -> u32 {
            unsafe {
                _mm512_cmpeq_epi32_mask(_mm512_castps_si512(a), _mm512_castps_si512(b)) as u32
            }
        }
        #[inline(always)]
        fn same_sign(self, a: __m512, b: __m512, c: __m512) -> u32 {
            unsafe {
                // Truth table 0x81: set where the three bits are 000 or 111.
                let e = _mm512_ternarylogic_epi32::<0x81>(
                    _mm512_castps_si512(a),
                    _mm512_castps_si512(b),
                    _mm512_castps_si512(c),
                );
                _mm512_cmplt_epi32_mask(e, _mm512_setzero_si512()) as u32
            }
        }
        #[inline(always)]
        fn load_rays(self, rays: &[Ray; 16]) -> [__m512; 8] {
            // A `Ray` is eight f32 (origin, dir, t_min, t_max), so the 16 rays are eight
            // 512-bit loads (`r[j]`: rays 2j and 2j + 1) transposed by three rounds of
            // two-source permutes (`TRANSPOSE`); no gathers.
            let base = rays.as_ptr() as *const f32;
            // SAFETY: the eight loads cover the 512 bytes of the 16 rays.
            unsafe {
                let mut r: [__m512; 8] = std::array::from_fn(|j| _mm512_loadu_ps(base.add(16 * j)));
                for (round, idx) in TRANSPOSE.iter().enumerate() {
                    let (lo, hi) = (
                        _mm512_loadu_si512(idx[0].as_ptr() as *const _),
                        _mm512_loadu_si512(idx[1].as_ptr() as *const _),
                    );
                    // Round `round` pairs the registers that differ in bit `2 - round` of
                    // their number; the outputs keep the pair's slots (`y = 0` low).
                    let bit = 4 >> round;
                    let mut next = r;
                    for a in (0..8).filter(|a| a & bit == 0) {
                        let (x, y) = (r[a], r[a | bit]);
                        next[a] = _mm512_permutex2var_ps(x, lo, y);
                        next[a | bit] = _mm512_permutex2var_ps(x, hi, y);
                    }
                    r = next;
                }
                r
            }
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// The AVX-512 lanes equal the portable ones bit for bit, NaN rules included.
    #[test]
    fn avx512_lanes_equal_portable_lanes() {
        #[cfg(target_arch = "x86_64")]
        if std::is_x86_feature_detected!("avx512f") {
            // SAFETY: detected.
            check_against_portable(unsafe { Avx512::new() });
        }
        check_against_portable(Portable16);
    }

    /// Every operation of `l` against [`Portable16`], bit for bit, NaN rules included
    /// (`avx2.rs` runs it for the AVX2 lanes).
    pub(super) fn check_against_portable<L: Lanes16>(l: L) {
        let vals = [
            0.0,
            -0.0,
            1.0,
            -1.5,
            f32::NAN,
            f32::INFINITY,
            -f32::INFINITY,
            3.0e-39,
            7.25,
            -2.0,
            f32::NAN,
            1e30,
            0.5,
            -0.0,
            2.0,
            1.0,
        ];
        let a = F16(vals);
        let mut bv = vals;
        bv.rotate_left(3);
        let b = F16(bv);
        let p = Portable16;
        let (x, y) = (l.load(&a), l.load(&b));
        let (px, py) = (p.load(&a), p.load(&b));
        let same = |v: L::V, w: [Vec4; 4]| {
            let (mut o, mut q) = (F16([0.0; 16]), F16([0.0; 16]));
            l.store(v, &mut o);
            p.store(w, &mut q);
            assert_eq!(o.0.map(f32::to_bits), q.0.map(f32::to_bits));
        };
        same(l.add(x, y), p.add(px, py));
        same(l.sub(x, y), p.sub(px, py));
        same(l.mul(x, y), p.mul(px, py));
        same(l.div(x, y), p.div(px, py));
        same(l.max(x, y), p.max(px, py));
        same(l.min(x, y), p.min(px, py));
        same(l.select(0xA5C3, x, y), p.select(0xA5C3, px, py));
        assert_eq!(l.le(x, y), p.le(px, py));
        assert_eq!(l.lt(x, y), p.lt(px, py));
        assert_eq!(l.gt(x, y), p.gt(px, py));
        assert_eq!(l.eq(x, y), p.eq(px, py));
        assert_eq!(l.ne(x, y), p.ne(px, py));
        let idx = U16(std::array::from_fn(|i| (i as u32 * 7) % 11));
        assert_eq!(l.gt_u32(0xFFF0, &idx, 5), p.gt_u32(0xFFF0, &idx, 5));
        // Lanes without NaN or zeros (the sign of a zero minimum is unspecified).
        for m in [0, 0xDBEC, 0x000C, 0x0800] {
            assert_eq!(l.hmin(m, x).to_bits(), p.hmin(m, px).to_bits(), "{m:x}");
            assert_eq!(l.hmax(m, x).to_bits(), p.hmax(m, px).to_bits(), "{m:x}");
        }
        same(l.abs(x), p.abs(px));
        assert_eq!(l.eq_bits(x, y), p.eq_bits(px, py));
        assert_eq!(l.eq_bits(x, x), 0xFFFF);
        let mut cv = vals;
        cv.rotate_left(7);
        let (z, pz) = (l.load(&F16(cv)), p.load(&F16(cv)));
        assert_eq!(l.same_sign(x, y, z), p.same_sign(px, py, pz));
        for (i, ((&u, &v), &w)) in vals.iter().zip(&bv).zip(&cv).enumerate() {
            let signs = [u, v, w].map(f32::is_sign_negative);
            let want = signs[0] == signs[1] && signs[1] == signs[2];
            assert_eq!(p.same_sign(px, py, pz) >> i & 1 != 0, want, "lane {i}");
        }
        let rays: [Ray; 16] = std::array::from_fn(|i| {
            let f = i as f32;
            Ray::segment(
                glam::Vec3::new(f, -f, 0.5 * f),
                glam::Vec3::new(1.0 + f, 2.0, -f),
                0.25 * f,
                10.0 + f,
            )
        });
        let (lr, pr) = (l.load_rays(&rays), p.load_rays(&rays));
        for k in 0..8 {
            same(lr[k], pr[k]);
        }
        let mut f0 = F16([0.0; 16]);
        p.store(pr[3], &mut f0);
        assert_eq!(f0.0[5], rays[5].dir.x);
        let (mut u, mut w) = (idx, idx);
        l.store_u32_masked(0x0F0F, &mut u, 99);
        p.store_u32_masked(0x0F0F, &mut w, 99);
        assert_eq!(u, w);
    }
}
