//! The sixteen lanes of [`Lanes16`] on AVX2: two 256-bit registers, lanes 0..8 in the first
//! and 8..16 in the second. Comparisons give their masks through `movemask` (bit `i` = lane
//! `i`); a mask becomes a vector again by shifting bit `i` of a broadcast into the sign bit of
//! lane `i` (`vpsllvd`), the only bit `vblendvps` reads.
//!
//! Each operation is the IEEE operation of the portable twin on every lane (`vmaxps` /
//! `vminps` return the second operand on NaN, as `maxps` / `minps`; ordered comparisons but
//! `ne`), so the results are bit-identical to [`Portable16`](super::Portable16)'s; the test
//! below holds them against each other wherever AVX2 is detected.
//!
//! | operation | instructions per 16 lanes |
//! |---|---|
//! | arithmetic, min / max | 2 |
//! | comparison to mask | 2 compares, 2 `vmovmskps`, shift-or |
//! | `select` | broadcast, 2 `vpsllvd`, 2 `vblendvps` |
//! | `load_rays` | 16 loads, an 8x8 transpose per half (24 shuffles) |

use std::arch::x86_64::*;

use parallax_core::Ray;

use super::{F16, Lanes16, U16};
use crate::traverse8::{Avx2Boxes8, RayBoxes8};

/// AVX2 lanes (a token: made only by [`Avx2::new`], which requires AVX2, so the safe methods
/// never run where the instructions do not exist).
#[derive(Clone, Copy, Debug)]
pub(crate) struct Avx2(());

impl Avx2 {
    /// # Safety
    /// The CPU must support AVX2.
    #[inline(always)]
    pub unsafe fn new() -> Self {
        Avx2(())
    }
}

/// Lanes `0..8` and `8..16`.
pub(crate) type V2 = [__m256; 2];

/// Mask bit `8 h + j` of a broadcast shifted into the sign bit of lane `j` of half `h`.
const SIGN_SHIFTS: [[i32; 8]; 2] = [
    [31, 30, 29, 28, 27, 26, 25, 24],
    [23, 22, 21, 20, 19, 18, 17, 16],
];

// SAFETY (every method): a value of `Avx2` exists only where AVX2 was detected (`Avx2::new`);
// aligned loads and stores are of the two 32-byte halves of 64-byte aligned `F16` / `U16`.
impl Avx2 {
    /// The sign-bit vectors of mask `m` (module docs).
    #[inline(always)]
    fn mask_vectors(self, m: u32) -> [__m256i; 2] {
        unsafe {
            let b = _mm256_set1_epi32(m as i32);
            let s = SIGN_SHIFTS.as_ptr() as *const __m256i;
            [
                _mm256_sllv_epi32(b, _mm256_loadu_si256(s)),
                _mm256_sllv_epi32(b, _mm256_loadu_si256(s.add(1))),
            ]
        }
    }

    /// The sign bits of the 16 lanes as a mask.
    #[inline(always)]
    fn signs(self, v: V2) -> u32 {
        unsafe { _mm256_movemask_ps(v[0]) as u32 | (_mm256_movemask_ps(v[1]) as u32) << 8 }
    }

    /// The 16-bit mask of comparison `P` lane by lane.
    #[inline(always)]
    fn cmp<const P: i32>(self, a: V2, b: V2) -> u32 {
        unsafe {
            self.signs([
                _mm256_cmp_ps::<P>(a[0], b[0]),
                _mm256_cmp_ps::<P>(a[1], b[1]),
            ])
        }
    }

    /// `v` with the lanes outside `m` replaced by `fill`, folded to one 128-bit half with `f`.
    #[inline(always)]
    fn fold_masked(self, m: u32, v: V2, fill: f32, max: bool) -> f32 {
        unsafe {
            let [k0, k1] = self.mask_vectors(m);
            let f = _mm256_set1_ps(fill);
            let lo = _mm256_blendv_ps(f, v[0], _mm256_castsi256_ps(k0));
            let hi = _mm256_blendv_ps(f, v[1], _mm256_castsi256_ps(k1));
            // Macros, not closures: closures do not inherit the caller's target features.
            macro_rules! op8 {
                ($a:expr, $b:expr) => {
                    if max {
                        _mm256_max_ps($a, $b)
                    } else {
                        _mm256_min_ps($a, $b)
                    }
                };
            }
            macro_rules! op4 {
                ($a:expr, $b:expr) => {
                    if max {
                        _mm_max_ps($a, $b)
                    } else {
                        _mm_min_ps($a, $b)
                    }
                };
            }
            let x = op8!(lo, hi);
            let x = op4!(_mm256_castps256_ps128(x), _mm256_extractf128_ps::<1>(x));
            let x = op4!(x, _mm_movehl_ps(x, x));
            let x = op4!(x, _mm_shuffle_ps::<0b01>(x, x));
            _mm_cvtss_f32(x)
        }
    }
}

