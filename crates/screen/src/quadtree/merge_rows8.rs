//! One row of a pruning level (Widmer et al. 2015, §3.3) with eight parents per step in
//! AVX2 lanes: `merge_rows`' four-parent kernel (its module docs list the operations and
//! their order) with the merge of the candidate parents — the child normals, their
//! normalised sum, the cosines, the 16 corner projections and their largest deviation, the
//! proxy — evaluated for eight parents in the lanes of `__m256`s (AVX2 and F16C, run-time
//! detection). The children are gathered four parents at a time as in `merge_rows`
//! (`Kids`), their f16 slopes decoded eight at a time by F16C (`vcvtph2ps`, equal to the
//! definition for every finite half; plane nodes hold only finite halves) and the proxy's
//! slopes encoded by `vcvtps2ph` (`leaf_avx2::f16x8`, the definition's rounding); the fixed
//! thresholds (`cos_norm`, `gamma_dist`) and flag `O` are applied in lanes, the adaptive
//! ones per lane. When all eight parents merge, their nodes are stored straight from the
//! lanes; otherwise the parents that do not merge get their AABB nodes (the children's
//! z-range union) in the same lanes (`ranges8`), or, in a group with an AABB child whose
//! word is NaN or `-0`, the parents take `merge_rows`' own per-group code
//! (`MergeCtx::group4`) with the merges passed in. Every lane does the four-lane kernel's operations in its order —
//! IEEE square root, division, products and sums are correctly rounded per lane, `minps` /
//! `maxps` pick the same operand in 8 lanes as in 4, nothing is fused (no FMA is enabled) —
//! so the nodes are the same bits; the pixel columns `2 (qx0 + p) + kx` and the parent
//! columns `qx0 + p` are exact small integers in f32 whichever group they start from.
//!
//! The merge itself ([`MergeCtx::merge_wide`]) is generic over the lanes ([`MergeLanes`]):
//! `F8` here, `merge_rows16`'s sixteen AVX-512 lanes there, the same operations per lane.
//! `F8` / `M8` wrap `__m256` with `#[inline(always)]` methods and are only used inside
//! [`MergeCtx::parent_row_fast`]'s AVX2 entry point (after `is_x86_feature_detected!`), so
//! every intrinsic compiles to one instruction there. The test below compares rows of random
//! levels with `merge_rows`' [`MergeCtx::parent_row_of`] (the SSE2 twin); the build's tests
//! compare whole trees with the reference build.

use core::arch::x86_64::*;
use core::ops::{Add, Div, Mul, Neg, Sub};

use glam::Vec4;

use super::leaf_avx2::f16x8;
use super::merge::MergeCtx;
use super::merge_kids::Kids;
use super::merge_wide::{MergeLanes, MergeMask, Merged, lane_ops};
use super::node::{FLAG_CRACK, Node};
use super::prune::Allow;
use super::tree::Z_EPS;

/// Per-thread counts of the groups of eight whose parents that do not merge took
/// `ranges8` and of those that took `group4`, for the test to check that both run.
#[cfg(test)]
mod tally {
    use std::cell::Cell;
    thread_local! {
        pub(super) static RANGES8: Cell<usize> = const { Cell::new(0) };
        pub(super) static GROUP4: Cell<usize> = const { Cell::new(0) };
    }
}

/// Eight f32 lanes. SAFETY (every method): only called from code compiled with AVX2 that
/// runs after AVX2 was detected (module docs).
#[derive(Clone, Copy)]
struct F8(__m256);

/// A lane mask of `F8` (all ones or all zeros per lane).
#[derive(Clone, Copy)]
struct M8(__m256);

lane_ops!(F8: _mm256_add_ps, _mm256_sub_ps, _mm256_mul_ps, _mm256_div_ps);

impl Neg for F8 {
    type Output = F8;
    /// Sign flip, as glam's `Vec4` negation (`xorps` with `-0`).
    #[inline(always)]
    fn neg(self) -> F8 {
        // SAFETY: AVX (module docs).
        F8(unsafe { _mm256_xor_ps(_mm256_set1_ps(-0.0), self.0) })
    }
}

