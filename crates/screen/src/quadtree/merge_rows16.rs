//! One row of a pruning level (Widmer et al. 2015, §3.3) with sixteen parents per step in
//! AVX-512 lanes (run-time detection of AVX-512 F, BW, DQ, VL and F16C): `merge_rows8`'s
//! merge ([`MergeCtx::merge_wide`], generic over the lanes) in the lanes of `__m512`s; and
//! the rows' entry point [`MergeCtx::parent_row_fast_of`], which takes it first where the CPU
//! has them (the eight-parent kernel does the rest of the row; without AVX2, `merge_rows`'
//! four-parent rows).
//!
//! **Same bits.** The merge is the same generic code as the eight-parent kernel's, each
//! [`MergeLanes`] method the same IEEE operation per lane (`vsqrtps`, `vdivps`, products
//! and sums correctly rounded per lane, `vminps` / `vmaxps` picking the same operand,
//! compares with the same predicates into `__mmask16` bits, a select as a masked blend,
//! nothing fused), so every lane computes what the eight-lane kernel computes for its parent.
//! The children are gathered four parents at a time (`Kids`, as there); the f16 increments
//! are decoded by `vcvtph2ps` and the proxy's encoded by `vcvtps2ph` with rounding to nearest
//! even, as `leaf_avx2::f16x8` (the definition's rounding). When all sixteen parents merge
//! their nodes are stored straight from the lanes; otherwise each half of eight takes the
//! eight-parent kernel's tail (`MergeCtx::finish8`) with the merges passed in.
//!
//! `F16` / `M16` wrap `__m512` / `__mmask16` with `#[inline(always)]` methods and are only
//! used inside [`MergeCtx::parent_row16`] (after [`available`]), so every intrinsic compiles
//! to one instruction there. The test below compares rows with `merge_rows`' four-parent
//! twin on `merge_rows8`'s random levels; the build's tests compare whole trees with the
//! reference build.
//!
//! | parameter | value |
//! |---|---|
//! | parents per step | 16 (the row's first `16 floor(W_parent / 16)`) |
//! | target features | `avx512f,avx512bw,avx512dq,avx512vl,f16c` |

use core::arch::x86_64::*;
use core::ops::{Add, Div, Mul, Neg, Sub};

use super::merge::MergeCtx;
use super::merge_kids::Kids;
use super::merge_wide::{MergeLanes, MergeMask, Merged, lane_ops};
use super::node::{FLAG_CRACK, Node};
use super::prune::Allow;
use super::tree::Level;

/// Whether this CPU runs [`MergeCtx::parent_row16`] (the build's AVX-512 kernels' one check).
pub(super) use super::avx512_available as available;

/// Sixteen f32 lanes. SAFETY (every method): only called from code compiled with AVX-512
/// that runs after [`available`] (module docs).
#[derive(Clone, Copy)]
struct F16(__m512);

/// A lane mask of `F16`.
#[derive(Clone, Copy)]
struct M16(__mmask16);

lane_ops!(F16: _mm512_add_ps, _mm512_sub_ps, _mm512_mul_ps, _mm512_div_ps);

impl Neg for F16 {
    type Output = F16;
    /// Sign flip (`xor` with `-0`), as the eight-lane kernel's.
    #[inline(always)]
    fn neg(self) -> F16 {
        // SAFETY: AVX-512 (module docs).
        F16(unsafe {
            _mm512_castsi512_ps(_mm512_xor_si512(
                _mm512_set1_epi32(i32::MIN),
                _mm512_castps_si512(self.0),
            ))
        })
    }
}

impl F16 {
    /// Lanes `4 i .. 4 i + 4` from `v[i]`.
    #[inline(always)]
    fn join4(v: [__m128; 4]) -> F16 {
        // SAFETY: AVX-512 (module docs).
        F16(unsafe {
            let lo = _mm256_set_m128(v[1], v[0]);
            let hi = _mm256_set_m128(v[3], v[2]);
            _mm512_insertf32x8::<1>(_mm512_castps256_ps512(lo), hi)
        })
    }
}