impl Lanes16 for Avx2 {
    type V = V2;
    const AVX2: bool = true;
    type Single = Avx2Boxes8;
    #[inline(always)]
    fn single(self, rb: RayBoxes8) -> Avx2Boxes8 {
        // SAFETY: AVX2 was detected (`Avx2::new`).
        unsafe { Avx2Boxes8::new(rb) }
    }
    #[inline(always)]
    fn splat(self, x: f32) -> V2 {
        unsafe { [_mm256_set1_ps(x); 2] }
    }
    #[inline(always)]
    fn load(self, a: &F16) -> V2 {
        let p = a.0.as_ptr();
        unsafe { [_mm256_load_ps(p), _mm256_load_ps(p.add(8))] }
    }
    #[inline(always)]
    fn store(self, v: V2, a: &mut F16) {
        let p = a.0.as_mut_ptr();
        unsafe {
            _mm256_store_ps(p, v[0]);
            _mm256_store_ps(p.add(8), v[1]);
        }
    }
    #[inline(always)]
    fn add(self, a: V2, b: V2) -> V2 {
        unsafe { [_mm256_add_ps(a[0], b[0]), _mm256_add_ps(a[1], b[1])] }
    }
    #[inline(always)]
    fn sub(self, a: V2, b: V2) -> V2 {
        unsafe { [_mm256_sub_ps(a[0], b[0]), _mm256_sub_ps(a[1], b[1])] }
    }
    #[inline(always)]
    fn mul(self, a: V2, b: V2) -> V2 {
        unsafe { [_mm256_mul_ps(a[0], b[0]), _mm256_mul_ps(a[1], b[1])] }
    }
    #[inline(always)]
    fn div(self, a: V2, b: V2) -> V2 {
        unsafe { [_mm256_div_ps(a[0], b[0]), _mm256_div_ps(a[1], b[1])] }
    }
    #[inline(always)]
    fn max(self, a: V2, b: V2) -> V2 {
        // VMAXPS: if either operand is a NaN, the second operand is returned.
        unsafe { [_mm256_max_ps(a[0], b[0]), _mm256_max_ps(a[1], b[1])] }
    }
    #[inline(always)]
    fn min(self, a: V2, b: V2) -> V2 {
        unsafe { [_mm256_min_ps(a[0], b[0]), _mm256_min_ps(a[1], b[1])] }
    }
    #[inline(always)]
    fn le(self, a: V2, b: V2) -> u32 {
        self.cmp::<_CMP_LE_OQ>(a, b)
    }
    #[inline(always)]
    fn lt(self, a: V2, b: V2) -> u32 {
        self.cmp::<_CMP_LT_OQ>(a, b)
    }
    #[inline(always)]
    fn gt(self, a: V2, b: V2) -> u32 {
        self.cmp::<_CMP_GT_OQ>(a, b)
    }
    #[inline(always)]
    fn eq(self, a: V2, b: V2) -> u32 {
        self.cmp::<_CMP_EQ_OQ>(a, b)
    }
    #[inline(always)]
    fn ne(self, a: V2, b: V2) -> u32 {
        self.cmp::<_CMP_NEQ_UQ>(a, b)
    }
    #[inline(always)]
    fn select(self, m: u32, a: V2, b: V2) -> V2 {
        let k = self.mask_vectors(m);
        unsafe {
            [
                _mm256_blendv_ps(b[0], a[0], _mm256_castsi256_ps(k[0])),
                _mm256_blendv_ps(b[1], a[1], _mm256_castsi256_ps(k[1])),
            ]
        }
    }
    #[inline(always)]
    fn gt_u32(self, m: u32, idx: &U16, x: u32) -> u32 {
        // Unsigned `>` as signed `>` with the sign bits flipped.
        unsafe {
            let flip = _mm256_set1_epi32(i32::MIN);
            let xs = _mm256_set1_epi32((x ^ 0x8000_0000) as i32);
            let p = idx.0.as_ptr() as *const __m256i;
            let mut g = [_mm256_setzero_ps(); 2];
            for (h, gh) in g.iter_mut().enumerate() {
                let v = _mm256_xor_si256(_mm256_load_si256(p.add(h)), flip);
                *gh = _mm256_castsi256_ps(_mm256_cmpgt_epi32(v, xs));
            }
            self.signs(g) & m
        }
    }
    #[inline(always)]
    fn hmin(self, m: u32, v: V2) -> f32 {
        self.fold_masked(m, v, f32::INFINITY, false)
    }
    #[inline(always)]
    fn hmax(self, m: u32, v: V2) -> f32 {
        self.fold_masked(m, v, f32::NEG_INFINITY, true)
    }
    #[inline(always)]
    fn store_u32_masked(self, m: u32, a: &mut U16, x: u32) {
        let k = self.mask_vectors(m);
        unsafe {
            let p = a.0.as_mut_ptr() as *mut __m256i;
            let xv = _mm256_castsi256_ps(_mm256_set1_epi32(x as i32));
            for (h, kh) in k.iter().enumerate() {
                let old = _mm256_castsi256_ps(_mm256_load_si256(p.add(h)));
                let new = _mm256_blendv_ps(old, xv, _mm256_castsi256_ps(*kh));
                _mm256_store_si256(p.add(h), _mm256_castps_si256(new));
            }
        }
    }
    #[inline(always)]
    fn abs(self, a: V2) -> V2 {
        unsafe {
            let sign = _mm256_set1_ps(-0.0);
            [_mm256_andnot_ps(sign, a[0]), _mm256_andnot_ps(sign, a[1])]
        }
    }
    #[inline(always)]
    fn eq_bits(self, a: V2, b: V2) -> u32 {
        unsafe {
            let mut e = [_mm256_setzero_ps(); 2];
            for (h, eh) in e.iter_mut().enumerate() {
                *eh = _mm256_castsi256_ps(_mm256_cmpeq_epi32(
                    _mm256_castps_si256(a[h]),
                    _mm256_castps_si256(b[h]),
                ));
            }
            self.signs(e)
        }
    }
    #[inline(always)]
    fn same_sign(self, a: V2, b: V2, c: V2) -> u32 {
        // The sign bit of `(a ^ b) | (a ^ c)` is set where the three differ.
        unsafe {
            let mut d = [_mm256_setzero_ps(); 2];
            for (h, dh) in d.iter_mut().enumerate() {
                *dh = _mm256_or_ps(_mm256_xor_ps(a[h], b[h]), _mm256_xor_ps(a[h], c[h]));
            }
            !self.signs(d) & 0xFFFF
        }
    }
    #[allow(clippy::needless_range_loop)] // the loop index addresses several arrays in step
    #[inline(always)]
    fn load_rays(self, rays: &[Ray; 16]) -> [V2; 8] {
        // A `Ray` is eight f32 (origin, dir, t_min, t_max): one 256-bit load per ray, and per
        // half of the packet an 8x8 transpose (unpack pairs of rays, shuffle quads, swap
        // 128-bit halves); no gathers.
        let base = rays.as_ptr() as *const f32;
        let mut out = [[unsafe { _mm256_setzero_ps() }; 2]; 8];
        for h in 0..2 {
            // SAFETY: the loads cover the 256 bytes of rays `8 h .. 8 h + 8`.
            unsafe {
                let mut r = [_mm256_setzero_ps(); 8];
                for (j, rj) in r.iter_mut().enumerate() {
                    *rj = _mm256_loadu_ps(base.add(8 * (8 * h + j)));
                }
                // `t[2p]`, `t[2p + 1]`: rays 2p, 2p + 1 interleaved, fields (0, 1 | 4, 5) and
                // (2, 3 | 6, 7).
                let mut t = [_mm256_setzero_ps(); 8];
                for p in 0..4 {
                    t[2 * p] = _mm256_unpacklo_ps(r[2 * p], r[2 * p + 1]);
                    t[2 * p + 1] = _mm256_unpackhi_ps(r[2 * p], r[2 * p + 1]);
                }
                // `s[4q + f]`: rays 4q .. 4q + 4 of field f (low 128 bits) and f + 4 (high).
                let mut s = [_mm256_setzero_ps(); 8];
                for q in 0..2 {
                    for g in 0..2 {
                        let (x, y) = (t[4 * q + g], t[4 * q + 2 + g]);
                        s[4 * q + 2 * g] = _mm256_shuffle_ps::<0x44>(x, y);
                        s[4 * q + 2 * g + 1] = _mm256_shuffle_ps::<0xEE>(x, y);
                    }
                }
                for f in 0..4 {
                    out[f][h] = _mm256_permute2f128_ps::<0x20>(s[f], s[4 + f]);
                    out[f + 4][h] = _mm256_permute2f128_ps::<0x31>(s[f], s[4 + f]);
                }
            }
        }
        out
    }
}

#[cfg(test)]
mod tests {
    /// The AVX2 lanes equal the portable ones bit for bit, NaN rules included (where AVX2 is
    /// detected at run time).
    #[test]
    fn avx2_lanes_equal_portable_lanes() {
        if crate::traverse8::use_avx2() {
            // SAFETY: detected.
            super::super::tests::check_against_portable(unsafe { super::Avx2::new() });
        }
    }
}