impl F8 {
    /// Lanes 0-3 from `lo`, 4-7 from `hi`.
    #[inline(always)]
    fn join(lo: Vec4, hi: Vec4) -> F8 {
        // SAFETY: AVX (module docs).
        F8(unsafe { _mm256_set_m128(hi.into(), lo.into()) })
    }
    #[inline(always)]
    fn lanes(v: [f32; 8]) -> F8 {
        // SAFETY: AVX (module docs).
        F8(unsafe { _mm256_loadu_ps(v.as_ptr()) })
    }
}

impl MergeLanes for F8 {
    type M = M8;
    const N: usize = 8;
    #[inline(always)]
    fn splat(v: f32) -> F8 {
        // SAFETY: AVX (module docs).
        F8(unsafe { _mm256_set1_ps(v) })
    }
    #[inline(always)]
    fn ramp(step: f32) -> F8 {
        F8::lanes(core::array::from_fn(|p| p as f32 * step))
    }
    #[inline(always)]
    fn to_array(self) -> [f32; 16] {
        let mut a = [0.0f32; 16];
        // SAFETY: AVX (module docs); a 32-byte store into the first half of a 64-byte array.
        unsafe { _mm256_storeu_ps(a.as_mut_ptr(), self.0) };
        a
    }
    #[inline(always)]
    fn sqrt(self) -> F8 {
        // SAFETY: AVX (module docs).
        F8(unsafe { _mm256_sqrt_ps(self.0) })
    }
    #[inline(always)]
    fn min(self, o: F8) -> F8 {
        // SAFETY: AVX (module docs).
        F8(unsafe { _mm256_min_ps(self.0, o.0) })
    }
    #[inline(always)]
    fn max_ps(self, o: F8) -> F8 {
        // SAFETY: AVX (module docs).
        F8(unsafe { _mm256_max_ps(self.0, o.0) })
    }
    #[inline(always)]
    fn abs(self) -> F8 {
        // SAFETY: AVX (module docs).
        F8(unsafe { _mm256_andnot_ps(_mm256_set1_ps(-0.0), self.0) })
    }
    #[inline(always)]
    fn gt(self, o: F8) -> M8 {
        // SAFETY: AVX (module docs).
        M8(unsafe { _mm256_cmp_ps::<_CMP_GT_OS>(self.0, o.0) })
    }
    #[inline(always)]
    fn lt(self, o: F8) -> M8 {
        // SAFETY: AVX (module docs).
        M8(unsafe { _mm256_cmp_ps::<_CMP_LT_OS>(self.0, o.0) })
    }
    #[inline(always)]
    fn ge(self, o: F8) -> M8 {
        // SAFETY: AVX (module docs).
        M8(unsafe { _mm256_cmp_ps::<_CMP_GE_OS>(self.0, o.0) })
    }
    #[inline(always)]
    fn ordered(self) -> M8 {
        // SAFETY: AVX (module docs).
        M8(unsafe { _mm256_cmp_ps::<_CMP_ORD_Q>(self.0, self.0) })
    }
    #[inline(always)]
    fn finite(self) -> M8 {
        self.abs().lt(F8::splat(f32::INFINITY))
    }
    /// glam's `Vec4::select`: `(a & m) | (b & !m)`.
    #[inline(always)]
    fn select(m: M8, a: F8, b: F8) -> F8 {
        // SAFETY: AVX (module docs).
        F8(unsafe { _mm256_or_ps(_mm256_andnot_ps(m.0, b.0), _mm256_and_ps(a.0, m.0)) })
    }
    #[inline(always)]
    fn increments(kids: &[Kids], k: usize) -> (F8, F8) {
        increments8(&kids[0], &kids[1], k)
    }
    #[inline(always)]
    fn zc(kids: &[Kids], k: usize) -> F8 {
        F8::join(kids[0].zc(k), kids[1].zc(k))
    }
}

impl MergeMask for M8 {
    #[inline(always)]
    fn and(self, o: M8) -> M8 {
        // SAFETY: AVX (module docs).
        M8(unsafe { _mm256_and_ps(self.0, o.0) })
    }
    #[inline(always)]
    fn bits(self) -> u32 {
        // SAFETY: AVX (module docs).
        unsafe { _mm256_movemask_ps(self.0) as u32 }
    }
}