impl MergeLanes for F16 {
    type M = M16;
    const N: usize = 16;
    #[inline(always)]
    fn splat(v: f32) -> F16 {
        // SAFETY: AVX-512 (module docs).
        F16(unsafe { _mm512_set1_ps(v) })
    }
    #[inline(always)]
    fn ramp(step: f32) -> F16 {
        let v: [f32; 16] = core::array::from_fn(|p| p as f32 * step);
        // SAFETY: AVX-512 (module docs); a 64-byte load of a 64-byte array.
        F16(unsafe { _mm512_loadu_ps(v.as_ptr()) })
    }
    #[inline(always)]
    fn to_array(self) -> [f32; 16] {
        let mut a = [0.0f32; 16];
        // SAFETY: AVX-512 (module docs); a 64-byte store into a 64-byte array.
        unsafe { _mm512_storeu_ps(a.as_mut_ptr(), self.0) };
        a
    }
    #[inline(always)]
    fn sqrt(self) -> F16 {
        // SAFETY: AVX-512 (module docs).
        F16(unsafe { _mm512_sqrt_ps(self.0) })
    }
    #[inline(always)]
    fn min(self, o: F16) -> F16 {
        // SAFETY: AVX-512 (module docs).
        F16(unsafe { _mm512_min_ps(self.0, o.0) })
    }
    #[inline(always)]
    fn max_ps(self, o: F16) -> F16 {
        // SAFETY: AVX-512 (module docs).
        F16(unsafe { _mm512_max_ps(self.0, o.0) })
    }
    #[inline(always)]
    fn abs(self) -> F16 {
        // SAFETY: AVX-512 (module docs).
        F16(unsafe {
            _mm512_castsi512_ps(_mm512_and_si512(
                _mm512_set1_epi32(i32::MAX),
                _mm512_castps_si512(self.0),
            ))
        })
    }
    #[inline(always)]
    fn gt(self, o: F16) -> M16 {
        // SAFETY: AVX-512 (module docs).
        M16(unsafe { _mm512_cmp_ps_mask::<_CMP_GT_OS>(self.0, o.0) })
    }
    #[inline(always)]
    fn lt(self, o: F16) -> M16 {
        // SAFETY: AVX-512 (module docs).
        M16(unsafe { _mm512_cmp_ps_mask::<_CMP_LT_OS>(self.0, o.0) })
    }
    #[inline(always)]
    fn ge(self, o: F16) -> M16 {
        // SAFETY: AVX-512 (module docs).
        M16(unsafe { _mm512_cmp_ps_mask::<_CMP_GE_OS>(self.0, o.0) })
    }
    #[inline(always)]
    fn ordered(self) -> M16 {
        // SAFETY: AVX-512 (module docs).
        M16(unsafe { _mm512_cmp_ps_mask::<_CMP_ORD_Q>(self.0, self.0) })
    }
    #[inline(always)]
    fn finite(self) -> M16 {
        self.abs().lt(F16::splat(f32::INFINITY))
    }
    #[inline(always)]
    fn select(m: M16, a: F16, b: F16) -> F16 {
        // SAFETY: AVX-512 (module docs).
        F16(unsafe { _mm512_mask_blend_ps(m.0, b.0, a.0) })
    }
    /// `increments8`'s decode for sixteen parents: per `Kids` one byte shuffle puts the `x`
    /// halves in the low eight bytes and the `y` halves in the high eight, then `vcvtph2ps`
    /// of the sixteen halves of each.
    #[inline(always)]
    fn increments(kids: &[Kids], k: usize) -> (F16, F16) {
        // SAFETY: AVX-512 and F16C (module docs).
        unsafe {
            let halves = _mm_setr_epi8(0, 1, 4, 5, 8, 9, 12, 13, 2, 3, 6, 7, 10, 11, 14, 15);
            let t: [__m128i; 4] =
                core::array::from_fn(|i| _mm_shuffle_epi8(kids[i].word_b(k), halves));
            let xs = _mm256_set_m128i(
                _mm_unpacklo_epi64(t[2], t[3]),
                _mm_unpacklo_epi64(t[0], t[1]),
            );
            let ys = _mm256_set_m128i(
                _mm_unpackhi_epi64(t[2], t[3]),
                _mm_unpackhi_epi64(t[0], t[1]),
            );
            (F16(_mm512_cvtph_ps(xs)), F16(_mm512_cvtph_ps(ys)))
        }
    }
    #[inline(always)]
    fn zc(kids: &[Kids], k: usize) -> F16 {
        F16::join4(core::array::from_fn(|i| kids[i].zc(k).into()))
    }
}

