//! The children of four neighbouring parents in SSE2 lanes, as the merge kernels read them
//! (`merge_rows`, `merge_wide`, `merge_rows8`, `merge_rows16`): two loads of two nodes per
//! parent from the two child rows below them and a 4x4 transpose give, for each child
//! position (0,0), (1,0), (0,1), (1,1), that child's `a` and `b` words of the four parents in
//! lanes ([`Kids`]); their tags, `z_c`, flags and f16 slopes decoded in those lanes by the
//! integer operations of [`super::node`]'s scalar decode; and the lane union of four AABB
//! ranges ([`union_lanes`], the definition's [`super::merge::union`] bit for bit; tested in
//! `merge_rows`).

use core::arch::x86_64::*;

use glam::Vec4;

use super::node::{FLAG_CRACK, Node};
use super::trigger_lanes::f16x4;

/// The four parents' children as words: `a[k]`, `b[k]` hold child `k`'s `a` and `b` of the
/// four parents, lane `p` = parent `p` (module docs).
pub(super) struct Kids {
    a: [__m128i; 4],
    b: [__m128i; 4],
}

impl Kids {
    /// The children of parents `qx0 .. qx0 + n` (`n <= 4`) from the child rows `r0`, `r1`;
    /// lanes beyond `n` hold empty nodes.
    #[inline(always)]
    pub(super) fn gather(r0: &[Node], r1: &[Node], qx0: usize, n: usize) -> Self {
        let pair = |r: &[Node], p: usize| -> __m128i {
            // SAFETY: SSE2 baseline; the load reads the two nodes `r[x..x + 2]` (checked).
            unsafe {
                if p < n {
                    let x = 2 * (qx0 + p);
                    let two = &r[x..x + 2];
                    _mm_loadu_si128(two.as_ptr() as *const __m128i)
                } else {
                    let e = Node::EMPTY;
                    _mm_setr_epi32(e.a as i32, e.b as i32, e.a as i32, e.b as i32)
                }
            }
        };
        // Rows (a, b, a, b) of nodes 2p, 2p + 1, transposed: columns a0, b0, a1, b1.
        let t = |r: &[Node]| -> [__m128i; 4] {
            let (v0, v1, v2, v3) = (pair(r, 0), pair(r, 1), pair(r, 2), pair(r, 3));
            // SAFETY: SSE2 baseline.
            unsafe {
                let (t0, t1) = (_mm_unpacklo_epi32(v0, v1), _mm_unpacklo_epi32(v2, v3));
                let (t2, t3) = (_mm_unpackhi_epi32(v0, v1), _mm_unpackhi_epi32(v2, v3));
                [
                    _mm_unpacklo_epi64(t0, t1),
                    _mm_unpackhi_epi64(t0, t1),
                    _mm_unpacklo_epi64(t2, t3),
                    _mm_unpackhi_epi64(t2, t3),
                ]
            }
        };
        let [a0, b0, a1, b1] = t(r0);
        let [a2, b2, a3, b3] = t(r1);
        Self {
            a: [a0, a1, a2, a3],
            b: [b0, b1, b2, b3],
        }
    }

    /// Per child, the lanes whose child is a plane node (sign bit of `a`), as a bit mask.
    #[inline(always)]
    pub(super) fn planes(&self, k: usize) -> u32 {
        // SAFETY: SSE baseline.
        unsafe { _mm_movemask_ps(_mm_castsi128_ps(self.a[k])) as u32 }
    }

    /// The children's `a` words (`[k]`: child `k` of the four parents in lanes).
    #[inline(always)]
    pub(super) fn words_a(&self) -> [__m128i; 4] {
        self.a
    }

    /// The four children's `a` words ORed, per lane (a flag any child has).
    #[inline(always)]
    pub(super) fn or_words_a(&self) -> __m128i {
        let w = self.a;
        // SAFETY: SSE2 baseline.
        unsafe { _mm_or_si128(_mm_or_si128(w[0], w[1]), _mm_or_si128(w[2], w[3])) }
    }

    /// Child `k`'s `b` words of the four parents in lanes.
    #[inline(always)]
    pub(super) fn word_b(&self, k: usize) -> __m128i {
        self.b[k]
    }

    /// Whether every child of every lane is [`Node::EMPTY`].
    #[inline(always)]
    pub(super) fn all_empty(&self) -> bool {
        let e = Node::EMPTY;
        // SAFETY: SSE2 baseline.
        unsafe {
            let (ea, eb) = (_mm_set1_epi32(e.a as i32), _mm_set1_epi32(e.b as i32));
            let mut m = _mm_set1_epi32(-1);
            for k in 0..4 {
                m = _mm_and_si128(m, _mm_cmpeq_epi32(self.a[k], ea));
                m = _mm_and_si128(m, _mm_cmpeq_epi32(self.b[k], eb));
            }
            _mm_movemask_epi8(m) == 0xffff
        }
    }

    /// [`union`] of the four children's stored ranges per lane (every child an AABB node),
    /// into `out` (at most four parents) — unless a word is NaN or `-0` (then `false`,
    /// nothing written, the caller takes the definition; see [`union_lanes`]).
    #[inline(always)]
    pub(super) fn aabb_union(&self, out: &mut [Node]) -> bool {
        let mut special = 0;
        let mut range = |k: usize| {
            special |= self.special(k);
            // SAFETY: SSE2 baseline.
            unsafe { (_mm_castsi128_ps(self.a[k]), _mm_castsi128_ps(self.b[k])) }
        };
        let ranges = [range(0), range(1), range(2), range(3)];
        if special != 0 {
            return false;
        }
        let (a, b) = union_lanes(ranges);
        for (p, o) in out.iter_mut().enumerate() {
            *o = Node { a: a[p], b: b[p] };
        }
        true
    }