/// Child `k`'s stored increments ([`Kids::increments`]) of the eight parents of `lo`
/// (lanes 0-3) and `hi` (lanes 4-7), by F16C: `vcvtph2ps` equals `f16x4` (and
/// `node::f16_bits_to_f32`) for every finite half (test in `trigger_avx2`), and plane
/// nodes hold only finite halves (slopes clamped to `±65504` before encoding); the lanes of
/// other children are not read. Per node, `b`'s low half is `x`, its high half `y`: one
/// byte shuffle per four nodes puts the `x` halves in the low eight bytes and the `y`
/// halves in the high eight.
#[inline(always)]
fn increments8(lo: &Kids, hi: &Kids, k: usize) -> (F8, F8) {
    // SAFETY: AVX2 and F16C (module docs).
    unsafe {
        let halves = _mm_setr_epi8(0, 1, 4, 5, 8, 9, 12, 13, 2, 3, 6, 7, 10, 11, 14, 15);
        let t_lo = _mm_shuffle_epi8(lo.word_b(k), halves);
        let t_hi = _mm_shuffle_epi8(hi.word_b(k), halves);
        (
            F8(_mm256_cvtph_ps(_mm_unpacklo_epi64(t_lo, t_hi))),
            F8(_mm256_cvtph_ps(_mm_unpackhi_epi64(t_lo, t_hi))),
        )
    }
}

impl MergeCtx {
    /// The parents `first..` of the row (`first` a multiple of 8), eight per step.
    #[target_feature(enable = "avx2,f16c")]
    pub(super) fn parent_row8(
        &self,
        two: &[Node],
        l: u32,
        qy: u32,
        out: &mut [Node],
        allow: Allow,
        first: usize,
    ) {
        debug_assert_eq!(first % 8, 0);
        let cw = two.len() / 2;
        let r0 = &two[..cw];
        let r1 = &two[cw..2 * cw];
        for (g, outs) in out[first..].chunks_mut(8).enumerate() {
            let qx0 = first + 8 * g;
            let n = outs.len();
            let kids = [
                Kids::gather(r0, r1, qx0, n.min(4)),
                Kids::gather(r0, r1, qx0 + 4, n.saturating_sub(4)),
            ];
            let mut planes = 0xff;
            for k in 0..4 {
                planes &= kids[0].planes(k) | (kids[1].planes(k) << 4);
            }
            let planes = planes & allow.mask8(qx0) & ((1u32 << n) - 1);
            let cand = if self.never { 0 } else { planes };
            let (mask, av, bv) = if cand != 0 {
                let m = self.merge_wide::<F8>(l, qx0 as u32, qy, &kids, cand);
                let (av, bv) = encode8(&m, &kids[0], &kids[1]);
                (m.mask, av, bv)
            } else {
                let z = _mm256_setzero_si256();
                (0, z, z)
            };
            if mask == 0xff {
                // All eight merged (so `n == 8`): the nodes `(a, b)` interleaved and stored.
                let (ul, uh) = (_mm256_unpacklo_epi32(av, bv), _mm256_unpackhi_epi32(av, bv));
                // SAFETY: `outs` holds eight nodes, 64 bytes (`Node` is two `u32`s,
                // `repr(C)`).
                unsafe {
                    let op = outs.as_mut_ptr() as *mut __m256i;
                    _mm256_storeu_si256(op, _mm256_permute2x128_si256::<0x20>(ul, uh));
                    _mm256_storeu_si256(op.add(1), _mm256_permute2x128_si256::<0x31>(ul, uh));
                }
                continue;
            }
            let (mut a, mut b) = ([0u32; 8], [0u32; 8]);
            // SAFETY: 32-byte stores into 32-byte arrays.
            unsafe {
                _mm256_storeu_si256(a.as_mut_ptr() as *mut __m256i, av);
                _mm256_storeu_si256(b.as_mut_ptr() as *mut __m256i, bv);
            }
            self.finish8(l, qx0, qy, &kids, outs, allow, mask, (&a, &b));
        }
    }