impl MergeMask for M16 {
    #[inline(always)]
    fn and(self, o: M16) -> M16 {
        M16(self.0 & o.0)
    }
    #[inline(always)]
    fn bits(self) -> u32 {
        self.0 as u32
    }
}

/// The `a` and `b` words of the sixteen proxies of `m` (lanes of `kids`), as `encode8`
/// makes them: the increments' halves as `x | y << 16`, `z_c` rounded to 21 bits, the tag,
/// and flag `O` where a child has it.
#[inline(always)]
fn encode16(m: &Merged<F16>, kids: &[Kids; 4]) -> (__m512i, __m512i) {
    // SAFETY: AVX-512 and F16C (module docs).
    unsafe {
        let (hx, hy) = (
            _mm512_cvtps_ph::<_MM_FROUND_TO_NEAREST_INT>(m.ex.0),
            _mm512_cvtps_ph::<_MM_FROUND_TO_NEAREST_INT>(m.ey.0),
        );
        let bv = _mm512_or_si512(
            _mm512_cvtepu16_epi32(hx),
            _mm512_slli_epi32::<16>(_mm512_cvtepu16_epi32(hy)),
        );
        let bits = _mm512_and_si512(
            _mm512_add_epi32(_mm512_castps_si512(m.zc.0), _mm512_set1_epi32(2)),
            _mm512_set1_epi32(!3),
        );
        let ors = F16::join4(core::array::from_fn(|i| {
            _mm_castsi128_ps(kids[i].or_words_a())
        }));
        let crack = _mm512_and_si512(
            _mm512_castps_si512(ors.0),
            _mm512_set1_epi32(FLAG_CRACK as i32),
        );
        let tag = _mm512_set1_epi32(0x8000_0000u32 as i32);
        (_mm512_or_si512(_mm512_or_si512(bits, tag), crack), bv)
    }
}

/// `vpermt2d` indices interleaving `a` (first operand) and `b` words into nodes: parents
/// 0-7 (`[0]`) and 8-15 (`[1]`).
const NODE_IDX: [[i32; 16]; 2] = [
    [0, 16, 1, 17, 2, 18, 3, 19, 4, 20, 5, 21, 6, 22, 7, 23],
    [8, 24, 9, 25, 10, 26, 11, 27, 12, 28, 13, 29, 14, 30, 15, 31],
];

impl MergeCtx {
    /// [`Self::parent_row_fast_of`] with the child rows read from level `l - 1` (`child`).
    pub(super) fn parent_row_fast(
        &self,
        child: &Level,
        l: u32,
        qy: u32,
        out: &mut [Node],
        allow: Allow,
    ) {
        let (cw, y0) = (child.w as usize, 2 * qy as usize);
        self.parent_row_fast_of(&child.nodes[y0 * cw..(y0 + 2) * cw], l, qy, out, allow);
    }

    /// [`MergeCtx::parent_row_of`] (same nodes), sixteen parents per step in AVX-512 lanes
    /// (`merge_rows16`) and then eight in AVX2 lanes, where the CPU has them (AVX2 and
    /// F16C); `two`: child rows `2 qy` and `2 qy + 1` of level `l - 1`, one after the other.
    pub(super) fn parent_row_fast_of(
        &self,
        two: &[Node],
        l: u32,
        qy: u32,
        out: &mut [Node],
        allow: Allow,
    ) {
        if std::arch::is_x86_feature_detected!("avx2")
            && std::arch::is_x86_feature_detected!("f16c")
        {
            let first = if available() {
                // SAFETY: the CPU has AVX-512 (checked).
                unsafe { self.parent_row16(two, l, qy, out, allow) }
            } else {
                0
            };
            // SAFETY: the CPU has AVX2 and F16C (checked).
            unsafe { self.parent_row8(two, l, qy, out, allow, first) }
        } else {
            self.parent_row_of(two.split_at(two.len() / 2), l, qy, out, allow)
        }
    }