    /// The lanes whose child `k` is an AABB node with a NaN or `-0` word, as a bit mask.
    #[inline(always)]
    pub(super) fn special(&self, k: usize) -> u32 {
        // SAFETY: SSE2 baseline.
        unsafe {
            let neg0 = _mm_set1_epi32(i32::MIN);
            let (a, b) = (_mm_castsi128_ps(self.a[k]), _mm_castsi128_ps(self.b[k]));
            let m = _mm_or_si128(
                _mm_castps_si128(_mm_or_ps(_mm_cmpunord_ps(a, a), _mm_cmpunord_ps(b, b))),
                _mm_or_si128(
                    _mm_cmpeq_epi32(self.a[k], neg0),
                    _mm_cmpeq_epi32(self.b[k], neg0),
                ),
            );
            (_mm_movemask_ps(_mm_castsi128_ps(m)) as u32) & !self.planes(k)
        }
    }

    /// Child `k` of every lane as nodes.
    #[inline(always)]
    pub(super) fn nodes(&self, k: usize) -> [Node; 4] {
        let (mut a, mut b) = ([0u32; 4], [0u32; 4]);
        // SAFETY: SSE2 baseline; 16-byte unaligned stores into 16-byte arrays.
        unsafe {
            _mm_storeu_si128(a.as_mut_ptr() as *mut __m128i, self.a[k]);
            _mm_storeu_si128(b.as_mut_ptr() as *mut __m128i, self.b[k]);
        }
        let n = |p: usize| Node { a: a[p], b: b[p] };
        [n(0), n(1), n(2), n(3)]
    }

    /// Child `k`'s `z_c` per lane ([`Node::zc`]).
    #[inline(always)]
    pub(super) fn zc(&self, k: usize) -> Vec4 {
        // SAFETY: SSE2 baseline.
        unsafe {
            let m = _mm_set1_epi32(0x7fff_fffc);
            Vec4::from(_mm_castsi128_ps(_mm_and_si128(self.a[k], m)))
        }
    }

    /// Child `k`'s crack flag per lane, as a lane mask (all ones where set).
    #[inline(always)]
    pub(super) fn crack(&self, k: usize) -> __m128 {
        // SAFETY: SSE2 baseline.
        unsafe {
            let one = _mm_set1_epi32(FLAG_CRACK as i32);
            _mm_castsi128_ps(_mm_cmpeq_epi32(_mm_and_si128(self.a[k], one), one))
        }
    }

    /// Child `k`'s stored increments per lane ([`Node::increments`]).
    #[inline(always)]
    pub(super) fn increments(&self, k: usize) -> (Vec4, Vec4) {
        // SAFETY: SSE2 baseline.
        unsafe { (f16x4(self.b[k]), f16x4(_mm_srli_epi32(self.b[k], 16))) }
    }
}

/// Child offsets `(dx, dy)` of the child positions, in the definition's order.
pub(super) const KID: [(usize, usize); 4] = [(0, 0), (1, 0), (0, 1), (1, 1)];
/// Footprint corner signs, in the definition's order.
pub(super) const CORNER: [(f32, f32); 4] = [(-1.0, -1.0), (1.0, -1.0), (-1.0, 1.0), (1.0, 1.0)];

/// [`union`] of four children's ranges `(lo, hi)` per lane, as the `a` and `b` words of
/// the four parents, by `minps` / `maxps` from `(+inf, -inf)`. The ranges must hold no NaN
/// and no `-0`: then `minps` / `maxps` equal `f32::min` / `f32::max` in any operand order
/// (no two different words compare equal), so the ranges, the emptiness test `lo > hi` and
/// [`Node::aabb`] (`zmin > 0 ? zmin : 0`, `zmax` not NaN) are the definition's bits.
#[inline(always)]
pub(super) fn union_lanes(ranges: [(__m128, __m128); 4]) -> ([u32; 4], [u32; 4]) {
    // SAFETY: SSE2 baseline; 16-byte stores into 16-byte arrays.
    unsafe {
        let (mut lo, mut hi) = (_mm_set1_ps(f32::INFINITY), _mm_set1_ps(f32::NEG_INFINITY));
        for (a, b) in ranges {
            lo = _mm_min_ps(a, lo);
            hi = _mm_max_ps(b, hi);
        }
        let e = Node::EMPTY;
        let empty = _mm_castps_si128(_mm_cmpgt_ps(lo, hi));
        let zmin = _mm_castps_si128(_mm_and_ps(_mm_cmpgt_ps(lo, _mm_setzero_ps()), lo));
        let a = _mm_or_si128(
            _mm_and_si128(empty, _mm_set1_epi32(e.a as i32)),
            _mm_andnot_si128(empty, zmin),
        );
        let b = _mm_or_si128(
            _mm_and_si128(empty, _mm_set1_epi32(e.b as i32)),
            _mm_andnot_si128(empty, _mm_castps_si128(hi)),
        );
        let (mut aw, mut bw) = ([0u32; 4], [0u32; 4]);
        _mm_storeu_si128(aw.as_mut_ptr() as *mut __m128i, a);
        _mm_storeu_si128(bw.as_mut_ptr() as *mut __m128i, b);
        (aw, bw)
    }
}