    /// The nodes of eight parents (`outs`, from column `qx0`; children `kids`) of which
    /// those in `mask` merged into the nodes `(a[p], b[p])`: the others get their AABB
    /// nodes (`ranges8`), or in a group with an AABB child whose word is NaN or `-0`,
    /// `merge_rows`' own per-group code (`MergeCtx::group4`) with the merges passed in.
    #[allow(clippy::too_many_arguments)]
    #[inline(always)]
    pub(super) fn finish8(
        &self,
        l: u32,
        qx0: usize,
        qy: u32,
        kids: &[Kids; 2],
        outs: &mut [Node],
        allow: Allow,
        mask: u32,
        (a, b): (&[u32; 8], &[u32; 8]),
    ) {
        let merged: [Option<Node>; 8] =
            core::array::from_fn(|p| (mask & (1 << p) != 0).then_some(Node { a: a[p], b: b[p] }));
        let (lo, hi) = (&kids[0], &kids[1]);
        let (o_lo, o_hi) = outs.split_at_mut(outs.len().min(4));
        if let Some((a, b)) = self.ranges8(l, lo, hi) {
            #[cfg(test)]
            tally::RANGES8.with(|c| c.set(c.get() + 1));
            for (p, o) in o_lo.iter_mut().chain(o_hi.iter_mut()).enumerate() {
                *o = merged[p].unwrap_or(Node { a: a[p], b: b[p] });
            }
            return;
        }
        #[cfg(test)]
        tally::GROUP4.with(|c| c.set(c.get() + 1));
        let (m_lo, m_hi) = (
            [merged[0], merged[1], merged[2], merged[3]],
            [merged[4], merged[5], merged[6], merged[7]],
        );
        self.group4(l, qx0 as u32, qy, lo, o_lo, allow, Some(m_lo));
        if !o_hi.is_empty() {
            self.group4(l, qx0 as u32 + 4, qy, hi, o_hi, allow, Some(m_hi));
        }
    }

    /// The AABB nodes of the eight parents of `lo` (lanes 0-3) and `hi` (lanes 4-7) that do
    /// not merge, as `merge_rows`' `group4` makes them when no child of the group is an
    /// AABB with a NaN or `-0` word (else `None`, and the caller takes `group4`): per child
    /// the spread `(|gx| half) / W + (|gy| half) / H` (`half` dilated by `crack_px` where the
    /// child has flag `O`), a plane child's `plane_range` (`[0, 1]` for a spread that is
    /// not finite) or an AABB child's stored range, their union by `minps` / `maxps` from
    /// `(+inf, -inf)` in child order, and `union_lanes`' encoding — the four-lane code's
    /// operations in its order, so the same bits. A group with no plane child gets the
    /// union of the stored ranges, as `group4`'s `aabb_union` (all empty: `Node::EMPTY`).
    /// Returns the nodes' `a` and `b` words (lanes that merged: garbage).
    #[inline(always)]
    fn ranges8(&self, l: u32, lo: &Kids, hi: &Kids) -> Option<([u32; 8], [u32; 8])> {
        let special = (0..4).fold(0, |m, k| m | lo.special(k) | hi.special(k));
        if special != 0 {
            return None;
        }
        let s = F8::splat;
        let cl = l - 1;
        let (ws, hs) = (
            f32::from_bits(self.wf.to_bits() - (cl << 23)),
            f32::from_bits(self.hf.to_bits() - (cl << 23)),
        );
        let size = (1u32 << cl) as f32;
        let (dil, none) = (s(0.5 * size + self.crack_px), s(0.5 * size + 0.0));
        let (zero, one, eps) = (s(0.0), s(1.0), s(Z_EPS));
        let clamp = |v: F8| v.max_ps(zero).min(one);
        let (mut zlo, mut zhi) = (s(f32::INFINITY), s(f32::NEG_INFINITY));
        let (la, ha) = (lo.words_a(), hi.words_a());
        for k in 0..4 {
            let (ex, ey) = increments8(lo, hi, k);
            let (gx, gy) = (ex * s(ws), ey * s(hs));
            // SAFETY: AVX2 (module docs).
            let (a, b, crack, zc, plane) = unsafe {
                let a = _mm256_set_m128i(ha[k], la[k]);
                let b = _mm256_set_m128i(hi.word_b(k), lo.word_b(k));
                let flag = _mm256_set1_epi32(FLAG_CRACK as i32);
                let crack = _mm256_cmpeq_epi32(_mm256_and_si256(a, flag), flag);
                let zc = _mm256_and_si256(a, _mm256_set1_epi32(0x7fff_fffc));
                (
                    F8(_mm256_castsi256_ps(a)),
                    F8(_mm256_castsi256_ps(b)),
                    M8(_mm256_castsi256_ps(crack)),
                    F8(_mm256_castsi256_ps(zc)),
                    M8(_mm256_castsi256_ps(_mm256_srai_epi32::<31>(a))),
                )
            };
            let half = F8::select(crack, dil, none);
            let sp = (gx.abs() * half) / s(self.wf) + (gy.abs() * half) / s(self.hf);
            let finite = sp.finite();
            let rlo = F8::select(finite, clamp((zc - sp) - eps), zero);
            let rhi = F8::select(finite, clamp((zc + sp) + eps), one);
            zlo = F8::select(plane, rlo, a).min(zlo);
            zhi = F8::select(plane, rhi, b).max_ps(zhi);
        }
        let e = Node::EMPTY;
        let (mut aw, mut bw) = ([0u32; 8], [0u32; 8]);
        // SAFETY: AVX2 (module docs); 32-byte stores into 32-byte arrays.
        unsafe {
            let empty = _mm256_castps_si256(_mm256_cmp_ps::<_CMP_GT_OS>(zlo.0, zhi.0));
            let zmin = _mm256_castps_si256(_mm256_and_ps(
                _mm256_cmp_ps::<_CMP_GT_OS>(zlo.0, _mm256_setzero_ps()),
                zlo.0,
            ));
            let a = _mm256_or_si256(
                _mm256_and_si256(empty, _mm256_set1_epi32(e.a as i32)),
                _mm256_andnot_si256(empty, zmin),
            );
            let b = _mm256_or_si256(
                _mm256_and_si256(empty, _mm256_set1_epi32(e.b as i32)),
                _mm256_andnot_si256(empty, _mm256_castps_si256(zhi.0)),
            );
            _mm256_storeu_si256(aw.as_mut_ptr() as *mut __m256i, a);
            _mm256_storeu_si256(bw.as_mut_ptr() as *mut __m256i, b);
        }
        Some((aw, bw))
    }
}