    /// `parent_row8` sixteen parents per step: the first `16 floor(P / 16)` parents of the
    /// row (`P = out.len()`; `two` the child rows `2 qy`, `2 qy + 1` of level `l - 1`, one
    /// after the other); returns how many it did.
    ///
    /// # Safety
    /// The CPU must have what [`available`] checks.
    #[target_feature(enable = "avx512f,avx512bw,avx512dq,avx512vl,f16c")]
    pub(super) unsafe fn parent_row16(
        &self,
        two: &[Node],
        l: u32,
        qy: u32,
        out: &mut [Node],
        allow: Allow,
    ) -> usize {
        let cw = two.len() / 2;
        let (r0, r1) = (&two[..cw], &two[cw..2 * cw]);
        let n16 = out.len() & !15;
        // SAFETY: 16 `i32`s each.
        let (i_lo, i_hi) = unsafe {
            (
                _mm512_loadu_si512(NODE_IDX[0].as_ptr() as *const _),
                _mm512_loadu_si512(NODE_IDX[1].as_ptr() as *const _),
            )
        };
        for (g, outs) in out[..n16].chunks_exact_mut(16).enumerate() {
            let qx0 = 16 * g;
            let kids: [Kids; 4] = core::array::from_fn(|i| Kids::gather(r0, r1, qx0 + 4 * i, 4));
            let mut planes = 0xffff;
            for k in 0..4 {
                planes &= (0..4).fold(0, |m, i| m | (kids[i].planes(k) << (4 * i)));
            }
            let planes = planes & (allow.mask8(qx0) | (allow.mask8(qx0 + 8) << 8));
            let cand = if self.never { 0 } else { planes };
            let (mask, av, bv) = if cand != 0 {
                let m = self.merge_wide::<F16>(l, qx0 as u32, qy, &kids, cand);
                let (av, bv) = encode16(&m, &kids);
                (m.mask, av, bv)
            } else {
                let z = _mm512_setzero_si512();
                (0, z, z)
            };
            if mask == 0xffff {
                // All sixteen merged: the nodes `(a, b)` interleaved and stored.
                // SAFETY: `outs` holds sixteen nodes, 128 bytes (`Node` is two `u32`s,
                // `repr(C)`).
                unsafe {
                    let op = outs.as_mut_ptr() as *mut __m512i;
                    _mm512_storeu_si512(op, _mm512_permutex2var_epi32(av, i_lo, bv));
                    _mm512_storeu_si512(op.add(1), _mm512_permutex2var_epi32(av, i_hi, bv));
                }
                continue;
            }
            let (mut a, mut b) = ([0u32; 16], [0u32; 16]);
            // SAFETY: 64-byte stores into 64-byte arrays.
            unsafe {
                _mm512_storeu_si512(a.as_mut_ptr() as *mut __m512i, av);
                _mm512_storeu_si512(b.as_mut_ptr() as *mut __m512i, bv);
            }
            let [k0, k1, k2, k3] = kids;
            for (h, (half, pair)) in outs
                .chunks_exact_mut(8)
                .zip([[k0, k1], [k2, k3]])
                .enumerate()
            {
                let words = |w: &[u32; 16]| -> [u32; 8] { core::array::from_fn(|p| w[8 * h + p]) };
                let (ah, bh) = (words(&a), words(&b));
                self.finish8(
                    l,
                    qx0 + 8 * h,
                    qy,
                    &pair,
                    half,
                    allow,
                    mask >> (8 * h),
                    (&ah, &bh),
                );
            }
        }
        n16
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::quadtree::merge_rows8::tests::random_rows;

    /// Rows made sixteen parents per step (then eight) equal `merge_rows`' four-parent rows
    /// node for node, on `merge_rows8`'s random levels (near-coplanar patches that mostly
    /// merge, empty, AABB and special AABB children, clamped and flagged planes, blocked
    /// parents, fixed and adaptive thresholds), with rows of up to 40 parents.
    #[test]
    fn rows_equal_the_four_parent_rows() {
        if !available() {
            eprintln!("no AVX-512: nothing to compare");
            return;
        }
        let (mut sixteen, mut merged) = (0usize, 0usize);
        random_rows(|ctx, child, l, qy, allow| {
            let mut four = vec![Node { a: 1, b: 1 }; child.w as usize / 2];
            let mut fast = vec![Node { a: 2, b: 2 }; four.len()];
            ctx.parent_row(child, l, qy, &mut four, allow);
            ctx.parent_row_fast(child, l, qy, &mut fast, allow);
            assert_eq!(four, fast, "level {l}, row {qy}");
            sixteen += four.len() & !15;
            merged += four.iter().filter(|n| n.is_plane()).count();
        });
        assert!(
            sixteen > 500 && merged > 500,
            "{sixteen} parents in 16 lanes, {merged} merged"
        );
    }
}