/// The `a` and `b` words of the eight proxies of `m` (lanes of `lo`, `hi`): the increments'
/// halves interleaved into `x | y << 16`, `z_c` rounded to 21 bits, the tag, and flag `O`
/// where a child has it.
#[inline(always)]
fn encode8(m: &Merged<F8>, lo: &Kids, hi: &Kids) -> (__m256i, __m256i) {
    // SAFETY: AVX2 and F16C (module docs).
    unsafe {
        let (hx, hy) = (f16x8(m.ex.0), f16x8(m.ey.0));
        let bv = _mm256_set_m128i(_mm_unpackhi_epi16(hx, hy), _mm_unpacklo_epi16(hx, hy));
        let bits = _mm256_and_si256(
            _mm256_add_epi32(_mm256_castps_si256(m.zc.0), _mm256_set1_epi32(2)),
            _mm256_set1_epi32(!3),
        );
        let crack = _mm256_and_si256(
            _mm256_set_m128i(hi.or_words_a(), lo.or_words_a()),
            _mm256_set1_epi32(FLAG_CRACK as i32),
        );
        let tag = _mm256_set1_epi32(0x8000_0000u32 as i32);
        (_mm256_or_si256(_mm256_or_si256(bits, tag), crack), bv)
    }
}

#[cfg(test)]
pub(super) mod tests {
    use super::*;
    use crate::quadtree::test_rng::Rng;
    use crate::quadtree::tree::Level;

    /// Calls `f(ctx, child, l, qy, allow)` for every parent row of 48 random child levels
    /// 0-3 of near-coplanar plane patches (so most parents merge, some fail the cosine or
    /// distance test; some nearly flat, with f16-subnormal increments), with empty and AABB
    /// children, AABB words that are NaN or `-0`, planes with clamped slopes, flagged
    /// planes, blocked parents, rows of 1 to 40 parents, fixed and adaptive thresholds.
    pub(in crate::quadtree) fn random_rows(mut f: impl FnMut(&MergeCtx, &Level, u32, u32, Allow)) {
        let mut rng = Rng(0x1234_5678_9abc_def1);
        for case in 0..48u32 {
            let ctx = MergeCtx::test_case(case);
            let (wf, hf) = (ctx.wf, ctx.hf);
            let cl = case % 4;
            let l = cl + 1;
            let pw = 1 + (rng.next() % 40) as u32;
            let ph = 3u32;
            let (cw, ch) = (2 * pw, 2 * ph);
            // One plane per case, `z = z0 + ax x + ay y`, with noise per child.
            // Every fifth case nearly flat: the increments are f16-subnormal halves.
            let amp = if case % 5 == 4 { 1e-2 } else { 2.0 };
            let (z0, ax, ay) = (rng.f(0.2, 0.8), rng.f(-amp, amp), rng.f(-amp, amp));
            let noise = [0.0, 1e-6, 1e-4, 1e-2][(case / 4) as usize % 4];
            let nodes: Vec<Node> = (0..cw * ch)
                .map(|k| {
                    let (x, y) = (k % cw, k / cw);
                    match rng.next() % 16 {
                        0 => Node::EMPTY,
                        1 => Node::aabb(rng.f(0.0, 0.5), rng.f(0.5, 1.0)),
                        // AABB words that are NaN or `-0` (`group4`'s scalar path), rarely.
                        3 if rng.next().is_multiple_of(4) => match rng.next() % 2 {
                            0 => Node {
                                a: 0x7fc0_0000,
                                b: 0x3f00_0000,
                            },
                            _ => Node {
                                a: 0,
                                b: 0x8000_0000,
                            },
                        },
                        // Slopes clamped to the f16 maximum.
                        2 => Node::plane_with_gradient(
                            rng.f(0.2, 0.8),
                            rng.f(-1e9, 1e9),
                            rng.f(-1e9, 1e9),
                            cl,
                            wf,
                            hf,
                            0,
                        )
                        .unwrap_or(Node::EMPTY),
                        _ => {
                            let size = (1u32 << cl) as f32;
                            let (xc, yc) =
                                ((x as f32 + 0.5) * size / wf, (y as f32 + 0.5) * size / hf);
                            let zc = z0 + ax * xc + ay * yc + rng.f(-noise, noise);
                            let gx = ax + rng.f(-noise, noise) * 100.0;
                            let gy = ay + rng.f(-noise, noise) * 100.0;
                            let flags = if rng.next().is_multiple_of(8) {
                                FLAG_CRACK
                            } else {
                                0
                            };
                            Node::plane_with_gradient(zc, gx, gy, cl, wf, hf, flags)
                                .unwrap_or(Node::EMPTY)
                        }
                    }
                })
                .collect();
            let child = Level {
                w: cw,
                h: ch,
                nodes,
            };
            let blocked: Vec<bool> = (0..pw * ph)
                .map(|_| rng.next().is_multiple_of(10))
                .collect();
            for qy in 0..ph {
                let allow = Allow(Some(&blocked[(qy * pw) as usize..((qy + 1) * pw) as usize]));
                f(&ctx, &child, l, qy, allow);
            }
        }
    }

    /// Rows made eight parents per step equal `merge_rows`' four-parent rows (the SSE2
    /// twin) node for node, on [`random_rows`].
    #[test]
    fn rows_equal_the_four_parent_rows() {
        if !(std::arch::is_x86_feature_detected!("avx2")
            && std::arch::is_x86_feature_detected!("f16c"))
        {
            eprintln!("no AVX2 and F16C: nothing to compare");
            return;
        }
        let (mut merged, mut total) = (0usize, 0usize);
        let tally0 = (
            tally::RANGES8.with(|c| c.get()),
            tally::GROUP4.with(|c| c.get()),
        );
        random_rows(|ctx, child, l, qy, allow| {
            let pw = child.w as usize / 2;
            let mut four = vec![Node { a: 1, b: 1 }; pw];
            let mut eight = vec![Node { a: 2, b: 2 }; pw];
            ctx.parent_row(child, l, qy, &mut four, allow);
            let (cw, y0) = (child.w as usize, 2 * qy as usize);
            let two = &child.nodes[y0 * cw..(y0 + 2) * cw];
            // SAFETY: AVX2 and F16C (checked above).
            unsafe { ctx.parent_row8(two, l, qy, &mut eight, allow, 0) };
            assert_eq!(four, eight, "level {l}, row {qy}");
            merged += four.iter().filter(|n| n.is_plane()).count();
            total += four.len();
        });
        assert!(
            merged > total / 4 && merged < total,
            "{merged} of {total} parents merged"
        );
        // Groups with parents that do not merge took both paths.
        let ranges8 = tally::RANGES8.with(|c| c.get()) - tally0.0;
        let group4 = tally::GROUP4.with(|c| c.get()) - tally0.1;
        assert!(
            ranges8 > 20 && group4 > 20,
            "{ranges8} groups by ranges8, {group4} by group4"
        );
    }
}
